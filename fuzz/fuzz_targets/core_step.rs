//! The core step on arbitrary input: a configuration from the first byte, then 33-byte records,
//! each either a healthy sample perturbed by the record (roll/pitch offsets, rotation increment
//! from stopped through reversed to double speed, latitude up to +-89.99 deg, gaps) or a raw
//! sample from the record's bits. Checks: no panic, every accepted output finite, a rejected
//! sample changes nothing but its counter, and the final state validates (checkpoint round trip).
#![no_main]

mod common;

use common::{assert_finite, assert_state_valid, healthy, CAP};
use estimator_core::{Attitude, Config, Estimator, Method, Real, Sample};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else { return };
    let period = 60 + (head as usize >> 3) % 25; // 60..=84 samples of 1 s
    let config = Config {
        method: Method::try_from(head % 3).unwrap_or_default(),
        max_filled_gap_samples: u32::from((head >> 2) & 1) * 3,
        // The period pinned or detected, the interval pinned or learned.
        rotation_period_s: ((head >> 6) & 1 == 1).then_some(period as f64),
        sample_interval_s: ((head >> 7) & 1 == 1).then_some(1.0),
        ..Config::default()
    };
    let mut est = Estimator::<CAP>::new(config).expect("valid config");
    let mut t = 100.0;
    let mut rho = 0.3;
    let step = 2.0 * std::f64::consts::PI / period as f64;
    for r in rest.chunks_exact(33) {
        let i16_at = |i: usize| i16::from_le_bytes([r[i], r[i + 1]]) as f64;
        let sample = if r[0] < 200 {
            t += if r[7] % 8 == 7 { 1.0 + f64::from(r[8]) } else { 1.0 };
            rho += step * (f64::from(r[5]) - 64.0) / 64.0;
            let lat = (f64::from(r[6]) - 128.0) / 128.0 * 89.99_f64.to_radians();
            healthy(t, rho, lat, i16_at(1) * 1e-5, i16_at(3) * 1e-5)
        } else {
            let f = |i: usize| f32::from_le_bytes([r[i], r[i + 1], r[i + 2], r[i + 3]]) as Real;
            Sample {
                time_s: f64::from_le_bytes(r[1..9].try_into().expect("8 bytes")),
                rotation_rad: f(9),
                platform_rad: f(13),
                latitude_rad: f(17),
                attitude: Attitude { heading_rad: f(21), roll_rad: f(25), pitch_rad: f(29) },
            }
        };
        let before = (est.estimate(), est.counters(), est.rejected().total());
        match est.step(&sample) {
            Ok(out) => assert_finite(&out),
            Err(_) => {
                assert_eq!((est.estimate(), est.counters()), (before.0, before.1));
                assert_eq!(est.rejected().total(), before.2 + 1);
            }
        }
    }
    assert_state_valid(&est);
});
