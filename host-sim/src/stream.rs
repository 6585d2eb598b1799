//! `host-sim stream`: feeds an attitude log to the firmware over its framed serial link and writes
//! the estimates CSV from the firmware's answers with the same writer as `host-sim estimate` (so
//! the two files can be compared byte for byte). By default one sample per request, each sent when
//! the last is answered; with `--push` without waiting for answers (up to a window of frames the
//! firmware's receive buffer holds, [`push::PushOptions`]), as fast as the link takes or, with
//! `--realtime`, at the log's own rate, as a navigation computer sends. Every request is numbered
//! (link protocol 5) and every answer matched to its request by its number; a request whose answer
//! never comes (lost on the line, or in a firmware restart) is counted as lost and its row left out
//! of the estimates. The summary ends with
//! `frames sent N, answered N, lost N, overruns N` and the firmware's link counters. With
//! `--nav-rate` each row goes as a navigation-rate sample, which the firmware bins itself
//! ([`nav`]), through the same two loops: what differs between the kinds of sample is a
//! [`sink::RowSink`]. With `--qemu FIRMWARE.elf` it boots the firmware in QEMU first
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
pub mod nav;
pub mod push;
pub mod qemu;
pub mod sink;

use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{LogLine, LogLines, RowFilter};
use crate::replay::sample_of;
use anyhow::{bail, Context};
use cost::{CostStats, CostUnit};
use estimator_core::{Output, SampleError};
use link::FirmwareLink;
use link_protocol::{Counters, Request, Response, SampleMsg, StatusReply, PROTOCOL_VERSION};
use qemu::{Machine, Qemu};
use sink::{RowSink, SampleSink};
use std::io::{IsTerminal, Write};
use std::path::Path;
use std::time::{Duration, Instant};

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
        Response::Nav(_) => bail!("the firmware answered a sample as a navigation-rate sample"),
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
    /// The step costs the firmware reported (with `--nav-rate`: those of the samples that completed
    /// a bin, [`nav::NavSummary`] has the rest).
    pub cost: CostStats,
    /// The firmware's status after the last row.
    pub final_status: StatusReply,
    /// Wall-clock time the stream took.
    pub wall: Duration,
    /// Unreadable rows skipped.
    pub unreadable: RowFilter,
    /// With `--nav-rate`: what the firmware did with the navigation-rate samples.
    pub nav: Option<nav::NavSummary>,
}

impl StreamSummary {
    /// A stream that sent one row at a time and had each answered before the next: every row
    /// sent was answered, none lost, no restart.
    pub(crate) fn one_at_a_time(
        rows: u64,
        cost: CostStats,
        final_status: StatusReply,
        wall: Duration,
        unreadable: RowFilter,
        nav: Option<nav::NavSummary>,
    ) -> StreamSummary {
        StreamSummary {
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
            wall,
            unreadable,
            nav,
        }
    }
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
/// ([`IntervalCheck`](crate::formats::time_stamps::IntervalCheck)).
pub fn stream_log<L: LogLines, W: Write>(
    target: &mut Target,
    lines: &mut L,
    filter: RowFilter,
    resume_after_s: Option<f64>,
    writer: &mut EstimatesWriter<W>,
    total_bytes: Option<u64>,
    each: &mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
) -> anyhow::Result<StreamSummary> {
    let mut sink = SampleSink::checked(writer, each);
    stream_rows_one_at_a_time(
        target,
        lines,
        filter,
        resume_after_s,
        &mut sink,
        total_bytes,
    )
}

/// Streams the log's rows through the target one at a time, each sent when the last is
/// answered, as `sink` says ([`RowSink`]: samples or navigation-rate samples); with
/// `resume_after_s` (the firmware's checkpoint) the rows it holds already are skipped. Unreadable
/// rows go through `filter` (skipped and counted, or refused when strict).
pub fn stream_rows_one_at_a_time<L: LogLines, S: RowSink>(
    target: &mut Target,
    lines: &mut L,
    mut filter: RowFilter,
    resume_after_s: Option<f64>,
    sink: &mut S,
    total_bytes: Option<u64>,
) -> anyhow::Result<StreamSummary> {
    let start = Instant::now();
    let progress = Progress::new(total_bytes);
    let mut rows = 0u64;
    while let Some(item) = lines.next() {
        let Some(line) = filter.admit(item, &mut |e| {
            progress
                .bar
                .suspend(|| eprintln!("warning: {e} (row skipped)"));
        })?
        else {
            continue;
        };
        if resume_after_s.is_some_and(|t| sink.before_resume(t, line.row.time_s)) {
            continue;
        }
        sink.check_stamp(line.row.time_s)?;
        let msg = SampleMsg::from(&sample_of(&line.row));
        let response = target
            .request(&sink.request(msg))
            .with_context(|| format!("log line {}", line.line))?;
        if let Some(warning) = sink.answered(&line, &msg, response)? {
            progress.bar.suspend(|| eprintln!("warning: {warning}"));
        }
        rows += 1;
        progress.update(rows, lines.bytes_read());
    }
    drop(progress);
    let final_status = target.status()?;
    let (cost, nav) = sink.finish();
    Ok(StreamSummary::one_at_a_time(
        rows,
        cost,
        final_status,
        start.elapsed(),
        filter,
        nav,
    ))
}
