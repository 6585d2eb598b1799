//! `host-sim commission LOG`: whether a log's conventions fit the model of eq (2).
//!
//! The log is read once (as `estimate` reads it: the same reader, time stamps and options) and
//! every row is handed to one replay per [`Variant`]: the log as it is, and the log with one of its
//! conventions changed (an angle negated, roll and pitch exchanged, the rotation angle read as
//! radians). Each replay runs the core's windowed method to the end of the log, as `estimate`
//! does (the evidence grows with the log, below; a fit keeps 104 bytes a rotation period, and the
//! seven fits together take about as long as one `estimate` of the log: docs/interface.md); the
//! replays run side by side (rayon), a batch of rows at a time.
//!
//! # The evidence: the unexplained share each fit leaves
//! Each fit's post-fit residual `z - H x` of its four correlation channels
//! ([`StepView::residuals_rad`], what the report's residual plot shows) is averaged over each
//! rotation period from the first estimate on; the **residual power** is the median, over the
//! later half of the periods, of the square of those period means (mean over the channels,
//! arcsec^2). A period's mean takes out the sway's leak into the window (it falls like `1 / N`
//! over `N` windows); what is left is what eq (2) with the fit's errors cannot explain. Under a
//! wrong convention eq (2) can still take up the oscillation at the start (a sign becomes the
//! errors' sign, a phase their mix), but not as the platform angle turns at the Earth rate: the
//! misfit grows with the angle's span, so the later half of the log holds it at its largest, and
//! the first periods, which hold the filter's own settling, are left out. The median, not the
//! mean: a turn's transient lifts a few periods, not the log (sea logs with turns heeling 3 deg
//! are told: docs/interface.md).
//!
//! The **measurement power** is the same of the measurement `z` itself, and the decision compares
//! the **unexplained share**, the residual power over the measurement power, among the fits that
//! found eq (2)'s oscillation: a measurement power at least [`FOUND_POWER_SHARE`] (1/3) of the
//! largest among the log's fits. The sign and exchange variants move the oscillation between
//! channels and phases without removing it: their measurement powers agree within 2 %
//! (`bash scripts/commission-study.sh` and the lines of docs/interface.md). Read as radians, a
//! rotation angle in degrees turns 57 times too fast and the references no longer correlate with
//! the oscillation: that fit finds at most 0.12 of the largest measurement power in the same
//! lines (1e-4 to 4e-3 with the scenarios' errors), and leaves little because there is little to
//! leave: on a paper log of 20,000 s (`host-sim generate --scenario paper --duration 20000 --out
//! paper.csv; host-sim commission paper.csv`) its residual power is 0.053 arcsec^2 against the
//! log's own 0.010, and on the study's paper logs the residual power alone put that wrong fit
//! below the right one (smallest ratio 0.003); the unexplained share of the fits compared never
//! did.
//!
//! # The decision rule
//! With `F` = [`DECISION_FACTOR`] = 10 and `u(v)` the unexplained share of variant `v` (infinite
//! for a fit without an estimate, without a period of residuals, or that did not find the
//! oscillation):
//!
//! - a variant `v` is named when `F u(v) <= u(as-is)` (it leaves at most a tenth of what the log
//!   as it is leaves) and `u(v) < F u(best)`, `best` the variant that leaves least: every variant
//!   within a factor `F` of the best is named with it;
//! - otherwise the conventions are **ok** when every variant leaves at least `F` times what the
//!   log as it is leaves: `u(v) >= F u(as-is)`;
//! - otherwise the fits are too close to tell (**undecided**): a longer log tells.
//!
//! `F` from the measured spread (`bash scripts/commission-study.sh`: 20 seeds, logs of `generate`
//! with the scenarios' errors of 150-300 arcsec, each rewritten into every variant): the smallest
//! ratio of a wrong fit's unexplained share to the right one's was, at sea, 2.1 at 2,000 s, 8.6
//! at 2,500 s, 25 at 3,000 s and 89 at 4,000 s; on the paper scenario 9.9, 35, 185 and 469. Of
//! its 1,120 verdicts none named a wrong variant (nor did any of the other lines in
//! docs/interface.md); with `F` = 10 the right one was named in every verdict from 3,000 s at sea
//! (with its twin for roll-negated and pitch-negated, below) and from 2,500 s on the paper
//! scenario, while at sea 9 of 140 were undecided at 2,000 s and 3 at 2,500 s, and 4 and 2 named
//! it with another variant. The misfit shrinks with the errors: with errors ten times smaller
//! (15-30 arcsec) the sea needs 16,000 s (smallest ratio 27 over 5 seeds; 2.1 at 4,000 s).
//!
//! # What the residuals cannot tell
//! Roll and pitch both negated is eq (2) with x1..x4 negated: a fit of roll and pitch cannot tell
//! a log with its roll negated under `roll-negated` (the log as it should be) from the same log
//! under `pitch-negated` (roll and pitch both negated). Their fits are the same to rounding, and
//! both are named, unless the heading tells: eq (2)'s heading oscillation changes sign with the
//! errors, so the heading, regressed on it for each fit's estimate ([`Fit::heading_agreement`]),
//! gives +1 for the right one and -1 for the other. It is taken when one is within 0.5 of +1 and
//! the other of -1, each at least [`HEADING_SIGMAS`] standard errors from 0 over at least
//! [`MIN_HEADING_PERIODS`] periods: on the paper scenario (a steady heading) from 2,500 s in all
//! of the study's logs; at sea the ship's course changes (a weave of 0.5 deg/s at a 600 s
//! period, next to the rotation's 480 s) swamp it (coefficients of tens, give or take hundreds)
//! and both are named. This assumes the heading's own sense is the model's; a log whose roll and
//! pitch are both negated fits as it is, and the same test of the heading says so in a note.

