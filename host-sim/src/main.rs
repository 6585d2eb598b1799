//! `host-sim`: scenario generator, log replay, reports and plots. `host-sim --help` lists the commands.

use anyhow::Context;
use clap::{Parser, Subcommand};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Method, SampleError};
use host_sim::cli_args::{method_label, MethodArg, ScenarioArg, ScenarioOverrides, TraditionalArgs};
use host_sim::log_csv::{self, Truth};
use host_sim::pipeline::{default_estimates_path, estimate_file, load_truth, report, Estimated};
use host_sim::replay::Replay;
use host_sim::report::{format_accuracy, format_rms, Report};
use host_sim::scenario::generate;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about = "RINS installation-error estimator: scenarios, log replay, reports and plots")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Generate an attitude log and its truth file (FILE.truth.json beside it).
    Generate(GenerateArgs),
    /// Replay an attitude log through the estimator, write the estimates CSV, print the final
    /// estimates, the rejected rows and (with FILE.truth.json beside the log) the accuracy table.
    Estimate(EstimateArgs),
    /// Generate + estimate with every method + report + plots, in one go.
    Run(RunArgs),
    /// Stream a log through the firmware over its link.
    Stream(host_sim::stream::StreamArgs),
}

#[derive(clap::Args, Debug)]
struct GenerateArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    scenario: ScenarioArg,
    /// Seed of the random phases, sway spectrum and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    overrides: ScenarioOverrides,
    /// Output attitude log (CSV).
    #[arg(long, value_name = "FILE.csv")]
    out: PathBuf,
}

#[derive(clap::Args, Debug)]
struct EstimateArgs {
    /// Attitude log (CSV, see shared/log-format.md).
    log: PathBuf,
    /// Estimates CSV to write (default: LOG.estimates.csv beside the log).
    #[arg(long, value_name = "EST.csv")]
    out: Option<PathBuf>,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = MethodArg::Windowed)]
    method: MethodArg,
    #[command(flatten)]
    traditional: TraditionalArgs,
}

#[derive(clap::Args, Debug)]
struct RunArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    scenario: ScenarioArg,
    /// Seed of the random phases, sway spectrum and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    overrides: ScenarioOverrides,
    #[command(flatten)]
    traditional: TraditionalArgs,
    /// Output directory (default: out/SCENARIO-SEED).
    #[arg(long, value_name = "DIR")]
    out_dir: Option<PathBuf>,
    /// Skip the plots.
    #[arg(long)]
    no_plots: bool,
}

fn main() {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Generate(a) => cmd_generate(a),
        Command::Estimate(a) => cmd_estimate(a),
        Command::Run(a) => cmd_run(a),
        Command::Stream(a) => host_sim::stream::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn cmd_generate(a: &GenerateArgs) -> anyhow::Result<()> {
    let params = a.overrides.params(a.scenario.into(), a.seed)?;
    let g = generate(&params);
    log_csv::write_log(&a.out, &g.rows)?;
    let truth_path = log_csv::truth_path(&a.out);
    log_csv::write_truth(&truth_path, &Truth::new(&params))?;
    println!("wrote {} ({} rows) and {}", a.out.display(), g.rows.len(), truth_path.display());
    Ok(())
}

fn cmd_estimate(a: &EstimateArgs) -> anyhow::Result<()> {
    let out = a.out.clone().unwrap_or_else(|| default_estimates_path(&a.log));
    let method: Method = a.method.into();
    let est = estimate_file(&a.log, &out, a.traditional.config(method))?;
    print_summary(&a.log.display().to_string(), method, &est.replay, &out.display().to_string());
    if let Some((truth, generated)) = load_truth(&a.log)? {
        print_report(method, &report(&est, &truth, &generated));
    }
    Ok(())
}

fn print_summary(log: &str, method: Method, r: &Replay, out: &str) {
    println!(
        "{log}: method {}: {} rows, {} accepted, {} bridged (gap samples interpolated), {} window restarts; estimates in {out}",
        method.name(),
        r.steps.len(),
        r.accepted,
        r.bridged,
        r.window_restarts
    );
    match r.final_estimate {
        Some(e) => {
            for i in 0..4 {
                println!("  x{} = {:+.3} arcsec (1-sigma {:.3})", i + 1, rad_to_arcsec(e.x_rad[i] as f64), rad_to_arcsec(e.sigma_rad[i] as f64));
            }
        }
        None => println!("  no estimate (log too short or no sample accepted)"),
    }
    let reasons: Vec<String> = (0..SampleError::COUNT).map(|i| format!("{} {}", SampleError::reason_name(i), r.rejected.0[i])).collect();
    println!("  rejected rows: {} ({})", r.rejected.total(), reasons.join(", "));
}

fn print_report(method: Method, rep: &Report) {
    println!("\naccuracy against the truth, {}:", method_label(method));
    print!("{}", format_accuracy(&rep.accuracy));
    if let Some(r) = &rep.rms_from_first_estimate {
        print!("{}", format_rms("from the first estimate", r));
    }
    print!("{}", format_rms("last quarter of the run", &rep.rms_last_quarter));
}

fn cmd_run(a: &RunArgs) -> anyhow::Result<()> {
    let params = a.overrides.params(a.scenario.into(), a.seed)?;
    let dir = a.out_dir.clone().unwrap_or_else(|| PathBuf::from(format!("out/{}-{}", params.scenario.name(), params.seed)));
    std::fs::create_dir_all(&dir).with_context(|| format!("{}:0: cannot create directory", dir.display()))?;
    let log = dir.join(format!("{}.csv", params.scenario.name()));
    let generated = generate(&params);
    log_csv::write_log(&log, &generated.rows)?;
    let truth = Truth::new(&params);
    log_csv::write_truth(&log_csv::truth_path(&log), &truth)?;
    println!("wrote {} ({} rows) and its truth file", log.display(), generated.rows.len());
    let mut runs: Vec<(Method, Estimated)> = Vec::new();
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        let out = dir.join(format!("{}.estimates.{}.csv", params.scenario.name(), method.name()));
        let est = estimate_file(&log, &out, a.traditional.config(method))?;
        print_summary(&log.display().to_string(), method, &est.replay, &out.display().to_string());
        print_report(method, &report(&est, &truth, &generated));
        println!();
        runs.push((method, est));
    }
    if !a.no_plots {
        let steps: Vec<(&str, &[host_sim::replay::Step])> = runs.iter().map(|(m, e)| (m.name(), e.replay.steps.as_slice())).collect();
        let window = (params.rotation_period_s / params.sample_interval_s).round() as usize;
        let files = host_sim::figures::write_figures(&dir, &generated.rows, &generated.truth, &params.errors_arcsec, params.sample_interval_s, window, &steps)?;
        println!("plots:");
        for f in files {
            println!("  {}", f.display());
        }
    }
    Ok(())
}
