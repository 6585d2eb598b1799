//! The truth file beside a generated log (`FILE.truth.json`): the installation errors and the
//! scenario's parameters; format in `docs/log-format.md`.

use crate::formats::log_csv::is_stdio;
use crate::formats::log_csv::LogError;
use crate::formats::log_paths::log_stem;
use crate::sim::scenario::{generate, Generated, ScenarioParams};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The truth file of a generated log: the installation errors and every scenario parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Installation errors x1..x4 at t = 0, arcsec (they drift only under a model mismatch).
    pub x_arcsec: [f64; 4],
    /// Every parameter of the scenario, written at the top level.
    #[serde(flatten)]
    pub params: ScenarioParams,
}

impl Truth {
    /// The truth file of the log `params` generates.
    pub fn new(params: &ScenarioParams) -> Truth {
        Truth {
            x_arcsec: params.errors_arcsec,
            params: params.clone(),
        }
    }
}

/// `<dir>/<stem>.truth.json` beside the log `<dir>/<stem>.csv` (or `.csv.gz`).
pub fn truth_path(log_path: &Path) -> PathBuf {
    let stem = log_stem(log_path);
    let name = format!(
        "{}.truth.json",
        stem.file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    stem.with_file_name(name)
}

/// Writes the truth file (through a temporary file beside it).
pub fn write_truth(path: &Path, truth: &Truth) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(truth)
        .map_err(|e| LogError::new(path, 0, format!("cannot encode: {e}")))?;
    crate::formats::output_file::write_bytes(path, (text + "\n").as_bytes())
}

/// A truth file as read: the errors, and the scenario when `generate` wrote it.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthFile {
    /// Installation errors x1..x4, arcsec.
    pub x_arcsec: [f64; 4],
    /// The scenario's parameters, when the file carries them.
    pub params: Option<ScenarioParams>,
    /// Why the scenario's parameters (the file has a `scenario` field) could not be read.
    pub params_error: Option<String>,
}

/// Reads a truth file; `Ok(None)` when it does not exist. Only `x_arcsec` is required.
pub fn read_truth(path: &Path) -> Result<Option<TruthFile>, LogError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(LogError::new(path, 0, format!("cannot read: {e}"))),
    };
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| LogError::new(path, e.line(), e.to_string()))?;
    let x = value
        .get("x_arcsec")
        .ok_or_else(|| LogError::new(path, 0, "no \"x_arcsec\": [x1, x2, x3, x4] (arcsec)"))?;
    let x_arcsec: [f64; 4] = serde_json::from_value(x.clone())
        .map_err(|e| LogError::new(path, 0, format!("x_arcsec: {e}")))?;
    let (params, params_error) = match value.get("scenario") {
        None => (None, None),
        Some(_) => match ScenarioParams::deserialize(&value) {
            Ok(p) => (Some(p), None),
            Err(e) => (None, Some(e.to_string())),
        },
    };
    Ok(Some(TruthFile {
        x_arcsec,
        params,
        params_error,
    }))
}

/// The truth beside a log: the file, and its scenario regenerated when it names one.
pub struct LogTruth {
    /// The truth file as read.
    pub file: TruthFile,
    /// The scenario it names, regenerated (`None` for a file with the errors only).
    pub generated: Option<Generated>,
}

/// The truth beside a log, if any. A truth file that cannot be read is a warning (`warn`), not an
/// error: no accuracy table.
pub fn load_truth(log: &Path, warn: &mut dyn FnMut(String)) -> Option<LogTruth> {
    if is_stdio(log) {
        return None;
    }
    match read_truth(&truth_path(log)) {
        Ok(None) => None,
        Err(e) => {
            warn(format!("{e}: truth file unreadable, no accuracy table"));
            None
        }
        Ok(Some(truth)) => {
            if let Some(why) = &truth.params_error {
                warn(format!(
                    "{}: scenario parameters unreadable ({why}): judging against x_arcsec only",
                    truth_path(log).display()
                ));
            }
            let generated = truth.params.as_ref().map(generate);
            Some(LogTruth {
                file: truth,
                generated,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scenario::ScenarioKind;

    #[test]
    fn truth_round_trips_with_params_and_needs_only_x_arcsec() {
        let p = crate::sim::scenario::ScenarioParams::new(ScenarioKind::Paper, 9);
        let truth = Truth::new(&p);
        let text = serde_json::to_string(&truth).unwrap();
        assert!(
            text.starts_with("{\"x_arcsec\":[200.0,-150.0,300.0,-250.0],"),
            "{text}"
        );
        let dir = std::env::temp_dir().join(format!("host-sim-truth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let full = dir.join("full.truth.json");
        write_truth(&full, &truth).unwrap();
        let minimal = dir.join("min.truth.json");
        std::fs::write(&minimal, "{\"x_arcsec\": [1, -2, 3.5, 0]}").unwrap();
        let broken = dir.join("broken.truth.json");
        std::fs::write(&broken, "{\"x\": 1}").unwrap();
        let (full, minimal, broken, missing) = (
            read_truth(&full),
            read_truth(&minimal),
            read_truth(&broken),
            read_truth(&dir.join("none.json")),
        );
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(
            full.unwrap().unwrap(),
            TruthFile {
                x_arcsec: truth.x_arcsec,
                params: Some(p),
                params_error: None
            }
        );
        assert_eq!(
            minimal.unwrap().unwrap(),
            TruthFile {
                x_arcsec: [1.0, -2.0, 3.5, 0.0],
                params: None,
                params_error: None
            }
        );
        assert!(broken.unwrap_err().to_string().contains("x_arcsec"));
        assert_eq!(missing.unwrap(), None);
    }
}
