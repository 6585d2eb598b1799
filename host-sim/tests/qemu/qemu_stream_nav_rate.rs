//! `host-sim stream --nav-rate` through the firmware in QEMU.
//!
//! A 100 Hz sea log, with a repeated row and a row stamped back in time added, sent row by row as
//! `NavSample`s on mps2-an386: the estimates CSV (a row a bin the firmware stepped) and the
//! corrected-attitude CSV (a row a sample) must be, byte for byte, what the core's `Binner`,
//! `Estimator::step` and `Estimator::compensate` give the same rows on the host, written with the
//! same writers, and the estimates CSV is `host-sim estimate --bin-interval-s 1`'s but for its last
//! row (the bin the firmware leaves open); the two refused rows are reported with their lines and
//! counted, and change nothing.
//!
//! The same kind of log at 20 Hz (as many bins and estimates for a fifth of the rows) through the
//! STM32F405 image, one row at a time and pushed (`--push --window 3`, frames sent without waiting
//! for the answers): both pairs of files byte-identical to each other and to the host core's, the
//! frames really queued in the firmware's receive ring.
//!
//! With `--push --realtime` a short 20 Hz log goes at its own rate (the run takes as long as the
//! log spans), answered as the host core answers it.
//!
//! After a power cut, on mps2-an386 built with a checkpoint every 20 s of sample time: a 150 s
//! log at 20 Hz with the two refused rows pushed (the default window) up to a cut in the middle of
//! a bin, then the whole log again with `--resume`, one row at a time, which sends the rows of the
//! bins after the restored checkpoint's; both runs' files byte-identical to the host core's mirror
//! of the firmware: the same binning, steps and saves, the checkpoint restored into a fresh
//! estimator with an empty bin.

use crate::qemu_support::*;
use estimator_core::binning::Binner;
use estimator_core::{Config, Estimator, Sample};
use firmware::checkpoint_store::SaveSchedule;
use host_sim::formats::corrected_csv::CorrectedWriter;
use host_sim::formats::estimates_csv::{read_estimates, EstimatesWriter};
use host_sim::formats::log_csv::read_log;
use host_sim::formats::truth_file::{read_truth, truth_path};
use host_sim::replay::{sample_of, HostEstimator};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What the host core writes for the log's rows: the estimates CSV (a row a completed bin) and
/// the corrected-attitude CSV (a row a sample).
fn host_outputs(log: &Path) -> (Vec<u8>, Vec<u8>) {
    let mut binner = Binner::default();
    let mut host: Estimator = Estimator::new(Config::default()).unwrap();
    let mut estimates = EstimatesWriter::new(Vec::new()).unwrap();
    let mut corrected = CorrectedWriter::new(Vec::new()).unwrap();
    for line in read_log(log).unwrap() {
        let sample = sample_of(&line.row);
        match binner.push(&sample) {
            Err(e) => corrected.write_refused(sample.time_s, e.reason()).unwrap(),
            Ok(bin) => {
                if let Some(bin) = bin {
                    estimates.write_step(bin.time_s, &host.step(&bin)).unwrap();
                }
                let angles = host
                    .compensate(&sample)
                    .ok()
                    .map(|a| [a.heading_rad, a.roll_rad, a.pitch_rad]);
                corrected.write_corrected(sample.time_s, angles).unwrap();
            }
        }
    }
    (estimates.finish().unwrap(), corrected.finish().unwrap())
}

/// The first line at which two files differ, if they do.
fn first_difference(got: &[u8], want: &[u8]) -> Option<usize> {
    let (got, want) = (
        String::from_utf8_lossy(got).into_owned(),
        String::from_utf8_lossy(want).into_owned(),
    );
    let mut lines = got.lines().zip(want.lines()).enumerate();
    if let Some((i, _)) = lines.find(|(_, (g, w))| g != w) {
        return Some(i + 1);
    }
    (got.lines().count() != want.lines().count())
        .then(|| got.lines().count().min(want.lines().count()) + 1)
}

