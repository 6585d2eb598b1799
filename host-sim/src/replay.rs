//! A log through the estimator, row by row: the one way the subcommands replay a log.
//!
//! A subcommand configures a [`LogReplay`]: the estimator's configuration, how the rows are taken
//! (unreadable rows skipped or refused, restarts from a checkpoint, binning at the navigation
//! rate) and what is recorded of them (the estimates CSV, the report against a truth, the
//! timeline of a report page, every step for the paper's figures). [`LogReplay::run`] reads the
//! log as it goes, on a thread of its own ([`crate::formats::read_ahead`]), and steps the
//! estimator with each row ([`replayer::Replayer`], which `commission` also runs, a row at a time,
//! to hand the same rows to several estimators). Nothing per row is kept unless asked for: memory
//! does not grow with the log (a truth file with the scenario's parameters is the exception: its
//! scenario is regenerated in memory).
//!
//! What is recorded of each row ([`records::Records`]) is the same for a log the firmware steps
//! (`stream`); [`summary`] puts a replay in words.

pub mod loss_cadence;
pub mod records;
pub mod replayer;
pub mod summary;

use crate::exit_status::RunEnd;
use crate::formats::binned_lines::{BinningSummary, Lines};
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{LogError, LogLine, LogReader, RowFilter};
use crate::formats::log_paths::{inputs_of, log_name};
use crate::formats::output_file::{check_not_input, OutputFile};
use crate::formats::read_ahead::read_ahead;
use crate::formats::time_stamps::IntervalError;
use crate::report::timeline::Timeline;
use crate::report::{Report, TruthRows};
use crate::sim::scenario::Row;
use anyhow::Context;
use estimator_core::binning::BinIntervalError;
use estimator_core::{
    Config, ConfigError, Counters, ErrorChange, Estimator, Holdup, Output, RejectCounts,
    RotationSummary, Sample, SampleError,
};
use records::Records;
use replayer::{Replayer, StepView};
use std::path::{Path, PathBuf};

/// The estimator type the host runs: the firmware's default capacity.
pub type HostEstimator = Estimator;

/// The result of one input row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// The input row's time, s.
    pub time_s: f64,
    /// The estimator's output for the row, or why it rejected the row.
    pub result: Result<Output, SampleError>,
}

/// What a replay produced, besides the rows it handed on (nothing per row is kept).
#[derive(Clone, Debug)]
pub struct Replay {
    /// Rows stepped (accepted or rejected by the core); with binning, the bins stepped.
    pub rows: u64,
    /// Rows the estimator rejected, by reason.
    pub rejected: RejectCounts,
    /// Samples accepted, lost samples filled, restarts of the moving average, clock steps.
    pub counters: Counters,
    /// The estimate at the end of the log.
    pub final_estimate: Option<estimator_core::Estimate>,
    /// The status of the last row accepted.
    pub final_status: Option<estimator_core::Status>,
    /// The sample interval learned (or pinned) at the end, s.
    pub sample_interval_s: Option<f64>,
    /// The rotation pattern learned (or pinned) at the end.
    pub rotation: RotationSummary,
    /// What held the estimate back at the end, if anything.
    pub holdup: Option<Holdup>,
    /// Every change of the installation errors the estimator declared, in order.
    pub error_changes: Vec<ErrorChange>,
    /// Rows that could not be read and were skipped (with the first few, for the report).
    pub unreadable: RowFilter,
    /// The latched alarms and the residuals' level at the end.
    pub health: estimator_core::Health,
    /// What binning did, when the rows were binned (`--bin-interval-s`).
    pub binning: Option<BinningSummary>,
    /// Rows lost at a regular cadence, when they were (a limit the 1-sigma does not carry).
    pub regular_loss: Option<loss_cadence::RegularLoss>,
}

