//! `crackbot tactile ...`: the tactile recordings, the authors' MAT-files and crackbot's CSV files.
//!
//! * `crackbot tactile convert INPUT... --out DIR|FILE` — converts recordings between `.mat` and `.csv`
//!   (`.csv` → `.csv` normalises the file). Inputs are files or folders (every `.mat`/`.csv` directly inside).

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use crackbot_recording::{collect_recordings, write_recording, Format, Recording};

/// Subcommands of `crackbot tactile`.
#[derive(Debug, Subcommand)]
pub enum TactileCommand {
    /// Convert recordings between the authors' .mat files and .csv (.csv → .csv normalises).
    ///
    /// With one input recording and `--out` ending in .csv or .mat, writes that file; otherwise `--out` is a
    /// folder (created if needed) and each input becomes `<stem>.<format>` there.
    Convert(ConvertArgs),
}

/// Arguments of `crackbot tactile convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Recordings (.mat or .csv), or folders holding them (not searched recursively).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Output file (.csv or .mat; one input recording only) or folder.
    #[arg(long, short)]
    out: PathBuf,
    /// Form of the files written into an output folder.
    #[arg(long, value_enum, default_value_t = OutFormat::Csv)]
    format: OutFormat,
}

/// Form of the files written into an output folder.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum OutFormat {
    /// CSV, crackbot's recording format.
    Csv,
    /// MAT-file level 5, the authors' format.
    Mat,
}

impl From<OutFormat> for Format {
    fn from(f: OutFormat) -> Format {
        match f {
            OutFormat::Csv => Format::Csv,
            OutFormat::Mat => Format::Mat,
        }
    }
}

/// Runs a `crackbot tactile` subcommand.
pub fn run(cmd: TactileCommand) -> Result<()> {
    match cmd {
        TactileCommand::Convert(args) => convert(args),
    }
}

/// Whether `--out` names a file (an extension of a recording form, and not an existing folder).
fn is_file_target(out: &Path) -> bool {
    Format::of_path(out).is_ok() && !out.is_dir()
}

fn convert(args: ConvertArgs) -> Result<()> {
    // Everything is read (and checked) before anything is written.
    let recordings = collect_recordings(&args.inputs)?;
    let targets: Vec<PathBuf> = if is_file_target(&args.out) {
        if recordings.len() != 1 {
            bail!(
                "--out {} names one file but the inputs hold {} recordings; give a folder",
                args.out.display(),
                recordings.len()
            );
        }
        create_parent(&args.out)?;
        vec![args.out.clone()]
    } else {
        if args.out.extension().is_some() && !args.out.is_dir() {
            bail!(
                "--out {}: a single output file must end in .csv or .mat; an output folder must exist \
                 already or have no extension",
                args.out.display()
            );
        }
        if args.out.exists() && !args.out.is_dir() {
            bail!(
                "--out {} exists and is not a folder (a single output file must end in .csv or .mat)",
                args.out.display()
            );
        }
        std::fs::create_dir_all(&args.out)
            .with_context(|| format!("creating folder {}", args.out.display()))?;
        let ext = Format::from(args.format).extension();
        let mut seen: HashMap<PathBuf, &Path> = HashMap::new();
        let mut targets = Vec::with_capacity(recordings.len());
        for (input, _) in &recordings {
            let stem = input
                .file_stem()
                .with_context(|| format!("{}: no file name", input.display()))?;
            let target = args.out.join(stem).with_extension(ext);
            if let Some(other) = seen.insert(target.clone(), input) {
                bail!(
                    "{} and {} would both be written to {}",
                    other.display(),
                    input.display(),
                    target.display()
                );
            }
            targets.push(target);
        }
        targets
    };
    let mut stdout = std::io::stdout().lock();
    for ((input, rec), target) in recordings.iter().zip(&targets) {
        write_recording(target, rec)?;
        // A closed stdout (e.g. piped into `head`) must not stop the conversion.
        let _ = writeln!(
            stdout,
            "{} → {}: {}",
            input.display(),
            target.display(),
            describe(rec)
        );
    }
    Ok(())
}

/// One line about a recording: rows, slides, label and repetition.
fn describe(rec: &Recording) -> String {
    let label = rec
        .label()
        .map_or_else(|| "mixed".to_string(), |l| l.to_string());
    let repetition = rec
        .repetition()
        .map_or_else(|| "mixed".to_string(), |r| r.to_string());
    format!(
        "{} rows, {} slides, label {label}, repetition {repetition}",
        rec.len(),
        rec.slides().len()
    )
}

fn create_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating folder {}", dir.display()))?;
    }
    Ok(())
}