use crate::exit_status::RunEnd;
use crate::formats::log_csv::{self, LogError, LogLine, RowFilter};
use crate::formats::read_ahead::{read_ahead, READ_AHEAD_BATCH};
use crate::replay::replayer::{Replayer, StepView};
use crate::replay::summary::pattern_summary;
use crate::replay::{Replay, ReplayError};
use crate::sim::scenario::Row;
use estimator_core::units::rad_to_arcsec;
use estimator_core::Config;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// The factor by which a variant's unexplained share must be below the log's as it is to be
/// named, and above it for the log's conventions to be ok (see the module doc).
pub const DECISION_FACTOR: f64 = 10.0;

/// The share of the largest measurement power among a log's fits that a fit must reach to have
/// found eq (2)'s oscillation, and be compared (see the module doc).
pub const FOUND_POWER_SHARE: f64 = 1.0 / 3.0;

/// A way the log's conventions may differ from the model's: applied to every row before the fit.
/// Each is its own inverse except [`Variant::RotationInRadians`] (a log whose rotation column
/// holds radians fits under it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// The log as it is.
    AsIs,
    /// The rotation angle negated.
    RotationReversed,
    /// The roll negated.
    RollNegated,
    /// The pitch negated.
    PitchNegated,
    /// Roll and pitch exchanged.
    RollPitchSwapped,
    /// The platform angle negated.
    PlatformReversed,
    /// The rotation column read as radians (the model takes degrees: the column is converted).
    RotationInRadians,
}

impl Variant {
    /// Every variant, the log as it is first.
    pub const ALL: [Variant; 7] = [
        Variant::AsIs,
        Variant::RotationReversed,
        Variant::RollNegated,
        Variant::PitchNegated,
        Variant::RollPitchSwapped,
        Variant::PlatformReversed,
        Variant::RotationInRadians,
    ];

    /// The variant's name, as printed.
    pub fn name(self) -> &'static str {
        match self {
            Variant::AsIs => "as-is",
            Variant::RotationReversed => "rotation-reversed",
            Variant::RollNegated => "roll-negated",
            Variant::PitchNegated => "pitch-negated",
            Variant::RollPitchSwapped => "roll-pitch-swapped",
            Variant::PlatformReversed => "platform-reversed",
            Variant::RotationInRadians => "rotation-in-radians",
        }
    }

    /// The row as the variant reads it.
    pub fn apply(self, row: &mut Row) {
        match self {
            Variant::AsIs => {}
            Variant::RotationReversed => row.rotation_deg = -row.rotation_deg,
            Variant::RollNegated => row.roll_deg = -row.roll_deg,
            Variant::PitchNegated => row.pitch_deg = -row.pitch_deg,
            Variant::RollPitchSwapped => std::mem::swap(&mut row.roll_deg, &mut row.pitch_deg),
            Variant::PlatformReversed => row.platform_deg = -row.platform_deg,
            // Wrapped: a log of many turns in radians would otherwise hold angles beyond what
            // the core keeps precise.
            Variant::RotationInRadians => {
                row.rotation_deg = row.rotation_deg.to_degrees().rem_euclid(360.0);
            }
        }
    }
}

/// What the fit of one variant gave.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The variant the log was fitted under.
    pub variant: Variant,
    /// The replay's summary: rows, final status and estimate, what held it back.
    pub replay: Replay,
    /// Rotation periods of residuals averaged, from the first estimate on (the later half of them
    /// make the powers).
    pub periods: usize,
    /// The post-fit residual's power: the median over the later half of the periods of the square
    /// of its period means (mean over the four channels), arcsec^2 (`None` without a period of
    /// residuals).
    pub residual_power_arcsec2: Option<f64>,
    /// The measurement's power, as the residual's, arcsec^2.
    pub measurement_power_arcsec2: Option<f64>,
    /// The heading regressed on eq (2)'s heading oscillation for the fit's estimate over every
    /// period from the first estimate, and its standard error: 1 when the heading carries that oscillation, -1 when it
    /// carries its opposite (the errors' sign wrong), 0 when neither.
    pub heading_agreement: Option<(f64, f64)>,
    /// Whether the fit found eq (2)'s oscillation: its measurement power at least
    /// [`FOUND_POWER_SHARE`] of the largest among the fits of the log. A fit that did not is not
    /// compared (see "The evidence" in the module doc).
    pub oscillation_found: bool,
}

