//! `host-sim commission`: whether a log's conventions fit the model of eq (2) ([`crate::commission`]).

use crate::cmd::args::{TimingArgs, TuningArgs};
use crate::cmd::warn_row;
use crate::commission::fitting::fit_variants;
use crate::commission::text::format_report;
use crate::commission::verdict::{run_end, verdict};
use crate::commission::Variant;
use crate::formats::log_paths::log_name;
use estimator_core::Method;
use std::io::Write;
use std::path::PathBuf;

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

/// `host-sim commission`.
#[derive(clap::Args, Debug)]
pub struct CommissionArgs {
    /// Attitude log (CSV, plain or gzip, `-` for standard input; format: docs/log-format.md).
    log: PathBuf,
    /// Refuse the log at its first unreadable row (default: skip it, count it, report its line).
    #[arg(long)]
    strict: bool,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    timing: TimingArgs,
}

/// `host-sim commission`: fits the log under every variant of its conventions, prints the table
/// and the verdict, and ends with the verdict's exit status.
pub fn run(a: &CommissionArgs) -> anyhow::Result<()> {
    a.timing.check()?;
    let config = a.timing.pin(a.tuning.checked_config(Method::Windowed)?);
    let fits = fit_variants(&a.log, config, a.strict, &Variant::ALL)?;
    if let Some(as_is) = fits.first() {
        for e in &as_is.replay.unreadable.first {
            warn_row(e);
        }
    }
    let verdict = verdict(&fits);
    let mut out = std::io::stdout().lock();
    write!(out, "{}", format_report(&log_name(&a.log), &fits, &verdict))?;
    out.flush()?;
    run_end(&fits, &verdict)?;
    Ok(())
}
