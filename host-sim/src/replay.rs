//! Replays an attitude log through the core, row by row, writing the estimates CSV.

use crate::formats::binned_lines::{BinningSummary, Lines};
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{LogError, LogLine, RowFilter};
use crate::formats::time_stamps::{IntervalCheck, IntervalError};
use crate::sim::scenario::Row;
use estimator_core::binning::BinIntervalError;
use estimator_core::time_grid::{Placement, TimeGrid};
use estimator_core::{
    Config, ConfigError, Counters, ErrorChange, Estimator, Holdup, Output, Real, RejectCounts,
    RotationSummary, Sample, SampleError,
};
use std::io::Write;

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

/// Checkpoints the estimator and restores a fresh one from the bytes (which the caller puts in its
/// place, dropping the old one).
fn restart(est: &HostEstimator, time_s: f64) -> Result<HostEstimator, ReplayError> {
    let fail = |e: estimator_core::checkpoint::CheckpointError| ReplayError::Checkpoint {
        time_s,
        message: e.to_string(),
    };
    let mut buf = vec![0u8; HostEstimator::CHECKPOINT_LEN];
    let n = est.checkpoint(&mut buf).map_err(fail)?;
    // Only the bytes carry the state into the new estimator.
    HostEstimator::from_checkpoint(&buf[..n]).map_err(fail)
}

/// A learned value for people, to 4 significant digits (the learned values carry the recorder's
/// clock error, 1e-6 s on 1 s), trailing zeros of the decimals dropped: `1000`, `1`, `0.1`, `479.9`.
pub fn significant_4(v: f64) -> String {
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// What was learned of the log's timing, for people: e.g. `rotation: reciprocating, period 720 s;
/// sample interval 1 s`.
pub fn pattern_summary(r: &Replay) -> String {
    let round = significant_4;
    let rotation = match (r.rotation.kind, r.rotation.period_s) {
        (Some(kind), Some(p)) => format!("{}, period {} s", kind.name(), round(p)),
        (None, Some(p)) => format!("period {} s (shape not yet learned)", round(p)),
        _ => "period not yet detected".to_string(),
    };
    let pinned = if r.rotation.pinned { " (pinned)" } else { "" };
    let bins = if r.rotation.samples_per_entry > 1 {
        format!(", {} samples a window entry", r.rotation.samples_per_entry)
    } else {
        String::new()
    };
    let interval = r
        .sample_interval_s
        .map_or("not yet learned".to_string(), |d| format!("{} s", round(d)));
    format!("rotation: {rotation}{pinned}{bins}; sample interval {interval}")
}

/// A change of the installation errors, for people: e.g. `change of the installation errors
/// detected at 13440 s (residuals showing it since 12240 s): x1, x3 learned again`.
pub fn describe_error_change(c: &ErrorChange) -> String {
    let which: Vec<String> = (0..4)
        .filter(|i| c.relearned[*i])
        .map(|i| format!("x{}", i + 1))
        .collect();
    format!(
        "change of the installation errors detected at {} s (residuals showing it since {} s): {} learned again",
        c.detected_s,
        c.seen_since_s,
        which.join(", ")
    )
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

/// One row as the replay saw it: handed to the caller of [`replay_each`] after each step.
pub struct StepView<'a> {
    /// The row and its line number in the log.
    pub line: &'a LogLine,
    /// The estimator's output for the row, or why it rejected the row.
    pub result: &'a Result<Output, SampleError>,
    /// Where an accepted row fell on the sample grid (lost samples before it, a clock step).
    pub placement: Option<Placement>,
    /// The estimator after this row.
    pub estimator: &'a HostEstimator,
}

impl StepView<'_> {
    /// The windowed method's post-fit residuals of the current window, rad, per correlation
    /// channel (pitch x sin, pitch x cos, roll x sin, roll x cos): `z - H x` with `z`, `H` the
    /// window's measurement ([`estimator_core::correlation::CorrelationSums::measurement`]) and `x`
    /// the filter's state: what eq (2) with the current estimate leaves unexplained in the
    /// window's correlations. `None` for the other methods and before the filter's first update.
    pub fn residuals_rad(&self) -> Option<[Real; 4]> {
        let w = self.estimator.windowed()?;
        if w.updates() == 0 || !w.window().is_full() {
            return None;
        }
        let m = w.window().sums().measurement()?;
        let x = w.filter().state();
        Some(core::array::from_fn(|ch| {
            m.z[ch] - (0..x.len()).map(|i| m.rows[ch][i] * x[i]).sum::<Real>()
        }))
    }
}