impl Fit {
    /// The share of the measurement's power the fit leaves unexplained (`None` without a period
    /// of residuals).
    pub fn unexplained(&self) -> Option<f64> {
        match (self.residual_power_arcsec2, self.measurement_power_arcsec2) {
            (Some(r), Some(m)) if m > 0.0 => Some(r / m),
            _ => None,
        }
    }

    /// [`Fit::unexplained`] when the fit found eq (2)'s oscillation, infinite otherwise: what the
    /// decision compares.
    fn score(&self) -> f64 {
        if self.oscillation_found {
            self.unexplained().unwrap_or(f64::INFINITY)
        } else {
            f64::INFINITY
        }
    }

    /// The largest final 1-sigma, arcsec.
    pub fn largest_sigma_arcsec(&self) -> Option<f64> {
        self.replay.final_estimate.map(|e| {
            e.sigma_rad
                .iter()
                .map(|s| rad_to_arcsec(f64::from(*s)))
                .fold(0.0, f64::max)
        })
    }
}

/// One rotation period's sums of a fit's measurement and post-fit residual, rad, and of the
/// heading (unwrapped, from the period's first row, rad) against eq (2)'s heading oscillation for
/// the fit's estimate at each row, rad: `[heading, oscillation, heading x oscillation,
/// oscillation^2]`.
#[derive(Clone, Copy, Debug, Default)]
struct Period {
    z: [f64; 4],
    residual: [f64; 4],
    heading: [f64; 4],
    n: u32,
}

impl Period {
    /// The covariance of the heading with the oscillation over the period, and the variance of
    /// the oscillation, rad^2.
    fn heading_moments(&self) -> (f64, f64) {
        let k = 1.0 / f64::from(self.n.max(1));
        let [h, o, ho, oo] = self.heading.map(|v| v * k);
        (ho - h * o, oo - o * o)
    }
}

/// What a fit keeps while its replay runs: one [`Period`] a rotation period (a 30-day log at a
/// 480 s period keeps 5,400 of 104 bytes).
#[derive(Default)]
struct Accumulator {
    current: Period,
    /// The last heading seen, deg, and the heading unwrapped from the period's first row, rad.
    heading: Option<(f64, f64)>,
    periods: Vec<Period>,
}

impl Accumulator {
    fn observe(&mut self, view: &StepView) {
        let Ok(out) = view.result else {
            return;
        };
        if out.estimate.is_none() {
            return;
        }
        let est = view.estimator;
        let (Some(residual), Some(m)) = (
            view.residuals_rad(),
            est.windowed().and_then(|w| w.window().sums().measurement()),
        ) else {
            return;
        };
        let row = &view.line.row;
        let unwrapped = match self.heading {
            Some((last, from_first)) if self.current.n > 0 => {
                from_first
                    + ((row.heading_deg - last + 180.0).rem_euclid(360.0) - 180.0).to_radians()
            }
            _ => 0.0,
        };
        self.heading = Some((row.heading_deg, unwrapped));
        let x = out.estimate.map_or([0.0; 4], |e| e.x_rad.map(f64::from));
        let oscillation = crate::sim::scenario::oscillation_rad(
            &x,
            row.rotation_deg.to_radians(),
            row.platform_deg.to_radians(),
            row.latitude_deg.to_radians(),
        )[0];
        let p = &mut self.current;
        p.n += 1;
        p.heading[0] += unwrapped;
        p.heading[1] += oscillation;
        p.heading[2] += unwrapped * oscillation;
        p.heading[3] += oscillation * oscillation;
        for ch in 0..4 {
            p.z[ch] += f64::from(m.z[ch]);
            p.residual[ch] += f64::from(residual[ch]);
        }
        // One period of rows (as learned or pinned; 1 until both are known).
        let rows = match (est.rotation().period_s, est.sample_interval_s()) {
            (Some(t), Some(d)) if d > 0.0 => (t / d).round().max(1.0) as u32,
            _ => 1,
        };
        if p.n >= rows {
            self.periods.push(std::mem::take(p));
        }
    }

