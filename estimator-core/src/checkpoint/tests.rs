//! What the checkpoint tests share (a running estimator of each method, its image, a part written
//! and read back, the check that a tampered image is refused with the estimator untouched) and the
//! tests of the frame: CRC, length, method code, padding, and the golden image that pins the
//! format. The tests of each part are next to the part (`<module>/checkpoint.rs`); the end-to-end
//! properties (a restart from every phase, every bit flip refused) are in
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
            let roll = 0.035 * (t * 1.047).sin() - x[0] * lat.sin() * (rho - s).cos()
                + x[2] * lat.cos() * rho.sin();
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
    let mut buf = vec![0u8; CHECKPOINT_LEN];
    assert_eq!(est.checkpoint(&mut buf), Ok(buf.len()));
    buf
}

/// `part` written (exactly [`Stored::LEN`] bytes, or the test fails) and read back with `context`.
pub(crate) fn written_and_read<T: Stored>(
    part: &T,
    context: T::Context<'_>,
) -> Result<T, CheckpointError> {
    let mut buf = vec![0u8; T::LEN];
    let mut w = Writer::new(&mut buf, 0);
    part.write(&mut w);
    assert_eq!(
        w.pos(),
        T::LEN,
        "{} writes {} bytes, its LEN says {}",
        core::any::type_name::<T>(),
        w.pos(),
        T::LEN
    );
    let mut r = Reader::new(&buf, 0);
    let back = T::read(&mut r, context);
    assert!(
        back.is_err() || r.pos() == T::LEN,
        "{} reads {} bytes",
        core::any::type_name::<T>(),
        r.pos()
    );
    back
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

#[test]
fn crc32_matches_the_standard_check_value() {
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(crc32(b""), 0);
}

#[test]
fn image_length() {
    // At most 2 KiB, the same for every ring capacity, a multiple of 4.
    #[cfg(not(feature = "f64"))]
    assert_eq!(CHECKPOINT_LEN, 944);
    #[cfg(feature = "f64")]
    assert_eq!(CHECKPOINT_LEN, 1116);
    const { assert!(CHECKPOINT_LEN <= 2048) };
    assert_eq!(Estimator::<720>::CHECKPOINT_LEN, CHECKPOINT_LEN);
    assert_eq!(Est::CHECKPOINT_LEN, CHECKPOINT_LEN);
    assert_eq!(CHECKPOINT_LEN % 4, 0);
}

#[test]
fn bad_method_codes_and_padding_are_refused() {
    use CheckpointError::*;
    let est = running(Method::Traditional);
    let good = image_of(&est);
    let edit = |at: usize, v: u8| {
        let mut b = good.clone();
        b[at] = v;
        reseal(&mut b);
        b
    };
    // Padding after the traditional method's state, and at the end of the image.
    refused(
        &edit(good.len() - CRC_LEN - 100, 1),
        UnusedNotZero(Part::Padding),
    );
    refused(
        &edit(good.len() - 1 - CRC_LEN, 1),
        UnusedNotZero(Part::Padding),
    );
    // Unknown method code.
    refused(&edit(7, 9), UnknownMethod(9));

    // And the genuine image restores into an estimator of another method, method and all.
    let mut target = running(Method::Windowed);
    target.restore(&good).unwrap();
    assert_eq!(target.config().method, Method::Traditional);
    assert_eq!(target.estimate(), est.estimate());
    assert_eq!(image_of(&target), good);
}

#[test]
fn errors_say_what_to_do_with_an_old_image() {
    use std::string::ToString;
    let old = CheckpointError::Version {
        found: 4,
        expected: VERSION,
    }
    .to_string();
    assert!(
        old.contains("older firmware") && old.contains("discarded"),
        "{old}"
    );
    let new = CheckpointError::Version {
        found: VERSION + 1,
        expected: VERSION,
    }
    .to_string();
    assert!(new.contains("newer firmware"), "{new}");
    let e: &dyn core::error::Error = &CheckpointError::Inconsistent(Part::TimeGrid);
    assert_eq!(e.to_string(), "checkpoint sample grid: inconsistent values");
}

/// The golden image of format version 7 (`f32`): the image [`running`]`(Method::Windowed)`
/// wrote when the format was made. A change of the format (a field added, dropped, reordered or
/// re-encoded) fails this test: bump [`VERSION`] and make a new golden image (print
/// `image_of(&running(Method::Windowed))` as hex), with the state it must decode to.
#[cfg(not(feature = "f64"))]
const GOLDEN_V7: &str = concat!(
    "5249454307000400b00300000000000000000000000000000000000000001fdd9e3b7cc90f38fede793281a6173d0000",
    "0000000000002eada2360ad7233c7958cb38020000009c02000001000000000000f03f01000000000000000000db514a",
    "3912bf1e3ab80200000000000000000000000000000000000000000000b8020000040000000000000000000000000000",
    "00000000000000000000000000000001000000000000f03f00010000000000d8854000000000000000000000803f00c0",
    "2e4400c02e44000000000000803f0000004000004040000080400000a0400000c0400000e04000000041000010410000",
    "20410000304100004041000050410000604100007041000080410000884100009041000098410000a0410000a8410000",
    "b0410000b8410000c0410000c8410000d0410000d8410000e0410000e8410000f0410000f84120000000a80200003296",
    "492800000000000000000178000000000101000000000001f93614400000000000000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
    "00000000000000000000000000000000000000000100000000000000000000000000000000000000017a000000e60fc9",
    "400000000000000000010000000000c51525324711e22a93000000c50000007e637d3a2f373eba151f9c3a5d1a11bad4",
    "dbed2de063ab276624b52df9542aade063ab27d6c9ed2d0d6c2a2d6709b52d6624b52d0d6c2a2daaff942e006e63a5f9",
    "542aad6709b52d006e63a552f8942e907fc4b45cf35b36dbff29b5805e7c35015900000058000000cbd38e3d17f38f3d",
    "d86d593dd86d593d7d852130280627300000000000000000000000000000000000000000000000000000000000000000",
    "00000000000000000000803f0000803f0000803f0000803fd27cae363876ae36f2510a37844e0a3700d800753adeff3c",
    "ba61ad983abc0e0bba8732c6315fc8b9315e67c12c09a1f92c5900000058000000000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000000006a049aac",
);

#[cfg(not(feature = "f64"))]
#[test]
fn the_golden_image_decodes_to_its_state_and_is_written_back_byte_for_byte() {
    assert_eq!(
        VERSION, 7,
        "a new format version needs a golden image of its own"
    );
    let golden: Vec<u8> = (0..GOLDEN_V7.len() / 2)
        .map(|i| u8::from_str_radix(&GOLDEN_V7[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    assert_eq!(golden.len(), CHECKPOINT_LEN);
    let est = Est::from_checkpoint(&golden).expect("the golden image restores");
    assert_eq!(
        image_of(&est),
        golden,
        "restored and written again, the golden image changed"
    );
    // What the bytes mean: the configuration, the grid, the pattern, the counters, the filter.
    // The default configuration when the image was written.
    assert_eq!(est.config(), &Config::with_method(Method::Windowed));
    assert_eq!(est.sample_interval_s(), Some(1.0));
    assert_eq!(est.last_sample_time_s(), Some(699.0));
    assert_eq!(est.rotation().period_s, Some(120.0));
    let c = est.counters();
    assert_eq!(
        (c.accepted, c.filled, c.window_restarts, c.clock_steps),
        (696, 4, 0, 0)
    );
    // The filter's states and 1-sigma, bit for bit.
    let e = est.estimate().expect("an estimate");
    assert_eq!(
        e.x_rad.map(f32::to_bits),
        [981_295_998, 3_124_639_535, 983_310_101, 3_121_683_037]
    );
    assert_eq!(
        e.sigma_rad.map(f32::to_bits),
        [917_404_882, 917_403_192, 923_423_218, 923_422_340]
    );
}
