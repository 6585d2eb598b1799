//! `host-sim stream`: feeds an attitude log to the firmware over its framed serial link and writes
//! the estimates CSV from the firmware's answers with the same writer as `host-sim estimate` (so
//! the two files can be compared byte for byte). By default one sample per request, each sent when
//! the last is answered; with `--push` without waiting for answers (up to a window of frames the
//! firmware's receive buffer holds, [`PushOptions`]), as fast as the link takes or, with
//! `--realtime`, at the log's own rate, as a navigation computer sends. Every request is numbered
//! (link protocol 5) and every answer matched to its request by its number; a request whose answer
//! never comes (lost on the line, or in a firmware restart) is counted as lost and its row left out
//! of the estimates. The summary ends with
//! `frames sent N, answered N, lost N, overruns N` and the firmware's link counters. With `--qemu FIRMWARE.elf` it boots the firmware in QEMU first
//! ([`qemu`]; `--machine` names the board the image was built for) and waits for the firmware's
//! `Ready` announcement before its first request; with `--port DEVICE --baud N` it talks to a board
//! over a serial port.
//!
//! At the end it prints `step cost: max N instructions, mean M instructions` (QEMU; cycles on a
//! board): the firmware times every `Estimator::step` with its cost counter ([`cost`]).
//!
//! Before streaming it reads the firmware's `Status`: a firmware that already holds an estimator
//! state (samples accepted, or a checkpoint restored from its flash) is never fed another log
//! silently. Without `--resume` (continue that log after its checkpoint) or `--reset` (the firmware
//! forgets the state and erases its checkpoints) the stream is refused. On a terminal it shows
//! its progress on standard error (rows, rate, time left).

pub mod cost;
pub mod link;
pub mod push;
pub mod qemu;

use crate::exit_status::RunEnd;
use crate::formats::binned_lines::{BinningSummary, Lines};
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{is_stdio, LogLine, LogLines, LogReader, RowFilter};
use crate::formats::output_file::{check_not_input, Input, OutputFile};
use crate::formats::time_stamps::IntervalCheck;
use crate::pipeline::{default_estimates_path, inputs_of, load_truth, log_name, truth_rows};
use crate::replay::{sample_of, GridFollower};
use crate::report::timeline::{Timeline, TimelineRow};
use crate::report::ReportBuilder;
use anyhow::{bail, Context};
use cost::{CostStats, CostUnit};
use estimator_core::{Output, RejectReason, SampleError};
use link::FirmwareLink;
use link_protocol::frame::FrameError;
use link_protocol::{
    ClockSource, Counters, Request, ResetCause, Response, SampleMsg, StatusReply, PROTOCOL_VERSION,
};
use push::{stream_log_push, PushOptions};
use qemu::{Machine, Qemu};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// `host-sim stream`.
#[derive(clap::Args, Debug)]
pub struct StreamArgs {
    /// Boot this firmware ELF in QEMU (`qemu-system-arm` or $QEMU_SYSTEM_ARM) on --machine and
    /// stream through its link serial port.
    #[arg(
        long,
        value_name = "FIRMWARE.elf",
        required_unless_present = "port",
        conflicts_with = "port"
    )]
    pub qemu: Option<PathBuf>,
    /// QEMU machine of --qemu (not used with --port): the board the firmware was built for
    /// (mps2-an386: feature board-mps2-an386, UART0; netduinoplus2: feature board-stm32f405, USART1).
    #[arg(long, value_enum, default_value_t = Machine::Mps2An386)]
    pub machine: Machine,
    /// Attitude log (CSV, plain or gzip, `-` for standard input; format: docs/log-format.md).
    #[arg(value_name = "FILE.csv")]
    pub log: PathBuf,
    /// Estimates CSV to write (default: LOG.estimates.csv beside the log, as `estimate`; `-`:
    /// standard output).
    #[arg(long, value_name = "EST.csv", allow_hyphen_values = true)]
    pub out: Option<PathBuf>,
    /// Serial device of a board running the firmware (instead of --qemu).
    #[arg(long, value_name = "DEVICE")]
    pub port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Seconds to wait for each answer before giving up (above 0, at most a day).
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub timeout_s: f64,
    /// Save the firmware's defmt log (QEMU's semihosting output; decode with `defmt-print -e ELF`),
    /// written through a temporary file renamed over FILE when the stream has run to its end (a
    /// run that fails leaves an earlier FILE as it was); never an input of the run.
    #[arg(long, value_name = "FILE")]
    pub defmt_log: Option<PathBuf>,
    /// QEMU's working directory, where the firmware keeps its flash (`rins-flash.bin`, the
    /// checkpoints) across runs (default: a fresh scratch directory, so every boot starts empty).
    #[arg(long, value_name = "DIR", requires = "qemu")]
    pub flash_dir: Option<PathBuf>,
    /// The firmware holds the state of this very log (e.g. restored after a power cut): skip the
    /// log rows up to the time of its checkpoint and continue from there.
    #[arg(long, conflicts_with = "reset")]
    pub resume: bool,
    /// Start clean: the firmware forgets any state it holds and erases its checkpoints (so that no
    /// power cut brings them back), then the whole log is streamed.
    #[arg(long)]
    pub reset: bool,
    /// Refuse the log at its first unreadable row (default: skip it, count it, report its line).
    #[arg(long)]
    pub strict: bool,
    /// Send samples without waiting for their answers (answers matched by their numbers), up to
    /// --window frames unanswered; as fast as the link takes them unless --realtime.
    #[arg(long)]
    pub push: bool,
    /// With --push: send each sample at the log's own rate (its time stamps), as a navigation
    /// computer does, instead of as fast as the link takes them.
    #[arg(long, requires = "push")]
    pub realtime: bool,
    /// With --push: most frames sent and not yet answered (default: what half the firmware's
    /// receive buffer holds, from its status; at least 1).
    #[arg(long, value_name = "N", requires = "push", value_parser = clap::value_parser!(u32).range(1..))]
    pub window: Option<u32>,
    /// Write plots and a self-contained report.html of the stream into DIR (created if missing).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Average the log's rows (any rate up to 200 Hz) into bins of S s (0.1-10) and send the
    /// firmware one sample a bin, the average stamped at the bin's centre, as `estimate
    /// --bin-interval-s` steps its estimator (docs/interface.md, "Attitude at the navigation
    /// rate"); the firmware learns the interval S from the bins' stamps.
    #[arg(long, value_name = "S")]
    pub bin_interval_s: Option<f64>,
}

