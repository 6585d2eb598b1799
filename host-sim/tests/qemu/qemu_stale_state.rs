//! A firmware's estimator state is never mixed with another log. `host-sim stream` twice into one
//! flash directory: the second run finds the first run's checkpoint and refuses (exit 1, nothing
//! written); with `--reset` it starts clean and gives estimates byte-identical to
//! `host-sim estimate`; with `--resume` it continues after the checkpoint. And a `Reset` erases the
//! checkpoints: a power cut right after it brings no state back.

use crate::qemu_support::*;
use host_sim::formats::log_csv::read_log;
use host_sim::replay::sample_of;
use host_sim::stream::{holds_state, step_remote, Target};
use link_protocol::{Request, Response, SampleMsg};
use std::process::Command;
use std::time::Duration;

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// Runs host-sim on a log too short for a first estimate: it must end with exit status 4 and say
/// so on standard error (every output written); returns stdout.
fn host_sim_no_estimate(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(
        out.status.code(),
        Some(4),
        "host-sim {args:?}:\n{stdout}\n{stderr}"
    );
    assert!(stderr.contains("no estimate: "), "{stderr}");
    stdout
}

#[test]
fn a_second_stream_into_the_same_flash_is_refused_unless_reset_or_resume() {
    let elf = firmware_elf(Board::Mps2An386);
    let dir = scratch("stale-state");
    // Shorter than the rotation period (480 s): no first estimate, one checkpoint (300 s).
    let first = paper_log(&dir, 450);
    // Another trial: other errors, other seed.
    let second = dir.join("second.csv");
    host_sim(&[
        "generate",
        "--scenario",
        "paper",
        "--seed",
        "2",
        "--duration",
        "1500",
        "--errors-arcsec",
        "-100,50,-200,120",
        "--out",
        s(&second),
    ]);
    let flash = dir.join("flash");
    std::fs::create_dir_all(&flash).unwrap();

    // 450 s: no estimate yet (exit status 4), a checkpoint saved.
    host_sim_no_estimate(&[
        "stream",
        "--qemu",
        s(&elf),
        s(&first),
        "--flash-dir",
        s(&flash),
        "--out",
        s(&dir.join("first.stream.csv")),
    ]);

    let refused_out = dir.join("refused.csv");
    let refused = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "stream",
            "--qemu",
            s(&elf),
            s(&second),
            "--flash-dir",
            s(&flash),
            "--out",
            s(&refused_out),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("already holds an estimator state")
            && stderr.contains("checkpoint of 300 s"),
        "{stderr}"
    );
    assert!(
        stderr.contains("--reset") && stderr.contains("--resume"),
        "{stderr}"
    );
    assert!(
        !refused_out.exists(),
        "a refused stream writes no estimates"
    );

    let (expected, streamed) = (
        dir.join("second.estimate.csv"),
        dir.join("second.stream.csv"),
    );
    host_sim(&["estimate", s(&second), "--out", s(&expected)]);
    let out = host_sim(&[
        "stream",
        "--qemu",
        s(&elf),
        s(&second),
        "--flash-dir",
        s(&flash),
        "--reset",
        "--out",
        s(&streamed),
    ]);
    assert!(out.contains("reset the firmware: it forgot"), "{out}");
    assert_eq!(
        std::fs::read(&expected).unwrap(),
        std::fs::read(&streamed).unwrap(),
        "--reset must give exactly `estimate`'s estimates"
    );

    // The flash now holds the second log's checkpoint (1200 s): --resume streams the rows after it.
    let resumed = dir.join("resumed.csv");
    let out = host_sim(&[
        "stream",
        "--qemu",
        s(&elf),
        s(&second),
        "--flash-dir",
        s(&flash),
        "--resume",
        "--out",
        s(&resumed),
    ]);
    assert!(
        out.contains("resuming after the firmware's checkpoint of 1200 s"),
        "{out}"
    );
    assert!(out.contains(": 299 rows streamed"), "{out}");
    // The first resumed row carries the estimate the uninterrupted run had at 1200 s (the
    // checkpoint's), while the window refills.
    let estimate = |line: &str| {
        line.split(',')
            .skip(1)
            .take(8)
            .collect::<Vec<_>>()
            .join(",")
    };
    let at_cut = std::fs::read_to_string(&expected)
        .unwrap()
        .lines()
        .nth(1 + 1200)
        .map(estimate)
        .unwrap();
    let first = std::fs::read_to_string(&resumed)
        .unwrap()
        .lines()
        .nth(1)
        .map(String::from)
        .unwrap();
    assert!(
        first.starts_with("1201.000000,") && !at_cut.starts_with(','),
        "{first}"
    );
    assert_eq!(estimate(&first), at_cut);
    assert!(first.contains(",holding,"), "{first}");
}

#[test]
fn reset_erases_the_checkpoints_so_a_power_cut_cannot_bring_the_state_back() {
    let elf = firmware_elf(Board::Mps2An386);
    let dir = scratch("reset-erases");
    let log = paper_log(&dir, 700);
    let lines = read_log(&log).unwrap();
    let flash = dir.join("flash");
    std::fs::create_dir_all(&flash).unwrap();
    let boot = || {
        Target::boot_qemu(
            &elf,
            Board::Mps2An386.machine(),
            None,
            Some(&flash),
            Duration::from_secs(10),
        )
        .unwrap()
    };

    let mut target = boot();
    assert!(
        !holds_state(&target.boot_status),
        "a fresh flash holds nothing"
    );
    for line in &lines[..650] {
        step_remote(&mut target, &SampleMsg::from(&sample_of(&line.row))).unwrap();
    }
    drop(target); // power cut
    let mut target = boot();
    assert_eq!(
        target.boot_status.checkpoint_time_s,
        Some(600.0),
        "saves at 300 and 600 s: the newest is restored"
    );
    assert!(holds_state(&target.boot_status));
    let after = match target.request(&Request::Reset).unwrap() {
        Response::Status(s) => s,
        other => panic!("Reset answered with {other:?}"),
    };
    assert_eq!(
        (after.accepted, after.checkpoint_time_s, after.estimate),
        (0, None, None)
    );
    drop(target); // power cut right after the reset's answer
    let target = boot();
    assert!(
        !holds_state(&target.boot_status),
        "the forgotten state came back: {:?}",
        target.boot_status
    );
}
