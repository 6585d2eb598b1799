//! What goes into one step and what comes out: the sample in degrees as a log holds it, the
//! status, the estimate with its 1-sigma and the corrected attitude in the core's radians.

use estimator_core::{
    Attitude, Estimate, Field, Health, Output, Real, RejectReason, RotationFault, Sample,
    SampleError, Status,
};

/// One sample as the RINS outputs it, in the units of the attitude log (`docs/log-format.md`):
/// degrees, seconds. Turned into the core's sample exactly as `host-sim` turns a log row into one
/// (rotation, platform and heading wrapped to [-180, 180) in double precision, then radians).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct RinsSample {
    /// Sample time, s, strictly increasing (Unix, GPS or any other origin).
    pub time_s: f64,
    /// Rotation angle of the sensor assembly (the paper's rho), deg, wrapped or not.
    pub rotation_deg: f64,
    /// Platform angle (the paper's s), deg, wrapped or not.
    pub platform_deg: f64,
    /// Latitude, deg, inside (-90, 90).
    pub latitude_deg: f64,
    /// Heading as the RINS outputs it, deg.
    pub heading_deg: f64,
    /// Roll as the RINS outputs it, deg.
    pub roll_deg: f64,
    /// Pitch as the RINS outputs it, deg.
    pub pitch_deg: f64,
}

impl From<&RinsSample> for Sample {
    fn from(s: &RinsSample) -> Sample {
        Sample::from_degrees(
            s.time_s,
            s.rotation_deg,
            s.platform_deg,
            s.latitude_deg,
            s.heading_deg,
            s.roll_deg,
            s.pitch_deg,
        )
    }
}

/// An attitude compensated by `rins_estimator_compensate`, rad.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct RinsAttitude {
    /// Heading with eq (2)'s oscillation removed, rad, in [-pi, pi].
    pub heading_rad: f32,
    /// Roll, corrected likewise, rad.
    pub roll_rad: f32,
    /// Pitch, corrected likewise, rad.
    pub pitch_rad: f32,
}

impl From<&Attitude> for RinsAttitude {
    fn from(a: &Attitude) -> RinsAttitude {
        RinsAttitude {
            heading_rad: a.heading_rad as f32,
            roll_rad: a.roll_rad as f32,
            pitch_rad: a.pitch_rad as f32,
        }
    }
}

/// The four installation errors x1..x4 and their 1-sigma, rad (multiply by
/// `RINS_ARCSEC_PER_RAD` for arcsec).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct RinsEstimate {
    /// x1..x4, rad.
    pub x_rad: [f32; 4],
    /// Their 1-sigma, rad.
    pub sigma_rad: [f32; 4],
}

impl From<&Estimate> for RinsEstimate {
    fn from(e: &Estimate) -> RinsEstimate {
        RinsEstimate {
            x_rad: e.x_rad.map(|v| v as f32),
            sigma_rad: e.sigma_rad.map(|v| v as f32),
        }
    }
}

impl From<&RinsEstimate> for Estimate {
    fn from(e: &RinsEstimate) -> Estimate {
        Estimate {
            x_rad: e.x_rad.map(|v| v as Real),
            sigma_rad: e.sigma_rad.map(|v| v as Real),
        }
    }
}

/// What the estimator is doing, or why it refused a sample. The names are those of the
/// estimates CSV's `status` column. Codes below 128 are the core's statuses (as on the firmware
/// link); 128 and above are rejected samples, 128 plus the rejection reason's code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum RinsStatus {
    /// `waiting_for_sway`: the sway gate has not opened yet.
    WaitingForSway = 0,
    /// `rotation_stopped`: the rotation stopped for longer than its pattern allows; estimates
    /// frozen.
    RotationStopped = 1,
    /// `rotation_reversed`: the rotation turns the other way in a pattern that never does;
    /// estimates frozen.
    RotationReversed = 2,
    /// `rotation_rate_mismatch`: the rotation no longer repeats its pattern; estimates frozen.
    RotationRateMismatch = 3,
    /// `warming_up`: the first window is filling; no estimate yet.
    WarmingUp = 4,
    /// `holding`: the window refills after a long gap or a rotation fault; estimates frozen.
    Holding = 5,
    /// `estimating`: the filter is updating.
    Estimating = 6,
    /// `converged`: the filter is updating and every 1-sigma is below `converged_sigma_rad`.
    Converged = 7,
    /// `model_mismatch`: the residuals show a bias the model does not explain; the 1-sigma has
    /// been widened to match.
    ModelMismatch = 8,
    /// `detecting_pattern`: the sample interval or the rotation period is not known yet.
    DetectingPattern = 9,
    /// `errors_changed`: a change of the installation errors was declared from the residuals;
    /// the errors that changed are being learned again. Said for one rotation period from the
    /// detection, then `estimating` again.
    ErrorsChanged = 10,
    /// `rejected_non_finite`: a field is NaN or infinite (`rejected_field` says which).
    RejectedNonFinite = 128,
    /// `rejected_latitude_out_of_range`: |latitude| >= 90 deg.
    RejectedLatitudeOutOfRange = 129,
    /// `rejected_angle_out_of_range`: |rotation|, |platform|, |heading| > 360 deg or |roll|,
    /// |pitch| > 90 deg (`rejected_field` says which).
    RejectedAngleOutOfRange = 130,
    /// `rejected_time_not_increasing`: the time is not later than the last accepted sample's.
    RejectedTimeNotIncreasing = 131,
    /// `rejected_irregular_time_step`: the time step is not a whole number of sample intervals.
    RejectedIrregularTimeStep = 132,
}

