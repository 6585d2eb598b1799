//! The replay's step: one row at a time through the estimator ([`Replayer`]), what it hands on of
//! each row ([`StepView`]), and the sample grid followed beside it ([`GridFollower`]).

use super::loss_cadence::LossCadence;
use super::{sample_of, HostEstimator, Replay, ReplayError};
use crate::formats::log_csv::{LogError, LogLine, RowFilter};
use crate::formats::time_stamps::IntervalCheck;
use estimator_core::time_grid::{Placement, TimeGrid};
use estimator_core::{Config, ErrorChange, Output, Real, SampleError};

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

/// One row as the replay saw it: handed to the caller of [`Replayer::push`] after the step.
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

/// The estimator stepped a row at a time: what [`super::LogReplay`] runs, and what a caller that
/// hands the same rows to several estimators runs itself. Unreadable rows go through the filter
/// (skipped and counted, `warn` told; or refused when strict). The stamps are checked
/// ([`IntervalCheck`]) unless they were binned. After the first row at or after each restart time
/// the estimator is checkpointed, dropped and restored from the bytes.
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
    loss: LossCadence,
}

impl<'a> Replayer<'a> {
    /// A fresh estimator of `config`, restarted from its checkpoint after the rows at
    /// `restart_at_s` (ascending; [`super::LogReplay::restart_at_s`]), its unreadable rows through
    /// `filter`.
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
            loss: LossCadence::default(),
        })
    }

    /// Leaves the rows' stamps unchecked: they were checked as they were binned, and the bins
    /// are one interval apart.
    pub(super) fn leave_stamps_to_the_binning(&mut self) {
        self.check_stamps = false;
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
        if let Some(p) = placement {
            self.loss.observe(p);
        }
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
            regular_loss: est.sample_interval_s().and_then(|dt| self.loss.regular(dt)),
        }
    }
}