/// The sample grid as the estimator sees it, followed beside it from the stamps it accepted: where
/// each accepted row falls ([`Placement`]: a gap, a clock step), which the reports mark row by row,
/// and the clock steps counted (what a stream, whose answers carry no counters, reports). A second
/// grid of the same code, given the same configuration and the same accepted stamps, places every
/// stamp as the estimator's did.
#[derive(Clone, Debug)]
pub struct GridFollower {
    grid: TimeGrid,
    clock_steps: u32,
}

impl GridFollower {
    /// The grid a fresh estimator of `config` starts with: its interval pinned by `config`, or
    /// to be learned from the stamps.
    pub fn new(config: &Config) -> GridFollower {
        GridFollower {
            grid: TimeGrid::new(config.sample_interval_s),
            clock_steps: 0,
        }
    }

    /// A row's result: where an accepted row fell; `None` for a rejected one.
    pub fn follow(
        &mut self,
        time_s: f64,
        result: &Result<Output, SampleError>,
    ) -> Option<Placement> {
        result.as_ref().ok()?;
        let placed = self.grid.place(time_s).ok()?;
        self.grid.accept(time_s, placed);
        let placement = placed.placement;
        if placement == Placement::ClockStep {
            self.clock_steps = self.clock_steps.saturating_add(1);
        }
        Some(placement)
    }

    /// The sample interval, s, as the estimator pins or learns it.
    pub fn interval_s(&self) -> Option<f64> {
        self.grid.interval_s()
    }

    /// Clock jumps and steps back seen.
    pub fn clock_steps(&self) -> u32 {
        self.clock_steps
    }
}

/// Runs rows through a fresh estimator; writes one estimates row per input row when `writer` is
/// given. Any unreadable row is an error.
pub fn replay<I, W>(
    rows: I,
    config: Config,
    writer: Option<&mut EstimatesWriter<W>>,
) -> Result<Replay, ReplayError>
where
    I: IntoIterator<Item = Result<LogLine, LogError>>,
    W: Write,
{
    let mut writer = writer;
    replay_each(
        rows,
        config,
        &ReplayOptions::default(),
        RowFilter::new(true),
        &mut |_| {},
        |view| {
            if let Some(w) = writer.as_deref_mut() {
                w.write_step(view.line.row.time_s, view.result)?;
            }
            Ok(())
        },
    )
}

