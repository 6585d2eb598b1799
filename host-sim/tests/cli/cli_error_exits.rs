//! Every subcommand through every error path it reaches without QEMU, each run under a deadline:
//! a run that has not ended by then is killed and fails the test. Each ends with the exit status
//! `host-sim --help` documents (0 done, 1 error, 2 bad command line, 3 no row readable, 4 no
//! estimate) and says why on standard error.
//!
//! The logs refused after their first rows are longer than the estimator's read-ahead holds (4
//! batches of 4096 rows waiting, one being read), so that its reader thread is still reading when
//! the refusal comes: the runs that used to hang.

use crate::common::path_str;
use rand::{Rng, SeedableRng};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Far longer than any run here takes (the longest, the 1 s a silent firmware is given to answer):
/// a run still going then hangs.
const DEADLINE: Duration = Duration::from_secs(60);

/// Rows of the long logs: more than the read-ahead's 5 batches of 4096 rows.
const LONG_ROWS: u32 = 30_000;

/// What the binary is given on standard input.
enum Input {
    /// Nothing (`/dev/null`).
    Nothing,
    /// These bytes, then the pipe is closed.
    Bytes(Vec<u8>),
    /// These bytes, then the pipe is held open, nothing more written, until the run ends.
    BytesHeldOpen(Vec<u8>),
}

/// How a run ended.
struct Ended {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Reads all of a pipe on a thread of its own.
fn drain(mut pipe: impl Read + Send + 'static) -> std::thread::JoinHandle<String> {
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        let _ = pipe.read_to_end(&mut bytes);
        String::from_utf8_lossy(&bytes).into_owned()
    })
}

/// Runs the binary in `dir` with `args`, `env` and `input`; kills it and fails the test if it has
/// not ended within [`DEADLINE`].
fn run_in(dir: &Path, args: &[&str], env: &[(&str, &str)], input: Input) -> Ended {
    let (bytes, hold) = match input {
        Input::Nothing => (None, false),
        Input::Bytes(b) => (Some(b), false),
        Input::BytesHeldOpen(b) => (Some(b), true),
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(dir)
        .stdin(if bytes.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = drain(child.stdout.take().unwrap());
    let stderr = drain(child.stderr.take().unwrap());
    // The writer gives the pipe back to be held open; a write that fails (the run stopped
    // reading and ended) is no matter.
    let feeder = child.stdin.take().zip(bytes).map(|(mut pipe, bytes)| {
        std::thread::spawn(move || {
            let _ = pipe.write_all(&bytes);
            hold.then_some(pipe)
        })
    });
    let deadline = Instant::now() + DEADLINE;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    drop(feeder.map(|f| f.join().unwrap()));
    let (stdout, stderr) = (stdout.join().unwrap(), stderr.join().unwrap());
    let Some(status) = status else {
        panic!(
            "host-sim {} did not end within {} s (killed); standard error: {stderr}",
            args.join(" "),
            DEADLINE.as_secs()
        );
    };
    Ended {
        code: status.code(),
        stdout,
        stderr,
    }
}

/// [`run_in`] with nothing on standard input and no other environment.
fn run(dir: &Path, args: &[&str]) -> Ended {
    run_in(dir, args, &[], Input::Nothing)
}

/// Requires that a run ended with `code` and said why on standard error: for 1 and 3 its last
/// line is `error: ...` (after any warnings), for 4 `no estimate: ...`, for 2 clap's usage error
/// starts with `error: `; the message holds every one of `needles`; no panic.
fn expect(what: &str, ended: &Ended, code: i32, needles: &[&str]) {
    let stderr = &ended.stderr;
    assert_eq!(
        ended.code,
        Some(code),
        "{what}: exit status (a panic is 101)\nstderr: {stderr}\nstdout: {}",
        ended.stdout
    );
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    let told = match code {
        2 => stderr.lines().next().unwrap_or_default(),
        _ => stderr.trim_end().lines().last().unwrap_or_default(),
    };
    let start = if code == 4 {
        "no estimate: "
    } else {
        "error: "
    };
    assert!(
        told.starts_with(start),
        "{what}: {told:?} should start with {start:?}; stderr: {stderr}"
    );
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "{what}: no {needle:?} in: {stderr}"
        );
    }
}

