//! The estimator: checks each sample, places it on the sample grid, fills short gaps, watches the
//! rotation pattern and the sway gate, drives the selected method and corrects the attitude.
//!
//! # One step
//! 1. **Checks** (every one before any state changes): a field NaN or infinite, |latitude| >= 90
//!    deg, |roll| or |pitch| > 90 deg or a wrapped angle beyond 360 deg ([`Sample::check`]); a time
//!    stamp that repeats or goes back less than two intervals ([`crate::time_grid`]). A rejected
//!    sample returns a [`SampleError`], is counted by reason and leaves the estimator exactly as it
//!    was.
//! 2. **Grid** ([`crate::time_grid`]): the sample interval is pinned or learned from the first
//!    stamps; jitter snaps; a clock jump or step backwards is counted and treated as a gap.
//! 3. **Gate**: with `sway_gate_rad > 0`, nothing is estimated until the roll sway amplitude
//!    (sqrt(2) times the RMS of roll about its mean, exponentially averaged over 64 samples) exceeds
//!    the gate, as in the paper's sea test; once open it stays open.
//! 4. **Gaps** ([`crate::gap_fill`]): up to `max_filled_gap_samples` lost in a row are filled from
//!    their neighbours (the window runs [`crate::gap_fill::NEIGHBOURS`] samples behind); a longer
//!    gap or a clock step restarts the moving average and the estimates hold ([`Status::Holding`])
//!    for one period.
//! 5. **Rotation** ([`crate::rotation_pattern`]): the pattern's period is pinned or detected, its
//!    shape learned over the next cycle; a sample that breaks the pattern is a
//!    [`Status::RotationFault`]: the window restarts, the estimates freeze, and estimation resumes
//!    one full window after the rotation repeats its pattern again.
//! 6. **Method** ([`crate::methods`]): the window takes the sample; the filter updates at most once
//!    a step.
//! 7. **Output**: the estimate, a [`Status`], and this sample's attitude with eq (2)'s oscillation
//!    for the current estimate removed.
//!
//! When there is no estimate, [`Estimator::progress`] says what holds it back.

pub(crate) mod checkpoint;
mod compensate;
mod feed;

use compensate::corrected;
pub use compensate::CompensateError;

use core::ptr::addr_of_mut;

use crate::config::{Config, ConfigError, ROTATION_PERIOD_RANGE_S};
use crate::correlation::ReferenceFilter;
use crate::gap_fill::GapFiller;
use crate::methods::MethodState;
use crate::output::{
    Counters, ErrorChange, Estimate, Health, Holdup, Output, RejectCounts, RotationSummary, Status,
};
use crate::rotation_pattern::{Limits, RotationFault, RotationMonitor};
use crate::sample::{Sample, SampleError};
use crate::sway_gate::SwayMonitor;
use crate::time_grid::{Placement, TimeGrid};
use crate::Real;

/// Most samples the window takes in one step (see `Estimator::take`).
pub const MAX_SAMPLES_PER_STEP: u32 = 2;
/// Most window operations (a sample taken, an old entry removed) in one step.
pub const MAX_WORK_PER_STEP: u32 = 4;

/// The ring capacity of the default estimator, in window entries: one period of up to 720 samples
/// without bins (720 s at 1 Hz); longer periods are binned. The ring is most of the estimator's
/// state, which stays under half the firmware's static RAM budget (its size and the limit a test
/// holds it to: docs/results.md).
pub const DEFAULT_CAPACITY: usize = 720;

/// The constants of the sample grid, fixed when samples start to be fed (from the interval known
/// then; a learned interval refined later does not change them, so a run is the same whether or
/// not it was restored from a checkpoint in between).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feed {
    /// The sample interval, s.
    pub interval_s: f64,
    /// The same, in the step's float type.
    pub interval: Real,
    /// Shortest and longest rotation period and the period tolerance, for the rotation monitor.
    pub limits: Limits,
    /// The stage gain of the correlation reference's low-pass (while `alpha_due`, not yet set).
    pub reference_alpha: Real,
    /// The stage gain is still to be computed ([`Feed::without_alpha`]).
    pub(crate) alpha_due: bool,
}

impl Feed {
    /// The constants for `interval_s`.
    pub fn new(interval_s: f64, config: &Config) -> Feed {
        Feed::without_alpha(interval_s, config).with_alpha()
    }

