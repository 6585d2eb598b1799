//! Synthetic RINS output with known installation errors, for tests and tools: the truth the core's
//! estimates are checked against.
//!
//! The roll of a RINS is eq (3): `phi = phi_p + d_phi_m + d_phi_g + d_phi_n`, the true roll (ship
//! sway), the oscillation caused by the installation errors, a low-frequency error and noise; pitch
//! likewise, and heading carries the oscillation too. [`Signal`] builds each term:
//! - sway, eq (4): `phi_p = A sin(w_y t)`, here with a phase (`roll_sway_*`, `pitch_sway_*`);
//! - the oscillation, eq (2), for the errors `x1..x4` ([`oscillation`]);
//! - the low-frequency error, eq (5), kept to its constant `a0` (`low_frequency_deg`: `+a0` on
//!   roll, `-a0` on pitch);
//! - white noise from a seeded 64-bit LCG, so every run draws the same numbers.
//!
//! Everything is `f64` with `libm`'s trigonometry, and eq (2) is written here again from the paper
//! rather than taken from [`crate::installation`]: the tests compare the core's estimates with a
//! truth computed independently of the core's own (f32) rows.
//!
//! Compiled only for the crate's own tests and with the `synthetic` feature (the integration tests
//! enable it); the firmware never has it.

use crate::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
use crate::Sample;
use core::f64::consts::PI;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The noise generator's state when a [`Signal`] is made (see [`Signal::with_seed`]).
pub const DEFAULT_SEED: u64 = 0x1234_5678;

/// A RINS's attitude output for known installation errors, sample by sample.
///
/// Fields are public: make one with [`Signal::new`] and change what the test needs.
#[derive(Clone, Debug)]
pub struct Signal {
    /// The installation errors `x1..x4` of eq (1)-(2), arcsec.
    pub x_arcsec: [f64; 4],
    /// Latitude `L`, deg.
    pub latitude_deg: f64,
    /// The true heading, constant, rad.
    pub heading_rad: f64,
    /// Amplitude `A` of the roll sway (eq 4), deg.
    pub roll_sway_deg: f64,
    /// Period `2 pi / w_y` of the roll sway, s.
    pub roll_sway_period_s: f64,
    /// Phase of the roll sway at `t = 0`, rad.
    pub roll_sway_phase_rad: f64,
    /// Amplitude of the pitch sway (eq 4 for pitch), deg.
    pub pitch_sway_deg: f64,
    /// Period of the pitch sway, s.
    pub pitch_sway_period_s: f64,
    /// Phase of the pitch sway at `t = 0`, rad.
    pub pitch_sway_phase_rad: f64,
    /// The constant `a0` of the low-frequency error (eq 5), deg: added to roll, taken from pitch.
    pub low_frequency_deg: f64,
    /// 1-sigma of the white noise on roll and on pitch, arcsec.
    pub noise_arcsec: f64,
    /// 1-sigma of the white noise on heading, arcsec.
    pub heading_noise_arcsec: f64,
    /// 1-sigma of the white jitter of the reported rotation angle (the encoder's), rad. Eq (2)
    /// sees the true angle.
    pub rotation_jitter_rad: f64,
    /// The rotation's period, s (used by [`Signal::sample`]).
    pub rotation_period_s: f64,
    /// How the rotation turns (used by [`Signal::sample`]).
    pub scheme: Scheme,
    /// Rotation angle `rho` at `t = 0`, rad (used by [`Signal::sample`]).
    pub rotation_phase_rad: f64,
    /// Platform angle `s` at `t = 0`, rad; it turns at the Earth rate.
    pub platform_phase_rad: f64,
    /// The noise generator (ChaCha8, seeded from [`DEFAULT_SEED`] or [`Signal::with_seed`]).
    rng: ChaCha8Rng,
}

