//! What a stream sends each log row as, and what it makes of the answers: the one place where a
//! stream of samples (`Sample`, each answered with the estimator's step: a row of the estimates CSV
//! a row, [`SampleSink`]) and one of navigation-rate samples (`NavSample`, binned by the firmware:
//! [`super::nav::NavSink`]) differ. The loop that sends the rows one at a time
//! ([`super::stream_rows_one_at_a_time`]) and the one that sends them without waiting for the
//! answers ([`super::push::stream_log_push`]) take either.

use super::answer_of;
use super::cost::CostStats;
use super::nav::NavSummary;
use crate::formats::estimates_csv::EstimatesWriter;
use crate::formats::log_csv::LogLine;
use crate::formats::time_stamps::IntervalCheck;
use anyhow::Context;
use estimator_core::{Output, SampleError};
use link_protocol::{Request, Response, SampleMsg};
use std::io::Write;

/// A kind of sample a stream sends its rows as, and where their answers go.
pub trait RowSink {
    /// The request that carries a row's sample.
    fn request(&self, msg: SampleMsg) -> Request;

    /// Whether the row stamped `time_s` is one the firmware's checkpoint of `checkpoint_s` holds
    /// already: a stream that resumes after it (`--resume`) skips it.
    fn before_resume(&self, checkpoint_s: f64, time_s: f64) -> bool;

    /// Sees each row's stamp before it is sent; an error (the stamps' interval makes no sense for
    /// this kind of sample) stops the stream.
    fn check_stamp(&mut self, time_s: f64) -> anyhow::Result<()>;

    /// The firmware's `response` to the row `line`, sent as `msg`: checked and written. Returns a
    /// warning for people, if any.
    fn answered(
        &mut self,
        line: &LogLine,
        msg: &SampleMsg,
        response: Response,
    ) -> anyhow::Result<Option<String>>;

    /// The firmware restarted in the middle of the stream (it announced `Ready`): what it held in
    /// RAM is gone, the answers after this are the restarted firmware's.
    fn restarted(&mut self);

    /// At the end: the step costs for the summary and, for navigation-rate samples, what the
    /// firmware did with them.
    fn finish(&mut self) -> (CostStats, Option<NavSummary>);
}

/// Rows sent as samples (`Sample`): each answered with the estimator's step, written to the
/// estimates CSV, a row a row.
pub struct SampleSink<'a, W: Write> {
    writer: &'a mut EstimatesWriter<W>,
    each: &'a mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
    interval_check: Option<IntervalCheck>,
    cost: CostStats,
}

impl<'a, W: Write> SampleSink<'a, W> {
    /// A sink whose rows' stamps are checked ([`IntervalCheck`]): a stream one row at a time.
    pub fn checked(
        writer: &'a mut EstimatesWriter<W>,
        each: &'a mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
    ) -> Self {
        SampleSink {
            writer,
            each,
            interval_check: Some(IntervalCheck::new(None)),
            cost: CostStats::default(),
        }
    }

    /// A sink that sends the stamps as they are, unchecked: `--push`, whose rows go at the log's
    /// own rate whatever it is (the firmware refuses what its core refuses).
    pub fn unchecked(
        writer: &'a mut EstimatesWriter<W>,
        each: &'a mut dyn FnMut(&LogLine, &Result<Output, SampleError>),
    ) -> Self {
        SampleSink {
            interval_check: None,
            ..Self::checked(writer, each)
        }
    }
}

impl<W: Write> RowSink for SampleSink<'_, W> {
    fn request(&self, msg: SampleMsg) -> Request {
        Request::Sample(msg)
    }

    fn before_resume(&self, checkpoint_s: f64, time_s: f64) -> bool {
        time_s <= checkpoint_s
    }

    fn check_stamp(&mut self, time_s: f64) -> anyhow::Result<()> {
        if let Some(check) = self.interval_check.as_mut() {
            check.observe(time_s)?;
        }
        Ok(())
    }

    fn answered(
        &mut self,
        line: &LogLine,
        msg: &SampleMsg,
        response: Response,
    ) -> anyhow::Result<Option<String>> {
        let a = answer_of(msg, response).with_context(|| format!("log line {}", line.line))?;
        self.cost.add(a.step_cost_ticks);
        self.writer.write_step(line.row.time_s, &a.result)?;
        (self.each)(line, &a.result);
        Ok(None)
    }

    fn restarted(&mut self) {}

    fn finish(&mut self) -> (CostStats, Option<NavSummary>) {
        (std::mem::take(&mut self.cost), None)
    }
}
