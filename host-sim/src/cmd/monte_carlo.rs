//! `host-sim monte-carlo`: many independent runs of a scenario in parallel, the error statistics
//! over them at the table's times, their JSON summary and their report.

use crate::cmd::args::generated_log::SpreadArgs;
use crate::cmd::args::{MethodArg, ScenarioArg, TuningArgs};
use crate::exit_status::RunEnd;
use crate::report::honesty::Honesty;
use crate::report::tables::method_label;
use crate::sim::rotation_scheme::RotationScheme;
use crate::study::monte_carlo::Draw;
use crate::study::monte_carlo::{
    format_summary, run_all, summarize, StudyJson, Summary, MC_TIMES_S,
};
use estimator_core::Method;
use std::path::{Path, PathBuf};

/// `host-sim monte-carlo`.
#[derive(clap::Args, Debug)]
pub struct MonteCarloArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    scenario: ScenarioArg,
    /// Number of runs.
    #[arg(long)]
    runs: usize,
    /// Master seed (run i uses a seed derived from it).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = MethodArg::Windowed)]
    method: MethodArg,
    /// Rotation scheme of the RINS.
    #[arg(long, value_enum, default_value_t)]
    scheme: RotationScheme,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    spread: SpreadArgs,
    /// Write the summary as JSON (with the scenario, method, seeds and command).
    #[arg(long, value_name = "summary.json")]
    out: Option<PathBuf>,
    /// Write the error percentiles and 2-sigma coverage over time (PNG) and a self-contained
    /// report.html into DIR (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

fn thread_pool(threads: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        anyhow::ensure!(n >= 1, "--threads must be at least 1");
        b = b.num_threads(n);
    }
    Ok(b.build()?)
}

/// A progress bar of `len` steps on standard error when it is a terminal (hidden otherwise).
fn progress_bar(len: u64, unit: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{eta}} left"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// `host-sim monte-carlo`: runs the draws in parallel, prints the statistics at the table's times,
/// writes the JSON summary and the report when asked; exit status 4 when no run has an estimate
/// by the table's times.
pub fn run(a: &MonteCarloArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.runs >= 1, "--runs must be at least 1");
    let draw = a.spread.draw(a.scenario.into(), a.scheme, a.seed)?;
    draw.check_duration()?;
    let method: Method = a.method.into();
    let config = a.tuning.config(method);
    if let Some(dir) = &a.report {
        crate::report::pages::create_dir(dir)?;
    }
    let duration_s = draw.params(0).duration_s;
    let times = crate::study::monte_carlo::tracked_times_s(duration_s);
    let bar = progress_bar(a.runs as u64, "runs");
    let start = std::time::Instant::now();
    let pool = thread_pool(a.threads)?;
    let results = pool.install(|| run_all(&draw, config, a.runs, &times, &|| bar.inc(1)))?;
    bar.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    let over_time = summarize(&results);
    let summary = over_time.at_times(&MC_TIMES_S);
    let description = crate::study::compare::describe(&draw);
    println!(
        "monte carlo: scenario {} ({description}), method {}, {} runs of {duration_s:.0} s in {elapsed:.1} s ({} threads)",
        draw.kind.name(),
        method.name(),
        a.runs,
        pool.current_num_threads()
    );
    println!("absolute error |x_hat - x| over runs, arcsec:");
    let honesty = crate::study::monte_carlo::pool_honesty(&results);
    let table = format_summary(&summary)
        + &crate::study::monte_carlo::format_honesty_over_runs(&honesty, results.len());
    print!("{table}");
    let ran = Ran {
        draw: &draw,
        method,
        runs: a.runs,
        duration_s,
        description,
        over_time,
        summary,
        honesty,
        table,
    };
    if let Some(out) = &a.out {
        write_json(out, &ran)?;
    }
    if let Some(dir) = &a.report {
        let wall = format!("{elapsed:.1} s on {} threads", pool.current_num_threads());
        write_report(dir, &ran, wall)?;
    }
    if ran.summary.no_estimate() {
        return Err(RunEnd::NoEstimate {
            reason: format!(
                "no run reached an estimate by the table's times ({} s and after)",
                MC_TIMES_S[0]
            ),
        }
        .into());
    }
    Ok(())
}

/// A study as it ran: what its JSON summary and its report say.
struct Ran<'a> {
    draw: &'a Draw,
    method: Method,
    runs: usize,
    duration_s: f64,
    description: String,
    over_time: Summary,
    summary: Summary,
    honesty: Honesty,
    /// The table as printed.
    table: String,
}

/// Writes the summary as JSON (with the scenario, method, seeds and command) to `out`.
fn write_json(out: &Path, ran: &Ran) -> anyhow::Result<()> {
    let draw = ran.draw;
    let json = StudyJson {
        scenario: draw.kind.name().to_string(),
        method: ran.method.name().to_string(),
        scheme: draw.scheme.name().to_string(),
        description: ran.description.clone(),
        duration_s: ran.duration_s,
        master_seed: draw.seed,
        run_seeds: (0..ran.runs).map(|i| draw.run_seed(i)).collect(),
        command: crate::report::html::command_line(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        summary: ran.summary.clone(),
        over_time: ran.over_time.clone(),
        honesty: ran.honesty,
    };
    let text = serde_json::to_string_pretty(&json)?;
    crate::formats::output_file::write_bytes(out, (text + "\n").as_bytes())?;
    println!("summary in {}", out.display());
    Ok(())
}

/// Writes the report of the study into `dir`; `wall`: the wall time it took, and on how many
/// threads.
fn write_report(dir: &Path, ran: &Ran, wall: String) -> anyhow::Result<()> {
    let draw = ran.draw;
    let facts = vec![
        ("scenario".to_string(), draw.kind.name().to_string()),
        ("draw".into(), ran.description.clone()),
        ("method".into(), method_label(ran.method).to_string()),
        ("rotation scheme".into(), draw.scheme.name().to_string()),
        (
            "runs".into(),
            format!("{} of {:.0} s", ran.runs, ran.duration_s),
        ),
        ("master seed".into(), draw.seed.to_string()),
        ("wall time".into(), wall),
    ];
    let study = crate::report::pages::MonteCarloStudy {
        description: ran.description.clone(),
        facts,
        summary: &ran.over_time,
        table: ran.table.clone(),
    };
    let page = crate::report::pages::write_monte_carlo_report(dir, &study)?;
    println!("report in {}", page.display());
    Ok(())
}
