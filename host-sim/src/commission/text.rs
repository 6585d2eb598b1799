//! The commission for people: the table of the fits, the verdict and why (what `host-sim
//! commission` prints).

use super::verdict::{heading_opposes, twins, Verdict, HEADING_SIGMAS};
use super::{Fit, Variant, DECISION_FACTOR};
use crate::replay::summary::pattern_summary;
use std::fmt::Write as _;

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
pub(super) fn undecided_reason(fits: &[Fit]) -> String {
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
    let mut s = String::new();
    match verdict {
        Verdict::Ok => ok_text(&mut s, as_is, variants),
        Verdict::Variants(named) => variants_text(&mut s, fits, named),
        Verdict::Undecided => {
            let _ = writeln!(s, "conventions: undecided\n  {}", undecided_reason(fits));
        }
    }
    s
}

/// `conventions: ok`: how far the closest variant compared is, the variants not compared, and a
/// heading that carries the opposite of eq (2)'s oscillation.
fn ok_text(s: &mut String, as_is: &Fit, variants: &[Fit]) {
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

/// `conventions: VARIANT`: what the best of the variants named leaves of the log's own share,
/// what the heading says of roll-negated and pitch-negated, and whether a longer log would tell.
fn variants_text(s: &mut String, fits: &[Fit], named: &[Variant]) {
    let Some(as_is) = fits.first() else {
        return;
    };
    let fit_of = |v: Variant| fits.iter().find(|f| f.variant == v);
    let names: Vec<&str> = named.iter().map(|v| v.name()).collect();
    let _ = writeln!(s, "conventions: {}", names.join(" or "));
    let best = named
        .iter()
        .filter_map(|v| fit_of(*v))
        .min_by(|a, b| a.score().total_cmp(&b.score()));
    let twins_named = matches!(named[..], [a, b] if twins(a, b));
    if let Some(best) = best {
        best_share_text(s, as_is, best, twins_named);
    }
    let alone =
        named.len() == 1 && matches!(named[0], Variant::RollNegated | Variant::PitchNegated);
    if let (true, Some(roll), Some(pitch)) = (
        twins_named || alone,
        fit_of(Variant::RollNegated),
        fit_of(Variant::PitchNegated),
    ) {
        twins_text(s, roll, pitch, alone);
    }
    if named.len() > 1 && !twins_named {
        let _ = writeln!(
            s,
            "  the variants named fit within a factor {DECISION_FACTOR} of each other: a longer log tells which"
        );
    }
}

/// What the best variant named (`both`, when the twins are named) leaves of the log's own
/// unexplained share, or its own share when the log as it is reached no estimate.
fn best_share_text(s: &mut String, as_is: &Fit, best: &Fit, both: bool) {
    let who = if both {
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

/// That roll and pitch cannot tell roll-negated from pitch-negated, and whether the heading does
/// (`alone`: one of them was named).
fn twins_text(s: &mut String, roll: &Fit, pitch: &Fit, alone: bool) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_three_significant_digits() {
        assert_eq!(number(0.035_91), "0.0359");
        assert_eq!(number(1283.2), "1283");
        assert_eq!(number(2.33e-6), "2.33e-6");
        assert_eq!(number(4.31e5), "4.31e5");
        assert_eq!(number(f64::INFINITY), "-");
    }
}
