//! A sample's way from the sample grid to the filter: the gap filler, the rotation monitor, the
//! window and the filter's update, with bounded work a step.
//!
//! [`Estimator::step`] hands each accepted sample, once the grid's interval is known and the sway
//! gate is open, to `Estimator::feed`: it is placed on the grid (its index), passed through the
//! gap filler ([`crate::gap_fill`]), whose delay line lets it out once its weight is known, and
//! the window takes what comes out (`Estimator::take`). The rotation monitor
//! ([`crate::rotation_pattern`]) watches each sample the window takes: a fault restarts the
//! window, a newly known period sets it. The filter updates at most once a step, and not in a
//! step that did a second sample's work: a step's work is at most [`MAX_WORK_PER_STEP`] window
//! operations and [`MAX_SAMPLES_PER_STEP`] samples, whatever the log's gaps.

use super::{Estimator, Feed, MAX_SAMPLES_PER_STEP, MAX_WORK_PER_STEP};
use crate::gap_fill::{GridSample, Passed};
use crate::installation::Angles;
use crate::math::wrap_pi;
use crate::methods::windowed::change::Alarm;
use crate::output::{ErrorChange, Status};
use crate::rotation_pattern::{PatternEvent, RotationFault, RotationMonitor};
use crate::sample::Sample;
use crate::time_grid::Placement;
use crate::Real;

impl<const CAP: usize> Estimator<CAP> {
    /// Places an accepted sample on the grid, passes it through the gap filler and the window
    /// takes what comes out; returns the status of the newest sample the window took.
    pub(super) fn feed(
        &mut self,
        sample: &Sample,
        angles: &Angles,
        placement: Placement,
        interval_s: f64,
        stamp_s: f64,
    ) -> Status {
        let (feed, restart) = match self.run.feed {
            None => (self.start_feeding(interval_s), false),
            Some(feed) => {
                let (step, restart) = match placement {
                    Placement::OnGrid { intervals } => (
                        intervals,
                        intervals.saturating_sub(1) >= self.restart_gap_samples(&feed),
                    ),
                    Placement::Learning | Placement::ClockStep => (1, true),
                };
                self.run.index = self.run.index.wrapping_add(step);
                (feed, restart)
            }
        };
        let grid_sample = GridSample {
            index: self.run.index,
            roll_rad: sample.attitude.roll_rad,
            pitch_rad: sample.attitude.pitch_rad,
            rotation_rad: sample.rotation_rad,
            rotation_minus_platform_rad: wrap_pi(sample.rotation_rad - sample.platform_rad),
            latitude_rad: sample.latitude_rad,
            // The heading with eq (2)'s oscillation for the estimate so far taken out: its rate is
            // the ship's turn (the heel in turns), not the installation errors' oscillation.
            heading_rad: match self.method.estimate(&self.config) {
                Some(e) => {
                    let row = angles.heading_row();
                    let d: Real = row.iter().zip(&e.x_rad).map(|(a, b)| a * b).sum();
                    wrap_pi(sample.attitude.heading_rad - d)
                }
                None => sample.attitude.heading_rad,
            },
            angles: *angles,
            fill_weight: 0,
        };
        self.run
            .filler
            .push(&grid_sample, restart, self.config.max_filled_gap_samples);
        self.take(feed, stamp_s);
        self.run.window_status
    }

    /// Lost rows in a row from which the window restarts rather than leaving them out: an eighth
    /// of the rotation period once known (a gap of an eighth of a period or more is not bridged);
    /// half the shortest period while it is being learned (the samples since the first row are kept
    /// for the first window, and gaps must not restart the period's detection).
    fn restart_gap_samples(&self, feed: &Feed) -> u32 {
        let fill = self.config.max_filled_gap_samples + 1;
        match self.run.rotation.period_samples() {
            Some(p) => (p / 8).max(fill),
            None => (feed.limits.min_period_samples / 2).max(fill),
        }
    }

