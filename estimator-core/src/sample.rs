//! One RINS sample and its sanity checks.

use crate::units::{wrap_deg, RAD_PER_DEG};
use crate::Real;

/// Largest accepted magnitude of a wrapped angle (rotation, platform, heading), rad.
pub const MAX_WRAPPED_ANGLE_RAD: Real = 2.0 * core::f64::consts::PI as Real;
/// Largest accepted magnitude of roll and pitch, rad (90 deg).
pub const MAX_TILT_RAD: Real = core::f64::consts::FRAC_PI_2 as Real;

/// What the RINS outputs once a second: time, the gimbal angles of eq (2) and the attitude of eq (3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Seconds since the start of the log; strictly increasing.
    pub time_s: f64,
    /// Rotation (case/gimbal) angle rho of eq (2), wrapped to [-pi, pi).
    pub rotation_rad: Real,
    /// Platform angle s of eq (2), wrapped to [-pi, pi).
    pub platform_rad: Real,
    /// Latitude L, in (-pi/2, pi/2).
    pub latitude_rad: Real,
    /// Heading, roll and pitch as the RINS outputs them (with the oscillation of eq (2) in them).
    pub attitude: Attitude,
}

/// Heading, roll and pitch, rad.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Attitude {
    pub heading_rad: Real,
    pub roll_rad: Real,
    pub pitch_rad: Real,
}

/// A field of [`Sample`], named in errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    Time,
    Rotation,
    Platform,
    Latitude,
    Heading,
    Roll,
    Pitch,
}

/// Why a sample was rejected. A rejected sample is not used and leaves the estimator untouched.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleError {
    /// A field is NaN or infinite.
    NonFinite(Field),
    /// |latitude| >= 90 deg.
    LatitudeOutOfRange,
    /// An angle is outside its range: |rotation|, |platform|, |heading| > 360 deg, |roll|, |pitch| > 90 deg.
    AngleOutOfRange(Field),
    /// The time is not later than the previous accepted sample's.
    TimeNotIncreasing,
    /// The time step is not a whole number of sample intervals (within a quarter interval).
    IrregularTimeStep,
}

impl SampleError {
    /// Number of distinct reasons (for counters).
    pub const COUNT: usize = 5;

    /// Index of this reason in [`crate::RejectCounts`].
    pub fn reason_index(&self) -> usize {
        match self {
            SampleError::NonFinite(_) => 0,
            SampleError::LatitudeOutOfRange => 1,
            SampleError::AngleOutOfRange(_) => 2,
            SampleError::TimeNotIncreasing => 3,
            SampleError::IrregularTimeStep => 4,
        }
    }

    /// Short machine-readable name of the reason.
    pub fn reason_name(index: usize) -> &'static str {
        match index {
            0 => "non_finite",
            1 => "latitude_out_of_range",
            2 => "angle_out_of_range",
            3 => "time_not_increasing",
            _ => "irregular_time_step",
        }
    }
}

impl core::fmt::Display for SampleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SampleError::NonFinite(field) => write!(f, "{field:?} is not a finite number"),
            SampleError::LatitudeOutOfRange => write!(f, "|latitude| must be below 90 deg"),
            SampleError::AngleOutOfRange(field) => write!(f, "{field:?} is out of range"),
            SampleError::TimeNotIncreasing => write!(f, "time does not increase"),
            SampleError::IrregularTimeStep => {
                write!(f, "time step is not a whole number of sample intervals")
            }
        }
    }
}

impl Sample {
    /// Builds a sample from degrees, as they appear in logs. Rotation, platform and heading are wrapped
    /// to [-180, 180) in `f64` before they are narrowed to [`Real`], so unwrapped angles of many turns
    /// keep their precision. Nothing is checked here: see [`Sample::check`].
    pub fn from_degrees(
        time_s: f64,
        rotation_deg: f64,
        platform_deg: f64,
        latitude_deg: f64,
        heading_deg: f64,
        roll_deg: f64,
        pitch_deg: f64,
    ) -> Sample {
        let rad = |deg: f64| (deg * RAD_PER_DEG) as Real;
        Sample {
            time_s,
            rotation_rad: rad(wrap_deg(rotation_deg)),
            platform_rad: rad(wrap_deg(platform_deg)),
            latitude_rad: rad(latitude_deg),
            attitude: Attitude {
                heading_rad: rad(wrap_deg(heading_deg)),
                roll_rad: rad(roll_deg),
                pitch_rad: rad(pitch_deg),
            },
        }
    }

    /// Checks every field on its own (time order is checked by the estimator).
    pub fn check(&self) -> Result<(), SampleError> {
        if !self.time_s.is_finite() {
            return Err(SampleError::NonFinite(Field::Time));
        }
        let fields = [
            (Field::Rotation, self.rotation_rad, MAX_WRAPPED_ANGLE_RAD),
            (Field::Platform, self.platform_rad, MAX_WRAPPED_ANGLE_RAD),
            (Field::Latitude, self.latitude_rad, MAX_TILT_RAD),
            (Field::Heading, self.attitude.heading_rad, MAX_WRAPPED_ANGLE_RAD),
            (Field::Roll, self.attitude.roll_rad, MAX_TILT_RAD),
            (Field::Pitch, self.attitude.pitch_rad, MAX_TILT_RAD),
        ];
        for (field, value, _) in fields {
            if !value.is_finite() {
                return Err(SampleError::NonFinite(field));
            }
        }
        for (field, value, max) in fields {
            let out = if field == Field::Latitude { value.abs() >= max } else { value.abs() > max };
            if out {
                return Err(if field == Field::Latitude {
                    SampleError::LatitudeOutOfRange
                } else {
                    SampleError::AngleOutOfRange(field)
                });
            }
        }
        Ok(())
    }
}
