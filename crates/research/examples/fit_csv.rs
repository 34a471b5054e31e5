//! Times `RandomForest::fit` on a CSV of windows, for the training-time comparison with scikit-learn
//! (`benches/sklearn_fit.py` on the same CSV; `benches/summary.py` prints the ratio).
//!
//! ```sh
//! cargo run --release -p crackbot-research --example fit_csv -- benches/out/train.csv \
//!     --threads 2 --repeats 5 --json benches/out/ours_fit.json [--trees 100] [--max-depth D] [--save model.forest]
//! ```
//!
//! The CSV has a header line, then one window per line: the features, then the class (an integer
//! 0..K-1) in the last column (as `crackbot-tactile`'s example `export_windows` writes them). The forest
//! is ours with the defaults (`ForestParams::classifier()`: fully grown unless `--max-depth`,
//! sqrt(n_features) features per split, bootstrap), seed 1, trained `--repeats` times; the median wall time is printed and written to
//! `--json` with every run's time.

use std::path::PathBuf;
use std::time::Instant;

use crackbot_forest::{Dataset, ForestParams, RandomForest};

struct Args {
    csv: PathBuf,
    threads: usize,
    repeats: usize,
    trees: usize,
    max_depth: Option<usize>,
    json: Option<PathBuf>,
    save: Option<PathBuf>,
}

fn parse_args() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let mut a = Args {
        csv: PathBuf::new(),
        threads: 2,
        repeats: 5,
        trees: 100,
        max_depth: None,
        json: None,
        save: None,
    };
    let mut csv = None;
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or_else(|| format!("{name} needs a value"));
        let number = |name: &str, v: String| {
            v.parse::<usize>()
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| format!("{name} {v:?}: expected a positive integer"))
        };
        match arg.as_str() {
            "--threads" => a.threads = number("--threads", value("--threads")?)?,
            "--repeats" => a.repeats = number("--repeats", value("--repeats")?)?,
            "--trees" => a.trees = number("--trees", value("--trees")?)?,
            "--max-depth" => a.max_depth = Some(number("--max-depth", value("--max-depth")?)?),
            "--json" => a.json = Some(value("--json")?.into()),
            "--save" => a.save = Some(value("--save")?.into()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            _ if csv.is_none() => csv = Some(PathBuf::from(arg)),
            _ => return Err(format!("unexpected argument {arg:?}")),
        }
    }
    a.csv = csv.ok_or("usage: fit_csv TRAIN.csv [--threads N] [--repeats R] [--trees T] [--max-depth D] [--json OUT] [--save FOREST]")?;
    Ok(a)
}

/// Features (row-major) and classes of the CSV.
fn read_csv(path: &std::path::Path) -> Result<Dataset, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header = lines
        .next()
        .ok_or_else(|| format!("{}: empty", path.display()))?;
    let n_features = header.split(',').count().saturating_sub(1);
    if n_features == 0 {
        return Err(format!(
            "{}: the header has no feature column",
            path.display()
        ));
    }
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let at = |m: String| format!("{}:{}: {m}", path.display(), i + 2);
        let cols: Vec<&str> = line.split(',').map(str::trim).collect();
        if cols.len() != n_features + 1 {
            return Err(at(format!(
                "{} columns, the header has {}",
                cols.len(),
                n_features + 1
            )));
        }
        for c in &cols[..n_features] {
            x.push(c.parse::<f32>().map_err(|e| at(format!("{c:?}: {e}")))?);
        }
        let class = cols[n_features];
        y.push(
            class
                .parse::<u32>()
                .map_err(|e| at(format!("class {class:?}: {e}")))?,
        );
    }
    Dataset::new(x, n_features, y).map_err(|e| format!("{}: {e}", path.display()))
}

fn main() -> Result<(), String> {
    let a = parse_args()?;
    let data = read_csv(&a.csv)?;
    let params = ForestParams::classifier()
        .n_trees(a.trees)
        .max_depth(a.max_depth)
        .seed(1)
        .n_threads(Some(a.threads))
        .quiet(true);
    let mut times = Vec::with_capacity(a.repeats);
    let mut forest = None;
    for _ in 0..a.repeats {
        let t0 = Instant::now();
        let f = RandomForest::fit(&data, &params).map_err(|e| e.to_string())?;
        times.push(t0.elapsed().as_secs_f64());
        forest = Some(f);
    }
    let forest = forest.ok_or("no run")?;
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let median = if sorted.len() % 2 == 1 {
        sorted[sorted.len() / 2]
    } else {
        0.5 * (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2])
    };
    println!(
        "ours: {} trees on {} rows × {} features, {} classes, {} threads: median {median:.3} s over {} runs {times:.3?}; {} nodes, depth {}",
        a.trees,
        data.n_rows(),
        data.n_features(),
        data.n_classes(),
        a.threads,
        a.repeats,
        forest.n_nodes(),
        forest.max_depth()
    );
    if let Some(path) = &a.json {
        let json = serde_json::json!({
            "csv": a.csv.display().to_string(),
            "rows": data.n_rows(),
            "n_features": data.n_features(),
            "trees": a.trees,
            "max_depth": a.max_depth,
            "threads": a.threads,
            "fit_s": times,
            "fit_median_s": median,
            "nodes": forest.n_nodes(),
        });
        std::fs::write(path, format!("{json:#}\n"))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &a.save {
        forest.save(path).map_err(|e| e.to_string())?;
    }
    Ok(())
}
