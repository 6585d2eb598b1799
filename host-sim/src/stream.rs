//! `host-sim stream`: feeds an attitude log to the firmware over its framed serial link, one
//! sample per request, as fast as the firmware answers, and writes the estimates CSV from the
//! firmware's answers with the same writer as `host-sim estimate` (so the two files can be compared
//! byte for byte). With `--qemu FIRMWARE.elf` it boots the firmware in QEMU first
//! ([`qemu`]); with `--port DEVICE --baud N` it talks to a board over a serial port.
//!
//! At the end it prints `step cost: max N instructions, mean M instructions` (QEMU; cycles on a
//! board): the firmware times every `Estimator::step` with its cost counter ([`cost`]).

pub mod cost;
pub mod link;
pub mod qemu;

use crate::estimates_csv::EstimatesWriter;
use crate::log_csv::{LogError, LogLine, LogReader};
use crate::pipeline::default_estimates_path;
use crate::replay::sample_of;
use anyhow::{bail, Context};
use cost::{CostStats, CostUnit};
use estimator_core::{Output, SampleError};
use link::FirmwareLink;
use link_protocol::frame::FrameError;
use link_protocol::{Counters, Request, Response, SampleMsg, StatusReply, PROTOCOL_VERSION};
use qemu::Qemu;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// `host-sim stream`.
#[derive(clap::Args, Debug)]
pub struct StreamArgs {
    /// Boot this firmware ELF in QEMU (mps2-an386, `qemu-system-arm` or $QEMU_SYSTEM_ARM) and
    /// stream through its UART0.
    #[arg(
        long,
        value_name = "FIRMWARE.elf",
        required_unless_present = "port",
        conflicts_with = "port"
    )]
    pub qemu: Option<PathBuf>,
    /// Attitude log (CSV, plain or gzip, `-` for standard input; format: docs/log-format.md).
    #[arg(value_name = "FILE.csv")]
    pub log: PathBuf,
    /// Estimates CSV to write (default: LOG.estimates.csv beside the log, as `estimate`).
    #[arg(long, value_name = "EST.csv")]
    pub out: Option<PathBuf>,
    /// Serial device of a board running the firmware (instead of --qemu).
    #[arg(long, value_name = "DEVICE")]
    pub port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Seconds to wait for each answer before giving up.
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub timeout_s: f64,
    /// Save the firmware's defmt log (QEMU's semihosting output; decode with `defmt-print -e ELF`).
    #[arg(long, value_name = "FILE")]
    pub defmt_log: Option<PathBuf>,
    /// QEMU's working directory, where the firmware keeps its flash (`rins-flash.bin`, the
    /// checkpoints) across runs (default: a fresh scratch directory, so every boot starts empty).
    #[arg(long, value_name = "DIR", requires = "qemu")]
    pub flash_dir: Option<PathBuf>,
    /// Skip the log rows up to the time of the checkpoint the firmware restored at boot.
    #[arg(long)]
    pub resume: bool,
}

/// The firmware, wherever it runs.
pub struct Target {
    pub link: FirmwareLink,
    pub qemu: Option<Qemu>,
    pub unit: CostUnit,
    /// The firmware's answer to the first `ReadStatus`.
    pub boot_status: StatusReply,
}

