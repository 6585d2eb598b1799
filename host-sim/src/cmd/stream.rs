//! `host-sim stream`: a log streamed through the firmware over its link ([`crate::stream`]), the
//! estimates CSV written from its answers, the summary of the stream and its report.

use crate::cmd::args::check_bin_interval;
use crate::cmd::summary_writer;
use crate::exit_status::RunEnd;
use crate::formats::binned_lines::{BinningSummary, Lines};
use crate::formats::corrected_csv::CorrectedWriter;
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{is_stdio, LogLine, LogLines, LogReader, RowFilter};
use crate::formats::log_paths::{default_estimates_path, inputs_of, log_name, output_name};
use crate::formats::output_file::{check_not_input, Input, OutputFile};
use crate::formats::truth_file::load_truth;
use crate::replay::records::Records;
use crate::replay::replayer::GridFollower;
use crate::report::pages::write_stream_report;
use crate::report::TruthRows;
use crate::stream::nav::{NavOutputs, NavSink};
use crate::stream::push::{stream_log_push, PushOptions};
use crate::stream::qemu::Machine;
use crate::stream::sink::{RowSink, SampleSink};
use crate::stream::{
    holds_state, prepare_firmware, stream_rows_one_at_a_time, StreamSummary, Target,
};
use anyhow::{bail, Context};
use estimator_core::binning::Binner;
use estimator_core::{Output, RejectReason, SampleError};
use link_protocol::frame::FrameError;
use link_protocol::{ClockSource, ResetCause, StatusReply};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

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
    /// log rows up to the time of its checkpoint (with --nav-rate: to the end of the checkpoint's
    /// bin) and continue from there.
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
    /// Send the log's rows (attitude at the navigation rate, 100-200 Hz) to the firmware as they
    /// come, each as a navigation-rate sample (`NavSample`): the firmware averages them into its
    /// 1 s grid, steps its estimator once a bin is complete and answers every sample with it
    /// compensated. The estimates CSV has one row per bin the firmware completed, at the bin's
    /// centre; --corrected-out writes every sample's corrected attitude. Every answer is checked
    /// against the core's binning on the host; rows the firmware refuses (a time not after the
    /// last one, a value out of range) are reported and counted. With --push the rows go without
    /// waiting for the answers (--realtime, --window as for samples). With --resume, after a
    /// restart, the rows of the bins after the firmware's checkpoint are sent: the checkpoint holds
    /// the bins up to its own, not the bin being filled, which the firmware starts empty again.
    /// Not with --bin-interval-s (that bins on the host).
    #[arg(long, conflicts_with = "bin_interval_s")]
    pub nav_rate: bool,
    /// With --nav-rate: write every sample's corrected heading, roll and pitch (deg), as the
    /// firmware answered it, to this CSV (`-`: standard output), one row a sample: about 23 MB an
    /// hour at 100 Hz (format: docs/log-format.md).
    #[arg(
        long,
        value_name = "FILE.csv",
        requires = "nav_rate",
        allow_hyphen_values = true
    )]
    pub corrected_out: Option<PathBuf>,
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

