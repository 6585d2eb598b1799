//! `host-sim commission`: whether a log's conventions fit the model of eq (2) ([`crate::commission`]).

use crate::cmd::args::{TimingArgs, TuningArgs};
use crate::cmd::warn_row;
use crate::formats::log_paths::log_name;
use estimator_core::Method;
use std::io::Write;
use std::path::PathBuf;

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
    use crate::commission::{fit_variants, format_report, run_end, verdict, Variant};
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