    /// The first sample on a known grid: the grid's constants are fixed, the rotation monitor
    /// starts (with the pinned period in samples, if any, and the window set to it).
    fn start_feeding(&mut self, interval_s: f64) -> Feed {
        // The reference's stage gain once the first sample reaches the window (`Estimator::take`).
        let feed = Feed::without_alpha(interval_s, &self.config);
        self.run.feed = Some(feed);
        self.run.index = 0;
        let pinned = self
            .config
            .rotation_period_s
            .map(|t| libm::round(t / interval_s).max(2.0) as u32);
        self.run.rotation = RotationMonitor::new(pinned);
        match pinned {
            Some(p) => self.method.configure(p),
            None => self
                .method
                .expect_period(expected_period_samples(interval_s)),
        }
        self.run.window_status = Status::DetectingPattern;
        feed
    }

    /// The window takes what the filler passes on, then the filter updates once. `stamp_s` is the
    /// time stamp of the newest sample received (at grid index `self.run.index`).
    ///
    /// # Bounded work a step
    /// Normally one sample comes out of the filler a step and the window takes it, removing the
    /// entry that leaves it; the filter then updates. A run of lost rows left out makes the samples
    /// before it ready at once, but needs no catching up: the window takes one a step, and steps
    /// over the run at once when it reaches it. A filled row, though, is a sample more for the
    /// window than the log gave a step for: the filler's `backlog`, made up by a second sample in a
    /// later step. And the window must drop the entries of a run's grid numbers a period later, a
    /// few a push. A step takes a second sample only while samples are waiting and when the first
    /// was not filled (a fill is the costliest sample; the second is never one), and does not
    /// update the filter when it took two, when it filled one, or when the window removed more than
    /// one entry (its work was then a second sample's); the window takes no measurement while it
    /// holds more than one period.
    ///
    /// The first sample to reach the window sets the reference's stage gain in the grid's
    /// constants (`feed`, and the ones kept: [`Feed::without_alpha`]).
    fn take(&mut self, feed: Feed, stamp_s: f64) {
        let mut feed = feed;
        let mut work = 0;
        let mut took = 0;
        let mut filled = false;
        while took < MAX_SAMPLES_PER_STEP && work < MAX_WORK_PER_STEP {
            if took > 0 && (filled || self.run.filler.backlog() == 0) {
                break;
            }
            // A second sample is never a filled one (a fill is the costliest sample).
            let Some(passed) = self.run.filler.pass_on(took == 0) else {
                break;
            };
            if feed.alpha_due {
                feed = self.set_reference_alpha(feed);
            }
            filled = passed.sample.fill_weight > 0;
            took += 1;
            work += 1 + self.take_one(&passed, &feed, stamp_s);
        }
        // A filled sample is a sample's work and a fill's: the filter waits for the next step.
        if took > 0 && work <= 2 && !filled {
            if let Some(alarm) =
                self.method
                    .update(&self.config, &feed, self.run.filler.single_fill_variance())
            {
                self.record_error_change(&alarm, &feed, stamp_s);
            }
        }
    }

    /// The grid's constants with the reference's stage gain set, kept. Out of line and cold, as
    /// [`Estimator::record_error_change`].
    #[cold]
    #[inline(never)]
    fn set_reference_alpha(&mut self, feed: Feed) -> Feed {
        let feed = feed.with_alpha();
        self.run.feed = Some(feed);
        feed
    }

