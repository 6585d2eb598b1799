//! `host-sim stream --push`: rows sent without waiting for their answers, as a navigation computer
//! sends them (`--realtime`: at the log's own rate), up to a window of unanswered frames that half
//! the firmware's receive buffer holds. Answers are matched to their requests by their numbers
//! (link protocol 5). The rows go as samples or, with `--nav-rate`, as navigation-rate samples:
//! one loop for both, the kind of frame and what its answers become given by a
//! [`RowSink`] (a `NavSample` frame is at most as long as a `Sample` frame, so the window is the
//! same).

use super::sink::RowSink;
use super::{describe_exit, LinkSummary, Progress, StreamSummary, Target};
use crate::formats::log_csv::{LogLine, LogLines, RowFilter};
use crate::replay::sample_of;
use anyhow::bail;
use link_protocol::{Request, ResetCause, Response, SampleMsg, StatusReply, MAX_SAMPLE_FRAME};
use std::collections::VecDeque;
use std::io::Write;
use std::time::{Duration, Instant};

/// How `--push` sends.
#[derive(Clone, Debug)]
pub struct PushOptions {
    /// Send each row at the log's own rate (wall clock follows its time stamps).
    pub realtime: bool,
    /// Most sample frames sent and not yet answered.
    pub window: usize,
    /// Send this request just before the row with this index (counted from 0 among the rows
    /// streamed); for tests (the watchdog test's `Hang`).
    pub inject: Option<(u64, Request)>,
}

impl PushOptions {
    /// The default window: the sample frames that half the firmware's receive buffer holds (a DMA
    /// ring's reader sees every overrun only while at most half of it arrives unread), at least 1.
    pub fn default_window(status: &StatusReply) -> usize {
        (status.link.rx_buffer_bytes as usize / 2 / MAX_SAMPLE_FRAME).max(1)
    }
}

/// What a request in flight was.
#[derive(Clone, Copy)]
enum Sent {
    /// A row's sample (of the sink's kind): its log line and the message.
    Sample { line: LogLine, msg: SampleMsg },
    /// The status asked for after a restart.
    RestartStatus,
    /// The status asked for at the end.
    FinalStatus,
    /// Anything else (injected); its answer, if any, is passed over.
    Other,
}

/// The requests in flight and what the stream has counted so far.
struct Push {
    in_flight: VecDeque<(u32, Sent)>,
    link: LinkSummary,
    restart_status: Vec<StatusReply>,
    final_status: Option<StatusReply>,
    progress: Progress,
}

impl Push {
    fn samples_in_flight(&self) -> usize {
        self.in_flight
            .iter()
            .filter(|(_, s)| matches!(s, Sent::Sample { .. }))
            .count()
    }

    fn send(&mut self, target: &mut Target, request: &Request, sent: Sent) -> anyhow::Result<()> {
        let seq = target.link.send(request)?;
        self.in_flight.push_back((seq, sent));
        if matches!(sent, Sent::Sample { .. }) {
            self.link.sent += 1;
        }
        Ok(())
    }