/// The firmware, wherever it runs.
pub struct Target {
    /// The framed link to the firmware.
    pub link: FirmwareLink,
    /// The QEMU the firmware runs in (`None` on a board).
    pub qemu: Option<Qemu>,
    /// What a tick of the firmware's cost counter is worth.
    pub unit: CostUnit,
    /// The firmware's answer to the first `ReadStatus`.
    pub boot_status: StatusReply,
}

impl Target {
    /// Boots `elf` in QEMU on `machine`, waits for the firmware's `Ready` and checks that it answers.
    pub fn boot_qemu(
        elf: &Path,
        machine: Machine,
        defmt_log: Option<&Path>,
        flash_dir: Option<&Path>,
        timeout: Duration,
    ) -> anyhow::Result<Target> {
        let (qemu, stream) = Qemu::boot(elf, machine, defmt_log, flash_dir)?;
        let reader = stream.try_clone()?;
        // Only how often the reader thread looks whether the link is still wanted.
        reader.set_read_timeout(Some(READER_POLL))?;
        let mut link = FirmwareLink::new(Box::new(reader), Box::new(stream), timeout);
        let mut qemu = Some(qemu);
        // A serial port drops what arrives before the firmware has enabled it (QEMU's STM32 USART
        // does): nothing is sent before the firmware says it is ready.
        match link.receive() {
            Ok(Response::Ready { protocol_version }) => check_protocol(protocol_version)?,
            Ok(other) => bail!("the firmware's first frame is {other:?}, not Ready"),
            Err(e) => return Err(e.context(describe_exit(&mut qemu))),
        }
        Target::hello(link, qemu, |hz| CostUnit::QemuInstructions {
            icount_shift: qemu::ICOUNT_SHIFT,
            counter_hz: hz,
        })
    }

    /// Opens a board's serial port and checks that the firmware answers.
    pub fn open_port(device: &str, baud: u32, timeout: Duration) -> anyhow::Result<Target> {
        let port = serialport::new(device, baud)
            .timeout(timeout)
            .open()
            .with_context(|| format!("cannot open serial port {device} at {baud} baud"))?;
        let mut reader = port.try_clone().with_context(|| {
            format!("cannot open serial port {device} a second time for reading")
        })?;
        reader.set_timeout(READER_POLL)?;
        let link = FirmwareLink::new(Box::new(reader), Box::new(port), timeout);
        Target::hello(link, None, |hz| CostUnit::BoardCycles { counter_hz: hz })
    }