/// `host-sim stream`: boots or opens the firmware, streams the log, writes the estimates CSV from
/// its answers, prints the summary and writes the report when asked; exit status 4 when the
/// firmware reports no estimate at the end.
pub fn run(args: &StreamArgs) -> anyhow::Result<()> {
    let timeout = answer_timeout(args.timeout_s)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_estimates_path(&args.log));
    check_outputs(args, &out)?;
    let (mut lines, total) = open_log(args)?;
    let (mut target, what) = connect(args, timeout)?;
    let mut info = summary_writer(&summary_beside(args, &out));
    let resume_after_s = prepare_firmware(&mut target, args.resume, args.reset, &mut info)?;
    // What the firmware holds now is this log's (prepare_firmware refuses it otherwise).
    let resuming = args.resume && holds_state(&target.boot_status);
    let mut outputs = Outputs::create(args, out)?;
    // The report's record of the answers: the truth beside the log, the grid from the stamps.
    let truth = args
        .report
        .as_ref()
        .and_then(|_| load_truth(&args.log, &mut |w| eprintln!("warning: {w}")));
    let mut records = Records::new(
        truth.as_ref().map(TruthRows::of),
        args.report.is_some(),
        false,
    );
    let mut grid = GridFollower::new(&estimator_core::Config::default());
    let summary = stream_rows(
        args,
        &mut target,
        &mut lines,
        resume_after_s,
        resuming,
        &mut outputs,
        total,
        &mut info,
        &mut |line: &LogLine, result: &Result<Output, SampleError>| {
            let placement = grid.follow(line.row.time_s, result);
            records.observe(&line.row, result, placement, None, None);
        },
    )?;
    check_rows_streamed(&args.log, &mut lines, &summary)?;
    let written = outputs.commit()?;
    if let Some(qemu) = target.qemu.take() {
        qemu.finish()?;
    }
    let recorded = records.finish(grid.interval_s().unwrap_or(1.0));
    let log = log_name(&args.log);
    let sent_as = if args.nav_rate {
        " as navigation-rate samples (NavSample)"
    } else {
        ""
    };
    let head = format!(
        "{log}: {} rows streamed through {what}{sent_as}",
        summary.rows
    );
    print_summary(
        &mut info,
        &head,
        &written,
        &summary,
        lines.binning(),
        &target,
    )?;
    if let (Some(dir), Some(timeline)) = (&args.report, &recorded.timeline) {
        let status = &summary.final_status;
        let report = recorded.report.as_ref();
        let page = write_stream_report(dir, &log, &what, status, report, timeline)?;
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

/// Where the summary goes: standard error when an output is standard output (`-`), else
/// standard output ([`summary_writer`] of the path returned).
fn summary_beside(args: &StreamArgs, out: &Path) -> PathBuf {
    match &args.corrected_out {
        Some(c) if is_stdio(c) => c.clone(),
        _ => out.to_path_buf(),
    }
}

/// The stream's output files, written as the answers come: the estimates CSV and, with
/// `--nav-rate --corrected-out`, the corrected-attitude CSV. Each goes through a temporary file
/// renamed over it by [`Outputs::commit`] (dropped uncommitted, it is deleted).
struct Outputs {
    out: PathBuf,
    estimates: EstimatesWriter<OutputFile>,
    corrected: Option<(PathBuf, CorrectedWriter<OutputFile>)>,
}

/// The paths of the outputs written, for the summary.
struct Written {
    estimates: PathBuf,
    corrected: Option<PathBuf>,
}

impl Outputs {
    fn create(args: &StreamArgs, out: PathBuf) -> anyhow::Result<Outputs> {
        let cannot = |p: &Path| format!("{}:0: cannot write", p.display());
        let estimates =
            EstimatesWriter::new(OutputFile::create(&out)?).with_context(|| cannot(&out))?;
        let corrected = match &args.corrected_out {
            Some(path) => {
                let w = CorrectedWriter::new(OutputFile::create(path)?)
                    .with_context(|| cannot(path))?;
                Some((path.clone(), w))
            }
            None => None,
        };
        Ok(Outputs {
            out,
            estimates,
            corrected,
        })
    }

    /// Every output complete: flushed and renamed over its target.
    fn commit(self) -> anyhow::Result<Written> {
        let cannot = |p: &Path| format!("{}:0: cannot write", p.display());
        self.estimates
            .finish()
            .with_context(|| cannot(&self.out))?
            .commit()?;
        let corrected = match self.corrected {
            Some((path, w)) => {
                w.finish().with_context(|| cannot(&path))?.commit()?;
                Some(path)
            }
            None => None,
        };
        Ok(Written {
            estimates: self.out,
            corrected,
        })
    }
}

/// A log's rows as the stream reads them, binned or not.
type StreamLines = Lines<LogReader<Box<dyn Read + Send>>>;

/// The log's rows, binned when asked (`--bin-interval-s`, checked), and its size when it tells
/// the time left (a plain file).
fn open_log(args: &StreamArgs) -> anyhow::Result<(StreamLines, Option<u64>)> {
    if let Some(bin_s) = args.bin_interval_s {
        check_bin_interval(bin_s)?;
    }
    let reader = LogReader::open(&args.log)?;
    // A gzip log's size says nothing of its rows: no time left then.
    let total = (!is_stdio(&args.log) && !reader.is_gzip())
        .then(|| std::fs::metadata(&args.log).ok())
        .flatten()
        .map(|m| m.len());
    let lines = Lines::new(reader, args.bin_interval_s)
        .map_err(|e| anyhow::anyhow!("invalid --bin-interval-s: {e}"))?;
    Ok((lines, total))
}

/// Refuses a stream that read no row, or whose rows were too slow for the bins (or not at a
/// RINS's rate: refused as an unbinned stream's are); nothing is written then, and an earlier
/// estimates file stays as it was.
fn check_rows_streamed<I>(
    log: &Path,
    lines: &mut Lines<I>,
    summary: &StreamSummary,
) -> anyhow::Result<()> {
    if let Some(e) = lines.take_interval_error() {
        return Err(e.into());
    }
    if summary.rows == 0 {
        return Err(RunEnd::nothing_read(
            &log_name(log),
            summary.unreadable.skipped,
            summary.unreadable.first.first(),
        )
        .into());
    }
    Ok(())
}

/// Refuses outputs that are inputs of the run, or another output (the estimates file, the
/// corrected-attitude file, the defmt log), and creates the report directory.
fn check_outputs(args: &StreamArgs, out: &Path) -> anyhow::Result<()> {
    check_not_input(out, "--out", &inputs_of(&args.log))?;
    let mut inputs = inputs_of(&args.log);
    inputs.extend(args.qemu.iter().map(|elf| Input {
        path: elf.clone(),
        what: "the firmware ELF",
    }));
    inputs.push(Input {
        path: out.to_path_buf(),
        what: "the estimates file (--out)",
    });
    if let Some(corrected) = &args.corrected_out {
        if is_stdio(corrected) && is_stdio(out) {
            bail!("--out and --corrected-out cannot both be standard output (-)");
        }
        check_not_input(corrected, "--corrected-out", &inputs)?;
        inputs.push(Input {
            path: corrected.clone(),
            what: "the corrected-attitude file (--corrected-out)",
        });
    }
    if let Some(log) = &args.defmt_log {
        check_not_input(log, "--defmt-log", &inputs)?;
    }
    if let Some(dir) = &args.report {
        crate::report::pages::create_dir(dir)?;
    }
    Ok(())
}

/// Boots the firmware in QEMU or opens the board's serial port; returns the target and what it
/// is, for the summary.
fn connect(args: &StreamArgs, timeout: Duration) -> anyhow::Result<(Target, String)> {
    Ok(match (&args.qemu, &args.port) {
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
    })
}

/// Streams the log's rows after `resume_after_s` through the target, as samples or, with
/// `--nav-rate`, as navigation-rate samples, each sent when the last is answered or, with
/// `--push`, without waiting for the answers; `resuming`: `--resume` into a firmware that holds a
/// state. `each` sees every row (with `--nav-rate`, every bin) and its answer.
#[allow(clippy::too_many_arguments)]
fn stream_rows<L: LogLines>(
    args: &StreamArgs,
    target: &mut Target,
    lines: &mut L,
    resume_after_s: Option<f64>,
    resuming: bool,
    outputs: &mut Outputs,
    total: Option<u64>,
    info: &mut dyn Write,
    each: &mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
) -> anyhow::Result<StreamSummary> {
    let writer = &mut outputs.estimates;
    if args.nav_rate {
        let out = NavOutputs {
            estimates: writer,
            corrected: outputs.corrected.as_mut().map(|(_, w)| w),
            each,
        };
        let mut sink = NavSink::new(out, resuming);
        if let Some(t) = resume_after_s {
            let bins = Binner::default();
            let from_s = (bins.bin_of(t) + 1.0) * bins.interval_s();
            writeln!(
                info,
                "  navigation-rate samples from {from_s} s on: the bins after the checkpoint's (the bin being filled is not in a checkpoint)"
            )?;
        }
        return send_rows(args, target, lines, resume_after_s, &mut sink, total, info);
    }
    // Pushed samples go with their stamps as they are: the firmware refuses what its core cannot step.
    let mut sink = if args.push {
        SampleSink::unchecked(writer, each)
    } else {
        SampleSink::checked(writer, each)
    };
    send_rows(args, target, lines, resume_after_s, &mut sink, total, info)
}

/// Sends the rows as `sink` says, one at a time or, with `--push`, without waiting.
fn send_rows<L: LogLines, S: RowSink>(
    args: &StreamArgs,
    target: &mut Target,
    lines: &mut L,
    resume_after_s: Option<f64>,
    sink: &mut S,
    total: Option<u64>,
    info: &mut dyn Write,
) -> anyhow::Result<StreamSummary> {
    let filter = RowFilter::new(args.strict);
    if !args.push {
        return stream_rows_one_at_a_time(target, lines, filter, resume_after_s, sink, total);
    }
    let options = PushOptions {
        realtime: args.realtime,
        window: args.window.map_or_else(
            || PushOptions::default_window(&target.boot_status),
            |w| w as usize,
        ),
        inject: None,
    };
    stream_log_push(
        target,
        lines,
        filter,
        resume_after_s,
        sink,
        total,
        &options,
        info,
    )
}

/// The summary of a stream: `head` (the log, its rows, what they went through), the wall time and
/// the estimates file, then the firmware's counts and state, the link's, and the step's cost.
fn print_summary(
    w: &mut dyn Write,
    head: &str,
    written: &Written,
    s: &StreamSummary,
    binning: Option<BinningSummary>,
    target: &Target,
) -> std::io::Result<()> {
    let corrected = written.corrected.as_deref().map_or(String::new(), |c| {
        format!("; corrected attitude in {}", output_name(c))
    });
    writeln!(
        w,
        "{head} in {:.1} s ({:.0} rows/s); estimates in {}{corrected}",
        s.wall.as_secs_f64(),
        s.rows as f64 / s.wall.as_secs_f64().max(1e-9),
        output_name(&written.estimates),
    )?;
    if let Some(b) = binning {
        writeln!(w, "  binned: {}", b.describe())?;
    }
    for line in s.nav.iter().flat_map(|n| n.describe()) {
        writeln!(w, "  {line}")?;
    }
    if let Some(skipped) = s.unreadable.describe_skipped() {
        writeln!(w, "  {skipped}")?;
    }
    let st = &s.final_status;
    write_firmware_counts(w, st)?;
    write_firmware_state(w, st)?;
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
    match &s.nav {
        None => writeln!(w, "{}", target.unit.summary(&s.cost)),
        Some(nav) => {
            let unit = &target.unit;
            writeln!(w, "{}", unit.describe("sample cost", &nav.sample_cost))?;
            writeln!(w, "{}", unit.describe("with its bin's step", &nav.bin_cost))
        }
    }
}

/// What the firmware counted: samples accepted and filled, window restarts, bad frames and
/// rejected samples by kind.
fn write_firmware_counts(w: &mut dyn Write, st: &StatusReply) -> std::io::Result<()> {
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
    )
}

/// The firmware's stack, checkpoints, link counters, last reset and clock.
fn write_firmware_state(w: &mut dyn Write, st: &StatusReply) -> std::io::Result<()> {
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
    writeln!(w, "  firmware's last reset: {cause}; clock: {clock}")
}
