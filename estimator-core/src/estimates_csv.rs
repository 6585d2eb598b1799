//! One row of the estimates CSV (the format is in `docs/log-format.md`), written into any
//! [`core::fmt::Write`] without allocation. The host tool's estimates writer and the C library's
//! `rins_format_row` both write their rows with this code, so a C program's file and
//! `host-sim estimate`'s are the same byte for byte.
//!
//! Fixed, deterministic formatting:
//! - `time_s`: 6 decimals;
//! - `x*_arcsec`, `sigma*_arcsec`: 4 decimals, empty while there is no estimate;
//! - `status`: [`crate::Status::name`], or `rejected_<reason>` with [`RejectReason::name`] for an input
//!   row the core rejected;
//! - `*_corrected_deg`: 9 decimals (heading in [-180, 180]); empty on a rejected row;
//! - the latched alarms and the residuals' level ([`crate::Health`]), empty on a rejected row:
//!   `changes`, `window_restarts`, `rejected` as integers, `last_change_s` with 6 decimals (empty
//!   before the first change), `mismatch_s` with 3, `residual_pitch_arcsec`,
//!   `residual_roll_arcsec`, `noise_scale_pitch`, `noise_scale_roll` with 4 (empty until the
//!   windowed method's first measurement, and for the other methods).
//!
//! A rejected row carries the estimate held on board at that moment: a rejected sample leaves
//! the estimator untouched, so that is [`crate::Estimator::estimate`] (the estimate of the last
//! [`Output`]).
//!
//! The numbers are exactly `format!("{value:.N}")` (pinned by the tests against the standard
//! formatter), without the standard formatter's big-number arithmetic for the values this file
//! holds.
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use crate::output::{Estimate, Health, Output};
use crate::sample::RejectReason;
use crate::units::{rad_to_arcsec, RAD_PER_DEG};
use core::fmt::{self, Write};

/// The estimates CSV header (no line end).
pub const HEADER: &str = "time_s,x1_arcsec,x2_arcsec,x3_arcsec,x4_arcsec,sigma1_arcsec,sigma2_arcsec,sigma3_arcsec,sigma4_arcsec,status,heading_corrected_deg,roll_corrected_deg,pitch_corrected_deg,changes,last_change_s,window_restarts,rejected,mismatch_s,residual_pitch_arcsec,residual_roll_arcsec,noise_scale_pitch,noise_scale_roll";
/// Prefix of the status of a rejected row.
pub const REJECTED_PREFIX: &str = "rejected_";

/// Bytes one row can take at most, its line end included: a buffer this long never truncates a
/// row. The widest row: a time of `-f64::MAX` (309 digits, 6 decimals, a sign: 317 bytes), eight
/// estimates of `-f32::MAX` rad in arcsec (44 digits, 4 decimals, a sign: 50 bytes each), the
/// longest status name (22 bytes), three corrected angles of `-f32::MAX` rad in degrees (41
/// digits, 9 decimals, a sign: 52 bytes each), three counts of `u32::MAX` (10 bytes each), a last
/// change at `-f64::MAX` (317 bytes), `mismatch_s` of `u32::MAX` samples of 10 s (15 bytes), two
/// residual levels of `-f32::MAX` rad in arcsec and two noise scales of `f32::MAX` (50 and 44
/// bytes each), 21 commas and the line end: 1,467 bytes (checked by `the_widest_row_fits`). A
/// typical row takes about 190.
pub const MAX_ROW_LEN: usize = 2048;

/// Writes the row of a step's output (no line end).
pub fn write_output<W: Write>(w: &mut W, out: &Output) -> fmt::Result {
    write_time(w, out.time_s)?;
    write_estimate(w, out.estimate.as_ref())?;
    w.write_char(',')?;
    w.write_str(out.status.name())?;
    let c = &out.corrected;
    for v in [c.heading_rad, c.roll_rad, c.pitch_rad] {
        w.write_char(',')?;
        write_fixed(w, f64::from(v) / RAD_PER_DEG, 9)?;
    }
    write_health(w, &out.health)
}