    /// `ReadStatus`; a `Ready` before the answer (a board that has just booted) is passed over.
    fn hello(
        mut link: FirmwareLink,
        mut qemu: Option<Qemu>,
        unit: impl Fn(u32) -> CostUnit,
    ) -> anyhow::Result<Target> {
        if let Err(e) = link.send(&Request::ReadStatus) {
            return Err(e.context(describe_exit(&mut qemu)));
        }
        let status = loop {
            match link.receive() {
                Ok(Response::Status(s)) => break s,
                Ok(Response::Ready { .. }) => continue,
                Ok(other) => bail!("the firmware answered ReadStatus with {other:?}"),
                Err(e) => return Err(e.context(describe_exit(&mut qemu))),
            }
        };
        check_protocol(status.protocol_version)?;
        Ok(Target {
            link,
            qemu,
            unit: unit(status.cost_counter_hz),
            boot_status: status,
        })
    }

    /// One request, one response (with QEMU's exit status in the error if it died).
    pub fn request(&mut self, request: &Request) -> anyhow::Result<Response> {
        self.link
            .request(request)
            .map_err(|e| e.context(describe_exit(&mut self.qemu)))
    }

    /// `ReadStatus`.
    pub fn status(&mut self) -> anyhow::Result<StatusReply> {
        match self.request(&Request::ReadStatus)? {
            Response::Status(s) => Ok(s),
            other => bail!("the firmware answered ReadStatus with {other:?}"),
        }
    }
}

/// How often the link's reader thread wakes to see whether the link is still wanted.
const READER_POLL: Duration = Duration::from_millis(500);

fn check_protocol(firmware: u8) -> anyhow::Result<()> {
    if firmware != PROTOCOL_VERSION {
        bail!("firmware speaks protocol {firmware}, host-sim speaks {PROTOCOL_VERSION}");
    }
    Ok(())
}

pub(crate) fn describe_exit(qemu: &mut Option<Qemu>) -> String {
    match qemu {
        Some(q) => match q.exited() {
            Some(status) => format!(
                "QEMU exited ({status}; 1 = firmware panic or fault, see --defmt-log); {}",
                q.stderr_tail()
            ),
            None => "QEMU is still running".to_string(),
        },
        None => "on the serial port".to_string(),
    }
}

/// One sample's answer: the core's result as the firmware computed it, and the step's cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Answer {
    /// The core's output for the sample, or why it rejected the sample.
    pub result: Result<Output, SampleError>,
    /// Ticks of the board's cost counter spent in the step.
    pub step_cost_ticks: u32,
    /// The firmware's bad frames and rejected samples since boot, by code.
    pub counters: Counters,
}

/// Sends one sample and decodes its answer; errors if the answer is not about this sample.
pub fn step_remote(target: &mut Target, msg: &SampleMsg) -> anyhow::Result<Answer> {
    let response = target.request(&Request::Sample(*msg))?;
    answer_of(msg, response)
}

/// The answer to the sample `msg` from its response; errors if it is not about this sample.
pub(crate) fn answer_of(msg: &SampleMsg, response: Response) -> anyhow::Result<Answer> {
    match response {
        Response::Step(r) => {
            if r.time_s.to_bits() != msg.time_s.to_bits() {
                bail!(
                    "answer for time {} to the sample of time {}",
                    r.time_s,
                    msg.time_s
                );
            }
            let output = r
                .output()
                .with_context(|| format!("unknown status code {}", r.status))?;
            Ok(Answer {
                result: Ok(output),
                step_cost_ticks: r.step_cost_ticks,
                counters: r.counters,
            })
        }
        Response::Rejected(r) => {
            if r.time_s.to_bits() != msg.time_s.to_bits() {
                bail!(
                    "rejection of time {} for the sample of time {}",
                    r.time_s,
                    msg.time_s
                );
            }
            let error = r
                .error()
                .with_context(|| format!("unknown rejection reason {}/{}", r.reason, r.field))?;
            Ok(Answer {
                result: Err(error),
                step_cost_ticks: r.step_cost_ticks,
                counters: r.counters,
            })
        }
        Response::Status(_) => bail!("the firmware answered a sample with a status"),
        Response::Ready { .. } => {
            bail!("the firmware restarted (it announced Ready instead of answering)")
        }
    }
}