    /// [`Feed::new`] but for the reference's stage gain, which waits for [`Feed::with_alpha`]: its
    /// double-precision exponential, a library call on the Cortex-M4F, would be the costliest
    /// part of the step that starts feeding, where nothing uses it yet (the gap filler holds the
    /// first samples back; `Estimator::take` sets it when the first reaches the window).
    pub(crate) fn without_alpha(interval_s: f64, config: &Config) -> Feed {
        Feed {
            interval_s,
            interval: interval_s as Real,
            limits: Limits {
                min_period_samples: libm::ceil(ROTATION_PERIOD_RANGE_S.0 / interval_s).max(2.0)
                    as u32,
                max_period_samples: libm::floor(ROTATION_PERIOD_RANGE_S.1 / interval_s).max(2.0)
                    as u32,
                period_tolerance: config.rotation_period_tolerance,
            },
            reference_alpha: 0.0,
            alpha_due: true,
        }
    }

    /// The same constants with the reference's stage gain set.
    pub(crate) fn with_alpha(self) -> Feed {
        Feed {
            reference_alpha: ReferenceFilter::alpha(self.interval_s),
            alpha_due: false,
            ..self
        }
    }
}

/// The installation-error estimator, with a ring capacity of `CAP` window entries.
///
/// # Example
/// Configure, step once a sample, read the estimate. The samples here are a ship's roll and pitch
/// sway (periods of 8 and 11 s) plus eq (2)'s oscillation for known errors, on a one-way rotation
/// of 480 s at 1 Hz; the estimator learns the interval and the period from them.
///
/// ```
/// use core::f64::consts::TAU;
/// use estimator_core::installation::Angles;
/// use estimator_core::units::{arcsec_to_rad, rad_to_arcsec, EARTH_RATE_RAD_PER_S};
/// use estimator_core::{Config, Estimator, Real, Sample, Status};
///
/// let x_arcsec = [200.0, -150.0, 300.0, -250.0]; // the installation errors to find
/// let x_rad = x_arcsec.map(|x| arcsec_to_rad(x) as Real);
/// let latitude_deg: f64 = 30.0;
/// let mut estimator: Estimator = Estimator::new(Config::default())?;
/// let mut last = None;
/// for k in 0..4000 {
///     let t_s = f64::from(k);
///     let rotation_deg = 360.0 * t_s / 480.0;
///     let platform_deg = (EARTH_RATE_RAD_PER_S * t_s).to_degrees();
///     let lat = latitude_deg.to_radians() as Real;
///     let rows = Angles::new(rotation_deg.to_radians() as Real, platform_deg.to_radians() as Real, (lat.sin(), lat.cos()));
///     let error = rows.oscillation(&x_rad); // eq (2): what the errors do to the attitude
///     let roll_deg = 3.0 * (TAU * t_s / 8.0).sin() + f64::from(error.roll_rad).to_degrees();
///     let pitch_deg = 1.0 * (TAU * t_s / 11.0).sin() + f64::from(error.pitch_rad).to_degrees();
///     let heading_deg = 45.0 + f64::from(error.heading_rad).to_degrees();
///     let sample = Sample::from_degrees(t_s, rotation_deg, platform_deg, latitude_deg, heading_deg, roll_deg, pitch_deg);
///     // A bad sample comes back as an error and changes nothing.
///     last = Some(estimator.step(&sample).expect("a healthy sample"));
/// }
/// let output = last.expect("4000 outputs");
/// assert_eq!(output.status, Status::Converged);
/// let estimate = output.estimate.expect("an estimate after 4000 s");
/// for i in 0..4 {
///     let error_arcsec = rad_to_arcsec(f64::from(estimate.x_rad[i])) - x_arcsec[i];
///     assert!(error_arcsec.abs() < 1.0, "x{}: off by {error_arcsec:.2} arcsec", i + 1);
/// }
/// # Ok::<(), estimator_core::ConfigError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Estimator<const CAP: usize = DEFAULT_CAPACITY> {
    config: Config,
    method: MethodState<CAP>,
    /// Everything else a step changes.
    run: RunState,
}

/// What the estimator keeps besides its configuration and its method: the sample grid, the gap
/// filler, the rotation monitor, the sway gate, the status and the counters. One value made by
/// [`RunState::new`], so that every way of making or resetting an estimator starts it the same.
#[derive(Clone, Debug, PartialEq)]
struct RunState {
    grid: TimeGrid,
    /// Grid index of the last accepted sample, once the grid is known.
    index: u32,
    /// Once samples are fed to the filler (interval known, gate open): the constants of the grid.
    feed: Option<Feed>,
    filler: GapFiller,
    rotation: RotationMonitor,
    /// Cached `(L, sin L, cos L)`.
    latitude_trig: (Real, Real, Real),
    sway: SwayMonitor,
    gate_open: bool,
    /// Status of the newest sample the window took.
    window_status: Status,
    /// The last rotation fault and the time stamp it began at.
    fault: Option<(RotationFault, f64)>,
    rejected: RejectCounts,
    counters: Counters,
    /// The last change of the errors the windowed method declared.
    error_change: Option<ErrorChange>,
    /// The rotation angle of the last accepted sample, rad, and the rate of the rotation angle
    /// over the last step on the grid, rad/s: what carries a lagging rotation angle forward
    /// ([`Config::angle_latency_s`]; neither is kept while the latency is 0). Not in the
    /// checkpoint: after a restore the rate is learned again from the first two samples.
    last_rotation_rad: Option<Real>,
    rotation_rate_rad_s: Real,
}