/// A fresh temporary directory, removed when dropped.
fn temp() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("host-sim-error-exits-")
        .tempdir()
        .unwrap()
}

/// A sea log of `rows` rows at 1 s in `dir`, read back as text.
fn sea_log(dir: &Path, name: &str, rows: u32) -> (PathBuf, String) {
    let log = dir.join(name);
    let rows = rows.to_string();
    let args = [
        "generate",
        "--scenario",
        "sea",
        "--duration",
        &rows,
        "--out",
        path_str(&log),
    ];
    expect_ok(&run(dir, &args), "generate");
    let text = std::fs::read_to_string(&log).unwrap();
    (log, text)
}

fn expect_ok(ended: &Ended, what: &str) {
    assert_eq!(ended.code, Some(0), "{what}: {}", ended.stderr);
}

/// `text` with each row's time stamp changed by `f` (the header kept).
fn restamp(text: &str, mut f: impl FnMut(f64) -> f64) -> String {
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.lines().enumerate() {
        match line.split_once(',') {
            Some((t, rest)) if i > 0 => {
                out.push_str(&format!("{},{rest}\n", f(t.parse().unwrap())));
            }
            _ => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    out
}

/// The sea log stamped at twice its rate (steps of 0.5 s), which a pinned 1 s interval refuses
/// after the first steps: their median is below 0.6 of it (stamps jittered by up to 0.45 s
/// either way are accepted).
fn twice_the_rate(text: &str) -> String {
    restamp(text, |t| 0.5 * t)
}

/// `text` gzip-compressed.
fn gzip(text: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(text).unwrap();
    enc.finish().unwrap()
}

/// The header and the first `rows` rows of a log.
fn first_rows(text: &str, rows: usize) -> String {
    text.lines()
        .take(rows + 1)
        .map(|l| format!("{l}\n"))
        .collect()
}

/// `command`, each of `defaults` (option, value) that `args` does not give, then `args`.
fn command_line<'a>(
    command: &[&'a str],
    defaults: &[(&'a str, &'a str)],
    args: &[&'a str],
) -> Vec<&'a str> {
    let mut all = command.to_vec();
    for (option, value) in defaults {
        if !args.contains(option) {
            all.extend_from_slice(&[option, value]);
        }
    }
    all.extend_from_slice(args);
    all
}

const CONTRADICTS: &str = "--sample-interval 1 s contradicts the log's time stamps";

#[test]
fn a_log_at_twice_the_rate_refused_by_the_pinned_interval_ends_at_once_with_every_method() {
    let dir = temp();
    let (_, text) = sea_log(dir.path(), "sea.csv", LONG_ROWS);
    let log = dir.path().join("twice.csv");
    std::fs::write(&log, twice_the_rate(&text)).unwrap();
    let out = dir.path().join("e.csv");
    for method in ["windowed", "traditional", "paper"] {
        let ended = run(
            dir.path(),
            &[
                "estimate",
                path_str(&log),
                "--sample-interval",
                "1",
                "--method",
                method,
                "--out",
                path_str(&out),
            ],
        );
        expect(
            method,
            &ended,
            1,
            &[&format!("{}: {CONTRADICTS}", log.display())],
        );
    }
    assert!(!out.exists(), "nothing written");
    // Its first rows alone are refused the same way.
    let short = dir.path().join("short.csv");
    std::fs::write(&short, first_rows(&twice_the_rate(&text), 400)).unwrap();
    let args = ["estimate", path_str(&short), "--sample-interval", "1"];
    expect("400 rows", &run(dir.path(), &args), 1, &[CONTRADICTS]);
}

#[test]
fn a_long_log_at_a_rate_the_interval_refuses_ends_at_once() {
    let dir = temp();
    let (_, text) = sea_log(dir.path(), "sea.csv", LONG_ROWS);
    // 10 Hz with a pinned 1 s interval.
    let tenth = dir.path().join("10hz.csv");
    std::fs::write(&tenth, restamp(&text, |t| t * 0.1)).unwrap();
    let ended = run(
        dir.path(),
        &["estimate", path_str(&tenth), "--sample-interval", "1"],
    );
    expect(
        "10 Hz, pinned 1 s",
        &ended,
        1,
        &[CONTRADICTS, "step by 0.1 s"],
    );
    // 200 Hz: faster than a RINS logs, refused with no interval pinned.
    let fast = dir.path().join("200hz.csv");
    std::fs::write(&fast, restamp(&text, |t| t * 0.005)).unwrap();
    let ended = run(dir.path(), &["estimate", path_str(&fast)]);
    expect(
        "200 Hz",
        &ended,
        1,
        &[
            "the time stamps step by 0.005 s",
            "a RINS logs every 0.01 to 10 s",
        ],
    );
}

#[test]
fn a_long_log_refused_at_an_early_unreadable_row_with_strict_ends_at_once() {
    let dir = temp();
    let (_, text) = sea_log(dir.path(), "sea.csv", LONG_ROWS);
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Line 10 (row 9): its roll is not a number.
    let mut cells: Vec<&str> = lines[9].split(',').collect();
    cells[5] = "abc";
    lines[9] = cells.join(",");
    let log = dir.path().join("bad.csv");
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    let out = dir.path().join("e.csv");
    for method in ["windowed", "traditional"] {
        let ended = run(
            dir.path(),
            &[
                "estimate",
                path_str(&log),
                "--strict",
                "--method",
                method,
                "--out",
                path_str(&out),
            ],
        );
        let at = format!("{}:10: roll_deg: not a number: \"abc\"", log.display());
        expect(method, &ended, 1, &[&at]);
        assert_eq!(ended.stderr.lines().count(), 1, "{}", ended.stderr);
    }
    assert!(!out.exists(), "nothing written");
    // Without --strict the row is skipped, counted, and the rest estimated.
    let ended = run(
        dir.path(),
        &["estimate", path_str(&log), "--out", path_str(&out)],
    );
    expect_ok(&ended, "lenient");
    assert!(
        ended.stderr.contains(":10: roll_deg: not a number") && ended.stderr.contains("skipped"),
        "{}",
        ended.stderr
    );
    assert!(
        ended
            .stdout
            .contains("unreadable rows skipped: 1 (lines 10;"),
        "{}",
        ended.stdout
    );
}

#[test]
fn gzip_logs_refused_or_truncated_end_with_their_error() {
    let dir = temp();
    let (_, text) = sea_log(dir.path(), "sea.csv", LONG_ROWS);
    let refused = dir.path().join("twice.csv.gz");
    std::fs::write(&refused, gzip(twice_the_rate(&text).as_bytes())).unwrap();
    let ended = run(
        dir.path(),
        &["estimate", path_str(&refused), "--sample-interval", "1"],
    );
    expect("twice the rate, gzip", &ended, 1, &[CONTRADICTS]);
    let whole = gzip(text.as_bytes());
    for (name, len) in [("cut in its header", 20), ("cut halfway", whole.len() / 2)] {
        let cut = dir.path().join("cut.csv.gz");
        std::fs::write(&cut, &whole[..len]).unwrap();
        let ended = run(dir.path(), &["estimate", path_str(&cut)]);
        expect(name, &ended, 1, &["cannot read: incomplete deflate stream"]);
        assert!(
            ended
                .stderr
                .starts_with(&format!("error: {}:", cut.display())),
            "{name}: {}",
            ended.stderr
        );
    }
}

#[test]
fn standard_input_closed_early_or_held_open_ends() {
    let dir = temp();
    let (_, text) = sea_log(dir.path(), "sea.csv", LONG_ROWS);
    let stdin = |input| run_in(dir.path(), &["estimate", "-", "--out", "-"], &[], input);
    expect(
        "closed at once",
        &stdin(Input::Bytes(Vec::new())),
        1,
        &["-:1: no header"],
    );
    // Closed in the middle of a row, after 60-odd rows: the cut row is skipped, and so few rows
    // give no estimate; --strict refuses the cut row.
    let cut = text.as_bytes()[..5000].to_vec();
    let ended = stdin(Input::Bytes(cut.clone()));
    expect(
        "cut",
        &ended,
        4,
        &["short row", "rotation period not yet detected"],
    );
    assert!(
        ended.stdout.starts_with("time_s,"),
        "estimates written: {}",
        ended.stdout
    );
    let ended = run_in(
        dir.path(),
        &["estimate", "-", "--strict", "--out", "-"],
        &[],
        Input::Bytes(cut),
    );
    expect("cut, strict", &ended, 1, &["short row"]);
    // The log at twice the rate refused, its writer still writing, or holding the pipe open with
    // no more.
    let twice = twice_the_rate(&text);
    let pinned = ["estimate", "-", "--sample-interval", "1", "--out", "-"];
    let ended = run_in(
        dir.path(),
        &pinned,
        &[],
        Input::Bytes(twice.clone().into_bytes()),
    );
    expect(
        "twice the rate",
        &ended,
        1,
        &[&format!("standard input: {CONTRADICTS}")],
    );
    let held = first_rows(&twice, 8000).into_bytes();
    let ended = run_in(dir.path(), &pinned, &[], Input::BytesHeldOpen(held));
    expect("twice the rate, held open", &ended, 1, &[CONTRADICTS]);
}

#[test]
fn unreadable_missing_empty_and_header_only_logs_end_with_their_status() {
    let dir = temp();
    let d = dir.path();
    let (log, text) = sea_log(d, "sea.csv", 2000);
    let est = |log: &Path| run(d, &["estimate", path_str(log), "--out", "e.csv"]);
    let missing = d.join("missing.csv");
    expect(
        "missing",
        &est(&missing),
        1,
        &[&format!("{}:0: cannot open: ", missing.display())],
    );
    // A directory cannot be read, whoever runs the test (root reads a file without permissions).
    let unreadable = d.join("a-directory.csv");
    std::fs::create_dir(&unreadable).unwrap();
    expect(
        "a directory",
        &est(&unreadable),
        1,
        &[&format!("{}:0: cannot read: ", unreadable.display())],
    );
    let empty = d.join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    expect("empty", &est(&empty), 1, &[":1: no header"]);
    let header = d.join("header.csv");
    std::fs::write(&header, first_rows(&text, 0)).unwrap();
    expect(
        "header only",
        &est(&header),
        3,
        &["no row of the log could be read (no rows after the header)"],
    );
    let unreadable_rows = d.join("x.csv");
    let rows: String = text
        .lines()
        .take(200)
        .enumerate()
        .map(|(i, l)| match i {
            0 => format!("{l}\n"),
            _ => format!("x{l}\n"),
        })
        .collect();
    std::fs::write(&unreadable_rows, rows).unwrap();
    expect(
        "every row unreadable",
        &est(&unreadable_rows),
        3,
        &["no row of the log could be read (199 unreadable rows; the first: "],
    );
    let garbage = d.join("garbage.csv");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let bytes: Vec<u8> = (0..5000).map(|_| rng.gen()).collect();
    std::fs::write(&garbage, bytes).unwrap();
    expect("random bytes", &est(&garbage), 1, &["bad header"]);
    assert!(!d.join("e.csv").exists(), "nothing written");
    // Outputs that cannot be written.
    let ended = run(
        d,
        &["estimate", path_str(&log), "--out", "no-such-dir/e.csv"],
    );
    expect(
        "--out in a missing directory",
        &ended,
        1,
        &["no-such-dir/e.csv:0: cannot create a temporary file in no-such-dir"],
    );
    let ended = run(d, &["estimate", path_str(&log), "--out", path_str(&log)]);
    expect("--out the log", &ended, 1, &["--out names the log itself"]);
    let ended = run(
        d,
        &["estimate", path_str(&log), "--report", path_str(&header)],
    );
    expect(
        "--report a file",
        &ended,
        1,
        &["cannot create the report directory"],
    );
}

#[test]
fn estimate_refuses_option_values_out_of_range_or_unreadable() {
    let dir = temp();
    let (log, _) = sea_log(dir.path(), "sea.csv", 200);
    let log = path_str(&log);
    for (args, code, needle) in [
        (
            vec!["--sample-interval", "0.01"],
            1,
            "--sample-interval must be between 0.1 and 10 s",
        ),
        (vec!["--sample-interval", "abc"], 2, "invalid value 'abc'"),
        (
            vec!["--rotation-period", "10"],
            1,
            "--rotation-period must be between 60 and 3600 s",
        ),
        (
            vec!["--restart-at", "nan"],
            1,
            "--restart-at needs finite times",
        ),
        (
            vec!["--traditional-sigma-deg", "0"],
            1,
            "traditional_sigma_rad = 0 must be positive",
        ),
        (
            vec!["--max-filled-gap-samples", "4"],
            1,
            "max_filled_gap_samples = 4 must be at most 3",
        ),
        (vec!["--method", "nope"], 2, "invalid value 'nope'"),
        (vec!["--bogus"], 2, "unexpected argument '--bogus'"),
    ] {
        let mut all = vec!["estimate", log];
        all.extend_from_slice(&args);
        expect(&args.join(" "), &run(dir.path(), &all), code, &[needle]);
    }
    expect(
        "no log",
        &run(dir.path(), &["estimate"]),
        2,
        &["required arguments were not provided"],
    );
    expect(
        "no command",
        &run(dir.path(), &["frobnicate"]),
        2,
        &["unrecognized subcommand"],
    );
}

#[test]
fn generate_refuses_bad_options_and_an_output_it_cannot_write() {
    let dir = temp();
    let base = ["generate", "--scenario", "paper", "--duration", "100"];
    for (args, code, needle) in [
        (
            vec!["--out", "no-such-dir/g.csv"],
            1,
            "cannot create a temporary file in no-such-dir",
        ),
        (
            vec!["--latitude", "95", "--out", "g.csv"],
            1,
            "--latitude must be inside (-90, 90)",
        ),
        (
            vec!["--errors-arcsec", "1,2", "--out", "g.csv"],
            2,
            "expected 4 comma-separated numbers",
        ),
        (
            vec!["--sample-interval", "0", "--out", "g.csv"],
            1,
            "--sample-interval must be between",
        ),
        (vec![], 2, "--out"),
    ] {
        let mut all = base.to_vec();
        all.extend_from_slice(&args);
        expect(&args.join(" "), &run(dir.path(), &all), code, &[needle]);
    }
    for (duration, code, needle) in [
        ("0", 1, "--duration must be between 1 and"),
        ("-5", 1, "--duration must be between 1 and"),
        ("abc", 2, "invalid value 'abc'"),
    ] {
        let args = [
            "generate",
            "--scenario",
            "paper",
            "--duration",
            duration,
            "--out",
            "g.csv",
        ];
        expect(duration, &run(dir.path(), &args), code, &[needle]);
    }
    let args = ["generate", "--scenario", "nope", "--out", "g.csv"];
    expect(
        "scenario",
        &run(dir.path(), &args),
        2,
        &["invalid value 'nope'"],
    );
    assert!(!dir.path().join("g.csv").exists(), "nothing written");
}

#[test]
fn run_refuses_bad_options_and_outputs_it_cannot_write() {
    let dir = temp();
    let d = dir.path();
    std::fs::write(d.join("a-file"), "").unwrap();
    // The log's place taken by a directory; then the first estimates file's.
    std::fs::create_dir_all(d.join("log-taken/paper.csv")).unwrap();
    std::fs::create_dir_all(d.join("est-taken/paper.estimates.windowed.csv")).unwrap();
    for (args, code, needle) in [
        (
            vec!["--duration", "0"],
            1,
            "--duration must be between 1 and",
        ),
        (
            vec!["--out-dir", "a-file/sub"],
            1,
            "a-file/sub:0: cannot create directory",
        ),
        (
            vec!["--out-dir", "log-taken"],
            1,
            "log-taken/paper.csv:0: cannot write",
        ),
        (
            vec!["--out-dir", "est-taken"],
            1,
            "est-taken/paper.estimates.windowed.csv:0: cannot write",
        ),
        (
            vec!["--out-dir", "out", "--report", "a-file"],
            1,
            "cannot create the report directory",
        ),
        (vec!["--scenario", "nope"], 2, "invalid value 'nope'"),
    ] {
        let all = command_line(
            &["run", "--no-plots"],
            &[
                ("--scenario", "paper"),
                ("--duration", "1000"),
                ("--out-dir", "out"),
            ],
            &args,
        );
        expect(&args.join(" "), &run(d, &all), code, &[needle]);
    }
}

#[test]
fn monte_carlo_refuses_bad_options_and_tells_a_study_without_an_estimate() {
    let dir = temp();
    for (args, code, needle) in [
        (vec!["--runs", "0"], 1, "--runs must be at least 1"),
        (
            vec!["--runs", "1", "--threads", "0"],
            1,
            "--threads must be at least 1",
        ),
        (
            vec!["--runs", "1", "--lat-range", "10,-10"],
            1,
            "--lat-range needs MIN,MAX",
        ),
        (
            vec!["--runs", "1", "--max-roll-deg", "95"],
            1,
            "--max-roll-deg must be inside (0, 90)",
        ),
        (
            vec!["--runs", "1", "--period-error", "-2"],
            1,
            "--period-error must be above -1",
        ),
        (
            vec!["--runs", "1", "--rotation-jitter-deg", "-1"],
            1,
            "noise levels must be >= 0",
        ),
        (
            vec!["--runs", "1", "--duration", "1000"],
            1,
            "ends before the table's first time",
        ),
        (
            vec!["--runs", "1", "--out", "no-such-dir/s.json"],
            1,
            "cannot create a temporary file in no-such-dir",
        ),
        (vec!["--runs", "abc"], 2, "invalid value 'abc'"),
        (vec![], 2, "--runs"),
        // A first estimate after 1.25 periods of 1800 s: none by 2000 s.
        (
            vec!["--runs", "2", "--rotation-period", "1800"],
            4,
            "no run reached an estimate by the table's times",
        ),
    ] {
        let all = command_line(
            &["monte-carlo"],
            &[("--scenario", "paper"), ("--duration", "2000")],
            &args,
        );
        expect(&args.join(" "), &run(dir.path(), &all), code, &[needle]);
    }
}

#[test]
fn compare_refuses_bad_options() {
    let dir = temp();
    for (args, code, needle) in [
        (vec!["--seeds", "0"], 1, "--seeds must be at least 1"),
        (
            vec!["--lat-range", "10,-10"],
            1,
            "--lat-range needs MIN,MAX",
        ),
        (
            vec!["--duration", "0"],
            1,
            "--duration must be between 1 and",
        ),
        (vec!["--schemes", "spiral"], 2, "spiral"),
        (vec!["--scenarios", "nope"], 2, "invalid value 'nope'"),
        (vec!["--methods", "nope"], 2, "invalid value 'nope'"),
    ] {
        let all = command_line(
            &["compare"],
            &[("--seeds", "1"), ("--scenarios", "paper")],
            &args,
        );
        expect(&args.join(" "), &run(dir.path(), &all), code, &[needle]);
    }
}

#[test]
fn flash_life_refuses_bad_options_and_a_run_without_a_save() {
    let dir = temp();
    for (args, code, needle) in [
        (vec!["--days", "0"], 1, "--days must be positive, got 0"),
        (vec!["--days", "nan"], 1, "--days must be positive, got NaN"),
        (
            vec!["--interval-s", "0.5"],
            1,
            "--interval-s must be at least 1 s",
        ),
        (
            vec!["--days", "0.0001", "--interval-s", "100000"],
            1,
            "no checkpoint was saved",
        ),
        (vec!["--days", "abc"], 2, "invalid value 'abc'"),
    ] {
        let mut all = vec!["flash-life", "--board", "mps2-an386"];
        all.extend_from_slice(&args);
        expect(&args.join(" "), &run(dir.path(), &all), code, &[needle]);
    }
    let args = ["flash-life", "--board", "nope"];
    expect(
        "board",
        &run(dir.path(), &args),
        2,
        &["invalid value 'nope'"],
    );
}

#[test]
fn stream_without_a_firmware_ends_with_its_error() {
    let dir = temp();
    let d = dir.path();
    let (log, _) = sea_log(d, "sea.csv", 200);
    let log = path_str(&log);
    let elf = d.join("firmware.elf");
    std::fs::write(&elf, "not an ELF").unwrap();
    let elf = path_str(&elf);
    let none: &[(&str, &str)] = &[];
    let no_qemu: &[(&str, &str)] = &[("QEMU_SYSTEM_ARM", "/no/such/qemu-system-arm")];
    let qemu_fails: &[(&str, &str)] = &[("QEMU_SYSTEM_ARM", "false")];
    for (args, env, code, needle) in [
        (
            vec!["missing.csv", "--qemu", elf],
            no_qemu,
            1,
            "missing.csv:0: cannot open",
        ),
        (
            vec![log, "--qemu", "missing.elf"],
            no_qemu,
            1,
            "missing.elf: no such firmware ELF",
        ),
        (
            vec![log, "--qemu", elf],
            no_qemu,
            1,
            "/no/such/qemu-system-arm not found",
        ),
        (
            vec![log, "--qemu", elf],
            qemu_fails,
            1,
            "QEMU exited (exit status: 1) before the link's socket connected",
        ),
        (
            vec![log, "--qemu", elf, "--out", log],
            no_qemu,
            1,
            "--out names the log itself",
        ),
        (
            vec![log, "--qemu", elf, "--timeout-s", "inf"],
            no_qemu,
            1,
            "--timeout-s must be above 0 and at most 86400 s, got inf",
        ),
        (
            vec![log, "--qemu", elf, "--timeout-s", "0"],
            no_qemu,
            1,
            "--timeout-s must be above 0",
        ),
        (
            vec![log, "--port", "/no/such/tty"],
            none,
            1,
            "cannot open serial port /no/such/tty",
        ),
        (vec![log, "--port", log], none, 1, "cannot open serial port"),
        (vec![log], &[], 2, "--qemu"),
        (
            vec![log, "--qemu", elf, "--port", "/dev/null"],
            none,
            2,
            "cannot be used with",
        ),
        (vec![log, "--qemu", elf, "--realtime"], &[], 2, "--push"),
        (
            vec![log, "--qemu", elf, "--push", "--window", "0"],
            none,
            2,
            "invalid value '0' for '--window <N>'",
        ),
        (
            vec![log, "--qemu", elf, "--resume", "--reset"],
            none,
            2,
            "cannot be used with",
        ),
        (
            vec![log, "--qemu", elf, "--timeout-s", "abc"],
            none,
            2,
            "invalid value 'abc'",
        ),
    ] {
        let mut all = vec!["stream"];
        all.extend_from_slice(&args);
        let ended = run_in(d, &all, env, Input::Nothing);
        expect(&args.join(" "), &ended, code, &[needle]);
    }
}

/// A pseudo-terminal: its master end, its slave end held open (so that the master reads no
/// hang-up before the run opens the slave, and one when it is dropped), and the slave's path.
#[cfg(target_os = "linux")]
fn pty() -> (std::fs::File, std::fs::File, String) {
    use std::os::fd::FromRawFd;
    use std::os::unix::fs::OpenOptionsExt;
    // SAFETY: plain libc calls on a descriptor this function owns; `name` is a buffer of the
    // length given, which ptsname_r NUL-terminates on success.
    let (master, name) = unsafe {
        let fd = libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY | libc::O_CLOEXEC);
        assert!(fd >= 0, "posix_openpt: {}", std::io::Error::last_os_error());
        let master = std::fs::File::from_raw_fd(fd);
        assert_eq!(libc::grantpt(fd), 0);
        assert_eq!(libc::unlockpt(fd), 0);
        let mut name = [0 as libc::c_char; 128];
        assert_eq!(libc::ptsname_r(fd, name.as_mut_ptr(), name.len()), 0);
        let name = std::ffi::CStr::from_ptr(name.as_ptr());
        (master, name.to_string_lossy().into_owned())
    };
    let slave = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_NOCTTY)
        .open(&name)
        .unwrap();
    (master, slave, name)
}