/// What happened on the link during a stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkSummary {
    /// Sample frames sent.
    pub sent: u64,
    /// Of them, answered.
    pub answered: u64,
    /// Of them, never answered (lost on the line or in a firmware restart).
    pub lost: u64,
    /// Times the firmware announced `Ready` in the middle of the stream (it restarted).
    pub restarts: u32,
}

/// What a stream did.
#[derive(Clone, Debug)]
pub struct StreamSummary {
    /// Rows answered (and written).
    pub rows: u64,
    /// What happened on the link.
    pub link: LinkSummary,
    /// The firmware's status after each restart in the stream (reset cause, restored checkpoint).
    pub restart_status: Vec<StatusReply>,
    /// The step costs the firmware reported.
    pub cost: CostStats,
    /// The firmware's status after the last row.
    pub final_status: StatusReply,
    /// Wall-clock time the stream took.
    pub wall: Duration,
    /// Unreadable rows skipped.
    pub unreadable: RowFilter,
}

/// Whether the firmware holds an estimator state: samples accepted since its last reset, or a
/// checkpoint (restored at boot or saved since). An estimate alone, before any sample and without
/// a checkpoint, is known values the firmware starts from (set at build time, or the learned
/// errors of a checkpoint of another version): a log streamed into it starts from them, as
/// `host-sim estimate --prior-arcsec` does.
pub fn holds_state(s: &StatusReply) -> bool {
    s.accepted > 0 || s.checkpoint_time_s.is_some()
}

fn describe_state(s: &StatusReply) -> String {
    let checkpoint = match s.checkpoint_time_s {
        Some(t) => format!("a checkpoint of {t} s"),
        None => "no checkpoint".to_string(),
    };
    format!("{} samples accepted, {checkpoint}", s.accepted)
}

/// Decides, from the firmware's state and `--resume` / `--reset`, where the log starts: `Ok(Some(t))`
/// to skip the rows up to `t` s. Refuses to feed a log into a state it did not come from.
pub fn prepare_firmware(
    target: &mut Target,
    resume: bool,
    reset: bool,
    info: &mut dyn Write,
) -> anyhow::Result<Option<f64>> {
    let before = target.boot_status;
    if reset {
        let after = match target.request(&Request::Reset)? {
            Response::Status(s) => s,
            other => bail!("the firmware answered Reset with {other:?}"),
        };
        if holds_state(&after) {
            bail!(
                "the firmware still holds {} after Reset: its checkpoints were not erased (a flash error, or a firmware older than this host-sim); nothing was streamed",
                describe_state(&after)
            );
        }
        if holds_state(&before) {
            writeln!(
                info,
                "reset the firmware: it forgot {} and erased its checkpoints",
                describe_state(&before)
            )?;
        }
        target.boot_status = after;
        return Ok(None);
    }
    if !holds_state(&before) {
        if resume {
            writeln!(
                info,
                "nothing to resume (the firmware holds no state): streaming the whole log"
            )?;
        }
        return Ok(None);
    }
    if !resume {
        bail!(
            "the firmware already holds an estimator state ({}), from another stream or a checkpoint in its flash: \
             streaming this log into it would mix two logs and give wrong estimates. \
             Give --reset to start clean (the firmware forgets that state and erases its checkpoints), \
             or --resume if that state came from this very log (the rows after the checkpoint are streamed)",
            describe_state(&before)
        );
    }
    match before.checkpoint_time_s {
        Some(t) => {
            writeln!(
                info,
                "resuming after the firmware's checkpoint of {t} s ({} samples accepted)",
                before.accepted
            )?;
            Ok(Some(t))
        }
        None => {
            writeln!(
                info,
                "resuming: the firmware holds {} samples but no checkpoint; every row is streamed (rows it has seen are rejected as time_not_increasing)",
                before.accepted
            )?;
            Ok(None)
        }
    }
}

/// Progress on standard error, only when it is a terminal (rows, rate, time left).
pub(crate) struct Progress {
    pub(crate) bar: indicatif::ProgressBar,
    start: Instant,
}