impl Signal {
    /// Errors `x_arcsec` at `latitude_deg`, and the defaults: the paper's simulation (3 deg roll
    /// sway of 6 s, 0.05 deg low-frequency error, here constant, 480 s one-way rotation) with a
    /// 1 deg, 9 s pitch sway, heading 0.5 rad, rotation phase 0.7 rad, platform phase 1.9 rad, no noise, no jitter,
    /// noise seed [`DEFAULT_SEED`].
    pub fn new(x_arcsec: [f64; 4], latitude_deg: f64) -> Signal {
        Signal {
            x_arcsec,
            latitude_deg,
            heading_rad: 0.5,
            roll_sway_deg: 3.0,
            roll_sway_period_s: 6.0,
            roll_sway_phase_rad: 0.0,
            pitch_sway_deg: 1.0,
            pitch_sway_period_s: 9.0,
            pitch_sway_phase_rad: 0.4,
            low_frequency_deg: 0.05,
            noise_arcsec: 0.0,
            heading_noise_arcsec: 0.0,
            rotation_jitter_rad: 0.0,
            rotation_period_s: 480.0,
            scheme: Scheme::OneWay(1.0),
            rotation_phase_rad: 0.7,
            platform_phase_rad: 1.9,
            rng: ChaCha8Rng::seed_from_u64(DEFAULT_SEED),
        }
    }

    /// The same signal with the noise generator started from `seed`.
    pub fn with_seed(mut self, seed: u64) -> Signal {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
        self
    }

    /// White noise of unit variance: the sum of four uniforms of the ChaCha8 stream, scaled by
    /// sqrt(3).
    fn unit_noise(&mut self) -> f64 {
        let mut acc = 0.0;
        for _ in 0..4 {
            acc += (self.rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        }
        acc * libm::sqrt(3.0)
    }

    /// White noise of 1-sigma `sigma_arcsec`, rad. A zero 1-sigma draws nothing.
    fn noise_rad(&mut self, sigma_arcsec: f64) -> f64 {
        if sigma_arcsec == 0.0 {
            return 0.0;
        }
        arcsec_to_rad(sigma_arcsec) * self.unit_noise()
    }

    /// The rotation angle `rho` of [`Signal::sample`] at `t_s`: the phase plus the scheme's angle,
    /// unwrapped, rad.
    pub fn rotation_rad(&self, t_s: f64) -> f64 {
        self.rotation_phase_rad + self.scheme.angle_rad(t_s, self.rotation_period_s)
    }

    /// The platform angle `s` at `t_s`: the phase plus the Earth's turn, unwrapped, rad.
    pub fn platform_rad(&self, t_s: f64) -> f64 {
        self.platform_phase_rad + EARTH_RATE_RAD_PER_S * t_s
    }

    /// Eq (2) at `t_s` with the scheme's rotation angle: heading, roll, pitch errors, rad.
    pub fn oscillation_rad(&self, t_s: f64) -> [f64; 3] {
        self.oscillation_at(t_s, self.rotation_rad(t_s))
    }

    /// Eq (2) at `t_s` and rotation angle `rotation_rad`: heading, roll, pitch errors, rad.
    pub fn oscillation_at(&self, t_s: f64, rotation_rad: f64) -> [f64; 3] {
        let x = self.x_arcsec.map(arcsec_to_rad);
        oscillation(
            &x,
            rotation_rad,
            self.platform_rad(t_s),
            self.latitude_deg * RAD_PER_DEG,
        )
    }

    /// The sample at `t_s`, the rotation turning by [`Signal::scheme`].
    pub fn sample(&mut self, t_s: f64) -> Sample {
        self.sample_at(t_s, self.rotation_rad(t_s))
    }

    /// The sample at `t_s` with the true rotation angle `rotation_rad` (any number of turns), for
    /// rotations a test drives itself. Noise is drawn in this order: roll, pitch, heading, rotation
    /// jitter.
    ///
    /// The sample is what a log in degrees would give: each angle in rad divided by
    /// [`RAD_PER_DEG`] and read by [`Sample::from_degrees`] (which wraps rotation, platform and
    /// heading in f64).
    pub fn sample_at(&mut self, t_s: f64, rotation_rad: f64) -> Sample {
        let s = self.platform_rad(t_s);
        let lat = self.latitude_deg * RAD_PER_DEG;
        let osc = self.oscillation_at(t_s, rotation_rad);
        let a0 = self.low_frequency_deg * RAD_PER_DEG;
        let roll_sway = self.roll_sway_deg
            * RAD_PER_DEG
            * libm::sin(2.0 * PI * t_s / self.roll_sway_period_s + self.roll_sway_phase_rad);
        let pitch_sway = self.pitch_sway_deg
            * RAD_PER_DEG
            * libm::sin(2.0 * PI * t_s / self.pitch_sway_period_s + self.pitch_sway_phase_rad);
        let roll = roll_sway + osc[1] + a0 + self.noise_rad(self.noise_arcsec);
        let pitch = pitch_sway + osc[2] - a0 + self.noise_rad(self.noise_arcsec);
        let heading = self.heading_rad + osc[0] + self.noise_rad(self.heading_noise_arcsec);
        let rotation_read = if self.rotation_jitter_rad == 0.0 {
            rotation_rad
        } else {
            rotation_rad + self.rotation_jitter_rad * self.unit_noise()
        };
        Sample::from_degrees(
            t_s,
            rotation_read / RAD_PER_DEG,
            s / RAD_PER_DEG,
            lat / RAD_PER_DEG,
            heading / RAD_PER_DEG,
            roll / RAD_PER_DEG,
            pitch / RAD_PER_DEG,
        )
    }
}

/// Rotation schemes of real RINS (the scenario generator of `host-sim` has the same ones).
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
    /// The rotation angle at `t_s` for a period of `period_s`, rad (unwrapped, 0 at t = 0).
    pub fn angle_rad(&self, t_s: f64, period_s: f64) -> f64 {
        let cycles = libm::floor(t_s / period_s);
        let tau = t_s - cycles * period_s;
        let quarter = PI / 2.0;
        // A 90 deg move of 15 s with a cosine velocity profile: fraction done `tau` s into it.
        let moved = |tau: f64| 0.5 * (1.0 - libm::cos((tau / 15.0).clamp(0.0, 1.0) * PI));
        match self {
            Scheme::OneWay(dir) => dir * 2.0 * PI * t_s / period_s,
            Scheme::Reciprocating => {
                let half = period_s / 2.0;
                if tau < half {
                    2.0 * PI * tau / half
                } else {
                    2.0 * PI * (1.0 - (tau - half) / half)
                }
            }
            Scheme::FourPosition => {
                let seg = period_s / 4.0;
                let q = libm::floor(tau / seg);
                2.0 * PI * cycles + (q + moved(tau - q * seg)) * quarter
            }
            Scheme::EightPosition => {
                let seg = period_s / 8.0;
                let j = libm::floor(tau / seg);
                let f = moved(tau - j * seg);
                if j < 4.0 {
                    (j + f) * quarter
                } else {
                    (8.0 - j - f) * quarter
                }
            }
        }
    }
}

