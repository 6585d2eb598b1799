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

use super::cost::CostStats;
use super::{answer_of, Progress, StreamSummary, Target};
use crate::formats::binned_lines::BinningSummary;
use crate::formats::corrected_csv::CorrectedWriter;
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::{LogLine, LogLines, RowFilter};
use crate::formats::time_stamps::IntervalCheck;
use crate::replay::{row_of, sample_of};
use anyhow::{bail, Context};
use estimator_core::binning::{Binner, DEFAULT_BIN_INTERVAL_S};
use estimator_core::{Output, RejectCounts, Sample, SampleError};
use link_protocol::{BinOutcome, NavReply, RejectedReply, Request, Response, SampleMsg};
use std::io::Write;
use std::time::Instant;

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
    summary: NavSummary,
}

impl Default for NavFollower {
    fn default() -> Self {
        NavFollower {
            binner: Binner::default(),
            bin_last_line: 0,
            summary: NavSummary::new(),
        }
    }
}

impl NavFollower {
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
            Response::Nav(reply) => {
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

/// Streams the log's rows through the target one at a time, each as a `NavSample` sent when the
/// last is answered (see the module doc). Unreadable rows go through `filter` as in
/// [`crate::stream::stream_log`]; the stamps are checked as a log binned into 1 s is
/// ([`IntervalCheck::binned`]: 5 ms to 10 s, at most a bin).
pub fn stream_log_nav<L: LogLines, W: Write, C: Write>(
    target: &mut Target,
    lines: &mut L,
    mut filter: RowFilter,
    out: &mut NavOutputs<'_, W, C>,
    total_bytes: Option<u64>,
) -> anyhow::Result<StreamSummary> {
    let start = Instant::now();
    let progress = Progress::new(total_bytes);
    let mut follower = NavFollower::default();
    let mut rows = 0u64;
    let mut interval_check = IntervalCheck::binned(DEFAULT_BIN_INTERVAL_S);
    let mut refused = 0usize;
    while let Some(item) = lines.next() {
        let Some(line) = filter.admit(item, &mut |e| {
            progress
                .bar
                .suspend(|| eprintln!("warning: {e} (row skipped)"));
        })?
        else {
            continue;
        };
        interval_check.observe(line.row.time_s)?;
        let sample = sample_of(&line.row);
        let at = || format!("log line {}", line.line);
        let response = target
            .request(&Request::NavSample(SampleMsg::from(&sample)))
            .with_context(at)?;
        if let Some(e) = follower
            .answered(&line, &sample, response, out)
            .with_context(at)?
        {
            refused += 1;
            if refused <= REFUSED_REPORTED {
                progress.bar.suspend(|| {
                    eprintln!(
                        "warning: log line {}: the firmware refused the sample: {e}",
                        line.line
                    )
                });
            }
        }
        rows += 1;
        progress.update(rows, lines.bytes_read());
    }
    drop(progress);
    let final_status = target.status()?;
    let nav = follower.finish();
    let cost = nav.bin_cost;
    Ok(StreamSummary::one_at_a_time(
        rows,
        cost,
        final_status,
        start.elapsed(),
        filter,
        Some(nav),
    ))
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
    use crate::formats::log_csv::LogReader;
    use crate::stream::cost::CostUnit;
    use crate::stream::link::FirmwareLink;
    use estimator_core::{Config, Estimator, RejectReason};
    use link_protocol::frame::MAX_FRAME;
    use link_protocol::{
        encode_frame, Counters, FrameAccumulator, LinkCounters, Numbered, StatusReply, StepReply,
        MAX_REQUEST_ENCODED, PROTOCOL_VERSION,
    };
    use std::os::unix::net::UnixStream;
    use std::path::Path;
    use std::time::Duration;

    /// How the stand-in firmware answers a navigation-rate sample.
    #[derive(Clone, Copy, PartialEq)]
    enum Behaviour {
        /// As the firmware does: the core's `Binner`, `step` and `compensate`.
        AsTheFirmware,
        /// Never completes a bin (a firmware whose binning differs from the host's).
        NeverCompletesABin,
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
            link: LinkCounters::default(),
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

    /// A firmware on the other end of a socket, answering as `behaviour` says.
    fn stand_in_firmware(mut port: UnixStream, behaviour: Behaviour) {
        use std::io::Read as _;
        let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
        let mut binner = Binner::default();
        let mut estimator = Box::new(Estimator::new(Config::default()).unwrap());
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
                let message = match request.message {
                    Request::NavSample(msg) => {
                        answer(&mut binner, &mut estimator, &Sample::from(&msg), behaviour)
                    }
                    Request::ReadStatus => Response::Status(status()),
                    _ => continue,
                };
                let mut out = [0u8; MAX_FRAME];
                let seq = request.seq;
                let n = encode_frame(&Numbered { seq, message }, &mut out).unwrap();
                port.write_all(&out[..n]).unwrap();
            }
        }
    }

    /// Streams the log `csv` through the stand-in firmware; returns the summary (or the error,
    /// as the tool prints it), the estimates CSV and the corrected-attitude CSV.
    fn stream(csv: &str, behaviour: Behaviour) -> (Result<StreamSummary, String>, String, String) {
        let (host_end, firmware_end) = UnixStream::pair().unwrap();
        std::thread::spawn(move || stand_in_firmware(firmware_end, behaviour));
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
        let mut out = NavOutputs {
            estimates: &mut estimates,
            corrected: Some(&mut corrected),
            each: &mut |_, _| {},
        };
        let filter = RowFilter::new(true);
        let summary = stream_log_nav(&mut target, &mut lines, filter, &mut out, None)
            .map_err(|e| format!("{e:#}"));
        let text = |b: Vec<u8>| String::from_utf8(b).unwrap();
        (
            summary,
            text(estimates.finish().unwrap()),
            text(corrected.finish().unwrap()),
        )
    }

    /// 3 s of rows at 100 Hz; `bad` rows (time, roll) inserted after the row of that index.
    /// Returns the log and the file lines of the inserted rows.
    fn log(bad: &[(usize, &str, &str)]) -> (String, Vec<usize>) {
        let mut rows: Vec<String> = (0..300u32)
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
}
