//! The method part: the state of whichever method the header names, zero-padded to the longest.
//!
//! Checked: Kalman states within [`MAX_STATE`], variances within `max(`[`MAX_VARIANCE`]`, 4
//! prior^2)`, every covariance exactly symmetric and positive definite; residual means within
//! [`MAX_RESIDUAL`]; gains within `[0, 4]` (a gain is the magnitude of a window mean of
//! products of sines and cosines, minus a product of two such means); the paper's start time
//! finite and its integrals within the fixed-point range times the samples integrated; the window.

use super::wire::{Float, Reader, Writer};
#[cfg(feature = "paper-method")]
use super::windows::{read_average, write_average};
use super::windows::{correlation_window_len, expected_correlation, read_correlation, window_average_len, write_correlation};
use super::{ensure, within, within_non_negative, CheckpointError, Part, MAX_RESIDUAL, MAX_STATE, MAX_VARIANCE, R};
use crate::config::{Config, Method};
use crate::correlation::ReferenceFilter;
use crate::kalman::ConstantStateKalman;
#[cfg(feature = "paper-method")]
use crate::methods::Paper;
use crate::methods::{MethodState, Traditional, Windowed};
#[cfg(feature = "paper-method")]
use crate::moving_average::{WindowAverage, MAX_MAGNITUDE};
use crate::Real;

const fn kalman_len(scalar_bytes: usize, n: usize) -> usize {
    scalar_bytes * (n + n * n)
}

const fn windowed_len(cap: usize) -> usize {
    4 + 4 + kalman_len(R, 4) + 4 * R + (1 + 8) + 4 * R + 2 * R + (8 * R + 8 + 4 * R) + (1 + 12 * R) + correlation_window_len(cap)
}

const fn paper_len(cap: usize) -> usize {
    4 + 4 + 8 + 4 * 8 + 4 * kalman_len(8, 3) + window_average_len(4, cap)
}

const fn traditional_len() -> usize {
    4 + kalman_len(R, 4)
}

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// Bytes of the method part for ring capacity `cap`: the longest of the three methods. (The
/// paper's layout is kept in a build without it, so that the image length does not depend on
/// the features.)
pub(super) const fn max_len(cap: usize) -> usize {
    max(windowed_len(cap), max(paper_len(cap), traditional_len()))
}

/// Bytes the method actually writes (for the layout test).
#[cfg(test)]
pub(super) const fn len(method: Method, cap: usize) -> usize {
    match method {
        Method::Windowed => windowed_len(cap),
        Method::Paper => paper_len(cap),
        Method::Traditional => traditional_len(),
    }
}

fn write_kalman<T: Float, const N: usize>(w: &mut Writer<'_>, kf: &ConstantStateKalman<T, N>) {
    for i in 0..N {
        w.float(kf.x[i]);
    }
    for i in 0..N {
        for j in 0..N {
            w.float(kf.p[(i, j)]);
        }
    }
}

