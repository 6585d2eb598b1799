//! The `estimate` and `run` pipelines: log file in, estimates CSV out, report against the truth.

use crate::estimates_csv::EstimatesWriter;
use crate::log_csv::{self, LogError, LogLine, Truth};
use crate::replay::{replay_with_restarts, Replay};
use crate::report::{evaluate, Report};
use crate::scenario::{generate, Generated, Row, ScenarioParams};
use anyhow::Context;
use estimator_core::Config;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// A replayed log file.
pub struct Estimated {
    pub rows: Vec<Row>,
    pub replay: Replay,
}

/// `<dir>/<stem>.estimates.csv` beside the log.
pub fn default_estimates_path(log: &Path) -> PathBuf {
    let stem = log.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    log.with_file_name(format!("{stem}.estimates.csv"))
}

/// Reads the log (any malformed line stops it with `FILE:LINE: message`), replays it and writes
/// the estimates CSV to `out`.
pub fn estimate_file(log: &Path, out: &Path, config: Config) -> anyhow::Result<Estimated> {
    estimate_file_with_restarts(log, out, config, &[])
}

/// As [`estimate_file`], restarting the estimator from a checkpoint at `restart_at_s`.
pub fn estimate_file_with_restarts(log: &Path, out: &Path, config: Config, restart_at_s: &[f64]) -> anyhow::Result<Estimated> {
    let lines: Vec<LogLine> = log_csv::read_log(log)?;
    let file = File::create(out).map_err(|e| LogError::new(out, 0, format!("cannot create: {e}")))?;
    let mut writer = EstimatesWriter::new(BufWriter::new(file)).with_context(|| format!("{}:0: cannot write", out.display()))?;
    let replay = replay_with_restarts(lines.iter().map(|l| Ok(*l)), config, Some(&mut writer), restart_at_s)?;
    writer.finish().with_context(|| format!("{}:0: cannot write", out.display()))?;
    Ok(Estimated { rows: lines.into_iter().map(|l| l.row).collect(), replay })
}

/// The truth beside a log, regenerated: `None` when there is no truth file.
pub fn load_truth(log: &Path) -> anyhow::Result<Option<(Truth, Generated)>> {
    let Some(truth) = log_csv::read_truth(&log_csv::truth_path(log))? else { return Ok(None) };
    let generated = generate(&truth.params);
    Ok(Some((truth, generated)))
}

/// The report of a replay against a regenerated truth (time stamps moved back onto the sample
/// instants the truth is indexed by, see [`on_sample_grid`]).
pub fn report(est: &Estimated, truth: &Truth, generated: &Generated) -> Report {
    let grid = on_sample_grid(est, &truth.params);
    evaluate(&grid.rows, &grid.replay.steps, &generated.truth, truth.params.sample_interval_s)
}

/// A replay of a generated log with every time (rows, steps, outputs) moved from the recorder's
/// stamp to the sample instant it was taken at, s from the log's start; a stamp that is no
/// instant's becomes NaN (and is left out of reports). Whole-second stamps at a whole-second
/// interval without offset or jitter map to themselves.
pub fn on_sample_grid(est: &Estimated, params: &ScenarioParams) -> Estimated {
    let rec = &params.recording;
    let grid = |t: f64| rec.sample_time_s(t, params.sample_interval_s).unwrap_or(f64::NAN);
    let mut out = Estimated { rows: est.rows.clone(), replay: est.replay.clone() };
    for r in &mut out.rows {
        r.time_s = grid(r.time_s);
    }
    for step in &mut out.replay.steps {
        step.time_s = grid(step.time_s);
        if let Ok(o) = &mut step.result {
            o.time_s = grid(o.time_s);
        }
    }
    out
}
