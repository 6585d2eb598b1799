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

use crate::config::{Config, ConfigError, ROTATION_PERIOD_RANGE_S};
use crate::correlation::ReferenceFilter;
use crate::gap_fill::{GapFiller, GridSample, SLOTS};
use crate::installation::Angles;
use crate::math::{sin_cos, sqrt, wrap_pi};
use crate::methods::MethodState;
pub use crate::rotation_pattern::RotationFault;
use crate::rotation_pattern::{Limits, PatternEvent, PatternKind, RotationMonitor};
use crate::sample::{Attitude, Sample, SampleError};
use crate::time_grid::{Placement, TimeGrid};
use crate::Real;

/// The ring capacity of the default estimator, in window entries: one period of up to 720 samples
/// without bins (720 s at 1 Hz); longer periods are binned. 30 bytes an entry (the inputs and a
/// fill weight): the estimator's state stays within 24 KiB.
pub const DEFAULT_CAPACITY: usize = 720;

/// What the estimator is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The sway gate has not opened yet.
    WaitingForSway,
    /// This sample's rotation breaks the learned pattern; estimates are frozen.
    RotationFault(RotationFault),
    /// The first window is filling; no estimate yet.
    WarmingUp,
    /// The window is refilling after a long gap or a rotation fault; estimates are frozen.
    Holding,
    /// The filter is updating; not every error is below `converged_sigma_rad` yet.
    Estimating,
    /// The filter is updating and every error's 1-sigma is below `converged_sigma_rad`.
    Converged,
    /// The filter is updating but its residuals show a bias the model does not explain (drifting
    /// errors, coloured noise): the 1-sigma has been widened to match.
    ModelMismatch,
    /// The sample interval or the rotation pattern's period is not known yet; estimates are
    /// frozen (or none yet).
    DetectingPattern,
}

impl Status {
    /// Every status, in code order.
    pub const ALL: [Status; 10] = [
        Status::WaitingForSway,
        Status::RotationFault(RotationFault::Stopped),
        Status::RotationFault(RotationFault::Reversed),
        Status::RotationFault(RotationFault::RateMismatch),
        Status::WarmingUp,
        Status::Holding,
        Status::Estimating,
        Status::Converged,
        Status::ModelMismatch,
        Status::DetectingPattern,
    ];

    /// Short name used in files.
    pub fn name(&self) -> &'static str {
        match self {
            Status::WaitingForSway => "waiting_for_sway",
            Status::RotationFault(RotationFault::Stopped) => "rotation_stopped",
            Status::RotationFault(RotationFault::Reversed) => "rotation_reversed",
            Status::RotationFault(RotationFault::RateMismatch) => "rotation_rate_mismatch",
            Status::WarmingUp => "warming_up",
            Status::Holding => "holding",
            Status::Estimating => "estimating",
            Status::Converged => "converged",
            Status::ModelMismatch => "model_mismatch",
            Status::DetectingPattern => "detecting_pattern",
        }
    }

    /// Code used on the firmware link (its index in [`Status::ALL`]).
    pub fn code(&self) -> u8 {
        match self {
            Status::WaitingForSway => 0,
            Status::RotationFault(RotationFault::Stopped) => 1,
            Status::RotationFault(RotationFault::Reversed) => 2,
            Status::RotationFault(RotationFault::RateMismatch) => 3,
            Status::WarmingUp => 4,
            Status::Holding => 5,
            Status::Estimating => 6,
            Status::Converged => 7,
            Status::ModelMismatch => 8,
            Status::DetectingPattern => 9,
        }
    }

    /// Inverse of [`Status::code`].
    pub fn from_code(code: u8) -> Option<Status> {
        Status::ALL.get(usize::from(code)).copied()
    }
}

/// The four installation errors with their 1-sigma, rad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub x_rad: [Real; 4],
    pub sigma_rad: [Real; 4],
}

