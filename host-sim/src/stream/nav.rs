//! `host-sim stream --nav-rate`: a log at the navigation rate (100-200 Hz) sent to the firmware
//! row by row as it comes, each row a `NavSample` (link protocol 7, docs/link-protocol.md,
//! "Navigation-rate samples"). The firmware averages the samples into its 1 s grid, steps its
//! estimator once a bin is complete and answers every sample with `Nav`: the sample compensated
//! with the current estimate and, for the sample that completed a bin, that bin's step.
//!
//! The host follows the firmware's binning with the core's own [`Binner`] (the firmware's, 1 s
//! bins): every answer must be the one that binning gives, bit for bit in its times (the sample's
//! stamp, the bin's centre) and in what it says of the bins (the sample kept in the open bin, a bin
//! completed, the sample refused and why); an answer that is not is an error that stops the
//! stream. The bins' steps are written to the estimates CSV (one row a bin, at its centre, as
//! `estimate --bin-interval-s 1` writes them), each sample's corrected attitude to the
//! corrected-attitude CSV when asked ([`crate::formats::corrected_csv`]). What the estimator
//! makes of a bin depends on the firmware's configuration (set at its build), which the host does
//! not know: the estimates are compared with the host core's by the tests (`qemu_nav_rate`, and
//! `qemu_stream_nav_rate` through this command), not here.
//!
//! A sample the firmware refuses (the binner's checks: a field not finite or out of range, a
//! time not after the last one) is answered `Rejected`; it is counted by reason, the first few
//! are reported with their log lines, and it changes nothing. The last bin stays open in the
//! firmware at the end of the log: a bin is stepped when a later sample arrives.
//!
//! The rows go one at a time or pushed (`--push`, [`super::push`]): [`NavSink`] is the
//! [`RowSink`] of both loops. The firmware's checkpoint holds its estimator, not the bin it is
//! filling: it is saved right after a bin's step, when that bin holds only the sample that
//! completed the last one, and a restarted firmware starts with an empty bin. A stream resumed
//! after a restart (`--resume`) therefore sends the rows of the bins after the checkpoint's, the
//! first of them whole ([`NavSink`]'s `before_resume`); a firmware that restarts in the middle of
//! a pushed stream ([`NavFollower::restarted`]) loses the part of its bin it had taken, and the
//! host's binner forgets it too.

use super::answer_of;
use super::cost::CostStats;
use super::sink::RowSink;
use crate::formats::binned_lines::BinningSummary;
use crate::formats::corrected_csv::CorrectedWriter;
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::LogLine;
use crate::formats::time_stamps::IntervalCheck;
use crate::replay::row_of;
use anyhow::{bail, Context};
use estimator_core::binning::{Binner, DEFAULT_BIN_INTERVAL_S};
use estimator_core::{Output, RejectCounts, RejectReason, Sample, SampleError};
use link_protocol::{BinOutcome, NavReply, RejectedReply, Request, Response, SampleMsg};
use std::io::Write;

/// How many refused samples are reported one by one (their log lines); all are counted.
pub const REFUSED_REPORTED: usize = 10;

/// What the firmware did with a stream's navigation-rate samples.
#[derive(Clone, Debug)]
pub struct NavSummary {
    /// Samples answered (`rows`), bins the firmware completed (`bins`: stepped, or their step
    /// rejected), samples it refused by reason (`refused`).
    pub binning: BinningSummary,
    /// Samples answered with their attitude compensated (the others came before the first
    /// estimate, or were refused).
    pub compensated: u64,
    /// Samples in the bin left open at the end of the log, never stepped.
    pub open_samples: u32,
    /// The first [`REFUSED_REPORTED`] refused samples: their log lines and why.
    pub first_refused: Vec<(usize, SampleError)>,
    /// Samples a resumed stream sent that the firmware had taken already, before this stream
    /// (refused as `time_not_increasing`, see [`NavFollower::resuming`]).
    pub already_held: u64,
    /// What a sample that completed no bin cost the firmware (its binning and compensation; a
    /// refused sample's checks).
    pub sample_cost: CostStats,
    /// What a sample that completed a bin cost (its binning, the bin's step, its compensation).
    pub bin_cost: CostStats,
}

impl NavSummary {
    fn new() -> NavSummary {
        NavSummary {
            binning: BinningSummary {
                interval_s: DEFAULT_BIN_INTERVAL_S,
                rows: 0,
                bins: 0,
                refused: RejectCounts::ZERO,
            },
            compensated: 0,
            open_samples: 0,
            first_refused: Vec::new(),
            already_held: 0,
            sample_cost: CostStats::default(),
            bin_cost: CostStats::default(),
        }
    }
}