/// Steps the estimator through `rows` as they come and hands each row and its result to `each`
/// (which writes it, reports it...); nothing per row is kept. Unreadable rows go through `filter`
/// (skipped and counted, `warn` told; or refused when strict). The first stamps are checked
/// ([`IntervalCheck`]: an interval that makes no sense for a RINS, or contradicts the pinned one,
/// stops the replay before any estimate). After the first row at or after each of
/// `options.restart_at_s` (ascending) the estimator is checkpointed, dropped and restored from the
/// bytes: a power cut right after a save. The estimates go on from the checkpoint's while the
/// window refills (see `estimator_core::checkpoint`). [`Replayer`] does the same a row at a time.
///
/// With `options.bin_interval_s` the rows (at any rate up to 200 Hz) are averaged into bins of
/// that interval ([`crate::formats::binned_lines::BinnedLines`]) and the estimator, its interval pinned to
/// the bins', steps once a bin, each bin's average handed to `each` as a row stamped at the bin's
/// centre; the last bin is stepped at the end of the rows. A row the binner refuses is counted
/// ([`BinningSummary::refused`]) and is in no bin.
pub fn replay_each<I, F>(
    rows: I,
    mut config: Config,
    options: &ReplayOptions,
    filter: RowFilter,
    warn: &mut dyn FnMut(&LogError),
    mut each: F,
) -> Result<Replay, ReplayError>
where
    I: IntoIterator<Item = Result<LogLine, LogError>>,
    F: FnMut(&StepView) -> Result<(), ReplayError>,
{
    let mut lines =
        Lines::new(rows.into_iter(), options.bin_interval_s).map_err(ReplayError::BinInterval)?;
    if let Some(bin_s) = options.bin_interval_s {
        config.sample_interval_s = Some(bin_s);
    }
    let mut replayer = Replayer::new(config, &options.restart_at_s, filter)?;
    // A binned log's stamps are checked as they are binned; its bins are one interval apart.
    replayer.check_stamps = !lines.is_binned();
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

/// One line of the latched alarms and the residuals' level (the estimates CSV's last columns):
/// `alarms: 1 change declared (the last at 12000 s), 2 window restarts, 0 rejected, 120 s in
/// model_mismatch; residual level pitch 0.041 / roll 0.073 arcsec, noise scale 1.00 / 1.25`.
pub fn describe_health(h: &estimator_core::Health) -> String {
    let plural = |n: u32, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    let mut s = format!(
        "alarms: {}",
        plural(h.changes_detected, "change declared", "changes declared")
    );
    if let Some(t) = h.last_change_s {
        s.push_str(&format!(" (the last at {t} s)"));
    }
    s.push_str(&format!(
        ", {}, {} rejected, {} s in model_mismatch",
        plural(h.window_restarts, "window restart", "window restarts"),
        h.rejected,
        h.mismatch_s
    ));
    if let (Some(r), Some(k)) = (h.residual_rad, h.noise_scale) {
        s.push_str(&format!(
            "; residual level pitch {:.3} / roll {:.3} arcsec, noise scale {:.2} / {:.2}",
            estimator_core::units::rad_to_arcsec(f64::from(r[0])),
            estimator_core::units::rad_to_arcsec(f64::from(r[1])),
            k[0],
            k[1]
        ));
    }
    s
}

/// How [`replay_each`] takes the rows, besides the estimator's configuration.
#[derive(Clone, Debug, Default)]
pub struct ReplayOptions {
    /// Checkpoint, drop and restore the estimator after the first row at or after each of these
    /// times (ascending).
    pub restart_at_s: Vec<f64>,
    /// Average the rows into bins of this interval, s, and step the estimator once a bin
    /// ([`estimator_core::binning`]); the estimator's sample interval is then pinned to it.
    pub bin_interval_s: Option<f64>,
}

/// A channel pair's noise scale at and beyond which the summary names the limit the log sets
/// ([`describe_limit`]): its errors' 1-sigma widened at least twofold over the white noise's.
pub const LIMIT_NOISE_SCALE: f32 = 4.0;

/// The limit the log sets, when a channel pair's residuals hold more than the configured white
/// noise gives (its noise scale at least [`LIMIT_NOISE_SCALE`]): which pair, by how much, the
/// likely causes, and that the pair's 1-sigma already carries it. `None` on a log whose residuals
/// are the model's, and before the first estimate.
pub fn describe_limit(h: &estimator_core::Health) -> Option<String> {
    let s = h.noise_scale?;
    let over: Vec<String> = [("pitch pair (x1, x2)", s[0]), ("roll pair (x3, x4)", s[1])]
        .iter()
        .filter(|(_, k)| *k >= LIMIT_NOISE_SCALE)
        .map(|(pair, k)| {
            format!(
                "the {pair} {k:.0} times (its 1-sigma widened {:.1}-fold)",
                k.sqrt()
            )
        })
        .collect();
    if over.is_empty() {
        return None;
    }
    Some(format!(
        "limit: the residuals hold more than the white noise the model gives, {}: a slow heel or \
         trim, rows lost at a cadence, or another disturbance near the rotation frequency, which \
         attitude alone does not tell from the installation errors; the 1-sigma above includes it",
        over.join(", ")
    ))
}

/// [`replay_each`] a row at a time, for a caller that hands the same rows to several replays.
pub struct Replayer<'a> {
    est: HostEstimator,
    restart_at_s: &'a [f64],
    next_restart: usize,
    count: u64,
    final_status: Option<estimator_core::Status>,
    error_changes: Vec<ErrorChange>,
    interval_check: IntervalCheck,
    /// Whether the rows' stamps are checked here (not when they were binned: the binning checks
    /// them, and its bins are one interval apart).
    check_stamps: bool,
    grid: GridFollower,
    filter: RowFilter,
}

