//! The estimator: checks each sample, handles gaps, watches the rotation and the sway gate, drives
//! the selected method and corrects the attitude.
//!
//! # Input checks (every one before any state changes)
//! A sample is rejected with a [`SampleError`], counted by reason, and leaves the estimator exactly
//! as it was, when: a field is NaN or infinite; |latitude| >= 90 deg; |roll| or |pitch| > 90 deg or a
//! wrapped angle exceeds 360 deg; its time is not after the previous accepted sample's; or the time
//! step is not a whole number of sample intervals within a quarter interval.
//!
//! # Gaps
//! A step of n intervals means n-1 missing samples. By default every gap restarts the moving
//! average: the filter keeps everything it has learnt, holds its estimates ([`Status::Holding`])
//! until the window has refilled (one rotation period), then goes on. Measured: a 1-sample gap
//! then moves the estimates at 8000 s by about 0.01 arcsec.
//!
//! Bridging (`max_bridged_gap_samples` > 0) instead interpolates up to that many missing samples
//! linearly from their neighbours (angles the short way round) and processes them as if received.
//! It keeps the filter updating through frequent drops, but a bridged sample weighs in the estimate
//! like a sample whose noise is its interpolation error: half the sway amplitude for a 3 deg roll at
//! 6 s, ~5000 arcsec, against ~5 arcsec for a received sample. Measured: one bridged sample moves
//! x3 at 8000 s by about 1.5 arcsec (each bridged sample costs about A/(2N) on the correlation,
//! A the sway amplitude, N the samples averaged). With the default, a log that drops samples more
//! often than once a rotation period never refills its window: the estimator holds, and says so;
//! bridging keeps it updating at that cost (measured: drops every 97 s, 3 deg roll, leave x3
//! about 10 arcsec off at 8000 s). The tests below pin these figures.
//!
//! # Rotation health
//! The moving average blocks the rotation harmonics only if the window spans one rotation. Each
//! step's rotation increment must be within `rotation_step_tolerance` of `2 pi / W` (else the
//! rotation has stopped or runs at another rate) and in the same direction as before (else it has
//! reversed), and the mean rate over about one period must be within `rotation_period_tolerance` of
//! nominal. A sample that fails is a [`Status::RotationFault`]: the window restarts, the estimates
//! freeze; estimation resumes one full window after the rotation is healthy again.
//!
//! # Sway gate
//! With `sway_gate_rad > 0`, estimation starts only once the roll sway amplitude (sqrt(2) times the
//! RMS of roll about its mean, exponentially averaged over 64 s) exceeds the gate, as in the paper's
//! sea test; once started it goes on.

use crate::config::{Config, ConfigError};
use crate::installation::Angles;
use crate::methods::MethodState;
use crate::sample::{Attitude, Sample, SampleError};
use crate::math::{sin_cos, sqrt, wrap_pi};
use crate::Real;

/// Why the rotation is not healthy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RotationFault {
    /// The rotation increment is below half the nominal one.
    Stopped,
    /// The rotation turned the other way.
    Reversed,
    /// The rotation rate is off nominal by more than the tolerances.
    RateMismatch,
}

/// What the estimator is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The sway gate has not opened yet.
    WaitingForSway,
    /// This sample's rotation is not healthy; estimates are frozen.
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
    /// errors, coloured noise, a wrong rotation period): the 1-sigma has been widened to match.
    ModelMismatch,
}

