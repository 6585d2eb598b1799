//! `host-sim run`: a scenario generated and estimated with every method, the report against its
//! truth, the three side by side, and the paper's figures.

use crate::cmd::args::generated_log::{LogShapeArgs, ScenarioOverrides, ShipMotionArgs};
use crate::cmd::args::{ScenarioArg, TuningArgs};
use crate::cmd::warn_row;
use crate::formats::log_csv;
use crate::formats::log_paths::inputs_of;
use crate::formats::truth_file::{truth_path, write_truth, Truth};
use crate::replay::summary::write_summary;
use crate::replay::{LogReplay, Replayed, Step};
use crate::report::figures::paper::{caption_of, write_figures};
use crate::report::html::{Block, Figure, Section};
use crate::report::tables::{format_side_by_side, method_label, write_report};
use crate::report::{Report, TruthRows};
use crate::sim::recorder::recorded_rows;
use crate::sim::scenario::{generate, Generated, Row, RowTruth, ScenarioParams};
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
    let logged = write_log_and_truth(&params, &generated, &log)?;
    let mut runs = Vec::new();
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        runs.push(estimate(a, &params, &generated, &log, &dir, method)?);
    }
    println!(
        "side by side ({} scenario, seed {}):",
        params.scenario.name(),
        params.seed
    );
    let side: Vec<(&str, &Report)> = runs
        .iter()
        .map(|r| (method_label(r.method), &r.report))
        .collect();
    let side_by_side = format_side_by_side(&side);
    print!("{side_by_side}");
    let figures = PaperFigures::new(&params, &generated.truth, &logged, &runs);
    if !a.no_plots {
        println!("plots:");
        for f in figures.write(&dir)? {
            println!("  {}", f.display());
        }
    }
    match (
        &a.report,
        runs.iter().find(|r| r.method == Method::Windowed),
    ) {
        (Some(report_dir), Some(ours)) => {
            write_report_page(report_dir, &log, ours, side_by_side, &figures)
        }
        _ => Ok(()),
    }
}

/// Writes the log as the recorder records it, and its truth file; returns the rows logged.
fn write_log_and_truth(
    params: &ScenarioParams,
    generated: &Generated,
    log: &Path,
) -> anyhow::Result<Vec<Row>> {
    let logged = recorded_rows(
        &params.recording,
        params.seed,
        params.sample_interval_s,
        &generated.rows,
    );
    log_csv::write_log(log, &logged)?;
    let truth = Truth::new(params);
    write_truth(&truth_path(log), &truth)?;
    println!(
        "wrote {} ({} rows) and its truth file",
        log.display(),
        logged.len()
    );
    Ok(logged)
}

/// One method's replay of the generated log, and its report against the truth.
struct MethodRun {
    method: Method,
    replayed: Replayed,
    report: Report,
}

/// Replays the log with `method` into its estimates file in `dir`, every step kept (and our
/// method's timeline for the report), and prints its summary and report.
fn estimate(
    a: &RunArgs,
    params: &ScenarioParams,
    generated: &Generated,
    log: &Path,
    dir: &Path,
    method: Method,
) -> anyhow::Result<MethodRun> {
    let out = dir.join(format!(
        "{}.estimates.{}.csv",
        params.scenario.name(),
        method.name()
    ));
    let replayed = LogReplay {
        config: a.tuning.config(method),
        strict: true,
        estimates: Some(out.clone()),
        truth: Some(TruthRows::Generated {
            rows: &generated.rows,
            truth: &generated.truth,
            time_offset_s: params.recording.time_offset_s,
            errors_step_at_s: params.errors_step.map(|step| step.at_s),
        }),
        timeline: a.report.is_some() && method == Method::Windowed,
        steps: true,
        ..LogReplay::default()
    }
    .run(log, &mut warn_row)?;
    let mut stdout = std::io::stdout().lock();
    write_summary(
        &mut stdout,
        log,
        method,
        &replayed.replay,
        &out.display().to_string(),
    )?;
    let report = replayed
        .report
        .clone()
        .context("a report against the generated truth")?;
    write_report(&mut stdout, method, &report)?;
    writeln!(stdout)?;
    Ok(MethodRun {
        method,
        replayed,
        report,
    })
}

/// What the paper's figures are drawn from: the logged rows and every method's steps, their
/// stamps moved back onto the sample instants (the figures index the truth by them).
struct PaperFigures<'a> {
    params: &'a ScenarioParams,
    truth: &'a [RowTruth],
    rows: Vec<Row>,
    steps: Vec<(Method, Vec<Step>)>,
}

impl<'a> PaperFigures<'a> {
    fn new(
        params: &'a ScenarioParams,
        truth: &'a [RowTruth],
        logged: &[Row],
        runs: &[MethodRun],
    ) -> PaperFigures<'a> {
        let grid = |t: f64| {
            params
                .recording
                .sample_time_s(t, params.sample_interval_s)
                .unwrap_or(f64::NAN)
        };
        let steps = runs
            .iter()
            .map(|r| {
                let moved = r
                    .replayed
                    .steps
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
                (r.method, moved)
            })
            .collect();
        let rows = logged
            .iter()
            .map(|r| Row {
                time_s: grid(r.time_s),
                ..*r
            })
            .collect();
        PaperFigures {
            params,
            truth,
            rows,
            steps,
        }
    }

    /// Writes the figures into `dir`; returns their files.
    fn write(&self, dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
        let steps: Vec<(&str, &[Step])> = self
            .steps
            .iter()
            .map(|(m, s)| (m.name(), s.as_slice()))
            .collect();
        let p = self.params;
        let window = (p.rotation_period_s / p.sample_interval_s).round() as usize;
        write_figures(
            dir,
            &self.rows,
            self.truth,
            &p.errors_arcsec,
            p.sample_interval_s,
            window,
            &steps,
        )
    }
}

/// Writes the report of our method's run into `dir`, with the three methods side by side and the
/// paper's figures.
fn write_report_page(
    dir: &Path,
    log: &Path,
    ours: &MethodRun,
    side_by_side: String,
    figures: &PaperFigures,
) -> anyhow::Result<()> {
    crate::report::pages::create_dir(dir)?;
    let mut paper = Section::new("The paper's figures, from this run");
    for path in figures.write(dir)? {
        let caption = caption_of(&path);
        paper = paper.with(Block::Figure(Figure { path, caption }));
    }
    let extra = vec![
        Section::new("The three methods side by side").with(Block::Code(side_by_side)),
        paper,
    ];
    let est = &ours.replayed;
    let tl = est.timeline.as_ref().context("our method's timeline")?;
    let page = crate::report::pages::write_replay_report(
        dir,
        &log.display().to_string(),
        method_label(Method::Windowed),
        &est.replay,
        est.report.as_ref(),
        tl,
        extra,
    )?;
    println!("report in {}", page.display());
    Ok(())
}