    /// Takes one answer, waiting until `deadline` (or the link's timeout), and writes the rows it
    /// settles: an answer to request `s` settles every earlier request still in flight as lost
    /// (the firmware answers in order). Returns false if nothing came before the deadline.
    fn settle<S: RowSink>(
        &mut self,
        target: &mut Target,
        sink: &mut S,
        info: &mut dyn Write,
        deadline: Option<Instant>,
    ) -> anyhow::Result<bool> {
        let received = match deadline {
            Some(d) => target.link.receive_until(d),
            None => target.link.receive_numbered().map(Some),
        };
        let answer = match received {
            Ok(Some(a)) => a,
            Ok(None) => return Ok(false),
            Err(e) => return Err(e.context(describe_exit(&mut target.qemu))),
        };
        if let Response::Ready { .. } = answer.message {
            self.link.restarts += 1;
            sink.restarted();
            writeln!(
                info,
                "the firmware restarted (it announced Ready): asking for its status"
            )?;
            self.send(target, &Request::ReadStatus, Sent::RestartStatus)?;
            return Ok(true);
        }
        if !self.in_flight.iter().any(|(seq, _)| *seq == answer.seq) {
            bail!(
                "an answer numbered {} to no request in flight: {:?}",
                answer.seq,
                answer.message
            );
        }
        while let Some((seq, sent)) = self.in_flight.pop_front() {
            if seq != answer.seq {
                if matches!(sent, Sent::Sample { .. }) {
                    self.link.lost += 1;
                }
                continue;
            }
            match (sent, answer.message) {
                (Sent::Sample { line, msg }, response) => {
                    if let Some(warning) = sink.answered(&line, &msg, response)? {
                        self.progress
                            .bar
                            .suspend(|| eprintln!("warning: {warning}"));
                    }
                    self.link.answered += 1;
                }
                (Sent::RestartStatus, Response::Status(s)) => {
                    let cause = ResetCause::try_from(s.reset_cause).map_or("unknown", |c| c.name());
                    let checkpoint = s
                        .checkpoint_time_s
                        .map_or("no checkpoint".to_string(), |t| {
                            format!("the checkpoint of {t} s")
                        });
                    writeln!(
                        info,
                        "  reset cause {cause}; the firmware restored {checkpoint}"
                    )?;
                    self.restart_status.push(s);
                }
                (Sent::FinalStatus, Response::Status(s)) => self.final_status = Some(s),
                (Sent::Other, _) => {}
                (_, other) => bail!("the firmware answered ReadStatus with {other:?}"),
            }
            break;
        }
        Ok(true)
    }
}