/// Where the answers go: the estimates CSV (a row a bin), the corrected-attitude CSV (a row a
/// sample, when asked), and `each`, which sees every bin (as a row: its average) and its step.
pub struct NavOutputs<'a, W: Write, C: Write> {
    /// The estimates CSV.
    pub estimates: &'a mut EstimatesWriter<W>,
    /// The corrected-attitude CSV, when asked for.
    pub corrected: Option<&'a mut CorrectedWriter<C>>,
    /// Sees every bin the firmware completed and the result of its step.
    pub each: &'a mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
}

/// Follows the firmware's binning with the host's [`Binner`] and checks each answer against it.
pub struct NavFollower {
    binner: Binner,
    /// The log line of the last sample in the open bin: a bin's row is numbered with it, as
    /// `--bin-interval-s` numbers its bins.
    bin_last_line: usize,
    /// The firmware may hold samples of this log that the host does not know of (a stream resumed
    /// into a firmware that did not restart), until it first takes one.
    catching_up: bool,
    summary: NavSummary,
}

impl Default for NavFollower {
    fn default() -> Self {
        NavFollower {
            binner: Binner::default(),
            bin_last_line: 0,
            catching_up: false,
            summary: NavSummary::new(),
        }
    }
}

impl NavFollower {
    /// A follower for a stream that resumes (`--resume`) into a firmware that holds a state of
    /// this log. After a restart the firmware holds its checkpoint and an empty bin, and the
    /// stream sends the rows of the bins after the checkpoint's: the host's binner starts empty
    /// too. A firmware that did not restart (the host stopped, the board ran on) may have taken
    /// later rows already, the open bin's among them: it refuses each of them again as
    /// `time_not_increasing`. Until the firmware first takes a row, such a refusal of a row the
    /// host's binner takes is one of those: the host bins the row as the firmware did before (a
    /// bin it completes was stepped then, and is not written again) and counts it as already
    /// held; from the first row the firmware takes on, its binner and the host's hold the same
    /// rows and every answer is checked as in a fresh stream.
    pub fn resuming() -> Self {
        NavFollower {
            catching_up: true,
            ..NavFollower::default()
        }
    }

    /// The firmware restarted (it announced `Ready`): its bin is empty, and so is the host's. The
    /// samples of the bin it was filling that it answered before are gone: the bin it fills next
    /// holds only those it takes from now on.
    pub fn restarted(&mut self) {
        self.binner = Binner::default();
    }

    /// The firmware's `response` to the navigation-rate `sample` of the log's `line`: checked
    /// against the host's binning and written out. Returns the reason when the firmware refused the
    /// sample.
    pub fn answered<W: Write, C: Write>(
        &mut self,
        line: &LogLine,
        sample: &Sample,
        response: Response,
        out: &mut NavOutputs<'_, W, C>,
    ) -> anyhow::Result<Option<SampleError>> {
        let expected = self.binner.push(sample);
        self.summary.binning.rows += 1;
        match response {
            Response::Rejected(r)
                if self.catching_up
                    && expected.is_ok()
                    && r.error() == Some(SampleError::TimeNotIncreasing) =>
            {
                check_time("rejection", r.time_s, sample.time_s)?;
                self.bin_last_line = line.line;
                self.summary.already_held += 1;
                self.summary.sample_cost.add(r.step_cost_ticks);
                if let Some(c) = out.corrected.as_mut() {
                    c.write_refused(sample.time_s, RejectReason::TimeNotIncreasing)?;
                }
                Ok(None)
            }
            Response::Nav(reply) => {
                self.catching_up = false;
                self.nav(line, sample, &reply, expected, out)?;
                Ok(None)
            }
            Response::Rejected(r) => self.refused(line, sample, &r, expected, out).map(Some),
            Response::Step(_) => bail!("the firmware answered a navigation-rate sample with Step"),
            Response::Status(_) => {
                bail!("the firmware answered a navigation-rate sample with a status")
            }
            Response::Ready { .. } => {
                bail!("the firmware restarted (it announced Ready instead of answering)")
            }
        }
    }

    /// What the firmware did, at the end of the log.
    pub fn finish(mut self) -> NavSummary {
        self.summary.open_samples = self.binner.pending();
        self.summary
    }