impl<'a> Replayer<'a> {
    /// A fresh estimator of `config`; `restart_at_s` and `filter` as for [`replay_each`].
    pub fn new(
        config: Config,
        restart_at_s: &'a [f64],
        filter: RowFilter,
    ) -> Result<Replayer<'a>, ReplayError> {
        Ok(Replayer {
            est: HostEstimator::new(config).map_err(ReplayError::Config)?,
            restart_at_s,
            next_restart: 0,
            count: 0,
            final_status: None,
            error_changes: Vec::new(),
            interval_check: IntervalCheck::new(config.sample_interval_s),
            check_stamps: true,
            grid: GridFollower::new(&config),
            filter,
        })
    }

    /// One item of the log: stepped and handed to `each`, or skipped (unreadable, `warn` told),
    /// or the error that ends the replay.
    pub fn push<F>(
        &mut self,
        item: Result<LogLine, LogError>,
        warn: &mut dyn FnMut(&LogError),
        each: &mut F,
    ) -> Result<(), ReplayError>
    where
        F: FnMut(&StepView) -> Result<(), ReplayError>,
    {
        let Some(line) = self.filter.admit(item, warn)? else {
            return Ok(());
        };
        if self.check_stamps {
            self.interval_check.observe(line.row.time_s)?;
        }
        let result = self.est.step(&sample_of(&line.row));
        self.count += 1;
        if let Ok(out) = &result {
            self.final_status = Some(out.status);
            if let Some(change) = self
                .est
                .error_change()
                .filter(|c| c.detected_s == out.time_s)
            {
                self.error_changes.push(change);
            }
        }
        let placement = self.grid.follow(line.row.time_s, &result);
        each(&StepView {
            line: &line,
            result: &result,
            placement,
            estimator: &self.est,
        })?;
        let mut due = false;
        while self.next_restart < self.restart_at_s.len()
            && line.row.time_s >= self.restart_at_s[self.next_restart]
        {
            self.next_restart += 1;
            due = true;
        }
        if due {
            self.est = restart(&self.est, line.row.time_s)?;
        }
        Ok(())
    }

    /// What the replay produced.
    pub fn finish(self) -> Replay {
        let est = &self.est;
        Replay {
            rows: self.count,
            rejected: est.rejected(),
            counters: est.counters(),
            final_estimate: est.estimate(),
            final_status: self.final_status,
            sample_interval_s: est.sample_interval_s(),
            rotation: est.rotation(),
            holdup: est.progress(),
            error_changes: self.error_changes,
            unreadable: self.filter,
            health: est.health(),
            binning: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn learned_values_keep_their_whole_digits() {
        // 1000 was printed as "1": the zeros of a whole number were trimmed as if decimals.
        assert_eq!(significant_4(1000.0), "1000");
        assert_eq!(significant_4(720.0), "720");
        assert_eq!(significant_4(1.000_000_3), "1");
        assert_eq!(significant_4(0.100_000_2), "0.1");
        assert_eq!(significant_4(479.93), "479.9");
        assert_eq!(significant_4(12_345.6), "12346");
    }
}
