//! Checkpoint and restore on the project's own scenarios (host_sim::scenario): for each scenario
//! and method, checkpoint at spread-out and random cut points, restore into a fresh estimator,
//! continue to the end: every output bit-identical to the uninterrupted run, and the final state
//! image identical. The sea scenario moves the latitude (the core's latitude cache changes) and
//! turns the heading; with rotation jitter on it also trips the rotation monitor.

use estimator_core::{Config, Estimator, Method, Output, Real, SampleError};
use host_sim::replay::sample_of;
use host_sim::scenario::{generate, ScenarioKind, ScenarioParams};

fn fingerprint(r: &Result<Output, SampleError>) -> Vec<u64> {
    match r {
        Err(e) => vec![u64::MAX, e.reason() as u64],
        Ok(o) => {
            let mut v = vec![o.time_s.to_bits(), u64::from(o.status.code())];
            let mut push = |x: Real| v.push(x.to_bits() as u64);
            push(o.corrected.heading_rad);
            push(o.corrected.roll_rad);
            push(o.corrected.pitch_rad);
            if let Some(e) = o.estimate {
                for i in 0..4 {
                    push(e.x_rad[i]);
                    push(e.sigma_rad[i]);
                }
            }
            v
        }
    }
}

fn image(est: &Estimator) -> Vec<u8> {
    let mut buf = vec![0u8; estimator_core::checkpoint::CHECKPOINT_LEN];
    est.checkpoint(&mut buf).unwrap();
    buf
}

fn check(kind: ScenarioKind, method: Method, jitter_deg: f64, cuts: usize) {
    let mut params = ScenarioParams::new(kind, 7);
    params.duration_s = params.duration_s.min(4.0 * 3600.0);
    params.mismatch.rotation_jitter_deg = jitter_deg;
    let samples: Vec<_> = generate(&params).rows.iter().map(sample_of).collect();
    let n = samples.len();
    let config = Config::with_method(method);
    let mut reference = Estimator::new(config).unwrap();
    let mut outputs = Vec::with_capacity(n);
    let mut images = Vec::new();
    // Cut points: first, last-but-one, evenly spread, and LCG-random.
    let mut lcg = 0x2545_F491_4F6C_DD1Du64 ^ (method as u64) << 7;
    let mut cut_points: Vec<usize> = vec![0, n - 2];
    cut_points.extend((1..cuts / 2).map(|i| i * n / (cuts / 2)));
    for _ in 0..cuts / 2 {
        lcg = lcg.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        cut_points.push((lcg >> 33) as usize % (n - 1));
    }
    cut_points.sort_unstable();
    let mut next_cut = cut_points.iter().peekable();
    for (k, s) in samples.iter().enumerate() {
        outputs.push(fingerprint(&reference.step(s)));
        while next_cut.peek() == Some(&&k) {
            images.push((k, image(&reference)));
            next_cut.next();
        }
    }
    let final_image = image(&reference);
    let mut faults = 0;
    for o in &outputs {
        if o.len() > 1 && (1..=3).contains(&o[1]) {
            faults += 1;
        }
    }
    for (cut, img) in &images {
        let mut resumed = Estimator::new(Config::with_method(Method::Traditional)).unwrap();
        resumed.restore(img).unwrap();
        for k in cut + 1..n {
            assert_eq!(fingerprint(&resumed.step(&samples[k])), outputs[k], "{kind:?} {method:?}: cut {cut}, output {k} differs");
        }
        assert_eq!(image(&resumed), final_image, "{kind:?} {method:?}: cut {cut}: final state differs");
    }
    println!("{kind:?} {method:?} jitter {jitter_deg}: {n} samples, {} cuts, {faults} rotation-fault steps", images.len());
}

#[test]
fn paper_scenario_restores_bit_identically_for_every_method() {
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        check(ScenarioKind::Paper, method, 0.0, 12);
    }
}

#[test]
fn sea_scenario_with_rotation_jitter_restores_bit_identically() {
    check(ScenarioKind::Sea, Method::Windowed, 0.0, 12);
    check(ScenarioKind::Sea, Method::Windowed, 0.1, 12);
}

#[test]
fn turntable_scenario_restores_bit_identically() {
    check(ScenarioKind::Turntable, Method::Windowed, 0.0, 8);
}
