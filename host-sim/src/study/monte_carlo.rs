//! Monte Carlo runs: many independent scenarios (random errors, phases, sea states, optional
//! latitude spread, rougher sway and model mismatch; any rotation scheme, sample interval and
//! recorder), each generated, recorded and replayed row by row in memory, in parallel (rayon), with
//! the error statistics per report time.

use crate::replay::sample_of;
use crate::report::accuracy::{Accuracy, Tracker};
use crate::report::honesty::Honesty;
use crate::report::tables::{format_honesty_shares, rows_text};
use crate::sim::recorder::{Recorder, RecorderError, RecorderSettings, Recording};
use crate::sim::rotation_scheme::RotationScheme;
use crate::sim::samples::Samples;
use crate::sim::scenario::{Mismatch, ScenarioKind, ScenarioParams, SwayComponent, SwayLinesError};
use crate::sim::ship_motion::ShipMotionSettings;
use estimator_core::Config;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

/// Report times of the Monte Carlo summary, s (those inside the run are used).
pub const MC_TIMES_S: [f64; 6] = [2_000.0, 5_000.0, 10_000.0, 20_000.0, 45_000.0, 86_400.0];

/// Points of the statistics over time drawn in the report (and written in the JSON's `over_time`).
pub const PLOT_POINTS: usize = 80;

/// The times tracked in each run: the table's ([`MC_TIMES_S`]) and [`PLOT_POINTS`] evenly spaced
/// over the run for the plot, ascending.
pub fn tracked_times_s(duration_s: f64) -> Vec<f64> {
    let step = duration_s / PLOT_POINTS as f64;
    let mut times: Vec<f64> = (1..=PLOT_POINTS)
        .map(|k| (k as f64 * step).round())
        .chain(MC_TIMES_S)
        .filter(|t| *t > 0.0)
        .collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    times
}

/// Why a Monte Carlo study cannot give its table.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum StudyError {
    /// The runs end before the table's first time.
    #[error(
        "--duration {duration_s} s ends before the table's first time, {first_s} s: nothing to report \
         (a first estimate takes about two rotation periods, {two_periods_s} s here, after the sample interval is learned); \
         give --duration {first_s} or more"
    )]
    TooShort {
        /// Length of each run, s.
        duration_s: f64,
        /// The table's first time, s.
        first_s: f64,
        /// Two rotation periods, s: about when a first estimate comes.
        two_periods_s: f64,
    },
}

impl Draw {
    /// Checks that the runs are long enough for the table.
    pub fn check_duration(&self) -> Result<(), StudyError> {
        let p = self.params(0);
        let first_s = MC_TIMES_S[0];
        if p.duration_s < first_s {
            return Err(StudyError::TooShort {
                duration_s: p.duration_s,
                first_s,
                two_periods_s: 2.0 * p.rotation_period_s,
            });
        }
        Ok(())
    }
}

