//! The paper method's state in a checkpoint image (its layout: the module doc of
//! [`crate::checkpoint`]; its length, [`super::super::checkpoint::paper_len`], is known in a build
//! without the method too).
//!
//! Checked: the start time finite; the integrals within the fixed-point range times the samples
//! integrated; the Kalman filters (see [`crate::kalman`]); the window (see
//! [`crate::moving_average`]), whose length must be the rotation period once it is known.

use super::Paper;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, CheckpointError, Part};
use crate::kalman::ConstantStateKalman;
use crate::moving_average::{WindowAverage, MAX_MAGNITUDE};

impl<const CAP: usize> Paper<CAP> {
    /// Writes the state.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        w.u32(self.updates);
        w.u32(self.samples);
        w.f64(self.start_time_s);
        for v in self.integrals {
            w.i64(v);
        }
        for kf in &self.kf {
            kf.write_checkpoint(w);
        }
        self.window.write_checkpoint(w);
    }

    /// Reads and checks the state for a rotation period of `period_samples`, if known, and
    /// variances up to `max_variance`. With `dst`, also writes it there.
    pub(crate) fn read_checkpoint(
        r: &mut Reader<'_>,
        mut dst: Option<&mut Self>,
        period_samples: Option<u32>,
        max_variance: f64,
    ) -> Result<(), CheckpointError> {
        let updates = r.u32();
        let samples = r.u32();
        let start_time_s = r.f64();
        ensure(start_time_s.is_finite(), CheckpointError::InvalidValue(Part::PaperStartTime))?;
        let bound = i64::from(WindowAverage::<4, CAP>::quantize(MAX_MAGNITUDE)) * i64::from(samples);
        let integrals: [i64; 4] = core::array::from_fn(|_| r.i64());
        ensure(integrals.iter().all(|v| (-bound..=bound).contains(v)), CheckpointError::InvalidValue(Part::PaperIntegrals))?;
        let mut kfs: [ConstantStateKalman<f64, 3>; 4] = core::array::from_fn(|_| ConstantStateKalman::new([0.0; 3]));
        for kf in kfs.iter_mut() {
            *kf = ConstantStateKalman::read_checkpoint(r, max_variance)?;
        }
        let expected_len = period_samples.map(|p| (p as usize).clamp(1, CAP.max(1)));
        WindowAverage::read_checkpoint(r, dst.as_deref_mut().map(|m| &mut m.window), expected_len)?;
        if let Some(m) = dst {
            m.updates = updates;
            m.samples = samples;
            m.start_time_s = start_time_s;
            m.integrals = integrals;
            m.kf = kfs;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{image_of, refused, reseal, running, tampered_part};
    use crate::checkpoint::METHOD_OFFSET;
    use crate::config::{Config, Method};
    use CheckpointError::*;

    fn read_paper(r: &mut Reader<'_>) -> Paper<64> {
        let mut m = Paper::new(&Config::with_method(Method::Paper));
        Paper::read_checkpoint(r, Some(&mut m), Some(120), f64::INFINITY).unwrap();
        m
    }

    #[test]
    fn a_tampered_paper_state_is_refused_with_a_typed_error() {
        let image = image_of(&running(Method::Paper));
        let tampered =
            |edit: &dyn Fn(&mut Paper<64>)| tampered_part(&image, METHOD_OFFSET, read_paper, edit, Paper::write_checkpoint);
        refused(&tampered(&|m| m.start_time_s = f64::NAN), InvalidValue(Part::PaperStartTime));
        refused(&tampered(&|m| m.integrals[1] = i64::MAX), InvalidValue(Part::PaperIntegrals));
        // Regression, fuzz target `checkpoint_restore`: the first filter's b2 state with its top
        // byte flipped (finite, ~1e300 in f64) was accepted, and the next update moved x1 beyond
        // f32 range. The Kalman filter's checks (see `kalman/checkpoint.rs`) refuse it.
        let mut b = image.clone();
        let b2 = METHOD_OFFSET + 4 + 4 + 8 + 4 * 8 + 2 * 8;
        b[b2..b2 + 8].copy_from_slice(&1e300f64.to_le_bytes());
        reseal(&mut b);
        refused(&b, InvalidValue(Part::KalmanState));
    }
}
