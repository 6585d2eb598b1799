//! Eq (2): the oscillating attitude errors that the installation errors cause.
//!
//! With rho the rotation angle, s the platform angle and L the latitude (eq 2):
//!
//! ```text
//! d_heading = -x1 cosL cos(rho-s) - x2 cosL sin(rho-s) - x3 sinL sin rho + x4 sinL cos rho
//! d_roll    = -x1 sinL cos(rho-s) - x2 sinL sin(rho-s) + x3 cosL sin rho - x4 cosL cos rho
//! d_pitch   =  x1 sin(rho-s)      - x2 cos(rho-s)
//! ```
//!
//! Each is linear in `x = (x1, x2, x3, x4)`: `d = row . x`. The rows are used three ways: to correct
//! the attitude output, as the measurement rows of the traditional baseline (Fig. 2), and (through
//! [`crate::correlation`]) to derive the correlation channels.

use crate::sample::Attitude;
use crate::math::sin_cos;
use crate::Real;

/// Sines and cosines of one sample's angles, computed once per step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angles {
    pub sin_rho: Real,
    pub cos_rho: Real,
    /// sin(rho - s), cos(rho - s).
    pub sin_rho_s: Real,
    pub cos_rho_s: Real,
    pub sin_lat: Real,
    pub cos_lat: Real,
}

impl Angles {
    /// Computes the trigonometry of rho, rho - s and L. `lat_sin_cos` is `(sin L, cos L)`, which the
    /// caller caches because latitude changes slowly.
    pub fn new(rotation_rad: Real, platform_rad: Real, lat_sin_cos: (Real, Real)) -> Angles {
        Angles::from_rotation(rotation_rad, rotation_rad - platform_rad, lat_sin_cos)
    }

    /// The same from rho and rho - s.
    pub fn from_rotation(rotation_rad: Real, rotation_minus_platform_rad: Real, lat_sin_cos: (Real, Real)) -> Angles {
        let (sin_rho, cos_rho) = sin_cos(rotation_rad);
        let (sin_rho_s, cos_rho_s) = sin_cos(rotation_minus_platform_rad);
        Angles { sin_rho, cos_rho, sin_rho_s, cos_rho_s, sin_lat: lat_sin_cos.0, cos_lat: lat_sin_cos.1 }
    }

    /// sin s and cos s, from rho and rho - s by the angle-difference identities
    /// (s = rho - (rho - s)); no further trigonometry needed.
    pub fn sin_cos_platform(&self) -> (Real, Real) {
        (
            self.sin_rho * self.cos_rho_s - self.cos_rho * self.sin_rho_s,
            self.cos_rho * self.cos_rho_s + self.sin_rho * self.sin_rho_s,
        )
    }

    /// Coefficients of x1..x4 in the heading error of eq (2).
    pub fn heading_row(&self) -> [Real; 4] {
        [
            -self.cos_lat * self.cos_rho_s,
            -self.cos_lat * self.sin_rho_s,
            -self.sin_lat * self.sin_rho,
            self.sin_lat * self.cos_rho,
        ]
    }

    /// Coefficients of x1..x4 in the roll error of eq (2).
    pub fn roll_row(&self) -> [Real; 4] {
        [
            -self.sin_lat * self.cos_rho_s,
            -self.sin_lat * self.sin_rho_s,
            self.cos_lat * self.sin_rho,
            -self.cos_lat * self.cos_rho,
        ]
    }

    /// Coefficients of x1..x4 in the pitch error of eq (2).
    pub fn pitch_row(&self) -> [Real; 4] {
        [self.sin_rho_s, -self.cos_rho_s, 0.0, 0.0]
    }

    /// The oscillating attitude error of eq (2) for installation errors `x_rad`.
    pub fn oscillation(&self, x_rad: &[Real; 4]) -> Attitude {
        let dot = |row: [Real; 4]| row.iter().zip(x_rad).map(|(a, b)| a * b).sum::<Real>();
        Attitude {
            heading_rad: dot(self.heading_row()),
            roll_rad: dot(self.roll_row()),
            pitch_rad: dot(self.pitch_row()),
        }
    }
}
