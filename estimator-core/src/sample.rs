//! One RINS sample and its sanity checks.

use crate::code::{from_code, UnknownCode};
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
    /// Heading, rad.
    pub heading_rad: Real,
    /// Roll, rad.
    pub roll_rad: Real,
    /// Pitch, rad.
    pub pitch_rad: Real,
}

/// A field of [`Sample`], named in errors; its code (`field as u8`) is the one on the firmware link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Field {
    /// [`Sample::time_s`].
    Time = 0,
    /// [`Sample::rotation_rad`].
    Rotation = 1,
    /// [`Sample::platform_rad`].
    Platform = 2,
    /// [`Sample::latitude_rad`].
    Latitude = 3,
    /// The attitude's [`Attitude::heading_rad`].
    Heading = 4,
    /// The attitude's [`Attitude::roll_rad`].
    Roll = 5,
    /// The attitude's [`Attitude::pitch_rad`].
    Pitch = 6,
}

impl Field {
    /// Every field, in code order.
    pub const ALL: [Field; 7] = [
        Field::Time,
        Field::Rotation,
        Field::Platform,
        Field::Latitude,
        Field::Heading,
        Field::Roll,
        Field::Pitch,
    ];
}

impl TryFrom<u8> for Field {
    type Error = UnknownCode;

    fn try_from(code: u8) -> Result<Field, UnknownCode> {
        from_code(&Field::ALL, "sample field", code)
    }
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

/// Why a sample was rejected, without the field: the index of the rejection counters and the
/// code on the firmware link (`reason as u8`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum RejectReason {
    /// [`SampleError::NonFinite`]: a field is NaN or infinite.
    NonFinite = 0,
    /// [`SampleError::LatitudeOutOfRange`]: |latitude| >= 90 deg.
    LatitudeOutOfRange = 1,
    /// [`SampleError::AngleOutOfRange`]: an angle is outside its range.
    AngleOutOfRange = 2,
    /// [`SampleError::TimeNotIncreasing`]: the time is not later than the previous accepted
    /// sample's.
    TimeNotIncreasing = 3,
    /// [`SampleError::IrregularTimeStep`]: the time step is not a whole number of sample
    /// intervals.
    IrregularTimeStep = 4,
}

impl RejectReason {
    /// Every reason, in code order.
    pub const ALL: [RejectReason; 5] = [
        RejectReason::NonFinite,
        RejectReason::LatitudeOutOfRange,
        RejectReason::AngleOutOfRange,
        RejectReason::TimeNotIncreasing,
        RejectReason::IrregularTimeStep,
    ];

    /// Short machine-readable name, used in files.
    pub fn name(&self) -> &'static str {
        match self {
            RejectReason::NonFinite => "non_finite",
            RejectReason::LatitudeOutOfRange => "latitude_out_of_range",
            RejectReason::AngleOutOfRange => "angle_out_of_range",
            RejectReason::TimeNotIncreasing => "time_not_increasing",
            RejectReason::IrregularTimeStep => "irregular_time_step",
        }
    }
}

impl TryFrom<u8> for RejectReason {
    type Error = UnknownCode;

    fn try_from(code: u8) -> Result<RejectReason, UnknownCode> {
        from_code(&RejectReason::ALL, "rejection reason", code)
    }
}

impl SampleError {
    /// The reason, without the field.
    pub fn reason(&self) -> RejectReason {
        match self {
            SampleError::NonFinite(_) => RejectReason::NonFinite,
            SampleError::LatitudeOutOfRange => RejectReason::LatitudeOutOfRange,
            SampleError::AngleOutOfRange(_) => RejectReason::AngleOutOfRange,
            SampleError::TimeNotIncreasing => RejectReason::TimeNotIncreasing,
            SampleError::IrregularTimeStep => RejectReason::IrregularTimeStep,
        }
    }

    /// The field the error names, if it names one.
    pub fn field(&self) -> Option<Field> {
        match self {
            SampleError::NonFinite(field) | SampleError::AngleOutOfRange(field) => Some(*field),
            _ => None,
        }
    }