/// The latched alarms and the residuals' level: nine cells, each after its comma.
fn write_health<W: Write>(w: &mut W, h: &Health) -> fmt::Result {
    w.write_char(',')?;
    write_digits(w, u64::from(h.changes_detected), 1)?;
    w.write_char(',')?;
    if let Some(t) = h.last_change_s {
        write_time(w, t)?;
    }
    for n in [h.window_restarts, h.rejected] {
        w.write_char(',')?;
        write_digits(w, u64::from(n), 1)?;
    }
    w.write_char(',')?;
    write_fixed(w, h.mismatch_s, 3)?;
    match h.residual_rad {
        Some(r) => {
            for v in r {
                w.write_char(',')?;
                write_fixed(w, rad_to_arcsec(f64::from(v)), 4)?;
            }
        }
        None => w.write_str(",,")?,
    }
    match h.noise_scale {
        Some(s) => {
            for v in s {
                w.write_char(',')?;
                write_fixed(w, f64::from(v), 4)?;
            }
        }
        None => w.write_str(",,")?,
    }
    Ok(())
}

/// Writes the row of a rejected input row (no line end): its time, the estimate `held` on board,
/// the reason, and empty corrected angles.
pub fn write_rejected<W: Write>(
    w: &mut W,
    time_s: f64,
    reason: RejectReason,
    held: Option<&Estimate>,
) -> fmt::Result {
    write_time(w, time_s)?;
    write_estimate(w, held)?;
    w.write_char(',')?;
    w.write_str(REJECTED_PREFIX)?;
    w.write_str(reason.name())?;
    w.write_str(",,,,,,,,,,,,")
}

fn write_estimate<W: Write>(w: &mut W, estimate: Option<&Estimate>) -> fmt::Result {
    match estimate {
        Some(e) => {
            for v in e.x_rad.iter().chain(e.sigma_rad.iter()) {
                w.write_char(',')?;
                write_fixed(w, rad_to_arcsec(f64::from(*v)), 4)?;
            }
            Ok(())
        }
        None => w.write_str(",,,,,,,,"),
    }
}

/// `{:.6}` of a time, byte for byte. Whole seconds (nearly every log row) are written as an
/// integer and `.000000`.
fn write_time<W: Write>(w: &mut W, time_s: f64) -> fmt::Result {
    if libm::trunc(time_s) == time_s
        && time_s.abs() < 9.0e15
        && !(time_s == 0.0 && time_s.is_sign_negative())
    {
        if time_s < 0.0 {
            w.write_char('-')?;
        }
        write_digits(w, time_s.abs() as u64, 1)?;
        w.write_str(".000000")
    } else {
        write_fixed(w, time_s, 6)
    }
}

/// Powers of ten up to 10^9, the most decimals [`write_fixed`] computes itself.
const POW10: [u128; 10] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
    1_000_000_000,
];

/// Writes `format!("{value:.decimals}")`, byte for byte.
///
/// The standard formatter's exact mode falls back to big-number arithmetic for most of the values
/// this file holds, which made formatting most of a replay's time. Here: a finite `f64` is
/// exactly `m * 2^e`; for `e < 0` the scaled value `m * 10^decimals / 2^-e` is computed exactly in
/// `u128` (`m < 2^53`, `10^9 < 2^30`) and rounded half to even on the exact remainder, which is
/// what the standard formatter does (pinned by `fixed_formatting_equals_the_standard_formatter`).
/// Anything else (more than 9 decimals, integers beyond 2^53, tiny or non-finite values) goes to
/// the standard formatter.
fn write_fixed<W: Write>(w: &mut W, value: f64, decimals: usize) -> fmt::Result {
    let bits = value.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    let (mantissa, shift) = if exponent == 0 {
        (fraction, 1074)
    } else {
        (fraction | (1u64 << 52), 1075 - exponent)
    };
    let (Some(&scale), true) = (
        POW10.get(decimals),
        exponent != 0x7ff && (1..=110).contains(&shift),
    ) else {
        return write!(w, "{value:.decimals$}");
    };
    let scaled = u128::from(mantissa) * scale;
    let mut q = scaled >> shift;
    let rem = scaled - (q << shift);
    let half = 1u128 << (shift - 1);
    if rem > half || (rem == half && q & 1 == 1) {
        q += 1;
    }
    let parts = u64::try_from(q)
        .ok()
        .zip(u64::try_from(scale).ok())
        .and_then(|(q, unit)| q.checked_div(unit).zip(q.checked_rem(unit)));
    let Some((whole, fraction)) = parts else {
        return write!(w, "{value:.decimals$}");
    };
    if value.is_sign_negative() {
        w.write_char('-')?;
    }
    write_digits(w, whole, 1)?;
    if decimals > 0 {
        w.write_char('.')?;
        write_digits(w, fraction, decimals)?;
    }
    Ok(())
}

