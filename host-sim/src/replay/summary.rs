//! A replay for people: the lines `estimate` and `run` print of it, and the parts the report
//! pages and `commission` say too (what was learned of the timing, the alarms, the limit the log
//! sets, the changes of the errors).

use super::Replay;
use crate::formats::log_paths::log_name;
use estimator_core::units::rad_to_arcsec;
use estimator_core::{ErrorChange, Method, RejectReason};
use std::io::Write;
use std::path::Path;

/// The summary `estimate` and `run` print of a replay of `log` with `method` whose estimates went
/// to `out` (named for people): the rows, what was learned of the timing, the changes of the
/// errors, the final status, the alarms and the limit the log sets, the final estimates and the
/// rows rejected or unreadable.
pub fn write_summary(
    w: &mut dyn Write,
    log: &Path,
    method: Method,
    r: &Replay,
    out: &str,
) -> std::io::Result<()> {
    // With binning the estimator stepped once a bin (the rows are counted on the next line).
    let rows = if r.binning.is_some() { "bins" } else { "rows" };
    let c = &r.counters;
    writeln!(
        w,
        "{}: method {}: {} {rows}, {} accepted, {} filled (lost samples interpolated), {} window restarts, {} clock steps; estimates in {out}",
        log_name(log),
        method.name(),
        r.rows,
        c.accepted,
        c.filled,
        c.window_restarts,
        c.clock_steps
    )?;
    if let Some(b) = &r.binning {
        writeln!(w, "  binned: {}", b.describe())?;
    }
    writeln!(w, "  {}", pattern_summary(r))?;
    for change in &r.error_changes {
        writeln!(w, "  {}", describe_error_change(change))?;
    }
    writeln!(
        w,
        "  final status: {}",
        r.final_status
            .map_or("none (no row accepted)", |s| s.name())
    )?;
    writeln!(w, "  {}", describe_health(&r.health))?;
    if let Some(limit) = describe_limit(&r.health) {
        writeln!(w, "  {limit}")?;
    }
    if let Some(loss) = &r.regular_loss {
        writeln!(w, "  {}", loss.describe())?;
    }
    write_final_estimate(w, r)?;
    write_rejected(w, r, rows)
}

/// The final estimates with their 1-sigma (and what froze them), or why there is none.
fn write_final_estimate(w: &mut dyn Write, r: &Replay) -> std::io::Result<()> {
    match (r.final_estimate, r.holdup) {
        (Some(e), holdup) => {
            for i in 0..4 {
                writeln!(
                    w,
                    "  x{} = {:+.3} arcsec (1-sigma {:.3})",
                    i + 1,
                    rad_to_arcsec(e.x_rad[i] as f64),
                    rad_to_arcsec(e.sigma_rad[i] as f64)
                )?;
            }
            if let Some(h) = holdup {
                writeln!(w, "  estimates frozen: {h}")?;
            }
        }
        (None, Some(h)) => writeln!(w, "  no estimate: {h}")?,
        (None, None) => writeln!(w, "  no estimate: no row accepted")?,
    }
    Ok(())
}

/// The `rows` (or bins) the estimator rejected, by reason, and the unreadable rows skipped.
fn write_rejected(w: &mut dyn Write, r: &Replay, rows: &str) -> std::io::Result<()> {
    let reasons: Vec<String> = RejectReason::ALL
        .iter()
        .map(|&reason| format!("{} {}", reason.name(), r.rejected.of(reason)))
        .collect();
    writeln!(
        w,
        "  rejected {rows}: {} ({})",
        r.rejected.total(),
        reasons.join(", ")
    )?;
    if let Some(skipped) = r.unreadable.describe_skipped() {
        writeln!(w, "  {skipped}")?;
    }
    Ok(())
}

