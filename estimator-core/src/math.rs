//! The step's elementary functions: sine and cosine, square root, rounding, angle wrapping, the
//! larger and smaller of two numbers.
//!
//! # Square root
//! `libm` has no ARM implementation of `sqrtf`: on the Cortex-M4F it runs a software loop of a few
//! hundred instructions, and stable Rust cannot reach the FPU's `vsqrt.f32` on this target (the
//! `sreg` asm operand class needs `vfp2`, which the single-precision M4F does not report). [`sqrt`]
//! is therefore a short Newton iteration in plain IEEE arithmetic, identical on every target.
//!
//! # Sine and cosine
//!
//! The `libm` crate's `sinf`/`cosf` compute in `f64`, which the Cortex-M4F runs in software (what
//! a pair costs against the step's budget: docs/firmware.md, "Measured figures"). The `f32` build
//! therefore uses its own [`sin_cos`]: Cody-Waite reduction by pi/2 with a two-part constant, then the Cephes
//! single-precision minimax polynomials on [-pi/4, pi/4]. It uses only `+`, `-`, `*` and a
//! round-to-nearest, so it gives bit-identical results on the host and on the target. Its error is
//! below 2e-7 for |x| <= 4 pi (tested against `f64` sine and cosine), i.e. below 0.05 arcsec on a
//! unit signal; every angle the core passes it is within 4 pi.

use crate::Real;

/// The larger and the smaller of two numbers by one comparison. On the Cortex-M4F `f32::max` and
/// `f32::min` are calls to `fmaxf` and `fminf` (IEEE 754 maxNum and minNum, whose rule that a NaN
/// operand gives the other costs instructions beyond the compare; docs/firmware.md, "Measured
/// figures", has the count), and the step's bookkeeping of noise, spread and change takes tens of
/// them; these are inline compares. Every value they are
/// given in the step is finite (no NaN reaches the filter), where they give what `max` and `min`
/// give; a NaN `self` would be passed on, not dropped.
pub trait Compare: Sized {
    /// `self` or `other`, whichever is larger (`self` when they are equal).
    fn larger(self, other: Self) -> Self;
    /// `self` or `other`, whichever is smaller (`self` when they are equal).
    fn smaller(self, other: Self) -> Self;
}

impl Compare for Real {
    #[inline(always)]
    fn larger(self, other: Real) -> Real {
        if self < other {
            other
        } else {
            self
        }
    }

    #[inline(always)]
    fn smaller(self, other: Real) -> Real {
        if other < self {
            other
        } else {
            self
        }
    }
}

/// Wraps an angle to [-pi, pi] in constant time (any finite input; exact for |x| < a few turns).
pub fn wrap_pi(angle_rad: Real) -> Real {
    let two_pi = 2.0 * core::f64::consts::PI as Real;
    angle_rad - two_pi * round(angle_rad / two_pi)
}

/// To the nearest integer, halves away from zero, saturating (NaN gives 0): an add and the FPU's
/// truncating conversion, a few instructions (against a library call for `round`). Within one
/// unit of the exact rounding (`0.49999997 + 0.5` rounds up in f32); IEEE operations only, so every
/// target gives the same integer.
pub fn round_to_i32(x: Real) -> i32 {
    (if x >= 0.0 { x + 0.5 } else { x - 0.5 }) as i32
}

/// Round to nearest, ties to even: `libm::rintf`, bit for bit, in a few FPU instructions and no
/// library code. For |x| < 2^23, adding 2^23 to |x| leaves no bits below the units, so the FPU's
/// addition rounds |x| to an integer (ties to even, which is symmetric: rounding |x| and giving
/// it x's sign is rounding x), and subtracting 2^23 again is exact; the sign is put back, as
/// `rintf` gives -0 for -0.3. From 2^23 on every float is an integer (or infinite, or NaN) and is
/// its own rounding.
#[cfg(not(feature = "f64"))]
pub fn round(x: f32) -> f32 {
    const TWO_23: f32 = 8_388_608.0;
    let magnitude = x.abs();
    if magnitude < TWO_23 {
        ((magnitude + TWO_23) - TWO_23).copysign(x)
    } else {
        x
    }
}
/// Round to nearest, ties to even.
#[cfg(feature = "f64")]
pub fn round(x: f64) -> f64 {
    libm::rint(x)
}