impl RunState {
    /// Nothing seen yet under `config`. Inlined, so that [`Estimator::init_in`] writes it into its
    /// place rather than building it on the stack (the gap filler's delay line is most of it).
    #[inline(always)]
    fn new(config: &Config) -> RunState {
        RunState {
            grid: TimeGrid::new(config.sample_interval_s),
            index: 0,
            feed: None,
            filler: GapFiller::new(),
            rotation: RotationMonitor::new(None),
            latitude_trig: (0.0, 0.0, 1.0),
            sway: SwayMonitor::NEW,
            gate_open: config.sway_gate_rad == 0.0,
            window_status: Status::DetectingPattern,
            fault: None,
            rejected: RejectCounts::ZERO,
            counters: Counters::ZERO,
            error_change: None,
            last_rotation_rad: None,
            rotation_rate_rad_s: 0.0,
        }
    }
}

impl Estimator<DEFAULT_CAPACITY> {
    /// [`Estimator::step`] at the default capacity, compiled in this crate at its own optimisation
    /// level. A firmware built for size calls this one: the step, its hot path, keeps the speed
    /// its instruction budget is measured at while the rest of the image is optimised for size.
    #[inline(never)]
    pub fn step_default_capacity(&mut self, sample: &Sample) -> Result<Output, SampleError> {
        self.step(sample)
    }
}

