//! `host-sim estimate`: a log replayed through the estimator into its estimates CSV, with the
//! summary, the accuracy against a truth file beside the log, and the report.

use crate::cmd::args::{check_bin_interval, MethodArg, TimingArgs, TuningArgs};
use crate::cmd::{summary_writer, warn_row};
use crate::exit_status::RunEnd;
use crate::formats::log_paths::{default_estimates_path, inputs_of, log_name, output_name};
use crate::formats::truth_file::load_truth;
use crate::replay::summary::write_summary;
use crate::replay::{LogReplay, Replay};
use crate::report::tables::{method_label, write_report};
use crate::report::TruthRows;
use estimator_core::Method;
use std::io::Write;
use std::path::PathBuf;

/// `host-sim estimate`.
#[derive(clap::Args, Debug)]
pub struct EstimateArgs {
    /// Attitude log (CSV, plain or gzip, `-` for standard input; format: docs/log-format.md).
    log: PathBuf,
    /// Estimates CSV to write (default: LOG.estimates.csv beside the log; `-`: standard output,
    /// the summary then goes to standard error). Never the log itself.
    #[arg(long, value_name = "EST.csv", allow_hyphen_values = true)]
    out: Option<PathBuf>,
    /// Refuse the log at its first unreadable row (default: skip it, count it, report its line).
    #[arg(long)]
    strict: bool,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = MethodArg::Windowed)]
    method: MethodArg,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    timing: TimingArgs,
    /// Average the log's rows (any rate up to 200 Hz: a navigation computer's attitude) into bins
    /// of S s (0.1-10) aligned to multiples of S, and step the estimator once a bin with the
    /// average, stamped at the bin's centre: the estimator's interval is S, and the estimates CSV
    /// has one row per bin (docs/interface.md, "Attitude at the navigation rate").
    #[arg(long, value_name = "S")]
    bin_interval_s: Option<f64>,
    /// Checkpoint the estimator after the rows at these times, drop it and restore a fresh one
    /// from the bytes, as after a power cut right after a save: the estimates go on from the
    /// checkpoint's while the window refills (docs/reliability.md).
    #[arg(long, value_name = "T1,T2,...", value_delimiter = ',')]
    restart_at: Vec<f64>,
    /// Write plots (estimates with 1-sigma, error against the truth, status timeline, attitude
    /// before and after compensation, residuals) and a self-contained report.html into DIR
    /// (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
}

/// `host-sim estimate`: replays the log into the estimates CSV, prints the summary (and the
/// accuracy with a truth file), writes the report when asked; exit status 4 without an estimate.
pub fn run(a: &EstimateArgs) -> anyhow::Result<()> {
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_estimates_path(&a.log));
    let method: Method = a.method.into();
    let restart_at = restart_times(&a.restart_at)?;
    a.timing.check()?;
    if let Some(bin_s) = a.bin_interval_s {
        check_bin_interval(bin_s)?;
        if let Some(d) = a.timing.sample_interval {
            anyhow::ensure!(
                d == bin_s,
                "--sample-interval {d} contradicts --bin-interval-s {bin_s}: the estimator's interval is the bins'; leave --sample-interval out"
            );
        }
    }
    if let Some(dir) = &a.report {
        crate::report::pages::check_dir(dir, &inputs_of(&a.log))?;
    }
    let config = a.timing.pin(a.tuning.checked_config(method)?);
    let truth = load_truth(&a.log, &mut |w| eprintln!("warning: {w}"));
    let est = LogReplay {
        config,
        strict: a.strict,
        restart_at_s: restart_at.clone(),
        bin_interval_s: a.bin_interval_s,
        estimates: Some(out.clone()),
        truth: truth.as_ref().map(TruthRows::of),
        timeline: a.report.is_some(),
        steps: false,
    }
    .run(&a.log, &mut warn_row)?;
    let mut info = summary_writer(&out);
    if !restart_at.is_empty() {
        writeln!(
            info,
            "restarted from a checkpoint after the rows at {restart_at:?} s"
        )?;
    }
    write_summary(&mut info, &a.log, method, &est.replay, &output_name(&out))?;
    if let Some(rep) = &est.report {
        write_report(&mut info, method, rep)?;
    }
    if let (Some(dir), Some(tl)) = (&a.report, &est.timeline) {
        let page = crate::report::pages::write_replay_report(
            dir,
            &log_name(&a.log),
            method_label(method),
            &est.replay,
            est.report.as_ref(),
            tl,
            vec![],
        )?;
        writeln!(info, "report in {}", page.display())?;
    }
    info.flush()?;
    no_estimate_end(&est.replay)
}

/// The `--restart-at` times, ascending; refused unless finite.
fn restart_times(times_s: &[f64]) -> anyhow::Result<Vec<f64>> {
    let mut restart_at = times_s.to_vec();
    anyhow::ensure!(
        restart_at.iter().all(|t| t.is_finite()),
        "--restart-at needs finite times"
    );
    restart_at.sort_by(f64::total_cmp);
    Ok(restart_at)
}

/// The end of a replay without an estimate (exit status 4, the reason on standard error).
fn no_estimate_end(r: &Replay) -> anyhow::Result<()> {
    if r.final_estimate.is_some() {
        return Ok(());
    }
    let reason = match (r.holdup, r.binning) {
        (Some(h), _) => format!("{h} at the end of the log"),
        (None, Some(b)) => format!(
            "no bin accepted ({} rejected; {} rows refused by the binning)",
            r.rejected.total(),
            b.refused.total()
        ),
        (None, None) => format!("no row accepted ({} rejected)", r.rejected.total()),
    };
    Err(RunEnd::NoEstimate { reason }.into())
}
