//! Benchmarks: the core's step (each method) and `estimate` on a 2-day log (read, replay, write).
//! `cargo bench -p host-sim --features bench --bench estimator`; results in docs/results.md.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use estimator_core::{Config, Method};
use host_sim::formats::log_csv::write_log;
use host_sim::replay::{sample_of, HostEstimator, LogReplay};
use host_sim::sim::scenario::{generate, ScenarioKind, ScenarioParams};
use std::hint::black_box;

fn core_step(c: &mut Criterion) {
    let mut p = ScenarioParams::new(ScenarioKind::Paper, 1);
    p.duration_s = 20_000.0;
    let samples: Vec<_> = generate(&p).rows.iter().map(sample_of).collect();
    let mut group = c.benchmark_group("core_step");
    group.throughput(Throughput::Elements(samples.len() as u64));
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        group.bench_function(method.name(), |b| {
            b.iter_batched(
                || HostEstimator::new(Config::with_method(method)).unwrap(),
                |mut est| {
                    for s in &samples {
                        let _ = black_box(est.step(black_box(s)));
                    }
                    est
                },
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn estimate_two_days(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("host-sim-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("paper.csv");
    let out = dir.join("paper.estimates.csv");
    let g = generate(&ScenarioParams::new(ScenarioKind::Paper, 1));
    write_log(&log, &g.rows).unwrap();
    let mut group = c.benchmark_group("estimate_2day_log");
    group.sample_size(10);
    group.throughput(Throughput::Elements(g.rows.len() as u64));
    group.bench_function("windowed", |b| {
        b.iter(|| {
            LogReplay {
                estimates: Some(out.clone()),
                ..LogReplay::default()
            }
            .run(&log, &mut |_| {})
            .unwrap()
            .replay
            .counters
            .accepted
        })
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, core_step, estimate_two_days);
criterion_main!(benches);