/// Reads a Kalman filter into `kf` and checks it: states within [`MAX_STATE`], variances within
/// `max_variance`, covariance symmetric positive definite.
fn read_kalman<T: Float, const N: usize>(
    r: &mut Reader<'_>,
    kf: &mut ConstantStateKalman<T, N>,
    max_variance: f64,
) -> Result<(), CheckpointError> {
    for i in 0..N {
        let v: T = r.float();
        ensure(v.is_finite() && v.to_f64().abs() <= MAX_STATE, CheckpointError::InvalidValue(Part::KalmanState))?;
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
    ensure(kf.covariance_is_spd(), CheckpointError::NotPositiveDefinite(Part::KalmanCovariance))
}

pub(super) fn write<const CAP: usize>(w: &mut Writer<'_>, state: &MethodState<CAP>) {
    match state {
        MethodState::Windowed(m) => {
            w.u32(m.updates);
            w.u32(m.entries_since_update);
            write_kalman(w, &m.kf);
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
            w.flag(m.reference.started);
            for stage in m.reference.stages {
                for v in stage {
                    w.real(v);
                }
            }
            write_correlation(w, &m.window);
        }
        #[cfg(feature = "paper-method")]
        MethodState::Paper(m) => {
            w.u32(m.updates);
            w.u32(m.samples);
            w.f64(m.start_time_s);
            for v in m.integrals {
                w.i64(v);
            }
            for kf in &m.kf {
                write_kalman(w, kf);
            }
            write_average(w, &m.window);
        }
        MethodState::Traditional(m) => {
            w.u32(m.updates);
            write_kalman(w, &m.kf);
        }
    }
}

/// Reads and checks the method part for `config` (whose method the header named) and the rotation
/// period, if known. With `dst` (a state already reset to `config`'s method), also writes it there.
pub(super) fn read<const CAP: usize>(
    r: &mut Reader<'_>,
    config: &Config,
    period_samples: Option<u32>,
    dst: Option<&mut MethodState<CAP>>,
) -> Result<(), CheckpointError> {
    let prior = f64::from(config.prior_sigma_rad);
    let max_variance = MAX_VARIANCE.max(4.0 * prior * prior);
    match config.method {
        Method::Windowed => {
            let dst = match dst {
                Some(MethodState::Windowed(m)) => Some(m),
                _ => None,
            };
            read_windowed(r, dst, period_samples, max_variance)
        }
        #[cfg(feature = "paper-method")]
        Method::Paper => {
            let dst = match dst {
                Some(MethodState::Paper(m)) => Some(m),
                _ => None,
            };
            read_paper(r, dst, period_samples, max_variance)
        }
        // Not reached: `Config::check` refused the configuration.
        #[cfg(not(feature = "paper-method"))]
        Method::Paper => Err(CheckpointError::InvalidConfig(crate::config::ConfigError::MethodUnavailable)),
        Method::Traditional => {
            let dst = match dst {
                Some(MethodState::Traditional(m)) => Some(m),
                _ => None,
            };
            read_traditional(r, dst, max_variance)
        }
    }
}

fn read_windowed<const CAP: usize>(
    r: &mut Reader<'_>,
    mut dst: Option<&mut Windowed<CAP>>,
    period_samples: Option<u32>,
    max_variance: f64,
) -> Result<(), CheckpointError> {
    let updates = r.u32();
    let entries_since_update = r.u32();
    let mut kf = ConstantStateKalman::new([0.0; 4]);
    read_kalman(r, &mut kf, max_variance)?;
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
    let start = r.pos();
    let started = r.flag(Part::Residuals)?;
    let stages: [[Real; 4]; 3] = core::array::from_fn(|_| core::array::from_fn(|_| r.real()));
    if !started {
        r.zeros_since(start, Part::Residuals)?;
    }
    // Variances: at most a filled sample's (a sum of 1 rad sigmas and 90 deg fills) per product.
    let in_range = residual_mean.iter().all(|v| within(*v, MAX_RESIDUAL as Real))
        && gains.iter().all(|g| within_non_negative(*g, 4.0))
        && product_variance_rad2.iter().all(|v| within_non_negative(*v, MAX_PRODUCT_VARIANCE_RAD2))
        && residual_mean_long.iter().all(|v| within(*v, MAX_RESIDUAL as Real))
        && residual_power.iter().chain(&noise_scale).all(|v| within_non_negative(*v, MAX_NOISE_SCALE))
        && drift_share.iter().all(|v| within_non_negative(*v, 1.0))
        && stages.iter().flatten().all(|c| within(*c, 1.0));
    ensure(in_range, CheckpointError::InvalidValue(Part::Residuals))?;
    read_correlation(r, dst.as_deref_mut().map(|m| &mut m.window), expected_correlation::<CAP>(period_samples))?;
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
        m.reference = ReferenceFilter { stages, started };
    }
    Ok(())
}

/// Largest residual power and noise scale restored: a residual mean of [`MAX_RESIDUAL`] over the
/// smallest standard error (about a 1e-7 rad product sigma averaged over one window), squared,
/// is far below; anything larger is a crafted image.
const MAX_NOISE_SCALE: Real = 1.0e30;

/// Largest per-product variance restored, rad^2: a 1 rad measurement sigma plus the window mean
/// of the fill variances (each below (4.1 x 90 deg)^2, times the saturated fill weight).
const MAX_PRODUCT_VARIANCE_RAD2: Real = 1.0e7;

#[cfg(feature = "paper-method")]
fn read_paper<const CAP: usize>(
    r: &mut Reader<'_>,
    mut dst: Option<&mut Paper<CAP>>,
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
        read_kalman(r, kf, max_variance)?;
    }
    let expected_len = period_samples.map(|p| (p as usize).clamp(1, CAP.max(1)));
    read_average(r, dst.as_deref_mut().map(|m| &mut m.window), expected_len)?;
    if let Some(m) = dst {
        m.updates = updates;
        m.samples = samples;
        m.start_time_s = start_time_s;
        m.integrals = integrals;
        m.kf = kfs;
    }
    Ok(())
}

fn read_traditional(r: &mut Reader<'_>, dst: Option<&mut Traditional>, max_variance: f64) -> Result<(), CheckpointError> {
    let updates = r.u32();
    let mut kf = ConstantStateKalman::new([0.0; 4]);
    read_kalman(r, &mut kf, max_variance)?;
    if let Some(m) = dst {
        m.updates = updates;
        m.kf = kf;
    }
    Ok(())
}