impl Status {
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
        }
    }

    /// Code used on the firmware link.
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
        }
    }

    /// Inverse of [`Status::code`].
    pub fn from_code(code: u8) -> Option<Status> {
        Some(match code {
            0 => Status::WaitingForSway,
            1 => Status::RotationFault(RotationFault::Stopped),
            2 => Status::RotationFault(RotationFault::Reversed),
            3 => Status::RotationFault(RotationFault::RateMismatch),
            4 => Status::WarmingUp,
            5 => Status::Holding,
            6 => Status::Estimating,
            7 => Status::Converged,
            8 => Status::ModelMismatch,
            _ => return None,
        })
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
    /// The sample's time, s.
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

/// Watches the rotation increments.
///
/// A single step's increment carries the jitter of two angle readings: 0.15 deg of encoder jitter
/// is 28 % of a 0.75 deg step, so bounds on single steps either miss faults or trip on noise (they
/// did: at 0.1 deg of jitter the window kept restarting, at 0.15 deg it never filled). Only a
/// reversal is judged on one step, because one step backwards by more than half a nominal step is
/// far beyond jitter (5 sigma at 0.15 deg). A stop and the rate are judged on the mean of the
/// signed increment over the last [`RotationMonitor::SHORT_STEPS`] steps (exponential), whose
/// jitter is about a fifth of one step's (5 % of a step at 0.15 deg, against the stop bound of
/// 50 %); the period on the mean of that over one rotation period (a running mean
/// until a period has passed, then exponential), updated on every step that is neither stopped nor
/// reversed so that no tail of the jitter is left out (leaving out the slow tail biased it by
/// 2.4 % at 0.15 deg). A stop is reported within 3 steps (the short mean falls below one half),
/// and the short mean's lag as the rotation stops and restarts moves the period mean by about
/// 0.5 %, inside the default 1 % tolerance, so a stop does not also leave a rate fault behind.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RotationMonitor {
    /// +1 or -1 once known, 0 before.
    pub direction: i8,
    /// Increments observed (saturating).
    pub steps: u32,
    /// Mean of increment / nominal along `direction` over about `SHORT_STEPS` steps.
    pub short_rate_ratio: Real,
    /// Mean of `short_rate_ratio` over about one period; 0 before the first healthy step.
    pub mean_rate_ratio: Real,
}

impl RotationMonitor {
    /// Steps of the short mean.
    pub const SHORT_STEPS: u32 = 4;

