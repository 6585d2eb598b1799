//! The windowed method's state in a checkpoint image (its layout: the module doc of
//! [`crate::checkpoint`]).
//!
//! Checked: the Kalman filter (see [`crate::kalman`]); residual means and their long means within
//! [`MAX_RESIDUAL`]; gains within `[0, 4]` (a gain is the magnitude of a window mean of products
//! of sines and cosines, minus a product of two such means); the per-product variances within
//! [`MAX_PRODUCT_VARIANCE_RAD2`]; powers and noise scales within [`MAX_NOISE_SCALE`]; drift shares
//! within `[0, 1]`; the low-pass stages within +-1; the window (see [`crate::moving_average`]),
//! whose layout must be the one the rotation period gives once it is known.

use super::Windowed;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, within_non_negative, CheckpointError, Part, MAX_RESIDUAL, R};
use crate::correlation::ReferenceFilter;
use crate::kalman::ConstantStateKalman;
use crate::moving_average::checkpoint::{correlation_window_len, expected_correlation};
use crate::moving_average::CorrelationWindow;
use crate::Real;

/// Largest residual power and noise scale restored: a residual mean of [`MAX_RESIDUAL`] over the
/// smallest standard error (about a 1e-7 rad product sigma averaged over one window), squared,
/// is far below; anything larger is a crafted image.
const MAX_NOISE_SCALE: Real = 1.0e30;

/// Largest per-product variance restored, rad^2: a 1 rad measurement sigma plus the window mean
/// of the fill variances (each below (4.1 x 90 deg)^2, times the saturated fill weight).
const MAX_PRODUCT_VARIANCE_RAD2: Real = 1.0e7;

/// Bytes of the state of a method with a ring of `cap` entries.
pub(crate) const fn checkpoint_len(cap: usize) -> usize {
    4 + 4
        + ConstantStateKalman::<Real, 4>::CHECKPOINT_LEN
        + 4 * R
        + (1 + 8)
        + 4 * R
        + 2 * R
        + (8 * R + 8 + 4 * R)
        + ReferenceFilter::CHECKPOINT_LEN
        + correlation_window_len(cap)
}