    fn finish(self, variant: Variant, replay: Replay) -> Fit {
        let later = &self.periods[self.periods.len() / 2..];
        // The median, not the mean: a turn's transient lifts a few periods, not the log.
        let power = |of: &dyn Fn(&Period) -> [f64; 4]| -> Option<f64> {
            if later.is_empty() {
                return None;
            }
            let mut sq: Vec<f64> = later
                .iter()
                .map(|p| {
                    let k = 1.0 / f64::from(p.n.max(1));
                    of(p)
                        .iter()
                        .map(|v| rad_to_arcsec(v * k).powi(2))
                        .sum::<f64>()
                        / 4.0
                })
                .collect();
            sq.sort_by(f64::total_cmp);
            Some(sq[sq.len() / 2])
        };
        // The heading's sign does not grow with the log, as the misfit does: every period from the
        // first estimate counts.
        let moments: Vec<(f64, f64)> = self.periods.iter().map(Period::heading_moments).collect();
        let variance: f64 = moments.iter().map(|m| m.1).sum();
        // A standard error needs a few periods' coefficients.
        let heading_agreement =
            (variance > 0.0 && moments.len() >= MIN_HEADING_PERIODS).then(|| {
                let c = moments.iter().map(|m| m.0).sum::<f64>() / variance;
                // The scatter of the periods' own coefficients about it.
                let n = moments.len() as f64;
                let mean_var = variance / n;
                let spread = moments
                    .iter()
                    .map(|m| ((m.0 - c * m.1) / mean_var).powi(2))
                    .sum::<f64>()
                    / (n - 1.0).max(1.0);
                (c, (spread / n).sqrt())
            });
        Fit {
            variant,
            heading_agreement,
            oscillation_found: false,
            periods: self.periods.len(),
            residual_power_arcsec2: power(&|p| p.residual),
            measurement_power_arcsec2: power(&|p| p.z),
            replay,
        }
    }
}

/// One variant's replay as the rows come.
struct Fitting {
    variant: Variant,
    replayer: Replayer<'static>,
    acc: Accumulator,
    /// The error that ended the replay, if one did.
    failed: Option<ReplayError>,
}

impl Fitting {
    fn push_all(&mut self, batch: &[Result<LogLine, LogError>]) {
        for item in batch {
            if self.failed.is_some() {
                return;
            }
            let item = item.clone().map(|mut line| {
                self.variant.apply(&mut line.row);
                line
            });
            let acc = &mut self.acc;
            let pushed = self.replayer.push(item, &mut |_| {}, &mut |view| {
                acc.observe(view);
                Ok(())
            });
            if let Err(e) = pushed {
                self.failed = Some(e);
            }
        }
    }
}

/// Fits the log under each of `variants` (the first should be [`Variant::AsIs`]: the errors and
/// the unreadable rows are its replay's; the others see the same rows). `strict`: the first
/// unreadable row refuses the log. Errors as `estimate`'s: a log that cannot be read or is refused
/// (exit status 1), no row read ([`RunEnd::NothingRead`], 3).
pub fn fit_variants(
    log: &Path,
    config: Config,
    strict: bool,
    variants: &[Variant],
) -> anyhow::Result<Vec<Fit>> {
    let mut fits = Vec::with_capacity(variants.len());
    for &variant in variants {
        fits.push(Fitting {
            variant,
            replayer: Replayer::new(config, &[], RowFilter::new(strict))?,
            acc: Accumulator::default(),
            failed: None,
        });
    }
    let lines = log_csv::LogReader::open(log)?;
    read_ahead(lines, |items| {
        // Batches of the reader's own size: once every replay has stopped on an error, no more
        // rows are asked for than the reader has handed over (standard input held open never
        // blocks a refused log).
        let mut batch = Vec::with_capacity(READ_AHEAD_BATCH);
        loop {
            batch.clear();
            batch.extend(items.take(READ_AHEAD_BATCH));
            if batch.is_empty() {
                break;
            }
            fits.par_iter_mut().for_each(|f| f.push_all(&batch));
            if fits.iter().all(|f| f.failed.is_some()) {
                break;
            }
        }
    });
    let mut out = Vec::with_capacity(fits.len());
    for f in fits {
        if let Some(e) = f.failed {
            return Err(e.for_people(log, None));
        }
        out.push(f.acc.finish(f.variant, f.replayer.finish()));
    }
    let top = out
        .iter()
        .filter_map(|f| f.measurement_power_arcsec2)
        .fold(0.0, f64::max);
    for f in &mut out {
        f.oscillation_found = f
            .measurement_power_arcsec2
            .is_some_and(|m| top > 0.0 && m >= FOUND_POWER_SHARE * top);
    }
    if let Some(first) = out.first() {
        first.replay.check_rows_read(log)?;
    }
    Ok(out)
}

/// What the fits say of the log's conventions.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// The log as it is fits best, every variant at least [`DECISION_FACTOR`] times worse.
    Ok,
    /// These variants fit at least [`DECISION_FACTOR`] times better than the log as it is, and
    /// within that factor of each other (in [`Variant::ALL`]'s order).
    Variants(Vec<Variant>),
    /// The fits are too close to tell (or none reached an estimate): a longer log tells.
    Undecided,
}