/// A generated sea log of `duration_s` (at least 61 s) at `hz` rows a second with the row of 30 s
/// repeated (its time not after the last one) and a row stamped back at 50.5 s after the row of
/// 60 s: both refused by the firmware's binner. Returns the log and the file lines of the two (the
/// header is line 1): 3,003 and 6,004 at 100 Hz.
fn log_with_two_refused_rows(dir: &Path, hz: usize, duration_s: usize) -> (PathBuf, [usize; 2]) {
    // A 60 s rotation, so that the first estimate comes (about 105 s in) within 120 s.
    let name = format!("nav-{hz}hz-{duration_s}s");
    let generated = generated_log(
        dir,
        &format!("{name}.csv"),
        &[
            "--scenario",
            "sea",
            "--duration",
            &duration_s.to_string(),
            "--sample-interval",
            &(1.0 / hz as f64).to_string(),
            "--rotation-period",
            "60",
        ],
    );
    let text = std::fs::read_to_string(&generated).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert_eq!(lines.len(), duration_s * hz + 1);
    // `lines[1 + k]` is row k, at k / hz s.
    let repeated = lines[1 + 30 * hz].clone();
    let mut back: Vec<String> = lines[1 + 60 * hz].split(',').map(String::from).collect();
    back[0] = "50.5".into();
    lines.insert(2 + 30 * hz, repeated);
    lines.insert(3 + 60 * hz, back.join(","));
    let log = dir.join(format!("{name}-refused.csv"));
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    std::fs::copy(truth_path(&generated), truth_path(&log)).unwrap();
    (log, [3 + 30 * hz, 4 + 60 * hz])
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

/// One estimates row a second at the bins' centres, the last bin (119 s) left open; an estimate
/// at the end, whose truth lies within three of its reported 1-sigma (15 s after the first
/// estimate the errors are far from learned: a 1-sigma of hundreds of arcsec on x3, x4).
fn assert_estimates_sensible(est: &Path, log: &Path) {
    let rows = read_estimates(est).unwrap();
    assert_eq!(rows.len(), 119);
    assert_eq!((rows[0].time_s, rows[118].time_s), (0.5, 118.5));
    let last = rows.last().unwrap();
    assert!(
        ["estimating", "converged"].contains(&last.status.as_str()),
        "{}",
        last.status
    );
    let (x, sigma) = (last.x_arcsec.unwrap(), last.sigma_arcsec.unwrap());
    let truth = read_truth(&truth_path(log)).unwrap().unwrap().x_arcsec;
    for i in 0..4 {
        assert!(
            (x[i] - truth[i]).abs() < 3.0 * sigma[i],
            "x{} = {} arcsec (1-sigma {}), truth {}",
            i + 1,
            x[i],
            sigma[i],
            truth[i]
        );
    }
}

/// `host-sim estimate --bin-interval-s 1` writes the same estimates CSV, and one row more: it
/// steps the last bin at the end of the log, which the firmware leaves open.
fn assert_estimate_binned_writes_the_same(dir: &Path, log: &Path, streamed: &[u8]) {
    let estimated = dir.join("estimate.csv");
    host_sim(&[
        "estimate",
        &s(log),
        "--bin-interval-s",
        "1",
        "--out",
        &s(&estimated),
    ]);
    let estimated = std::fs::read_to_string(&estimated).unwrap();
    let mut all_but_last: Vec<&str> = estimated.lines().collect();
    all_but_last.pop();
    assert_eq!(
        first_difference(streamed, (all_but_last.join("\n") + "\n").as_bytes()),
        None,
        "stream --nav-rate and estimate --bin-interval-s 1 differ at that line"
    );
}

#[test]
fn stream_nav_rate_sends_a_100_hz_log_as_navigation_samples_and_answers_as_the_host_core() {
    let board = Board::Mps2An386;
    let dir = scratch("stream-nav-rate-mps2-an386");
    let (log, refused_lines) = log_with_two_refused_rows(&dir, 100, 120);
    assert_eq!(refused_lines, [3003, 6004]);
    let (est, cor) = (dir.join("est.csv"), dir.join("corrected.csv"));
    let stdout = host_sim(&[
        "stream",
        "--qemu",
        &s(&firmware_elf(board)),
        &s(&log),
        "--nav-rate",
        "--out",
        &s(&est),
        "--corrected-out",
        &s(&cor),
        "--defmt-log",
        &s(&dir.join("defmt.bin")),
    ]);
    println!("{stdout}");

    let (want_est, want_cor) = host_outputs(&log);
    let (got_est, got_cor) = (std::fs::read(&est).unwrap(), std::fs::read(&cor).unwrap());
    assert_eq!(
        first_difference(&got_est, &want_est),
        None,
        "estimates CSV: firmware and host core differ at that line"
    );
    assert_eq!(
        first_difference(&got_cor, &want_cor),
        None,
        "corrected-attitude CSV: firmware and host core differ at that line"
    );
    assert_estimates_sensible(&est, &log);
    assert_estimate_binned_writes_the_same(&dir, &log, &got_est);

    // A row a sample, the refused ones too.
    let corrected = String::from_utf8_lossy(&got_cor);
    assert_eq!(corrected.lines().count(), 1 + 12_002);
    let compensated = corrected
        .lines()
        .filter(|l| l.ends_with(",compensated"))
        .count();
    assert!(compensated >= 1_000, "{compensated} samples compensated");
    for expected in [
        "rows streamed through QEMU mps2-an386",
        "as navigation-rate samples (NavSample)",
        "  binned by the firmware: 12002 rows averaged into 119 bins of 1 s (2 rows refused: time_not_increasing 2)",
        "  rows the firmware refused: lines 3003 (time_not_increasing), 6004 (time_not_increasing); they changed nothing",
        "  the last bin (100 rows) left open",
        &format!("  compensated: {compensated} of 12002 samples"),
        "  rejected samples: 2 (",
        "frames sent 12002, answered 12002, lost 0, overruns 0",
        "sample cost: max ",
        "with its bin's step: max ",
    ] {
        assert!(stdout.contains(expected), "{expected:?} not in:\n{stdout}");
    }
}

/// `host-sim stream --nav-rate LOG` through `board`'s image `elf` with `extra` arguments; returns
/// the estimates CSV, the corrected-attitude CSV (written in `dir` as `NAME.est.csv` and
/// `NAME.corrected.csv`) and the summary.
fn stream_nav(
    board: Board,
    elf: &Path,
    dir: &Path,
    log: &Path,
    name: &str,
    extra: &[&str],
) -> (Vec<u8>, Vec<u8>, String) {
    stream_nav_exiting(board, elf, dir, log, name, extra, 0)
}

/// [`stream_nav`], the run ending with exit status `code`.
fn stream_nav_exiting(
    board: Board,
    elf: &Path,
    dir: &Path,
    log: &Path,
    name: &str,
    extra: &[&str],
    code: i32,
) -> (Vec<u8>, Vec<u8>, String) {
    let est = dir.join(format!("{name}.est.csv"));
    let cor = dir.join(format!("{name}.corrected.csv"));
    let mut args = vec![
        "stream".to_string(),
        "--qemu".into(),
        s(elf),
        "--machine".into(),
        board.machine().name().into(),
        s(log),
        "--nav-rate".into(),
        "--out".into(),
        s(&est),
        "--corrected-out".into(),
        s(&cor),
    ];
    args.extend(extra.iter().map(|a| a.to_string()));
    let stdout = host_sim_exiting(&args.iter().map(String::as_str).collect::<Vec<_>>(), code);
    println!("{}: {name}:\n{stdout}", board.name());
    (
        std::fs::read(&est).unwrap(),
        std::fs::read(&cor).unwrap(),
        stdout,
    )
}

/// The receive buffer's peak, bytes, from the summary's `firmware's link` line, which must count
/// no fault.
fn receive_peak_without_faults(stdout: &str) -> u32 {
    let link = stdout
        .lines()
        .find(|l| l.starts_with("  firmware's link: "))
        .expect("the link line");
    assert!(
        link.starts_with("  firmware's link: 0 lost frames, 0 UART overruns, 0 buffer overruns, 0 framing errors, 0 noise errors;"),
        "{link}"
    );
    link.split("peak ")
        .nth(1)
        .and_then(|p| p.split(' ').next())
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn stm32f405_stream_nav_rate_pushed_answers_as_one_at_a_time() {
    let board = Board::Stm32f405;
    let elf = firmware_elf(board);
    let dir = scratch("stream-nav-rate-push-stm32f405");
    let (log, [repeated, back]) = log_with_two_refused_rows(&dir, 20, 120);
    let (want_est, want_cor) = host_outputs(&log);
    let (one_est, one_cor, _) = stream_nav(board, &elf, &dir, &log, "one", &[]);
    let push_args = ["--push", "--window", "3"];
    let (push_est, push_cor, stdout) = stream_nav(board, &elf, &dir, &log, "push", &push_args);
    for (what, got, want) in [
        ("one at a time: estimates CSV", &one_est, &want_est),
        ("one at a time: corrected-attitude CSV", &one_cor, &want_cor),
        ("pushed: estimates CSV", &push_est, &want_est),
        ("pushed: corrected-attitude CSV", &push_cor, &want_cor),
    ] {
        assert_eq!(
            first_difference(got, want),
            None,
            "{what}: firmware and host core differ at that line"
        );
    }
    assert_eq!((&push_est, &push_cor), (&one_est, &one_cor));
    assert_estimates_sensible(&dir.join("push.est.csv"), &log);
    let compensated = String::from_utf8_lossy(&push_cor)
        .lines()
        .filter(|l| l.ends_with(",compensated"))
        .count();
    assert!(compensated >= 200, "{compensated} samples compensated");
    for expected in [
        "  binned by the firmware: 2402 rows averaged into 119 bins of 1 s (2 rows refused: time_not_increasing 2)",
        &format!("  rows the firmware refused: lines {repeated} (time_not_increasing), {back} (time_not_increasing); they changed nothing"),
        "  the last bin (20 rows) left open",
        "frames sent 2402, answered 2402, lost 0, overruns 0",
        "with its bin's step: max ",
    ] {
        assert!(stdout.contains(expected), "{expected:?} not in:\n{stdout}");
    }
    assert_pushed_frames_queued(&stdout);
}

/// `--realtime`: a 20 Hz log of 8 s pushed at its own rate takes as long as the log spans, and
/// the firmware answers every frame as the host core does (8 s give no estimate: the run ends with
/// the exit status that says so, 4).
#[test]
fn stream_nav_rate_realtime_sends_at_the_log_s_rate_and_answers_as_the_host_core() {
    let board = Board::Mps2An386;
    let dir = scratch("stream-nav-rate-realtime");
    let log = generated_log(
        &dir,
        "nav-20hz-8s.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "8",
            "--sample-interval",
            "0.05",
        ],
    );
    let (want_est, want_cor) = host_outputs(&log);
    let started = std::time::Instant::now();
    let (got_est, got_cor, stdout) = stream_nav_exiting(
        board,
        &firmware_elf(board),
        &dir,
        &log,
        "realtime",
        &["--push", "--realtime"],
        4,
    );
    let took_s = started.elapsed().as_secs_f64();
    // The rows span 7.95 s; QEMU's start comes on top.
    assert!(
        took_s >= 7.9,
        "{took_s:.2} s: the rows were not paced at the log's rate"
    );
    assert_eq!(first_difference(&got_est, &want_est), None, "estimates CSV");
    assert_eq!(
        first_difference(&got_cor, &want_cor),
        None,
        "corrected-attitude CSV"
    );
    assert_eq!(String::from_utf8_lossy(&got_cor).lines().count(), 1 + 160);
    assert!(
        stdout.contains("frames sent 160, answered 160, lost 0, overruns 0"),
        "{stdout}"
    );
    receive_peak_without_faults(&stdout);
}

/// The frames of a push really queued in the firmware's receive ring (more than one frame waited),
/// and its link counted no fault.
fn assert_pushed_frames_queued(stdout: &str) {
    let peak = receive_peak_without_faults(stdout);
    assert!(
        peak > 43,
        "receive buffer peak {peak} bytes: the push did not queue frames"
    );
}

/// The host's mirror of the firmware's navigation-rate path: the core's binner, estimator and
/// save schedule (the 20 s build's), an image of every checkpoint saved by the time of its last
/// sample, and the two CSVs the answers give.
struct NavMirror {
    binner: Binner,
    estimator: HostEstimator,
    schedule: SaveSchedule,
    images: BTreeMap<u64, Vec<u8>>,
    estimates: EstimatesWriter<Vec<u8>>,
    corrected: CorrectedWriter<Vec<u8>>,
}

/// The checkpoint interval of [`firmware_elf_checkpoint_20s`], s.
const CHECKPOINT_20S: f64 = 20.0;

impl NavMirror {
    fn new() -> NavMirror {
        NavMirror {
            binner: Binner::default(),
            estimator: HostEstimator::new(Config::default()).unwrap(),
            schedule: SaveSchedule::new(CHECKPOINT_20S, None),
            images: BTreeMap::new(),
            estimates: EstimatesWriter::new(Vec::new()).unwrap(),
            corrected: CorrectedWriter::new(Vec::new()).unwrap(),
        }
    }

    /// What the firmware does with one navigation-rate sample (`firmware/src/app/service.rs`).
    fn push(&mut self, sample: &Sample) {
        let bin = match self.binner.push(sample) {
            Err(e) => {
                self.corrected
                    .write_refused(sample.time_s, e.reason())
                    .unwrap();
                return;
            }
            Ok(bin) => bin,
        };
        if let Some(bin) = bin {
            let result = self.estimator.step(&bin);
            self.estimates.write_step(bin.time_s, &result).unwrap();
            if let Ok(output) = result {
                if self.schedule.due(output.time_s) {
                    let mut image = vec![0u8; HostEstimator::CHECKPOINT_LEN];
                    self.estimator.checkpoint(&mut image).unwrap();
                    self.images.insert(output.time_s.to_bits(), image);
                }
            }
        }
        let angles = self
            .estimator
            .compensate(sample)
            .ok()
            .map(|a| [a.heading_rad, a.roll_rad, a.pitch_rad]);
        self.corrected
            .write_corrected(sample.time_s, angles)
            .unwrap();
    }

    /// The newest checkpoint's time, s.
    fn newest_checkpoint_s(&self) -> f64 {
        f64::from_bits(*self.images.keys().next_back().expect("a checkpoint saved"))
    }

    /// The two CSVs so far; new ones start empty.
    fn take_outputs(&mut self) -> (Vec<u8>, Vec<u8>) {
        let estimates = std::mem::replace(
            &mut self.estimates,
            EstimatesWriter::new(Vec::new()).unwrap(),
        );
        let corrected = std::mem::replace(
            &mut self.corrected,
            CorrectedWriter::new(Vec::new()).unwrap(),
        );
        (estimates.finish().unwrap(), corrected.finish().unwrap())
    }

    /// What the firmware does at boot: the checkpoint of `time_s` restored into a fresh
    /// estimator, the bin empty, the next save 20 s after the checkpoint.
    fn boot(&mut self, time_s: f64) {
        let image = self.images.get(&time_s.to_bits()).unwrap_or_else(|| {
            panic!("the firmware restored a checkpoint of {time_s} s it never saved")
        });
        self.estimator = HostEstimator::new(Config::default()).unwrap();
        self.estimator.restore(image).unwrap();
        self.binner = Binner::default();
        self.schedule = SaveSchedule::new(CHECKPOINT_20S, Some(time_s));
    }
}

/// When the power is cut, s: within the bin of 127 s, which is then open with 6 of its 20 rows.
const NAV_CUT_S: f64 = 127.3;

/// `--nav-rate --resume` after a power cut: a 150 s log at 20 Hz with two refused rows pushed up to
/// the cut (the last checkpoint that of the bin of 120 s, the bins up to 126 s stepped after it,
/// the bin of 127 s open), QEMU killed; the whole log streamed again with `--resume` into the
/// restarted firmware, which restored the checkpoint of 120.5 s: the rows of 121 s on are sent
/// (the bins after the checkpoint's, those stepped before the cut among them), so that the bin the
/// restarted firmware fills first is whole. Both runs' outputs byte-identical to the host core's
/// mirror of the firmware.
#[test]
fn stream_nav_rate_resumes_after_a_power_cut_from_the_bin_after_the_checkpoint() {
    let board = Board::Mps2An386;
    let elf = firmware_elf_checkpoint_20s();
    let dir = scratch("stream-nav-rate-resume");
    let (whole, [repeated, back]) = log_with_two_refused_rows(&dir, 20, 150);
    let text = std::fs::read_to_string(&whole).unwrap();
    let before_cut: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, l)| {
            *i == 0 || l.split(',').next().unwrap().parse::<f64>().unwrap() < NAV_CUT_S
        })
        .map(|(_, l)| l)
        .collect();
    let first = dir.join("before-cut.csv");
    std::fs::write(&first, before_cut.join("\n") + "\n").unwrap();
    let flash = dir.join("flash");
    std::fs::create_dir_all(&flash).unwrap();
    let flash_args = ["--flash-dir", &s(&flash)];

    let mut mirror = NavMirror::new();
    for line in read_log(&first).unwrap() {
        mirror.push(&sample_of(&line.row));
    }
    let (want_est, want_cor) = mirror.take_outputs();
    let checkpoint_s = mirror.newest_checkpoint_s();
    assert_eq!(checkpoint_s, 120.5, "the mirror's newest checkpoint");
    let mut args = vec!["--push"];
    args.extend_from_slice(&flash_args);
    let (est, cor, stdout) = stream_nav(board, &elf, &dir, &first, "before-cut", &args);
    for expected in [
        &format!("  rows the firmware refused: lines {repeated} (time_not_increasing), {back} (time_not_increasing); they changed nothing"),
        "  the last bin (6 rows) left open",
        "  checkpoints: 6 saved in this run, newest at 120.5 s",
        "frames sent 2548, answered 2548, lost 0, overruns 0",
    ] {
        assert!(stdout.contains(expected), "{expected:?} not in:\n{stdout}");
    }
    assert_pushed_frames_queued(&stdout);
    assert_eq!(
        first_difference(&est, &want_est),
        None,
        "estimates CSV before the cut"
    );
    assert_eq!(
        first_difference(&cor, &want_cor),
        None,
        "corrected CSV before the cut"
    );

    // QEMU was killed at the end of the stream: the power cut. The restarted firmware restores
    // the checkpoint of 120.5 s.
    let mut args = vec!["--resume"];
    args.extend_from_slice(&flash_args);
    let (est, cor, stdout) = stream_nav(board, &elf, &dir, &whole, "resumed", &args);
    for expected in [
        "resuming after the firmware's checkpoint of 120.5 s",
        "  navigation-rate samples from 121 s on: the bins after the checkpoint's",
        "frames sent 580, answered 580, lost 0, overruns 0",
        "  binned by the firmware: 580 rows averaged into 28 bins of 1 s (0 rows refused)",
    ] {
        assert!(stdout.contains(expected), "{expected:?} not in:\n{stdout}");
    }
    mirror.boot(checkpoint_s);
    let bins = Binner::default();
    for line in read_log(&whole).unwrap() {
        if bins.bin_of(line.row.time_s) > bins.bin_of(checkpoint_s) {
            mirror.push(&sample_of(&line.row));
        }
    }
    let (want_est, want_cor) = mirror.take_outputs();
    assert_eq!(
        first_difference(&est, &want_est),
        None,
        "estimates CSV resumed"
    );
    assert_eq!(
        first_difference(&cor, &want_cor),
        None,
        "corrected CSV resumed"
    );
    // The first bin after the restart is whole, at its centre, with the restored estimates.
    let rows = read_estimates(&dir.join("resumed.est.csv")).unwrap();
    assert_eq!(
        (rows[0].time_s, rows.last().unwrap().time_s),
        (121.5, 148.5)
    );
    assert!(rows[0].x_arcsec.is_some(), "no estimate after the restore");
    let corrected = String::from_utf8_lossy(&cor);
    let first_sample = corrected.lines().nth(1).unwrap();
    assert!(first_sample.starts_with("121.000000,"), "{first_sample}");
}
