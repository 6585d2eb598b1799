//! What a report draws of one replay or stream, kept as the rows come in bounded memory: the
//! rows are gathered into at most [`MAX_BUCKETS`] buckets of consecutive rows (two neighbours
//! merge and the bucket size doubles when they are full), so a 30-day log takes as little as an
//! hour's; the last [`TAIL_ROWS`] accepted rows are also kept whole, for the zoom on the last
//! rotation periods.
//!
//! Per bucket: the estimate and its 1-sigma at the bucket's last row, the error against the truth
//! (when there is one), the envelopes (least and greatest value) of the attitude signals, the
//! statuses seen (by their place in [`Status::ALL`], so a status added to the core shows without
//! a change here), rejected rows, lost samples, window restarts and clock steps. A list of the
//! first [`MAX_EVENTS`] events (status changes, gaps, restarts, clock steps) goes into the report's
//! table.
//!
//! The attitude signals, arcsec (heading, roll, pitch):
//! - `removed`: the oscillation the compensation took out, raw attitude minus corrected (eq (2)
//!   with the running estimate);
//! - with a truth: `before`, the oscillation eq (2) puts in for the true errors, and `after`, what
//!   is left after compensation, `before - removed` ([`crate::report::attitude_rms::residual_arcsec`]);
//! - `residual`: the windowed method's post-fit residuals of its correlation channels
//!   ([`crate::replay::replayer::StepView::residuals_rad`]), when the replay has them.

use crate::report::TruthAt;
use crate::sim::scenario::Row;
use estimator_core::time_grid::Placement;
use estimator_core::units::{rad_to_arcsec, wrap_deg};
use estimator_core::{Counters, Estimate, Output, SampleError, Status};
use std::collections::VecDeque;

/// Buckets kept at most (between half and all of them are in use once the log is long).
pub const MAX_BUCKETS: usize = 2048;
/// Accepted rows kept whole at the end of the log.
pub const TAIL_ROWS: usize = 8192;
/// Events listed at most.
pub const MAX_EVENTS: usize = 200;

/// Least and greatest value, and the sum, of `N` signals over some rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Envelope<const N: usize> {
    /// Least value of each signal.
    pub min: [f64; N],
    /// Greatest value of each signal.
    pub max: [f64; N],
    /// Sum of each signal, for [`Envelope::mean`].
    pub sum: [f64; N],
    /// Rows taken: those whose `N` values were all finite.
    pub rows: u64,
}

impl<const N: usize> Envelope<N> {
    fn add(this: &mut Option<Self>, v: &[f64; N]) {
        if v.iter().any(|x| !x.is_finite()) {
            return;
        }
        let e = this.get_or_insert(Envelope {
            min: *v,
            max: *v,
            sum: [0.0; N],
            rows: 0,
        });
        for (i, x) in v.iter().enumerate() {
            e.min[i] = e.min[i].min(*x);
            e.max[i] = e.max[i].max(*x);
            e.sum[i] += x;
        }
        e.rows += 1;
    }

    fn merge(this: &mut Option<Self>, other: &Option<Self>) {
        match (this.as_mut(), other) {
            (_, None) => {}
            (None, Some(o)) => *this = Some(*o),
            (Some(e), Some(o)) => {
                for i in 0..N {
                    e.min[i] = e.min[i].min(o.min[i]);
                    e.max[i] = e.max[i].max(o.max[i]);
                    e.sum[i] += o.sum[i];
                }
                e.rows += o.rows;
            }
        }
    }

    /// The mean of signal `i`.
    pub fn mean(&self, i: usize) -> f64 {
        self.sum[i] / self.rows.max(1) as f64
    }
}

/// The estimate in arcsec.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimateArcsec {
    /// The estimates of x1..x4, arcsec.
    pub x: [f64; 4],
    /// Their 1-sigma, arcsec.
    pub sigma: [f64; 4],
}

impl EstimateArcsec {
    /// The core's estimate `e` (rad) in arcsec.
    pub fn of(e: &Estimate) -> EstimateArcsec {
        EstimateArcsec {
            x: e.x_rad.map(|v| rad_to_arcsec(v as f64)),
            sigma: e.sigma_rad.map(|v| rad_to_arcsec(v as f64)),
        }
    }
}