/// What the firmware on the other end of the port does.
#[cfg(target_os = "linux")]
#[derive(Clone, Copy)]
enum Firmware {
    /// Reads the requests and never answers.
    Silent,
    /// Closes the port after the first request.
    Hangs,
    /// Answers the first request with a frame that is not one.
    Babbles,
    /// Answers everything as a fresh firmware would, every sample rejected.
    Answers,
}

/// Runs `firmware` on the master end of a pty until the port hangs up.
#[cfg(target_os = "linux")]
fn firmware_on(mut master: std::fs::File, firmware: Firmware) {
    use link_protocol::frame::MAX_FRAME;
    use link_protocol::{
        encode_frame, Counters, FrameAccumulator, LinkCounters, Numbered, RejectedReply, Request,
        Response, StatusReply, MAX_REQUEST_ENCODED, PROTOCOL_VERSION,
    };
    let status = StatusReply {
        protocol_version: PROTOCOL_VERSION,
        method: 0,
        counters: Counters::default(),
        accepted: 0,
        filled: 0,
        window_restarts: 0,
        estimate: None,
        cost_counter_hz: 1,
        boot_stack_peak_bytes: 0,
        stack_peak_bytes: 0,
        stack_size_bytes: 0,
        checkpoint_time_s: None,
        checkpoints_saved: 0,
        link: LinkCounters::default(),
        reset_cause: 0,
        clock_source: 0,
    };
    let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
    let mut buf = [0u8; 512];
    loop {
        let n = match master.read(&mut buf) {
            Ok(0) | Err(_) => return,
            Ok(n) => n,
        };
        for &b in &buf[..n] {
            let Some(Ok(request)) = rx.push_decode::<Numbered<Request>>(b) else {
                continue;
            };
            let message = match (firmware, request.message) {
                (Firmware::Silent, _) => continue,
                (Firmware::Hangs, _) => return,
                (Firmware::Babbles, _) => {
                    let _ = master.write_all(&[0x05, 0x17, 0x2a, 0x01, 0x99, 0x00]);
                    continue;
                }
                (Firmware::Answers, Request::Sample(msg)) => {
                    let error = estimator_core::SampleError::IrregularTimeStep;
                    Response::Rejected(RejectedReply::new(
                        msg.time_s,
                        &error,
                        7,
                        Counters::default(),
                    ))
                }
                (Firmware::Answers, _) => Response::Status(status),
            };
            let mut frame = [0u8; MAX_FRAME];
            let len = encode_frame(
                &Numbered {
                    seq: request.seq,
                    message,
                },
                &mut frame,
            )
            .unwrap();
            if master.write_all(&frame[..len]).is_err() {
                return;
            }
        }
    }
}

