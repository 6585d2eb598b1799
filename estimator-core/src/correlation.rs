//! Eq (8): correlating roll and pitch with the rotation angle.
//!
//! # Derivation of the four channels from eq (2)
//!
//! Multiply the roll error of eq (2) by `sin rho` and expand the products with the product-to-sum
//! identities (`cos(rho-s) sin rho = [sin(2rho-s) + sin s]/2`, `sin(rho-s) sin rho = [cos s - cos(2rho-s)]/2`,
//! `sin^2 rho = [1 - cos 2rho]/2`, `cos rho sin rho = sin(2rho)/2`):
//!
//! ```text
//! d_roll sin rho  = x3 cosL/2 - x1 sinL sin(s)/2 - x2 sinL cos(s)/2            (slow part)
//!                 + harmonics at 2 rho and 2 rho - s                             (blocked by eq 11)
//! d_roll cos rho  = -x4 cosL/2 - x1 sinL cos(s)/2 + x2 sinL sin(s)/2 + harmonics
//! d_pitch sin(rho-s) = x1/2 + harmonic at 2(rho-s)
//! d_pitch cos(rho-s) = -x2/2 + harmonic at 2(rho-s)
//! ```
//!
//! So roll with `sin rho` isolates x3 (the paper's channel), roll with `cos rho` isolates x4 (sign
//! negative), pitch with `sin(rho-s)` isolates x1 and pitch with `cos(rho-s)` isolates x2 (sign
//! negative). The two roll channels also carry x1 and x2 through `sinL sin s` and `sinL cos s`: the
//! leakage of eq (12). It is not small (x1 sinL/2 is ~100 arcsec at 40 deg) and it is not a 1/t
//! transient when the product is averaged over a moving window instead of from t = 0: it is a slow
//! term with *known* coefficients (s and L are inputs), which the default filter models exactly.
//!
//! **Check of eq (12).** Integrating the slow part from 0 to t with s = w_e t and dividing by t (eq 8)
//! gives `x3 cosL/2 - x1 sinL (1 - cos w_e t)/(2 w_e t) - x2 sinL sin(w_e t)/(2 w_e t)`. The paper's
//! eq (12) has `-x1 sinL sin(w_e t) + x2 sinL (cos w_e t - 1)` in the numerator instead: x1 and x2
//! exchanged (and a sign on x2), which corresponds to its eq (10), last line. The simulation in
//! `tests/` sides with the derivation above (`roll_sin_channel_leakage_follows_derivation`).
//! Either way the leakage keeps its 1/t factor, which the constant b1, b2 of eq (13) cannot represent
//! (see [`crate::methods::paper`]).
//!
//! The ship's sway (eq 4) multiplies `sin rho` into components at the sway frequency +- 1/480 Hz;
//! the low-frequency errors of eq (5) multiply it into components at (multiples of) 1/480 Hz +- the
//! Earth rate. Both are removed by the averaging of [`crate::moving_average`].

use crate::installation::Angles;
use crate::sample::Attitude;
use crate::Real;

/// Index of the channel that isolates x1: pitch * sin(rho - s).
pub const PITCH_SIN: usize = 0;
/// Index of the channel that isolates x2: pitch * cos(rho - s).
pub const PITCH_COS: usize = 1;
/// Index of the channel that isolates x3: roll * sin(rho).
pub const ROLL_SIN: usize = 2;
/// Index of the channel that isolates x4: roll * cos(rho).
pub const ROLL_COS: usize = 3;

/// The four correlation products of one sample, in channel order.
pub fn products(attitude: &Attitude, angles: &Angles) -> [Real; 4] {
    [
        attitude.pitch_rad * angles.sin_rho_s,
        attitude.pitch_rad * angles.cos_rho_s,
        attitude.roll_rad * angles.sin_rho,
        attitude.roll_rad * angles.cos_rho,
    ]
}

/// The coefficients of the leakage of x1, x2 into the roll channels for one sample:
/// `(sinL sin s, sinL cos s, cosL)`. Their means over the same window as the products give the
/// exact slow-part measurement rows (see [`measurement_rows`]).
pub fn leakage_coefficients(angles: &Angles) -> [Real; 3] {
    let (sin_s, cos_s) = angles.sin_cos_platform();
    [angles.sin_lat * sin_s, angles.sin_lat * cos_s, angles.cos_lat]
}

/// Rows `h` with `mean(channel) = h . x` for the slow parts derived above, given the window means of
/// [`leakage_coefficients`] `(m_ss, m_sc, m_c) = mean(sinL sin s), mean(sinL cos s), mean(cosL)`.
pub fn measurement_rows(leakage_means: &[Real; 3]) -> [[Real; 4]; 4] {
    let [m_ss, m_sc, m_c] = *leakage_means;
    let mut rows = [[0.0; 4]; 4];
    rows[PITCH_SIN] = [0.5, 0.0, 0.0, 0.0];
    rows[PITCH_COS] = [0.0, -0.5, 0.0, 0.0];
    rows[ROLL_SIN] = [-0.5 * m_ss, -0.5 * m_sc, 0.5 * m_c, 0.0];
    rows[ROLL_COS] = [-0.5 * m_sc, 0.5 * m_ss, 0.0, -0.5 * m_c];
    rows
}
