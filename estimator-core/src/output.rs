//! What the estimator reports: its status, the estimate with its 1-sigma, the output of one step,
//! its counters, what it knows of the rotation pattern and why there is no estimate yet.

use crate::code::{from_code, UnknownCode};
use crate::rotation_pattern::{PatternKind, RotationFault};
use crate::sample::{Attitude, RejectReason};
use crate::Real;

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
    /// The residuals showed a step of the installation errors (a re-installation, a shock): the
    /// errors that changed are learned again (from the residuals that showed the change, at
    /// once, or from the next half period of them), their 1-sigma from the learning; said for
    /// one rotation period from the detection, then `estimating` again. When and which:
    /// [`crate::Estimator::error_change`].
    ErrorsChanged,
}

impl Status {
    /// Every status, in code order.
    pub const ALL: [Status; 11] = [
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
        Status::ErrorsChanged,
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
            Status::ErrorsChanged => "errors_changed",
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
            Status::ErrorsChanged => 10,
        }
    }
}

impl TryFrom<u8> for Status {
    type Error = UnknownCode;

    /// Inverse of [`Status::code`].
    fn try_from(code: u8) -> Result<Status, UnknownCode> {
        from_code(&Status::ALL, "status", code)
    }
}

/// The four installation errors with their 1-sigma, rad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// x1..x4, rad.
    pub x_rad: [Real; 4],
    /// Their 1-sigma, rad.
    pub sigma_rad: [Real; 4],
}

/// What one step returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// The sample's time stamp, s, as received.
    pub time_s: f64,
    /// What the estimator is doing at this sample.
    pub status: Status,
    /// `None` until the filter has had its first measurement.
    pub estimate: Option<Estimate>,
    /// The sample's attitude minus eq (2)'s oscillation for the current estimate (unchanged while
    /// there is none). Heading wrapped to [-pi, pi].
    pub corrected: Attitude,
    /// What has happened since the estimator was made or reset, latched, and the residuals' level
    /// now: what a loop that polls only now and then needs to know.
    pub health: Health,
}

/// The latched alarms and the residuals' level, in every step's output ([`Output::health`]).
/// Counts and times hold until a reset (the rejections even past it), so a loop that reads only
/// now and then misses nothing: a change declared and learned again between two reads still
/// shows in `changes_detected` and `last_change_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Health {
    /// Changes of the installation errors declared (status `errors_changed`).
    pub changes_detected: u32,
    /// The time stamp of the sample at which the last change was declared, s.
    pub last_change_s: Option<f64>,
    /// Restarts of the moving average (gaps too long to fill, clock steps, rotation faults).
    pub window_restarts: u32,
    /// Samples rejected, every reason ([`crate::Estimator::rejected`] has them by reason).
    pub rejected: u32,
    /// Time spent in status `model_mismatch`, s (samples in it times the sample interval).
    pub mismatch_s: f64,
    /// Windowed method, once the filter has measured: the residual level of each channel pair
    /// (pitch: x1, x2; roll: x3, x4), the larger of its two channels' residual means, rad: what
    /// the model-mismatch check compares with its bound.
    pub residual_rad: Option<[Real; 2]>,
    /// Windowed method, once the filter has measured: the factor by which each pair's learned
    /// noise widens the filter's variance in the reported 1-sigma (1: white noise as configured).
    pub noise_scale: Option<[Real; 2]>,
}

impl Health {
    /// Nothing happened, no residuals yet.
    pub const NONE: Health = Health {
        changes_detected: 0,
        last_change_s: None,
        window_restarts: 0,
        rejected: 0,
        mismatch_s: 0.0,
        residual_rad: None,
        noise_scale: None,
    };
}

/// A change of the installation errors the residuals showed (windowed method, see
/// [`crate::methods::windowed::change`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorChange {
    /// Time stamp of the sample at which the change was declared, s.
    pub detected_s: f64,
    /// Time stamp from which the residuals showed it (the start of the first block of the run
    /// that declared it), s. The change itself began up to one rotation period before.
    pub seen_since_s: f64,
    /// The errors x1..x4 learned again (those whose residuals showed the change).
    pub relearned: [bool; 4],
}

/// Rejected samples by reason (index: the [`RejectReason`] code).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RejectCounts(pub [u32; RejectReason::ALL.len()]);

impl RejectCounts {
    /// Nothing rejected.
    pub const ZERO: RejectCounts = RejectCounts([0; RejectReason::ALL.len()]);

    /// Rejected for `reason`.
    pub fn of(&self, reason: RejectReason) -> u32 {
        self.0[reason as usize]
    }

    /// Counts one more rejection for `reason` (saturating).
    pub fn count(&mut self, reason: RejectReason) {
        let slot = &mut self.0[reason as usize];
        *slot = slot.saturating_add(1);
    }

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
    /// Changes of the installation errors declared.
    pub changes_detected: u32,
    /// Samples whose status was `model_mismatch`.
    pub mismatch_samples: u32,
}

impl Counters {
    /// Nothing counted.
    pub const ZERO: Counters = Counters {
        accepted: 0,
        filled: 0,
        window_restarts: 0,
        clock_steps: 0,
        changes_detected: 0,
        mismatch_samples: 0,
    };
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
    /// The sample grid (its interval, unless pinned, and its phase) is being learned from the
    /// time stamps.
    SampleIntervalNotKnown,
    /// The rotation pattern's period is being detected.
    RotationPeriodNotDetected,
    /// The rotation has broken its pattern since this sample time, s.
    RotationFault {
        /// How the rotation breaks its pattern.
        fault: RotationFault,
        /// Time stamp of the sample at which the fault began, s.
        since_s: f64,
    },
    /// The window is filling: `filled` of `len` entries.
    WindowFilling {
        /// Entry numbers the window spans so far.
        filled: u32,
        /// Entries in a full window (one rotation period).
        len: u32,
    },
}

impl core::fmt::Display for Holdup {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Holdup::WaitingForSway => {
                write!(f, "waiting for the roll sway to exceed the start gate")
            }
            Holdup::SampleIntervalNotKnown => {
                write!(f, "sample interval not yet learned from the time stamps")
            }
            Holdup::RotationPeriodNotDetected => write!(f, "rotation period not yet detected"),
            Holdup::RotationFault { fault, since_s } => {
                let what = match fault {
                    RotationFault::Stopped => "rotation stopped",
                    RotationFault::Reversed => "rotation reversed",
                    RotationFault::RateMismatch => "rotation no longer repeats its pattern",
                };
                write!(f, "{what} since {since_s} s")
            }
            Holdup::WindowFilling { filled, len } => {
                write!(f, "moving average filling ({filled} of {len} entries)")
            }
        }
    }
}