/// What one step returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// The sample's time stamp, s, as received.
    pub time_s: f64,
    pub status: Status,
    /// `None` until the filter has had its first measurement.
    pub estimate: Option<Estimate>,
    /// The sample's attitude minus eq (2)'s oscillation for the current estimate (unchanged while
    /// there is none). Heading wrapped to [-pi, pi].
    pub corrected: Attitude,
}

/// Rejected samples by reason (index: [`SampleError::reason_index`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RejectCounts(pub [u32; SampleError::COUNT]);

impl RejectCounts {
    /// Total rejected.
    pub fn total(&self) -> u32 {
        self.0.iter().fold(0u32, |a, b| a.saturating_add(*b))
    }
}

/// What the estimator has counted since it was made or reset (saturating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Samples accepted.
    pub accepted: u32,
    /// Lost samples filled from their neighbours.
    pub filled: u32,
    /// Restarts of the moving average (gaps too long to fill, clock steps, rotation faults).
    pub window_restarts: u32,
    /// Clock jumps and steps backwards in the time stamps.
    pub clock_steps: u32,
}

/// The rotation pattern as far as it is known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationSummary {
    /// The period, s (sample interval times samples), once pinned or detected.
    pub period_s: Option<f64>,
    /// Whether the period was pinned by the configuration.
    pub pinned: bool,
    /// The pattern's shape, once a whole cycle has been watched.
    pub kind: Option<PatternKind>,
    /// Samples per window entry (1 unless one period holds more samples than the ring).
    pub samples_per_entry: u32,
}

/// Why there is no estimate, or no fresh one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Holdup {
    /// The sway gate is closed.
    WaitingForSway,
    /// The sample interval is being learned from the time stamps.
    SampleIntervalNotKnown,
    /// The rotation pattern's period is being detected.
    RotationPeriodNotDetected,
    /// The rotation has broken its pattern since this sample time, s.
    RotationFault { fault: RotationFault, since_s: f64 },
    /// The window is filling: `filled` of `len` entries.
    WindowFilling { filled: u32, len: u32 },
}

impl core::fmt::Display for Holdup {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Holdup::WaitingForSway => write!(f, "waiting for the roll sway to exceed the start gate"),
            Holdup::SampleIntervalNotKnown => write!(f, "sample interval not yet learned from the time stamps"),
            Holdup::RotationPeriodNotDetected => write!(f, "rotation period not yet detected"),
            Holdup::RotationFault { fault, since_s } => {
                let what = match fault {
                    RotationFault::Stopped => "rotation stopped",
                    RotationFault::Reversed => "rotation reversed",
                    RotationFault::RateMismatch => "rotation no longer repeats its pattern",
                };
                write!(f, "{what} since {since_s} s")
            }
            Holdup::WindowFilling { filled, len } => write!(f, "moving average filling ({filled} of {len} entries)"),
        }
    }
}

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
    /// The stage gain of the correlation reference's low-pass.
    pub reference_alpha: Real,
}

impl Feed {
    /// The constants for `interval_s`.
    pub fn new(interval_s: f64, config: &Config) -> Feed {
        Feed {
            interval_s,
            interval: interval_s as Real,
            limits: Limits {
                min_period_samples: libm::ceil(ROTATION_PERIOD_RANGE_S.0 / interval_s).max(2.0) as u32,
                max_period_samples: libm::floor(ROTATION_PERIOD_RANGE_S.1 / interval_s).max(2.0) as u32,
                period_tolerance: config.rotation_period_tolerance,
            },
            reference_alpha: ReferenceFilter::alpha(interval_s),
        }
    }
}

/// Roll sway amplitude for the start gate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SwayMonitor {
    pub mean_rad: Real,
    pub mean_square_rad2: Real,
    pub samples: u32,
}

impl SwayMonitor {
    const SAMPLES: u32 = 64;

    fn observe(&mut self, roll_rad: Real) {
        self.samples = self.samples.saturating_add(1);
        let alpha = 1.0 / (self.samples.min(Self::SAMPLES) as Real);
        self.mean_rad += alpha * (roll_rad - self.mean_rad);
        self.mean_square_rad2 += alpha * (roll_rad * roll_rad - self.mean_square_rad2);
    }

