//! `compare`: every method on every scenario over several seeds, as a markdown table for docs/results.md;
//! one table per rotation scheme, headed by how its logs are made ([`describe`]). Besides the
//! errors at two times, the honesty of the 1-sigma row by row ([`crate::report::honesty::Honesty`]): the
//! share of the runs' rows where some error lies beyond 2 and 3 sigma, and the largest
//! |error| / 1-sigma of any run.

use crate::replay::HostEstimator;
use crate::report::accuracy::Accuracy;
use crate::report::honesty::Honesty;
use crate::report::tables::{method_label, percent_of_rows};
use crate::sim::scenario::ScenarioKind;
use crate::sim::ship_motion::ShipMotionSettings;
use crate::study::monte_carlo::{coverage_2sigma, pool_honesty, quantile, run_all, sorted, Draw};
use estimator_core::{Config, Method};

/// Times of the error columns, s.
pub const COMPARE_TIMES_S: [f64; 3] = [2_000.0, 20_000.0, 45_000.0];

/// One line of the table: a method on a scenario over seeds.
#[derive(Clone, Debug)]
pub struct CompareRow {
    /// The scenario.
    pub scenario: ScenarioKind,
    /// The identification method.
    pub method: Method,
    /// Runs, one per seed.
    pub runs: usize,
    /// Time after which all four errors stay within 0.5 % (infinite: not within at the end),
    /// median and 95th percentile over seeds, s.
    pub to_percent_s: (f64, f64),
    /// Time after which all four errors stay within 10 arcsec (infinite: not within at the end),
    /// median and 95th percentile over seeds, s.
    pub to_arcsec_s: (f64, f64),
    /// Largest |error| of the four at each of [`COMPARE_TIMES_S`] inside the run (NaN outside),
    /// median and 95th percentile, arcsec.
    pub error_at_arcsec: Vec<(f64, f64)>,
    /// Share of (run, error) pairs within twice the reported 1-sigma at each of
    /// [`COMPARE_TIMES_S`] inside the run (NaN outside; [`coverage_2sigma`]).
    pub coverage_2sigma: Vec<f64>,
    /// Length of each run, s.
    pub duration_s: f64,
    /// Row-level honesty of the 1-sigma, pooled over the runs' rows (the largest |error| /
    /// 1-sigma: the largest over the runs).
    pub honesty: Honesty,
    /// Status at the end of each run, with how many runs ended in it (most frequent first); a
    /// configuration the estimator rejects counts every run under `configuration rejected (...)`.
    pub final_status: Vec<(String, usize)>,
}

fn stats(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let v = sorted(values);
    (quantile(&v, 0.5), quantile(&v, 0.95))
}

/// Runs `seeds` draws of a scenario with a method. A configuration the estimator rejects (e.g. a
/// rotation period longer than its window holds) gives a line without estimates that says so.
pub fn compare_one(draw: &Draw, config: Config, seeds: usize) -> anyhow::Result<CompareRow> {
    let inf = f64::INFINITY;
    let duration_s = draw.params(0).duration_s;
    if let Err(e) = HostEstimator::new(config) {
        return Ok(rejected_row(draw, config, seeds, duration_s, &e));
    }
    let results: Vec<Accuracy> = run_all(draw, config, seeds, &COMPARE_TIMES_S, &|| {})?;
    let error_at_arcsec = COMPARE_TIMES_S
        .iter()
        .enumerate()
        .map(|(k, t)| {
            if *t > duration_s {
                return (f64::NAN, f64::NAN);
            }
            stats(results.iter().map(|r| {
                r.points
                    .get(k)
                    .and_then(|p| p.error_arcsec)
                    .map_or(inf, |e| e.iter().fold(0.0, |m, x| f64::max(m, x.abs())))
            }))
        })
        .collect();
    let coverage = COMPARE_TIMES_S
        .iter()
        .enumerate()
        .map(|(k, t)| {
            if *t > duration_s {
                f64::NAN
            } else {
                coverage_2sigma(&results, k)
            }
        })
        .collect();
    let honesty = pool_honesty(&results);
    Ok(CompareRow {
        scenario: draw.kind,
        final_status: final_statuses(&results),
        method: config.method,
        runs: seeds,
        to_percent_s: stats(
            results
                .iter()
                .map(|r| r.all_within_percent_from_s().unwrap_or(inf)),
        ),
        to_arcsec_s: stats(
            results
                .iter()
                .map(|r| r.all_within_arcsec_from_s().unwrap_or(inf)),
        ),
        error_at_arcsec,
        coverage_2sigma: coverage,
        duration_s,
        honesty,
    })
}

/// The line of a configuration the estimator rejects (`e`): no estimate in any run.
fn rejected_row(
    draw: &Draw,
    config: Config,
    seeds: usize,
    duration_s: f64,
    e: &estimator_core::ConfigError,
) -> CompareRow {
    let inf = f64::INFINITY;
    CompareRow {
        scenario: draw.kind,
        method: config.method,
        runs: seeds,
        to_percent_s: (inf, inf),
        to_arcsec_s: (inf, inf),
        error_at_arcsec: COMPARE_TIMES_S
            .iter()
            .map(|t| {
                if *t > duration_s {
                    (f64::NAN, f64::NAN)
                } else {
                    (inf, inf)
                }
            })
            .collect(),
        coverage_2sigma: COMPARE_TIMES_S
            .iter()
            .map(|t| if *t > duration_s { f64::NAN } else { 0.0 })
            .collect(),
        duration_s,
        honesty: Honesty::default(),
        final_status: vec![(format!("configuration rejected ({e:?})"), seeds)],
    }
}

