//! The windowed method in a checkpoint image: what it learned, not its window. In order: updates
//! (u32), the Kalman filter (`x` 4 `R`, `P` 16 `R` row-major), residual means (4 `R`), the pair the
//! next update takes (u8: 0 pitch, 1 roll), residuals averaged per pair (2 x u32), channel gains
//! (4 `R`), the per-product variances of the pitch and roll channels (2 `R`), the long means of
//! the residual means (4 `R`) and of their powers (4 `R`), the residual means in the long
//! averages per pair (2 x u32), the noise scale and the drift share per pair (2 + 2 `R`). The
//! window, the low-pass of its references and the entries since the last update are not kept: the
//! next period of samples refills them (the window restarts, as after a long gap).
//!
//! Checked: the Kalman filter (see [`crate::kalman`]); residual means and their long means within
//! [`MAX_RESIDUAL`]; gains within `[0, 4]` (a gain is the magnitude of a window mean of products
//! of sines and cosines, minus a product of two such means); the per-product variances within
//! [`MAX_PRODUCT_VARIANCE_RAD2`]; powers and noise scales within [`MAX_NOISE_SCALE`]; drift shares
//! within `[0, 1]`; the pair 0 or 1.

use super::Windowed;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, within_non_negative, CheckpointError, Part, Stored, MAX_RESIDUAL, R};
use crate::kalman::ConstantStateKalman;
use crate::Real;

/// Largest residual power and noise scale restored: a residual mean of [`MAX_RESIDUAL`] over the
/// smallest standard error (about a 1e-7 rad product sigma averaged over one window), squared,
/// is far below; anything larger is a crafted image.
const MAX_NOISE_SCALE: Real = 1.0e30;

/// Largest per-product variance restored, rad^2: a 1 rad measurement sigma plus the window mean
/// of the fill variances (each below (4.1 x 90 deg)^2, times the saturated fill weight).
const MAX_PRODUCT_VARIANCE_RAD2: Real = 1.0e7;

/// What a restart keeps of the windowed method (the fields of [`Windowed`] of the same names).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Learned {
    updates: u32,
    kf: ConstantStateKalman<Real, 4>,
    residual_mean: [Real; 4],
    next_pair: u8,
    residual_count: [u32; 2],
    gains: [Real; 4],
    product_variance_rad2: [Real; 2],
    residual_mean_long: [Real; 4],
    residual_power: [Real; 4],
    long_count: [u32; 2],
    noise_scale: [Real; 2],
    drift_share: [Real; 2],
}

impl<const CAP: usize> Windowed<CAP> {
    /// What a restart keeps.
    pub(crate) fn learned(&self) -> Learned {
        Learned {
            updates: self.updates,
            kf: self.kf.clone(),
            residual_mean: self.residual_mean,
            next_pair: self.next_pair,
            residual_count: self.residual_count,
            gains: self.gains,
            product_variance_rad2: self.product_variance_rad2,
            residual_mean_long: self.residual_mean_long,
            residual_power: self.residual_power,
            long_count: self.long_count,
            noise_scale: self.noise_scale,
            drift_share: self.drift_share,
        }
    }

    /// Takes over what a restart keeps (into a fresh state, at restore); the window stays empty.
    pub(crate) fn keep_learned(&mut self, l: Learned) {
        self.updates = l.updates;
        self.kf = l.kf;
        self.residual_mean = l.residual_mean;
        self.next_pair = l.next_pair;
        self.residual_count = l.residual_count;
        self.gains = l.gains;
        self.product_variance_rad2 = l.product_variance_rad2;
        self.residual_mean_long = l.residual_mean_long;
        self.residual_power = l.residual_power;
        self.long_count = l.long_count;
        self.noise_scale = l.noise_scale;
        self.drift_share = l.drift_share;
    }
}

