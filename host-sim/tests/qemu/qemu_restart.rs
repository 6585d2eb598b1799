//! A realistic restart, on both boards, through `host-sim stream` as a user runs it: 10,000 s of a
//! sea log streamed into the firmware with `--flash-dir`; the stream ends and QEMU is killed (the
//! power cut); 200 s of rows are left out (the navigation computer kept sending while the board
//! was off); the rest of the log is streamed with `--resume`. The first answer after the restart
//! carries the estimates (the window refilling: `holding`), and at the end every error is within
//! 0.1 arcsec of an uncut run's (`host-sim estimate` on the whole log, which the firmware matches
//! bit for bit). The start-up with the restore stays within its 4 KiB of stack.

use crate::qemu_support::*;
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

fn restart(board: Board) {
    let elf = firmware_elf(board);
    let dir = scratch(&format!("restart-{}", board.name()));
    let whole = generated_log(
        &dir,
        "sea.csv",
        &["--scenario", "sea", "--duration", "11500"],
    );
    let text = std::fs::read_to_string(&whole).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let (mut before, mut after) = (vec![header], vec![header]);
    for line in lines {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        if t < 10_000.0 {
            before.push(line);
        } else if t >= 10_200.0 {
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
    host_sim(&[
        "stream",
        "--qemu",
        &s(&elf),
        "--machine",
        &machine,
        &s(&first),
        "--flash-dir",
        &s(&flash),
        "--out",
        &s(&est_before),
    ]);
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
