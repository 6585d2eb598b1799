//! The `estimate` and `run` pipelines: log in, estimates CSV out, report against the truth, all
//! as the rows come (memory does not grow with the log; a truth file with the scenario's
//! parameters is the exception: its scenario is regenerated in memory).

use crate::exit_status::RunEnd;
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{self, LogError, RowFilter};
use crate::formats::log_paths::{inputs_of, log_name};
use crate::formats::output_file::{check_not_input, OutputFile};
use crate::formats::read_ahead::read_ahead;
use crate::replay::{replay_each, Replay, ReplayError, ReplayOptions, StepView};
use crate::report::timeline::{Timeline, TimelineRow};
use crate::report::{Report, ReportBuilder, TruthRows};
use anyhow::Context;
use estimator_core::Config;
use std::path::Path;

/// A replayed log.
pub struct Estimated {
    /// What the replay produced.
    pub replay: Replay,
    /// Against the truth, when there was one.
    pub report: Option<Report>,
    /// What the report draws, when asked for ([`EstimateOptions::timeline`]).
    pub timeline: Option<Timeline>,
}

/// How a log is replayed.
#[derive(Clone, Debug, Default)]
pub struct EstimateOptions {
    /// The estimator's configuration.
    pub config: Config,
    /// Checkpoint, drop and restore the estimator after the rows at these times (ascending).
    pub restart_at_s: Vec<f64>,
    /// Refuse the log at its first unreadable row (default: skip and count it).
    pub strict: bool,
    /// Keep a [`Timeline`] for a report.
    pub timeline: bool,
    /// Average the rows (any rate up to 200 Hz) into bins of this interval, s, and step the
    /// estimator once a bin, its interval pinned to the bins' (`--bin-interval-s`,
    /// [`estimator_core::binning`]): the estimates CSV then has one row per bin.
    pub bin_interval_s: Option<f64>,
}

/// Reads the log as it goes, replays it, writes the estimates CSV to `out` (`-`: standard output)
/// and, with `truth`, builds the report. `warn` is told each unreadable row skipped (the first
/// few); `each` sees every row as the replay saw it (e.g. to keep them for plots).
///
/// The estimates go to a temporary file renamed over `out` at the end ([`OutputFile`]): a run
/// that fails, or reads no row at all ([`RunEnd::NothingRead`]), leaves an earlier file as it was.
/// Neither the log nor its truth file is ever `out`.
pub fn estimate_log(
    log: &Path,
    out: &Path,
    options: &EstimateOptions,
    truth: Option<TruthRows<'_>>,
    warn: &mut dyn FnMut(&LogError),
    each: &mut dyn FnMut(&StepView),
) -> anyhow::Result<Estimated> {
    check_not_input(out, "--out", &inputs_of(log))?;
    let lines = log_csv::LogReader::open(log)?;
    let mut writer = EstimatesWriter::new(OutputFile::create(out)?)
        .with_context(|| format!("{}:0: cannot write", out.display()))?;
    let mut report = truth.map(ReportBuilder::new);
    let mut timeline = options.timeline.then(Timeline::new);
    let replay = read_ahead(lines, |lines| {
        replay_each(
            lines,
            options.config,
            &ReplayOptions {
                restart_at_s: options.restart_at_s.clone(),
                bin_interval_s: options.bin_interval_s,
            },
            RowFilter::new(options.strict),
            warn,
            |view| {
                let row = &view.line.row;
                writer
                    .write_step(row.time_s, view.result)
                    .map_err(ReplayError::Write)?;
                let truth = report.as_mut().and_then(|r| r.observe(row, view.result));
                if let Some(t) = timeline.as_mut() {
                    t.observe(TimelineRow {
                        row,
                        result: view.result,
                        placement: view.placement,
                        counters: Some(view.estimator.counters()),
                        residuals_rad: view.residuals_rad(),
                        truth,
                    });
                }
                each(view);
                Ok(())
            },
        )
    })
    .map_err(|e| match e {
        ReplayError::Interval(i) => anyhow::anyhow!("{}: {i}", log_name(log)),
        ReplayError::Write(io) => {
            anyhow::Error::new(io).context(format!("{}:0: cannot write", out.display()))
        }
        other => other.into(),
    })?;
    let rows_read = replay.binning.map_or(replay.rows, |b| b.rows);
    if rows_read == 0 {
        // Nothing to write: an earlier estimates file stays as it was.
        return Err(RunEnd::nothing_read(
            &log_name(log),
            replay.unreadable.skipped,
            replay.unreadable.first.first(),
        )
        .into());
    }
    writer
        .finish()
        .with_context(|| format!("{}:0: cannot write", out.display()))?
        .commit()?;
    // The interval the estimator used (pinned or learned; 1 s if it never learned one).
    let interval_s = replay.sample_interval_s.unwrap_or(1.0);
    Ok(Estimated {
        replay,
        report: report.map(|r| r.finish(interval_s)),
        timeline,
    })
}

/// [`estimate_log`] with no truth, no restarts, unreadable rows skipped: the benchmark's path.
pub fn estimate_file(log: &Path, out: &Path, config: Config) -> anyhow::Result<Estimated> {
    let options = EstimateOptions {
        config,
        ..EstimateOptions::default()
    };
    estimate_log(log, out, &options, None, &mut |_| {}, &mut |_| {})
}