/// Consecutive rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bucket {
    /// Time of the first row, s.
    pub t0_s: f64,
    /// Time of the last row, s.
    pub t1_s: f64,
    /// Rows in the bucket, accepted and rejected.
    pub rows: u64,
    /// The estimate on board at the last row that had one.
    pub estimate: Option<EstimateArcsec>,
    /// The true errors x1..x4 at the last row judged, arcsec.
    pub truth_x_arcsec: Option<[f64; 4]>,
    /// The estimate's error against the true errors (estimate minus truth) at the last row
    /// judged, arcsec.
    pub error_arcsec: Option<[f64; 4]>,
    /// Envelope of `removed` over the accepted rows (heading, roll, pitch), arcsec: the
    /// oscillation the compensation took out.
    pub removed_arcsec: Option<Envelope<3>>,
    /// Envelope of `before` over the accepted rows with a truth (heading, roll, pitch), arcsec:
    /// the oscillation eq (2) puts in for the true errors.
    pub before_arcsec: Option<Envelope<3>>,
    /// Envelope of `after` over the accepted rows with a truth (heading, roll, pitch), arcsec:
    /// what is left after compensation.
    pub after_arcsec: Option<Envelope<3>>,
    /// Envelope of the post-fit residuals of the four correlation channels over the rows that
    /// have them, arcsec.
    pub residual_arcsec: Option<Envelope<4>>,
    /// Statuses seen: bit `i` for `Status::ALL[i]`.
    pub statuses: u64,
    /// Rows the estimator rejected.
    pub rejected: u64,
    /// Samples lost before these rows, from where the rows fell on the sample grid.
    pub lost_samples: u64,
    /// Restarts of the moving average, from the estimator's counters (counted only where they
    /// are known row by row: [`Timeline::knows_restarts`]).
    pub window_restarts: u64,
    /// Clock jumps and steps back in the rows' stamps.
    pub clock_steps: u64,
}

impl Bucket {
    fn merge(&mut self, next: &Bucket) {
        if self.rows == 0 {
            *self = next.clone();
            return;
        }
        self.t1_s = next.t1_s;
        self.rows += next.rows;
        self.estimate = next.estimate.or(self.estimate);
        self.truth_x_arcsec = next.truth_x_arcsec.or(self.truth_x_arcsec);
        self.error_arcsec = next.error_arcsec.or(self.error_arcsec);
        Envelope::merge(&mut self.removed_arcsec, &next.removed_arcsec);
        Envelope::merge(&mut self.before_arcsec, &next.before_arcsec);
        Envelope::merge(&mut self.after_arcsec, &next.after_arcsec);
        Envelope::merge(&mut self.residual_arcsec, &next.residual_arcsec);
        self.statuses |= next.statuses;
        self.rejected += next.rejected;
        self.lost_samples += next.lost_samples;
        self.window_restarts += next.window_restarts;
        self.clock_steps += next.clock_steps;
    }

    /// Whether `status` was seen in these rows.
    pub fn saw(&self, status: Status) -> bool {
        status_bit(status).is_some_and(|b| self.statuses & b != 0)
    }
}

fn status_bit(status: Status) -> Option<u64> {
    Status::ALL
        .iter()
        .position(|s| *s == status)
        .filter(|i| *i < 64)
        .map(|i| 1u64 << i)
}

/// One accepted row kept whole (arcsec, heading, roll, pitch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TailRow {
    /// Time of the row, s.
    pub time_s: f64,
    /// The oscillation the compensation took out, raw attitude minus corrected, arcsec.
    pub removed_arcsec: [f64; 3],
    /// With a truth: the oscillation eq (2) puts in for the true errors, arcsec.
    pub before_arcsec: Option<[f64; 3]>,
    /// With a truth: what is left after compensation, `before - removed`, arcsec.
    pub after_arcsec: Option<[f64; 3]>,
}

/// Something that happened at a row.
#[derive(Clone, Debug, PartialEq)]
pub enum EventKind {
    /// The status changed (the first status too).
    Status {
        /// Name of the status before (`None` at the first status).
        from: Option<&'static str>,
        /// Name of the status from this row on.
        to: &'static str,
    },
    /// Samples lost before this row (from the stamps).
    Gap {
        /// Samples lost.
        lost: u64,
    },
    /// The moving average restarted (the estimator's counter; not known from a stream).
    WindowRestart,
    /// A clock jump or step back.
    ClockStep,
}