/// A learned value for people, to 4 significant digits (the learned values carry the recorder's
/// clock error, 1e-6 s on 1 s), trailing zeros of the decimals dropped: `1000`, `1`, `0.1`, `479.9`.
pub fn significant_4(v: f64) -> String {
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// What was learned of the log's timing, for people: e.g. `rotation: reciprocating, period 720 s;
/// sample interval 1 s`.
pub fn pattern_summary(r: &Replay) -> String {
    let round = significant_4;
    let rotation = match (r.rotation.kind, r.rotation.period_s) {
        (Some(kind), Some(p)) => format!("{}, period {} s", kind.name(), round(p)),
        (None, Some(p)) => format!("period {} s (shape not yet learned)", round(p)),
        _ => "period not yet detected".to_string(),
    };
    let pinned = if r.rotation.pinned { " (pinned)" } else { "" };
    let bins = if r.rotation.samples_per_entry > 1 {
        format!(", {} samples a window entry", r.rotation.samples_per_entry)
    } else {
        String::new()
    };
    let interval = r
        .sample_interval_s
        .map_or("not yet learned".to_string(), |d| format!("{} s", round(d)));
    format!("rotation: {rotation}{pinned}{bins}; sample interval {interval}")
}

/// A change of the installation errors, for people: e.g. `change of the installation errors
/// detected at 13440 s (residuals showing it since 12240 s): x1, x3 learned again`.
pub fn describe_error_change(c: &ErrorChange) -> String {
    let which: Vec<String> = (0..4)
        .filter(|i| c.relearned[*i])
        .map(|i| format!("x{}", i + 1))
        .collect();
    format!(
        "change of the installation errors detected at {} s (residuals showing it since {} s): {} learned again",
        c.detected_s,
        c.seen_since_s,
        which.join(", ")
    )
}

/// One line of the latched alarms and the residuals' level (the estimates CSV's last columns):
/// `alarms: 1 change declared (the last at 12000 s), 2 window restarts, 0 rejected, 120 s in
/// model_mismatch; residual level pitch 0.041 / roll 0.073 arcsec, noise scale 1.00 / 1.25`.
pub fn describe_health(h: &estimator_core::Health) -> String {
    let plural = |n: u32, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    let mut s = format!(
        "alarms: {}",
        plural(h.changes_detected, "change declared", "changes declared")
    );
    if let Some(t) = h.last_change_s {
        s.push_str(&format!(" (the last at {t} s)"));
    }
    s.push_str(&format!(
        ", {}, {} rejected, {} s in model_mismatch",
        plural(h.window_restarts, "window restart", "window restarts"),
        h.rejected,
        h.mismatch_s
    ));
    if let (Some(r), Some(k)) = (h.residual_rad, h.noise_scale) {
        s.push_str(&format!(
            "; residual level pitch {:.3} / roll {:.3} arcsec, noise scale {:.2} / {:.2}",
            estimator_core::units::rad_to_arcsec(f64::from(r[0])),
            estimator_core::units::rad_to_arcsec(f64::from(r[1])),
            k[0],
            k[1]
        ));
    }
    s
}

/// A channel pair's noise scale at and beyond which the summary names the limit the log sets
/// ([`describe_limit`]): its errors' 1-sigma widened at least twofold over the white noise's.
pub const LIMIT_NOISE_SCALE: f32 = 4.0;

/// The limit the log sets, when a channel pair's residuals hold more than the configured white
/// noise gives (its noise scale at least [`LIMIT_NOISE_SCALE`]): which pair, by how much, the
/// likely causes, and that the pair's 1-sigma already carries it. `None` on a log whose residuals
/// are the model's, and before the first estimate.
pub fn describe_limit(h: &estimator_core::Health) -> Option<String> {
    let s = h.noise_scale?;
    let over: Vec<String> = [("pitch pair (x1, x2)", s[0]), ("roll pair (x3, x4)", s[1])]
        .iter()
        .filter(|(_, k)| *k >= LIMIT_NOISE_SCALE)
        .map(|(pair, k)| {
            format!(
                "the {pair} {k:.0} times (its 1-sigma widened {:.1}-fold)",
                k.sqrt()
            )
        })
        .collect();
    if over.is_empty() {
        return None;
    }
    Some(format!(
        "limit: the residuals hold more than the white noise the model gives, {}: a slow heel or \
         trim, rows lost at a cadence, or another disturbance near the rotation frequency, which \
         attitude alone does not tell from the installation errors; the 1-sigma above includes it",
        over.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn learned_values_keep_their_whole_digits() {
        // 1000 was printed as "1": the zeros of a whole number were trimmed as if decimals.
        assert_eq!(significant_4(1000.0), "1000");
        assert_eq!(significant_4(720.0), "720");
        assert_eq!(significant_4(1.000_000_3), "1");
        assert_eq!(significant_4(0.100_000_2), "0.1");
        assert_eq!(significant_4(479.93), "479.9");
        assert_eq!(significant_4(12_345.6), "12346");
    }
}
