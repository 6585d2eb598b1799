//! The decision rule of the module doc of [`crate::commission`]: what the fits say of the log's
//! conventions ([`Verdict`]), the heading's say on roll-negated against pitch-negated, and the
//! exit status it ends with.

use super::text::undecided_reason;
use super::{Fit, Variant, DECISION_FACTOR};
use crate::exit_status::RunEnd;

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
pub(super) fn heading_opposes(f: &Fit) -> bool {
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
pub(super) fn twins(a: Variant, b: Variant) -> bool {
    matches!(
        (a, b),
        (Variant::RollNegated, Variant::PitchNegated)
            | (Variant::PitchNegated, Variant::RollNegated)
    )
}

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