/// One line of the report's table of events.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// Time of the row it happened at, s.
    pub time_s: f64,
    /// What happened.
    pub kind: EventKind,
}

/// One row as the timeline takes it.
pub struct TimelineRow<'a> {
    /// The row, as read from the log or generated.
    pub row: &'a Row,
    /// The estimator's answer to the row: its output, or why the row was rejected.
    pub result: &'a Result<Output, SampleError>,
    /// Where an accepted row fell on the sample grid.
    pub placement: Option<Placement>,
    /// The estimator's counters after this row (a replay; a stream has them only at its end).
    pub counters: Option<Counters>,
    /// Post-fit residuals of the correlation channels, rad.
    pub residuals_rad: Option<[estimator_core::Real; 4]>,
    /// The truth the row was judged against.
    pub truth: Option<TruthAt>,
}

/// The bounded record of one run (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct Timeline {
    buckets: Vec<Bucket>,
    current: Bucket,
    rows_per_bucket: u64,
    tail: VecDeque<TailRow>,
    events: Vec<Event>,
    /// Events seen in all (the list keeps the first [`MAX_EVENTS`]).
    pub event_count: u64,
    last_status: Option<Status>,
    last_counters: Counters,
    held: Option<EstimateArcsec>,
    /// Time of the first row, s.
    pub first_time_s: Option<f64>,
    /// Time of the last row, s.
    pub last_time_s: Option<f64>,
    /// Time of the first row with an estimate, s.
    pub first_estimate_s: Option<f64>,
    /// Time of the first row whose status was `converged`, s.
    pub first_converged_s: Option<f64>,
    /// Whether any row had a truth.
    pub has_truth: bool,
    /// Whether any row had residuals.
    pub has_residuals: bool,
    /// Whether window restarts are known row by row (a replay) or not (a stream).
    pub knows_restarts: bool,
}

impl Timeline {
    /// An empty timeline, one row a bucket.
    pub fn new() -> Timeline {
        Timeline {
            rows_per_bucket: 1,
            ..Timeline::default()
        }
    }

    fn event(&mut self, time_s: f64, kind: EventKind) {
        self.event_count += 1;
        if self.events.len() < MAX_EVENTS {
            self.events.push(Event { time_s, kind });
        }
    }

    /// Takes one row.
    pub fn observe(&mut self, r: TimelineRow) {
        let t = r.row.time_s;
        if self.current.rows >= self.rows_per_bucket {
            self.close_bucket();
        }
        let b = &mut self.current;
        if b.rows == 0 {
            b.t0_s = t;
        }
        b.t1_s = t;
        b.rows += 1;
        self.first_time_s.get_or_insert(t);
        self.last_time_s = Some(t);
        match r.result {
            Ok(out) => self.observe_output(&r, out),
            Err(_) => self.current.rejected += 1,
        }
        if let Some(e) = self.held {
            self.current.estimate = Some(e);
            if let Some(truth) = &r.truth {
                self.current.truth_x_arcsec = Some(truth.errors_arcsec);
                self.current.error_arcsec =
                    Some(core::array::from_fn(|i| e.x[i] - truth.errors_arcsec[i]));
            }
        }
        if r.truth.is_some() {
            self.has_truth = true;
        }
        self.observe_placement(t, r.placement);
        if let Some(c) = r.counters {
            self.knows_restarts = true;
            let restarts = c
                .window_restarts
                .saturating_sub(self.last_counters.window_restarts);
            if restarts > 0 {
                self.current.window_restarts += u64::from(restarts);
                self.event(t, EventKind::WindowRestart);
            }
            self.last_counters = c;
        }
        if let Some(res) = r.residuals_rad {
            self.has_residuals = true;
            Envelope::add(
                &mut self.current.residual_arcsec,
                &res.map(|v| rad_to_arcsec(v as f64)),
            );
        }
    }

    /// An accepted row: its status (and the status's change), its estimate, its attitude.
    fn observe_output(&mut self, r: &TimelineRow, out: &Output) {
        let t = r.row.time_s;
        if let Some(bit) = status_bit(out.status) {
            self.current.statuses |= bit;
        }
        self.held = out.estimate.as_ref().map(EstimateArcsec::of);
        if self.held.is_some() {
            self.first_estimate_s.get_or_insert(t);
        }
        if out.status == Status::Converged {
            self.first_converged_s.get_or_insert(t);
        }
        if self.last_status != Some(out.status) {
            let from = self.last_status.map(|s| s.name());
            self.last_status = Some(out.status);
            self.event(
                t,
                EventKind::Status {
                    from,
                    to: out.status.name(),
                },
            );
        }
        self.observe_attitude(r, out);
    }

