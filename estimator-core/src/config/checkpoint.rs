//! The configuration part (the method code is in the header): `rotation_period_s` (optional
//! f64), `sample_interval_s` (optional f64), `prior_sigma_rad`, `measurement_sigma_rad`,
//! `drift_rad_per_sqrt_s`, `traditional_sigma_rad`, `traditional_drift_rad_per_sqrt_s`,
//! `sway_gate_rad`, `converged_sigma_rad`, `rotation_period_tolerance`,
//! `change_detection_step_rad` (`R` each), `max_filled_gap_samples` (u32), `prior` (optional:
//! `x_rad` then `sigma_rad`, `R` each), `angle_latency_s` (f64).
//!
//! Checked: [`Config::check`] for the estimator's ring capacity, which bounds every value (ranges
//! of the pinned period and interval, sigmas, random walks, the gap that may be filled).

use super::{Config, Method, Prior};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{CheckpointError, Part, Stored, R};

/// What reading the configuration needs: the method the header names and the ring capacity of
/// the estimator restoring it.
#[derive(Clone, Copy)]
pub(crate) struct ConfigContext {
    pub(crate) method: Method,
    pub(crate) capacity: usize,
}

impl Stored for Config {
    const LEN: usize = 2 * (1 + 8) + 9 * R + 4 + (1 + 8 * R) + 8;
    type Context<'a> = ConfigContext;

    fn write(&self, w: &mut Writer<'_>) {
        let c = self;
        w.option(c.rotation_period_s, 0.0, |w, v| w.f64(v));
        w.option(c.sample_interval_s, 0.0, |w, v| w.f64(v));
        for v in [
            c.prior_sigma_rad,
            c.measurement_sigma_rad,
            c.drift_rad_per_sqrt_s,
            c.traditional_sigma_rad,
            c.traditional_drift_rad_per_sqrt_s,
            c.sway_gate_rad,
            c.converged_sigma_rad,
            c.rotation_period_tolerance,
            c.change_detection_step_rad,
        ] {
            w.real(v);
        }
        w.u32(c.max_filled_gap_samples);
        let none = Prior {
            x_rad: [0.0; 4],
            sigma_rad: [0.0; 4],
        };
        w.option(c.prior, none, |w, p| {
            for v in p.x_rad.into_iter().chain(p.sigma_rad) {
                w.real(v);
            }
        });
        w.f64(c.angle_latency_s);
    }

    fn read(r: &mut Reader<'_>, cx: ConfigContext) -> Result<Config, CheckpointError> {
        let rotation_period_s = r.option(Part::Config, |r| Ok(r.f64()))?;
        let sample_interval_s = r.option(Part::Config, |r| Ok(r.f64()))?;
        let config = Config {
            method: cx.method,
            rotation_period_s,
            sample_interval_s,
            prior_sigma_rad: r.real(),
            measurement_sigma_rad: r.real(),
            drift_rad_per_sqrt_s: r.real(),
            traditional_sigma_rad: r.real(),
            traditional_drift_rad_per_sqrt_s: r.real(),
            sway_gate_rad: r.real(),
            converged_sigma_rad: r.real(),
            rotation_period_tolerance: r.real(),
            change_detection_step_rad: r.real(),
            max_filled_gap_samples: r.u32(),
            prior: r.option(Part::Config, |r| {
                Ok(Prior {
                    x_rad: core::array::from_fn(|_| r.real()),
                    sigma_rad: core::array::from_fn(|_| r.real()),
                })
            })?,
            angle_latency_s: r.f64(),
        };
        config
            .check(cx.capacity)
            .map_err(CheckpointError::InvalidConfig)?;
        Ok(config)
    }
}