/// The statuses the runs ended in, each with how many runs ended in it, most frequent first.
fn final_statuses(results: &[Accuracy]) -> Vec<(String, usize)> {
    let mut final_status: Vec<(String, usize)> = Vec::new();
    for name in results
        .iter()
        .map(|r| r.final_status.map_or("none", |s| s.name()))
    {
        match final_status.iter_mut().find(|(n, _)| n == name) {
            Some((_, count)) => *count += 1,
            None => final_status.push((name.to_string(), 1)),
        }
    }
    final_status.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    final_status
}

fn fmt_time(t: f64, duration_s: f64) -> String {
    if t.is_finite() {
        format!("{t:.0}")
    } else {
        format!("> {duration_s:.0}")
    }
}

fn fmt_share(v: f64) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{:.1} %", 100.0 * v)
    }
}

fn fmt_err(e: f64) -> String {
    if e.is_nan() {
        "-".into()
    } else if e.is_infinite() {
        "no estimate".into()
    } else {
        format!("{e:.2}")
    }
}

/// The markdown table.
pub fn format_table(rows: &[CompareRow]) -> String {
    let mut s = String::from(
        "| scenario | method | runs | time to 0.5 % s (median / p95) | time to 10 arcsec s (median / p95) | max abs error at 2000 s arcsec (median / p95) | max abs error at 20000 s arcsec (median / p95) | max abs error at 45000 s arcsec (median / p95) | errors within 2 sigma at 20000 / 45000 s | rows beyond 2 / 3 sigma | largest error/sigma | status at the end (runs) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let d = r.duration_s;
        let h = &r.honesty;
        s.push_str(&format!(
            "| {} | {} | {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} | {} |\n",
            r.scenario.name(),
            method_label(r.method),
            r.runs,
            fmt_time(r.to_percent_s.0, d),
            fmt_time(r.to_percent_s.1, d),
            fmt_time(r.to_arcsec_s.0, d),
            fmt_time(r.to_arcsec_s.1, d),
            fmt_err(r.error_at_arcsec[0].0),
            fmt_err(r.error_at_arcsec[0].1),
            fmt_err(r.error_at_arcsec[1].0),
            fmt_err(r.error_at_arcsec[1].1),
            fmt_err(r.error_at_arcsec[2].0),
            fmt_err(r.error_at_arcsec[2].1),
            fmt_share(r.coverage_2sigma[1]),
            fmt_share(r.coverage_2sigma[2]),
            percent_of_rows(h.beyond_2_sigma_rows, h.rows),
            percent_of_rows(h.beyond_3_sigma_rows, h.rows),
            h.largest.map_or("-".to_string(), |l| format!("{:.1}", l.ratio)),
            r.final_status
                .iter()
                .map(|(n, c)| format!("{n} ({c})"))
                .collect::<Vec<_>>()
                .join(", "),
        ));
    }
    s
}

/// How the logs of a draw are made, one line: scheme, period, interval, the recorder and the
/// ship's slow motions (when there are any).
pub fn describe(draw: &Draw) -> String {
    let p = draw.params(0);
    let mut s = format!(
        "scheme {}, rotation period {} s, a row every {} s",
        p.scheme.name(),
        p.rotation_period_s,
        p.sample_interval_s
    );
    let r = &draw.recorder;
    let mut rec = Vec::new();
    if r.drop_fraction > 0.0 {
        rec.push(format!(
            "{} % of rows dropped at random",
            100.0 * r.drop_fraction
        ));
    }
    if r.outages > 0 {
        rec.push(format!(
            "{} outages of {} s",
            r.outages,
            crate::sim::recorder::OUTAGE_S
        ));
    }
    if r.gap_every_s > 0.0 && r.gap_rows > 0 {
        rec.push(format!(
            "{} rows lost every {} s",
            r.gap_rows, r.gap_every_s
        ));
    }
    if r.time_offset_s != 0.0 {
        rec.push(format!("time stamps offset by {} s", r.time_offset_s));
    }
    if r.time_jitter_s > 0.0 {
        rec.push(format!(
            "time stamps jittered by up to {} s",
            r.time_jitter_s
        ));
    }
    if rec.is_empty() {
        s.push_str(", every row, exact time stamps");
    } else {
        s.push_str(&format!("; recorder: {}", rec.join(", ")));
    }
    let ship = describe_ship(&draw.ship_motion, draw.mismatch.heel_in_turns_deg);
    if !ship.is_empty() {
        s.push_str(&format!("; ship: {ship}"));
    }
    s
}

/// The ship's slow motions in words (empty when there are none).
fn describe_ship(m: &ShipMotionSettings, heel_in_turns_deg: f64) -> String {
    let sinusoids = |items: &[(f64, f64)]| {
        items
            .iter()
            .map(|(a, p)| format!("{a} deg / {p} s"))
            .collect::<Vec<_>>()
            .join(" + ")
    };
    let mut parts = Vec::new();
    if !m.slow_heel.is_empty() {
        parts.push(format!("slow heel {}", sinusoids(&m.slow_heel)));
    }
    if !m.slow_trim.is_empty() {
        parts.push(format!("slow trim {}", sinusoids(&m.slow_trim)));
    }
    if heel_in_turns_deg != 0.0 {
        parts.push(format!("turns heeling {heel_in_turns_deg} deg"));
    }
    if m.heel_per_turn_rate_deg_per_deg_s != 0.0 {
        parts.push(format!(
            "heel {} deg per deg/s of turn",
            m.heel_per_turn_rate_deg_per_deg_s
        ));
    }
    parts.join(", ")
}