/// Whether the heading carries eq (2)'s heading oscillation for the fit's estimate: its
/// coefficient within 0.5 of 1 and at least [`HEADING_SIGMAS`] standard errors from 0.
fn heading_agrees(f: &Fit) -> bool {
    matches!(f.heading_agreement, Some((c, se)) if (c - 1.0).abs() < 0.5 && c > HEADING_SIGMAS * se)
}

/// Whether the heading carries the opposite of eq (2)'s heading oscillation for the fit's
/// estimate (its coefficient within 0.5 of -1, as [`heading_agrees`]).
fn heading_opposes(f: &Fit) -> bool {
    matches!(f.heading_agreement, Some((c, se)) if (c + 1.0).abs() < 0.5 && -c > HEADING_SIGMAS * se)
}

/// Periods a fit's heading coefficient needs to be given.
pub const MIN_HEADING_PERIODS: usize = 3;

/// Standard errors from zero the heading's coefficient needs to count (see [`Fit::heading_agreement`];
/// the periods' coefficients are taken as independent, which the ship's slow course changes make
/// them not quite).
pub const HEADING_SIGMAS: f64 = 5.0;

/// The decision rule of the module doc; `fits[0]` is the log as it is.
pub fn verdict(fits: &[Fit]) -> Verdict {
    let Some((as_is, variants)) = fits.split_first() else {
        return Verdict::Undecided;
    };
    let best = variants
        .iter()
        .map(Fit::score)
        .fold(f64::INFINITY, f64::min);
    let mut named: Vec<&Fit> = variants
        .iter()
        .filter(|f| {
            let u = f.score();
            u.is_finite() && DECISION_FACTOR * u <= as_is.score() && u < DECISION_FACTOR * best
        })
        .collect();
    // Roll and pitch cannot tell roll-negated from pitch-negated; the heading can, when it
    // carries eq (2)'s oscillation for one and its opposite for the other.
    if let [a, b] = named[..] {
        if twins(a.variant, b.variant) {
            if heading_agrees(a) && heading_opposes(b) {
                named = vec![a];
            } else if heading_agrees(b) && heading_opposes(a) {
                named = vec![b];
            }
        }
    }
    if !named.is_empty() {
        return Verdict::Variants(named.iter().map(|f| f.variant).collect());
    }
    let u = as_is.score();
    if u.is_finite() && variants.iter().all(|f| f.score() >= DECISION_FACTOR * u) {
        Verdict::Ok
    } else {
        Verdict::Undecided
    }
}

/// Whether two variants differ by roll and pitch both negated, which eq (2) takes as x1..x4
/// negated: their fits of roll and pitch are the same.
fn twins(a: Variant, b: Variant) -> bool {
    matches!(
        (a, b),
        (Variant::RollNegated, Variant::PitchNegated)
            | (Variant::PitchNegated, Variant::RollNegated)
    )
}

/// A number for the table: 3 significant digits, in scientific notation when small or large.
fn number(v: f64) -> String {
    if !v.is_finite() {
        return "-".to_string();
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let magnitude = v.abs().log10().floor() as i32;
    if (-2..5).contains(&magnitude) {
        let digits = (2 - magnitude).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.2e}")
    }
}

/// A fit's heading coefficient and its standard error, for people: `+0.998 +- 0.001`.
fn heading_text(f: &Fit) -> String {
    match f.heading_agreement {
        Some((c, se)) => format!(
            "{}{} +- {}",
            if c >= 0.0 { "+" } else { "" },
            number(c),
            number(se)
        ),
        None => "-".to_string(),
    }
}