/// Why a replay stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The log cannot be read, or one of its rows (when unreadable rows are refused).
    #[error(transparent)]
    Log(#[from] LogError),
    /// The estimator's configuration is invalid.
    #[error("invalid estimator configuration: {0}")]
    Config(ConfigError),
    /// The `--bin-interval-s` is invalid.
    #[error("invalid --bin-interval-s: {0}")]
    BinInterval(BinIntervalError),
    /// The estimates cannot be written.
    #[error("cannot write estimates")]
    Write(#[from] std::io::Error),
    /// The log's time stamps step by an interval that makes no sense.
    #[error(transparent)]
    Interval(#[from] IntervalError),
    /// The estimator cannot be checkpointed, or restored from its checkpoint (`--restart-at`).
    #[error("checkpoint at {time_s} s: {message}")]
    Checkpoint {
        /// Time of the row after which the checkpoint was taken, s.
        time_s: f64,
        /// What went wrong.
        message: String,
    },
}

/// A sample as a log row, in degrees (a binned sample's row, for the reports).
pub fn row_of(sample: &Sample) -> Row {
    let [time_s, rotation_deg, platform_deg, latitude_deg, heading_deg, roll_deg, pitch_deg] =
        sample.to_degrees();
    Row {
        time_s,
        rotation_deg,
        platform_deg,
        latitude_deg,
        heading_deg,
        roll_deg,
        pitch_deg,
    }
}

/// The core's sample for a log row.
pub fn sample_of(row: &Row) -> Sample {
    Sample::from_degrees(
        row.time_s,
        row.rotation_deg,
        row.platform_deg,
        row.latitude_deg,
        row.heading_deg,
        row.roll_deg,
        row.pitch_deg,
    )
}

/// A replay of a log, as a subcommand configures it.
#[derive(Clone, Debug, Default)]
pub struct LogReplay<'a> {
    /// The estimator's configuration.
    pub config: Config,
    /// Refuse the log at its first unreadable row (default: skip it, count it, tell `warn`).
    pub strict: bool,
    /// Checkpoint the estimator after the first row at or after each of these times (ascending),
    /// drop it and restore a fresh one from the bytes: a power cut right after a save. The
    /// estimates go on from the checkpoint's while the window refills
    /// (`estimator_core::checkpoint`).
    pub restart_at_s: Vec<f64>,
    /// Average the rows (any rate up to 200 Hz) into bins of this interval, s
    /// ([`crate::formats::binned_lines`]), and step the estimator once a bin with the bin's
    /// average stamped at its centre, its interval pinned to the bins' (`--bin-interval-s`): the
    /// estimates CSV then has one row per bin, and a row the binner refuses is counted
    /// ([`BinningSummary::refused`]) and is in no bin.
    pub bin_interval_s: Option<f64>,
    /// Write the estimates CSV here (`-`: standard output), through a temporary file renamed over
    /// it at the end ([`OutputFile`]): a replay that fails, or reads no row at all
    /// ([`RunEnd::NothingRead`]), leaves an earlier file as it was. Never the log nor its truth
    /// file.
    pub estimates: Option<PathBuf>,
    /// Judge each row against this truth: the [`Report`].
    pub truth: Option<TruthRows<'a>>,
    /// Keep a [`Timeline`] for a report page.
    pub timeline: bool,
    /// Keep every row's time and result ([`Step`]), for the paper's figures.
    pub steps: bool,
}

/// A replayed log: what the replay produced and what was recorded of its rows.
pub struct Replayed {
    /// What the replay produced.
    pub replay: Replay,
    /// Against the truth, when there was one ([`LogReplay::truth`]).
    pub report: Option<Report>,
    /// What a report page draws, when asked for ([`LogReplay::timeline`]).
    pub timeline: Option<Timeline>,
    /// Every row's result, when asked for ([`LogReplay::steps`]); empty otherwise.
    pub steps: Vec<Step>,
}

impl LogReplay<'_> {
    /// Replays `log` (a file, or `-` for standard input; plain or gzip) as configured. `warn` is
    /// told each unreadable row skipped (the first few). The first stamps are checked
    /// ([`crate::formats::time_stamps::IntervalCheck`]: an interval that makes no sense for a
    /// RINS, or contradicts the pinned one, stops the replay before any estimate).
    pub fn run(&self, log: &Path, warn: &mut dyn FnMut(&LogError)) -> anyhow::Result<Replayed> {
        let out = self.estimates.as_deref();
        if let Some(out) = out {
            check_not_input(out, "--out", &inputs_of(log))?;
        }
        let lines = LogReader::open(log)?;
        let mut writer = match out {
            Some(out) => Some(
                EstimatesWriter::new(OutputFile::create(out)?)
                    .with_context(|| format!("{}:0: cannot write", out.display()))?,
            ),
            None => None,
        };
        let mut records = Records::new(self.truth, self.timeline, self.steps);
        let replay = read_ahead(lines, |lines| {
            self.replay_lines(lines, warn, |view| {
                if let Some(w) = writer.as_mut() {
                    w.write_step(view.line.row.time_s, view.result)
                        .map_err(ReplayError::Write)?;
                }
                records.observe_step(view);
                Ok(())
            })
        })
        .map_err(|e| e.for_people(log, out))?;
        // Nothing to write: an earlier estimates file stays as it was.
        replay.check_rows_read(log)?;
        if let (Some(w), Some(out)) = (writer, out) {
            w.finish()
                .with_context(|| format!("{}:0: cannot write", out.display()))?
                .commit()?;
        }
        // The interval the estimator used (pinned or learned; 1 s if it never learned one).
        let recorded = records.finish(replay.sample_interval_s.unwrap_or(1.0));
        Ok(Replayed {
            replay,
            report: recorded.report,
            timeline: recorded.timeline,
            steps: recorded.steps,
        })
    }

    /// Steps the estimator through `rows` as they come (binned first when asked) and hands each
    /// row and its result to `each`.
    fn replay_lines<I, F>(
        &self,
        rows: I,
        warn: &mut dyn FnMut(&LogError),
        mut each: F,
    ) -> Result<Replay, ReplayError>
    where
        I: IntoIterator<Item = Result<LogLine, LogError>>,
        F: FnMut(&StepView) -> Result<(), ReplayError>,
    {
        let mut lines =
            Lines::new(rows.into_iter(), self.bin_interval_s).map_err(ReplayError::BinInterval)?;
        let mut config = self.config;
        if let Some(bin_s) = self.bin_interval_s {
            config.sample_interval_s = Some(bin_s);
        }
        let mut replayer = Replayer::new(config, &self.restart_at_s, RowFilter::new(self.strict))?;
        if lines.is_binned() {
            replayer.leave_stamps_to_the_binning();
        }
        for item in lines.by_ref() {
            replayer.push(item, warn, &mut each)?;
        }
        if let Some(e) = lines.take_interval_error() {
            return Err(e.into());
        }
        let mut replay = replayer.finish();
        replay.binning = lines.binning();
        Ok(replay)
    }
}

impl Replay {
    /// The log's rows read: those stepped, or with binning, those binned.
    pub fn rows_read(&self) -> u64 {
        self.binning.map_or(self.rows, |b| b.rows)
    }

    /// [`RunEnd::NothingRead`] when no row of `log` could be read.
    pub fn check_rows_read(&self, log: &Path) -> Result<(), RunEnd> {
        if self.rows_read() > 0 {
            return Ok(());
        }
        Err(RunEnd::nothing_read(
            &log_name(log),
            self.unreadable.skipped,
            self.unreadable.first.first(),
        ))
    }
}

impl ReplayError {
    /// The error as the tool tells it: a refused interval names the log, a failed write the
    /// estimates file `out`.
    pub fn for_people(self, log: &Path, out: Option<&Path>) -> anyhow::Error {
        match (self, out) {
            (ReplayError::Interval(i), _) => anyhow::anyhow!("{}: {i}", log_name(log)),
            (ReplayError::Write(io), Some(out)) => {
                anyhow::Error::new(io).context(format!("{}:0: cannot write", out.display()))
            }
            (other, _) => other.into(),
        }
    }
}
