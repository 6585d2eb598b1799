//! Any rotation scheme, period and sample interval, learned from the data; lost samples and loose
//! time stamps cost accuracy, never the estimate.
mod common;

use common::{Scheme, Signal};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Config, Estimator, Status};

const X: [f64; 4] = [200.0, -150.0, 300.0, -250.0];

struct Run {
    errors_arcsec: [f64; 4],
    sigma_arcsec: [f64; 4],
    status: Status,
    first_estimate_s: Option<f64>,
}

fn run(signal: &mut Signal, config: Config, duration_s: f64, interval_s: f64, keep: impl Fn(u64) -> bool, stamp: impl Fn(f64, u64) -> f64) -> (Estimator, Run) {
    let mut est: Estimator = Estimator::new(config).unwrap();
    let mut status = Status::WarmingUp;
    let mut first = None;
    let n = (duration_s / interval_s) as u64;
    for k in 0..n {
        if !keep(k) {
            continue;
        }
        let t = k as f64 * interval_s;
        let mut s = signal.sample(t);
        s.time_s = stamp(t, k);
        let out = est.step(&s).unwrap();
        status = out.status;
        if first.is_none() && out.estimate.is_some() {
            first = Some(t);
        }
    }
    let e = est.estimate().unwrap();
    let errors_arcsec = core::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - X[i]);
    let sigma_arcsec = core::array::from_fn(|i| rad_to_arcsec(e.sigma_rad[i] as f64));
    (est, Run { errors_arcsec, sigma_arcsec, status, first_estimate_s: first })
}

fn noisy(scheme: Scheme, period_s: f64, latitude_deg: f64) -> Signal {
    let mut s = Signal::new(X, latitude_deg);
    s.scheme = scheme;
    s.rotation_period_s = period_s;
    s.noise_arcsec = 5.0;
    s
}

#[test]
fn every_scheme_is_detected_and_estimated() {
    for scheme in [Scheme::OneWay(1.0), Scheme::OneWay(-1.0), Scheme::Reciprocating, Scheme::FourPosition, Scheme::EightPosition] {
        for period in [360.0, 720.0] {
            let mut sig = noisy(scheme, period, 40.0);
            let (est, r) = run(&mut sig, Config::default(), 10_000.0, 1.0, |_| true, |t, _| t);
            let rot = est.rotation();
            std::println!("{scheme:?} {period}: {:?} first {:?} err {:?} sigma {:?} {:?}", rot, r.first_estimate_s, r.errors_arcsec, r.sigma_arcsec, r.status);
            assert_eq!(rot.period_s, Some(period));
            for e in r.errors_arcsec {
                assert!(e.abs() < 3.0, "{scheme:?} {period}: {:?}", r.errors_arcsec);
            }
        }
    }
}

/// A deterministic pseudo-random stream in [0, 1).
fn uniform(seed: u64, k: u64) -> f64 {
    let mut z = seed.wrapping_add(k.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn lost_rows_outages_and_jittered_unix_stamps() {
    for (scheme, loss) in [(Scheme::OneWay(1.0), 0.02), (Scheme::Reciprocating, 0.05), (Scheme::FourPosition, 0.02)] {
        let mut sig = noisy(scheme, 480.0, 40.0);
        sig.roll_sway_deg = 6.0;
        let outages = [7000u64, 19000, 31000];
        let keep = |k: u64| uniform(7, k) >= loss && !outages.iter().any(|o| k >= *o && k < o + 60);
        let stamp = |t: f64, k: u64| 1.7e9 + t + 0.02 * (2.0 * uniform(11, k) - 1.0);
        let (est, r) = run(&mut sig, Config::default(), 45_000.0, 1.0, keep, stamp);
        std::println!("{scheme:?} loss {loss}: {:?} {:?} first {:?} err {:?} sigma {:?} {:?}", est.rotation(), est.counters(), r.first_estimate_s, r.errors_arcsec, r.sigma_arcsec, r.status);
    }
}

#[test]
fn sample_intervals_of_2_s_and_a_10_hz_log() {
    for interval in [2.0, 0.1] {
        let mut sig = noisy(Scheme::OneWay(1.0), 480.0, 40.0);
        let dur = if interval < 1.0 { 20_000.0 } else { 45_000.0 };
        let (est, r) = run(&mut sig, Config::default(), dur, interval, |_| true, |t, _| t);
        std::println!("{interval}: {:?} {:?} first {:?} err {:?} sigma {:?} {:?}", est.rotation(), est.sample_interval_s(), r.first_estimate_s, r.errors_arcsec, r.sigma_arcsec, r.status);
    }
}

#[test]
fn a_constant_heel_with_lost_rows_moves_no_error() {
    let keep = |k: u64| uniform(3, k) >= 0.02;
    let mut level = noisy(Scheme::FourPosition, 480.0, 40.0);
    let (_, a) = run(&mut level, Config::default(), 20_000.0, 1.0, keep, |t, _| t);
    let mut heeled = noisy(Scheme::FourPosition, 480.0, 40.0);
    heeled.low_frequency_deg = 3.0;
    let (_, b) = run(&mut heeled, Config::default(), 20_000.0, 1.0, keep, |t, _| t);
    std::println!("level {:?}\nheeled {:?}", a.errors_arcsec, b.errors_arcsec);
}