    fn nav<W: Write, C: Write>(
        &mut self,
        line: &LogLine,
        sample: &Sample,
        reply: &NavReply,
        expected: Result<Option<Sample>, SampleError>,
        out: &mut NavOutputs<'_, W, C>,
    ) -> anyhow::Result<()> {
        check_time("answer", reply.time_s, sample.time_s)?;
        match (expected, reply.bin) {
            (Ok(None), BinOutcome::Open) => self.summary.sample_cost.add(reply.cost_ticks),
            (Ok(Some(bin)), BinOutcome::Step(r)) => {
                self.stepped(&bin, Response::Step(r), reply.cost_ticks, out)?;
            }
            (Ok(Some(bin)), BinOutcome::Rejected(r)) => {
                self.stepped(&bin, Response::Rejected(r), reply.cost_ticks, out)?;
            }
            (expected, got) => bail!(
                "the firmware's answer says {}, the host's binner {}",
                describe_outcome(&got),
                describe_expected(&expected)
            ),
        }
        self.bin_last_line = line.line;
        self.summary.compensated += u64::from(reply.corrected_rad.is_some());
        if let Some(c) = out.corrected.as_mut() {
            c.write_corrected(sample.time_s, reply.corrected_rad)?;
        }
        Ok(())
    }

    /// The step of a completed bin (`response`: the `Step` or `Rejected` the answer carried).
    fn stepped<W: Write, C: Write>(
        &mut self,
        bin: &Sample,
        response: Response,
        cost_ticks: u32,
        out: &mut NavOutputs<'_, W, C>,
    ) -> anyhow::Result<()> {
        let answer = answer_of(&SampleMsg::from(bin), response)
            .with_context(|| format!("the step of the bin at {} s", bin.time_s))?;
        out.estimates.write_step(bin.time_s, &answer.result)?;
        let bin_line = LogLine {
            line: self.bin_last_line,
            row: row_of(bin),
        };
        (out.each)(&bin_line, &answer.result);
        self.summary.binning.bins += 1;
        self.summary.bin_cost.add(cost_ticks);
        Ok(())
    }

    fn refused<W: Write, C: Write>(
        &mut self,
        line: &LogLine,
        sample: &Sample,
        r: &RejectedReply,
        expected: Result<Option<Sample>, SampleError>,
        out: &mut NavOutputs<'_, W, C>,
    ) -> anyhow::Result<SampleError> {
        check_time("rejection", r.time_s, sample.time_s)?;
        let error = r
            .error()
            .with_context(|| format!("unknown rejection reason {}/{}", r.reason, r.field))?;
        if expected != Err(error) {
            bail!(
                "the firmware refused the sample ({error}), the host's binner {}",
                describe_expected(&expected)
            );
        }
        let s = &mut self.summary;
        s.binning.refused.count(error.reason());
        if s.first_refused.len() < REFUSED_REPORTED {
            s.first_refused.push((line.line, error));
        }
        s.sample_cost.add(r.step_cost_ticks);
        if let Some(c) = out.corrected.as_mut() {
            c.write_refused(sample.time_s, error.reason())?;
        }
        Ok(error)
    }
}

/// An answer about the sample stamped `sent_s` must carry that stamp, bit for bit.
fn check_time(what: &str, got_s: f64, sent_s: f64) -> anyhow::Result<()> {
    if got_s.to_bits() != sent_s.to_bits() {
        bail!("{what} for time {got_s} to the navigation-rate sample of time {sent_s}");
    }
    Ok(())
}

fn describe_outcome(got: &BinOutcome) -> String {
    match got {
        BinOutcome::Open => "no bin completed".to_string(),
        BinOutcome::Step(r) => format!("the bin at {} s stepped", r.time_s),
        BinOutcome::Rejected(r) => format!("the bin at {} s rejected", r.time_s),
    }
}

fn describe_expected(expected: &Result<Option<Sample>, SampleError>) -> String {
    match expected {
        Ok(None) => "completes no bin".to_string(),
        Ok(Some(bin)) => format!("completes the bin at {} s", bin.time_s),
        Err(e) => format!("refuses the sample ({e})"),
    }
}

/// Rows sent as navigation-rate samples (`NavSample`): the answers checked against the host's
/// binning ([`NavFollower`]) and written to [`NavOutputs`]; the stamps checked as a log binned
/// into 1 s is ([`IntervalCheck::binned`]: 5 ms to 10 s, at most a bin). A stream resumed after
/// the firmware's checkpoint starts at the bin after the checkpoint's (see
/// [`RowSink::before_resume`] below).
pub struct NavSink<'a, W: Write, C: Write> {
    follower: NavFollower,
    out: NavOutputs<'a, W, C>,
    interval_check: IntervalCheck,
    /// A binner of the firmware's bins, for the bin a stamp falls in.
    bins: Binner,
    refused: usize,
}

impl<'a, W: Write, C: Write> NavSink<'a, W, C> {
    /// A sink writing to `out`; `resuming`: the stream resumes into a firmware that holds a state
    /// of this log (`--resume`, [`NavFollower::resuming`]).
    pub fn new(out: NavOutputs<'a, W, C>, resuming: bool) -> Self {
        NavSink {
            follower: if resuming {
                NavFollower::resuming()
            } else {
                NavFollower::default()
            },
            out,
            interval_check: IntervalCheck::binned(DEFAULT_BIN_INTERVAL_S),
            bins: Binner::default(),
            refused: 0,
        }
    }
}