/// `host-sim stream LOG --port PTY ARGS` with `firmware` on the other end.
#[cfg(target_os = "linux")]
fn stream_through(dir: &Path, log: &Path, firmware: Firmware, args: &[&str]) -> Ended {
    let (master, slave, name) = pty();
    let firmware = std::thread::spawn(move || firmware_on(master, firmware));
    let mut all = vec!["stream", path_str(log), "--port", &name, "--timeout-s", "1"];
    all.extend_from_slice(args);
    let ended = run(dir, &all);
    // The port hung up: the firmware's thread ends.
    drop(slave);
    firmware.join().unwrap();
    ended
}

#[cfg(target_os = "linux")]
#[test]
fn stream_through_a_silent_closed_or_babbling_port_ends_with_its_error() {
    let dir = temp();
    let (log, _) = sea_log(dir.path(), "sea.csv", 200);
    for (firmware, what, needle) in [
        (
            Firmware::Silent,
            "silent",
            "no response from the firmware (read timed out)",
        ),
        // A port that closes is told by the read or by the write that meets it first
        // ("... from the firmware's port: ..." or "cannot write to the firmware's port: ..."):
        // which one is a matter of timing, both name the port.
        (Firmware::Hangs, "closed", "the firmware's port: "),
        (Firmware::Babbles, "babbling", "bad frame from the firmware"),
    ] {
        let ended = stream_through(dir.path(), &log, firmware, &["--out", "e.csv"]);
        expect(what, &ended, 1, &[needle]);
    }
    assert!(!dir.path().join("e.csv").exists(), "nothing written");
}

#[cfg(target_os = "linux")]
#[test]
fn stream_refusing_a_log_after_its_first_rows_ends_with_its_error() {
    let dir = temp();
    let (_, text) = sea_log(dir.path(), "sea.csv", 300);
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[9] = lines[9].replace(',', ";");
    let log = dir.path().join("bad.csv");
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    for push in [false, true] {
        let mut args = vec!["--strict", "--out", "e.csv"];
        if push {
            args.push("--push");
        }
        let ended = stream_through(dir.path(), &log, Firmware::Answers, &args);
        let at = format!("{}:10: short row", log.display());
        expect(&format!("strict, push {push}"), &ended, 1, &[&at]);
    }
    assert!(!dir.path().join("e.csv").exists(), "nothing written");
    // Read to its end, every sample rejected: no estimate, the estimates written.
    let ended = stream_through(dir.path(), &log, Firmware::Answers, &["--out", "e.csv"]);
    expect(
        "lenient",
        &ended,
        4,
        &["the firmware reports no estimate at the end of the log"],
    );
    assert!(
        ended.stdout.contains("299 rows streamed"),
        "{}",
        ended.stdout
    );
    assert!(dir.path().join("e.csv").exists());
}
