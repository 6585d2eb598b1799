//! `commission`: a generated log, and the same log rewritten into each variant of its
//! conventions, each told for what it is (the truth: how the test rewrote it); bad input ends as
//! `estimate`'s does.
//!
//! The lengths are the shortest at which `bash scripts/commission-study.sh` (20 seeds) found every
//! verdict right with a margin: at sea 3,000 s (every wrong fit at least 25 times the right one's
//! unexplained share, the decision asks 10), on the paper scenario 2,500 s (35; and at least
//! 3 periods for the heading to tell roll-negated from pitch-negated).

use crate::common::{host_sim, path_str, temp_dir};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The variants, as `commission` names them.
const VARIANTS: [&str; 6] = [
    "rotation-reversed",
    "roll-negated",
    "pitch-negated",
    "roll-pitch-swapped",
    "platform-reversed",
    "rotation-in-radians",
];

/// A generated log of `scenario` and `duration_s` in `dir`; its text.
fn generated(dir: &Path, scenario: &str, duration_s: u32) -> String {
    let log = dir.join(format!("{scenario}.csv"));
    let out = host_sim(&[
        "generate",
        "--scenario",
        scenario,
        "--duration",
        &duration_s.to_string(),
        "--out",
        path_str(&log),
    ]);
    assert!(out.status.success(), "{out:?}");
    std::fs::read_to_string(&log).unwrap()
}