/// Writes `n` in decimal, zero-padded to at least `width` digits (`width` at most 20).
fn write_digits<W: Write>(w: &mut W, mut n: u64, width: usize) -> fmt::Result {
    let mut digits = [b'0'; 20];
    let mut start = digits.len();
    while start > 0 && (n > 0 || digits.len() - start < width) {
        start -= 1;
        if let Some(d) = digits.get_mut(start) {
            *d = b'0' + (n % 10) as u8;
        }
        n /= 10;
    }
    for &d in digits.get(start..).unwrap_or(&[]) {
        w.write_char(char::from(d))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use crate::output::Status;
    use crate::sample::Attitude;
    use crate::units::arcsec_to_rad;
    use crate::Real;
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::format;
    use std::string::String;
    use std::vec;

    fn output(time_s: f64, estimate: Option<Estimate>) -> Output {
        Output {
            time_s,
            status: if estimate.is_some() {
                Status::Estimating
            } else {
                Status::WarmingUp
            },
            estimate,
            // Exact in f32 and in f64: the same row in either build.
            corrected: Attitude {
                heading_rad: 0.5,
                roll_rad: -0.25,
                pitch_rad: 0.125,
            },
            health: Health::NONE,
        }
    }

    fn row(f: impl FnOnce(&mut String) -> fmt::Result) -> String {
        let mut s = String::new();
        f(&mut s).unwrap();
        s
    }

    #[test]
    fn rows_as_documented() {
        let e = Estimate {
            x_rad: [200.0, -150.0, 300.0, -250.0].map(|a| arcsec_to_rad(a) as Real),
            sigma_rad: [1.0, 2.0, 3.0, 4.0].map(|a| arcsec_to_rad(a) as Real),
        };
        assert_eq!(
            row(|w| write_output(w, &output(0.0, None))),
            "0.000000,,,,,,,,,warming_up,28.647889757,-14.323944878,7.161972439,0,,0,0,0.000,,,,"
        );
        let mut later = output(2.0, Some(e));
        later.health = Health {
            changes_detected: 2,
            last_change_s: Some(1234.5),
            window_restarts: 3,
            rejected: 4,
            mismatch_s: 60.0,
            residual_rad: Some([arcsec_to_rad(0.5) as Real, arcsec_to_rad(1.25) as Real]),
            noise_scale: Some([1.0, 2.5]),
        };
        let latched = row(|w| write_output(w, &later));
        assert!(
            latched.ends_with(",estimating,28.647889757,-14.323944878,7.161972439,2,1234.500000,3,4,60.000,0.5000,1.2500,1.0000,2.5000"),
            "{latched}"
        );
        let with = row(|w| write_output(w, &output(1.0, Some(e))));
        assert!(with.starts_with("1.000000,200.0000,-150.0000,300.0000,-250.0000,1.0000,2.0000,3.0000,4.0000,estimating,"), "{with}");
        let rejected = row(|w| write_rejected(w, 2.0, RejectReason::NonFinite, Some(&e)));
        assert!(
            rejected.starts_with("2.000000,200.0000,")
                && rejected.ends_with(",rejected_non_finite,,,,,,,,,,,,"),
            "{rejected}"
        );
        assert_eq!(
            row(|w| write_rejected(w, f64::NAN, RejectReason::NonFinite, None)),
            "NaN,,,,,,,,,rejected_non_finite,,,,,,,,,,,,"
        );
        // As many cells as the header names, on every kind of row.
        let cells = HEADER.split(',').count();
        for r in [&with, &latched, &rejected] {
            assert_eq!(r.split(',').count(), cells, "{r}");
        }
    }

    #[test]
    fn the_widest_row_fits() {
        let huge = Estimate {
            x_rad: [-Real::MAX; 4],
            sigma_rad: [-Real::MAX; 4],
        };
        let longest = Status::ALL.iter().map(|s| s.name().len()).max().unwrap();
        let status = *Status::ALL
            .iter()
            .find(|s| s.name().len() == longest)
            .unwrap();
        let out = Output {
            time_s: -f64::MAX,
            status,
            estimate: Some(huge),
            corrected: Attitude {
                heading_rad: -Real::MAX,
                roll_rad: -Real::MAX,
                pitch_rad: -Real::MAX,
            },
            health: Health {
                changes_detected: u32::MAX,
                last_change_s: Some(-f64::MAX),
                window_restarts: u32::MAX,
                rejected: u32::MAX,
                mismatch_s: f64::from(u32::MAX) * 10.0,
                residual_rad: Some([-Real::MAX; 2]),
                noise_scale: Some([Real::MAX; 2]),
            },
        };
        let accepted = row(|w| write_output(w, &out));
        let reason = RejectReason::ALL
            .iter()
            .copied()
            .max_by_key(|r| r.name().len())
            .unwrap();
        let rejected = row(|w| write_rejected(w, -f64::MAX, reason, Some(&huge)));
        for r in [accepted, rejected] {
            assert!(r.len() < MAX_ROW_LEN, "{} bytes", r.len() + 1);
        }
    }

    #[test]
    fn times_are_written_as_the_float_formatter_writes_them() {
        for t in [
            0.0,
            -0.0,
            1.0,
            172_799.0,
            -3.0,
            0.5,
            1e-7,
            123_456.000_000_4,
            8.9e15,
            9.1e15,
            1e300,
            f64::NAN,
            f64::INFINITY,
        ] {
            assert_eq!(row(|w| write_time(w, t)), format!("{t:.6}"), "{t}");
        }
    }

    #[test]
    fn fixed_formatting_equals_the_standard_formatter() {
        // ChaCha8 from a fixed seed: the same values on every run.
        let mut rng = ChaCha8Rng::seed_from_u64(0x9E37_79B9_7F4A_7C15);
        let mut next = || rng.next_u64();
        let mut values = vec![
            0.0,
            -0.0,
            0.5,
            1.5,
            2.5,
            -2.5,
            0.125,
            0.375,
            1e-5,
            -1e-5,
            0.00005,
            0.00015,
            1e300,
            -1e-300,
            5e-324,
            f64::NAN,
            f64::INFINITY,
            9.007_199_254_740_993e15,
        ];
        for _ in 0..100_000 {
            let r = next();
            // Random bit patterns between 2^-64 and 2^64, arcsec-like and degree-like values.
            values.push(f64::from_bits(
                (r & 0x800f_ffff_ffff_ffff) | ((1023 - 64 + (r >> 52) % 128) << 52),
            ));
            values.push(((r >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2000.0);
            values.push(
                ((r >> 40) as f32 / (1u32 << 24) as f32 - 0.5) as f64 * 57.295_779_513_082_32,
            );
            // Exact ties at each number of decimals: k + 1/2 units of the last place.
            let k = (r >> 44) as f64;
            values.push((k + 0.5) / 16.0);
        }
        let mut fast = String::new();
        for v in values {
            for decimals in [0, 4, 6, 9, 10] {
                fast.clear();
                write_fixed(&mut fast, v, decimals).unwrap();
                assert_eq!(
                    fast,
                    format!("{v:.decimals$}"),
                    "{v:e} to {decimals} decimals"
                );
            }
        }
    }
}
