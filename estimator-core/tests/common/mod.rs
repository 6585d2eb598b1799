//! A small deterministic RINS signal for the core's tests: sinusoidal sway (eq 4), eq (2)'s
//! oscillation for known errors, a constant low-frequency error (eq 5's a0) and optional white
//! noise. Computed in f64; the scenario generator of `host-sim` is the full-featured one.
#![allow(dead_code)]

use estimator_core::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
use estimator_core::Sample;
use std::f64::consts::PI;

pub struct Signal {
    pub x_arcsec: [f64; 4],
    pub latitude_deg: f64,
    pub roll_sway_deg: f64,
    pub pitch_sway_deg: f64,
    pub low_frequency_deg: f64,
    pub noise_arcsec: f64,
    pub rotation_period_s: f64,
    pub scheme: Scheme,
    pub rotation_phase_rad: f64,
    pub platform_phase_rad: f64,
    state: u64,
}

impl Signal {
    pub fn new(x_arcsec: [f64; 4], latitude_deg: f64) -> Signal {
        Signal {
            x_arcsec,
            latitude_deg,
            roll_sway_deg: 3.0,
            pitch_sway_deg: 1.0,
            low_frequency_deg: 0.05,
            noise_arcsec: 0.0,
            rotation_period_s: 480.0,
            scheme: Scheme::OneWay(1.0),
            rotation_phase_rad: 0.7,
            platform_phase_rad: 1.9,
            state: 0x1234_5678,
        }
    }

    fn noise(&mut self) -> f64 {
        // Sum of 4 uniforms: roughly normal, unit variance.
        let mut acc = 0.0;
        for _ in 0..4 {
            self.state = self.state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            acc += (self.state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        }
        acc * (3.0f64).sqrt()
    }

    /// Rotation angle, platform angle and latitude at time `t`, rad.
    pub fn angles(&self, t: f64) -> (f64, f64, f64) {
        (
            self.rotation_phase_rad + self.scheme.angle_rad(t, self.rotation_period_s),
            self.platform_phase_rad + EARTH_RATE_RAD_PER_S * t,
            self.latitude_deg * RAD_PER_DEG,
        )
    }

    /// Eq (2), f64: heading, roll, pitch errors in rad.
    pub fn oscillation(&self, t: f64) -> [f64; 3] {
        let x: [f64; 4] = core::array::from_fn(|i| arcsec_to_rad(self.x_arcsec[i]));
        let (rho, s, lat) = self.angles(t);
        oscillation(&x, rho, s, lat)
    }

    /// The sample at time `t`.
    pub fn sample(&mut self, t: f64) -> Sample {
        let (rho, s, lat) = self.angles(t);
        let osc = self.oscillation(t);
        let n = arcsec_to_rad(self.noise_arcsec);
        let a0 = self.low_frequency_deg * RAD_PER_DEG;
        let roll = self.roll_sway_deg * RAD_PER_DEG * (2.0 * PI * t / 6.0).sin() + osc[1] + a0 + n * self.noise();
        let pitch = self.pitch_sway_deg * RAD_PER_DEG * (2.0 * PI * t / 9.0 + 0.4).sin() + osc[2] - a0 + n * self.noise();
        let heading = 0.5 + osc[0];
        Sample::from_degrees(
            t,
            rho / RAD_PER_DEG,
            s / RAD_PER_DEG,
            lat / RAD_PER_DEG,
            heading / RAD_PER_DEG,
            roll / RAD_PER_DEG,
            pitch / RAD_PER_DEG,
        )
    }
}

/// Rotation schemes of real RINS (the generator of `host-sim` has the same ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// One way at a constant rate, +1 or -1.
    OneWay(f64),
    /// +360 deg in half a period, back in the other half.
    Reciprocating,
    /// Four 90 deg moves of 15 s (cosine profile) one way, dwelling between them.
    FourPosition,
    /// Eight 90 deg moves of 15 s: four forward, four back, dwelling between them.
    EightPosition,
}

impl Scheme {
    /// The rotation angle at `t`, rad (unwrapped, 0 at t = 0).
    pub fn angle_rad(&self, t: f64, period_s: f64) -> f64 {
        let cycles = (t / period_s).floor();
        let tau = t - cycles * period_s;
        let quarter = PI / 2.0;
        // A 90 deg move of 15 s with a cosine velocity profile: fraction done `tau` s into it.
        let moved = |tau: f64| 0.5 * (1.0 - ((tau / 15.0).clamp(0.0, 1.0) * PI).cos());
        match self {
            Scheme::OneWay(dir) => dir * 2.0 * PI * t / period_s,
            Scheme::Reciprocating => {
                let half = period_s / 2.0;
                if tau < half { 2.0 * PI * tau / half } else { 2.0 * PI * (1.0 - (tau - half) / half) }
            }
            Scheme::FourPosition => {
                let seg = period_s / 4.0;
                let q = (tau / seg).floor();
                2.0 * PI * cycles + (q + moved(tau - q * seg)) * quarter
            }
            Scheme::EightPosition => {
                let seg = period_s / 8.0;
                let j = (tau / seg).floor();
                let f = moved(tau - j * seg);
                if j < 4.0 { (j + f) * quarter } else { (8.0 - j - f) * quarter }
            }
        }
    }
}

/// Eq (2) in f64: heading, roll, pitch errors (rad) for errors `x` (rad) at rotation angle `rho`,
/// platform angle `s` and latitude `lat`. The core's tests' truth, independent of the core's f32 rows.
pub fn oscillation(x: &[f64; 4], rho: f64, s: f64, lat: f64) -> [f64; 3] {
    let (sl, cl) = lat.sin_cos();
    let (sr, cr) = rho.sin_cos();
    let (srs, crs) = (rho - s).sin_cos();
    [
        -x[0] * cl * crs - x[1] * cl * srs - x[2] * sl * sr + x[3] * sl * cr,
        -x[0] * sl * crs - x[1] * sl * srs + x[2] * cl * sr - x[3] * cl * cr,
        x[0] * srs - x[1] * crs,
    ]
}