/// Read with the largest variance allowed (see [`crate::checkpoint::MAX_VARIANCE`]).
impl Stored for Learned {
    const LEN: usize = 4 + ConstantStateKalman::<Real, 4>::LEN + 4 * R + 1 + 8 + 4 * R + 2 * R + 8 * R + 8 + 4 * R;
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        let m = self;
        w.u32(m.updates);
        m.kf.write(w);
        for v in m.residual_mean {
            w.real(v);
        }
        w.u8(m.next_pair);
        for c in m.residual_count {
            w.u32(c);
        }
        for v in m.gains.into_iter().chain(m.product_variance_rad2) {
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
    }

    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Learned, CheckpointError> {
        let updates = r.u32();
        let kf = ConstantStateKalman::read(r, max_variance)?;
        let residual_mean: [Real; 4] = core::array::from_fn(|_| r.real());
        let next_pair = r.u8();
        ensure(next_pair <= 1, CheckpointError::InvalidValue(Part::Residuals))?;
        let m = Learned {
            updates,
            kf,
            residual_mean,
            next_pair,
            residual_count: [r.u32(), r.u32()],
            gains: core::array::from_fn(|_| r.real()),
            product_variance_rad2: core::array::from_fn(|_| r.real()),
            residual_mean_long: core::array::from_fn(|_| r.real()),
            residual_power: core::array::from_fn(|_| r.real()),
            long_count: [r.u32(), r.u32()],
            noise_scale: core::array::from_fn(|_| r.real()),
            drift_share: core::array::from_fn(|_| r.real()),
        };
        let in_range = m.residual_mean.iter().all(|v| within(*v, MAX_RESIDUAL as Real))
            && m.gains.iter().all(|g| within_non_negative(*g, 4.0))
            && m.product_variance_rad2.iter().all(|v| within_non_negative(*v, MAX_PRODUCT_VARIANCE_RAD2))
            && m.residual_mean_long.iter().all(|v| within(*v, MAX_RESIDUAL as Real))
            && m.residual_power.iter().chain(&m.noise_scale).all(|v| within_non_negative(*v, MAX_NOISE_SCALE))
            && m.drift_share.iter().all(|v| within_non_negative(*v, 1.0));
        ensure(in_range, CheckpointError::InvalidValue(Part::Residuals))?;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{running, written_and_read};
    use crate::config::Method;
    use crate::methods::MethodState;
    use CheckpointError::*;

    #[test]
    fn a_tampered_windowed_state_is_refused_with_a_typed_error() {
        let est = running(Method::Windowed);
        let MethodState::Windowed(m) = est.method_for_test() else { unreachable!() };
        let base = m.learned();
        let with = |edit: &dyn Fn(&mut Learned)| {
            let mut t = base.clone();
            edit(&mut t);
            written_and_read(&t, 1e12)
        };
        assert_eq!(with(&|_| {}), Ok(base.clone()));
        assert_eq!(with(&|m| m.gains[3] = -0.5), Err(InvalidValue(Part::Residuals)));
        assert_eq!(with(&|m| m.gains[1] = Real::NAN), Err(InvalidValue(Part::Residuals)));
        assert_eq!(with(&|m| m.next_pair = 2), Err(InvalidValue(Part::Residuals)));
        assert_eq!(with(&|m| m.drift_share[0] = 1.5), Err(InvalidValue(Part::Residuals)));
        // Regression, fuzz target `checkpoint_restore`: finite but absurd residuals and gains
        // (a flipped top byte) were accepted and overflowed the outputs.
        assert_eq!(with(&|m| m.residual_mean[2] = 1e30), Err(InvalidValue(Part::Residuals)));
        assert_eq!(with(&|m| m.gains[0] = 1e30), Err(InvalidValue(Part::Residuals)));
        // A zero gain (a window whose reference does not move) is a state the estimator can be in.
        assert!(with(&|m| m.gains[3] = 0.0).is_ok());
        // The Kalman filter's checks (see `kalman/checkpoint.rs`) apply to the method's.
        assert_eq!(with(&|m| m.kf = ConstantStateKalman::new([Real::NAN; 4])), Err(InvalidValue(Part::KalmanCovariance)));
    }
}