/// Why a Monte Carlo draw cannot make its scenarios.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ScenarioError {
    /// The rotation scheme needs a longer period (its stops and turns do not fit).
    #[error("the {scheme} scheme needs a rotation period of at least {min_period_s} s")]
    PeriodTooShortForScheme {
        /// Name of the rotation scheme.
        scheme: &'static str,
        /// The shortest rotation period the scheme takes, s.
        min_period_s: f64,
    },
    /// The log is shorter than one sample interval.
    #[error("the log ({duration_s} s) is shorter than one sample interval ({interval_s} s)")]
    ShorterThanOneSample {
        /// Length of the log, s.
        duration_s: f64,
        /// Interval between samples, s.
        interval_s: f64,
    },
    /// The recorder's settings.
    #[error(transparent)]
    Recorder(#[from] RecorderError),
    /// The sea's sway cannot be drawn with the lines asked for.
    #[error(transparent)]
    SwayLines(#[from] SwayLinesError),
}

/// How the runs are drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw {
    /// The scenario every run starts from.
    pub kind: ScenarioKind,
    /// Master seed: run `i` uses [`Draw::run_seed`] of `i`.
    pub seed: u64,
    /// Installation errors: magnitude uniform in this range (arcsec), random sign.
    pub error_magnitude_arcsec: (f64, f64),
    /// Latitude uniform in this range, deg (default: the scenario's).
    pub lat_range_deg: Option<(f64, f64)>,
    /// Roll sway amplitude (sqrt(2) x RMS) uniform between the scenario's and this, deg.
    pub max_roll_deg: Option<f64>,
    /// Effects outside eq (2), the same in every run.
    pub mismatch: Mismatch,
    /// The ship's slow heel and trim and its heel per turn rate; the phases drawn per run, from
    /// the run's seed.
    pub ship_motion: ShipMotionSettings,
    /// Log length override, s.
    pub duration_s: Option<f64>,
    /// Rotation scheme of every run.
    pub scheme: RotationScheme,
    /// Rotation period override, s.
    pub rotation_period_s: Option<f64>,
    /// Sample interval override, s.
    pub sample_interval_s: Option<f64>,
    /// The recorder; outages are placed per run, from the run's seed.
    pub recorder: RecorderSettings,
    /// Sea scenario: sinusoids in each wave spectrum of the sway, drawn per run from the run's
    /// seed ([`ScenarioParams::redraw_sea_sway`]); `None`: the scenario's own.
    pub sway_lines: Option<usize>,
}

impl Draw {
    /// Runs of `kind` from master seed `seed`: error magnitudes from 100 to 500 arcsec, no spread,
    /// mismatch, ship motion or recorder effects, everything else the scenario's.
    pub fn new(kind: ScenarioKind, seed: u64) -> Draw {
        Draw {
            kind,
            seed,
            error_magnitude_arcsec: (100.0, 500.0),
            lat_range_deg: None,
            max_roll_deg: None,
            mismatch: Mismatch::default(),
            ship_motion: ShipMotionSettings::default(),
            duration_s: None,
            scheme: RotationScheme::Continuous,
            rotation_period_s: None,
            sample_interval_s: None,
            recorder: RecorderSettings::default(),
            sway_lines: None,
        }
    }

    /// Checks that every run's scenario can be made: the scheme fits in its period, the recorder's
    /// settings are valid and its outages fit in the log.
    pub fn check(&self) -> Result<(), ScenarioError> {
        if let Some(lines) = self.sway_lines {
            ScenarioParams::new(self.kind, self.run_seed(0)).redraw_sea_sway(lines)?;
        }
        let p = self.params(0);
        if p.rotation_period_s < p.scheme.min_period_s() {
            return Err(ScenarioError::PeriodTooShortForScheme {
                scheme: p.scheme.name(),
                min_period_s: p.scheme.min_period_s(),
            });
        }
        if p.duration_s < p.sample_interval_s {
            return Err(ScenarioError::ShorterThanOneSample {
                duration_s: p.duration_s,
                interval_s: p.sample_interval_s,
            });
        }
        self.recorder
            .recording(self.run_seed(0), p.duration_s, p.sample_interval_s)?;
        Ok(())
    }

