//! The subcommands, one module each: its arguments (their doc comments are its `--help`) and the
//! function that runs it. The argument groups several subcommands share are in [`args`]; what
//! several print is here.

pub mod args;
pub mod commission;
pub mod compare;
pub mod estimate;
pub mod flash_life;
pub mod generate;
pub mod monte_carlo;
pub mod run;
pub mod stream;

use crate::formats::log_csv::{self, LogError};
use crate::replay::Replay;
use crate::report::{format_accuracy, format_honesty, format_rms, method_label, Report};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Method, RejectReason};
use std::io::Write;
use std::path::Path;

/// Tells each unreadable row skipped (the first few) on standard error.
pub fn warn_row(e: &LogError) {
    eprintln!("warning: {e} (row skipped)");
}

/// The summary of a replay of `log` with `method` whose estimates went to `out`: its rows, what
/// was learned of the timing, the alarms, the final estimates and the rows rejected or unreadable.
pub fn print_summary(
    w: &mut dyn Write,
    log: &Path,
    method: Method,
    r: &Replay,
    out: &str,
) -> std::io::Result<()> {
    let log = if log_csv::is_stdio(log) {
        "standard input".to_string()
    } else {
        log.display().to_string()
    };
    let c = &r.counters;
    // With binning the estimator stepped once a bin (the rows are counted on the next line).
    let rows = if r.binning.is_some() { "bins" } else { "rows" };
    writeln!(
        w,
        "{log}: method {}: {} {rows}, {} accepted, {} filled (lost samples interpolated), {} window restarts, {} clock steps; estimates in {out}",
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
    writeln!(w, "  {}", crate::replay::pattern_summary(r))?;
    for change in &r.error_changes {
        writeln!(w, "  {}", crate::replay::describe_error_change(change))?;
    }
    writeln!(
        w,
        "  final status: {}",
        r.final_status
            .map_or("none (no row accepted)", |s| s.name())
    )?;
    writeln!(w, "  {}", crate::replay::describe_health(&r.health))?;
    if let Some(limit) = crate::replay::describe_limit(&r.health) {
        writeln!(w, "  {limit}")?;
    }
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
    if r.unreadable.skipped > 0 {
        let lines: Vec<String> = r
            .unreadable
            .first
            .iter()
            .map(|e| e.line.to_string())
            .collect();
        let more = if r.unreadable.skipped as usize > lines.len() {
            ", ..."
        } else {
            ""
        };
        writeln!(
            w,
            "  unreadable rows skipped: {} (lines {}{more}; --strict refuses such a log)",
            r.unreadable.skipped,
            lines.join(", ")
        )?;
    }
    Ok(())
}

/// The accuracy of a replay against the truth: the table, the honesty of the 1-sigma and the
/// attitude error's RMS.
pub fn print_report(w: &mut dyn Write, method: Method, rep: &Report) -> std::io::Result<()> {
    writeln!(w, "\naccuracy against the truth, {}:", method_label(method))?;
    write!(w, "{}", format_accuracy(&rep.accuracy))?;
    write!(w, "{}", format_honesty(&rep.accuracy.honesty))?;
    if let Some(r) = &rep.rms_from_first_estimate {
        write!(w, "{}", format_rms("from the first estimate", r))?;
    }
    if let Some(r) = &rep.rms_last_quarter {
        write!(w, "{}", format_rms("last quarter of the run", r))?;
    }
    Ok(())
}
