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

use crate::math::sin_cos;
use crate::sample::Attitude;
use crate::Real;

/// Sines and cosines of one sample's angles, computed once per step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angles {
    /// sin rho, of the rotation angle rho.
    pub sin_rho: Real,
    /// cos rho.
    pub cos_rho: Real,
    /// sin(rho - s), with s the platform angle.
    pub sin_rho_s: Real,
    /// cos(rho - s).
    pub cos_rho_s: Real,
    /// sin L, of the latitude L.
    pub sin_lat: Real,
    /// cos L.
    pub cos_lat: Real,
}

impl Angles {
    /// Computes the trigonometry of rho, rho - s and L. `lat_sin_cos` is `(sin L, cos L)`, which the
    /// caller caches because latitude changes slowly.
    pub fn new(rotation_rad: Real, platform_rad: Real, lat_sin_cos: (Real, Real)) -> Angles {
        Angles::from_rotation(rotation_rad, rotation_rad - platform_rad, lat_sin_cos)
    }

    /// The same from rho and rho - s.
    pub fn from_rotation(
        rotation_rad: Real,
        rotation_minus_platform_rad: Real,
        lat_sin_cos: (Real, Real),
    ) -> Angles {
        let (sin_rho, cos_rho) = sin_cos(rotation_rad);
        let (sin_rho_s, cos_rho_s) = sin_cos(rotation_minus_platform_rad);
        Angles {
            sin_rho,
            cos_rho,
            sin_rho_s,
            cos_rho_s,
            sin_lat: lat_sin_cos.0,
            cos_lat: lat_sin_cos.1,
        }
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

#[cfg(test)]
mod tests {
    use super::Angles;
    use crate::math::sin_cos;
    use crate::synthetic::oscillation;
    use crate::Real;

    /// The core's rows of eq (2) and the test signal's eq (2), written separately, agree to f32
    /// precision over the whole range of the angles: the truth the tests judge against and the
    /// model the filter uses are the same equation.
    #[test]
    fn rows_agree_with_the_independent_eq_2_of_the_test_signal() {
        let x_rad = [9.7e-4, -7.3e-4, 1.45e-3, -1.2e-3];
        for k in 0..2000 {
            let rotation_rad = -3.1 + 6.2 * (k as f64 * 0.618_034).fract();
            let platform_rad = -3.1 + 6.2 * (k as f64 * 0.414_214).fract();
            let latitude_rad = -1.5 + 3.0 * (k as f64 * 0.732_051).fract();
            let want = oscillation(&x_rad, rotation_rad, platform_rad, latitude_rad);
            let rows = Angles::new(
                rotation_rad as Real,
                platform_rad as Real,
                sin_cos(latitude_rad as Real),
            );
            let got = rows.oscillation(&x_rad.map(|x| x as Real));
            let got = [got.heading_rad, got.roll_rad, got.pitch_rad];
            for i in 0..3 {
                let diff = (f64::from(got[i]) - want[i]).abs();
                assert!(
                    diff < 1e-8,
                    "k {k} axis {i}: {} vs {} (diff {diff:e} rad)",
                    got[i],
                    want[i]
                );
            }
        }
    }
}