impl<const CAP: usize> Estimator<CAP> {
    /// A fresh estimator, or why the configuration cannot run.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        config.check(CAP)?;
        Ok(Estimator {
            config,
            method: MethodState::new(&config),
            run: RunState::new(&config),
        })
    }

    /// Makes a fresh estimator in `slot`, in place, and returns it; or returns why the
    /// configuration cannot run (and leaves `slot` as it was). The same as [`Estimator::new`],
    /// without building the state (tens of KB for the default capacity, most of it the window) on
    /// the stack and copying it: how a microcontroller, whose stack is a few KiB, makes its
    /// estimator in a static, and how the C library makes one in the caller's memory. Every field
    /// is written in place, the window's ring not at all (it is uninitialised until it fills);
    /// then the state is reset to `config` in place ([`Estimator::reset`]'s way). The firmware's
    /// start-up stack peak, a fraction of the state's size (both in docs/firmware.md, "Measured
    /// figures"), shows that nothing the size of the state is copied.
    ///
    /// ```
    /// use core::mem::MaybeUninit;
    /// use estimator_core::{Config, Estimator};
    /// let mut slot: Box<MaybeUninit<Estimator>> = Box::new(MaybeUninit::uninit());
    /// let estimator = Estimator::init_in(&mut slot, Config::default())?;
    /// assert!(estimator.estimate().is_none());
    /// # Ok::<(), estimator_core::ConfigError>(())
    /// ```
    pub fn init_in(
        slot: &mut core::mem::MaybeUninit<Self>,
        config: Config,
    ) -> Result<&mut Self, ConfigError> {
        config.check(CAP)?;
        let p = slot.as_mut_ptr();
        // SAFETY: each of the three fields of `*p` is written (through raw pointers, never read)
        // before `p` is made a reference: the configuration, the windowed method's state whose
        // ring is uninitialised (`heapless::Deque::new` stores nothing in it) and the run state.
        let estimator = unsafe {
            addr_of_mut!((*p).config).write(config);
            addr_of_mut!((*p).method).write(MethodState::Windowed(
                crate::methods::Windowed::unconfigured(),
            ));
            addr_of_mut!((*p).run).write(RunState::new(&config));
            slot.assume_init_mut()
        };
        // The windowed method resets in place; another method's state is built by value (see
        // `MethodState::reset`).
        estimator.reinit(config)?;
        Ok(estimator)
    }

    /// Forgets everything learnt (keeps the configuration and the rejection counters). In place:
    /// nothing the size of the estimator passes through the stack.
    pub fn reset(&mut self) {
        let rejected = self.run.rejected;
        // The configuration passed its check when this estimator was made.
        if self.reinit(self.config).is_ok() {
            self.run.rejected = rejected;
        }
    }

    /// Becomes, in place, what [`Estimator::new`]`(config)` returns (`tests::reinit_equals_new`),
    /// or returns why the configuration cannot run and changes nothing. Used by [`Estimator::reset`]
    /// and by checkpoint restore, so that neither needs a second estimator on the stack.
    pub(crate) fn reinit(&mut self, config: Config) -> Result<(), ConfigError> {
        config.check(CAP)?;
        self.method.reset(&config);
        self.config = config;
        self.run = RunState::new(&config);
        Ok(())
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Rejected samples by reason.
    pub fn rejected(&self) -> RejectCounts {
        self.run.rejected
    }

    /// What has been counted.
    pub fn counters(&self) -> Counters {
        self.run.counters
    }

    /// The sample interval, s, once pinned or learned.
    pub fn sample_interval_s(&self) -> Option<f64> {
        self.run.grid.interval_s()
    }

    /// The time stamp of the last accepted sample, s.
    pub fn last_sample_time_s(&self) -> Option<f64> {
        self.run.grid.last_stamp_s()
    }

    /// The rotation pattern as far as it is known.
    pub fn rotation(&self) -> RotationSummary {
        let period_s = match (
            self.run.rotation.period_samples(),
            self.run.grid.interval_s(),
        ) {
            (Some(p), Some(dt)) if self.run.feed.is_some() => Some(f64::from(p) * dt),
            _ => None,
        };
        RotationSummary {
            period_s,
            pinned: self.config.rotation_period_s.is_some(),
            kind: self.run.rotation.features().map(|f| f.kind()),
            samples_per_entry: match &self.method {
                MethodState::Windowed(m) => m.window().bin(),
                #[allow(unreachable_patterns)]
                _ => 1,
            },
        }
    }

    /// What holds the estimate back, if anything does.
    pub fn progress(&self) -> Option<Holdup> {
        if !self.run.gate_open {
            return Some(Holdup::WaitingForSway);
        }
        if self.run.grid.placing_interval_s().is_none() {
            return Some(Holdup::SampleIntervalNotKnown);
        }
        if self.run.rotation.period_samples().is_none() {
            return Some(Holdup::RotationPeriodNotDetected);
        }
        if let (Status::RotationFault(fault), Some((_, since_s))) =
            (self.run.window_status, self.run.fault)
        {
            return Some(Holdup::RotationFault { fault, since_s });
        }
        match &self.method {
            MethodState::Windowed(m) if !m.window().has_spanned_a_period() => {
                Some(Holdup::WindowFilling {
                    filled: m.window().filled() as u32,
                    len: m.window().len() as u32,
                })
            }
            _ => None,
        }
    }

    /// The windowed method's state (its window, filter and residual check), for inspection; `None`
    /// for the other methods.
    pub fn windowed(&self) -> Option<&crate::methods::Windowed<CAP>> {
        match &self.method {
            MethodState::Windowed(m) => Some(m),
            #[allow(unreachable_patterns)]
            _ => None,
        }
    }

    /// The last change of the installation errors declared (windowed method), if any: when, and
    /// which errors are learned again.
    pub fn error_change(&self) -> Option<ErrorChange> {
        self.run.error_change
    }

    /// The latched alarms and the residuals' level now ([`Output::health`]).
    pub fn health(&self) -> Health {
        let c = &self.run.counters;
        // Double-precision arithmetic is a library call on the Cortex-M4F: none while nothing
        // was in mismatch (nearly every step).
        let mismatch_s = match c.mismatch_samples {
            0 => 0.0,
            n => f64::from(n) * self.run.grid.interval_s().unwrap_or(0.0),
        };
        let (residual_rad, noise_scale) = match &self.method {
            MethodState::Windowed(m) if m.estimate(&self.config).is_some() => {
                let (r, s) = m.pair_levels();
                (Some(r), Some(s))
            }
            _ => (None, None),
        };
        Health {
            changes_detected: c.changes_detected,
            last_change_s: self.run.error_change.map(|e| e.detected_s),
            window_restarts: c.window_restarts,
            rejected: self.run.rejected.total(),
            mismatch_s,
            residual_rad,
            noise_scale,
        }
    }

    /// The current estimate as a record every later version reads ([`crate::learned`]), with the
    /// time of the last sample; `None` while there is no estimate.
    // The casts are the f64 build's; in the default build `Real` is f32 already.
    #[allow(clippy::unnecessary_cast)]
    pub fn learned_errors(&self) -> Option<crate::learned::LearnedErrors> {
        let e = self.estimate()?;
        Some(crate::learned::LearnedErrors {
            time_s: self.run.grid.last_stamp_s().unwrap_or(0.0),
            x_rad: e.x_rad.map(|x| x as f32),
            sigma_rad: e.sigma_rad.map(|s| s as f32),
        })
    }

    /// Starts afresh from a record of learned errors, as from known values: the configuration's
    /// prior becomes the record's ([`crate::learned::LearnedErrors::prior`]), everything else is
    /// forgotten (as [`Estimator::reset`]), and the record's estimate is reported, and compensates,
    /// from the next sample. For a build that refused a checkpoint of another version.
    pub fn start_from_learned(
        &mut self,
        learned: &crate::learned::LearnedErrors,
    ) -> Result<(), ConfigError> {
        let config = Config {
            prior: Some(learned.prior(self.config.prior_sigma_rad)),
            ..self.config
        };
        let rejected = self.run.rejected;
        self.reinit(config)?;
        self.run.rejected = rejected;
        Ok(())
    }

    /// The current estimate, if any.
    pub fn estimate(&self) -> Option<Estimate> {
        self.method.estimate(&self.config).map(|e| Estimate {
            x_rad: e.x_rad,
            sigma_rad: e.sigma_rad,
        })
    }

    /// Processes one sample. On error nothing changes but the rejection counter.
    pub fn step(&mut self, sample: &Sample) -> Result<Output, SampleError> {
        let placed = match sample
            .check()
            .and_then(|()| self.run.grid.place(sample.time_s))
        {
            Ok(p) => p,
            Err(e) => {
                self.run.rejected.count(e.reason());
                return Err(e);
            }
        };
        self.run.grid.accept(sample.time_s, placed);
        let placement = placed.placement;
        let carried = self.carry_rotation(sample, placement);
        let sample = &carried;
        self.run.counters.accepted = self.run.counters.accepted.saturating_add(1);
        if placement == Placement::ClockStep {
            self.run.counters.clock_steps = self.run.counters.clock_steps.saturating_add(1);
        }
        let angles = self.angles(sample);
        self.run.sway.observe(sample.attitude.roll_rad);
        if !self.run.gate_open && self.run.sway.opens(self.config.sway_gate_rad) {
            self.run.gate_open = true;
        }
        let status = match self.run.grid.placing_interval_s() {
            Some(interval_s) if self.run.gate_open => {
                self.feed(sample, &angles, placement, interval_s, sample.time_s)
            }
            _ if !self.run.gate_open => Status::WaitingForSway,
            _ => Status::DetectingPattern,
        };
        let estimate = self.method.estimate(&self.config);
        let status = match (status, estimate) {
            (Status::Estimating | Status::WarmingUp, Some(e)) if e.relearning => {
                Status::ErrorsChanged
            }
            (Status::Estimating, Some(e)) if e.mismatch => Status::ModelMismatch,
            (Status::Estimating, Some(e))
                if e.sigma_rad
                    .iter()
                    .all(|s| *s < self.config.converged_sigma_rad) =>
            {
                Status::Converged
            }
            (Status::WarmingUp, Some(_)) => Status::Holding,
            // A window just full, its first measurement not yet taken (the step that filled it
            // also removed the first window's last extra entries: its update waits a step).
            (Status::Estimating, None) => Status::WarmingUp,
            (s, _) => s,
        };
        let estimate = estimate.map(|e| Estimate {
            x_rad: e.x_rad,
            sigma_rad: e.sigma_rad,
        });
        if status == Status::ModelMismatch {
            self.run.counters.mismatch_samples =
                self.run.counters.mismatch_samples.saturating_add(1);
        }
        let corrected = match estimate {
            Some(e) => corrected(&angles, &sample.attitude, &e.x_rad),
            None => sample.attitude,
        };
        Ok(Output {
            time_s: sample.time_s,
            status,
            estimate,
            corrected,
            health: self.health(),
        })
    }
}

/// The parts, for the checkpoint tests of each part (next to the part's type).
#[cfg(test)]
impl<const CAP: usize> Estimator<CAP> {
    pub(crate) fn grid_for_test(&self) -> TimeGrid {
        self.run.grid
    }
    pub(crate) fn rotation_for_test(&self) -> RotationMonitor {
        self.run.rotation
    }
    pub(crate) fn filler_for_test(&self) -> &GapFiller {
        &self.run.filler
    }
    pub(crate) fn method_for_test(&self) -> &MethodState<CAP> {
        &self.method
    }
}

#[cfg(test)]
mod tests;
