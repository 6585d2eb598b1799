//! What `--report DIR` writes: the plots ([`crate::report::figures`]) and `report.html`
//! ([`crate::report::html`]) of a replayed log (`estimate`, `run`), of a log streamed through the
//! firmware (`stream`) and of a Monte Carlo study (`monte-carlo`).
//!
//! The page of a log says what the estimator reported (the final estimate and status, or why
//! there is none), what it learned (the sample interval, the rotation pattern and its period),
//! what happened to the rows (accepted, rejected by reason, unreadable, filled, window restarts,
//! clock steps, the first events), the accuracy against the truth when there is a truth file,
//! and shows the plots. Statuses are named by the core ([`estimator_core::Status::name`]).

use crate::formats::time_stamps::format_utc;
use crate::replay::summary::{describe_health, describe_limit, pattern_summary, significant_4};
use crate::replay::Replay;
use crate::report::figures::monte_carlo_figure;
use crate::report::figures::report_page::timeline_figures;
use crate::report::html::{command_line, Block, Figure, Page, Section};
use crate::report::tables::{accuracy_table, format_honesty, rms_table, rms_title};
use crate::report::timeline::{EstimateArcsec, EventKind, Timeline};
use crate::report::Report;
use crate::study::monte_carlo::Summary;
use anyhow::Context;
use estimator_core::RejectReason;
use std::path::{Path, PathBuf};

/// The page's name in the report directory.
pub const PAGE: &str = "report.html";

/// Every file a report directory may get.
/// (`run --report` also writes the paper's figures, named by [`crate::report::figures::paper::write_figures`].)
pub const FILES: [&str; 7] = [
    PAGE,
    "estimates.png",
    "error.png",
    "status.png",
    "attitude.png",
    "residuals.png",
    "monte_carlo.png",
];

/// Refuses a report directory in which a report would overwrite one of the run's inputs.
pub fn check_dir(dir: &Path, inputs: &[crate::formats::output_file::Input]) -> anyhow::Result<()> {
    FILES.iter().try_for_each(|name| {
        crate::formats::output_file::check_not_input(&dir.join(name), "--report", inputs)
    })
}

/// Creates the report directory (and its parents).
pub fn create_dir(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}:0: cannot create the report directory", dir.display()))
}

/// A time for people: seconds, and the UTC date and time when the stamps are Unix time.
fn when(t: f64) -> String {
    match format_utc(t) {
        Some(utc) => format!("{utc} ({t:.3} s)"),
        None => format!("{t:.3} s"),
    }
}

fn final_estimate_section(
    estimate: Option<EstimateArcsec>,
    status: Option<&str>,
    no_estimate: Option<String>,
) -> Section {
    let mut s = Section::new("Final estimate").with(Block::Facts(vec![(
        "final status".into(),
        status.unwrap_or("none (no row accepted)").into(),
    )]));
    match estimate {
        Some(e) => {
            let rows = (0..4)
                .map(|i| {
                    vec![
                        format!("x{}", i + 1),
                        format!("{:+.3}", e.x[i]),
                        format!("{:.3}", e.sigma[i]),
                    ]
                })
                .collect();
            s = s.with(Block::Table {
                head: vec![
                    "error".into(),
                    "estimate, arcsec".into(),
                    "1-sigma, arcsec".into(),
                ],
                rows,
            });
        }
        None => {
            s = s.with(Block::Paragraph(format!(
                "No estimate: {}.",
                no_estimate.unwrap_or_else(|| "no row accepted".into())
            )))
        }
    }
    s
}

fn timeline_facts(tl: &Timeline) -> Vec<(String, String)> {
    let mut f = Vec::new();
    if let (Some(a), Some(b)) = (tl.first_time_s, tl.last_time_s) {
        f.push(("first row".into(), when(a)));
        f.push(("last row".into(), when(b)));
        f.push((
            "span".into(),
            format!("{:.0} s ({:.2} h)", b - a, (b - a) / 3600.0),
        ));
    }
    f.push((
        "first estimate at".into(),
        tl.first_estimate_s.map_or("-".into(), when),
    ));
    f.push((
        "first converged at".into(),
        tl.first_converged_s.map_or("-".into(), when),
    ));
    f
}

fn events_section(tl: &Timeline) -> Section {
    let rows: Vec<Vec<String>> = tl
        .events()
        .iter()
        .map(|e| {
            let what = match &e.kind {
                EventKind::Status { from: None, to } => format!("status {to}"),
                EventKind::Status {
                    from: Some(from),
                    to,
                } => format!("status {from} -> {to}"),
                EventKind::Gap { lost } => format!("{lost} samples lost before this row"),
                EventKind::WindowRestart => "moving average restarted".into(),
                EventKind::ClockStep => "clock step (jump or step back)".into(),
            };
            vec![when(e.time_s), what]
        })
        .collect();
    let shown = rows.len() as u64;
    let mut s = Section::new("Events");
    if tl.event_count > shown {
        s = s.with(Block::Paragraph(format!(
            "The first {shown} of {} events.",
            tl.event_count
        )));
    }
    s.with(Block::Table {
        head: vec!["time".into(), "event".into()],
        rows,
    })
}

