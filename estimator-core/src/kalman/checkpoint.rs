//! A Kalman filter in a checkpoint image, in the filter's own float type (`Real`, or `f64` for the
//! paper method's filters): the `N` states, then the `N x N` covariance row by row.
//!
//! Checked: every state finite and within [`MAX_STATE`]; every covariance element finite, the
//! variances within the bound the caller gives; the covariance exactly symmetric and positive
//! definite ([`ConstantStateKalman::covariance_is_spd`]).

use super::ConstantStateKalman;
use crate::checkpoint::wire::{Float, Reader, Writer};
use crate::checkpoint::{ensure, CheckpointError, Part, Stored, MAX_STATE};

/// Read with the largest variance allowed (see [`crate::checkpoint::MAX_VARIANCE`]).
impl<T: Float, const N: usize> Stored for ConstantStateKalman<T, N> {
    const LEN: usize = core::mem::size_of::<T>() * (N + N * N);
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        for i in 0..N {
            w.float(self.x[i]);
        }
        for i in 0..N {
            for j in 0..N {
                w.float(self.p[(i, j)]);
            }
        }
    }

    /// States within [`MAX_STATE`], variances within `max_variance`, covariance symmetric
    /// positive definite.
    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Self, CheckpointError> {
        let mut kf = Self::new([T::zero(); N]);
        for i in 0..N {
            let v: T = r.float();
            ensure(
                v.is_finite() && v.to_f64().abs() <= MAX_STATE,
                CheckpointError::InvalidValue(Part::KalmanState),
            )?;
            kf.x[i] = v;
        }
        for i in 0..N {
            for j in 0..N {
                let v: T = r.float();
                let ok = v.is_finite() && (i != j || v.to_f64() <= max_variance);
                ensure(ok, CheckpointError::InvalidValue(Part::KalmanCovariance))?;
                kf.p[(i, j)] = v;
            }
        }
        ensure(
            kf.covariance_is_spd(),
            CheckpointError::NotPositiveDefinite(Part::KalmanCovariance),
        )?;
        Ok(kf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::checkpoint::tests::written_and_read;

    /// A filter after a few updates: states and a full covariance.
    fn updated<T: Float, const N: usize>(prior: T) -> ConstantStateKalman<T, N> {
        let mut kf = ConstantStateKalman::<T, N>::new([prior; N]);
        for k in 0..N + 2 {
            let h: [T; N] = core::array::from_fn(|i| nalgebra::convert(((i + k) % 3) as f64 - 0.7));
            kf.update(
                &h,
                nalgebra::convert(1e-4 * k as f64),
                nalgebra::convert(1e-10),
            )
            .unwrap();
        }
        kf
    }

    #[test]
    fn a_filter_round_trips_and_a_tampered_one_is_refused() {
        use CheckpointError::*;
        let kf = updated::<f32, 4>(1e-3);
        assert_eq!(written_and_read(&kf, 1e12), Ok(kf.clone()));
        let with = |f: &dyn Fn(&mut ConstantStateKalman<f32, 4>)| {
            let mut t = kf.clone();
            f(&mut t);
            written_and_read(&t, 1e12)
        };
        assert_eq!(
            with(&|t| t.x[2] = f32::NAN),
            Err(InvalidValue(Part::KalmanState))
        );
        assert_eq!(
            with(&|t| t.x[0] = 1e30),
            Err(InvalidValue(Part::KalmanState))
        );
        assert_eq!(
            with(&|t| t.p[(3, 3)] = f32::INFINITY),
            Err(InvalidValue(Part::KalmanCovariance))
        );
        assert_eq!(
            with(&|t| t.p[(1, 1)] = 1e30),
            Err(InvalidValue(Part::KalmanCovariance))
        );
        assert_eq!(
            with(&|t| t.p[(0, 1)] += 1e-12),
            Err(NotPositiveDefinite(Part::KalmanCovariance))
        );
        assert_eq!(
            with(&|t| t.p[(2, 2)] = -t.p[(2, 2)]),
            Err(NotPositiveDefinite(Part::KalmanCovariance))
        );

        // The paper method's filters, in f64: a finite but absurd state or variance is refused
        // (narrowed to f32 on output it would be infinite).
        let kf = updated::<f64, 3>(1e-3);
        assert_eq!(written_and_read(&kf, 1e12), Ok(kf.clone()));
        let with = |f: &dyn Fn(&mut ConstantStateKalman<f64, 3>)| {
            let mut t = kf.clone();
            f(&mut t);
            written_and_read(&t, 1e12)
        };
        assert_eq!(
            with(&|t| t.x[2] = 1e300),
            Err(InvalidValue(Part::KalmanState))
        );
        assert_eq!(
            with(&|t| t.p[(0, 0)] = 1e200),
            Err(InvalidValue(Part::KalmanCovariance))
        );
        assert_eq!(
            with(&|t| t.p[(1, 2)] = 2.0 * t.p[(1, 2)] + 1.0),
            Err(NotPositiveDefinite(Part::KalmanCovariance))
        );
    }
}