impl RinsStatus {
    /// Every status, in code order.
    pub(crate) const ALL: [RinsStatus; 16] = [
        RinsStatus::WaitingForSway,
        RinsStatus::RotationStopped,
        RinsStatus::RotationReversed,
        RinsStatus::RotationRateMismatch,
        RinsStatus::WarmingUp,
        RinsStatus::Holding,
        RinsStatus::Estimating,
        RinsStatus::Converged,
        RinsStatus::ModelMismatch,
        RinsStatus::DetectingPattern,
        RinsStatus::ErrorsChanged,
        RinsStatus::RejectedNonFinite,
        RinsStatus::RejectedLatitudeOutOfRange,
        RinsStatus::RejectedAngleOutOfRange,
        RinsStatus::RejectedTimeNotIncreasing,
        RinsStatus::RejectedIrregularTimeStep,
    ];

    /// The core's status or rejection reason of this code.
    pub fn to_core(self) -> Result<Status, RejectReason> {
        Ok(match self {
            RinsStatus::WaitingForSway => Status::WaitingForSway,
            RinsStatus::RotationStopped => Status::RotationFault(RotationFault::Stopped),
            RinsStatus::RotationReversed => Status::RotationFault(RotationFault::Reversed),
            RinsStatus::RotationRateMismatch => Status::RotationFault(RotationFault::RateMismatch),
            RinsStatus::WarmingUp => Status::WarmingUp,
            RinsStatus::Holding => Status::Holding,
            RinsStatus::Estimating => Status::Estimating,
            RinsStatus::Converged => Status::Converged,
            RinsStatus::ModelMismatch => Status::ModelMismatch,
            RinsStatus::DetectingPattern => Status::DetectingPattern,
            RinsStatus::ErrorsChanged => Status::ErrorsChanged,
            RinsStatus::RejectedNonFinite => return Err(RejectReason::NonFinite),
            RinsStatus::RejectedLatitudeOutOfRange => return Err(RejectReason::LatitudeOutOfRange),
            RinsStatus::RejectedAngleOutOfRange => return Err(RejectReason::AngleOutOfRange),
            RinsStatus::RejectedTimeNotIncreasing => return Err(RejectReason::TimeNotIncreasing),
            RinsStatus::RejectedIrregularTimeStep => return Err(RejectReason::IrregularTimeStep),
        })
    }

    /// The status of this code, if it is one.
    pub fn from_code(code: u32) -> Option<RinsStatus> {
        RinsStatus::ALL.iter().copied().find(|s| *s as u32 == code)
    }
}

impl From<Status> for RinsStatus {
    fn from(status: Status) -> RinsStatus {
        match status {
            Status::WaitingForSway => RinsStatus::WaitingForSway,
            Status::RotationFault(RotationFault::Stopped) => RinsStatus::RotationStopped,
            Status::RotationFault(RotationFault::Reversed) => RinsStatus::RotationReversed,
            Status::RotationFault(RotationFault::RateMismatch) => RinsStatus::RotationRateMismatch,
            Status::WarmingUp => RinsStatus::WarmingUp,
            Status::Holding => RinsStatus::Holding,
            Status::Estimating => RinsStatus::Estimating,
            Status::Converged => RinsStatus::Converged,
            Status::ModelMismatch => RinsStatus::ModelMismatch,
            Status::DetectingPattern => RinsStatus::DetectingPattern,
            Status::ErrorsChanged => RinsStatus::ErrorsChanged,
        }
    }
}