fn accuracy_sections(report: &Report, method: &str) -> Section {
    let (head, rows) = accuracy_table(&report.accuracy);
    let mut s = Section::new(format!("Accuracy against the truth ({method})"))
        .with(Block::Table { head, rows })
        .with(Block::Paragraph(
            format_honesty(&report.accuracy.honesty)
                .trim_end()
                .to_string(),
        ));
    for (label, rms) in [
        ("from the first estimate", &report.rms_from_first_estimate),
        ("last quarter of the run", &report.rms_last_quarter),
    ] {
        if let Some(r) = rms {
            let (head, rows) = rms_table(r);
            s = s
                .with(Block::Paragraph(rms_title(label, r)))
                .with(Block::Table { head, rows });
        }
    }
    s
}

fn figures_section(figures: Vec<Figure>) -> Section {
    figures
        .into_iter()
        .fold(Section::new("Plots"), |s, f| s.with(Block::Figure(f)))
}

/// What the core counted of the rows, for the summary facts.
fn rejected_text(counts: impl Fn(RejectReason) -> u32) -> String {
    let total: u32 = RejectReason::ALL.iter().map(|r| counts(*r)).sum();
    let by: Vec<String> = RejectReason::ALL
        .iter()
        .filter(|r| counts(**r) > 0)
        .map(|r| format!("{} {}", r.name(), counts(*r)))
        .collect();
    if by.is_empty() {
        total.to_string()
    } else {
        format!("{total} ({})", by.join(", "))
    }
}

/// Writes the plots and `report.html` of a replayed log into `dir`; returns the page's path.
/// `extra` sections go after the plots.
pub fn write_replay_report(
    dir: &Path,
    log: &str,
    method: &str,
    r: &Replay,
    report: Option<&Report>,
    tl: &Timeline,
    extra: Vec<Section>,
) -> anyhow::Result<PathBuf> {
    create_dir(dir)?;
    let figures = timeline_figures(dir, tl, method, r.rotation.period_s)?;
    let mut sections = vec![
        Section::new("Summary").with(Block::Facts(replay_facts(log, method, r, tl))),
        final_estimate_section(
            tl.final_estimate(),
            r.final_status.map(|s| s.name()),
            r.holdup.map(|h| h.to_string()),
        ),
        Section::new("What was learned from the log").with(Block::Facts(learned_facts(r))),
    ];
    if let Some(rep) = report {
        sections.push(accuracy_sections(rep, method));
    }
    sections.push(figures_section(figures));
    sections.extend(extra);
    sections.push(events_section(tl));
    let page = Page {
        title: format!("RINS installation errors: {log}"),
        command: command_line(),
        sections,
    };
    let path = dir.join(PAGE);
    page.write(&path)?;
    Ok(path)
}

/// The summary of a replay: the log, the method, what happened to the rows, the alarms and the
/// limit the log sets, and the timeline's times.
fn replay_facts(log: &str, method: &str, r: &Replay, tl: &Timeline) -> Vec<(String, String)> {
    let c = &r.counters;
    let mut rows = vec![
        ("log".to_string(), log.to_string()),
        ("method".into(), method.into()),
        (
            "rows".into(),
            format!("{} stepped, {} accepted", r.rows, c.accepted),
        ),
        (
            "rejected rows".into(),
            rejected_text(|reason| r.rejected.of(reason)),
        ),
        (
            "unreadable rows skipped".into(),
            r.unreadable.skipped.to_string(),
        ),
        ("lost samples filled".into(), c.filled.to_string()),
        ("window restarts".into(), c.window_restarts.to_string()),
        ("clock steps".into(), c.clock_steps.to_string()),
        (
            "alarms".into(),
            describe_health(&r.health)
                .trim_start_matches("alarms: ")
                .to_string(),
        ),
    ];
    if let Some(limit) = describe_limit(&r.health) {
        rows.push((
            "limit".into(),
            limit.trim_start_matches("limit: ").to_string(),
        ));
    }
    if let Some(loss) = &r.regular_loss {
        rows.push((
            "limit".into(),
            loss.describe().trim_start_matches("limit: ").to_string(),
        ));
    }
    if let Some(b) = &r.binning {
        // The rows above are the bins the estimator stepped.
        rows.insert(2, ("binned".into(), b.describe()));
    }
    rows.extend(timeline_facts(tl));
    rows
}