    /// Seed of run `i` (distinct runs, reproducible).
    pub fn run_seed(&self, i: usize) -> u64 {
        // SplitMix64 of (seed, i).
        let mut z = self
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(i as u64)
            .wrapping_add(0x632B_E59B_D9B4_E019);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// The scenario of run `i`: the scenario's own phases and sea state for the run's seed, plus
    /// random errors and the spreads asked for.
    pub fn params(&self, i: usize) -> ScenarioParams {
        let seed = self.run_seed(i);
        let mut p = ScenarioParams::new(self.kind, seed);
        if let Some(lines) = self.sway_lines {
            // Checked once by `check`.
            let _ = p.redraw_sea_sway(lines);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xD1CE_5EED);
        let (lo, hi) = self.error_magnitude_arcsec;
        p.errors_arcsec = core::array::from_fn(|_| {
            let m = if hi > lo { rng.gen_range(lo..hi) } else { lo };
            if rng.gen_bool(0.5) {
                m
            } else {
                -m
            }
        });
        if let Some((a, b)) = self.lat_range_deg {
            p.latitude_deg = if b > a { rng.gen_range(a..b) } else { a };
        }
        if let Some(max) = self.max_roll_deg {
            let nominal = sway_amplitude_deg(&p.roll_sway);
            if nominal > 0.0 {
                let target = if max > nominal {
                    rng.gen_range(nominal..max)
                } else {
                    max
                };
                let k = target / nominal;
                for c in &mut p.roll_sway {
                    c.amplitude_deg *= k;
                }
            }
        }
        p.mismatch = self.mismatch;
        p.ship_motion = self.ship_motion.motion(seed);
        if let Some(d) = self.duration_s {
            p.duration_s = d;
        }
        p.scheme = self.scheme;
        if let Some(t) = self.rotation_period_s {
            p.rotation_period_s = t;
        }
        if let Some(d) = self.sample_interval_s {
            p.sample_interval_s = d;
        }
        // Outages fit in every run alike (checked once by `check`).
        p.recording = self
            .recorder
            .recording(seed, p.duration_s, p.sample_interval_s)
            .unwrap_or_else(|_| Recording::default());
        p
    }
}

/// Sinusoid-equivalent amplitude of a sway (sqrt(2) x RMS), deg.
pub fn sway_amplitude_deg(comps: &[SwayComponent]) -> f64 {
    comps
        .iter()
        .map(|c| c.amplitude_deg * c.amplitude_deg)
        .sum::<f64>()
        .sqrt()
}

/// Generates, records and replays one scenario, tracking accuracy at `times_s` (at the logged
/// rows' sample instants, from the log's start).
pub fn track_run(
    params: &ScenarioParams,
    config: Config,
    times_s: &[f64],
) -> anyhow::Result<Accuracy> {
    track_run_with_capacity::<{ estimator_core::estimator::DEFAULT_CAPACITY }>(
        params, config, times_s,
    )
}

/// As [`track_run`], with an estimator of another ring capacity (to measure what binning costs).
pub fn track_run_with_capacity<const CAP: usize>(
    params: &ScenarioParams,
    config: Config,
    times_s: &[f64],
) -> anyhow::Result<Accuracy> {
    let mut est = estimator_core::Estimator::<CAP>::new(config)
        .map_err(|e| anyhow::anyhow!("invalid estimator configuration: {e:?}"))?;
    let mut recorder = Recorder::new(&params.recording, params.seed, params.sample_interval_s);
    let mut tracker =
        Tracker::new(times_s).with_errors_step(params.errors_step.map(|step| step.at_s));
    let mut held = None;
    let mut status = None;
    for (row, truth) in Samples::new(params) {
        let Some(logged) = recorder.record(&row) else {
            continue;
        };
        let row_status = match est.step(&sample_of(&logged)) {
            Ok(out) => {
                held = out.estimate;
                status = Some(out.status);
                Some(out.status)
            }
            Err(_) => None,
        };
        tracker.observe(row.time_s, held.as_ref(), row_status, &truth.errors_arcsec);
    }
    Ok(Accuracy {
        final_status: status,
        ..tracker.finish(params.sample_interval_s)
    })
}

/// Runs `runs` draws in parallel; `on_done` is called after each run (progress).
pub fn run_all(
    draw: &Draw,
    config: Config,
    runs: usize,
    times_s: &[f64],
    on_done: &(dyn Fn() + Sync),
) -> anyhow::Result<Vec<Accuracy>> {
    (0..runs)
        .into_par_iter()
        .map(|i| {
            let r = track_run(&draw.params(i), config, times_s);
            on_done();
            r
        })
        .collect()
}

/// The row-level honesty of the 1-sigma over runs: the runs' rows pooled, the largest |error| /
/// 1-sigma of any run (with its index in `results`).
pub fn pool_honesty(results: &[Accuracy]) -> Honesty {
    let mut h = Honesty::default();
    for (i, r) in results.iter().enumerate() {
        h.pool(&r.honesty, i);
    }
    h
}

/// The honesty lines printed under the Monte Carlo table.
pub fn format_honesty_over_runs(h: &Honesty, runs: usize) -> String {
    if h.rows == 0 {
        return "\n1-sigma honesty: no row with an estimate to judge\n".into();
    }
    let mut s = format!(
        "\n1-sigma honesty over the {runs} runs, {} from their first estimates: {}\n",
        rows_text(h.rows),
        format_honesty_shares(h)
    );
    let mut notes = Vec::new();
    if h.rows_left_out > 0 {
        notes.push(format!(
            "{} of changes of the errors left out (each until 2,000 s after the estimator \
             declared it, or after the change when it never did)",
            rows_text(h.rows_left_out)
        ));
    }
    if h.rows_without_estimate > 0 {
        notes.push(format!(
            "{} after a first estimate without one, not judged",
            rows_text(h.rows_without_estimate)
        ));
    }
    if !notes.is_empty() {
        s.push_str(&format!("  {}\n", notes.join("; ")));
    }
    s
}

/// Linear-interpolated quantile of sorted values (`q` in [0, 1]).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q * (sorted.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos - pos.floor());
    if i + 1 < sorted.len() {
        if f == 0.0 {
            sorted[i]
        } else if !sorted[i + 1].is_finite() {
            // Past the last finite value (runs without an estimate count as infinite errors).
            sorted[i + 1]
        } else {
            sorted[i] + (sorted[i + 1] - sorted[i]) * f
        }
    } else {
        sorted[i]
    }
}