impl Progress {
    /// `total_bytes`: the log's size when known (a plain file), for the time left.
    pub(crate) fn new(total_bytes: Option<u64>) -> Progress {
        let bar = if !std::io::stderr().is_terminal() {
            indicatif::ProgressBar::hidden()
        } else if let Some(n) = total_bytes {
            let bar = indicatif::ProgressBar::new(n);
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:30}] {percent:>3}% {msg}, {eta} left",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        } else {
            let bar = indicatif::ProgressBar::new_spinner();
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{elapsed_precise} {spinner} {msg}")
            {
                bar.set_style(style);
            }
            bar
        };
        Progress {
            bar,
            start: Instant::now(),
        }
    }

    pub(crate) fn update(&self, rows: u64, bytes: u64) {
        if rows.is_multiple_of(256) && !self.bar.is_hidden() {
            let rate = rows as f64 / self.start.elapsed().as_secs_f64().max(1e-9);
            self.bar.set_position(bytes);
            self.bar
                .set_message(format!("{rows} rows, {rate:.0} rows/s"));
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

/// Streams the log's rows after `resume_after_s` through the target, writing one estimates row
/// per row; `each` sees every row and its answer. Unreadable rows go through `filter` (skipped and
/// counted, or refused when strict); stamps whose interval makes no sense are refused
/// ([`IntervalCheck`]).
pub fn stream_log<L: LogLines, W: Write>(
    target: &mut Target,
    lines: &mut L,
    mut filter: RowFilter,
    resume_after_s: Option<f64>,
    writer: &mut EstimatesWriter<W>,
    total_bytes: Option<u64>,
    each: &mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
) -> anyhow::Result<StreamSummary> {
    let start = Instant::now();
    let progress = Progress::new(total_bytes);
    let mut cost = CostStats::default();
    let mut rows = 0u64;
    let mut interval_check = IntervalCheck::new(None);
    while let Some(item) = lines.next() {
        let Some(line) = filter.admit(item, &mut |e| {
            progress
                .bar
                .suspend(|| eprintln!("warning: {e} (row skipped)"));
        })?
        else {
            continue;
        };
        if resume_after_s.is_some_and(|t| line.row.time_s <= t) {
            continue;
        }
        interval_check.observe(line.row.time_s)?;
        let sample = sample_of(&line.row);
        let answer = step_remote(target, &SampleMsg::from(&sample))
            .with_context(|| format!("log line {}", line.line))?;
        cost.add(answer.step_cost_ticks);
        writer.write_step(line.row.time_s, &answer.result)?;
        each(&line, &answer.result);
        rows += 1;
        progress.update(rows, lines.bytes_read());
    }
    drop(progress);
    let final_status = target.status()?;
    Ok(StreamSummary {
        rows,
        link: LinkSummary {
            sent: rows,
            answered: rows,
            lost: 0,
            restarts: 0,
        },
        restart_status: Vec::new(),
        cost,
        final_status,
        wall: start.elapsed(),
        unreadable: filter,
    })
}

/// The longest `--timeout-s`, s: a firmware that has not answered within a day is lost.
const MAX_TIMEOUT_S: f64 = 86_400.0;

/// `--timeout-s` as a duration; refused unless above 0 and at most [`MAX_TIMEOUT_S`].
fn answer_timeout(timeout_s: f64) -> anyhow::Result<Duration> {
    anyhow::ensure!(
        timeout_s > 0.0 && timeout_s <= MAX_TIMEOUT_S,
        "--timeout-s must be above 0 and at most {MAX_TIMEOUT_S} s, got {timeout_s}"
    );
    Ok(Duration::from_secs_f64(timeout_s))
}

/// `host-sim stream`.
pub fn run(args: &StreamArgs) -> anyhow::Result<()> {
    let timeout = answer_timeout(args.timeout_s)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_estimates_path(&args.log));
    check_not_input(&out, "--out", &inputs_of(&args.log))?;
    if let Some(log) = &args.defmt_log {
        let mut inputs = inputs_of(&args.log);
        inputs.extend(args.qemu.iter().map(|elf| Input {
            path: elf.clone(),
            what: "the firmware ELF",
        }));
        inputs.push(Input {
            path: out.clone(),
            what: "the estimates file (--out)",
        });
        check_not_input(log, "--defmt-log", &inputs)?;
    }
    if let Some(dir) = &args.report {
        crate::report::pages::create_dir(dir)?;
    }
    if let Some(bin_s) = args.bin_interval_s {
        let (lo, hi) = estimator_core::binning::BIN_INTERVAL_RANGE_S;
        anyhow::ensure!(
            bin_s.is_finite() && (lo..=hi).contains(&bin_s),
            "--bin-interval-s must be between {lo} and {hi} s, got {bin_s}"
        );
    }
    let reader = LogReader::open(&args.log)?;
    // Read before the reader is wrapped: whether the log is gzip.
    let gzip_log = reader.is_gzip();
    let mut lines = Lines::new(reader, args.bin_interval_s)
        .map_err(|e| anyhow::anyhow!("invalid --bin-interval-s: {e}"))?;
    let plain_size = (!is_stdio(&args.log))
        .then(|| std::fs::metadata(&args.log).ok())
        .flatten()
        .map(|m| m.len());
    let (mut target, what) = match (&args.qemu, &args.port) {
        (Some(elf), _) => (
            Target::boot_qemu(
                elf,
                args.machine,
                args.defmt_log.as_deref(),
                args.flash_dir.as_deref(),
                timeout,
            )?,
            format!("QEMU {} ({})", args.machine, elf.display()),
        ),
        (None, Some(device)) => (
            Target::open_port(device, args.baud, timeout)?,
            format!("{device} at {} baud", args.baud),
        ),
        (None, None) => bail!("give --qemu FIRMWARE.elf or --port DEVICE"),
    };
    // The summary goes where the estimates do not.
    let mut info: Box<dyn Write> = if is_stdio(&out) {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout().lock())
    };
    let resume_after_s = prepare_firmware(&mut target, args.resume, args.reset, &mut info)?;
    let mut writer = EstimatesWriter::new(OutputFile::create(&out)?)
        .with_context(|| format!("{}:0: cannot write", out.display()))?;
    // A gzip log's size says nothing of its rows: no time left then.
    let gzip = plain_size.is_some() && gzip_log;
    let total = if gzip { None } else { plain_size };
    // The report's record of the answers: the truth beside the log, the grid from the stamps.
    let truth = args
        .report
        .as_ref()
        .and_then(|_| load_truth(&args.log, &mut |w| eprintln!("warning: {w}")));
    let mut judge = truth
        .as_ref()
        .map(|t| ReportBuilder::new(truth_rows(&t.file, t.generated.as_ref())));
    let mut grid = GridFollower::new(&estimator_core::Config::default());
    let mut timeline = args.report.as_ref().map(|_| Timeline::new());
    let mut each = |line: &LogLine, result: &Result<Output, SampleError>| {
        if let Some(tl) = timeline.as_mut() {
            let truth = judge.as_mut().and_then(|j| j.observe(&line.row, result));
            let placement = grid.follow(line.row.time_s, result);
            tl.observe(TimelineRow {
                row: &line.row,
                result,
                placement,
                counters: None,
                residuals_rad: None,
                truth,
            });
        }
    };
    let filter = RowFilter::new(args.strict);
    let summary = if args.push {
        let options = PushOptions {
            realtime: args.realtime,
            window: args.window.map_or_else(
                || PushOptions::default_window(&target.boot_status),
                |w| w as usize,
            ),
            inject: None,
        };
        stream_log_push(
            &mut target,
            &mut lines,
            filter,
            resume_after_s,
            &mut writer,
            total,
            &options,
            &mut info,
            &mut each,
        )?
    } else {
        stream_log(
            &mut target,
            &mut lines,
            filter,
            resume_after_s,
            &mut writer,
            total,
            &mut each,
        )?
    };
    if let Some(e) = lines.take_interval_error() {
        // Rows too slow for the bins (or not a RINS's rate): refused as an unbinned stream's are.
        return Err(e.into());
    }
    if summary.rows == 0 {
        // Nothing to write: an earlier estimates file stays as it was.
        return Err(RunEnd::nothing_read(
            &log_name(&args.log),
            summary.unreadable.skipped,
            summary.unreadable.first.first(),
        )
        .into());
    }
    writer
        .finish()
        .with_context(|| format!("{}:0: cannot write", out.display()))?
        .commit()?;
    if let Some(qemu) = target.qemu.take() {
        qemu.finish()?;
    }
    print_summary(
        &mut info,
        &args.log,
        &out,
        &what,
        &summary,
        lines.binning(),
        &target,
    )?;
    if let (Some(dir), Some(tl)) = (&args.report, &timeline) {
        let interval_s = grid.interval_s().unwrap_or(1.0);
        let report = judge.map(|j| j.finish(interval_s));
        let page = crate::report::pages::write_stream_report(
            dir,
            &log_name(&args.log),
            &what,
            &summary.final_status,
            report.as_ref(),
            tl,
        )?;
        writeln!(info, "report in {}", page.display())?;
    }
    info.flush()?;
    if summary.final_status.estimate.is_none() {
        return Err(RunEnd::NoEstimate {
            reason: "the firmware reports no estimate at the end of the log".into(),
        }
        .into());
    }
    Ok(())
}

