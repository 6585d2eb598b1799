//! The paper's method, literally: eqs (8), (11), (13)-(18), kept for comparison.
//!
//! For each error j, with its correlation channel p_j of [`crate::correlation`]:
//! - eq (8): `R_j(t) = (sum of p_j from the start to t) / n`, n samples since the start
//!   (the integral is kept exactly, in fixed point);
//! - eq (11): `Rbar_j` = mean of `R_j` over the last W samples, belonging to the window's middle
//!   `t_c = t - (W-1)/2` samples;
//! - eqs (13)-(18): a 3-state filter (in `f64`, see [`crate::kalman`]) `(x_j, b1, b2)` with `H = (c_j, cos w_e t_c, sin w_e t_c)`, where
//!   `c_j` is the channel's gain from the derivation in [`crate::correlation`]:
//!   `1/2` (x1), `-1/2` (x2), `cosL/2` (x3, the paper's eq 17), `-cosL/2` (x4).
//!
//! What this cannot do: the leakage of x1, x2 into `Rbar_3`, `Rbar_4` is
//! `-x1 sinL (1 - cos w_e t)/(2 w_e t) - x2 sinL sin(w_e t)/(2 w_e t)` (our derivation; the paper's
//! eq 12 has x1 and x2 exchanged), and the constant `b1, b2` of eq (13) fit a `1/t` curve only
//! approximately; the `a0 (1 - cos rho)/(w_r t)` transient of a constant attitude error is not
//! modelled at all. `host-sim` reports what it achieves.

pub(crate) mod checkpoint;

use crate::config::Config;
use crate::correlation::products;
use crate::gap_fill::GridSample;
use crate::kalman::ConstantStateKalman;
use crate::moving_average::{WindowAverage, COUNTS_PER_UNIT};
use crate::output::Estimate;
use crate::sample::Attitude;
use crate::units::EARTH_RATE_RAD_PER_S;
use crate::Real;

/// State of the paper's method.
#[derive(Clone, Debug, PartialEq)]
pub struct Paper<const CAP: usize> {
    /// Exact fixed-point integrals of the four products since the start (eq 8 numerator).
    integrals: [i64; 4],
    /// Samples integrated.
    samples: u32,
    /// Time of the first integrated sample, s.
    start_time_s: f64,
    /// Moving average of `R_j(t)` (eq 11).
    window: WindowAverage<4, CAP>,
    /// One `(x_j, b1, b2)` filter per error (eqs 15-18).
    kf: [ConstantStateKalman<f64, 3>; 4],
    /// Measurement steps applied so far.
    updates: u32,
}

impl<const CAP: usize> Paper<CAP> {
    /// The moving average of the correlation integrals.
    pub fn window(&self) -> &WindowAverage<4, CAP> {
        &self.window
    }

    /// Fresh state.
    pub fn new(config: &Config) -> Self {
        let s = config.prior_sigma_rad as f64;
        Paper {
            integrals: [0; 4],
            samples: 0,
            start_time_s: 0.0,
            window: WindowAverage::new(CAP),
            kf: core::array::from_fn(|_| ConstantStateKalman::new([s, s, s])),
            updates: 0,
        }
    }

    /// Back to the state of [`Paper::new`], in place (see [`WindowAverage::reset`]).
    pub fn reset(&mut self, config: &Config) {
        let s = config.prior_sigma_rad as f64;
        self.integrals = [0; 4];
        self.samples = 0;
        self.start_time_s = 0.0;
        self.window.reset(CAP);
        self.kf = core::array::from_fn(|_| ConstantStateKalman::new([s, s, s]));
        self.updates = 0;
    }

    /// Sets the moving average to one period (this method does not bin: a period longer than the
    /// ring is averaged over the ring's length).
    pub fn configure(&mut self, period_samples: u32) {
        self.window.reset(period_samples as usize);
    }

    /// Integrates one sample, averages, and updates the four filters once the window is full.
    pub fn step(&mut self, config: &Config, interval_s: f64, sample: &GridSample) -> bool {
        let time_s = f64::from(sample.index) * interval_s;
        if self.samples == 0 {
            self.start_time_s = time_s;
        }
        let angles = &sample.angles;
        let attitude = Attitude {
            heading_rad: 0.0,
            roll_rad: sample.roll_rad,
            pitch_rad: sample.pitch_rad,
        };
        let p = products(&attitude, angles);
        let mut r_t = [0.0; 4];
        self.samples = self.samples.saturating_add(1);
        for ch in 0..4 {
            self.integrals[ch] += i64::from(WindowAverage::<4, CAP>::quantize(p[ch]));
            r_t[ch] = self.integrals[ch] as Real / (COUNTS_PER_UNIT * self.samples as Real);
        }
        self.window.push(&r_t);
        let Some(r_bar) = self.window.means() else {
            return false;
        };
        let half_window_s = (self.window.len() - 1) as f64 * 0.5 * interval_s;
        let t_c = time_s - self.start_time_s - half_window_s;
        let phase = EARTH_RATE_RAD_PER_S * t_c;
        let (sin_e, cos_e) = (libm::sin(phase), libm::cos(phase));
        let half_cos_lat = 0.5 * angles.cos_lat as f64;
        let gains = [0.5, -0.5, half_cos_lat, -half_cos_lat];
        let sigma = config.measurement_sigma_rad as f64;
        let mut applied = false;
        for j in 0..4 {
            // No prediction step: eq (18) neglects the state equation (constant states, Q = 0).
            applied |= self.kf[j]
                .update(&[gains[j], cos_e, sin_e], r_bar[j] as f64, sigma * sigma)
                .is_ok();
        }
        if applied {
            self.updates = self.updates.saturating_add(1);
        }
        applied
    }

    /// Restarts the moving average (the integrals go on, as eq 8 runs from the start).
    pub fn restart_window(&mut self) {
        self.window.clear();
    }

    /// Current estimate and 1-sigma, once updated.
    pub fn estimate(&self) -> Option<Estimate> {
        if self.updates == 0 {
            return None;
        }
        Some(Estimate {
            x_rad: core::array::from_fn(|j| self.kf[j].state()[0] as Real),
            sigma_rad: core::array::from_fn(|j| self.kf[j].sigma(0) as Real),
        })
    }
}
