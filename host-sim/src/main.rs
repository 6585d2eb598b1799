//! `host-sim`: scenario generator, log replay, reports and plots. `host-sim --help` lists the commands.

use anyhow::Context;
use clap::{Parser, Subcommand};
use host_sim::cli_args::{MethodArg, ScenarioArg, ScenarioOverrides, TraditionalArgs};
use host_sim::estimates_csv::EstimatesWriter;
use host_sim::log_csv::{self, LogReader, Truth};
use host_sim::replay::{replay, Replay};
use host_sim::scenario::generate;
use estimator_core::units::rad_to_arcsec;
use estimator_core::SampleError;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

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
    /// Replay an attitude log through the estimator and write the estimates CSV.
    Estimate(EstimateArgs),
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

fn main() {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Generate(a) => cmd_generate(a),
        Command::Estimate(a) => cmd_estimate(a).map(|_| ()),
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

fn default_estimates_path(log: &Path) -> PathBuf {
    let stem = log.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    log.with_file_name(format!("{stem}.estimates.csv"))
}

fn cmd_estimate(a: &EstimateArgs) -> anyhow::Result<Replay> {
    let out_path = a.out.clone().unwrap_or_else(|| default_estimates_path(&a.log));
    let config = a.traditional.config(a.method.into());
    let reader = LogReader::open(&a.log)?;
    let file = File::create(&out_path).with_context(|| format!("{}:0: cannot create", out_path.display()))?;
    let mut writer = EstimatesWriter::new(BufWriter::new(file))?;
    let r = replay(reader, config, Some(&mut writer))?;
    writer.finish()?;
    println!("{}: {} rows, {} accepted, {} bridged, {} window restarts; estimates in {}", a.log.display(), r.steps.len(), r.accepted, r.bridged, r.window_restarts, out_path.display());
    print_final(&r);
    Ok(r)
}

fn print_final(r: &Replay) {
    match r.final_estimate {
        Some(e) => {
            for i in 0..4 {
                println!("x{} = {:+.2} arcsec (1-sigma {:.2})", i + 1, rad_to_arcsec(e.x_rad[i] as f64), rad_to_arcsec(e.sigma_rad[i] as f64));
            }
        }
        None => println!("no estimate (log too short or never accepted)"),
    }
    println!("rejected rows: {}", r.rejected.total());
    for (i, n) in r.rejected.0.iter().enumerate().take(SampleError::COUNT) {
        println!("  {}: {}", SampleError::reason_name(i), n);
    }
}