    /// Keeps a change of the errors the filter declared at the sample stamped `stamp_s`. Out of
    /// line and cold: inlined, the compiler would begin its double-precision arithmetic (a library
    /// call on the Cortex-M4F) on the step's path before knowing whether there was a change.
    #[cold]
    #[inline(never)]
    fn record_error_change(&mut self, alarm: &Alarm, feed: &Feed, stamp_s: f64) {
        // The run's first block began `run_blocks` blocks of half a window before this update.
        let entry_s = feed.interval_s * f64::from(self.rotation().samples_per_entry);
        let window_s = entry_s * self.method.window_len() as f64;
        self.run.counters.changes_detected = self.run.counters.changes_detected.saturating_add(1);
        self.run.error_change = Some(ErrorChange {
            detected_s: stamp_s,
            seen_since_s: stamp_s - f64::from(alarm.run_blocks) * 0.5 * window_s,
            relearned: alarm.changed,
        });
    }

    /// The window takes one sample; returns how many old entries it removed.
    fn take_one(&mut self, passed: &Passed, feed: &Feed, stamp_s: f64) -> u32 {
        let s = &passed.sample;
        if passed.restart {
            self.restart_window();
            self.run.rotation.restart();
        }
        if s.fill_weight > 0 {
            self.run.counters.filled = self.run.counters.filled.saturating_add(1);
        }
        let observed = self
            .run
            .rotation
            .observe(s.index, s.rotation_rad, &feed.limits);
        if self.run.rotation.period_samples().is_none() {
            // The pattern is being learned anew: no window of the old period goes on filling.
            self.method.forget_period();
        }
        match observed {
            Err(fault) => {
                if !matches!(self.run.window_status, Status::RotationFault(_)) {
                    let behind = f64::from(self.run.index.wrapping_sub(s.index));
                    self.run.fault = Some((fault, stamp_s - behind * feed.interval_s));
                }
                self.restart_window();
                if fault != RotationFault::RateMismatch {
                    self.run.rotation.after_fault();
                }
                self.run.window_status = Status::RotationFault(fault);
                return 0;
            }
            Ok(PatternEvent::PeriodKnown(period)) => self.method.configure(period),
            Ok(PatternEvent::None) => {}
        }
        // The window keeps the samples from the first row on while the period is being learned,
        // so that it holds a whole period as soon as the period is known.
        let removed = self.method.push(
            &self.config,
            feed,
            s,
            passed.weight,
            self.run.rotation.period_samples().is_some(),
        );
        self.run.window_status = if self.run.rotation.period_samples().is_none() {
            Status::DetectingPattern
        } else if self.method.window_full() {
            Status::Estimating
        } else {
            Status::WarmingUp
        };
        removed
    }

    pub(super) fn restart_window(&mut self) {
        self.method.restart_window();
        self.run.counters.window_restarts = self.run.counters.window_restarts.saturating_add(1);
        self.run.window_status = if self.run.rotation.period_samples().is_some() {
            Status::WarmingUp
        } else {
            Status::DetectingPattern
        };
    }
}

/// The rotation period expected while the pattern is learned, s: the paper's. At rates whose
/// period does not fit the window one sample an entry (above about 1.5 Hz at 480 s), the window
/// bins as this period needs from the first sample, so that the samples gathered while the period
/// is learned stay when it comes out at this (a period that needs another bin starts the window
/// afresh).
pub const EXPECTED_PERIOD_S: f64 = 480.0;

/// [`EXPECTED_PERIOD_S`] in samples of `interval_s`. A rate within 10 % of a whole number of
/// samples a second (2 or more) counts as that number: the interval is first learned from a few
/// stamps, which jitter of up to half an interval leaves several percent off before the grid
/// refines it, and the bin chosen for the period should not depend on that.
pub(super) fn expected_period_samples(interval_s: f64) -> u32 {
    let rate_hz = 1.0 / interval_s;
    let whole_hz = libm::round(rate_hz);
    let samples = if whole_hz >= 2.0 && libm::fabs(rate_hz - whole_hz) < 0.1 * whole_hz {
        EXPECTED_PERIOD_S * whole_hz
    } else {
        libm::round(EXPECTED_PERIOD_S / interval_s)
    };
    samples.clamp(2.0, f64::from(u32::MAX)) as u32
}