fn print_summary(
    w: &mut dyn Write,
    log: &Path,
    out: &Path,
    what: &str,
    s: &StreamSummary,
    binning: Option<BinningSummary>,
    target: &Target,
) -> std::io::Result<()> {
    let st = &s.final_status;
    let out = if is_stdio(out) {
        "standard output".to_string()
    } else {
        out.display().to_string()
    };
    let log = if is_stdio(log) {
        "standard input".to_string()
    } else {
        log.display().to_string()
    };
    writeln!(
        w,
        "{log}: {} rows streamed through {what} in {:.1} s ({:.0} rows/s); estimates in {out}",
        s.rows,
        s.wall.as_secs_f64(),
        s.rows as f64 / s.wall.as_secs_f64().max(1e-9),
    )?;
    if let Some(b) = binning {
        writeln!(w, "  binned: {}", b.describe())?;
    }
    if s.unreadable.skipped > 0 {
        let lines: Vec<String> = s
            .unreadable
            .first
            .iter()
            .map(|e| e.line.to_string())
            .collect();
        let more = if s.unreadable.skipped as usize > lines.len() {
            ", ..."
        } else {
            ""
        };
        writeln!(
            w,
            "  unreadable rows skipped: {} (lines {}{more}; --strict refuses such a log)",
            s.unreadable.skipped,
            lines.join(", ")
        )?;
    }
    writeln!(
        w,
        "  firmware: {} accepted, {} filled, {} window restarts",
        st.accepted, st.filled, st.window_restarts
    )?;
    let frames: Vec<String> = FrameError::ALL
        .iter()
        .map(|kind| format!("{} {}", kind.name(), st.counters.bad_frames[*kind as usize]))
        .collect();
    writeln!(
        w,
        "  bad frames: {} ({})",
        st.counters.bad_frames_total(),
        frames.join(", ")
    )?;
    let samples: Vec<String> = RejectReason::ALL
        .iter()
        .map(|&reason| {
            format!(
                "{} {}",
                reason.name(),
                st.counters.rejected_samples[reason as usize]
            )
        })
        .collect();
    writeln!(
        w,
        "  rejected samples: {} ({})",
        st.counters.rejected_samples_total(),
        samples.join(", ")
    )?;
    writeln!(
        w,
        "  stack (painted): start-up peak {} bytes, service loop peak {} bytes, of {} bytes",
        st.boot_stack_peak_bytes, st.stack_peak_bytes, st.stack_size_bytes
    )?;
    if let Some(t) = st.checkpoint_time_s {
        writeln!(
            w,
            "  checkpoints: {} saved in this run, newest at {t} s",
            st.checkpoints_saved
        )?;
    }
    let l = &st.link;
    writeln!(
        w,
        "  firmware's link: {} lost frames, {} UART overruns, {} buffer overruns, {} framing errors, {} noise errors; receive buffer peak {} of {} bytes",
        l.lost_frames, l.uart_overruns, l.buffer_overruns, l.framing_errors, l.noise_errors, l.rx_peak_bytes, l.rx_buffer_bytes
    )?;
    let cause = ResetCause::try_from(st.reset_cause).map_or("unknown", |c| c.name());
    let clock = ClockSource::try_from(st.clock_source).map_or("unknown", |c| c.name());
    writeln!(w, "  firmware's last reset: {cause}; clock: {clock}")?;
    if s.link.restarts > 0 {
        writeln!(
            w,
            "  the firmware restarted {} times during the stream",
            s.link.restarts
        )?;
    }
    writeln!(
        w,
        "frames sent {}, answered {}, lost {}, overruns {}",
        s.link.sent,
        s.link.answered,
        s.link.lost,
        st.link.overruns()
    )?;
    writeln!(w, "{}", target.unit.summary(&s.cost))
}
