//! End to end through QEMU, on both boards: a scenario streamed through the firmware by
//! `host-sim stream --qemu ELF --machine M` gives an estimates CSV byte-identical to
//! `host-sim estimate` on the same log, and final estimates within 10 arcsec of the truth:
//! 10000 s through the mps2-an386 image, one sample per answer; 10000 s through the STM32F405
//! image on netduinoplus2 in push mode (`--push`: frames sent without waiting for answers, queued
//! in the firmware's receive ring, matched by their numbers: every frame answered, none lost, no
//! overrun); and a real log's shape (reciprocating rotation, 2 % of rows lost, jittered Unix time
//! stamps) through the mps2-an386 image in push mode: the rotation pattern and the interval
//! learned, the gaps filled, on the target bit for bit as on the host.

use crate::qemu_support::*;
use host_sim::estimates_csv::read_estimates;
use host_sim::log_csv::{read_truth, truth_path};
use std::time::Instant;

#[test]
fn stream_of_10000_s_through_mps2_an386_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
) {
    let dir = scratch("e2e-mps2-an386");
    let log = paper_log(&dir, 10_000);
    stream_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
        Board::Mps2An386,
        &log,
        false,
    );
}

#[test]
fn reciprocating_log_with_2_percent_loss_and_jittered_unix_stamps_pushed_through_mps2_an386_is_byte_identical(
) {
    let dir = scratch("e2e-lossy-mps2-an386");
    let log = generated_log(
        &dir,
        "reciprocating.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "12000",
            "--scheme",
            "reciprocating",
            "--rotation-period",
            "360",
            "--drop-fraction",
            "0.02",
            "--time-offset",
            "1700000000",
            "--time-jitter",
            "0.02",
        ],
    );
    stream_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
        Board::Mps2An386,
        &log,
        true,
    );
}

#[test]
fn stream_of_10000_s_pushed_through_stm32f405_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
) {
    let dir = scratch("e2e-stm32f405");
    let log = paper_log(&dir, 10_000);
    stream_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
        Board::Stm32f405,
        &log,
        true,
    );
}

/// Streams `log` (in a scratch directory, whose files the caller's guard removes) through the
/// board, one sample per answer or (`push`) without waiting for answers.
fn stream_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
    board: Board,
    log: &std::path::Path,
    push: bool,
) {
    let elf = firmware_elf(board);
    let dir = log.parent().unwrap();
    let (log_s, est_s, stream_s) = (
        log.to_str().unwrap(),
        dir.join("estimate.csv"),
        dir.join("stream.csv"),
    );
    host_sim(&["estimate", log_s, "--out", est_s.to_str().unwrap()]);
    let start = Instant::now();
    let elf_s = elf.to_str().unwrap();
    let stream_out = stream_s.to_str().unwrap();
    let mut args = vec![
        "stream",
        "--qemu",
        elf_s,
        "--machine",
        board.machine().name(),
        log_s,
        "--out",
        stream_out,
    ];
    if push {
        args.push("--push");
    }
    let out = host_sim(&args);
    let wall = start.elapsed();
    println!(
        "{out}e2e {} wall time {:.1} s",
        board.name(),
        wall.as_secs_f64()
    );
    if !push {
        // One sample at a time, the step's cost is the step's alone: the budgets of
        // `qemu_budgets` hold here too (this is mps2-an386's paper stream for them).
        assert_step_and_start_up_stack_within_budgets(board, "paper, every row", &out);
    }

    let expected = std::fs::read(&est_s).unwrap();
    let streamed = std::fs::read(&stream_s).unwrap();
    let log_rows = std::fs::read_to_string(log)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .count();
    assert_eq!(
        expected.iter().filter(|b| **b == b'\n').count(),
        log_rows,
        "header + one row per input row"
    );
    if let Some(i) = (0..expected.len().min(streamed.len())).find(|&i| expected[i] != streamed[i]) {
        let line = expected[..i].iter().filter(|b| **b == b'\n').count() + 1;
        panic!("stream and estimate differ first at line {line}");
    }
    assert_eq!(
        expected.len(),
        streamed.len(),
        "stream and estimate differ in length"
    );

    let truth = read_truth(&truth_path(log))
        .unwrap()
        .expect("generate writes the truth");
    let rows = read_estimates(&stream_s).unwrap();
    let last = rows.last().unwrap();
    let x = last.x_arcsec.expect("an estimate at the end of the run");
    for i in 0..4 {
        let err = (x[i] - truth.x_arcsec[i]).abs();
        assert!(
            err < 10.0,
            "x{} = {} arcsec, truth {} arcsec: off by {err}",
            i + 1,
            x[i],
            truth.x_arcsec[i]
        );
    }
    let (max, mean) = step_cost(&out);
    assert!(
        max >= mean && mean > 0.0,
        "step cost must be measured: {max} {mean}"
    );
    // Every frame answered, none lost, no overrun, as the summary says.
    let rows = log_rows - 1;
    assert!(
        out.lines()
            .any(|l| l == format!("frames sent {rows}, answered {rows}, lost 0, overruns 0")),
        "summary:\n{out}"
    );
    let link = out
        .lines()
        .find(|l| l.starts_with("  firmware's link: "))
        .expect("the link line");
    assert!(
        link.starts_with("  firmware's link: 0 lost frames, 0 UART overruns, 0 buffer overruns, 0 framing errors, 0 noise errors;"),
        "{link}"
    );
    if push {
        // The frames really queued in the firmware's receive ring: more than one frame waited.
        let peak: u32 = link
            .split("peak ")
            .nth(1)
            .and_then(|p| p.split(' ').next())
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            peak > 43,
            "receive buffer peak {peak} bytes: the push did not queue frames"
        );
    }
}