impl<W: Write, C: Write> RowSink for NavSink<'_, W, C> {
    fn request(&self, msg: SampleMsg) -> Request {
        Request::NavSample(msg)
    }

    /// The firmware saves a checkpoint right after a bin's step, stamped at the bin's centre,
    /// while its open bin holds only the sample that completed that bin; it does not save the open
    /// bin, and restarts with an empty one. The rows of the checkpoint's bin and the bins before
    /// are in the checkpoint; a resumed stream starts with the first row of a later bin, so that
    /// the bin the firmware fills first after a restart is whole.
    fn before_resume(&self, checkpoint_s: f64, time_s: f64) -> bool {
        self.bins.bin_of(time_s) <= self.bins.bin_of(checkpoint_s)
    }

    fn check_stamp(&mut self, time_s: f64) -> anyhow::Result<()> {
        Ok(self.interval_check.observe(time_s)?)
    }

    fn answered(
        &mut self,
        line: &LogLine,
        msg: &SampleMsg,
        response: Response,
    ) -> anyhow::Result<Option<String>> {
        let sample = Sample::from(msg);
        let refused = self
            .follower
            .answered(line, &sample, response, &mut self.out)
            .with_context(|| format!("log line {}", line.line))?;
        let Some(e) = refused else {
            return Ok(None);
        };
        self.refused += 1;
        Ok((self.refused <= REFUSED_REPORTED).then(|| {
            format!(
                "log line {}: the firmware refused the sample: {e}",
                line.line
            )
        }))
    }

    fn restarted(&mut self) {
        self.follower.restarted();
    }

    fn finish(&mut self) -> (CostStats, Option<NavSummary>) {
        let nav = std::mem::take(&mut self.follower).finish();
        (nav.bin_cost, Some(nav))
    }
}

