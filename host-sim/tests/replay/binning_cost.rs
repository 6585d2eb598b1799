//! What binning costs: when one rotation period holds more samples than the ring (720 entries by
//! default), consecutive samples are averaged into bins. The same logs through the default
//! estimator (binned) and through one whose ring holds the whole period (not binned), sea
//! scenario, seeds 1-3: the worst error over x1..x4 at 20000 and 45000 s of each, and their
//! difference. Bound: binning costs at most 0.5 arcsec (the figures are printed and quoted in
//! docs/real-logs.md).

use estimator_core::Config;
use host_sim::report::accuracy::Accuracy;
use host_sim::sim::rotation_scheme::RotationScheme;
use host_sim::sim::scenario::{ScenarioKind, ScenarioParams};
use host_sim::study::monte_carlo::{track_run, track_run_with_capacity};
use rayon::prelude::*;

const TIMES_S: [f64; 2] = [20_000.0, 45_000.0];

fn worst(a: &Accuracy) -> [f64; 2] {
    core::array::from_fn(|k| {
        a.points[k]
            .error_arcsec
            .map_or(f64::INFINITY, |e| e.iter().fold(0.0, |m, v| m.max(v.abs())))
    })
}

fn params(seed: u64, scheme: RotationScheme, period_s: f64, interval_s: f64) -> ScenarioParams {
    let mut p = ScenarioParams::new(ScenarioKind::Sea, seed);
    p.duration_s = 45_001.0;
    p.scheme = scheme;
    p.rotation_period_s = period_s;
    p.sample_interval_s = interval_s;
    p
}

#[test]
fn binning_a_10_hz_log_or_a_long_period_costs_at_most_half_an_arcsec() {
    // (scheme, period, interval, a capacity that holds the whole period)
    let cases: Vec<(u64, RotationScheme, f64, f64)> = (1..=3)
        .flat_map(|seed| {
            [
                (seed, RotationScheme::Continuous, 480.0, 0.1),
                (seed, RotationScheme::FourPosition, 1440.0, 1.0),
            ]
        })
        .collect();
    let results: Vec<_> = cases
        .par_iter()
        .map(|&(seed, scheme, period, interval)| {
            let p = params(seed, scheme, period, interval);
            let binned = worst(&track_run(&p, Config::default(), &TIMES_S).unwrap());
            let whole = if interval < 1.0 {
                worst(&track_run_with_capacity::<4800>(&p, Config::default(), &TIMES_S).unwrap())
            } else {
                worst(&track_run_with_capacity::<1440>(&p, Config::default(), &TIMES_S).unwrap())
            };
            (seed, scheme, period, interval, binned, whole)
        })
        .collect();
    for (seed, scheme, period, interval, binned, whole) in &results {
        println!(
            "seed {seed} {} {period} s every {interval} s: binned {:.3} / {:.3} arcsec, whole period {:.3} / {:.3} arcsec (20000 / 45000 s)",
            scheme.name(),
            binned[0],
            binned[1],
            whole[0],
            whole[1]
        );
    }
    for (seed, scheme, period, interval, binned, whole) in &results {
        for k in 0..2 {
            assert!(
                binned[k] - whole[k] < 0.5,
                "seed {seed} {} {period} s every {interval} s: binned {:.3}, whole {:.3}",
                scheme.name(),
                binned[k],
                whole[k]
            );
        }
    }
}