/// Sorted copy (non-finite values last).
pub fn sorted(values: impl IntoIterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(|a, b| a.total_cmp(b));
    v
}

/// The summary written by `monte-carlo --out`. A run without an estimate at a time counts as an
/// infinite error (written as `null`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Summary {
    /// Runs the statistics are over.
    pub runs: usize,
    /// Report times, s.
    pub times_s: Vec<f64>,
    /// Median over the runs of the |error| of x1..x4, per time, arcsec.
    pub median_abs_error_arcsec: Vec<[f64; 4]>,
    /// 95th percentile over the runs of the |error| of x1..x4, per time, arcsec.
    pub p95_abs_error_arcsec: Vec<[f64; 4]>,
    /// Largest |error| of x1..x4 over the runs, per time, arcsec.
    pub max_abs_error_arcsec: Vec<[f64; 4]>,
    /// Share of runs with all four errors within 10 arcsec, per time.
    pub share_within_10_arcsec: Vec<f64>,
    /// Share of (run, error) pairs whose |error| is within twice the estimate's reported 1-sigma,
    /// per time ([`coverage_2sigma`]): about 0.95 when the 1-sigma is honest.
    pub coverage_2sigma: Vec<f64>,
}

impl Summary {
    /// The statistics at those of its times that are in `times_s`.
    pub fn at_times(&self, times_s: &[f64]) -> Summary {
        let keep: Vec<usize> = (0..self.times_s.len())
            .filter(|&k| times_s.contains(&self.times_s[k]))
            .collect();
        Summary {
            runs: self.runs,
            times_s: keep.iter().map(|&k| self.times_s[k]).collect(),
            median_abs_error_arcsec: keep
                .iter()
                .map(|&k| self.median_abs_error_arcsec[k])
                .collect(),
            p95_abs_error_arcsec: keep.iter().map(|&k| self.p95_abs_error_arcsec[k]).collect(),
            max_abs_error_arcsec: keep.iter().map(|&k| self.max_abs_error_arcsec[k]).collect(),
            share_within_10_arcsec: keep
                .iter()
                .map(|&k| self.share_within_10_arcsec[k])
                .collect(),
            coverage_2sigma: keep.iter().map(|&k| self.coverage_2sigma[k]).collect(),
        }
    }

    /// Whether no run had an estimate at any of the times.
    pub fn no_estimate(&self) -> bool {
        self.median_abs_error_arcsec
            .iter()
            .all(|m| m.iter().all(|v| v.is_infinite()))
    }
}

