//! Citations of the experiments' record stay honest.
//!
//! Sources and docs cite a section of the record by its title in quotes after the file's name,
//! e.g. `crates/research/EXPERIMENTS.md`, "Prints told by two heights". This walks the
//! repository's `.rs`, `.md`, `.py` and `.sh` files, takes the quoted title (`"…"`, `'…'` or
//! `“…”`) that follows each mention of the file on the same or the next line, and checks that it
//! begins one of the record's headings. The record is organised by question, so no heading may
//! name a session.

use std::fs;
use std::path::{Path, PathBuf};

/// The record's file name, spelt in two parts so that this file does not cite it by accident.
const FILE_NAME: &str = concat!("EXPERIMENTS", ".md");

/// The kinds of file whose citations are checked.
const EXTENSIONS: &[&str] = &["rs", "md", "py", "sh"];

/// What may stand between the file's name and the quoted title: code spans, the end of a link
/// or a parenthesis, a comma.
const SEPARATORS: &[char] = &['`', ')', ']', ',', ':', ';'];

/// A quoted title after a mention of the record.
#[derive(Debug, PartialEq)]
enum Title {
    /// The title between the quotes, its whitespace collapsed.
    Quoted(String),
    /// A quote opened and not closed within the two lines after the mention.
    Unclosed,
}

/// A citation of a section of the record: the 1-based line of the mention and what it cites.
#[derive(Debug, PartialEq)]
struct Citation {
    line: usize,
    title: Title,
}

fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn record_path() -> PathBuf {
    repository_root().join("crates/research").join(FILE_NAME)
}

fn read_record() -> String {
    let path = record_path();
    fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()))
}

/// One run of whitespace for every run of whitespace, none at the ends.
fn collapse(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The titles of the record's headings (`#` to `####`), outside code fences.
fn headings(markdown: &str) -> Vec<String> {
    let mut in_fence = false;
    let mut found = Vec::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if let Some(title) = line[hashes..]
            .strip_prefix(' ')
            .filter(|_| (1..=4).contains(&hashes))
        {
            found.push(collapse(title));
        }
    }
    found
}

/// A line that may carry on a citation from the line before, without its comment marker.
fn continuation(line: &str) -> &str {
    let line = line.trim_start();
    ["//!", "///", "//", "#", "*", ">"]
        .iter()
        .find_map(|marker| line.strip_prefix(*marker))
        .unwrap_or(line)
        .trim_start()
}

/// The quoted title that follows a mention of the record, if one does: `rest` is what follows
/// the file's name on its line, `next` and `after` the two lines after it. The opening quote must
/// lie on the mention's line or the next one, past nothing but separators.
fn quoted_after(rest: &str, next: &str, after: &str) -> Option<Title> {
    let near = format!("{rest} {next}");
    let start = near.find(|c: char| !(c.is_whitespace() || SEPARATORS.contains(&c)))?;
    let window = format!("{near} {after}");
    let mut chars = window[start..].chars();
    let open = chars.next()?;
    let close = match open {
        '"' | '\'' => open,
        '“' => '”',
        _ => return None,
    };
    let body: Vec<char> = chars.collect();
    // A closing quote is not followed by a letter or digit: the apostrophe of "finger's" is not
    // one.
    for (k, &c) in body.iter().enumerate() {
        if c == close && !body.get(k + 1).is_some_and(|n| n.is_alphanumeric()) {
            let title: String = body[..k].iter().collect();
            return Some(Title::Quoted(collapse(&title)));
        }
    }
    Some(Title::Unclosed)
}

/// Every citation of a section of the record in `text`.
fn citations(text: &str) -> Vec<Citation> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        for (at, _) in line.match_indices(FILE_NAME) {
            let rest = &line[at + FILE_NAME.len()..];
            let next = lines.get(i + 1).copied().map_or("", continuation);
            let after = lines.get(i + 2).copied().map_or("", continuation);
            if let Some(title) = quoted_after(rest, next, after) {
                found.push(Citation { line: i + 1, title });
            }
        }
    }
    found
}

/// What is wrong with `citations`, one line each: a title that begins no heading, an empty one,
/// a quote not closed.
fn problems(citations: &[Citation], headings: &[String]) -> Vec<String> {
    citations
        .iter()
        .filter_map(|c| {
            let why = match &c.title {
                Title::Unclosed => {
                    "its quoted title is not closed within the two lines after it".to_string()
                }
                Title::Quoted(title) if title.is_empty() => "its quoted title is empty".to_string(),
                Title::Quoted(title) if headings.iter().any(|h| h.starts_with(title.as_str())) => {
                    return None
                }
                Title::Quoted(title) => {
                    format!("no heading of {FILE_NAME} begins with \"{title}\"")
                }
            };
            Some(format!("line {}: {why}", c.line))
        })
        .collect()
}

