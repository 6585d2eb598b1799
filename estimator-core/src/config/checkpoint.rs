//! The configuration part (the method code is in the header).
//!
//! Checked: [`Config::check`] for this capacity, which bounds every value (ranges of the pinned
//! period and interval, sigmas, random walks, the gap that may be filled).

use super::{Config, Method};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{CheckpointError, Part, R};

impl Config {
    /// Bytes of the part.
    pub(crate) const CHECKPOINT_LEN: usize = 2 * (1 + 8) + 9 * R + 4;

    /// Writes the part.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
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
    }

    /// Reads the configuration of a `CAP` estimator running `method` and checks it.
    pub(crate) fn read_checkpoint<const CAP: usize>(r: &mut Reader<'_>, method: Method) -> Result<Config, CheckpointError> {
        let rotation_period_s = r.option(Part::Config, |r| Ok(r.f64()))?;
        let sample_interval_s = r.option(Part::Config, |r| Ok(r.f64()))?;
        let config = Config {
            method,
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
        };
        config.check(CAP).map_err(CheckpointError::InvalidConfig)?;
        Ok(config)
    }
}
