//! What a replay records of its rows for the subcommand, besides the estimates CSV: the report
//! against the truth, the timeline of a report page and every step. The same for a log the
//! firmware steps (`stream`), whose answers carry no counters and no residuals.

use super::replayer::StepView;
use super::Step;
use crate::report::timeline::{Timeline, TimelineRow};
use crate::report::{Report, ReportBuilder, TruthRows};
use crate::sim::scenario::Row;
use estimator_core::time_grid::Placement;
use estimator_core::{Counters, Output, Real, SampleError};

/// The records kept as the rows come.
pub struct Records<'a> {
    report: Option<ReportBuilder<'a>>,
    timeline: Option<Timeline>,
    steps: Option<Vec<Step>>,
}

/// What was recorded, at the end.
pub struct Recorded {
    /// Against the truth, when there was one.
    pub report: Option<Report>,
    /// What a report page draws, when asked for.
    pub timeline: Option<Timeline>,
    /// Every row's result, when asked for; empty otherwise.
    pub steps: Vec<Step>,
}

impl<'a> Records<'a> {
    /// Records judging the rows against `truth` (if any), keeping a timeline and every step when
    /// asked.
    pub fn new(truth: Option<TruthRows<'a>>, timeline: bool, steps: bool) -> Records<'a> {
        Records {
            report: truth.map(ReportBuilder::new),
            timeline: timeline.then(Timeline::new),
            steps: steps.then(Vec::new),
        }
    }

    /// A row the host's estimator stepped: its counters and residuals go into the timeline.
    pub fn observe_step(&mut self, view: &StepView) {
        let (counters, residuals_rad) = match self.timeline {
            Some(_) => (Some(view.estimator.counters()), view.residuals_rad()),
            None => (None, None),
        };
        self.observe(
            &view.line.row,
            view.result,
            view.placement,
            counters,
            residuals_rad,
        );
    }

    /// A row and its result; `placement`: where an accepted row fell on the sample grid;
    /// `counters` and `residuals_rad` when the estimator is at hand.
    pub fn observe(
        &mut self,
        row: &Row,
        result: &Result<Output, SampleError>,
        placement: Option<Placement>,
        counters: Option<Counters>,
        residuals_rad: Option<[Real; 4]>,
    ) {
        let truth = self.report.as_mut().and_then(|r| r.observe(row, result));
        if let Some(t) = self.timeline.as_mut() {
            t.observe(TimelineRow {
                row,
                result,
                placement,
                counters,
                residuals_rad,
                truth,
            });
        }
        if let Some(steps) = self.steps.as_mut() {
            steps.push(Step {
                time_s: row.time_s,
                result: *result,
            });
        }
    }

    /// What was recorded; `interval_s` is the log's sample interval (as the estimator used it).
    pub fn finish(self, interval_s: f64) -> Recorded {
        Recorded {
            report: self.report.map(|r| r.finish(interval_s)),
            timeline: self.timeline,
            steps: self.steps.unwrap_or_default(),
        }
    }
}