    /// The error of `reason` naming `field`; `None` when the field does not fit the reason (a
    /// reason that names a field without one, or one that names none with one).
    pub fn from_parts(reason: RejectReason, field: Option<Field>) -> Option<SampleError> {
        match (reason, field) {
            (RejectReason::NonFinite, Some(field)) => Some(SampleError::NonFinite(field)),
            (RejectReason::AngleOutOfRange, Some(field)) => {
                Some(SampleError::AngleOutOfRange(field))
            }
            (RejectReason::LatitudeOutOfRange, None) => Some(SampleError::LatitudeOutOfRange),
            (RejectReason::TimeNotIncreasing, None) => Some(SampleError::TimeNotIncreasing),
            (RejectReason::IrregularTimeStep, None) => Some(SampleError::IrregularTimeStep),
            _ => None,
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

impl core::error::Error for SampleError {}

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

    /// The sample in a log row's units, in the order [`Sample::from_degrees`] takes them: time (s),
    /// rotation, platform, latitude, heading, roll, pitch (deg). `from_degrees` turns them back
    /// into this sample, bit for bit in the f32 build (a binned sample goes to the estimator, and
    /// into a file, that way).
    pub fn to_degrees(&self) -> [f64; 7] {
        let deg = |rad: Real| f64::from(rad).to_degrees();
        [
            self.time_s,
            deg(self.rotation_rad),
            deg(self.platform_rad),
            deg(self.latitude_rad),
            deg(self.attitude.heading_rad),
            deg(self.attitude.roll_rad),
            deg(self.attitude.pitch_rad),
        ]
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
            (
                Field::Heading,
                self.attitude.heading_rad,
                MAX_WRAPPED_ANGLE_RAD,
            ),
            (Field::Roll, self.attitude.roll_rad, MAX_TILT_RAD),
            (Field::Pitch, self.attitude.pitch_rad, MAX_TILT_RAD),
        ];
        for (field, value, _) in fields {
            if !value.is_finite() {
                return Err(SampleError::NonFinite(field));
            }
        }
        for (field, value, max) in fields {
            let out = if field == Field::Latitude {
                value.abs() >= max
            } else {
                value.abs() > max
            };
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A sample in degrees and back is the same sample across the wrap of the angles, bit for bit
    /// in the f32 build (the double-precision degrees carry every bit of an f32 angle), to within
    /// a few units of the last place in the f64 build: what lets a binned sample go to the
    /// estimator and into a file through degrees.
    #[test]
    fn degrees_and_back_give_the_same_sample() {
        let mut k = 0u32;
        for rotation_deg in [-179.999, -90.5, 0.0, 0.001, 45.25, 179.75] {
            for latitude_deg in [-89.5, -30.0, 0.0, 40.0, 89.9] {
                k += 1;
                let f = f64::from(k);
                let s = Sample::from_degrees(
                    1.7e9 + 0.5 * f,
                    rotation_deg,
                    rotation_deg * 0.37 - 20.0,
                    latitude_deg,
                    359.99 - 7.0 * f,
                    (f * 0.73).sin() * 12.0,
                    (f * 0.41).cos() * -5.0,
                );
                let [t, r, p, l, h, ro, pi] = s.to_degrees();
                let back = Sample::from_degrees(t, r, p, l, h, ro, pi);
                if cfg!(feature = "f64") {
                    let fields = |x: &Sample| {
                        [
                            x.rotation_rad,
                            x.platform_rad,
                            x.latitude_rad,
                            x.attitude.heading_rad,
                            x.attitude.roll_rad,
                            x.attitude.pitch_rad,
                        ]
                    };
                    for (a, b) in fields(&back).iter().zip(fields(&s)) {
                        assert!((a - b).abs() <= 1e-14, "{back:?} against {s:?}");
                    }
                    assert_eq!(back.time_s, s.time_s);
                } else {
                    assert_eq!(back, s);
                }
            }
        }
    }
}
