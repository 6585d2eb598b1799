//! A log's name in messages and the names of the files that go with it: the stem they are made
//! from, its default estimates file, and the inputs no output may be (the truth file's name:
//! [`crate::formats::truth_file::truth_path`]).

use crate::formats::log_csv::{is_stdio, STDIO};
use crate::formats::output_file::Input;
use crate::formats::truth_file::truth_path;
use std::path::{Path, PathBuf};

/// The name a log's companion files are made from: `dir/trial.csv` and `dir/trial.csv.gz` both
/// give `dir/trial`.
pub fn log_stem(log_path: &Path) -> PathBuf {
    let name = log_path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    let stem = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    log_path.with_file_name(stem)
}

/// `<dir>/<stem>.estimates.csv` beside the log (`trial.csv` and `trial.csv.gz` give
/// `trial.estimates.csv`); standard output for a log read from standard input.
pub fn default_estimates_path(log: &Path) -> PathBuf {
    if is_stdio(log) {
        return PathBuf::from(STDIO);
    }
    let stem = log_stem(log);
    let name = format!(
        "{}.estimates.csv",
        stem.file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    stem.with_file_name(name)
}

/// The inputs of a run on `log`: the log itself and its truth file (none for standard input).
pub fn inputs_of(log: &Path) -> Vec<Input> {
    if is_stdio(log) {
        return vec![];
    }
    vec![
        Input {
            path: log.to_path_buf(),
            what: "the log itself",
        },
        Input {
            path: truth_path(log),
            what: "the log's truth file",
        },
    ]
}

/// The name of an output in messages: `standard output` for `-`.
pub fn output_name(out: &Path) -> String {
    if is_stdio(out) {
        "standard output".to_string()
    } else {
        out.display().to_string()
    }
}

/// The name of a log in messages.
pub fn log_name(log: &Path) -> String {
    if is_stdio(log) {
        "standard input".to_string()
    } else {
        log.display().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::truth_file::truth_path;

    #[test]
    fn companion_files_drop_csv_and_gz() {
        assert_eq!(
            truth_path(Path::new("/a/b/log.csv")),
            PathBuf::from("/a/b/log.truth.json")
        );
        assert_eq!(
            truth_path(Path::new("/a/b/log.csv.gz")),
            PathBuf::from("/a/b/log.truth.json")
        );
        assert_eq!(
            log_stem(Path::new("x/trial.csv.gz")),
            PathBuf::from("x/trial")
        );
    }
}
