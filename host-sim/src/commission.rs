//! `host-sim commission LOG`: whether a log's conventions fit the model of eq (2).
//!
//! The log is read once (as `estimate` reads it) and every row is handed to one replay per
//! [`Variant`] (the log as it is, or with one convention changed: an angle negated, roll and pitch
//! exchanged, the rotation angle read as radians), each the core's windowed method to the end of
//! the log; the replays run side by side (rayon), a batch of rows at a time.
//!
//! # The evidence: the unexplained share each fit leaves
//! A fit's measurement `z` and post-fit residual `z - H x` of its four channels
//! ([`StepView::residuals_rad`]) are averaged over each rotation period from the first estimate
//! on; the **measurement** and **residual power** are the medians, over the later half of the
//! periods, of their squares. A wrong convention's misfit grows as the platform angle turns at the
//! Earth rate, so the later half holds it at its largest. The decision compares the **unexplained
//! share**, residual over measurement power, among the fits that found eq (2)'s oscillation (a
//! measurement power at least [`FOUND_POWER_SHARE`] of the largest): the residual power alone
//! would favour a fit that correlates with nothing (a rotation angle in degrees read as radians).
//!
//! # The decision rule
//! With `F` = [`DECISION_FACTOR`] and `u(v)` the unexplained share of variant `v` (infinite for a
//! fit without an estimate, without a period of residuals, or that did not find the oscillation):
//! - `v` is named when `F u(v) <= u(as-is)` and `u(v) < F u(best)`, `best` the variant that
//!   leaves least (every variant within a factor `F` of the best is named with it);
//! - otherwise the conventions are **ok** when every variant has `u(v) >= F u(as-is)`;
//! - otherwise the fits are too close to tell (**undecided**): a longer log tells.
//!
//! Roll and pitch both negated is eq (2) with x1..x4 negated, so `roll-negated` and
//! `pitch-negated` fit alike; the heading tells them apart ([`Fit::heading_agreement`]: +1 for the
//! right one, -1 for the other, each at least [`HEADING_SIGMAS`] standard errors from 0 over
//! [`MIN_HEADING_PERIODS`] periods), on a steady heading but not at sea. The reasons, how `F` and
//! [`FOUND_POWER_SHARE`] were set (`scripts/commission-study.sh`) and what it does not do:
//! docs/interface.md, "How it decides", "How long a log, measured" and "What it does not do".
//!
//! The parts: [`fitting`] (the replays, their sums), [`verdict`] (the rule), [`text`] (the print).
//!
//! [`StepView::residuals_rad`]: crate::replay::replayer::StepView::residuals_rad
//! [`HEADING_SIGMAS`]: verdict::HEADING_SIGMAS
//! [`MIN_HEADING_PERIODS`]: verdict::MIN_HEADING_PERIODS

pub mod fitting;
pub mod text;
pub mod verdict;

use crate::replay::Replay;
use crate::sim::scenario::Row;
use estimator_core::units::rad_to_arcsec;

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

#[cfg(test)]
mod tests {
    use super::verdict::*;
    use super::*;
    use crate::formats::log_csv::RowFilter;
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
                regular_loss: None,
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
}
