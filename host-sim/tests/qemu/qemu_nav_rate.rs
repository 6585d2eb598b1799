//! Attitude at the navigation rate through the firmware: a 100 Hz sea log sent sample by sample
//! as `NavSample`s. The firmware bins the samples into its 1 s grid, steps each completed bin and
//! compensates every sample; its answers must be, bit for bit, what the core's `Binner`,
//! `Estimator::step` and `Estimator::compensate` give the same samples on the host. Prints what a
//! navigation sample costs on the Cortex-M4F, with and without a bin's step (docs/firmware.md).

use crate::qemu_support::*;
use estimator_core::binning::Binner;
use estimator_core::{Config, Estimator, SampleError};
use host_sim::formats::log_csv::read_log;
use host_sim::replay::sample_of;
use host_sim::stream::Target;
use link_protocol::{BinOutcome, Request, Response, SampleMsg};
use std::time::Duration;

/// Instructions per tick of the cost counter under `-icount shift=0` (docs/link-protocol.md).
fn instructions(ticks: u32, cost_counter_hz: u32) -> f64 {
    f64::from(ticks) * 1e9 / f64::from(cost_counter_hz)
}

#[test]
fn a_100_hz_log_sent_as_navigation_samples_is_binned_stepped_and_compensated_as_on_the_host() {
    let board = Board::Mps2An386;
    let dir = scratch("nav-rate-mps2-an386");
    // A 60 s rotation, so that estimates come within the test's 150 s (15,000 samples).
    let log = generated_log(
        &dir,
        "nav-100hz.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "150",
            "--sample-interval",
            "0.01",
            "--rotation-period",
            "60",
        ],
    );
    let lines = read_log(&log).unwrap();
    assert_eq!(lines.len(), 15_000);

    let mut binner = Binner::default();
    let mut host: Estimator = Estimator::new(Config::default()).unwrap();
    let mut target = Target::boot_qemu(
        &firmware_elf(board),
        board.machine(),
        Some(&dir.join("defmt.bin")),
        None,
        Duration::from_secs(10),
    )
    .unwrap();
    let hz = target.status().unwrap().cost_counter_hz;

    let (mut steps, mut compensated) = (0, 0);
    let (mut open_max, mut open_sum, mut opens) = (0.0f64, 0.0f64, 0u32);
    let mut step_max = 0.0f64;
    for (k, line) in lines.iter().enumerate() {
        let sample = sample_of(&line.row);
        // The host: the bin the sample completes stepped first, then the sample compensated.
        let expected_bin = binner
            .push(&sample)
            .unwrap()
            .map(|bin| host.step(&bin).unwrap());
        let expected_corrected = host
            .compensate(&sample)
            .ok()
            .map(|a| [a.heading_rad, a.roll_rad, a.pitch_rad]);
        let Response::Nav(reply) = target
            .request(&Request::NavSample(SampleMsg::from(&sample)))
            .unwrap()
        else {
            panic!("sample {k}: not a Nav answer");
        };
        assert_eq!(
            reply.time_s.to_bits(),
            sample.time_s.to_bits(),
            "sample {k}"
        );
        assert_eq!(
            reply.corrected_rad.map(|c| c.map(f32::to_bits)),
            expected_corrected.map(|c| c.map(f32::to_bits)),
            "sample {k}: compensation"
        );
        compensated += usize::from(expected_corrected.is_some());
        let cost = instructions(reply.cost_ticks, hz);
        match (reply.bin, expected_bin) {
            (BinOutcome::Open, None) => {
                open_max = open_max.max(cost);
                open_sum += cost;
                opens += 1;
            }
            (BinOutcome::Step(r), Some(output)) => {
                assert_eq!(r.output(), Some(output), "sample {k}: the bin's step");
                step_max = step_max.max(cost);
                steps += 1;
            }
            (got, want) => panic!("sample {k}: bin {got:?}, host {want:?}"),
        }
    }
    // A sample whose time is not after the last one's: refused with its reason, counted with the
    // rejected samples, the firmware's binner and estimator unchanged (the next bin's step, at
    // the next second, is still the host's).
    let last = sample_of(&lines[lines.len() - 1].row);
    let Response::Rejected(r) = target
        .request(&Request::NavSample(SampleMsg::from(&last)))
        .unwrap()
    else {
        panic!("a repeated time was not refused");
    };
    assert_eq!(r.error(), Some(SampleError::TimeNotIncreasing));
    assert_eq!(r.counters.rejected_samples_total(), 1);
    let mut next = last;
    next.time_s += 1.0;
    let expected = binner
        .push(&next)
        .unwrap()
        .map(|bin| host.step(&bin).unwrap());
    let Response::Nav(reply) = target
        .request(&Request::NavSample(SampleMsg::from(&next)))
        .unwrap()
    else {
        panic!("not a Nav answer after the refused sample");
    };
    let BinOutcome::Step(r) = reply.bin else {
        panic!("the last bin was not stepped: {:?}", reply.bin);
    };
    assert_eq!(r.output(), expected);
    drop(target);
    // One step a second (the first bin completes at 1 s); the first estimate comes at 1.25
    // periods of the window, 105 s in, and every sample from then on is compensated with it.
    assert_eq!(steps, 149);
    assert!(compensated >= 4_000, "{compensated} samples compensated");
    println!(
        "mps2-an386: 100 Hz navigation samples: without a bin's step max {open_max:.0}, mean {:.0} instructions; with a bin's step max {step_max:.0} ({steps} bins, {compensated} samples compensated)",
        open_sum / f64::from(opens)
    );
    // A navigation sample that completes no bin costs its binning (double-precision arithmetic in
    // software on the Cortex-M4F) and its compensation: within a step's budget; one that completes
    // a bin adds the bin's step, within two. At 200 Hz that is at most 1.2 million instructions a
    // second, under 1 % of the STM32F405's 168 MHz.
    assert!(
        open_max <= STEP_BUDGET_INSTRUCTIONS,
        "{open_max} instructions"
    );
    assert!(
        step_max <= 2.0 * STEP_BUDGET_INSTRUCTIONS,
        "{step_max} instructions"
    );
}
