//! The paper's Fig. 2 baseline: a Kalman filter straight on raw roll and pitch.
//!
//! States x1..x4; every second two scalar measurements, roll and pitch, with eq (2)'s rows
//! ([`crate::installation::Angles::roll_row`], [`crate::installation::Angles::pitch_row`]) as the
//! measurement model. The ship's sway, the low-frequency errors and the noise are all measurement
//! noise, of 1-sigma `traditional_sigma_rad`; `traditional_drift_rad_per_sqrt_s` adds process noise.
//! No correlation, no averaging. Implemented as honestly as ours: how well it does depends on those
//! two settings, which `host-sim` reports.

mod checkpoint;

use crate::config::Config;
use crate::gap_fill::GridSample;
use crate::kalman::ConstantStateKalman;
use crate::output::Estimate;
use crate::Real;

/// State of the traditional baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct Traditional {
    /// The 4-state filter of x1..x4.
    kf: ConstantStateKalman<Real, 4>,
    /// Measurement steps applied so far.
    updates: u32,
}

impl Traditional {
    /// Fresh state with the prior covariance.
    pub fn new(config: &Config) -> Self {
        Traditional {
            kf: match config.prior {
                Some(p) => ConstantStateKalman::with_mean(p.x_rad, p.sigma_rad),
                None => ConstantStateKalman::new([config.prior_sigma_rad; 4]),
            },
            updates: 0,
        }
    }

    /// Updates with this sample's roll and pitch.
    pub fn step(&mut self, config: &Config, interval: Real, sample: &GridSample) -> bool {
        let angles = &sample.angles;
        let q = config.traditional_drift_rad_per_sqrt_s
            * config.traditional_drift_rad_per_sqrt_s
            * interval;
        self.kf.predict(&[q; 4]);
        let r = config.traditional_sigma_rad * config.traditional_sigma_rad;
        let roll = self
            .kf
            .update(&angles.roll_row(), sample.roll_rad, r)
            .is_ok();
        let pitch = self
            .kf
            .update(&angles.pitch_row(), sample.pitch_rad, r)
            .is_ok();
        if roll || pitch {
            self.updates = self.updates.saturating_add(1);
        }
        roll || pitch
    }

    /// Current estimate and 1-sigma, once updated.
    pub fn estimate(&self) -> Option<Estimate> {
        if self.updates == 0 {
            return None;
        }
        Some(Estimate {
            x_rad: [
                self.kf.state()[0],
                self.kf.state()[1],
                self.kf.state()[2],
                self.kf.state()[3],
            ],
            sigma_rad: [
                self.kf.sigma(0),
                self.kf.sigma(1),
                self.kf.sigma(2),
                self.kf.sigma(3),
            ],
        })
    }
}
