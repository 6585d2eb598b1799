//! Restore on arbitrary bytes. Even first byte: the bytes are the image. Odd: a genuine image of a
//! running estimator, edited by (u16 offset, u8 xor) triples and re-sealed with a correct CRC, so
//! the edits reach the field validation. Checks: no panic; on error the target is untouched; an
//! accepted image gives an estimator whose next 40 steps run without panic and with finite output
//! (1 s apart from t = 10^4 s: a clock jump for the restored grid, or its first samples).
#![no_main]

mod common;

use common::{assert_finite, healthy, CAP};
use estimator_core::checkpoint::crc32;
use estimator_core::{Config, Estimator, Method};
use libfuzzer_sys::fuzz_target;

/// Period of the rotation the sources run, samples of 1 s: 64 s, binned by 2 in the ring of `CAP`.
const PERIOD_SAMPLES: f64 = 64.0;

/// An estimator of `method` (interval and period learned from the data) after `steps` samples:
/// a few hundred take it through learning the interval, detecting the period, learning the
/// pattern, filling the window and estimating.
fn running(method: u8, steps: usize) -> Estimator<CAP> {
    let config = Config { method: Method::try_from(method % 3).unwrap_or_default(), ..Config::default() };
    let mut est = Estimator::<CAP>::new(config).expect("valid config");
    let step = 2.0 * std::f64::consts::PI / PERIOD_SAMPLES;
    for k in 0..steps {
        est.step(&healthy(k as f64, 0.3 + step * k as f64, 0.7, 0.0, 0.0)).expect("healthy");
    }
    est
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else { return };
    let len = Estimator::<CAP>::CHECKPOINT_LEN;
    let image: Vec<u8> = if head & 1 == 0 {
        rest.to_vec()
    } else {
        let source = running(head >> 1, 4 * usize::from(rest.first().copied().unwrap_or(0)));
        let mut buf = vec![0u8; len];
        source.checkpoint(&mut buf).expect("checkpoint");
        for e in rest.get(1..).unwrap_or(&[]).chunks_exact(3) {
            let at = usize::from(u16::from_le_bytes([e[0], e[1]])) % len;
            buf[at] ^= e[2];
        }
        let crc = crc32(&buf[..len - 4]);
        buf[len - 4..].copy_from_slice(&crc.to_le_bytes());
        buf
    };
    let mut target = running(1, 40);
    let before = target.clone();
    match target.restore(&image) {
        Err(_) => assert!(target == before, "failed restore changed the estimator"),
        Ok(()) => {
            let period_s = target.rotation().period_s.unwrap_or(PERIOD_SAMPLES);
            let step = 2.0 * std::f64::consts::PI / period_s;
            for k in 0..40 {
                let t = 1e4 + k as f64;
                if let Ok(out) = target.step(&healthy(t, step * t, 0.7, 0.0, 0.0)) {
                    assert_finite(&out);
                }
            }
        }
    }
});