impl Target {
    /// Boots `elf` in QEMU and checks that the firmware answers.
    pub fn boot_qemu(
        elf: &Path,
        defmt_log: Option<&Path>,
        flash_dir: Option<&Path>,
        timeout: Duration,
    ) -> anyhow::Result<Target> {
        let (qemu, stream) = Qemu::boot(elf, defmt_log, flash_dir)?;
        stream.set_read_timeout(Some(timeout))?;
        let link = FirmwareLink::new(Box::new(stream));
        Target::hello(link, Some(qemu), |hz| CostUnit::QemuInstructions {
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
        let link = FirmwareLink::new(Box::new(port));
        Target::hello(link, None, |hz| CostUnit::BoardCycles { counter_hz: hz })
    }

    fn hello(mut link: FirmwareLink, mut qemu: Option<Qemu>, unit: impl Fn(u32) -> CostUnit) -> anyhow::Result<Target> {
        let status = match link.request(&Request::ReadStatus) {
            Ok(Response::Status(s)) => s,
            Ok(other) => bail!("the firmware answered ReadStatus with {other:?}"),
            Err(e) => return Err(e.context(describe_exit(&mut qemu))),
        };
        if status.protocol_version != PROTOCOL_VERSION {
            bail!(
                "firmware speaks protocol {}, host-sim speaks {PROTOCOL_VERSION}",
                status.protocol_version
            );
        }
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

fn describe_exit(qemu: &mut Option<Qemu>) -> String {
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
    pub result: Result<Output, SampleError>,
    pub step_cost_ticks: u32,
    pub counters: Counters,
}

/// Sends one sample and decodes its answer; errors if the answer is not about this sample.
pub fn step_remote(target: &mut Target, msg: &SampleMsg) -> anyhow::Result<Answer> {
    match target.request(&Request::Sample(*msg))? {
        Response::Step(r) => {
            if r.time_s.to_bits() != msg.time_s.to_bits() {
                bail!("answer for time {} to the sample of time {}", r.time_s, msg.time_s);
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
                bail!("rejection of time {} for the sample of time {}", r.time_s, msg.time_s);
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
    }
}

/// What a stream did.
#[derive(Clone, Debug)]
pub struct StreamSummary {
    pub rows: u64,
    pub cost: CostStats,
    pub final_status: StatusReply,
    pub wall: Duration,
}

/// Streams log lines through the target, writing one estimates row per line.
pub fn stream_lines<I, W>(
    target: &mut Target,
    lines: I,
    writer: &mut EstimatesWriter<W>,
) -> anyhow::Result<StreamSummary>
where
    I: IntoIterator<Item = Result<LogLine, LogError>>,
    W: Write,
{
    let start = Instant::now();
    let mut cost = CostStats::default();
    let mut rows = 0u64;
    for line in lines {
        let line = line?;
        let sample = sample_of(&line.row);
        let answer =
            step_remote(target, &SampleMsg::from(&sample)).with_context(|| format!("log line {}", line.line))?;
        cost.add(answer.step_cost_ticks);
        writer.write_step(line.row.time_s, &answer.result)?;
        rows += 1;
    }
    let final_status = target.status()?;
    Ok(StreamSummary {
        rows,
        cost,
        final_status,
        wall: start.elapsed(),
    })
}

/// `host-sim stream`.
pub fn run(args: &StreamArgs) -> anyhow::Result<()> {
    let timeout = Duration::from_secs_f64(args.timeout_s.max(0.001));
    let out = args.out.clone().unwrap_or_else(|| default_estimates_path(&args.log));
    let lines = LogReader::open(&args.log)?;
    let (mut target, what) = match (&args.qemu, &args.port) {
        (Some(elf), _) => (
            Target::boot_qemu(elf, args.defmt_log.as_deref(), args.flash_dir.as_deref(), timeout)?,
            format!("QEMU mps2-an386 ({})", elf.display()),
        ),
        (None, Some(device)) => (
            Target::open_port(device, args.baud, timeout)?,
            format!("{device} at {} baud", args.baud),
        ),
        (None, None) => bail!("give --qemu FIRMWARE.elf or --port DEVICE"),
    };
    let file = File::create(&out).map_err(|e| LogError::new(&out, 0, format!("cannot create: {e}")))?;
    let mut writer =
        EstimatesWriter::new(BufWriter::new(file)).with_context(|| format!("{}:0: cannot write", out.display()))?;
    let resume_after_s = if args.resume {
        target.boot_status.checkpoint_time_s
    } else {
        None
    };
    if let Some(t) = resume_after_s {
        println!("resuming after the firmware's checkpoint of {t} s");
    }
    let lines = lines.filter(move |l| match (l, resume_after_s) {
        (Ok(line), Some(t)) => line.row.time_s > t,
        _ => true,
    });
    let summary = stream_lines(&mut target, lines, &mut writer)?;
    writer
        .finish()
        .with_context(|| format!("{}:0: cannot write", out.display()))?;
    drop(target.qemu.take());
    print_summary(&args.log, &out, &what, &summary, &target);
    Ok(())
}

fn print_summary(log: &Path, out: &Path, what: &str, s: &StreamSummary, target: &Target) {
    let st = &s.final_status;
    println!(
        "{}: {} rows streamed through {what} in {:.1} s ({:.0} rows/s); estimates in {}",
        log.display(),
        s.rows,
        s.wall.as_secs_f64(),
        s.rows as f64 / s.wall.as_secs_f64().max(1e-9),
        out.display()
    );
    println!(
        "  firmware: {} accepted, {} bridged, {} window restarts",
        st.accepted, st.bridged, st.window_restarts
    );
    let frames: Vec<String> = (0..FrameError::COUNT)
        .map(|i| format!("{} {}", FrameError::name(i), st.counters.bad_frames[i]))
        .collect();
    println!(
        "  bad frames: {} ({})",
        st.counters.bad_frames_total(),
        frames.join(", ")
    );
    let samples: Vec<String> = (0..SampleError::COUNT)
        .map(|i| format!("{} {}", SampleError::reason_name(i), st.counters.rejected_samples[i]))
        .collect();
    println!(
        "  rejected samples: {} ({})",
        st.counters.rejected_samples_total(),
        samples.join(", ")
    );
    println!(
        "  stack (painted): start-up peak {} bytes, service loop peak {} bytes, of {} bytes",
        st.boot_stack_peak_bytes, st.stack_peak_bytes, st.stack_size_bytes
    );
    if let Some(t) = st.checkpoint_time_s {
        println!(
            "  checkpoints: {} saved in this run, newest at {t} s",
            st.checkpoints_saved
        );
    }
    println!("{}", target.unit.summary(&s.cost));
}
