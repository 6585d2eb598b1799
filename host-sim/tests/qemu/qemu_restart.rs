//! A realistic restart, on both boards, through `host-sim stream` as a user runs it, and the
//! boards' long end-to-end streams: 20,000 s of a sea log streamed into the firmware with
//! `--flash-dir` (one sample at a time on mps2-an386, where the step and start-up stack budgets
//! are checked too; pushed on the STM32F405, frames sent without waiting for answers), its
//! estimates CSV byte-identical to `host-sim estimate`'s and within 10 arcsec of the truth; the
//! stream ends and QEMU is killed (the power cut); 200 s of rows are left out (the navigation
//! computer kept sending while the board was off); the rest of the log is streamed with
//! `--resume`. The first answer after the restart carries the estimates (the window refilling:
//! `holding`), and at the end every error is within 0.1 arcsec of an uncut run's (`host-sim
//! estimate` on the whole log, which the firmware matches bit for bit). The start-up with the
//! restore stays within its 4 KiB of stack.

use crate::qemu_support::*;
use host_sim::formats::truth_file::{read_truth, truth_path};
use std::path::Path;

/// The estimates (x1..x4 arcsec, empty while none) and status of an estimates CSV's data row.
fn row(line: &str) -> ([Option<f64>; 4], String) {
    let f: Vec<&str> = line.split(',').collect();
    (
        std::array::from_fn(|i| f[1 + i].parse().ok()),
        f[9].to_string(),
    )
}

fn data_rows(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(str::to_string)
        .collect()
}

#[test]
fn mps2_an386_restart_after_a_power_cut_and_200_s_of_lost_rows() {
    restart(Board::Mps2An386);
}

#[test]
fn stm32f405_restart_after_a_power_cut_and_200_s_of_lost_rows() {
    restart(Board::Stm32f405);
}

/// When the power is cut, seconds into the log.
const CUT_S: f64 = 20_000.0;

fn restart(board: Board) {
    let elf = firmware_elf(board);
    let dir = scratch(&format!("restart-{}", board.name()));
    let whole = generated_log(
        &dir,
        "sea.csv",
        &["--scenario", "sea", "--duration", "21500"],
    );
    let text = std::fs::read_to_string(&whole).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let (mut before, mut after) = (vec![header], vec![header]);
    for line in lines {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        if t < CUT_S {
            before.push(line);
        } else if t >= CUT_S + 200.0 {
            after.push(line);
        }
    }
    let (first, second) = (dir.join("before-cut.csv"), dir.join("after-cut.csv"));
    std::fs::write(&first, before.join("\n") + "\n").unwrap();
    std::fs::write(&second, after.join("\n") + "\n").unwrap();
    let flash = dir.join("flash");
    std::fs::create_dir_all(&flash).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let machine = board.machine().to_string();

    let uncut = dir.join("uncut.csv");
    host_sim(&["estimate", &s(&whole), "--out", &s(&uncut)]);
    let est_before = dir.join("before.estimates.csv");
    let pushed = board == Board::Stm32f405;
    let mut args = vec![
        "stream".to_string(),
        "--qemu".to_string(),
        s(&elf),
        "--machine".to_string(),
        machine.clone(),
        s(&first),
        "--flash-dir".to_string(),
        s(&flash),
        "--out".to_string(),
        s(&est_before),
    ];
    if pushed {
        args.push("--push".to_string());
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = host_sim(&args);
    println!("{}: before the cut:\n{out}", board.name());
    if !pushed {
        // One sample at a time, the step's cost is the step's alone: the budgets of
        // `qemu_budgets` hold here too (this is mps2-an386's one-sample-at-a-time stream for them).
        assert_step_and_start_up_stack_within_budgets(board, "sea, 20000 s", &out);
    }
    let truth = read_truth(&truth_path(&whole))
        .unwrap()
        .expect("generate writes the truth");
    assert_stream_is_byte_identical_to_estimate_and_within_10_arcsec_of_truth(
        board,
        &first,
        &est_before,
        &uncut,
        truth.x_arcsec,
        &out,
        pushed,
    );
    let est_after = dir.join("after.estimates.csv");
    let stdout = host_sim(&[
        "stream",
        "--qemu",
        &s(&elf),
        "--machine",
        &machine,
        &s(&second),
        "--flash-dir",
        &s(&flash),
        "--resume",
        "--out",
        &s(&est_after),
    ]);
    assert!(
        stdout.contains("resuming after the firmware's checkpoint"),
        "{stdout}"
    );
    // Making the estimator and restoring the checkpoint in place keeps the start-up stack small.
    let (boot, _, _) = stack_peaks(&stdout);
    println!(
        "{}: start-up stack {boot} bytes with a checkpoint restored",
        board.name()
    );
    assert!(
        boot <= START_UP_STACK_BUDGET_BYTES,
        "start-up stack {boot} bytes with a restore"
    );

    // The first answer after the restart carries the estimates, while the window refills.
    let after_rows = data_rows(&est_after);
    let (x, status) = row(&after_rows[0]);
    assert!(
        x.iter().all(Option::is_some),
        "the first answer after the restart has no estimate: {}",
        after_rows[0]
    );
    assert_eq!(status, "holding", "{}", after_rows[0]);
    // At the end: within 0.1 arcsec of the uncut run.
    let (cut, _) = row(after_rows.last().unwrap());
    let (reference, _) = row(data_rows(&uncut).last().unwrap());
    for i in 0..4 {
        let d = cut[i].unwrap() - reference[i].unwrap();
        println!(
            "{}: x{} {d:+.4} arcsec from the uncut run at the end",
            board.name(),
            i + 1
        );
        assert!(d.abs() <= 0.1, "x{}: {d} arcsec from the uncut run", i + 1);
    }
}
