//! `host-sim stream`: a log streamed through the firmware over its link ([`crate::stream`]), the
//! estimates CSV written from its answers, the summary of the stream and its report.

use crate::exit_status::RunEnd;
use crate::formats::binned_lines::{BinningSummary, Lines};
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{is_stdio, LogLine, LogReader, RowFilter};
use crate::formats::log_paths::{default_estimates_path, inputs_of, log_name};
use crate::formats::output_file::{check_not_input, Input, OutputFile};
use crate::formats::truth_file::load_truth;
use crate::replay::GridFollower;
use crate::report::timeline::{Timeline, TimelineRow};
use crate::report::{ReportBuilder, TruthRows};
use crate::stream::push::{stream_log_push, PushOptions};
use crate::stream::qemu::Machine;
use crate::stream::{prepare_firmware, stream_log, StreamSummary, Target};
use anyhow::{bail, Context};
use estimator_core::{Output, RejectReason, SampleError};
use link_protocol::frame::FrameError;
use link_protocol::{ClockSource, ResetCause};
use std::io::Write;
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
    let mut judge = truth.as_ref().map(|t| ReportBuilder::new(TruthRows::of(t)));
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