/// Streams like [`crate::stream::stream_rows_one_at_a_time`], but sends without waiting for each
/// answer ([`PushOptions`]); `sink` says what the rows go as and where their answers go
/// ([`RowSink`]). Answers are matched to their requests by number. A `Ready` in the middle (the
/// firmware restarted: watchdog, power) is counted and told to the sink; the host asks for the
/// status (reset cause, restored checkpoint) and carries on. Rows whose answer never came are
/// counted as lost and left out of the outputs; a final status request settles every row sent
/// before it.
#[allow(clippy::too_many_arguments)]
pub fn stream_log_push<L: LogLines, S: RowSink>(
    target: &mut Target,
    lines: &mut L,
    mut filter: RowFilter,
    resume_after_s: Option<f64>,
    sink: &mut S,
    total_bytes: Option<u64>,
    options: &PushOptions,
    info: &mut dyn Write,
) -> anyhow::Result<StreamSummary> {
    let start = Instant::now();
    let mut push = Push {
        in_flight: VecDeque::new(),
        link: LinkSummary::default(),
        restart_status: Vec::new(),
        final_status: None,
        progress: Progress::new(total_bytes),
    };
    let mut streamed = 0u64;
    let mut first_time_s: Option<f64> = None;
    let window = options.window.max(1);
    while let Some(item) = lines.next() {
        let Some(line) = filter.admit(item, &mut |e| {
            push.progress
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
        if let Some((at, request)) = &options.inject {
            if *at == streamed {
                push.send(target, request, Sent::Other)?;
            }
        }
        if options.realtime {
            if let Some(due) = realtime_due(start, &mut first_time_s, line.row.time_s) {
                while Instant::now() < due {
                    push.settle(target, sink, info, Some(due))?;
                }
            }
        }
        while push.samples_in_flight() >= window {
            push.settle(target, sink, info, None)?;
        }
        let msg = SampleMsg::from(&sample_of(&line.row));
        let sent = Sent::Sample { line, msg };
        push.send(target, &sink.request(msg), sent)?;
        streamed += 1;
        // Whatever answers are there already, without waiting.
        while push.settle(target, sink, info, Some(Instant::now()))? {}
        push.progress.update(push.link.answered, lines.bytes_read());
    }
    push.send(target, &Request::ReadStatus, Sent::FinalStatus)?;
    let final_status = loop {
        push.settle(target, sink, info, None)?;
        if let Some(s) = push.final_status {
            break s;
        }
    };
    drop(push.progress);
    let (cost, nav) = sink.finish();
    Ok(StreamSummary {
        rows: push.link.answered,
        link: push.link,
        restart_status: push.restart_status,
        cost,
        final_status,
        wall: start.elapsed(),
        unreadable: filter,
        nav,
    })
}

/// When a row stamped `time_s` is due with `--realtime`: as long after `start` as it is after the
/// first stamp (`first_s`, set by the first finite one). `None`, sent at once: a stamp that is not
/// finite (the firmware rejects it), or so far ahead that no clock reaches it.
fn realtime_due(start: Instant, first_s: &mut Option<f64>, time_s: f64) -> Option<Instant> {
    if !time_s.is_finite() {
        return None;
    }
    let first = *first_s.get_or_insert(time_s);
    let after = Duration::try_from_secs_f64((time_s - first).max(0.0)).ok()?;
    start.checked_add(after)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::binned_lines::Lines;
    use crate::formats::estimates_csv::EstimatesWriter;
    use crate::formats::log_csv::LogReader;
    use crate::stream::cost::CostUnit;
    use crate::stream::link::FirmwareLink;
    use crate::stream::sink::SampleSink;
    use estimator_core::{Output, SampleError};
    use link_protocol::frame::MAX_FRAME;
    use link_protocol::{
        encode_frame, Counters, FrameAccumulator, LinkCounters, Numbered, RejectedReply,
        MAX_REQUEST_ENCODED, UNNUMBERED,
    };
    use std::os::unix::net::UnixStream;
    use std::path::Path;

    fn status(reset_cause: ResetCause) -> StatusReply {
        StatusReply {
            protocol_version: link_protocol::PROTOCOL_VERSION,
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
            checkpoint_time_s: Some(5.0),
            checkpoints_saved: 0,
            link: LinkCounters {
                rx_buffer_bytes: 1023,
                ..LinkCounters::default()
            },
            reset_cause: reset_cause as u8,
            clock_source: 2,
        }
    }

    /// A firmware on the other end of a socket: answers every sample with a rejection (enough to
    /// match answers), except the samples numbered in `drop`; after the request numbered
    /// `restart_after` it announces `Ready`, as after a watchdog reset.
    fn fake_firmware(mut port: UnixStream, drop: Vec<u32>, restart_after: Option<u32>) {
        use std::io::Read as _;
        let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
        let mut buf = [0u8; 256];
        let send = |port: &mut UnixStream, seq: u32, message: Response| {
            let mut out = [0u8; MAX_FRAME];
            let n = encode_frame(&Numbered { seq, message }, &mut out).unwrap();
            port.write_all(&out[..n]).unwrap();
        };
        let mut restarted = false;
        loop {
            let n = match port.read(&mut buf) {
                Ok(0) | Err(_) => return,
                Ok(n) => n,
            };
            for &b in &buf[..n] {
                let Some(Ok(request)) = rx.push_decode::<Numbered<Request>>(b) else {
                    continue;
                };
                match request.message {
                    Request::Sample(msg) if !drop.contains(&request.seq) => {
                        let error = SampleError::IrregularTimeStep;
                        let reply = RejectedReply::new(msg.time_s, &error, 7, Counters::default());
                        send(&mut port, request.seq, Response::Rejected(reply));
                    }
                    Request::Sample(_) => {}
                    Request::ReadStatus => {
                        let cause = if restarted {
                            ResetCause::Watchdog
                        } else {
                            ResetCause::PowerOn
                        };
                        send(&mut port, request.seq, Response::Status(status(cause)));
                    }
                    _ => {}
                }
                if Some(request.seq) == restart_after {
                    restarted = true;
                    send(
                        &mut port,
                        UNNUMBERED,
                        Response::Ready {
                            protocol_version: link_protocol::PROTOCOL_VERSION,
                        },
                    );
                }
            }
        }
    }

    /// Pushes `rows` rows at 1 s through the fake firmware; returns the summary, the estimates
    /// CSV and what the stream said.
    fn push(
        rows: u32,
        drop: Vec<u32>,
        restart_after: Option<u32>,
        window: usize,
    ) -> (StreamSummary, String, String) {
        push_at(rows, 1.0, false, drop, restart_after, window)
    }

    /// The same with rows `interval_s` apart, and `realtime`.
    fn push_at(
        rows: u32,
        interval_s: f64,
        realtime: bool,
        drop: Vec<u32>,
        restart_after: Option<u32>,
        window: usize,
    ) -> (StreamSummary, String, String) {
        let times: Vec<String> = (0..rows)
            .map(|k| (f64::from(k) * interval_s).to_string())
            .collect();
        push_times(&times, realtime, drop, restart_after, window)
    }

    /// The same with rows stamped `times` (as the log writes them).
    fn push_times(
        times: &[String],
        realtime: bool,
        drop: Vec<u32>,
        restart_after: Option<u32>,
        window: usize,
    ) -> (StreamSummary, String, String) {
        push_binned(times, None, realtime, drop, restart_after, window)
    }

    /// A target on the fake firmware (`drop`, `restart_after` as [`fake_firmware`] takes them).
    fn fake_target(drop: Vec<u32>, restart_after: Option<u32>) -> Target {
        let (host_end, firmware_end) = UnixStream::pair().unwrap();
        std::thread::spawn(move || fake_firmware(firmware_end, drop, restart_after));
        let reader = host_end.try_clone().unwrap();
        reader
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        Target {
            link: FirmwareLink::new(Box::new(reader), Box::new(host_end), Duration::from_secs(5)),
            qemu: None,
            unit: CostUnit::BoardCycles { counter_hz: 1 },
            boot_status: status(ResetCause::PowerOn),
        }
    }

    /// A log of constant rows stamped `times`, as the reader reads it.
    fn log_of(times: &[String]) -> LogReader<std::io::Cursor<Vec<u8>>> {
        let mut csv = String::from(
            "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n",
        );
        for t in times {
            csv.push_str(&format!("{t},10,20,30,40,1,2\n"));
        }
        LogReader::new(
            Path::new("test.csv"),
            std::io::Cursor::new(csv.into_bytes()),
        )
    }

    /// The same with the rows averaged into bins of `bin_interval_s` when given.
    fn push_binned(
        times: &[String],
        bin_interval_s: Option<f64>,
        realtime: bool,
        drop: Vec<u32>,
        restart_after: Option<u32>,
        window: usize,
    ) -> (StreamSummary, String, String) {
        let mut target = fake_target(drop, restart_after);
        let mut lines = Lines::new(log_of(times), bin_interval_s).unwrap();
        let mut writer = EstimatesWriter::new(Vec::new()).unwrap();
        let mut info = Vec::new();
        let options = PushOptions {
            realtime,
            window,
            inject: None,
        };
        let mut each = |_: &LogLine, _: &Result<Output, SampleError>| {};
        let mut sink = SampleSink::unchecked(&mut writer, &mut each);
        let summary = stream_log_push(
            &mut target,
            &mut lines,
            RowFilter::new(true),
            None,
            &mut sink,
            None,
            &options,
            &mut info,
        )
        .unwrap();
        let out = String::from_utf8(writer.finish().unwrap()).unwrap();
        (summary, out, String::from_utf8(info).unwrap())
    }

    fn times(csv: &str) -> Vec<u32> {
        csv.lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().parse::<f64>().unwrap() as u32)
            .collect()
    }

    #[test]
    fn every_answer_is_matched_to_its_row_and_unanswered_rows_are_counted_lost() {
        // Samples are numbered from 1 (row 0 is sample 1): drop the answers to rows 4, 5 and 20.
        let (summary, csv, _) = push(40, vec![5, 6, 21], None, 4);
        assert_eq!(
            (summary.link.sent, summary.link.answered, summary.link.lost),
            (40, 37, 3)
        );
        let want: Vec<u32> = (0..40).filter(|t| ![4, 5, 20].contains(t)).collect();
        assert_eq!(times(&csv), want);
        assert_eq!(summary.cost.steps, 37);
    }

    #[test]
    fn the_last_rows_lost_are_settled_by_the_final_status() {
        let (summary, csv, _) = push(10, vec![9, 10], None, 3);
        assert_eq!((summary.link.answered, summary.link.lost), (8, 2));
        assert_eq!(times(&csv), (0..8).collect::<Vec<_>>());
    }

    #[test]
    fn a_restart_is_reported_with_its_cause_and_the_stream_carries_on() {
        // The firmware announces Ready after sample 12 (row 11) and loses nothing else.
        let (summary, csv, info) = push(30, vec![], Some(12), 5);
        assert_eq!(summary.link.restarts, 1);
        assert_eq!(
            (summary.link.sent, summary.link.answered, summary.link.lost),
            (30, 30, 0)
        );
        assert_eq!(times(&csv), (0..30).collect::<Vec<_>>());
        assert!(
            info.contains("reset cause watchdog; the firmware restored the checkpoint of 5 s"),
            "{info}"
        );
        assert_eq!(summary.restart_status.len(), 1);
    }

    #[test]
    fn realtime_sends_at_the_log_s_own_rate() {
        // 11 rows 0.1 s apart: the last is sent 1 s after the first, not at once (the upper
        // bound leaves room for a loaded machine).
        let start = Instant::now();
        let (summary, _, _) = push_at(11, 0.1, true, vec![], None, 50);
        let wall = start.elapsed().as_secs_f64();
        assert_eq!((summary.link.answered, summary.link.lost), (11, 0));
        assert!((1.0..5.0).contains(&wall), "11 rows at 10 Hz took {wall} s");
        // Without it, 11 rows 10 s apart (100 s of log) go as fast as the link takes them.
        let start = Instant::now();
        push_at(11, 10.0, false, vec![], None, 50);
        let wall = start.elapsed().as_secs_f64();
        assert!(
            wall < 10.0,
            "without --realtime as fast as the link takes them: {wall} s"
        );
    }

    #[test]
    fn realtime_sends_a_stamp_no_clock_reaches_at_once() {
        // Not finite, or 1e300 s after the first: each sent at once, every one answered (it used
        // to panic converting the wait into a duration).
        let times: Vec<String> = ["-inf", "0", "0.1", "inf", "nan", "1e300", "0.2"]
            .iter()
            .map(|t| t.to_string())
            .collect();
        let start = Instant::now();
        let (summary, _, _) = push_times(&times, true, vec![], None, 50);
        let wall = start.elapsed().as_secs_f64();
        assert_eq!((summary.link.answered, summary.link.lost), (7, 0));
        assert!(wall < 5.0, "7 rows 0.2 s of log apart took {wall} s");
    }

    #[test]
    fn rows_at_200_hz_binned_are_pushed_one_sample_a_bin() {
        // 5 s at 200 Hz in bins of 1 s: 5 samples sent, stamped at the bins' centres.
        let times: Vec<String> = (0..1000u32)
            .map(|k| (f64::from(k) * 0.005).to_string())
            .collect();
        let (summary, pushed, _) = push_binned(&times, Some(1.0), false, vec![], None, 4);
        assert_eq!((summary.link.sent, summary.link.answered), (5, 5));
        let stamps: Vec<f64> = pushed
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(stamps, [0.5, 1.5, 2.5, 3.5, 4.5]);
        // The same one request at a time (`stream` without --push).
        let mut target = fake_target(vec![], None);
        let mut lines = Lines::new(log_of(&times), Some(1.0)).unwrap();
        let mut writer = EstimatesWriter::new(Vec::new()).unwrap();
        let summary = crate::stream::stream_log(
            &mut target,
            &mut lines,
            RowFilter::new(true),
            None,
            &mut writer,
            None,
            &mut |_, _| {},
        )
        .unwrap();
        assert_eq!(summary.rows, 5);
        assert_eq!(lines.binning().map(|b| (b.rows, b.bins)), Some((1000, 5)));
        let out = String::from_utf8(writer.finish().unwrap()).unwrap();
        assert_eq!(
            out, pushed,
            "one request at a time, the same answers as pushed"
        );
    }

    #[test]
    fn the_default_window_is_what_half_the_receive_buffer_holds() {
        let mut s = status(ResetCause::PowerOn);
        s.link.rx_buffer_bytes = 2048;
        assert_eq!(PushOptions::default_window(&s), 23);
        s.link.rx_buffer_bytes = 1023;
        assert_eq!(PushOptions::default_window(&s), 11);
        s.link.rx_buffer_bytes = 0;
        assert_eq!(PushOptions::default_window(&s), 1);
    }
}