    /// Where an accepted row at `t` fell on the sample grid: the samples lost before it, a clock
    /// step.
    fn observe_placement(&mut self, t: f64, placement: Option<Placement>) {
        match placement {
            Some(Placement::OnGrid { intervals }) if intervals > 1 => {
                let lost = u64::from(intervals - 1);
                self.current.lost_samples += lost;
                self.event(t, EventKind::Gap { lost });
            }
            Some(Placement::ClockStep) => {
                self.current.clock_steps += 1;
                self.event(t, EventKind::ClockStep);
            }
            _ => {}
        }
    }

    fn observe_attitude(&mut self, r: &TimelineRow, out: &Output) {
        let raw = [r.row.heading_deg, r.row.roll_deg, r.row.pitch_deg];
        let corrected = [
            out.corrected.heading_rad,
            out.corrected.roll_rad,
            out.corrected.pitch_rad,
        ]
        .map(|v| (v as f64).to_degrees());
        let removed: [f64; 3] = core::array::from_fn(|a| {
            let d = raw[a] - corrected[a];
            (if a == 0 { wrap_deg(d) } else { d }) * 3600.0
        });
        Envelope::add(&mut self.current.removed_arcsec, &removed);
        let before = r.truth.map(|t| t.oscillation_deg.map(|d| d * 3600.0));
        let after = before.map(|b| core::array::from_fn(|a| b[a] - removed[a]));
        if let (Some(b), Some(a)) = (before, after) {
            Envelope::add(&mut self.current.before_arcsec, &b);
            Envelope::add(&mut self.current.after_arcsec, &a);
        }
        if self.tail.len() == TAIL_ROWS {
            self.tail.pop_front();
        }
        self.tail.push_back(TailRow {
            time_s: r.row.time_s,
            removed_arcsec: removed,
            before_arcsec: before,
            after_arcsec: after,
        });
    }

    fn close_bucket(&mut self) {
        self.buckets.push(std::mem::take(&mut self.current));
        if self.buckets.len() >= MAX_BUCKETS {
            let merged: Vec<Bucket> = self
                .buckets
                .chunks(2)
                .map(|pair| {
                    let mut b = pair[0].clone();
                    if let Some(next) = pair.get(1) {
                        b.merge(next);
                    }
                    b
                })
                .collect();
            self.buckets = merged;
            self.rows_per_bucket *= 2;
        }
    }

    /// The buckets, the last one possibly partial.
    pub fn buckets(&self) -> impl Iterator<Item = &Bucket> {
        self.buckets
            .iter()
            .chain((self.current.rows > 0).then_some(&self.current))
    }

    /// The accepted rows kept whole at the end.
    pub fn tail(&self) -> impl Iterator<Item = &TailRow> {
        self.tail.iter()
    }