impl From<RejectReason> for RinsStatus {
    fn from(reason: RejectReason) -> RinsStatus {
        match reason {
            RejectReason::NonFinite => RinsStatus::RejectedNonFinite,
            RejectReason::LatitudeOutOfRange => RinsStatus::RejectedLatitudeOutOfRange,
            RejectReason::AngleOutOfRange => RinsStatus::RejectedAngleOutOfRange,
            RejectReason::TimeNotIncreasing => RinsStatus::RejectedTimeNotIncreasing,
            RejectReason::IrregularTimeStep => RinsStatus::RejectedIrregularTimeStep,
        }
    }
}

/// A field of `RinsSample`, named by a rejection (codes as on the firmware link).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum RinsField {
    /// The sample's `time_s`.
    Time = 0,
    /// The sample's `rotation_deg`.
    Rotation = 1,
    /// The sample's `platform_deg`.
    Platform = 2,
    /// The sample's `latitude_deg`.
    Latitude = 3,
    /// The sample's `heading_deg`.
    Heading = 4,
    /// The sample's `roll_deg`.
    Roll = 5,
    /// The sample's `pitch_deg`.
    Pitch = 6,
    /// No field: the sample was accepted, or its rejection names none.
    None = 255,
}

impl From<Option<Field>> for RinsField {
    fn from(field: Option<Field>) -> RinsField {
        match field {
            Some(Field::Time) => RinsField::Time,
            Some(Field::Rotation) => RinsField::Rotation,
            Some(Field::Platform) => RinsField::Platform,
            Some(Field::Latitude) => RinsField::Latitude,
            Some(Field::Heading) => RinsField::Heading,
            Some(Field::Roll) => RinsField::Roll,
            Some(Field::Pitch) => RinsField::Pitch,
            None => RinsField::None,
        }
    }
}

/// What one step returns, for an accepted sample and for a rejected one alike.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct RinsOutput {
    /// The sample's time, s, as given.
    pub time_s: f64,
    /// What the estimator is doing; a `RINS_STATUS_REJECTED_...` when it refused the sample.
    pub status: RinsStatus,
    /// The field a rejection names, `RINS_FIELD_NONE` otherwise.
    pub rejected_field: RinsField,
    /// Whether `estimate` holds an estimate (false until the filter's first measurement). On a
    /// rejected sample: the estimate held, unchanged by the sample.
    pub has_estimate: bool,
    /// The estimate and its 1-sigma when `has_estimate`; zeros otherwise.
    pub estimate: RinsEstimate,
    /// The sample's heading with eq (2)'s oscillation for the current estimate removed, rad, in
    /// [-pi, pi] (the sample's own while there is no estimate). NaN on a rejected sample.
    pub heading_corrected_rad: f32,
    /// The sample's roll, corrected likewise, rad. NaN on a rejected sample.
    pub roll_corrected_rad: f32,
    /// The sample's pitch, corrected likewise, rad. NaN on a rejected sample.
    pub pitch_corrected_rad: f32,
    /// The latched alarms and the residuals' level after this sample (also on a rejected one).
    pub health: RinsHealth,
}

/// What has happened since the estimator was set up or reset, latched, and the residuals' level
/// now: a loop that reads only now and then misses nothing (a change declared and learned again
/// between two reads still shows in `changes_detected` and `last_change_s`). The counts saturate
/// at 2^32 - 1; `rejected` is not cleared by `rins_estimator_reset`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct RinsHealth {
    /// Changes of the installation errors declared (`RINS_STATUS_ERRORS_CHANGED`).
    pub changes_detected: u32,
    /// The time stamp of the sample at which the last change was declared, s; NaN before the
    /// first.
    pub last_change_s: f64,
    /// Restarts of the moving average (gaps too long to fill, clock steps, rotation faults).
    pub window_restarts: u32,
    /// Samples rejected, every reason.
    pub rejected: u32,
    /// Time spent in `RINS_STATUS_MODEL_MISMATCH`, s.
    pub mismatch_s: f64,
    /// The residual level of each channel pair (pitch: x1, x2; roll: x3, x4), rad: the larger of
    /// the pair's two residual means, what the model-mismatch check bounds. NaN until the windowed
    /// method's first measurement, and for the other methods.
    pub residual_rad: [f32; 2],
    /// The factor by which each pair's learned noise widens the filter's variance in the reported
    /// 1-sigma (1: white noise as configured). NaN as `residual_rad`.
    pub noise_scale: [f32; 2],
}