    /// Amplitude of a sinusoid with the same RMS about the mean.
    pub fn amplitude_rad(&self) -> Real {
        let var = (self.mean_square_rad2 - self.mean_rad * self.mean_rad).max(0.0);
        sqrt(2.0 * var)
    }
}

/// The installation-error estimator, with a ring capacity of `CAP` window entries.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimator<const CAP: usize = DEFAULT_CAPACITY> {
    pub(crate) config: Config,
    pub(crate) method: MethodState<CAP>,
    pub(crate) grid: TimeGrid,
    /// Grid index of the last accepted sample, once the grid is known.
    pub(crate) index: u32,
    /// Once samples are fed to the filler (interval known, gate open): the constants of the grid.
    pub(crate) feed: Option<Feed>,
    pub(crate) filler: GapFiller,
    pub(crate) rotation: RotationMonitor,
    /// Cached `(L, sin L, cos L)`.
    pub(crate) latitude_trig: (Real, Real, Real),
    pub(crate) sway: SwayMonitor,
    pub(crate) gate_open: bool,
    /// Status of the newest sample the window took.
    pub(crate) window_status: Status,
    /// The last rotation fault and the time stamp it began at.
    pub(crate) fault: Option<(RotationFault, f64)>,
    pub(crate) rejected: RejectCounts,
    pub(crate) counters: Counters,
}