/// What was learned of the log: the sample interval and the rotation pattern.
fn learned_facts(r: &Replay) -> Vec<(String, String)> {
    vec![
        (
            "sample interval".to_string(),
            r.sample_interval_s.map_or("not yet learned".into(), |d| {
                format!("{} s", significant_4(d))
            }),
        ),
        (
            "rotation pattern".into(),
            r.rotation
                .kind
                .map_or("not yet learned".into(), |k| k.name().to_string()),
        ),
        (
            "rotation period".into(),
            match r.rotation.period_s {
                Some(p) => format!(
                    "{} s{}",
                    significant_4(p),
                    if r.rotation.pinned { " (pinned)" } else { "" }
                ),
                None => "not yet detected".into(),
            },
        ),
        (
            "samples per window entry".into(),
            r.rotation.samples_per_entry.to_string(),
        ),
        ("in one line".into(), pattern_summary(r)),
    ]
}

/// Writes the plots and `report.html` of a log streamed through the firmware into `dir`.
pub fn write_stream_report(
    dir: &Path,
    log: &str,
    through: &str,
    status: &link_protocol::StatusReply,
    report: Option<&Report>,
    tl: &Timeline,
) -> anyhow::Result<PathBuf> {
    create_dir(dir)?;
    let method = estimator_core::Method::try_from(status.method).map_or("unknown", |m| m.name());
    let figures = timeline_figures(dir, tl, method, None)?;
    let mut facts = vec![
        ("log".to_string(), log.to_string()),
        ("streamed through".into(), through.to_string()),
        ("method (the firmware's)".into(), method.to_string()),
        (
            "samples accepted by the firmware".into(),
            status.accepted.to_string(),
        ),
        (
            "rejected samples".into(),
            rejected_text(|reason| {
                status
                    .counters
                    .rejected_samples
                    .get(reason as usize)
                    .copied()
                    .unwrap_or(0)
            }),
        ),
        (
            "bad frames".into(),
            status.counters.bad_frames_total().to_string(),
        ),
        ("lost samples filled".into(), status.filled.to_string()),
        ("window restarts".into(), status.window_restarts.to_string()),
        (
            "clock steps (from the stamps)".into(),
            tl.buckets().map(|b| b.clock_steps).sum::<u64>().to_string(),
        ),
    ];
    facts.extend(timeline_facts(tl));
    let final_status = tl.events().iter().rev().find_map(|e| match e.kind {
        EventKind::Status { to, .. } => Some(to),
        _ => None,
    });
    let mut sections = vec![
        Section::new("Summary").with(Block::Facts(facts)),
        final_estimate_section(tl.final_estimate(), final_status, Some("the firmware reports none".into())),
        Section::new("What was learned from the log").with(Block::Paragraph(
            "The firmware does not report the sample interval or the rotation pattern it learned over the link; `host-sim estimate` on the same log prints them (its estimates are byte-identical).".into(),
        )),
    ];
    if let Some(rep) = report {
        sections.push(accuracy_sections(rep, method));
    }
    sections.push(figures_section(figures));
    sections.push(events_section(tl));
    let page = Page {
        title: format!("RINS installation errors, streamed through the firmware: {log}"),
        command: command_line(),
        sections,
    };
    let path = dir.join(PAGE);
    page.write(&path)?;
    Ok(path)
}

/// What a Monte Carlo report says of its study.
pub struct MonteCarloStudy<'a> {
    /// The draw in words, in the page's title.
    pub description: String,
    /// Name-value pairs of the study (scenario, method, runs, seeds...).
    pub facts: Vec<(String, String)>,
    /// The statistics over time, plotted.
    pub summary: &'a Summary,
    /// The table as printed (markdown).
    pub table: String,
}

/// Writes the statistics over time (`monte_carlo.png`) and `report.html` of a Monte Carlo study.
pub fn write_monte_carlo_report(dir: &Path, study: &MonteCarloStudy) -> anyhow::Result<PathBuf> {
    create_dir(dir)?;
    let png = dir.join("monte_carlo.png");
    monte_carlo_figure(&png, study.summary)?;
    let sections = vec![
        Section::new("Study").with(Block::Facts(study.facts.clone())),
        Section::new("Absolute error over the runs, arcsec").with(Block::Code(study.table.clone())),
        figures_section(vec![Figure {
            path: png,
            caption: "Median, 95th percentile and largest absolute error over the runs, and the share of errors within twice their reported 1-sigma, over time".into(),
        }]),
    ];
    let page = Page {
        title: format!(
            "RINS installation errors: Monte Carlo, {}",
            study.description
        ),
        command: command_line(),
        sections,
    };
    let path = dir.join(PAGE);
    page.write(&path)?;
    Ok(path)
}