impl From<&Health> for RinsHealth {
    fn from(h: &Health) -> RinsHealth {
        RinsHealth {
            changes_detected: h.changes_detected,
            last_change_s: h.last_change_s.unwrap_or(f64::NAN),
            window_restarts: h.window_restarts,
            rejected: h.rejected,
            mismatch_s: h.mismatch_s,
            residual_rad: h
                .residual_rad
                .map_or([f32::NAN; 2], |r| r.map(|v| v as f32)),
            noise_scale: h.noise_scale.map_or([f32::NAN; 2], |s| s.map(|v| v as f32)),
        }
    }
}

impl From<&RinsHealth> for Health {
    fn from(h: &RinsHealth) -> Health {
        let pair = |v: [f32; 2]| (!v[0].is_nan()).then(|| v.map(|x| x as Real));
        Health {
            changes_detected: h.changes_detected,
            last_change_s: (!h.last_change_s.is_nan()).then_some(h.last_change_s),
            window_restarts: h.window_restarts,
            rejected: h.rejected,
            mismatch_s: h.mismatch_s,
            residual_rad: pair(h.residual_rad),
            noise_scale: pair(h.noise_scale),
        }
    }
}

impl RinsOutput {
    /// The output of an accepted sample.
    pub fn accepted(out: &Output) -> RinsOutput {
        RinsOutput {
            time_s: out.time_s,
            status: RinsStatus::from(out.status),
            rejected_field: RinsField::None,
            has_estimate: out.estimate.is_some(),
            estimate: out
                .estimate
                .as_ref()
                .map(RinsEstimate::from)
                .unwrap_or_default(),
            heading_corrected_rad: out.corrected.heading_rad as f32,
            roll_corrected_rad: out.corrected.roll_rad as f32,
            pitch_corrected_rad: out.corrected.pitch_rad as f32,
            health: RinsHealth::from(&out.health),
        }
    }

    /// The output of a sample rejected at `time_s` for `error`, with the estimate `held`.
    pub fn rejected(
        time_s: f64,
        error: &SampleError,
        held: Option<&Estimate>,
        health: &Health,
    ) -> RinsOutput {
        RinsOutput {
            time_s,
            status: RinsStatus::from(error.reason()),
            rejected_field: RinsField::from(error.field()),
            has_estimate: held.is_some(),
            estimate: held.map(RinsEstimate::from).unwrap_or_default(),
            heading_corrected_rad: f32::NAN,
            roll_corrected_rad: f32::NAN,
            pitch_corrected_rad: f32::NAN,
            health: RinsHealth::from(health),
        }
    }

    /// The estimate, when there is one.
    pub fn estimate(&self) -> Option<Estimate> {
        self.has_estimate.then(|| Estimate::from(&self.estimate))
    }

    /// The corrected attitude in the core's type.
    pub fn corrected(&self) -> Attitude {
        Attitude {
            heading_rad: self.heading_corrected_rad as Real,
            roll_rad: self.roll_corrected_rad as Real,
            pitch_rad: self.pitch_corrected_rad as Real,
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    /// The first code of a rejected sample's status.
    const REJECTED: u32 = 128;

    #[test]
    fn statuses_follow_the_cores_codes_and_names() {
        for s in Status::ALL {
            let c = RinsStatus::from(s);
            assert_eq!(c as u32, u32::from(s.code()), "{s:?}");
            assert_eq!(c.to_core(), Ok(s));
            assert_eq!(RinsStatus::from_code(c as u32), Some(c));
            assert_eq!(
                std::format!("{c:?}").to_lowercase(),
                s.name().replace('_', "")
            );
        }
        for r in RejectReason::ALL {
            let c = RinsStatus::from(r);
            assert_eq!(c as u32, REJECTED + u32::from(r as u8), "{r:?}");
            assert_eq!(c.to_core(), Err(r));
            assert_eq!(
                std::format!("{c:?}").to_lowercase(),
                std::format!("rejected{}", r.name().replace('_', ""))
            );
        }
        assert_eq!(
            RinsStatus::ALL.len(),
            Status::ALL.len() + RejectReason::ALL.len()
        );
        // The first code after the core's statuses is none.
        assert_eq!(RinsStatus::from_code(Status::ALL.len() as u32), None);
        assert_eq!(RinsStatus::from_code(127), None);
        for f in Field::ALL {
            assert_eq!(RinsField::from(Some(f)) as u32, u32::from(f as u8));
        }
    }
}