impl<const CAP: usize> Estimator<CAP> {
    /// A fresh estimator, or why the configuration cannot run.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        config.check(CAP)?;
        let (s, c) = sin_cos(0.0);
        Ok(Estimator {
            config,
            method: MethodState::new(&config),
            grid: TimeGrid::new(config.sample_interval_s),
            index: 0,
            feed: None,
            filler: GapFiller::default(),
            rotation: RotationMonitor::new(None),
            latitude_trig: (0.0, s, c),
            sway: SwayMonitor::default(),
            gate_open: config.sway_gate_rad == 0.0,
            window_status: Status::DetectingPattern,
            fault: None,
            rejected: RejectCounts::default(),
            counters: Counters::default(),
        })
    }

    /// Forgets everything learnt (keeps the configuration and the rejection counters). In place:
    /// nothing the size of the estimator passes through the stack.
    pub fn reset(&mut self) {
        let rejected = self.rejected;
        // The configuration passed its check when this estimator was made.
        if self.reinit(self.config).is_ok() {
            self.rejected = rejected;
        }
    }

    /// Becomes, in place, what [`Estimator::new`]`(config)` returns (`tests::reinit_equals_new`),
    /// or returns why the configuration cannot run and changes nothing. Used by [`Estimator::reset`]
    /// and by checkpoint restore, so that neither needs a second estimator on the stack.
    pub(crate) fn reinit(&mut self, config: Config) -> Result<(), ConfigError> {
        config.check(CAP)?;
        self.method.reset(&config);
        let (s, c) = sin_cos(0.0);
        self.config = config;
        self.grid = TimeGrid::new(config.sample_interval_s);
        self.index = 0;
        self.feed = None;
        self.filler = GapFiller::default();
        self.rotation = RotationMonitor::new(None);
        self.latitude_trig = (0.0, s, c);
        self.sway = SwayMonitor::default();
        self.gate_open = config.sway_gate_rad == 0.0;
        self.window_status = Status::DetectingPattern;
        self.fault = None;
        self.rejected = RejectCounts::default();
        self.counters = Counters::default();
        Ok(())
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Rejected samples by reason.
    pub fn rejected(&self) -> RejectCounts {
        self.rejected
    }

    /// What has been counted.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// The sample interval, s, once pinned or learned.
    pub fn sample_interval_s(&self) -> Option<f64> {
        self.grid.interval_s
    }

    /// The rotation pattern as far as it is known.
    pub fn rotation(&self) -> RotationSummary {
        let period_s = match (self.rotation.period_samples, self.grid.interval_s) {
            (Some(p), Some(dt)) if self.feed.is_some() => Some(f64::from(p) * dt),
            _ => None,
        };
        RotationSummary {
            period_s,
            pinned: self.config.rotation_period_s.is_some(),
            kind: self.rotation.features.map(|f| f.kind()),
            samples_per_entry: match &self.method {
                MethodState::Windowed(m) => m.window.bin(),
                #[allow(unreachable_patterns)]
                _ => 1,
            },
        }
    }

    /// What holds the estimate back, if anything does.
    pub fn progress(&self) -> Option<Holdup> {
        if !self.gate_open {
            return Some(Holdup::WaitingForSway);
        }
        if self.grid.interval_s.is_none() {
            return Some(Holdup::SampleIntervalNotKnown);
        }
        if self.rotation.period_samples.is_none() {
            return Some(Holdup::RotationPeriodNotDetected);
        }
        if let (Status::RotationFault(fault), Some((_, since_s))) = (self.window_status, self.fault) {
            return Some(Holdup::RotationFault { fault, since_s });
        }
        match &self.method {
            MethodState::Windowed(m) if !m.window.is_full() => {
                Some(Holdup::WindowFilling { filled: m.window.filled() as u32, len: m.window.len() as u32 })
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

    /// The current estimate, if any.
    pub fn estimate(&self) -> Option<Estimate> {
        self.method.estimate(&self.config).map(|e| Estimate { x_rad: e.x_rad, sigma_rad: e.sigma_rad })
    }

    /// Processes one sample. On error nothing changes but the rejection counter.
    pub fn step(&mut self, sample: &Sample) -> Result<Output, SampleError> {
        let placement = match sample.check().and_then(|()| self.grid.place(sample.time_s)) {
            Ok(p) => p,
            Err(e) => {
                let slot = &mut self.rejected.0[e.reason_index()];
                *slot = slot.saturating_add(1);
                return Err(e);
            }
        };
        self.grid.accept(sample.time_s, placement);
        self.counters.accepted = self.counters.accepted.saturating_add(1);
        let angles = self.angles(sample);
        self.sway.observe(sample.attitude.roll_rad);
        if !self.gate_open
            && self.sway.samples >= SwayMonitor::SAMPLES
            && self.sway.amplitude_rad() >= self.config.sway_gate_rad
        {
            self.gate_open = true;
        }
        let status = match self.grid.interval_s {
            Some(interval_s) if self.gate_open => self.feed(sample, &angles, placement, interval_s, sample.time_s),
            _ if !self.gate_open => Status::WaitingForSway,
            _ => Status::DetectingPattern,
        };
        let estimate = self.method.estimate(&self.config);
        let status = match (status, estimate) {
            (Status::Estimating, Some(e)) if e.mismatch => Status::ModelMismatch,
            (Status::Estimating, Some(e)) if e.sigma_rad.iter().all(|s| *s < self.config.converged_sigma_rad) => {
                Status::Converged
            }
            (Status::WarmingUp, Some(_)) => Status::Holding,
            (s, _) => s,
        };
        let estimate = estimate.map(|e| Estimate { x_rad: e.x_rad, sigma_rad: e.sigma_rad });
        let corrected = match estimate {
            Some(e) => {
                let d = angles.oscillation(&e.x_rad);
                Attitude {
                    heading_rad: wrap_pi(sample.attitude.heading_rad - d.heading_rad),
                    roll_rad: sample.attitude.roll_rad - d.roll_rad,
                    pitch_rad: sample.attitude.pitch_rad - d.pitch_rad,
                }
            }
            None => sample.attitude,
        };
        Ok(Output { time_s: sample.time_s, status, estimate, corrected })
    }

    /// Places an accepted sample on the grid, passes it through the gap filler and the window
    /// takes what comes out; returns the status of the newest sample the window took.
    fn feed(&mut self, sample: &Sample, angles: &Angles, placement: Placement, interval_s: f64, stamp_s: f64) -> Status {
        let mut out: heapless::Vec<GridSample, SLOTS> = heapless::Vec::new();
        let feed = match self.feed {
            None => self.start_feeding(interval_s),
            Some(feed) => {
                let (step, restart) = match placement {
                    Placement::OnGrid { intervals } => (intervals, intervals.saturating_sub(1) > self.config.max_filled_gap_samples),
                    Placement::Learning | Placement::ClockStep => (1, true),
                };
                self.index = self.index.wrapping_add(step);
                if restart {
                    self.filler.flush(&mut |s| {
                        let _ = out.push(*s);
                    });
                    self.take(&out, &feed, stamp_s);
                    out.clear();
                    self.restart_window();
                    self.rotation.restart();
                }
                feed
            }
        };
        let grid_sample = GridSample {
            index: self.index,
            roll_rad: sample.attitude.roll_rad,
            pitch_rad: sample.attitude.pitch_rad,
            rotation_rad: sample.rotation_rad,
            rotation_minus_platform_rad: wrap_pi(sample.rotation_rad - sample.platform_rad),
            latitude_rad: sample.latitude_rad,
            angles: *angles,
            fill_weight: 0,
        };
        self.filler.push(grid_sample, &mut |s| {
            let _ = out.push(*s);
        });
        self.take(&out, &feed, stamp_s);
        self.window_status
    }

    /// The first sample on a known grid: the grid's constants are fixed, the rotation monitor
    /// starts (with the pinned period in samples, if any, and the window set to it).
    fn start_feeding(&mut self, interval_s: f64) -> Feed {
        let feed = Feed::new(interval_s, &self.config);
        self.feed = Some(feed);
        self.index = 0;
        let pinned = self.config.rotation_period_s.map(|t| libm::round(t / interval_s).max(2.0) as u32);
        self.rotation = RotationMonitor::new(pinned);
        if let Some(p) = pinned {
            self.method.configure(p);
        }
        self.window_status = Status::DetectingPattern;
        feed
    }

    /// The window takes the samples the filler passed on, then the filter updates once. `stamp_s`
    /// is the time stamp of the newest sample received (at grid index `self.index`).
    fn take(&mut self, samples: &[GridSample], feed: &Feed, stamp_s: f64) {
        if samples.is_empty() {
            return;
        }
        for s in samples {
            if s.fill_weight > 0 {
                self.counters.filled = self.counters.filled.saturating_add(1);
            }
            match self.rotation.observe(s.index, s.rotation_rad, &feed.limits) {
                Err(fault) => {
                    if !matches!(self.window_status, Status::RotationFault(_)) {
                        let behind = f64::from(self.index.wrapping_sub(s.index));
                        self.fault = Some((fault, stamp_s - behind * feed.interval_s));
                    }
                    self.restart_window();
                    if fault != RotationFault::RateMismatch {
                        self.rotation.after_fault();
                    }
                    self.window_status = Status::RotationFault(fault);
                    continue;
                }
                Ok(PatternEvent::PeriodKnown(period)) => self.method.configure(period),
                Ok(PatternEvent::None) => {}
            }
            if self.rotation.period_samples.is_none() {
                self.window_status = Status::DetectingPattern;
                continue;
            }
            self.method.push(&self.config, feed, s);
            self.window_status = if self.method.window_full() { Status::Estimating } else { Status::WarmingUp };
        }
        self.method.update(&self.config, feed, self.filler.single_fill_variance_rad2());
    }

    fn restart_window(&mut self) {
        self.method.restart_window();
        self.counters.window_restarts = self.counters.window_restarts.saturating_add(1);
        self.window_status = if self.rotation.period_samples.is_some() { Status::WarmingUp } else { Status::DetectingPattern };
    }

    fn angles(&mut self, sample: &Sample) -> Angles {
        if sample.latitude_rad != self.latitude_trig.0 {
            let (s, c) = sin_cos(sample.latitude_rad);
            self.latitude_trig = (sample.latitude_rad, s, c);
        }
        Angles::new(sample.rotation_rad, sample.platform_rad, (self.latitude_trig.1, self.latitude_trig.2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::{arcsec_to_rad, rad_to_arcsec, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
    use crate::gap_fill::NEIGHBOURS;
    use crate::Field;

    const X_ARCSEC: [f64; 4] = [200.0, -150.0, 300.0, -250.0];

    /// Sway plus eq (2)'s oscillation (computed with the core's own rows) at time `t`.
    fn sample(t: f64, roll_sway_deg: f64) -> Sample {
        let rho = 0.3 + 2.0 * core::f64::consts::PI * t / 480.0;
        let s = 1.1 + EARTH_RATE_RAD_PER_S * t;
        let lat = 40.0 * RAD_PER_DEG;
        let x: [Real; 4] = core::array::from_fn(|i| arcsec_to_rad(X_ARCSEC[i]) as Real);
        let angles = Angles::new(
            wrap_pi(rho as Real),
            wrap_pi(s as Real),
            sin_cos(lat as Real),
        );
        let d = angles.oscillation(&x);
        let deg = |r: Real| r as f64 / RAD_PER_DEG;
        Sample::from_degrees(
            t,
            rho / RAD_PER_DEG,
            s / RAD_PER_DEG,
            40.0,
            10.0 + deg(d.heading_rad),
            roll_sway_deg * libm::sin(2.0 * core::f64::consts::PI * t / 6.0) + deg(d.roll_rad),
            libm::sin(2.0 * core::f64::consts::PI * t / 9.0) + deg(d.pitch_rad),
        )
    }

    fn errors_arcsec(est: &Estimator) -> [f64; 4] {
        let e = est.estimate().unwrap();
        core::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - X_ARCSEC[i])
    }

    #[test]
    fn bad_samples_are_rejected_by_reason_and_change_nothing_else() {
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        for k in 0..1000 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        let good = sample(1000.0, 3.0);
        let mut bad = std::vec::Vec::new();
        let mut nan_roll = good;
        nan_roll.attitude.roll_rad = Real::NAN;
        bad.push((nan_roll, SampleError::NonFinite(Field::Roll)));
        let mut inf_time = good;
        inf_time.time_s = f64::INFINITY;
        bad.push((inf_time, SampleError::NonFinite(Field::Time)));
        let mut inf_rot = good;
        inf_rot.rotation_rad = Real::NEG_INFINITY;
        bad.push((inf_rot, SampleError::NonFinite(Field::Rotation)));
        bad.push((Sample::from_degrees(1000.0, 1.0, 1.0, 90.0, 1.0, 1.0, 1.0), SampleError::LatitudeOutOfRange));
        bad.push((Sample::from_degrees(1000.0, 1.0, 1.0, -95.0, 1.0, 1.0, 1.0), SampleError::LatitudeOutOfRange));
        bad.push((Sample::from_degrees(1000.0, 1.0, 1.0, 40.0, 1.0, 120.0, 1.0), SampleError::AngleOutOfRange(Field::Roll)));
        let mut huge_platform = good;
        huge_platform.platform_rad = 1e6;
        bad.push((huge_platform, SampleError::AngleOutOfRange(Field::Platform)));
        let mut back = good;
        back.time_s = 998.0;
        bad.push((back, SampleError::TimeNotIncreasing));
        let mut same = good;
        same.time_s = 999.0;
        bad.push((same, SampleError::TimeNotIncreasing));
        let mut close = good;
        close.time_s = 999.3;
        bad.push((close, SampleError::IrregularTimeStep));
        for (s, expected) in bad {
            let before = est.clone();
            assert_eq!(est.step(&s), Err(expected));
            let counted = est.rejected.0[expected.reason_index()];
            assert_eq!(counted, before.rejected.0[expected.reason_index()] + 1);
            let mut restored = est.clone();
            restored.rejected = before.rejected;
            assert!(restored == before, "state changed by {expected:?}");
        }
        assert_eq!(est.rejected().total(), 10);
        assert!(est.step(&good).is_ok());
    }

    /// Runs 8000 s, dropping sample `k` where `drop(k)`; returns the estimate errors of a plain and
    /// of the gappy run, the gappy run's counters and its 1-sigma.
    fn gappy_run(config: Config, drop: impl Fn(u32) -> bool) -> ([f64; 4], [f64; 4], Counters, [f64; 4]) {
        let mut plain: Estimator = Estimator::new(Config::default()).unwrap();
        let mut gappy: Estimator = Estimator::new(config).unwrap();
        for k in 0..8000u32 {
            let s = sample(k as f64, 3.0);
            plain.step(&s).unwrap();
            if !drop(k) {
                let out = gappy.step(&s).unwrap();
                assert!(k < 2000 || matches!(out.status, Status::Estimating | Status::Converged), "{k}: {:?}", out.status);
            }
        }
        let sigma = gappy.estimate().unwrap().sigma_rad.map(|s| rad_to_arcsec(s as f64));
        (errors_arcsec(&plain), errors_arcsec(&gappy), gappy.counters(), sigma)
    }

    /// One or two samples lost every ~15 min: filled, the window never restarts, and the estimates
    /// move by what the interpolation errors carry. The 10-point interpolation of a 3 deg, 6 s
    /// roll is 0.4 % (43 arcsec) off for one lost sample, 2 % for two; each filled sample's error
    /// enters the filter's average over ~7500 updates once (it passes through 480 windows of
    /// 1/480 weight), 0.006 arcsec for one, 0.03 for two, times 2 / cos L = 2.6 on x3, x4: with 8
    /// single and 3 double gaps (and one unfilled pair), up to about 0.3 arcsec if they all add up.
    /// (Restarting the window instead cost nothing here, but never estimates through frequent loss.)
    #[test]
    fn short_gaps_are_filled_and_cost_little_accuracy() {
        let (a, b, counters, _) = gappy_run(Config::default(), |k| k % 907 == 5 || k % 1814 == 6);
        assert_eq!(counters.window_restarts, 0);
        // 14 lost, of which the two at 5 and 6 s fall in the first 9 samples, from which the
        // sample interval is learned (nothing is estimated from those).
        assert_eq!(counters.filled, 12);
        for i in 0..4 {
            assert!((a[i] - b[i]).abs() < 0.3, "x{}: plain {:.3}, gappy {:.3}", i + 1, a[i], b[i]);
        }
    }

    /// A sample lost every 97 s: the window never holds a gap, estimation never stops, and the
    /// accuracy stays within a few tenths of an arcsec of the plain run, inside the 1-sigma.
    #[test]
    fn frequent_drops_cost_accuracy_never_the_estimate() {
        let (a, b, counters, sigma) = gappy_run(Config::default(), |k| k % 97 == 5);
        assert_eq!(counters.window_restarts, 0);
        for i in 0..4 {
            assert!((a[i] - b[i]).abs() < 0.3, "x{}: plain {:.3}, gappy {:.3}", i + 1, a[i], b[i]);
            assert!(b[i].abs() < 3.0 * sigma[i], "x{}: error {:.3} vs 1-sigma {:.3}", i + 1, b[i], sigma[i]);
        }
    }

    /// With filling switched off, every gap restarts the window: the estimates hold, then resume.
    #[test]
    fn without_filling_a_gap_restarts_the_window() {
        let none = Config { max_filled_gap_samples: 0, ..Config::default() };
        let mut est: Estimator = Estimator::new(none).unwrap();
        for k in 0..3000u32 {
            if k != 2500 {
                est.step(&sample(k as f64, 3.0)).unwrap();
            }
        }
        assert_eq!((est.counters().window_restarts, est.counters().filled), (1, 0));
    }

    #[test]
    fn a_long_gap_restarts_the_window_and_holds_the_estimates() {
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        for k in 0..2000u32 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        // 300 s missing: too long to fill, the window restarts (after taking the samples still
        // waiting in the filler's delay line).
        let mut k = 2300u32;
        let out = est.step(&sample(k as f64, 3.0)).unwrap();
        let held = out.estimate.unwrap();
        assert_eq!(out.status, Status::Holding);
        assert_eq!(est.counters().window_restarts, 1);
        while est.step(&sample((k + 1) as f64, 3.0)).unwrap().status == Status::Holding {
            k += 1;
            assert_eq!(est.estimate().unwrap(), held, "estimates moved while holding");
        }
        assert_eq!(k + 1, 2300 + 479 + NEIGHBOURS as u32, "refilled after one window and the filler's delay");
        for t in (k + 2)..6000 {
            est.step(&sample(t as f64, 3.0)).unwrap();
        }
        for (i, e) in errors_arcsec(&est).iter().enumerate() {
            assert!(e.abs() < 1.0, "x{}: {e:.3}", i + 1);
        }
    }

    #[test]
    fn sway_gate_waits_for_enough_roll() {
        let config = Config { sway_gate_rad: (3.0 * RAD_PER_DEG) as Real, ..Config::default() };
        let mut est: Estimator = Estimator::new(config).unwrap();
        for k in 0..1000u32 {
            let out = est.step(&sample(k as f64, 2.0)).unwrap();
            assert_eq!(out.status, Status::WaitingForSway);
            assert!(out.estimate.is_none());
        }
        let mut opened_at = None;
        for k in 1000..4000u32 {
            let out = est.step(&sample(k as f64, 4.0)).unwrap();
            if opened_at.is_none() && out.status != Status::WaitingForSway {
                opened_at = Some(k);
            }
        }
        let opened_at = opened_at.unwrap();
        assert!(opened_at > 1000 && opened_at < 1100, "gate opened at {opened_at}");
        for (i, e) in errors_arcsec(&est).iter().enumerate() {
            assert!(e.abs() < 1.5, "x{}: {e:.3}", i + 1);
        }
    }

    /// `reinit` (behind `reset` and checkpoint restore) and `new` give the same estimator, for every
    /// method, from a used estimator of the same or another method.
    #[test]
    fn reinit_equals_new() {
        use crate::config::Method;
        let methods = [Method::Windowed, Method::Paper, Method::Traditional];
        for from in methods {
            for to in methods {
                let mut est: Estimator = Estimator::new(Config::with_method(from)).unwrap();
                for k in 0..700 {
                    est.step(&sample(k as f64, 3.0)).unwrap();
                }
                let config = Config { rotation_period_s: Some(300.0), sway_gate_rad: 0.01, ..Config::with_method(to) };
                est.reinit(config).unwrap();
                assert!(est == Estimator::new(config).unwrap(), "{from:?} -> {to:?}");
            }
        }
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        for k in 0..700 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        let before = est.clone();
        let bad = Config { rotation_period_s: Some(4000.0), ..Config::default() };
        assert_eq!(est.reinit(bad), Err(ConfigError::RotationPeriod { value_s: 4000.0 }));
        assert!(est == before, "a refused configuration changed the estimator");
    }

    #[test]
    fn reset_forgets_all_but_the_configuration_and_rejections() {
        let config = Config { rotation_period_s: Some(300.0), ..Config::default() };
        let mut est: Estimator = Estimator::new(config).unwrap();
        for k in 0..700 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        // A repeated time stamp.
        assert!(est.step(&sample(699.0, 3.0)).is_err());
        let rejected = est.rejected();
        est.reset();
        let mut fresh: Estimator = Estimator::new(config).unwrap();
        fresh.rejected = rejected;
        assert!(est == fresh);
    }

    #[test]
    fn covariance_stays_symmetric_positive_definite_over_two_days() {
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        for k in 0..172_800u32 {
            est.step(&sample(k as f64, 3.0)).unwrap();
            if k % 3600 == 0 || k == 172_799 {
                let w = est.windowed().expect("default is windowed");
                if w.updates > 0 {
                    assert!(w.kf.covariance_is_spd(), "not SPD at {k} s");
                }
            }
        }
        for (i, e) in errors_arcsec(&est).iter().enumerate() {
            assert!(e.abs() < 0.5, "x{}: {e:.3}", i + 1);
        }
    }
}