impl<const CAP: usize> Windowed<CAP> {
    /// Writes the state.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        let m = self;
        w.u32(m.updates);
        w.u32(m.entries_since_update);
        m.kf.write_checkpoint(w);
        for v in m.residual_mean {
            w.real(v);
        }
        w.u8(m.next_pair);
        for c in m.residual_count {
            w.u32(c);
        }
        for v in m.gains {
            w.real(v);
        }
        for v in m.product_variance_rad2 {
            w.real(v);
        }
        for v in m.residual_mean_long.into_iter().chain(m.residual_power) {
            w.real(v);
        }
        for c in m.long_count {
            w.u32(c);
        }
        for v in m.noise_scale.into_iter().chain(m.drift_share) {
            w.real(v);
        }
        m.reference.write_checkpoint(w);
        m.window.write_checkpoint(w);
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
        let entries_since_update = r.u32();
        let kf = ConstantStateKalman::read_checkpoint(r, max_variance)?;
        let residual_mean: [Real; 4] = core::array::from_fn(|_| r.real());
        let next_pair = r.u8();
        ensure(next_pair <= 1, CheckpointError::InvalidValue(Part::Residuals))?;
        let residual_count = [r.u32(), r.u32()];
        let gains: [Real; 4] = core::array::from_fn(|_| r.real());
        let product_variance_rad2: [Real; 2] = core::array::from_fn(|_| r.real());
        let residual_mean_long: [Real; 4] = core::array::from_fn(|_| r.real());
        let residual_power: [Real; 4] = core::array::from_fn(|_| r.real());
        let long_count = [r.u32(), r.u32()];
        let noise_scale: [Real; 2] = core::array::from_fn(|_| r.real());
        let drift_share: [Real; 2] = core::array::from_fn(|_| r.real());
        let reference = ReferenceFilter::read_checkpoint(r)?;
        // Variances: at most a filled sample's (a sum of 1 rad sigmas and 90 deg fills) per product.
        let in_range = residual_mean.iter().all(|v| within(*v, MAX_RESIDUAL as Real))
            && gains.iter().all(|g| within_non_negative(*g, 4.0))
            && product_variance_rad2.iter().all(|v| within_non_negative(*v, MAX_PRODUCT_VARIANCE_RAD2))
            && residual_mean_long.iter().all(|v| within(*v, MAX_RESIDUAL as Real))
            && residual_power.iter().chain(&noise_scale).all(|v| within_non_negative(*v, MAX_NOISE_SCALE))
            && drift_share.iter().all(|v| within_non_negative(*v, 1.0));
        ensure(in_range, CheckpointError::InvalidValue(Part::Residuals))?;
        CorrelationWindow::read_checkpoint(
            r,
            dst.as_deref_mut().map(|m| &mut m.window),
            expected_correlation::<CAP>(period_samples),
        )?;
        if let Some(m) = dst {
            m.updates = updates;
            m.entries_since_update = entries_since_update;
            m.kf = kf;
            m.residual_mean = residual_mean;
            m.next_pair = next_pair;
            m.residual_count = residual_count;
            m.gains = gains;
            m.product_variance_rad2 = product_variance_rad2;
            m.residual_mean_long = residual_mean_long;
            m.residual_power = residual_power;
            m.long_count = long_count;
            m.noise_scale = noise_scale;
            m.drift_share = drift_share;
            m.reference = reference;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{image_of, refused, reseal, running, tampered_part, Est};
    use crate::checkpoint::METHOD_OFFSET;
    use crate::config::{Config, Method};
    use CheckpointError::*;

    fn read_windowed(r: &mut Reader<'_>) -> Windowed<64> {
        let mut m = Windowed::new(&Config::with_method(Method::Windowed));
        Windowed::read_checkpoint(r, Some(&mut m), Some(120), f64::INFINITY).unwrap();
        m
    }

    #[test]
    fn a_tampered_windowed_state_is_refused_with_a_typed_error() {
        let base = running(Method::Windowed);
        let image = image_of(&base);
        let tampered = |edit: &dyn Fn(&mut Windowed<64>)| {
            tampered_part(&image, METHOD_OFFSET, read_windowed, edit, Windowed::write_checkpoint)
        };
        refused(&tampered(&|m| m.gains[3] = -0.5), InvalidValue(Part::Residuals));
        refused(&tampered(&|m| m.gains[1] = Real::NAN), InvalidValue(Part::Residuals));
        refused(&tampered(&|m| m.next_pair = 2), InvalidValue(Part::Residuals));
        refused(&tampered(&|m| m.drift_share[0] = 1.5), InvalidValue(Part::Residuals));
        // Regression, fuzz target `checkpoint_restore`: finite but absurd residuals and gains
        // (a flipped top byte) were accepted and overflowed the outputs.
        refused(&tampered(&|m| m.residual_mean[2] = 1e30), InvalidValue(Part::Residuals));
        refused(&tampered(&|m| m.gains[0] = 1e30), InvalidValue(Part::Residuals));
        // A zero gain (a window whose reference does not move) is a state the estimator can be in.
        let zero_gain = tampered(&|m| m.gains[3] = 0.0);
        assert!(Est::from_checkpoint(&zero_gain).is_ok());

        // The Kalman filter's checks (see `kalman/checkpoint.rs`) apply to the method's: a NaN
        // state in the image.
        let mut b = image.clone();
        let x2 = METHOD_OFFSET + 8 + 2 * R;
        b[x2..x2 + R].copy_from_slice(&Real::NAN.to_le_bytes());
        reseal(&mut b);
        refused(&b, InvalidValue(Part::KalmanState));
    }
}