/// Square root (NaN for negative input), within 1 ulp: an exponent-halving seed (relative error
/// below 4 %) and three Newton steps `y = (y + x/y) / 2` (error 4e-2 -> 8e-4 -> 3e-7 -> rounding).
/// About 15 instructions on the M4F, against several hundred for `libm::sqrtf`, which has no ARM
/// implementation and runs a bit-by-bit loop. Only IEEE operations: the same bits on every target.
#[cfg(not(feature = "f64"))]
// On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
#[inline]
pub fn sqrt(x: f32) -> f32 {
    if !(x > 0.0) || x == f32::INFINITY {
        // 0 -> 0, +inf -> +inf, negative or NaN -> NaN.
        return if x == 0.0 || x == f32::INFINITY {
            x
        } else {
            f32::NAN
        };
    }
    // Scale subnormals into the normal range first (sqrt(x) = sqrt(x 2^24) / 2^12).
    let (x, scale) = if x < f32::MIN_POSITIVE {
        (x * 16_777_216.0, 1.0 / 4096.0)
    } else {
        (x, 1.0)
    };
    let mut y = f32::from_bits((x.to_bits() >> 1) + 0x1FBD_1DF5);
    y = 0.5 * (y + x / y);
    y = 0.5 * (y + x / y);
    y = 0.5 * (y + x / y);
    y * scale
}
/// Square root (NaN for negative input).
#[cfg(feature = "f64")]
pub fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}

/// `(sin x, cos x)`.
#[cfg(not(feature = "f64"))]
// On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
    // pi/2 split so that k * PIO2_HI is exact for |k| < 2^8.
    const PIO2_HI: f32 = 1.570_312_5;
    const PIO2_MID: f32 = 4.837_513e-4;
    const PIO2_LO: f32 = 7.549_79e-8;
    let k = round(x * FRAC_2_PI);
    let r = ((x - k * PIO2_HI) - k * PIO2_MID) - k * PIO2_LO;
    let z = r * r;
    let s = r + r * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * -1.951_529_6e-4));
    let c = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
    // k mod 4 selects the quadrant; `as i32` saturates and |k| is small for every caller.
    match (k as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `(sin x, cos x)`.
#[cfg(feature = "f64")]
pub fn sin_cos(x: f64) -> (f64, f64) {
    (libm::sin(x), libm::cos(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_matches_f64_within_2e7_over_four_turns() {
        let mut worst: f64 = 0.0;
        let n = 200_000;
        for i in 0..=n {
            let x =
                -4.0 * core::f64::consts::PI + 8.0 * core::f64::consts::PI * (i as f64) / n as f64;
            let xr = x as Real;
            let (s, c) = sin_cos(xr);
            let xe = xr as f64;
            worst = worst
                .max((s as f64 - libm::sin(xe)).abs())
                .max((c as f64 - libm::cos(xe)).abs());
        }
        assert!(worst < 2e-7, "worst error {worst}");
    }

    #[test]
    fn sqrt_is_within_one_ulp_and_handles_edge_cases() {
        // Every 997th float from the smallest subnormal to the largest finite value.
        let mut bits: u32 = 1;
        while bits < f32::MAX.to_bits() {
            let x = f32::from_bits(bits) as Real;
            let exact = libm::sqrt(x as f64);
            let got = sqrt(x) as f64;
            let ulp = (exact as f32).to_bits().abs_diff((got as f32).to_bits());
            assert!(ulp <= 1, "sqrt({x:e}) = {got:e}, exact {exact:e}");
            bits += 997;
        }
        assert_eq!(sqrt(0.0), 0.0);
        assert!(sqrt(-1.0).is_nan() && sqrt(Real::NAN).is_nan());
        assert_eq!(sqrt(Real::INFINITY), Real::INFINITY);
    }

    #[test]
    #[cfg(not(feature = "f64"))]
    fn round_is_rintf_bit_for_bit() {
        let mut bits: u32 = 0;
        loop {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                assert_eq!(round(x).to_bits(), libm::rintf(x).to_bits(), "{x:e}");
            }
            // Every 331st float of either sign from 0 to infinity (below: every half-integer
            // near 0).
            if bits >= 0x7F80_0000 {
                break;
            }
            bits = (bits + 331).min(0x7F80_0000);
        }
        // Every half-integer near 0, and ties where a float has one bit below the units
        // (2^22 to 2^23) and where it has none (2^23 on).
        for k in -4000..4000 {
            for x in [
                k as f32 * 0.5,
                4_194_304.0 + k as f32 * 0.5,
                -4_194_304.0 + k as f32 * 0.5,
                8_388_608.0 + k as f32,
            ] {
                assert_eq!(round(x).to_bits(), libm::rintf(x).to_bits(), "{x}");
            }
        }
        assert!(round(f32::NAN).is_nan());
    }

    #[test]
    fn wrap_pi_brings_angles_into_range() {
        assert!(wrap_pi(1e30).is_finite());
        for &a in &[-12.0 as Real, -3.5, 0.0, 3.5, 12.0] {
            let w = wrap_pi(a);
            assert!(w.abs() <= core::f64::consts::PI as Real + 1e-6);
            let (s1, c1) = sin_cos(a);
            let (s2, c2) = sin_cos(w);
            assert!((s1 - s2).abs() < 1e-5 && (c1 - c2).abs() < 1e-5);
        }
    }
}