/// Whether a folder is left out of the walk: build output, hidden folders, fuzzers' inputs.
fn skipped(folder: &Path, name: &str) -> bool {
    let in_fuzz = folder
        .parent()
        .and_then(Path::file_name)
        .is_some_and(|parent| parent == "fuzz");
    name == "target"
        || name.starts_with('.')
        || (in_fuzz && (name == "corpus" || name == "artifacts"))
}

/// The files under `folder` whose citations are checked.
fn source_files(folder: &Path, out: &mut Vec<PathBuf>) {
    let entries =
        fs::read_dir(folder).unwrap_or_else(|e| panic!("reading {}: {e}", folder.display()));
    for entry in entries {
        let entry = entry.unwrap_or_else(|e| panic!("reading {}: {e}", folder.display()));
        let path = entry.path();
        let kind = entry
            .file_type()
            .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
        if kind.is_dir() {
            if !skipped(&path, &entry.file_name().to_string_lossy()) {
                source_files(&path, out);
            }
        } else if kind.is_file()
            && path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| EXTENSIONS.contains(&e))
        {
            out.push(path);
        }
    }
}

#[test]
fn every_cited_section_of_the_experiments_record_exists() {
    let root = repository_root();
    let headings = headings(&read_record());
    assert!(
        !headings.is_empty(),
        "no headings in {}",
        record_path().display()
    );
    let mut files = Vec::new();
    source_files(&root, &mut files);
    files.sort();
    assert!(
        files
            .iter()
            .any(|f| f.ends_with("crates/research/tests/experiments_citations.rs")),
        "the walk from {} did not reach this test's own file",
        root.display()
    );
    let mut failures = Vec::new();
    for file in &files {
        let bytes = fs::read(file).unwrap_or_else(|e| panic!("reading {}: {e}", file.display()));
        let text = String::from_utf8_lossy(&bytes);
        let shown = file
            .strip_prefix(root.as_path())
            .unwrap_or(file)
            .display()
            .to_string();
        for problem in problems(&citations(&text), &headings) {
            failures.push(format!("{shown}, {problem}"));
        }
    }
    assert!(
        failures.is_empty(),
        "citations of sections of {FILE_NAME} that it does not have (cite a heading's title, or \
         its leading words):\n{}",
        failures.join("\n")
    );
}

#[test]
fn the_experiments_record_is_organised_by_question_not_by_session() {
    let by_session: Vec<String> = headings(&read_record())
        .into_iter()
        .filter(|h| h.to_lowercase().contains("session"))
        .collect();
    assert!(
        by_session.is_empty(),
        "headings of {FILE_NAME} that name a session: {by_session:?}"
    );
}

#[test]
fn the_checker_reports_a_section_that_does_not_exist() {
    let headings = headings(
        "# Record\n\n## A question?\n\n### Prints told by two heights, shallow dips\n\n\
         ```sh\n# not a heading\n```\n#### The finger's reach\n",
    );
    assert_eq!(
        headings,
        [
            "Record",
            "A question?",
            "Prints told by two heights, shallow dips",
            "The finger's reach"
        ]
    );
    let text = format!(
        "/// the gate (`crates/research/{FILE_NAME}`, \"Prints told by two\n\
         /// heights\"); its reach ({FILE_NAME}, 'The finger's reach') and ({FILE_NAME},\n\
         /// “A section never\n\
         /// written”); see [{FILE_NAME}]({FILE_NAME}) for the rest.\n"
    );
    let found = citations(&text);
    assert_eq!(
        found,
        [
            Citation {
                line: 1,
                title: Title::Quoted("Prints told by two heights".to_string()),
            },
            Citation {
                line: 2,
                title: Title::Quoted("The finger's reach".to_string()),
            },
            Citation {
                line: 2,
                title: Title::Quoted("A section never written".to_string()),
            },
        ]
    );
    assert_eq!(
        problems(&found, &headings),
        [format!(
            "line 2: no heading of {FILE_NAME} begins with \"A section never written\""
        )]
    );
}

#[test]
fn the_checker_reports_a_quote_left_open_and_an_empty_title() {
    let headings = ["Scoring".to_string()];
    let text = format!("{FILE_NAME}, \"Scoring\n\nand on\nand on\n{FILE_NAME}, \"\".\n");
    let found = citations(&text);
    assert_eq!(
        problems(&found, &headings),
        [
            "line 1: its quoted title is not closed within the two lines after it".to_string(),
            "line 5: its quoted title is empty".to_string(),
        ]
    );
}