/// The table of the fits and the verdict, for people (what `host-sim commission` prints).
pub fn format_report(log: &str, fits: &[Fit], verdict: &Verdict) -> String {
    let mut s = String::new();
    let Some(as_is) = fits.first() else {
        return s;
    };
    let r = &as_is.replay;
    let _ = writeln!(s, "{log}: {} rows; {}", r.rows, pattern_summary(r));
    let _ = writeln!(
        s,
        "fitted as it is and under {} variants of its conventions, to the end of the log; for each fit:\n\
         \x20 measurement and residual power: its four correlation channels' measurement and post-fit\n\
         \x20   residual, averaged over each rotation period; median square over the later half of the periods\n\
         \x20   from the first estimate ({} as it is)\n\
         \x20 unexplained: the residual power over the measurement power; the decision compares these\n\
         \x20   (factor {DECISION_FACTOR}) among the fits whose measurement power is at least 1/3 of the largest\n\
         \x20   (the others have not found eq (2)'s oscillation: `no oscillation`)\n\
         \x20 heading: the heading regressed on eq (2)'s heading oscillation for the fit's estimate, +- its\n\
         \x20   standard error (+1: the heading carries that oscillation; -1: its opposite)\n",
        fits.len() - 1,
        if as_is.periods == 0 {
            "none".to_string()
        } else {
            format!("{} of {}", as_is.periods - as_is.periods / 2, as_is.periods)
        }
    );
    let _ = writeln!(
        s,
        "| variant | measurement power, arcsec^2 | residual power, arcsec^2 | unexplained | times the log's | final status | largest 1-sigma, arcsec | heading |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let base = as_is.score();
    for f in fits {
        let times = if f.unexplained().is_some() && !f.oscillation_found {
            "no oscillation".to_string()
        } else if !base.is_finite() {
            "-".to_string()
        } else if f.variant == Variant::AsIs {
            "1".to_string()
        } else {
            number(f.score() / base)
        };
        let status = match (f.replay.final_estimate, f.replay.holdup) {
            (None, Some(h)) => format!("no estimate ({h})"),
            (None, None) => "no estimate".to_string(),
            (Some(_), _) => f.replay.final_status.map_or("-", |s| s.name()).to_string(),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {times} | {status} | {} | {} |",
            f.variant.name(),
            number(f.measurement_power_arcsec2.unwrap_or(f64::NAN)),
            number(f.residual_power_arcsec2.unwrap_or(f64::NAN)),
            number(f.unexplained().unwrap_or(f64::NAN)),
            number(f.largest_sigma_arcsec().unwrap_or(f64::NAN)),
            heading_text(f),
        );
    }
    s.push('\n');
    s.push_str(&verdict_text(fits, verdict));
    s
}

/// Why the fits are undecided, for people.
fn undecided_reason(fits: &[Fit]) -> String {
    if fits.iter().any(|f| f.unexplained().is_some()) {
        return format!(
            "the log as it is and its variants fit within a factor {DECISION_FACTOR} of each other: a longer log tells"
        );
    }
    let why = fits
        .first()
        .and_then(|f| f.replay.holdup)
        .map_or(String::new(), |h| format!(" (as it is: {h})"));
    format!("no fit reached a whole rotation period of residuals after its first estimate{why}")
}

/// The verdict and why, for people.
fn verdict_text(fits: &[Fit], verdict: &Verdict) -> String {
    let Some((as_is, variants)) = fits.split_first() else {
        return String::new();
    };
    let fit_of = |v: Variant| fits.iter().find(|f| f.variant == v);
    let mut s = String::new();
    match verdict {
        Verdict::Ok => {
            let _ = writeln!(s, "conventions: ok");
            let compared = variants.iter().filter(|f| f.oscillation_found);
            if let Some(c) = compared.min_by(|a, b| a.score().total_cmp(&b.score())) {
                let _ = writeln!(
                    s,
                    "  every variant leaves at least {DECISION_FACTOR} times the log's own unexplained share (the closest, {}, {} times)",
                    c.variant.name(),
                    number(c.score() / as_is.score())
                );
            }
            let unfound: Vec<&str> = variants
                .iter()
                .filter(|f| !f.oscillation_found)
                .map(|f| f.variant.name())
                .collect();
            if !unfound.is_empty() {
                let _ = writeln!(
                    s,
                    "  not compared, without eq (2)'s oscillation (no estimate, or under 1/3 of the largest measurement power): {}",
                    unfound.join(", ")
                );
            }
            if heading_opposes(as_is) {
                let _ = writeln!(
                    s,
                    "  but the heading carries the opposite of eq (2)'s heading oscillation for the estimate ({}):\n  \
                     roll and pitch both negated (which eq (2) takes as x1..x4 negated), or the heading's sense reversed",
                    heading_text(as_is)
                );
            }
        }
        Verdict::Variants(named) => {
            let names: Vec<&str> = named.iter().map(|v| v.name()).collect();
            let _ = writeln!(s, "conventions: {}", names.join(" or "));
            let best = named
                .iter()
                .filter_map(|v| fit_of(*v))
                .min_by(|a, b| a.score().total_cmp(&b.score()));
            let twins_named = matches!(named[..], [a, b] if twins(a, b));
            if let Some(best) = best {
                let who = if twins_named {
                    "both leave".to_string()
                } else {
                    format!("{} leaves", best.variant.name())
                };
                if as_is.score().is_finite() {
                    let _ = writeln!(
                        s,
                        "  {who} 1/{} of the log's own unexplained share",
                        number(as_is.score() / best.score())
                    );
                } else {
                    let why = as_is
                        .replay
                        .holdup
                        .map_or("no estimate".to_string(), |h| format!("no estimate: {h}"));
                    let _ = writeln!(
                        s,
                        "  {who} an unexplained share of {}, where the log as it is reached {why}",
                        number(best.score())
                    );
                }
            }
            let alone = named.len() == 1
                && matches!(named[0], Variant::RollNegated | Variant::PitchNegated);
            if let (true, Some(roll), Some(pitch)) = (
                twins_named || alone,
                fit_of(Variant::RollNegated),
                fit_of(Variant::PitchNegated),
            ) {
                let coefficients = format!(
                    "{} for roll-negated's estimate, {} for pitch-negated's",
                    heading_text(roll),
                    heading_text(pitch)
                );
                let _ = writeln!(
                    s,
                    "  roll and pitch cannot tell roll-negated from pitch-negated: they differ by both negated, which eq (2)\n  \
                     takes as x1..x4 negated"
                );
                if alone {
                    let _ = writeln!(
                        s,
                        "  the heading tells: against eq (2)'s heading oscillation it gives {coefficients}"
                    );
                } else {
                    let _ = writeln!(
                        s,
                        "  nor can the heading here: against eq (2)'s heading oscillation it gives {coefficients}\n  \
                         (it tells when one is within 0.5 of +1 and {HEADING_SIGMAS} standard errors from 0, and the other the opposite)"
                    );
                }
            }
            if named.len() > 1 && !twins_named {
                let _ = writeln!(
                    s,
                    "  the variants named fit within a factor {DECISION_FACTOR} of each other: a longer log tells which"
                );
            }
        }
        Verdict::Undecided => {
            let _ = writeln!(s, "conventions: undecided\n  {}", undecided_reason(fits));
        }
    }
    s
}

/// The help's tail of `host-sim commission`: what it prints and its exit statuses.
pub const HELP: &str = "Prints the log's rows and what was learned of its timing, then one table row per fit: the \
variant (as-is, rotation-reversed, roll-negated, pitch-negated, roll-pitch-swapped, platform-reversed, \
rotation-in-radians), its residual power (arcsec^2), its unexplained share, that share over the log's own, its \
final status and its largest 1-sigma; then `conventions: ok`, `conventions: VARIANT` (`A or B` when two fit \
alike) or `conventions: undecided`, with why. A variant is named when it leaves at most a tenth of the log's own \
unexplained share (docs/interface.md).

Exit status:
  0  conventions: ok (the log as it is fits best, every variant at least 10 times worse)
  1  failed (reason on standard error): the log cannot be read or is refused, an option out of range
  2  the command line cannot be parsed
  3  no row of the log could be read
  4  conventions: undecided (the fits too close to tell, or none reached an estimate)
  5  conventions: VARIANT (a variant of the log's conventions fits better than the log as it is)";

/// The end of a commission run: `Ok` for exit status 0, or the [`RunEnd`] of 4 or 5.
pub fn run_end(fits: &[Fit], verdict: &Verdict) -> Result<(), RunEnd> {
    match verdict {
        Verdict::Ok => Ok(()),
        Verdict::Variants(named) => Err(RunEnd::VariantFitsBetter {
            variants: named
                .iter()
                .map(|v| v.name())
                .collect::<Vec<_>>()
                .join(" or "),
        }),
        Verdict::Undecided => Err(RunEnd::Undecided {
            reason: undecided_reason(fits),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::RotationSummary;

    /// A fit of `variant` leaving `unexplained` (`None`: no estimate), with this heading
    /// coefficient and standard error.
    fn fit(variant: Variant, unexplained: Option<f64>, heading: Option<(f64, f64)>) -> Fit {
        Fit {
            variant,
            replay: Replay {
                rows: 1000,
                rejected: Default::default(),
                counters: Default::default(),
                final_estimate: None,
                final_status: None,
                sample_interval_s: Some(1.0),
                rotation: RotationSummary {
                    period_s: Some(480.0),
                    pinned: false,
                    kind: None,
                    samples_per_entry: 1,
                },
                holdup: None,
                error_changes: vec![],
                unreadable: RowFilter::new(false),
                health: estimator_core::Health::NONE,
                binning: None,
            },
            periods: 8,
            residual_power_arcsec2: unexplained,
            measurement_power_arcsec2: unexplained.map(|_| 1.0),
            heading_agreement: heading,
            oscillation_found: unexplained.is_some(),
        }
    }

    /// Every variant's shares: the log's `as_is`, the others 1 unless given.
    fn fits(as_is: Option<f64>, given: &[(Variant, Option<f64>)]) -> Vec<Fit> {
        Variant::ALL
            .iter()
            .map(|&v| {
                let u = if v == Variant::AsIs {
                    as_is
                } else {
                    given
                        .iter()
                        .find(|(g, _)| *g == v)
                        .map_or(Some(1.0), |(_, u)| *u)
                };
                fit(v, u, None)
            })
            .collect()
    }

    #[test]
    fn the_sign_and_exchange_variants_undo_themselves() {
        let row = Row {
            time_s: 3.0,
            rotation_deg: 123.4,
            platform_deg: 210.5,
            latitude_deg: 40.0,
            heading_deg: 30.0,
            roll_deg: -1.25,
            pitch_deg: 0.5,
        };
        for v in Variant::ALL {
            let mut twice = row;
            v.apply(&mut twice);
            if v != Variant::AsIs {
                assert_ne!(twice, row, "{}", v.name());
            }
            v.apply(&mut twice);
            if v != Variant::RotationInRadians {
                assert_eq!(twice, row, "{}", v.name());
            }
        }
        let mut radians = Row {
            rotation_deg: 1.0,
            ..row
        };
        Variant::RotationInRadians.apply(&mut radians);
        assert!((radians.rotation_deg - 57.295_779_513).abs() < 1e-6);
    }

    #[test]
    fn a_variant_is_named_only_ten_times_better_than_the_log() {
        // Every variant ten times worse or more: ok.
        assert_eq!(verdict(&fits(Some(0.1), &[])), Verdict::Ok);
        // One variant only 5 times worse: undecided.
        let close = fits(Some(0.1), &[(Variant::RollPitchSwapped, Some(0.5))]);
        assert_eq!(verdict(&close), Verdict::Undecided);
        // One variant 5 times better: undecided; 10 times better: named.
        let better = fits(Some(1.0), &[(Variant::RollPitchSwapped, Some(0.2))]);
        assert_eq!(verdict(&better), Verdict::Undecided);
        let named = fits(Some(1.0), &[(Variant::RollPitchSwapped, Some(0.1))]);
        assert_eq!(
            verdict(&named),
            Verdict::Variants(vec![Variant::RollPitchSwapped])
        );
        // Two within a factor 10 of each other: both named, in the table's order.
        let two = fits(
            Some(1.0),
            &[
                (Variant::PlatformReversed, Some(1e-3)),
                (Variant::RotationReversed, Some(5e-3)),
            ],
        );
        assert_eq!(
            verdict(&two),
            Verdict::Variants(vec![Variant::RotationReversed, Variant::PlatformReversed])
        );
        // The log as it is without an estimate: the one variant that fits is named.
        let radians = fits(None, &[(Variant::RotationInRadians, Some(1e-6))]);
        let radians: Vec<Fit> = radians
            .into_iter()
            .map(|f| match f.variant {
                Variant::RotationInRadians => f,
                _ => fit(f.variant, None, None),
            })
            .collect();
        assert_eq!(
            verdict(&radians),
            Verdict::Variants(vec![Variant::RotationInRadians])
        );
        // No fit at all: undecided.
        let none: Vec<Fit> = Variant::ALL.iter().map(|&v| fit(v, None, None)).collect();
        assert_eq!(verdict(&none), Verdict::Undecided);
        assert!(run_end(&none, &Verdict::Undecided).is_err_and(|e| e.status() == 4));
        assert!(run_end(&named, &verdict(&named)).is_err_and(|e| e.status() == 5));
        assert!(run_end(&fits(Some(0.1), &[]), &Verdict::Ok).is_ok());
    }

    #[test]
    fn the_heading_tells_roll_negated_from_pitch_negated_only_when_clear() {
        let with_heading = |roll: (f64, f64), pitch: (f64, f64)| -> Vec<Fit> {
            let mut f = fits(
                Some(1.0),
                &[
                    (Variant::RollNegated, Some(1e-5)),
                    (Variant::PitchNegated, Some(1e-5)),
                ],
            );
            f[2].heading_agreement = Some(roll);
            f[3].heading_agreement = Some(pitch);
            f
        };
        let both = Verdict::Variants(vec![Variant::RollNegated, Variant::PitchNegated]);
        assert_eq!(
            verdict(&with_heading((0.998, 0.001), (-0.998, 0.001))),
            Verdict::Variants(vec![Variant::RollNegated])
        );
        assert_eq!(
            verdict(&with_heading((-0.998, 0.001), (0.998, 0.001))),
            Verdict::Variants(vec![Variant::PitchNegated])
        );
        // A heading the ship's course changes swamp, or one that does not carry eq (2)'s
        // oscillation: both named.
        assert_eq!(verdict(&with_heading((-54.0, 199.0), (54.0, 199.0))), both);
        assert_eq!(verdict(&with_heading((0.9, 0.3), (-0.9, 0.3))), both);
        assert_eq!(verdict(&with_heading((0.01, 0.001), (-0.01, 0.001))), both);
    }

    /// What the docs say a fit keeps a rotation period.
    #[test]
    fn a_period_keeps_104_bytes() {
        assert_eq!(std::mem::size_of::<Period>(), 104);
    }

    #[test]
    fn numbers_keep_three_significant_digits() {
        assert_eq!(number(0.035_91), "0.0359");
        assert_eq!(number(1283.2), "1283");
        assert_eq!(number(2.33e-6), "2.33e-6");
        assert_eq!(number(4.31e5), "4.31e5");
        assert_eq!(number(f64::INFINITY), "-");
    }
}
