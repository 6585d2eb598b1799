//! What the checkpoint tests share: a running estimator of each method, its image, tampering
//! with one part of an image, and the check that a tampered image is refused with the estimator
//! untouched. The tests of each part are next to the part (`<module>/checkpoint.rs`); here are
//! the tests of the frame: CRC, lengths, flags, codes and padding in the bytes. The end-to-end
//! properties (bit-identical continuation from every phase, every bit flip refused) are in
//! `tests/checkpoint_roundtrip.rs`.

use super::wire::{Reader, Writer};
use super::*;
use crate::config::{Config, Method};
use crate::estimator::Estimator;
use crate::sample::Sample;
use crate::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S};
use std::vec;
use std::vec::Vec;

/// The estimator the tests checkpoint: a ring of 64 entries.
pub(crate) type Est = Estimator<64>;

#[test]
fn crc32_matches_the_standard_check_value() {
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(crc32(b""), 0);
}

#[test]
fn default_image_is_23384_bytes_with_f32() {
    #[cfg(not(feature = "f64"))]
    assert_eq!(CHECKPOINT_LEN, 23_384);
    #[cfg(feature = "f64")]
    assert_eq!(CHECKPOINT_LEN, 24_416);
    assert_eq!(Estimator::<720>::CHECKPOINT_LEN, CHECKPOINT_LEN);
    assert_eq!(CHECKPOINT_LEN % 4, 0);
}

/// A 1 Hz log: a one-way rotation of 120 s (two samples a bin in a ring of 64), 2 deg of roll
/// sway, eq (2) for known errors; every 97th sample lost (filled) from sample 300 on.
fn log(n: u32) -> Vec<Sample> {
    let x = [200.0, -150.0, 300.0, -250.0].map(arcsec_to_rad);
    (0..n)
        .filter(|k| k % 97 != 50 || *k < 300)
        .map(|k| {
            let t = f64::from(k);
            let rho = 0.3 + 2.0 * core::f64::consts::PI * t / 120.0;
            let s = 1.1 + EARTH_RATE_RAD_PER_S * t;
            let lat = 0.7f64;
            let roll = 0.035 * (t * 1.047).sin() - x[0] * lat.sin() * (rho - s).cos() + x[2] * lat.cos() * rho.sin();
            let pitch = 0.01 * (t * 0.698).sin() + x[0] * (rho - s).sin() - x[1] * (rho - s).cos();
            let deg = |r: f64| r.to_degrees();
            Sample::from_degrees(t, deg(rho), deg(s), deg(lat), 20.0, deg(roll), deg(pitch))
        })
        .collect()
}

/// An estimator of `method` after 700 samples of [`log`]: estimating, with bins of 2 samples
/// over the 120 s period, filled gaps, a fill-error estimate, learned features and a timing pass.
pub(crate) fn running(method: Method) -> Est {
    let mut est = Est::new(Config::with_method(method)).unwrap();
    for s in log(700) {
        est.step(&s).unwrap();
    }
    assert!(est.estimate().is_some(), "{method:?}");
    est
}

/// The image of `est`.
pub(crate) fn image_of<const CAP: usize>(est: &Estimator<CAP>) -> Vec<u8> {
    let mut buf = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
    assert_eq!(est.checkpoint(&mut buf), Ok(buf.len()));
    buf
}

/// Makes the CRC of a tampered image valid again.
pub(crate) fn reseal(buf: &mut [u8]) {
    let n = buf.len();
    let crc = crc32(&buf[..n - CRC_LEN]);
    buf[n - CRC_LEN..].copy_from_slice(&crc.to_le_bytes());
}

/// Restores an image into a running estimator: the error, and the estimator must not change.
pub(crate) fn refused(buf: &[u8], expected: CheckpointError) {
    let mut target = running(Method::Windowed);
    let before = target.clone();
    assert_eq!(target.restore(buf), Err(expected));
    assert_eq!(target, before);
}

/// The image with the part at `offset` read with `read`, changed with `edit`, written back with
/// `write` and resealed: an image whose CRC is valid and whose part holds what `edit` made of it.
pub(crate) fn tampered_part<T>(
    image: &[u8],
    offset: usize,
    read: impl FnOnce(&mut Reader<'_>) -> T,
    edit: impl FnOnce(&mut T),
    write: impl FnOnce(&T, &mut Writer<'_>),
) -> Vec<u8> {
    let mut part = read(&mut Reader::new(image, offset));
    edit(&mut part);
    let mut out = image.to_vec();
    write(&part, &mut Writer::new(&mut out, offset));
    reseal(&mut out);
    out
}

/// Writes a `u32` into an image at `pos`.
pub(crate) fn put_u32(b: &mut [u8], pos: usize, v: u32) {
    b[pos..pos + 4].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn bad_flags_codes_unused_bytes_and_padding_are_refused() {
    use CheckpointError::*;
    let est = running(Method::Traditional);
    let good = image_of(&est);
    let edit = |at: usize, v: u8| {
        let mut b = good.clone();
        b[at] = v;
        reseal(&mut b);
        b
    };
    let running_at = RUNNING_OFFSET;
    // Padding after the traditional method's state.
    refused(&edit(good.len() - 10, 1), UnusedNotZero(Part::Padding));
    // An absent pinned period with a non-zero value.
    assert_eq!(good[HEADER_LEN], 0);
    refused(&edit(HEADER_LEN + 3, 1), UnusedNotZero(Part::Config));
    // The feed interval's presence flag (after the grid index) set to 2.
    refused(&edit(running_at + 4, 2), InvalidValue(Part::Estimator));
    // Status and fault codes.
    refused(&edit(running_at + 14 + R, 10), InvalidValue(Part::Status));
    refused(&edit(running_at + 15 + R, 4), InvalidValue(Part::Fault));
    refused(&edit(running_at + 15 + R, 0x10), InvalidValue(Part::Fault));
    // No fault, but a time for it.
    refused(&edit(running_at + 16 + R, 1), UnusedNotZero(Part::Fault));
    // Unknown method code.
    refused(&edit(7, 9), UnknownMethod(9));

    // And the genuine image restores into an estimator of another method, method and all.
    let mut target = running(Method::Windowed);
    target.restore(&good).unwrap();
    assert_eq!(target, est);
}

#[test]
fn errors_say_what_to_do_with_an_old_image() {
    use std::string::ToString;
    let old = CheckpointError::Version { found: 2, expected: VERSION }.to_string();
    assert!(old.contains("older firmware") && old.contains("discarded"), "{old}");
    let new = CheckpointError::Version { found: VERSION + 1, expected: VERSION }.to_string();
    assert!(new.contains("newer firmware"), "{new}");
    let e: &dyn core::error::Error = &CheckpointError::Inconsistent(Part::WindowSums);
    assert_eq!(e.to_string(), "checkpoint window running sums: inconsistent values");
}