    /// The first [`MAX_EVENTS`] events.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// The estimate at the end.
    pub fn final_estimate(&self) -> Option<EstimateArcsec> {
        self.held
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::units::arcsec_to_rad;
    use estimator_core::{Attitude, Field, Real};

    fn row(t: f64) -> Row {
        Row {
            time_s: t,
            rotation_deg: 0.0,
            platform_deg: 0.0,
            latitude_deg: 40.0,
            heading_deg: 10.0,
            roll_deg: 0.0,
            pitch_deg: 0.0,
        }
    }

    fn output(
        t: f64,
        status: Status,
        x: Option<f64>,
        roll_removed_arcsec: f64,
    ) -> Result<Output, SampleError> {
        Ok(Output {
            time_s: t,
            status,
            estimate: x.map(|x| Estimate {
                x_rad: [arcsec_to_rad(x) as Real; 4],
                sigma_rad: [arcsec_to_rad(1.0) as Real; 4],
            }),
            corrected: Attitude {
                heading_rad: 10f64.to_radians() as Real,
                roll_rad: -(arcsec_to_rad(roll_removed_arcsec) as Real),
                pitch_rad: 0.0,
            },
            health: estimator_core::Health::NONE,
        })
    }

    #[test]
    fn memory_stays_bounded_and_envelopes_keep_the_extremes() {
        let mut tl = Timeline::new();
        let n = 3 * MAX_BUCKETS * 10;
        for k in 0..n {
            let t = k as f64;
            // A spike of 500 arcsec once, in the middle; 10 otherwise.
            let removed = if k == n / 2 { 500.0 } else { 10.0 };
            let status = if k < 100 {
                Status::WarmingUp
            } else {
                Status::Estimating
            };
            let result = output(t, status, (k >= 100).then_some(200.0), removed);
            tl.observe(TimelineRow {
                row: &row(t),
                result: &result,
                placement: None,
                counters: None,
                residuals_rad: None,
                truth: None,
            });
        }
        let buckets: Vec<&Bucket> = tl.buckets().collect();
        assert!(
            buckets.len() <= MAX_BUCKETS && buckets.len() >= MAX_BUCKETS / 2,
            "{}",
            buckets.len()
        );
        assert_eq!(
            buckets.iter().map(|b| b.rows).sum::<u64>(),
            n as u64,
            "every row in one bucket"
        );
        let peak = buckets
            .iter()
            .filter_map(|b| b.removed_arcsec)
            .map(|e| e.max[1])
            .fold(0.0, f64::max);
        assert!(
            (peak - 500.0).abs() < 1e-3,
            "the spike survives the merging: {peak}"
        );
        let (sum, rows) = buckets
            .iter()
            .filter_map(|b| b.removed_arcsec)
            .fold((0.0, 0), |(s, n), e| (s + e.sum[1], n + e.rows));
        assert_eq!(rows, n as u64);
        assert!(
            (sum / rows as f64 - (10.0 + 490.0 / n as f64)).abs() < 1e-6,
            "means over merged buckets"
        );
        assert!(
            buckets[0].saw(Status::WarmingUp) && !buckets.last().unwrap().saw(Status::WarmingUp)
        );
        assert_eq!(tl.tail().count(), TAIL_ROWS);
        assert_eq!(tl.first_estimate_s, Some(100.0));
        let changes: Vec<_> = tl
            .events()
            .iter()
            .filter(|e| matches!(e.kind, EventKind::Status { .. }))
            .collect();
        assert_eq!(changes.len(), 2, "warming_up, then estimating");
    }

    #[test]
    fn gaps_clock_steps_restarts_rejections_and_truth_are_recorded() {
        let mut tl = Timeline::new();
        let truth = TruthAt {
            errors_arcsec: [190.0; 4],
            oscillation_deg: [0.0, 15.0 / 3600.0, 0.0],
        };
        let steps: [(f64, Option<Placement>, u32); 4] = [
            (0.0, None, 0),
            (4.0, Some(Placement::OnGrid { intervals: 4 }), 1),
            (5.0, Some(Placement::ClockStep), 2),
            (6.0, None, 2),
        ];
        for (t, placement, restarts) in steps {
            let result = if t == 6.0 {
                Err(SampleError::NonFinite(Field::Roll))
            } else {
                output(t, Status::Estimating, Some(200.0), 10.0)
            };
            let counters = Counters {
                window_restarts: restarts,
                ..Counters::default()
            };
            tl.observe(TimelineRow {
                row: &row(t),
                result: &result,
                placement,
                counters: Some(counters),
                residuals_rad: Some([0.0; 4]),
                truth: Some(truth),
            });
        }
        let total = tl.buckets().fold(Bucket::default(), |mut acc, b| {
            acc.merge(b);
            acc
        });
        assert_eq!(
            (
                total.lost_samples,
                total.clock_steps,
                total.window_restarts,
                total.rejected
            ),
            (3, 1, 2, 1)
        );
        let e = total.error_arcsec.unwrap();
        assert!((e[0] - 10.0).abs() < 1e-3, "{e:?}");
        let after = total.after_arcsec.unwrap();
        assert!(
            (after.max[1] - 5.0).abs() < 1e-3,
            "15 arcsec put in, 10 removed: {after:?}"
        );
        assert!(tl.has_truth && tl.has_residuals && tl.knows_restarts);
        assert_eq!(
            tl.events()
                .iter()
                .filter(|e| e.kind == EventKind::WindowRestart)
                .count(),
            2
        );
    }
}
