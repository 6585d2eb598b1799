//! What a script running the tool relies on: exit codes (0 with an estimate, 3 when no row could
//! be read, 4 when no estimate was reached), errors printed once, outputs that fail safe (an
//! earlier good file is kept when a run fails, no temporary file is left, no input is ever an
//! output) and negative values accepted by every numeric option.

use crate::common::{host_sim, host_sim_ok, paper, path_str, temp_dir};
use std::path::Path;
use std::process::Command;

/// The names of the files in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn exit_codes_tell_an_estimate_no_readable_row_and_no_estimate_apart() {
    let dir = temp_dir("cli-exit-codes");
    let log = paper(&dir, 3000);
    let out = host_sim(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("good.csv")),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "an estimate: {}",
        String::from_utf8_lossy(&out.stderr)
    );

    // Every row unreadable: 3, the reason on standard error, no estimates file.
    let text = std::fs::read_to_string(&log).unwrap();
    let unreadable: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l}\n")
            } else {
                format!("{},x\n", l.rsplit_once(',').unwrap().0)
            }
        })
        .collect();
    let bad = dir.join("unreadable.csv");
    std::fs::write(&bad, unreadable).unwrap();
    let est = dir.join("unreadable.est.csv");
    let out = host_sim(&["estimate", path_str(&bad), "--out", path_str(&est)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("no row of the log could be read")
            && stderr.contains("pitch_deg: not a number: \"x\""),
        "{stderr}"
    );
    assert!(!est.exists(), "nothing to write");

    // 300 s: rows read, no estimate yet: 4, the reason on standard error, the estimates written.
    let short = dir.join("short.csv");
    std::fs::write(
        &short,
        text.lines().take(301).collect::<Vec<_>>().join("\n") + "\n",
    )
    .unwrap();
    let est = dir.join("short.est.csv");
    let out = host_sim(&["estimate", path_str(&short), "--out", path_str(&est)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("no estimate: "), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(&est).unwrap().lines().count(),
        301,
        "header and 300 rows"
    );

    // The codes are documented in the help.
    let help = host_sim_ok(&["estimate", "--help"]);
    for code in ["0 ", "1 ", "2 ", "3 ", "4 "] {
        assert!(
            help.contains(&format!("  {code}")),
            "exit status {code}in --help: {help}"
        );
    }
}

#[test]
fn an_error_is_printed_once() {
    let dir = temp_dir("cli-error-once");
    let log = paper(&dir, 100);
    let text = std::fs::read_to_string(&log)
        .unwrap()
        .replacen("\n10,", "\nten,", 1);
    std::fs::write(&log, text).unwrap();
    let out = host_sim(&[
        "estimate",
        path_str(&log),
        "--strict",
        "--out",
        path_str(&dir.join("e.csv")),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.matches("not a number").count(), 1, "once: {stderr}");
    assert_eq!(
        stderr.matches(&format!("{}:12:", log.display())).count(),
        1,
        "once: {stderr}"
    );
}

#[test]
fn a_failed_run_keeps_the_earlier_estimates_and_leaves_no_temporary_file() {
    let dir = temp_dir("cli-fail-safe");
    let log = paper(&dir, 2000);
    let est = dir.join("paper.estimates.csv");
    host_sim_ok(&["estimate", path_str(&log)]);
    let good = std::fs::read(&est).unwrap();
    let files = listing(&dir);
    // The same log with an unreadable row near its end, refused by --strict after most rows are written.
    let text = std::fs::read_to_string(&log)
        .unwrap()
        .replacen("\n1990,", "\n1990x,", 1);
    std::fs::write(&log, text).unwrap();
    let out = host_sim(&["estimate", path_str(&log), "--strict"]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        std::fs::read(&est).unwrap() == good,
        "the earlier estimates are kept"
    );
    assert_eq!(listing(&dir), files, "no temporary file left");
}

#[test]
fn no_input_is_ever_an_output() {
    let dir = temp_dir("cli-no-input-out");
    let log = paper(&dir, 600);
    let truth = dir.join("paper.truth.json");
    let (log_before, truth_before) = (std::fs::read(&log).unwrap(), std::fs::read(&truth).unwrap());
    for out in [
        log.clone(),
        truth.clone(),
        dir.join(".").join("paper.truth.json"),
    ] {
        let result = host_sim(&["estimate", path_str(&log), "--out", path_str(&out)]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{}: {stderr}", out.display());
        assert!(
            stderr.contains("--out names the log")
                || stderr.contains("--out names the log's truth file"),
            "{stderr}"
        );
    }
    assert!(
        std::fs::read(&log).unwrap() == log_before
            && std::fs::read(&truth).unwrap() == truth_before
    );
}

#[test]
fn negative_values_of_numeric_options_get_the_options_own_message() {
    let dir = temp_dir("cli-negative-values");
    let log = paper(&dir, 100);
    let cases: [(&[&str], &str); 6] = [
        (
            &[
                "generate",
                "--scenario",
                "paper",
                "--duration",
                "-100",
                "--out",
                "x.csv",
            ],
            "--duration must be between",
        ),
        (
            &[
                "generate",
                "--scenario",
                "paper",
                "--noise-arcsec",
                "-1",
                "--out",
                "x.csv",
            ],
            "--noise-arcsec must be >= 0",
        ),
        (
            &["estimate", path_str(&log), "--rotation-period", "-480"],
            "--rotation-period must be between",
        ),
        (
            &["estimate", path_str(&log), "--sample-interval", "-1"],
            "--sample-interval must be between",
        ),
        (
            &["estimate", path_str(&log), "--traditional-sigma-deg", "-2"],
            "traditional_sigma_rad",
        ),
        (
            &[
                "monte-carlo",
                "--scenario",
                "paper",
                "--runs",
                "1",
                "--max-roll-deg",
                "-3",
            ],
            "--max-roll-deg must be inside",
        ),
    ];
    for (args, needle) in cases {
        let out = host_sim(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains(needle) && !stderr.contains("unexpected argument"),
            "{args:?}: {stderr}"
        );
    }
}

/// `stream --defmt-log` is an output like the others: it may not name an input of the run (the
/// log, its truth file, the firmware ELF) or the estimates file, and it is written through a
/// temporary file that only a run that ends well renames over it. A run whose QEMU fails at once
/// leaves an earlier log as it was, and neither a temporary file nor QEMU's scratch directory.
#[test]
fn the_defmt_log_is_never_an_input_and_a_failed_run_keeps_the_earlier_one() {
    let dir = temp_dir("cli-defmt-log");
    let log = paper(&dir, 100);
    let elf = dir.join("firmware.elf");
    std::fs::write(&elf, b"an ELF that is never booted").unwrap();
    let out = dir.join("estimates.csv");
    let scratch = dir.join("scratch");
    std::fs::create_dir_all(&scratch).unwrap();
    let stream = |defmt_log: &Path| {
        Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(["stream", "--qemu", path_str(&elf), path_str(&log)])
            .args(["--out", path_str(&out), "--defmt-log", path_str(defmt_log)])
            .env("QEMU_SYSTEM_ARM", "/bin/false")
            .env("TMPDIR", &scratch)
            .output()
            .unwrap()
    };
    let log_before = std::fs::read(&log).unwrap();
    for (target, what) in [
        (log.clone(), "the log itself"),
        (dir.join("paper.truth.json"), "the log's truth file"),
        (elf.clone(), "the firmware ELF"),
        (out.clone(), "the estimates file"),
    ] {
        let result = stream(&target);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{what}: {stderr}");
        assert!(
            stderr.contains(&format!("--defmt-log names {what}")),
            "{stderr}"
        );
    }
    assert_eq!(std::fs::read(&log).unwrap(), log_before);

    let defmt_log = dir.join("firmware.defmt");
    std::fs::write(&defmt_log, b"the log of an earlier run").unwrap();
    let result = stream(&defmt_log);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_ne!(result.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("QEMU exited"), "{stderr}");
    assert_eq!(
        std::fs::read(&defmt_log).unwrap(),
        b"the log of an earlier run"
    );
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    assert_eq!(std::fs::read_dir(&scratch).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An output that is not a regular file (a named pipe here; `/dev/null`, a terminal) is written
/// to as it is: the estimates go through the pipe, byte for byte those of a file, and the pipe is
/// still a pipe afterwards. (A file renamed over it would replace the pipe, or, as root,
/// `/dev/null` itself.)
#[test]
fn an_output_that_is_a_pipe_is_written_through_not_replaced() {
    use std::io::Read;
    use std::os::unix::fs::FileTypeExt;
    let dir = temp_dir("out-fifo");
    let log = paper(&dir, 1500);
    let file = dir.join("est.csv");
    host_sim_ok(&["estimate", path_str(&log), "--out", path_str(&file)]);
    let fifo = dir.join("est.fifo");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success(), "mkfifo");
    // The reader: it opens the pipe (blocking until the writer does) and reads to the end.
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_end(&mut bytes)
                .unwrap();
            bytes
        })
    };
    host_sim_ok(&["estimate", path_str(&log), "--out", path_str(&fifo)]);
    let still_a_pipe = std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo();
    assert!(still_a_pipe, "the named pipe was replaced by a file");
    let through = reader.join().unwrap();
    assert_eq!(through, std::fs::read(&file).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}