/// What `monte-carlo --out` writes: the study (scenario, method, scheme, every run's seed, the
/// command and the tool's version), the table's statistics (at the top level, as before) and the
/// same at [`PLOT_POINTS`] times over the runs (`over_time`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StudyJson {
    /// Name of the scenario (`paper`, `turntable`, `sea`).
    pub scenario: String,
    /// Name of the identification method (`windowed`, `paper`, `traditional`).
    pub method: String,
    /// Name of the rotation scheme.
    pub scheme: String,
    /// The draw in words (latitudes, sway, mismatch, recorder...).
    pub description: String,
    /// Length of each run, s.
    pub duration_s: f64,
    /// The seed each run's seed is derived from ([`Draw::run_seed`]).
    pub master_seed: u64,
    /// The seed of each run, in order (`generate --seed S` with the draw's spreads gives run i).
    pub run_seeds: Vec<u64>,
    /// The command line that ran the study.
    pub command: String,
    /// Version of host-sim that ran it.
    pub version: String,
    /// The statistics at the table's times ([`MC_TIMES_S`] inside the runs), written at the top
    /// level.
    #[serde(flatten)]
    pub summary: Summary,
    /// The statistics at every time tracked ([`tracked_times_s`]): [`PLOT_POINTS`] evenly spaced
    /// over the runs and the table's.
    pub over_time: Summary,
    /// The 1-sigma's honesty row by row, the runs' rows pooled ([`pool_honesty`]; `largest.run`
    /// indexes `run_seeds`).
    pub honesty: Honesty,
}

/// Share of the (run, error) pairs at report time `k` whose |error| is within twice the reported
/// 1-sigma. A run without an estimate at that time counts as four pairs outside.
pub fn coverage_2sigma(results: &[Accuracy], k: usize) -> f64 {
    let within: usize = results
        .iter()
        .map(|r| r.points.get(k).map_or(0, |p| p.within_sigmas(2.0)))
        .sum();
    within as f64 / (4 * results.len()).max(1) as f64
}

/// Statistics over runs at each report time inside the runs.
pub fn summarize(results: &[Accuracy]) -> Summary {
    let times_s: Vec<f64> = results
        .first()
        .map(|r| r.points.iter().map(|p| p.time_s).collect())
        .unwrap_or_default();
    let mut s = Summary {
        runs: results.len(),
        times_s: times_s.clone(),
        median_abs_error_arcsec: vec![],
        p95_abs_error_arcsec: vec![],
        max_abs_error_arcsec: vec![],
        share_within_10_arcsec: vec![],
        coverage_2sigma: vec![],
    };
    for k in 0..times_s.len() {
        let abs = |r: &Accuracy, i: usize| {
            r.points
                .get(k)
                .and_then(|p| p.error_arcsec)
                .map_or(f64::INFINITY, |e| e[i].abs())
        };
        let mut med = [0.0; 4];
        let mut p95 = [0.0; 4];
        let mut max = [0.0; 4];
        for i in 0..4 {
            let v = sorted(results.iter().map(|r| abs(r, i)));
            med[i] = quantile(&v, 0.5);
            p95[i] = quantile(&v, 0.95);
            max[i] = v.last().copied().unwrap_or(f64::NAN);
        }
        s.median_abs_error_arcsec.push(med);
        s.p95_abs_error_arcsec.push(p95);
        s.max_abs_error_arcsec.push(max);
        let within = results
            .iter()
            .filter(|r| (0..4).all(|i| abs(r, i) <= crate::report::accuracy::ARCSEC_THRESHOLD))
            .count();
        s.share_within_10_arcsec
            .push(within as f64 / results.len().max(1) as f64);
        s.coverage_2sigma.push(coverage_2sigma(results, k));
    }
    s
}

