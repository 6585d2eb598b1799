//! The attitude with eq (2)'s oscillation for the current estimate removed: what each step
//! returns ([`crate::Output::corrected`]) and what [`Estimator::compensate`] computes for an
//! attitude sample between steps, bit for bit the same for the same sample and estimate.
//!
//! Both use the same sines and cosines: the latitude's are cached by the step and reused when the
//! latitude is the one cached, and the rotation angle is carried forward over
//! [`crate::Config::angle_latency_s`] at the rate of the last step on the grid (the angle at the
//! row's time, when the attitude was taken); a latency of 0 leaves the sample as it is.

use super::Estimator;
use crate::installation::Angles;
use crate::math::{sin_cos, wrap_pi};
use crate::sample::{Attitude, Sample, SampleError};
use crate::time_grid::Placement;
use crate::Real;

impl<const CAP: usize> Estimator<CAP> {
    /// The attitude of `sample` with eq (2)'s oscillation for the current estimate removed, without
    /// stepping the estimator: what [`Estimator::step`] returns as [`crate::Output::corrected`] for
    /// the same sample and estimate, bit for bit, at the cost of eq (2) alone (the sines and
    /// cosines of rho, rho - s and L and twelve products). For a navigation computer whose attitude
    /// comes faster than the estimator's grid: every attitude sample is compensated with the
    /// estimate of the last step, and only the grid's samples are stepped. The sample's time is not
    /// used (its fields are checked as a step checks them).
    ///
    /// Returns [`CompensateError::NoEstimate`] before the filter's first measurement and
    /// [`CompensateError::Rejected`] for a sample a step would refuse on its fields; the estimator
    /// is never changed.
    pub fn compensate(&self, sample: &Sample) -> Result<Attitude, CompensateError> {
        sample.check().map_err(CompensateError::Rejected)?;
        let estimate = self
            .method
            .estimate(&self.config)
            .ok_or(CompensateError::NoEstimate)?;
        let sample = &self.carried(sample);
        let angles = Angles::new(
            sample.rotation_rad,
            sample.platform_rad,
            self.latitude_sin_cos(sample.latitude_rad),
        );
        Ok(corrected(&angles, &sample.attitude, &estimate.x_rad))
    }

    /// `sample` with its rotation angle carried forward over [`crate::Config::angle_latency_s`] at
    /// the rate of the last step on the grid (`rho + rate S`, wrapped to [-pi, pi)): the angle at
    /// the row's time, when the attitude was taken. The rate is the change of the angle over the
    /// last one or two grid intervals (the grid's interval, not the stamps: jittered stamps would
    /// make it jitter); across a longer gap or a clock step the last rate is kept. A latency of 0
    /// returns the sample as it is.
    pub(super) fn carry_rotation(&mut self, sample: &Sample, placement: Placement) -> Sample {
        if !self.latency_set() {
            return *sample;
        }
        if let (Some(last), Placement::OnGrid { intervals }, Some(interval_s)) = (
            self.run.last_rotation_rad,
            placement,
            self.run.grid.placing_interval_s(),
        ) {
            if (1..=2).contains(&intervals) {
                self.run.rotation_rate_rad_s = wrap_pi(sample.rotation_rad - last)
                    / (f64::from(intervals) * interval_s) as Real;
            }
        }
        self.run.last_rotation_rad = Some(sample.rotation_rad);
        self.carried(sample)
    }

    /// `sample` with its rotation angle carried forward at the last rate (see
    /// [`Estimator::carry_rotation`]); unchanged while the latency is 0.
    fn carried(&self, sample: &Sample) -> Sample {
        let mut s = *sample;
        if self.latency_set() {
            s.rotation_rad = wrap_pi(
                s.rotation_rad + self.run.rotation_rate_rad_s * self.config.angle_latency_s as Real,
            );
        }
        s
    }

    /// Whether a latency is configured: its bits, not a double-precision comparison (a library call
    /// on the Cortex-M4F, on every step).
    fn latency_set(&self) -> bool {
        self.config.angle_latency_s.to_bits() << 1 != 0
    }

    /// `(sin L, cos L)` of `latitude_rad`: the step's cached values when the latitude is the one it
    /// cached (so that [`Estimator::compensate`] computes what the step does, bit for bit).
    fn latitude_sin_cos(&self, latitude_rad: Real) -> (Real, Real) {
        if latitude_rad == self.run.latitude_trig.0 {
            (self.run.latitude_trig.1, self.run.latitude_trig.2)
        } else {
            sin_cos(latitude_rad)
        }
    }

    pub(super) fn angles(&mut self, sample: &Sample) -> Angles {
        if sample.latitude_rad != self.run.latitude_trig.0 {
            let (s, c) = sin_cos(sample.latitude_rad);
            self.run.latitude_trig = (sample.latitude_rad, s, c);
        }
        Angles::new(
            sample.rotation_rad,
            sample.platform_rad,
            (self.run.latitude_trig.1, self.run.latitude_trig.2),
        )
    }
}

/// `attitude` with eq (2)'s oscillation for `x_rad` at `angles` removed; the heading wrapped to
/// [-pi, pi].
pub(super) fn corrected(angles: &Angles, attitude: &Attitude, x_rad: &[Real; 4]) -> Attitude {
    let d = angles.oscillation(x_rad);
    Attitude {
        heading_rad: wrap_pi(attitude.heading_rad - d.heading_rad),
        roll_rad: attitude.roll_rad - d.roll_rad,
        pitch_rad: attitude.pitch_rad - d.pitch_rad,
    }
}

/// Why [`Estimator::compensate`] returned no attitude.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompensateError {
    /// There is no estimate yet: the attitude is the RINS's own.
    NoEstimate,
    /// A field of the sample is one a step would refuse (NaN, infinite, out of range).
    Rejected(SampleError),
}

impl core::fmt::Display for CompensateError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CompensateError::NoEstimate => f.write_str("no estimate yet"),
            CompensateError::Rejected(e) => write!(f, "sample refused: {e}"),
        }
    }
}
