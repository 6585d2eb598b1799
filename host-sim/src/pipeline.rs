//! The `estimate` and `run` pipelines: log in, estimates CSV out, report against the truth, all
//! as the rows come (memory does not grow with the log; a truth file with the scenario's
//! parameters is the exception: its scenario is regenerated in memory).

use crate::estimates_csv::EstimatesWriter;
use crate::log_csv::{self, is_stdio, read_ahead, LogError, LogLine, LogReader, RowFilter, TruthFile};
use crate::replay::{replay_each, Replay, ReplayError};
use crate::report::{Report, ReportBuilder, TruthRows};
use crate::scenario::{generate, Generated};
use anyhow::Context;
use estimator_core::{Config, Output, SampleError};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A replayed log.
pub struct Estimated {
    pub replay: Replay,
    /// Against the truth, when there was one.
    pub report: Option<Report>,
}

/// `<dir>/<stem>.estimates.csv` beside the log (`trial.csv` and `trial.csv.gz` give
/// `trial.estimates.csv`); standard output for a log read from standard input.
pub fn default_estimates_path(log: &Path) -> PathBuf {
    if is_stdio(log) {
        return PathBuf::from(log_csv::STDIO);
    }
    let stem = log_csv::log_stem(log);
    let name = format!("{}.estimates.csv", stem.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default());
    stem.with_file_name(name)
}

/// Refuses an output that is the input itself (the log would be overwritten while read).
pub fn check_output_is_not_input(log: &Path, out: &Path) -> anyhow::Result<()> {
    if is_stdio(log) || is_stdio(out) {
        return Ok(());
    }
    let same = match (std::fs::metadata(log), std::fs::metadata(out)) {
        (Ok(a), Ok(b)) => {
            use std::os::unix::fs::MetadataExt;
            a.dev() == b.dev() && a.ino() == b.ino()
        }
        _ => false,
    };
    anyhow::ensure!(!same, "{}:0: --out names the log itself; it would be overwritten while it is read", out.display());
    Ok(())
}

/// Opens the estimates output: a file, or standard output for `-`.
pub fn open_output(out: &Path) -> Result<Box<dyn Write>, LogError> {
    if is_stdio(out) {
        return Ok(Box::new(BufWriter::with_capacity(1 << 16, std::io::stdout().lock())));
    }
    let file = File::create(out).map_err(|e| LogError::new(out, 0, format!("cannot create: {e}")))?;
    Ok(Box::new(BufWriter::with_capacity(1 << 16, file)))
}

/// The truth beside a log: the file, and its scenario regenerated when it names one.
pub struct LogTruth {
    pub file: TruthFile,
    pub generated: Option<Generated>,
}

/// The truth beside a log, if any. A truth file that cannot be read is a warning (`warn`), not an
/// error: no accuracy table.
pub fn load_truth(log: &Path, warn: &mut dyn FnMut(String)) -> Option<LogTruth> {
    if is_stdio(log) {
        return None;
    }
    match log_csv::read_truth(&log_csv::truth_path(log)) {
        Ok(None) => None,
        Err(e) => {
            warn(format!("{e}: truth file unreadable, no accuracy table"));
            None
        }
        Ok(Some(truth)) => {
            if let Some(why) = &truth.params_error {
                warn(format!(
                    "{}: scenario parameters unreadable ({why}): judging against x_arcsec only",
                    log_csv::truth_path(log).display()
                ));
            }
            let generated = truth.params.as_ref().map(generate);
            Some(LogTruth { file: truth, generated })
        }
    }
}

/// The rows a report judges against.
pub fn truth_rows<'a>(truth: &'a TruthFile, generated: Option<&'a Generated>) -> TruthRows<'a> {
    match generated {
        Some(g) => TruthRows::Generated {
            rows: &g.rows,
            truth: &g.truth,
            time_offset_s: truth.params.as_ref().map_or(0.0, |p| p.recording.time_offset_s),
        },
        None => TruthRows::Constant(truth.x_arcsec),
    }
}

/// How a log is replayed.
#[derive(Clone, Debug, Default)]
pub struct EstimateOptions {
    pub config: Config,
    /// Checkpoint, drop and restore the estimator after the rows at these times (ascending).
    pub restart_at_s: Vec<f64>,
    /// Refuse the log at its first unreadable row (default: skip and count it).
    pub strict: bool,
}

/// Reads the log as it goes, replays it, writes the estimates CSV to `out` (`-`: standard output)
/// and, with `truth`, builds the report. `warn` is told each unreadable row skipped (the first
/// few); `each` sees every row and its result (e.g. to keep them for plots).
pub fn estimate_log(
    log: &Path,
    out: &Path,
    options: &EstimateOptions,
    truth: Option<TruthRows<'_>>,
    warn: &mut dyn FnMut(&LogError),
    each: &mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
) -> anyhow::Result<Estimated> {
    check_output_is_not_input(log, out)?;
    let lines = LogReader::open(log)?;
    let mut writer = EstimatesWriter::new(open_output(out)?).with_context(|| format!("{}:0: cannot write", out.display()))?;
    let mut report = truth.map(ReportBuilder::new);
    let replay = read_ahead(lines, |lines| {
        replay_each(lines, options.config, &options.restart_at_s, RowFilter::new(options.strict), warn, |line, result| {
            writer.write_step(line.row.time_s, result).map_err(ReplayError::Write)?;
            if let Some(r) = report.as_mut() {
                r.observe(&line.row, result);
            }
            each(line, result);
            Ok(())
        })
    })?;
    writer.finish().with_context(|| format!("{}:0: cannot write", out.display()))?;
    // The interval the estimator used (pinned or learned; 1 s if it never learned one).
    let interval_s = replay.sample_interval_s.unwrap_or(1.0);
    Ok(Estimated { replay, report: report.map(|r| r.finish(interval_s)) })
}

/// [`estimate_log`] with no truth, no restarts, unreadable rows skipped: the benchmark's path.
pub fn estimate_file(log: &Path, out: &Path, config: Config) -> anyhow::Result<Estimated> {
    let options = EstimateOptions { config, ..EstimateOptions::default() };
    estimate_log(log, out, &options, None, &mut |_| {}, &mut |_, _| {})
}