/// Eq (2), the oscillation the installation errors cause, in f64: heading, roll and pitch errors
/// (rad) for errors `x_rad` at rotation angle `rotation_rad` (`rho`), platform angle
/// `platform_rad` (`s`) and latitude `latitude_rad` (`L`):
///
/// ```text
/// d_psi   = -x1 cosL cos(rho - s) - x2 cosL sin(rho - s) - x3 sinL sin(rho) + x4 sinL cos(rho)
/// d_phi   = -x1 sinL cos(rho - s) - x2 sinL sin(rho - s) + x3 cosL sin(rho) - x4 cosL cos(rho)
/// d_theta =  x1 sin(rho - s) - x2 cos(rho - s)
/// ```
pub fn oscillation(
    x_rad: &[f64; 4],
    rotation_rad: f64,
    platform_rad: f64,
    latitude_rad: f64,
) -> [f64; 3] {
    let x = x_rad;
    let (sl, cl) = (libm::sin(latitude_rad), libm::cos(latitude_rad));
    let (sr, cr) = (libm::sin(rotation_rad), libm::cos(rotation_rad));
    let d = rotation_rad - platform_rad;
    let (srs, crs) = (libm::sin(d), libm::cos(d));
    [
        -x[0] * cl * crs - x[1] * cl * srs - x[2] * sl * sr + x[3] * sl * cr,
        -x[0] * sl * crs - x[1] * sl * srs + x[2] * cl * sr - x[3] * cl * cr,
        x[0] * srs - x[1] * crs,
    ]
}