impl NavSummary {
    /// For people: the binning (`3000 rows averaged into 29 bins of 1 s (0 rows refused)`), the
    /// first refused rows' lines, the bin left open and the samples compensated; a line each.
    pub fn describe(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "binned by the firmware: {}",
            self.binning.describe()
        )];
        if !self.first_refused.is_empty() {
            let first: Vec<String> = self
                .first_refused
                .iter()
                .map(|(line, e)| format!("{line} ({})", e.reason().name()))
                .collect();
            let more = if u64::from(self.binning.refused.total()) > first.len() as u64 {
                ", ..."
            } else {
                ""
            };
            lines.push(format!(
                "rows the firmware refused: lines {}{more}; they changed nothing",
                first.join(", ")
            ));
        }
        if self.already_held > 0 {
            lines.push(format!(
                "rows the firmware had taken already, before this stream: {} (refused as time_not_increasing, passed over)",
                self.already_held
            ));
        }
        if self.open_samples > 0 {
            lines.push(format!(
                "the last bin ({} rows) left open: the firmware steps a bin once a later sample arrives",
                self.open_samples
            ));
        }
        lines.push(format!(
            "compensated: {} of {} samples (none before the first estimate)",
            self.compensated, self.binning.rows
        ));
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::log_csv::{LogReader, RowFilter};
    use crate::replay::sample_of;
    use crate::stream::cost::CostUnit;
    use crate::stream::link::FirmwareLink;
    use crate::stream::push::{stream_log_push, PushOptions};
    use crate::stream::{stream_rows_one_at_a_time, StreamSummary, Target};
    use estimator_core::{Config, Estimator};
    use link_protocol::frame::MAX_FRAME;
    use link_protocol::{
        encode_frame, Counters, FrameAccumulator, LinkCounters, Numbered, StatusReply, StepReply,
        MAX_REQUEST_ENCODED, PROTOCOL_VERSION, UNNUMBERED,
    };
    use std::os::unix::net::UnixStream;
    use std::path::Path;
    use std::time::{Duration, Instant};

    /// How the stand-in firmware answers a navigation-rate sample.
    #[derive(Clone, Copy, PartialEq)]
    enum Behaviour {
        /// As the firmware does: the core's `Binner`, `step` and `compensate`.
        AsTheFirmware,
        /// Never completes a bin (a firmware whose binning differs from the host's).
        NeverCompletesABin,
    }

    /// The stand-in firmware: how it answers, what it holds before the stream, and a restart.
    #[derive(Clone)]
    struct StandIn {
        behaviour: Behaviour,
        /// Samples it took before the stream (a board that ran on after its host stopped).
        held: Vec<Sample>,
        /// After answering the request of this number it goes down: it never gets the next
        /// `down` navigation samples (at least 1), then it is up again with an empty bin and a
        /// fresh estimator and announces `Ready`.
        restart_after: Option<u32>,
        down: u32,
    }

    impl StandIn {
        fn as_the_firmware() -> StandIn {
            StandIn {
                behaviour: Behaviour::AsTheFirmware,
                held: Vec::new(),
                restart_after: None,
                down: 0,
            }
        }
    }

    fn status() -> StatusReply {
        StatusReply {
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
            link: LinkCounters {
                rx_buffer_bytes: 1023,
                ..LinkCounters::default()
            },
            reset_cause: 0,
            clock_source: 2,
        }
    }

    /// The answer to a navigation-rate sample, as `firmware/src/app/service.rs` gives it.
    fn answer(
        binner: &mut Binner,
        estimator: &mut Estimator,
        sample: &Sample,
        behaviour: Behaviour,
    ) -> Response {
        let counters = Counters::default();
        let completed = match binner.push(sample) {
            Err(e) => {
                return Response::Rejected(RejectedReply::new(sample.time_s, &e, 1, counters))
            }
            Ok(completed) => completed,
        };
        let bin = match completed.filter(|_| behaviour == Behaviour::AsTheFirmware) {
            None => BinOutcome::Open,
            Some(bin) => match estimator.step(&bin) {
                Ok(o) => BinOutcome::Step(StepReply::new(&o, 2, counters)),
                Err(e) => BinOutcome::Rejected(RejectedReply::new(bin.time_s, &e, 2, counters)),
            },
        };
        let corrected_rad = estimator
            .compensate(sample)
            .ok()
            .map(|a| [a.heading_rad, a.roll_rad, a.pitch_rad]);
        Response::Nav(NavReply {
            time_s: sample.time_s,
            corrected_rad,
            bin,
            cost_ticks: 3,
        })
    }

    /// A firmware on the other end of a socket, answering as `stand_in` says.
    fn stand_in_firmware(mut port: UnixStream, stand_in: StandIn) {
        use std::io::Read as _;
        let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
        let fresh = || Box::new(Estimator::new(Config::default()).unwrap());
        let mut binner = Binner::default();
        let mut estimator = fresh();
        for held in &stand_in.held {
            answer(&mut binner, &mut estimator, held, stand_in.behaviour);
        }
        // Navigation samples still to miss, as sent while it is down.
        let mut down = 0u32;
        let mut buf = [0u8; 256];
        loop {
            let n = match port.read(&mut buf) {
                Ok(0) | Err(_) => return,
                Ok(n) => n,
            };
            for &b in &buf[..n] {
                let Some(Ok(request)) = rx.push_decode::<Numbered<Request>>(b) else {
                    continue;
                };
                let seq = request.seq;
                if down > 0 && matches!(request.message, Request::NavSample(_)) {
                    down -= 1;
                    if down == 0 {
                        // Up again, with nothing of what it held.
                        binner = Binner::default();
                        estimator = fresh();
                        let message = Response::Ready {
                            protocol_version: PROTOCOL_VERSION,
                        };
                        let mut out = [0u8; MAX_FRAME];
                        let n = encode_frame(
                            &Numbered {
                                seq: UNNUMBERED,
                                message,
                            },
                            &mut out,
                        )
                        .unwrap();
                        port.write_all(&out[..n]).unwrap();
                    }
                    continue;
                }
                let message = match request.message {
                    Request::NavSample(msg) => answer(
                        &mut binner,
                        &mut estimator,
                        &Sample::from(&msg),
                        stand_in.behaviour,
                    ),
                    Request::ReadStatus => Response::Status(status()),
                    _ => continue,
                };
                let mut out = [0u8; MAX_FRAME];
                let n = encode_frame(&Numbered { seq, message }, &mut out).unwrap();
                port.write_all(&out[..n]).unwrap();
                if stand_in.restart_after == Some(seq) {
                    down = stand_in.down;
                }
            }
        }
    }

    /// How the host streams: one row at a time or pushed (`window`, `realtime`), and from where.
    #[derive(Clone, Copy)]
    struct Sending {
        push: Option<(usize, bool)>,
        resume_after_s: Option<f64>,
        resuming: bool,
    }

    const ONE_AT_A_TIME: Sending = Sending {
        push: None,
        resume_after_s: None,
        resuming: false,
    };

    fn pushed(window: usize, realtime: bool) -> Sending {
        Sending {
            push: Some((window, realtime)),
            ..ONE_AT_A_TIME
        }
    }

    /// `--resume` after a firmware checkpoint of `checkpoint_s`, pushed or not.
    fn resumed(push: Option<(usize, bool)>, checkpoint_s: f64) -> Sending {
        Sending {
            push,
            resume_after_s: Some(checkpoint_s),
            resuming: true,
        }
    }

    /// What a stream gave: the summary (or the error, as the tool prints it), the estimates CSV,
    /// the corrected-attitude CSV and what the push said.
    struct Streamed {
        summary: Result<StreamSummary, String>,
        estimates: String,
        corrected: String,
        info: String,
    }

    /// Streams the log `csv` through the stand-in firmware as `sending` says.
    fn stream_with(csv: &str, stand_in: StandIn, sending: Sending) -> Streamed {
        let (host_end, firmware_end) = UnixStream::pair().unwrap();
        std::thread::spawn(move || stand_in_firmware(firmware_end, stand_in));
        let reader = host_end.try_clone().unwrap();
        reader
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        let mut target = Target {
            link: FirmwareLink::new(Box::new(reader), Box::new(host_end), Duration::from_secs(5)),
            qemu: None,
            unit: CostUnit::BoardCycles { counter_hz: 1 },
            boot_status: status(),
        };
        let bytes = std::io::Cursor::new(csv.as_bytes().to_vec());
        let mut lines = LogReader::new(Path::new("nav.csv"), bytes);
        let mut estimates = EstimatesWriter::new(Vec::new()).unwrap();
        let mut corrected = CorrectedWriter::new(Vec::new()).unwrap();
        let out = NavOutputs {
            estimates: &mut estimates,
            corrected: Some(&mut corrected),
            each: &mut |_, _| {},
        };
        let mut sink = NavSink::new(out, sending.resuming);
        let filter = RowFilter::new(true);
        let mut info = Vec::new();
        let summary = match sending.push {
            None => stream_rows_one_at_a_time(
                &mut target,
                &mut lines,
                filter,
                sending.resume_after_s,
                &mut sink,
                None,
            ),
            Some((window, realtime)) => {
                let options = PushOptions {
                    realtime,
                    window,
                    inject: None,
                };
                stream_log_push(
                    &mut target,
                    &mut lines,
                    filter,
                    sending.resume_after_s,
                    &mut sink,
                    None,
                    &options,
                    &mut info,
                )
            }
        }
        .map_err(|e| format!("{e:#}"));
        drop(sink);
        let text = |b: Vec<u8>| String::from_utf8(b).unwrap();
        Streamed {
            summary,
            estimates: text(estimates.finish().unwrap()),
            corrected: text(corrected.finish().unwrap()),
            info: text(info),
        }
    }

    /// Streams the log `csv` one row at a time; returns the summary (or the error, as the tool
    /// prints it), the estimates CSV and the corrected-attitude CSV.
    fn stream(csv: &str, behaviour: Behaviour) -> (Result<StreamSummary, String>, String, String) {
        let stand_in = StandIn {
            behaviour,
            ..StandIn::as_the_firmware()
        };
        let s = stream_with(csv, stand_in, ONE_AT_A_TIME);
        (s.summary, s.estimates, s.corrected)
    }

    /// 3 s of rows at 100 Hz; `bad` rows (time, roll) inserted after the row of that index.
    /// Returns the log and the file lines of the inserted rows.
    fn log(bad: &[(usize, &str, &str)]) -> (String, Vec<usize>) {
        log_of(300, bad)
    }

    /// `rows` rows at 100 Hz from 0 s, with `bad` rows as [`log`] inserts them.
    fn log_of(rows: u32, bad: &[(usize, &str, &str)]) -> (String, Vec<usize>) {
        let mut rows: Vec<String> = (0..rows)
            .map(|k| {
                let t = f64::from(k) / 100.0;
                format!("{t},{},20,30,40,1,2", 10.0 + 0.75 * t)
            })
            .collect();
        let mut lines = Vec::new();
        for (i, &(after, time, roll)) in bad.iter().enumerate() {
            rows.insert(after + 1 + i, format!("{time},10,20,30,40,{roll},2"));
            // The header is line 1, row 0 line 2.
            lines.push(after + 1 + i + 2);
        }
        let header = "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg";
        (format!("{header}\n{}\n", rows.join("\n")), lines)
    }

    /// The samples of a log made by [`log_of`], in order.
    fn samples_of(csv: &str) -> Vec<Sample> {
        let bytes = std::io::Cursor::new(csv.as_bytes().to_vec());
        LogReader::new(Path::new("nav.csv"), bytes)
            .map(|line| sample_of(&line.unwrap().row))
            .collect()
    }

    #[test]
    fn refused_rows_are_counted_reported_and_change_nothing() {
        // A repeated time, a time back in the first second, a NaN roll: each refused.
        let bad = [(150, "1.5", "1"), (250, "0.5", "1"), (260, "2.605", "nan")];
        let (csv, bad_lines) = log(&bad);
        let (summary, estimates, corrected) = stream(&csv, Behaviour::AsTheFirmware);
        let nav = summary.unwrap().nav.unwrap();
        assert_eq!((nav.binning.rows, nav.binning.bins), (303, 2));
        let refused = |r| nav.binning.refused.of(r);
        assert_eq!(refused(RejectReason::TimeNotIncreasing), 2);
        assert_eq!(refused(RejectReason::NonFinite), 1);
        let lines: Vec<usize> = nav.first_refused.iter().map(|(l, _)| *l).collect();
        assert_eq!(lines, bad_lines);
        assert_eq!(nav.open_samples, 100);
        assert_eq!((nav.sample_cost.steps, nav.bin_cost.steps), (301, 2));
        // The same estimates and corrected attitude as the log without them.
        let (clean, _) = log(&[]);
        let (_, clean_estimates, clean_corrected) = stream(&clean, Behaviour::AsTheFirmware);
        assert_eq!(estimates, clean_estimates);
        let times: Vec<&str> = estimates.lines().skip(1).map(|l| &l[..8]).collect();
        assert_eq!(times, ["0.500000", "1.500000"]);
        let kept: Vec<&str> = corrected
            .lines()
            .filter(|l| !l.contains(",rejected_"))
            .collect();
        assert_eq!(kept, clean_corrected.lines().collect::<Vec<_>>());
        let rejected: Vec<&str> = corrected
            .lines()
            .filter(|l| l.contains(",rejected_"))
            .collect();
        assert_eq!(
            rejected,
            [
                "1.500000,,,,rejected_time_not_increasing",
                "0.500000,,,,rejected_time_not_increasing",
                "2.605000,,,,rejected_non_finite"
            ]
        );
        let described = nav.describe().join("\n");
        assert!(
            described.contains(&format!(
                "rows the firmware refused: lines {} (time_not_increasing), {} (time_not_increasing), {} (non_finite)",
                bad_lines[0], bad_lines[1], bad_lines[2]
            )),
            "{described}"
        );
    }

    #[test]
    fn an_answer_the_host_s_binning_does_not_give_stops_the_stream() {
        let (csv, _) = log(&[]);
        let (summary, _, _) = stream(&csv, Behaviour::NeverCompletesABin);
        let error = summary.unwrap_err();
        // Row 100 (1 s, line 102) completes the first bin.
        assert!(
            error.contains("log line 102: the firmware's answer says no bin completed, the host's binner completes the bin at 0.5 s"),
            "{error}"
        );
    }

    #[test]
    fn pushed_navigation_samples_are_answered_as_one_at_a_time() {
        let bad = [(150, "1.5", "1"), (250, "0.5", "1"), (260, "2.605", "nan")];
        let (csv, bad_lines) = log(&bad);
        let one = stream_with(&csv, StandIn::as_the_firmware(), ONE_AT_A_TIME);
        let one_nav = one.summary.unwrap().nav.unwrap();
        for window in [1, 4, 11] {
            let push = stream_with(&csv, StandIn::as_the_firmware(), pushed(window, false));
            assert_eq!(push.estimates, one.estimates, "window {window}");
            assert_eq!(push.corrected, one.corrected, "window {window}");
            let summary = push.summary.unwrap();
            let l = summary.link;
            assert_eq!((l.sent, l.answered, l.lost, l.restarts), (303, 303, 0, 0));
            let nav = summary.nav.unwrap();
            assert_eq!(nav.binning, one_nav.binning, "window {window}");
            assert_eq!(nav.first_refused, one_nav.first_refused);
            let lines: Vec<usize> = nav.first_refused.iter().map(|(l, _)| *l).collect();
            assert_eq!(lines, bad_lines);
            assert_eq!(
                (nav.open_samples, nav.compensated),
                (100, one_nav.compensated)
            );
            assert_eq!((nav.sample_cost.steps, nav.bin_cost.steps), (301, 2));
            assert_eq!(summary.cost.steps, 2, "the summary's cost: the bins' steps");
        }
    }

    #[test]
    fn realtime_pushes_navigation_samples_at_the_log_s_rate() {
        // 1.2 s of rows at 100 Hz: the last sent 1.19 s after the first (the upper bound leaves
        // room for a loaded machine), answered as one at a time.
        let (csv, _) = log_of(120, &[]);
        let start = Instant::now();
        let push = stream_with(&csv, StandIn::as_the_firmware(), pushed(11, true));
        let wall = start.elapsed().as_secs_f64();
        assert!((1.19..6.0).contains(&wall), "1.2 s of rows took {wall} s");
        let one = stream_with(&csv, StandIn::as_the_firmware(), ONE_AT_A_TIME);
        assert_eq!(
            (push.estimates, push.corrected),
            (one.estimates, one.corrected)
        );
    }

    #[test]
    fn a_stream_resumed_after_a_checkpoint_starts_at_the_next_bin() {
        // The firmware restarted with the checkpoint of bin 1's step (1.5 s) and an empty bin:
        // the rows of bins 0 and 1 are skipped, the first sent is 2 s's.
        let (csv, _) = log_of(400, &[]);
        let stand_in = StandIn::as_the_firmware();
        for push in [None, Some((4, false))] {
            let s = stream_with(&csv, stand_in.clone(), resumed(push, 1.5));
            let nav = s.summary.unwrap().nav.unwrap();
            assert_eq!((nav.binning.rows, nav.binning.bins), (200, 1));
            assert_eq!(nav.already_held, 0);
            let first = s.corrected.lines().nth(1).unwrap();
            assert!(first.starts_with("2.000000,"), "{first}");
            let times: Vec<&str> = s.estimates.lines().skip(1).map(|l| &l[..8]).collect();
            assert_eq!(times, ["2.500000"]);
        }
    }

    #[test]
    fn a_stream_resumed_into_a_firmware_that_ran_on_passes_over_the_rows_it_had_taken() {
        // The firmware's checkpoint is bin 0's (0.5 s), but it ran on (its host stopped, it did
        // not restart): it holds the rows up to 1.37 s, bin 1's first 38 in its open bin.
        let (csv, _) = log_of(300, &[]);
        let samples = samples_of(&csv);
        let stand_in = StandIn {
            held: samples[..138].to_vec(),
            ..StandIn::as_the_firmware()
        };
        let uncut = stream_with(&csv, StandIn::as_the_firmware(), ONE_AT_A_TIME);
        // From 1.38 s on the firmware answers as in the uncut stream; before, 1.00 to 1.37 s are
        // refused as taken already; bin 0 is not stepped again.
        let uncut_estimates: Vec<&str> = uncut.estimates.lines().collect();
        let want_estimates = [uncut_estimates[0], uncut_estimates[2]].join("\n") + "\n";
        let uncut_corrected: Vec<&str> = uncut.corrected.lines().collect();
        let mut want_corrected = vec![uncut_corrected[0].to_string()];
        want_corrected.extend((100..138).map(|k| {
            format!(
                "{}.{:02}0000,,,,rejected_time_not_increasing",
                k / 100,
                k % 100
            )
        }));
        want_corrected.extend(uncut_corrected[139..].iter().map(|l| l.to_string()));
        let want_corrected = want_corrected.join("\n") + "\n";
        for push in [None, Some((4, false))] {
            let s = stream_with(&csv, stand_in.clone(), resumed(push, 0.5));
            let nav = s.summary.unwrap().nav.unwrap();
            assert_eq!(nav.already_held, 38);
            assert_eq!(nav.binning.refused.total(), 0);
            assert_eq!(
                (nav.binning.rows, nav.binning.bins, nav.open_samples),
                (200, 1, 100)
            );
            assert_eq!(s.estimates, want_estimates);
            assert_eq!(s.corrected, want_corrected);
            assert!(
                nav.describe().join("\n").contains(
                    "rows the firmware had taken already, before this stream: 38 (refused as time_not_increasing, passed over)"
                ),
                "{:?}",
                nav.describe()
            );
        }
        // Not told it resumes, the host takes those refusals for a binning that differs.
        let sending = Sending {
            resume_after_s: Some(0.5),
            ..ONE_AT_A_TIME
        };
        let error = stream_with(&csv, stand_in, sending).summary.unwrap_err();
        assert!(
            error.contains("log line 102: the firmware refused the sample (time does not increase), the host's binner completes no bin"),
            "{error}"
        );
    }

    #[test]
    fn a_restart_in_a_pushed_stream_empties_the_host_s_bin_too() {
        // The firmware goes down after answering 1.95 s (request 196) and misses the four rows
        // sent meanwhile (the window), up to 1.99 s: bin 1 went with the firmware's RAM and is
        // never stepped; bin 2 starts the restarted firmware's binning, whose first sample
        // completes no bin (a host's binner still holding bin 1 would say it does).
        let (csv, _) = log_of(400, &[]);
        let stand_in = StandIn {
            restart_after: Some(196),
            down: 4,
            ..StandIn::as_the_firmware()
        };
        let s = stream_with(&csv, stand_in, pushed(4, false));
        let summary = s.summary.unwrap();
        let l = summary.link;
        assert_eq!((l.sent, l.answered, l.lost, l.restarts), (400, 396, 4, 1));
        let times: Vec<&str> = s.estimates.lines().skip(1).map(|l| &l[..8]).collect();
        assert_eq!(times, ["0.500000", "2.500000"]);
        let nav = summary.nav.unwrap();
        assert_eq!((nav.binning.bins, nav.open_samples), (2, 100));
        assert!(
            s.info
                .contains("the firmware restarted (it announced Ready)"),
            "{}",
            s.info
        );
    }
}