/// The summary as a markdown table.
pub fn format_summary(s: &Summary) -> String {
    let mut out = String::from(
        "| time s | stat | x1 arcsec | x2 arcsec | x3 arcsec | x4 arcsec | runs within 10 arcsec | errors within 2 sigma |\n|---|---|---|---|---|---|---|---|\n",
    );
    for (k, t) in s.times_s.iter().enumerate() {
        let row = |v: &[f64; 4]| {
            v.iter()
                .map(|x| format!("{x:.2}"))
                .collect::<Vec<_>>()
                .join(" | ")
        };
        out.push_str(&format!(
            "| {t:.0} | median | {} | {:.1} % | {:.1} % |\n",
            row(&s.median_abs_error_arcsec[k]),
            100.0 * s.share_within_10_arcsec[k],
            100.0 * s.coverage_2sigma[k]
        ));
        out.push_str(&format!(
            "| | p95 | {} | | |\n",
            row(&s.p95_abs_error_arcsec[k])
        ));
        out.push_str(&format!(
            "| | max | {} | | |\n",
            row(&s.max_abs_error_arcsec[k])
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_draw_that_cannot_make_its_scenarios_is_refused_with_a_typed_error() {
        let ok = Draw {
            duration_s: Some(3000.0),
            ..Draw::new(ScenarioKind::Paper, 1)
        };
        assert_eq!(ok.check(), Ok(()));
        let four_position = Draw {
            scheme: RotationScheme::FourPosition,
            rotation_period_s: Some(1.0),
            ..ok.clone()
        };
        let min_period_s = RotationScheme::FourPosition.min_period_s();
        assert!(min_period_s > 1.0);
        assert_eq!(
            four_position.check(),
            Err(ScenarioError::PeriodTooShortForScheme {
                scheme: "four-position",
                min_period_s
            })
        );
        let short = Draw {
            duration_s: Some(0.5),
            ..ok.clone()
        };
        assert_eq!(
            short.check(),
            Err(ScenarioError::ShorterThanOneSample {
                duration_s: 0.5,
                interval_s: 1.0
            })
        );
        let outages = Draw {
            recorder: RecorderSettings {
                outages: 100,
                ..RecorderSettings::default()
            },
            ..ok.clone()
        };
        let e = outages.check().unwrap_err();
        assert!(
            matches!(
                e,
                ScenarioError::Recorder(RecorderError::OutagesDoNotFit { count: 100, .. })
            ),
            "{e:?}"
        );
        assert!(e.to_string().starts_with("--outages: 100 outages"), "{e}");
    }

    #[test]
    fn a_study_shorter_than_the_first_report_time_is_refused() {
        let short = Draw {
            duration_s: Some(1500.0),
            ..Draw::new(ScenarioKind::Paper, 1)
        };
        let e = short.check_duration().unwrap_err();
        assert_eq!(
            e,
            StudyError::TooShort {
                duration_s: 1500.0,
                first_s: 2000.0,
                two_periods_s: 960.0
            }
        );
        assert!(
            e.to_string().contains("give --duration 2000 or more"),
            "{e}"
        );
        assert_eq!(
            Draw {
                duration_s: Some(2000.0),
                ..short
            }
            .check_duration(),
            Ok(())
        );
    }

    #[test]
    fn tracked_times_hold_the_table_times_and_an_even_grid() {
        let t = tracked_times_s(20_000.0);
        assert!(MC_TIMES_S.iter().all(|m| t.contains(m)));
        assert!(t.windows(2).all(|w| w[0] < w[1]));
        assert!(t.contains(&250.0) && t.contains(&20_000.0), "{t:?}");
        let s = Summary {
            runs: 1,
            times_s: vec![250.0, 2000.0],
            median_abs_error_arcsec: vec![[f64::INFINITY; 4], [1.0; 4]],
            p95_abs_error_arcsec: vec![[f64::INFINITY; 4], [2.0; 4]],
            max_abs_error_arcsec: vec![[f64::INFINITY; 4], [3.0; 4]],
            share_within_10_arcsec: vec![0.0, 1.0],
            coverage_2sigma: vec![0.0, 1.0],
        };
        let table = s.at_times(&MC_TIMES_S);
        assert_eq!(
            (table.times_s, table.p95_abs_error_arcsec),
            (vec![2000.0], vec![[2.0; 4]])
        );
        assert!(!s.no_estimate() && s.at_times(&[250.0]).no_estimate());
    }

    #[test]
    fn quantiles() {
        let v = sorted([5.0, 1.0, 3.0, 2.0, 4.0]);
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert_eq!(quantile(&v, 1.0), 5.0);
        assert!((quantile(&v, 0.95) - 4.8).abs() < 1e-12);
        let with_inf = sorted([1.0, f64::INFINITY, f64::INFINITY]);
        assert_eq!(quantile(&with_inf, 0.95), f64::INFINITY);
        assert_eq!(quantile(&with_inf, 0.25), f64::INFINITY);
    }

    fn point(
        time_s: f64,
        error_arcsec: Option<[f64; 4]>,
        sigma_arcsec: [f64; 4],
    ) -> crate::report::accuracy::AccuracyAt {
        crate::report::accuracy::AccuracyAt {
            time_s,
            error_arcsec,
            sigma_arcsec: error_arcsec.map(|_| sigma_arcsec),
            percent: None,
        }
    }

    fn accuracy(points: Vec<crate::report::accuracy::AccuracyAt>) -> Accuracy {
        Accuracy {
            points,
            within_percent_from_s: [None; 4],
            within_arcsec_from_s: [None; 4],
            final_status: None,
            honesty: crate::report::honesty::Honesty::default(),
        }
    }

    #[test]
    fn coverage_counts_run_error_pairs_within_two_sigma() {
        // Three runs, two report times. At the first: run 0 has 3 of 4 within 2 sigma, run 1 all
        // four, run 2 no estimate (4 outside): 7 / 12. At the second: 2 + 0 + 4 = 6 / 12.
        let runs = vec![
            accuracy(vec![
                point(1.0, Some([1.0, -1.9, 0.0, 2.1]), [1.0; 4]),
                point(2.0, Some([0.5, 0.5, -3.0, 3.0]), [1.0; 4]),
            ]),
            accuracy(vec![
                point(1.0, Some([10.0, -10.0, 5.0, 0.0]), [5.0, 5.0, 2.5, 0.1]),
                point(2.0, Some([10.0, -10.0, 5.0, 1.0]), [4.0, 4.0, 2.0, 0.1]),
            ]),
            accuracy(vec![
                point(1.0, None, [0.0; 4]),
                point(2.0, Some([0.0; 4]), [1.0; 4]),
            ]),
        ];
        assert!((coverage_2sigma(&runs, 0) - 7.0 / 12.0).abs() < 1e-12);
        assert!((coverage_2sigma(&runs, 1) - 6.0 / 12.0).abs() < 1e-12);
        assert_eq!(
            coverage_2sigma(&runs, 2),
            0.0,
            "a time past every run: nothing covered"
        );
        let s = summarize(&runs);
        assert_eq!(s.coverage_2sigma.len(), 2);
        assert!((s.coverage_2sigma[1] - 0.5).abs() < 1e-12);
        assert!(
            format_summary(&s).contains("| 58.3 % |"),
            "{}",
            format_summary(&s)
        );
    }

    #[test]
    fn draws_are_distinct_and_within_ranges() {
        let mut d = Draw::new(ScenarioKind::Sea, 7);
        d.lat_range_deg = Some((-60.0, 60.0));
        d.max_roll_deg = Some(10.0);
        let a = d.params(0);
        let b = d.params(1);
        assert_ne!(a.errors_arcsec, b.errors_arcsec);
        assert_eq!(a, d.params(0));
        for (i, p) in [&a, &b].into_iter().enumerate() {
            assert!(p
                .errors_arcsec
                .iter()
                .all(|x| (100.0..=500.0).contains(&x.abs())));
            assert!((-60.0..60.0).contains(&p.latitude_deg));
            let amp = sway_amplitude_deg(&p.roll_sway);
            let nominal = sway_amplitude_deg(
                &ScenarioParams::new(ScenarioKind::Sea, d.run_seed(i)).roll_sway,
            );
            assert!(
                nominal < 10.0 && amp <= 10.0 + 1e-9 && amp >= nominal - 1e-9,
                "{amp} {nominal}"
            );
        }
    }
}
