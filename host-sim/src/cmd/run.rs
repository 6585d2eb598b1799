//! `host-sim run`: a scenario generated and estimated with every method, the report against its
//! truth, the three side by side, and the paper's figures.

use crate::cmd::args::generated_log::{LogShapeArgs, ScenarioOverrides, ShipMotionArgs};
use crate::cmd::args::{ScenarioArg, TuningArgs};
use crate::cmd::{print_report, print_summary, warn_row};
use crate::formats::log_csv;
use crate::formats::log_paths::inputs_of;
use crate::formats::truth_file::{truth_path, write_truth, Truth};
use crate::pipeline::{estimate_log, EstimateOptions};
use crate::replay::Step;
use crate::report::method_label;
use crate::report::{Report, TruthRows};
use crate::sim::recorder::recorded_rows;
use crate::sim::scenario::generate;
use anyhow::Context;
use estimator_core::Method;
use std::io::Write;
use std::path::{Path, PathBuf};

/// `host-sim run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    scenario: ScenarioArg,
    /// Seed of the random phases, sway spectrum and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    overrides: ScenarioOverrides,
    #[command(flatten)]
    shape: LogShapeArgs,
    #[command(flatten)]
    motion: ShipMotionArgs,
    #[command(flatten)]
    tuning: TuningArgs,
    /// Output directory (default: out/SCENARIO-SEED).
    #[arg(long, value_name = "DIR")]
    out_dir: Option<PathBuf>,
    /// Skip the plots.
    #[arg(long)]
    no_plots: bool,
    /// Write the report of our method's run (its plots and the paper's figures) and a
    /// self-contained report.html into DIR (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
}

/// `host-sim run`: generates the scenario's log and truth, estimates it with every method, prints
/// each summary and report and the three side by side, and draws the paper's figures and the
/// report when asked.
pub fn run(a: &RunArgs) -> anyhow::Result<()> {
    let mut params = a.overrides.params(a.scenario.into(), a.seed)?;
    a.shape.apply(&mut params)?;
    a.motion.apply(&mut params)?;
    let dir = a.out_dir.clone().unwrap_or_else(|| {
        PathBuf::from(format!("out/{}-{}", params.scenario.name(), params.seed))
    });
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("{}:0: cannot create directory", dir.display()))?;
    let log = dir.join(format!("{}.csv", params.scenario.name()));
    if let Some(report_dir) = &a.report {
        crate::report::pages::check_dir(report_dir, &inputs_of(&log))?;
    }
    let generated = generate(&params);
    let logged = recorded_rows(
        &params.recording,
        params.seed,
        params.sample_interval_s,
        &generated.rows,
    );
    log_csv::write_log(&log, &logged)?;
    let truth = Truth::new(&params);
    write_truth(&truth_path(&log), &truth)?;
    println!(
        "wrote {} ({} rows) and its truth file",
        log.display(),
        logged.len()
    );
    let mut runs: Vec<(Method, Vec<Step>)> = Vec::new();
    let mut reports: Vec<(Method, Report)> = Vec::new();
    let mut ours = None;
    let mut stdout = std::io::stdout().lock();
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        let out = dir.join(format!(
            "{}.estimates.{}.csv",
            params.scenario.name(),
            method.name()
        ));
        let timeline = a.report.is_some() && method == Method::Windowed;
        let options = EstimateOptions {
            config: a.tuning.config(method),
            restart_at_s: vec![],
            strict: true,
            timeline,
            bin_interval_s: None,
        };
        let mut steps = Vec::with_capacity(generated.rows.len());
        let rows = TruthRows::Generated {
            rows: &generated.rows,
            truth: &generated.truth,
            time_offset_s: params.recording.time_offset_s,
            errors_step_at_s: params.errors_step.map(|step| step.at_s),
        };
        let est = estimate_log(
            &log,
            &out,
            &options,
            Some(rows),
            &mut warn_row,
            &mut |view| {
                steps.push(Step {
                    time_s: view.line.row.time_s,
                    result: *view.result,
                })
            },
        )?;
        print_summary(
            &mut stdout,
            &log,
            method,
            &est.replay,
            &out.display().to_string(),
        )?;
        let rep = est
            .report
            .clone()
            .context("a report against the generated truth")?;
        print_report(&mut stdout, method, &rep)?;
        writeln!(stdout)?;
        runs.push((method, steps));
        reports.push((method, rep));
        if timeline {
            ours = Some(est);
        }
    }
    drop(stdout);
    println!(
        "side by side ({} scenario, seed {}):",
        params.scenario.name(),
        params.seed
    );
    let side: Vec<(&str, &Report)> = reports.iter().map(|(m, r)| (method_label(*m), r)).collect();
    let side_by_side = crate::report::format_side_by_side(&side);
    print!("{side_by_side}");
    // The figures index the truth by sample instant: stamps moved back onto it.
    let grid = |t: f64| {
        params
            .recording
            .sample_time_s(t, params.sample_interval_s)
            .unwrap_or(f64::NAN)
    };
    let on_grid: Vec<(Method, Vec<Step>)> = runs
        .iter()
        .map(|(m, steps)| {
            let moved = steps
                .iter()
                .map(|s| {
                    let mut s = *s;
                    s.time_s = grid(s.time_s);
                    if let Ok(o) = &mut s.result {
                        o.time_s = grid(o.time_s);
                    }
                    s
                })
                .collect();
            (*m, moved)
        })
        .collect();
    let steps: Vec<(&str, &[Step])> = on_grid
        .iter()
        .map(|(m, s)| (m.name(), s.as_slice()))
        .collect();
    let window = (params.rotation_period_s / params.sample_interval_s).round() as usize;
    let grid_rows: Vec<_> = logged
        .iter()
        .map(|r| crate::sim::scenario::Row {
            time_s: grid(r.time_s),
            ..*r
        })
        .collect();
    let paper_figures = |into: &Path| {
        crate::report::figures::write_figures(
            into,
            &grid_rows,
            &generated.truth,
            &params.errors_arcsec,
            params.sample_interval_s,
            window,
            &steps,
        )
    };
    if !a.no_plots {
        println!("plots:");
        for f in paper_figures(&dir)? {
            println!("  {}", f.display());
        }
    }
    if let (Some(report_dir), Some(est)) = (&a.report, &ours) {
        use crate::report::html::{Block, Figure, Section};
        crate::report::pages::create_dir(report_dir)?;
        let figures = paper_figures(report_dir)?;
        let mut paper = Section::new("The paper's figures, from this run");
        for path in figures {
            let caption = crate::report::figures::caption_of(&path);
            paper = paper.with(Block::Figure(Figure { path, caption }));
        }
        let extra = vec![
            Section::new("The three methods side by side").with(Block::Code(side_by_side)),
            paper,
        ];
        let tl = est.timeline.as_ref().context("our method's timeline")?;
        let page = crate::report::pages::write_replay_report(
            report_dir,
            &log.display().to_string(),
            method_label(Method::Windowed),
            &est.replay,
            est.report.as_ref(),
            tl,
            extra,
        )?;
        println!("report in {}", page.display());
    }
    Ok(())
}
