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

/// Four bits at a time, the same CRC as the `crc` crate's CRC-32/ISO-HDLC, for every length up
/// to beyond an image's and every byte value.
#[test]
fn crc32_is_the_crc_crates() {
    let reference = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
    let bytes: std::vec::Vec<u8> = (0..1200u32)
        .map(|k| (k.wrapping_mul(2_654_435_761) >> 13) as u8 ^ k as u8)
        .collect();
    for n in 0..bytes.len() {
        assert_eq!(
            crc32(&bytes[..n]),
            reference.checksum(&bytes[..n]),
            "{n} bytes"
        );
    }
    let all: std::vec::Vec<u8> = (0..=255).collect();
    assert_eq!(crc32(&all), reference.checksum(&all));
}

#[test]
fn image_length() {
    // At most 2 KiB, the same for every ring capacity, a multiple of 4.
    #[cfg(not(feature = "f64"))]
    assert_eq!(CHECKPOINT_LEN, 900);
    #[cfg(feature = "f64")]
    assert_eq!(CHECKPOINT_LEN, 1344);
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

/// The golden image of format version 9 (`f32`): the image [`running`]`(Method::Windowed)`
/// wrote when the format was made. A change of the format (a field added, dropped, reordered or
/// re-encoded) fails this test: bump [`VERSION`] and make a new golden image (the ignored test
/// `print_golden_image` prints it, with the state it must decode to).
#[cfg(not(feature = "f64"))]
const GOLDEN_V9: &str = concat!(
    "5249454309000400840300000000000000000000000000000000000000001fdd9e3b7cc90f38fede793281a6173d0000",
    "0000000000002eada2360ad7233c7958cb38020000000000000000000000000000000000000000000000000000000000",
    "000000000000000000000000000000b302000001000000000000f03f01000000000000000000db514a3912bf1e3ab802",
    "00000000000000000000000000000000000000000000b802000004000000000000000000000000000000000000000000",
    "0000000000000000000000000000000001000000000000f03f00010000000000d8854000000000000000000000803f00",
    "c02e4400c02e44000000000000803f0000004000004040000080400000a0400000c0400000e0400000004109000000b8",
    "0200002ef9c9270000000000000000017800000000010100000000000131488e3f000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
    "000000000000000000000000000000000000000000000000000100000000000000000000000000000000000000017a00",
    "0000eb0fc94000000000000000000100000000003e35253285cede2a99000000d00000003ff87c3ac91340ba93889b3a",
    "2f6812ba000000003419e22d288447a7b10fac2da94e22ad00000000288447a72c13e22d5032222d850fac2d00000000",
    "b10fac2d5032222d18fd8b2e60fb4ea700000000a94e22ad850fac2d60fb4ea733fe8b2e000000000000000000000000",
    "0000000000000000ee92932100301209b53a5f10b65d0000000000000000000000000000000000000000000000000000",
    "00000000000000803f0000803ff89a8e3d882c903d7d852130bfcf1c37a7cd1c37002ff9b23107e8a6315d0000001a35",
    "dbb40148a7355e000000000000000000000000000000000000000000000000000000000000000000803f0000803fca6c",
    "593dca6c593da400273051e12d37b8e22d370098d6d32c5142f72c5e000000103c5726d6b73aa217340d26f856b9a500",
    "000000becd4f26f269b325acf0082600000000f4c0472e00904da400000000e8c0472e000000000000000000086d813a",
    "734a42ba0b549c3a2be814ba000000000000000000000000000000000000000000000000000000000000000000000000",
    "0000000000000000000000000000000000000000000000000000000000000000f1254693",
);

#[cfg(not(feature = "f64"))]
#[test]
fn the_golden_image_decodes_to_its_state_and_is_written_back_byte_for_byte() {
    assert_eq!(
        VERSION, 9,
        "a new format version needs a golden image of its own"
    );
    let golden: Vec<u8> = (0..GOLDEN_V9.len() / 2)
        .map(|i| u8::from_str_radix(&GOLDEN_V9[2 * i..2 * i + 2], 16).unwrap())
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
        [981_268_543, 3_124_761_545, 983_271_571, 3_121_768_495]
    );
    assert_eq!(
        e.sigma_rad.map(f32::to_bits),
        [924_635_071, 924_634_535, 925_753_681, 925_754_040]
    );
}

#[cfg(not(feature = "f64"))]
#[test]
#[ignore]
fn print_golden_image() {
    let est = running(Method::Windowed);
    let img = image_of(&est);
    let hex: std::string::String = img.iter().map(|b| std::format!("{b:02x}")).collect();
    for chunk in hex.as_bytes().chunks(96) {
        std::println!("    \"{}\",", std::str::from_utf8(chunk).unwrap());
    }
    let back = Est::from_checkpoint(&img).unwrap();
    let c = back.counters();
    std::println!(
        "counters {:?}",
        (c.accepted, c.filled, c.window_restarts, c.clock_steps)
    );
    std::println!(
        "last {:?} period {:?}",
        back.last_sample_time_s(),
        back.rotation().period_s
    );
    let e = back.estimate().unwrap();
    std::println!("x {:?}", e.x_rad.map(f32::to_bits));
    std::println!("s {:?}", e.sigma_rad.map(f32::to_bits));
}