    fn observe(&mut self, increment_rad: Real, config: &Config) -> Result<(), RotationFault> {
        let nominal = (2.0 * core::f64::consts::PI / config.rotation_period_samples as f64) as Real;
        let ratio = increment_rad / nominal;
        let sign: i8 = if ratio >= 0.0 { 1 } else { -1 };
        self.steps = self.steps.saturating_add(1);
        if self.direction == 0 {
            self.direction = sign;
        } else if sign != self.direction && ratio.abs() >= 0.5 {
            // The other way round: the short mean starts again in the new direction.
            self.direction = sign;
            self.short_rate_ratio = ratio.abs();
            return Err(RotationFault::Reversed);
        }
        let along = ratio * Real::from(self.direction);
        let short_n = self.steps.min(Self::SHORT_STEPS) as Real;
        self.short_rate_ratio += (along - self.short_rate_ratio) / short_n;
        if self.short_rate_ratio < 0.5 {
            return Err(RotationFault::Stopped);
        }
        let mean_n = self.steps.min(config.rotation_period_samples as u32) as Real;
        self.mean_rate_ratio += (self.short_rate_ratio - self.mean_rate_ratio) / mean_n;
        // The period is judged once a quarter period has been averaged: the mean of n increments
        // carries the jitter of its two end readings only, sqrt(2) sigma / (n nominal), under
        // 0.3 % for 0.15 deg at n = 120 (one step: 28 %).
        let period_known = self.steps >= (config.rotation_period_samples / 4) as u32;
        if (self.short_rate_ratio - 1.0).abs() > config.rotation_step_tolerance
            || (period_known && (self.mean_rate_ratio - 1.0).abs() > config.rotation_period_tolerance)
        {
            return Err(RotationFault::RateMismatch);
        }
        Ok(())
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

/// The installation-error estimator, with a ring capacity of `CAP` samples (at least the rotation
/// period in samples; 480 by default).
#[derive(Clone, Debug, PartialEq)]
pub struct Estimator<const CAP: usize = 480> {
    pub(crate) config: Config,
    pub(crate) method: MethodState<CAP>,
    /// Last accepted sample (for time order, gap bridging and the rotation increment).
    pub(crate) previous: Option<Sample>,
    /// Whether the next rotation increment can be checked (false after a restart).
    pub(crate) rotation_continuous: bool,
    /// Cached `(L, sin L, cos L)`.
    pub(crate) latitude_trig: (Real, Real, Real),
    pub(crate) rotation: RotationMonitor,
    pub(crate) sway: SwayMonitor,
    pub(crate) gate_open: bool,
    pub(crate) rejected: RejectCounts,
    pub(crate) accepted: u32,
    pub(crate) bridged: u32,
    pub(crate) window_restarts: u32,
}

impl<const CAP: usize> Estimator<CAP> {
    /// A fresh estimator, or why the configuration cannot run.
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        config.check(CAP)?;
        let (s, c) = sin_cos(0.0);
        Ok(Estimator {
            config,
            method: MethodState::new(&config),
            previous: None,
            rotation_continuous: false,
            latitude_trig: (0.0, s, c),
            rotation: RotationMonitor::default(),
            sway: SwayMonitor::default(),
            gate_open: config.sway_gate_rad == 0.0,
            rejected: RejectCounts::default(),
            accepted: 0,
            bridged: 0,
            window_restarts: 0,
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
        self.previous = None;
        self.rotation_continuous = false;
        self.latitude_trig = (0.0, s, c);
        self.rotation = RotationMonitor::default();
        self.sway = SwayMonitor::default();
        self.gate_open = config.sway_gate_rad == 0.0;
        self.rejected = RejectCounts::default();
        self.accepted = 0;
        self.bridged = 0;
        self.window_restarts = 0;
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

    /// Samples accepted, samples bridged by interpolation, and restarts of the moving average.
    pub fn counters(&self) -> (u32, u32, u32) {
        (self.accepted, self.bridged, self.window_restarts)
    }

    /// The current estimate, if any.
    pub fn estimate(&self) -> Option<Estimate> {
        self.method.estimate(&self.config).map(|(x_rad, sigma_rad, _)| Estimate { x_rad, sigma_rad })
    }

    /// Processes one sample. On error nothing changes but the rejection counter.
    pub fn step(&mut self, sample: &Sample) -> Result<Output, SampleError> {
        let intervals = match self.check(sample) {
            Ok(n) => n,
            Err(e) => {
                let slot = &mut self.rejected.0[e.reason_index()];
                *slot = slot.saturating_add(1);
                return Err(e);
            }
        };
        if let Some(prev) = self.previous {
            let missing = intervals.saturating_sub(1);
            if missing > self.config.max_bridged_gap_samples {
                self.restart_window();
            } else {
                for m in 1..=missing {
                    let filler = interpolate(&prev, sample, m as Real / intervals as Real);
                    let _ = self.process(&filler);
                    self.bridged = self.bridged.saturating_add(1);
                }
            }
        }
        let (status, angles) = self.process(sample);
        self.accepted = self.accepted.saturating_add(1);
        let method_estimate = self.method.estimate(&self.config);
        let mismatch = matches!(method_estimate, Some((_, _, true)));
        let estimate = method_estimate.map(|(x_rad, sigma_rad, _)| Estimate { x_rad, sigma_rad });
        let status = match (status, estimate) {
            (Status::Estimating, Some(_)) if mismatch => Status::ModelMismatch,
            (Status::Estimating, Some(e)) if e.sigma_rad.iter().all(|s| *s < self.config.converged_sigma_rad) => {
                Status::Converged
            }
            (Status::WarmingUp, Some(_)) => Status::Holding,
            (s, _) => s,
        };
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

    /// Checks a sample against its fields and the previous sample; returns the number of sample
    /// intervals since the previous one (1 for the first sample).
    fn check(&self, sample: &Sample) -> Result<u32, SampleError> {
        sample.check()?;
        let Some(prev) = self.previous else {
            return Ok(1);
        };
        let dt = sample.time_s - prev.time_s;
        if !(dt > 0.0) {
            return Err(SampleError::TimeNotIncreasing);
        }
        let interval = self.config.sample_interval_s;
        if dt == interval {
            // The usual case, without the (software, on the M4F) f64 division below.
            return Ok(1);
        }
        let n = libm::round(dt / interval);
        if n < 1.0 || (dt - n * interval).abs() > 0.25 * interval {
            return Err(SampleError::IrregularTimeStep);
        }
        Ok(if n > u32::MAX as f64 { u32::MAX } else { n as u32 })
    }

    fn restart_window(&mut self) {
        self.method.restart_window();
        self.rotation_continuous = false;
        self.window_restarts = self.window_restarts.saturating_add(1);
    }

    fn angles(&mut self, sample: &Sample) -> Angles {
        if sample.latitude_rad != self.latitude_trig.0 {
            let (s, c) = sin_cos(sample.latitude_rad);
            self.latitude_trig = (sample.latitude_rad, s, c);
        }
        Angles::new(sample.rotation_rad, sample.platform_rad, (self.latitude_trig.1, self.latitude_trig.2))
    }

    /// Runs one checked (or interpolated) sample through gate, rotation check and method; returns
    /// the status and the sample's angles (reused for the corrected attitude).
    fn process(&mut self, sample: &Sample) -> (Status, Angles) {
        let angles = self.angles(sample);
        let increment = self.previous.map(|p| wrap_pi(sample.rotation_rad - p.rotation_rad));
        let continuous = self.rotation_continuous;
        self.previous = Some(*sample);
        self.rotation_continuous = true;
        self.sway.observe(sample.attitude.roll_rad);
        if !self.gate_open {
            if self.sway.samples >= SwayMonitor::SAMPLES && self.sway.amplitude_rad() >= self.config.sway_gate_rad {
                self.gate_open = true;
            } else {
                return (Status::WaitingForSway, angles);
            }
        }
        if let (Some(inc), true) = (increment, continuous) {
            if let Err(fault) = self.rotation.observe(inc, &self.config) {
                self.restart_window();
                // The sample after a fault is compared with this one again.
                self.rotation_continuous = true;
                return (Status::RotationFault(fault), angles);
            }
        }
        let status = if self.method.step(&self.config, sample, &angles) { Status::Estimating } else { Status::WarmingUp };
        (status, angles)
    }
}

/// The sample a fraction `f` of the way from `a` to `b` (angles along the short way round).
fn interpolate(a: &Sample, b: &Sample, f: Real) -> Sample {
    let lin = |x: Real, y: Real| x + (y - x) * f;
    let ang = |x: Real, y: Real| wrap_pi(x + wrap_pi(y - x) * f);
    Sample {
        time_s: a.time_s + (b.time_s - a.time_s) * f as f64,
        rotation_rad: ang(a.rotation_rad, b.rotation_rad),
        platform_rad: ang(a.platform_rad, b.platform_rad),
        latitude_rad: lin(a.latitude_rad, b.latitude_rad),
        attitude: Attitude {
            heading_rad: ang(a.attitude.heading_rad, b.attitude.heading_rad),
            roll_rad: lin(a.attitude.roll_rad, b.attitude.roll_rad),
            pitch_rad: lin(a.attitude.pitch_rad, b.attitude.pitch_rad),
        },
    }
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::{arcsec_to_rad, rad_to_arcsec, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
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
        let mut half = good;
        half.time_s = 999.5;
        bad.push((half, SampleError::IrregularTimeStep));
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
    /// of the gappy run and the gappy run's counters.
    fn gappy_run(config: Config, drop: impl Fn(u32) -> bool) -> ([f64; 4], [f64; 4], (u32, u32, u32)) {
        let mut plain: Estimator = Estimator::new(Config::default()).unwrap();
        let mut gappy: Estimator = Estimator::new(config).unwrap();
        for k in 0..8000u32 {
            let s = sample(k as f64, 3.0);
            plain.step(&s).unwrap();
            if !drop(k) {
                gappy.step(&s).unwrap();
            }
        }
        (errors_arcsec(&plain), errors_arcsec(&gappy), gappy.counters())
    }

    #[test]
    fn gaps_restart_the_window_and_cost_no_accuracy() {
        // A 1-sample and a 2-sample gap every ~15 min.
        let (a, b, (_, bridged, restarts)) =
            gappy_run(Config::default(), |k| k % 907 == 5 || k % 1814 == 6);
        assert_eq!(bridged, 0);
        assert_eq!(restarts, 9);
        for i in 0..4 {
            assert!((a[i] - b[i]).abs() < 0.05, "x{}: plain {:.3}, gappy {:.3}", i + 1, a[i], b[i]);
        }
    }

    #[test]
    fn bridging_one_sample_costs_the_documented_accuracy() {
        let bridge = Config { max_bridged_gap_samples: 2, ..Config::default() };
        let (a, b, (_, bridged, restarts)) = gappy_run(bridge, |k| k == 3001);
        assert_eq!((bridged, restarts), (1, 0));
        let moved = (a[2] - b[2]).abs();
        assert!(moved > 0.5 && moved < 3.0, "x3 moved {moved:.3} arcsec");
    }

    #[test]
    fn frequent_drops_hold_the_estimates_instead_of_corrupting_them() {
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        // 3012 is dropped (3012 % 97 == 5): from the next sample on, the window never refills.
        for k in 0..3012u32 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        let held = est.estimate().unwrap();
        for k in 3013..6000u32 {
            if k % 97 == 5 {
                continue;
            }
            let out = est.step(&sample(k as f64, 3.0)).unwrap();
            assert_eq!(out.status, Status::Holding);
            assert_eq!(out.estimate, Some(held));
        }
    }

    #[test]
    fn a_long_gap_restarts_the_window_and_holds_the_estimates() {
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        for k in 0..2000u32 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        let held = est.estimate().unwrap();
        // 300 s missing: beyond the bridge, the window restarts.
        let mut k = 2300u32;
        let out = est.step(&sample(k as f64, 3.0)).unwrap();
        assert_eq!(out.status, Status::Holding);
        assert_eq!(est.counters().2, 1);
        while est.step(&sample((k + 1) as f64, 3.0)).unwrap().status == Status::Holding {
            k += 1;
            assert_eq!(est.estimate().unwrap(), held, "estimates moved while holding");
        }
        assert_eq!(k + 1, 2300 + 479, "refilled after one window");
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
                let config = Config { rotation_period_samples: 300, sway_gate_rad: 0.01, ..Config::with_method(to) };
                est.reinit(config).unwrap();
                assert!(est == Estimator::new(config).unwrap(), "{from:?} -> {to:?}");
            }
        }
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        for k in 0..700 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        let before = est.clone();
        let bad = Config { rotation_period_samples: 481, ..Config::default() };
        assert_eq!(est.reinit(bad), Err(ConfigError::RotationPeriod { samples: 481, capacity: 480 }));
        assert!(est == before, "a refused configuration changed the estimator");
    }

    #[test]
    fn reset_forgets_all_but_the_configuration_and_rejections() {
        let config = Config { rotation_period_samples: 300, ..Config::default() };
        let mut est: Estimator = Estimator::new(config).unwrap();
        for k in 0..700 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
        let mut late = sample(10.0, 3.0);
        late.time_s = 5.0;
        assert!(est.step(&late).is_err());
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
                let MethodState::Windowed(w) = &est.method else { panic!("default is windowed") };
                if k >= 480 {
                    assert!(w.kf.covariance_is_spd(), "not SPD at {k} s");
                }
            }
        }
        for (i, e) in errors_arcsec(&est).iter().enumerate() {
            assert!(e.abs() < 0.5, "x{}: {e:.3}", i + 1);
        }
    }
}