/// The log rewritten into `variant`, by its columns' names: an angle negated, roll and pitch
/// exchanged, the rotation angle in radians.
fn rewritten(text: &str, variant: &str) -> String {
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let names: Vec<&str> = header.split(',').collect();
    let col = |name: &str| names.iter().position(|n| *n == name).unwrap();
    let (rotation, platform, roll, pitch) = (
        col("rotation_deg"),
        col("platform_deg"),
        col("roll_deg"),
        col("pitch_deg"),
    );
    let mut out = format!("{header}\n");
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        let value = |cells: &[String], i: usize| cells[i].parse::<f64>().unwrap();
        match variant {
            "rotation-reversed" => cells[rotation] = (-value(&cells, rotation)).to_string(),
            "roll-negated" => cells[roll] = (-value(&cells, roll)).to_string(),
            "pitch-negated" => cells[pitch] = (-value(&cells, pitch)).to_string(),
            "roll-pitch-swapped" => cells.swap(roll, pitch),
            "platform-reversed" => cells[platform] = (-value(&cells, platform)).to_string(),
            "rotation-in-radians" => {
                cells[rotation] = value(&cells, rotation).to_radians().to_string()
            }
            other => panic!("no variant {other}"),
        }
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// Runs `commission` on `log`: its exit status, its verdict line and the whole of its output.
fn commission(log: &Path) -> (Option<i32>, String, String) {
    let out = host_sim(&["commission", path_str(log)]);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let verdict = stdout
        .lines()
        .find(|l| l.starts_with("conventions: "))
        .unwrap_or("")
        .to_string();
    let all = format!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    (out.status.code(), verdict, all)
}

/// The log as it is fits (0), and each rewritten log names its variant (5). `twins`: what a
/// log rewritten into roll-negated or pitch-negated gives (both named when the heading cannot
/// tell them apart).
fn each_variant_told(scenario: &str, duration_s: u32, twins: &dyn Fn(&str) -> String) {
    let dir = temp_dir(&format!("commission-{scenario}"));
    let text = generated(&dir, scenario, duration_s);
    let (code, verdict, all) = commission(&dir.join(format!("{scenario}.csv")));
    assert_eq!(
        (code, verdict.as_str()),
        (Some(0), "conventions: ok"),
        "{all}"
    );
    for v in VARIANTS {
        assert!(
            all.contains(&format!("| {v} | ")),
            "{v} has no row of the table:\n{all}"
        );
    }
    for variant in VARIANTS {
        let log = dir.join(format!("{variant}.csv"));
        std::fs::write(&log, rewritten(&text, variant)).unwrap();
        let (code, verdict, all) = commission(&log);
        let expected = match variant {
            "roll-negated" | "pitch-negated" => twins(variant),
            v => format!("conventions: {v}"),
        };
        assert_eq!((code, verdict), (Some(5), expected), "{variant}:\n{all}");
    }
}

/// At sea the ship's course changes swamp eq (2)'s oscillation in the heading: roll-negated and
/// pitch-negated, which roll and pitch cannot tell apart, are both named.
#[test]
fn a_sea_log_and_each_of_its_variants_are_told() {
    each_variant_told("sea", 3_000, &|_| {
        "conventions: roll-negated or pitch-negated".to_string()
    });
}

/// On the paper's scenario (a steady heading) the heading tells roll-negated from pitch-negated.
#[test]
fn a_paper_log_and_each_of_its_variants_are_told_exactly() {
    each_variant_told("paper", 2_500, &|v| format!("conventions: {v}"));
}

/// Roll and pitch both negated fit as eq (2) with x1..x4 negated: the conventions are ok by roll
/// and pitch, and the heading, which carries eq (2)'s oscillation of the true errors, says so.
#[test]
fn roll_and_pitch_both_negated_are_told_by_the_heading() {
    let dir = temp_dir("commission-both");
    let text = generated(&dir, "paper", 2_500);
    let log = dir.join("both.csv");
    let both = rewritten(&rewritten(&text, "roll-negated"), "pitch-negated");
    std::fs::write(&log, both).unwrap();
    let (code, verdict, all) = commission(&log);
    assert_eq!(
        (code, verdict.as_str()),
        (Some(0), "conventions: ok"),
        "{all}"
    );
    assert!(
        all.contains("but the heading carries the opposite of eq (2)'s heading oscillation"),
        "{all}"
    );
}

/// Too short for a period of residuals after the first estimate: undecided (4).
#[test]
fn a_log_too_short_to_tell_is_undecided() {
    let dir = temp_dir("commission-short");
    generated(&dir, "sea", 800);
    let (code, verdict, all) = commission(&dir.join("sea.csv"));
    assert_eq!(
        (code, verdict.as_str()),
        (Some(4), "conventions: undecided"),
        "{all}"
    );
}

/// Runs the binary with `input` on its standard input, which is then held open until the run
/// ends; a run not ended within 20 s fails the test.
fn held_open(args: &[&str], input: Vec<u8>) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        // The run may end before it has read everything (a broken pipe here).
        let _ = stdin.write_all(&input);
        stdin
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            panic!("host-sim {args:?} still running after 20 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    drop(writer.join());
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    (status.code(), stderr)
}

/// Bad input ends as `estimate`'s: the same exit status (1 a log that cannot be opened or is
/// refused, 3 no row readable) and the same error line; a long log refused on standard input held
/// open ends at once.
#[test]
fn bad_input_ends_as_estimate_does() {
    let dir = temp_dir("commission-bad");
    let header = "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n";
    let write = |name: &str, text: &str| -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let unreadable = write(
        "unreadable.csv",
        &format!("{header}0,x,0,40,30,0,0\n1,0,y,40,30,0,0\n"),
    );
    let empty = write("empty.csv", header);
    let bad_header = write("header.csv", "time_s,roll_deg\n0,1\n");
    let missing = dir.join("missing.csv");
    for (log, code) in [
        (&unreadable, 3),
        (&empty, 3),
        (&bad_header, 1),
        (&missing, 1),
    ] {
        let estimate = host_sim(&["estimate", path_str(log), "--out", "-"]);
        let ours = host_sim(&["commission", path_str(log)]);
        let last_line = |o: &std::process::Output| {
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("")
                .to_string()
        };
        assert_eq!(estimate.status.code(), Some(code), "{log:?}");
        assert_eq!(ours.status.code(), Some(code), "{log:?}");
        assert!(last_line(&ours).starts_with("error: "), "{log:?}");
        assert_eq!(last_line(&ours), last_line(&estimate), "{log:?}");
    }
    // --strict refuses a log at its first unreadable row.
    let text = generated(&dir, "sea", 1_200);
    let mut lines: Vec<&str> = text.lines().collect();
    lines[600] = "600,not a number,0,18,30,0,0";
    let cut = write("cut.csv", &(lines.join("\n") + "\n"));
    let strict = host_sim(&["commission", path_str(&cut), "--strict"]);
    assert_eq!(strict.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&strict.stderr).contains("cut.csv:601: rotation_deg"));
    // A log at twice the rate a pinned interval allows, on standard input held open: refused
    // after its first stamps, while the reader still has rows to read.
    let fast = dir.join("fast.csv");
    let out = host_sim(&[
        "generate",
        "--scenario",
        "sea",
        "--duration",
        "15000",
        "--sample-interval",
        "0.5",
        "--out",
        path_str(&fast),
    ]);
    assert!(out.status.success());
    let (code, stderr) = held_open(
        &["commission", "-", "--sample-interval", "1"],
        std::fs::read(&fast).unwrap(),
    );
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("--sample-interval 1 s contradicts the log's time stamps"),
        "{stderr}"
    );
}

/// The help says what is printed and every exit status.
#[test]
fn the_help_tells_the_output_and_the_exit_statuses() {
    let out = host_sim(&["commission", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "conventions: ok",
        "conventions: VARIANT",
        "residual power",
        "  0  conventions: ok",
        "  1  failed",
        "  3  no row of the log could be read",
        "  4  conventions: undecided",
        "  5  conventions: VARIANT (a variant of the log's conventions fits better than the log as it is)",
    ] {
        assert!(help.contains(needle), "{needle:?} not in:\n{help}");
    }
    // Every other command's help lists 5 too.
    let estimate = host_sim(&["estimate", "--help"]);
    assert!(String::from_utf8_lossy(&estimate.stdout).contains(
        "5  commission: a variant of the log's conventions fits better than the log as it is"
    ));
}
