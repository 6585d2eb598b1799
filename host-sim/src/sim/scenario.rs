//! Scenario generator: ship sway, gimbal angles and a RINS attitude with known installation errors.
//!
//! The attitude follows eq (3): `true attitude + eq (2) oscillation + low-frequency error (eq 5) + noise`.
//! Eq (2) is written out again here, in `f64`, on purpose: it is the truth the core's `f32`
//! implementation is tested against, so a sign slip in one would show against the other.
//!
//! Three scenarios (every parameter documented on [`ScenarioParams`] and overridable):
//! - `paper`: Section II: roll 3 deg at 6 s, pitch 1 deg at 8-10 s, low-frequency errors of 0.05 deg
//!   at Earth-rate periods, white noise, rotation 480 s, latitude 40 deg, 2 days;
//! - `turntable`: Section IV-A: roll 3 deg, pitch 1 deg, periods near 10 s, static base;
//! - `sea`: Section IV-B and rougher: irregular sway from a wave spectrum (roll about 6 deg, pitch
//!   about 1.5 deg, periods 6-14 s), heading changes up to 0.5 deg/s, 5 m/s forward speed so the
//!   latitude drifts, low latitude, 47340 s.
//!
//! Effects eq (2) does not contain ([`Mismatch`]) can be switched on for robustness studies, and
//! so can a ship's ordinary day ([`ShipMotion`]: slow heel and trim, heel in course changes), true
//! attitude the estimator must cancel.
//!
//! The rotation angle `rho(t)` follows a [`RotationScheme`] (one way at a constant rate by
//! default, as in the paper; also reversed, reciprocating and stop-and-go), and eq (2) is
//! evaluated at the angle actually applied (scheme, period error and angle jitter included), the
//! angle the log's `rotation_deg` reports.
//!
//! The generator makes one row per sample instant; what reaches the log (lost rows, outages,
//! loose time stamps) is the [`crate::sim::recorder`]'s business, described by
//! [`ScenarioParams::recording`]. [`Samples`] yields the rows one at a time, so a log of millions
//! of rows can be written without holding it.

use crate::sim::recorder::Recording;
use crate::sim::rotation_scheme::RotationScheme;
use crate::sim::samples::Samples;
use crate::sim::ship_motion::ShipMotion;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Which scenario.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ScenarioKind {
    /// The paper's Section II simulation: roll 3 deg at 6 s, pitch 1 deg at 8-10 s, latitude
    /// 40 deg, 2 days.
    Paper,
    /// The paper's Section IV-A turntable test: roll 3 deg, pitch 1 deg, periods near 10 s, static
    /// base.
    Turntable,
    /// The paper's Section IV-B sea trial, and rougher: irregular sway from a wave spectrum,
    /// heading changes, a ship under way at low latitude.
    Sea,
}

impl ScenarioKind {
    /// The scenario's name on the command line and in truth files: `paper`, `turntable`, `sea`.
    pub fn name(&self) -> &'static str {
        match self {
            ScenarioKind::Paper => "paper",
            ScenarioKind::Turntable => "turntable",
            ScenarioKind::Sea => "sea",
        }
    }

    /// The scenario named `s` as [`ScenarioKind::name`] writes it, if there is one.
    pub fn parse(s: &str) -> Option<ScenarioKind> {
        match s {
            "paper" => Some(ScenarioKind::Paper),
            "turntable" => Some(ScenarioKind::Turntable),
            "sea" => Some(ScenarioKind::Sea),
            _ => None,
        }
    }
}

/// One sinusoidal sway component: `amplitude sin(2 pi t / period + phase)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwayComponent {
    /// Amplitude, deg.
    pub amplitude_deg: f64,
    /// Period, s.
    pub period_s: f64,
    /// Phase at t = 0, rad.
    pub phase_rad: f64,
}

/// Effects outside eq (2), all off by default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mismatch {
    /// Relative error of the true rotation period against the nominal one (0.005 = 0.5 % slower).
    /// Stop-and-go schemes keep their moves and lengthen their dwells.
    pub rotation_period_error: f64,
    /// 1-sigma of white jitter on the rotation angle, deg.
    pub rotation_jitter_deg: f64,
    /// Linear drift of every installation error, arcsec per day.
    pub error_drift_arcsec_per_day: f64,
    /// Frequency of the low-frequency errors relative to the Earth rate (0 = exactly Earth rate;
    /// 0.2 = 20 % faster).
    pub low_frequency_rate_error: f64,
    /// 1-sigma of a first-order Gauss-Markov (coloured) attitude noise, arcsec, time constant 60 s.
    pub coloured_noise_arcsec: f64,
    /// Heel in turns, deg: course changes of [`TURN_DEG`] at [`TURN_RATE_DEG_S`] every
    /// [`TURN_EVERY_S`] from [`FIRST_TURN_S`] on, alternately to starboard and to port, the ship
    /// heeling outward by this much while it turns (a frigate at 15 m/s heels some 3 deg in a
    /// standard-rate turn). Truth files without it: no turns.
    ///
    /// [`TURN_DEG`]: crate::sim::ship_motion::TURN_DEG
    /// [`TURN_RATE_DEG_S`]: crate::sim::ship_motion::TURN_RATE_DEG_S
    /// [`TURN_EVERY_S`]: crate::sim::ship_motion::TURN_EVERY_S
    /// [`FIRST_TURN_S`]: crate::sim::ship_motion::FIRST_TURN_S
    #[serde(default)]
    pub heel_in_turns_deg: f64,
    /// The RINS's interface: how long before the row's time its rotation angle was measured, s
    /// (the logged angle is the one at `t - S`; eq (2) acts with the angle at `t`). Truth files
    /// without it: 0.
    #[serde(default)]
    pub angle_latency_s: f64,
    /// The RINS's interface: the rotation encoder's zero off the angle eq (2) counts from, deg
    /// (the logged angle is the true one plus this). Truth files without it: 0.
    #[serde(default)]
    pub encoder_offset_deg: f64,
    /// A gyro bias fixed in the rotating sensor assembly, deg/h: horizontal, along the axis at
    /// the rotation angle, it tilts the attitude by its integral, roll by `b cos(rho)` and pitch
    /// by `b sin(rho)` integrated over time (the Earth rate's coupling left out): on a one-way
    /// rotation an oscillation of `b / omega` locked to the rotation angle. Truth files without
    /// it: 0.
    #[serde(default)]
    pub rotating_gyro_bias_deg_h: f64,
}

/// A change of the installation errors during the log: a re-installation after maintenance, or a
/// shock that shifts the RINS on its mounting. From `at_s` on, the errors are
/// `errors_after_arcsec` (a drift of [`Mismatch`] goes on from them).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorsStep {
    /// Time of the change, s from the start of the log.
    pub at_s: f64,
    /// Installation errors x1..x4 from then on, arcsec.
    pub errors_after_arcsec: [f64; 4],
}

/// Everything that defines a generated log. Written into the truth file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScenarioParams {
    /// The scenario whose defaults these parameters started from.
    pub scenario: ScenarioKind,
    /// Seed of the random phases, sway spectrum and noise.
    pub seed: u64,
    /// Length of the log, s (one sample per `sample_interval_s`).
    pub duration_s: f64,
    /// Interval between sample instants, s.
    pub sample_interval_s: f64,
    /// Installation errors x1..x4 of eqs (1)-(2), arcsec (from the start; see `errors_step`).
    pub errors_arcsec: [f64; 4],
    /// A change of the errors during the log (truth files without it: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors_step: Option<ErrorsStep>,
    /// Latitude at the start, deg.
    pub latitude_deg: f64,
    /// Forward speed, m/s (northward component moves the latitude).
    pub speed_m_s: f64,
    /// Course over ground, deg from north (sets how the speed moves the latitude).
    pub course_deg: f64,
    /// Rotation period of the RINS, s (nominal).
    pub rotation_period_s: f64,
    /// How the RINS turns within a period (truth files without it: one way, the paper's).
    #[serde(default)]
    pub scheme: RotationScheme,
    /// Rotation angle at t = 0, deg.
    pub rotation_phase_deg: f64,
    /// Platform angle s at t = 0, deg; it then turns at the Earth rate.
    pub platform_phase_deg: f64,
    /// Roll sway components (eq 4).
    pub roll_sway: Vec<SwayComponent>,
    /// Pitch sway components (eq 4).
    pub pitch_sway: Vec<SwayComponent>,
    /// Mean heading, deg; the yaw sway, the slow weave of `heading_weave_rate_deg_s` and the
    /// turns come on top of it.
    pub heading_deg: f64,
    /// Yaw sway components about the heading.
    pub heading_sway: Vec<SwayComponent>,
    /// Peak heading rate of the ship's slow course changes, deg/s (0 = none); period 600 s.
    pub heading_weave_rate_deg_s: f64,
    /// Amplitude of the low-frequency attitude errors of eq (5), deg (per axis: a0..a4 drawn so
    /// that |a| = this).
    pub low_frequency_deg: f64,
    /// 1-sigma of white attitude noise, arcsec.
    pub noise_arcsec: f64,
    /// Effects outside eq (2) (default: none).
    pub mismatch: Mismatch,
    /// The ship's slow heel and trim and its heel in course changes: true attitude, not errors
    /// (truth files without it: none).
    #[serde(default)]
    pub ship_motion: ShipMotion,
    /// What the data recorder loses and how it stamps time (default: nothing lost, exact stamps).
    #[serde(flatten)]
    pub recording: Recording,
}

/// One generated row, degrees (the log format's units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Sample time, s.
    pub time_s: f64,
    /// Rotation angle rho of the sensor assembly (eq (2)), deg.
    pub rotation_deg: f64,
    /// Platform angle s (eq (2)), deg.
    pub platform_deg: f64,
    /// Latitude L, deg.
    pub latitude_deg: f64,
    /// Heading the RINS outputs, with the oscillation of eq (2) in it, deg.
    pub heading_deg: f64,
    /// Roll the RINS outputs, with the oscillation of eq (2) in it, deg.
    pub roll_deg: f64,
    /// Pitch the RINS outputs, with the oscillation of eq (2) in it, deg.
    pub pitch_deg: f64,
}

/// The truth of one row, for evaluating corrections: the true attitude (sway only) and the
/// installation-error oscillation actually put into the row, deg.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowTruth {
    /// The true attitude (heading, roll, pitch), deg: the ship's motion, without the errors.
    pub true_attitude_deg: [f64; 3],
    /// The oscillation of eq (2) put into the row for the errors in force (heading, roll,
    /// pitch), deg.
    pub oscillation_deg: [f64; 3],
    /// Installation errors in force at this row (they drift only under [`Mismatch`] and change
    /// only at an [`ErrorsStep`]), arcsec.
    pub errors_arcsec: [f64; 4],
}

/// Sinusoids of these (amplitude deg, period s), each with a phase drawn uniformly in [0, 2 pi).
pub(crate) fn sway_set(rng: &mut ChaCha8Rng, items: &[(f64, f64)]) -> Vec<SwayComponent> {
    items
        .iter()
        .map(|&(amplitude_deg, period_s)| SwayComponent {
            amplitude_deg,
            period_s,
            phase_rad: rng.gen_range(0.0..2.0 * PI),
        })
        .collect()
}

/// Most sinusoids `--sway-lines` may ask for in each spectrum.
pub const MAX_SWAY_LINES: usize = 10_000;

/// Why the sea's sway cannot be drawn with the lines asked for.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum SwayLinesError {
    /// Only the sea scenario's sway comes from wave spectra.
    #[error("--sway-lines applies to the sea scenario only (its wave spectra), not to {scenario}")]
    NotSea {
        /// The scenario asked for.
        scenario: &'static str,
    },
    /// Lines outside 1..=[`MAX_SWAY_LINES`].
    #[error("--sway-lines must be within 1 to {MAX_SWAY_LINES}, got {lines}")]
    OutOfRange {
        /// The lines asked for.
        lines: usize,
    },
}

/// Sinusoids in each of the sea scenario's wave spectra unless `--sway-lines` asks otherwise.
pub const SEA_SWAY_LINES: usize = 40;

/// The sea scenario's spectra: roll, pitch and heading sway, each `(significant amplitude deg,
/// peak period s, shortest period s, longest period s)`.
const SEA_SWAY: [(f64, f64, f64, f64); 3] = [
    (6.0 * 2.0 / std::f64::consts::SQRT_2, 10.0, 6.0, 14.0),
    (1.5 * 2.0 / std::f64::consts::SQRT_2, 9.0, 6.0, 14.0),
    (0.5, 10.0, 6.0, 14.0),
];

/// Irregular sway from a Pierson-Moskowitz-shaped spectrum between `min_period_s` and
/// `max_period_s` peaking at `peak_period_s`: `lines` sinusoids, one at a random frequency in each
/// of `lines` equal bins, with random phases, scaled so the significant amplitude (2 x RMS) is
/// `significant_deg`. Few lines make a sea whose lines stay in step with a rotation-locked
/// pattern for hours (a steady swell); many approach a continuous spectrum.
fn wave_spectrum(
    rng: &mut ChaCha8Rng,
    (significant_deg, peak_period_s, min_period_s, max_period_s): (f64, f64, f64, f64),
    lines: usize,
) -> Vec<SwayComponent> {
    let n = lines;
    let w_min = 2.0 * PI / max_period_s;
    let w_max = 2.0 * PI / min_period_s;
    let wp = 2.0 * PI / peak_period_s;
    let dw = (w_max - w_min) / n as f64;
    let mut comps: Vec<SwayComponent> = (0..n)
        .map(|i| {
            // A random frequency inside each bin, so the sum does not repeat.
            let w = w_min + (i as f64 + rng.gen_range(0.0..1.0)) * dw;
            let s = (wp / w).powi(5) * (-1.25 * (wp / w).powi(4)).exp();
            SwayComponent {
                amplitude_deg: (2.0 * s * dw).sqrt(),
                period_s: 2.0 * PI / w,
                phase_rad: rng.gen_range(0.0..2.0 * PI),
            }
        })
        .collect();
    let rms = (comps
        .iter()
        .map(|c| c.amplitude_deg * c.amplitude_deg / 2.0)
        .sum::<f64>())
    .sqrt();
    let scale = significant_deg / (2.0 * rms);
    for c in &mut comps {
        c.amplitude_deg *= scale;
    }
    comps
}

impl ScenarioParams {
    /// The sea scenario's roll, pitch and heading sway drawn again as `lines` sinusoids each, from
    /// the seed (another draw than the default's, even at [`SEA_SWAY_LINES`]); the same spectra
    /// and amplitudes. Only the sea scenario has wave spectra.
    pub fn redraw_sea_sway(&mut self, lines: usize) -> Result<(), SwayLinesError> {
        if self.scenario != ScenarioKind::Sea {
            return Err(SwayLinesError::NotSea {
                scenario: self.scenario.name(),
            });
        }
        if !(1..=MAX_SWAY_LINES).contains(&lines) {
            return Err(SwayLinesError::OutOfRange { lines });
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x5ea5_11e5);
        self.roll_sway = wave_spectrum(&mut rng, SEA_SWAY[0], lines);
        self.pitch_sway = wave_spectrum(&mut rng, SEA_SWAY[1], lines);
        self.heading_sway = wave_spectrum(&mut rng, SEA_SWAY[2], lines);
        Ok(())
    }

    /// The scenario's defaults for `seed`. Phases (and for `sea` the spectrum components) are drawn
    /// from the seed; everything else is fixed.
    pub fn new(kind: ScenarioKind, seed: u64) -> ScenarioParams {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0005_eed0_f5ea);
        let rotation_phase_deg = rng.gen_range(0.0..360.0);
        let platform_phase_deg = rng.gen_range(0.0..360.0);
        let base = ScenarioParams {
            scenario: kind,
            seed,
            duration_s: 172_800.0,
            sample_interval_s: 1.0,
            errors_arcsec: [200.0, -150.0, 300.0, -250.0],
            errors_step: None,
            latitude_deg: 40.0,
            speed_m_s: 0.0,
            course_deg: 0.0,
            rotation_period_s: 480.0,
            scheme: RotationScheme::Continuous,
            rotation_phase_deg,
            platform_phase_deg,
            roll_sway: Vec::new(),
            pitch_sway: Vec::new(),
            heading_deg: 30.0,
            heading_sway: Vec::new(),
            heading_weave_rate_deg_s: 0.0,
            low_frequency_deg: 0.05,
            noise_arcsec: 5.0,
            mismatch: Mismatch::default(),
            ship_motion: ShipMotion::default(),
            recording: Recording::default(),
        };
        match kind {
            ScenarioKind::Paper => ScenarioParams {
                roll_sway: sway_set(&mut rng, &[(3.0, 6.0)]),
                pitch_sway: sway_set(&mut rng, &[(0.8, 8.0), (0.6, 10.0)]),
                ..base
            },
            ScenarioKind::Turntable => ScenarioParams {
                duration_s: 50_000.0,
                roll_sway: sway_set(&mut rng, &[(3.0, 10.0)]),
                pitch_sway: sway_set(&mut rng, &[(1.0, 9.5)]),
                low_frequency_deg: 0.02,
                ..base
            },
            ScenarioKind::Sea => ScenarioParams {
                duration_s: 47_340.0,
                latitude_deg: 18.0,
                speed_m_s: 5.0,
                course_deg: 40.0,
                roll_sway: wave_spectrum(&mut rng, SEA_SWAY[0], SEA_SWAY_LINES),
                pitch_sway: wave_spectrum(&mut rng, SEA_SWAY[1], SEA_SWAY_LINES),
                heading_sway: wave_spectrum(&mut rng, SEA_SWAY[2], SEA_SWAY_LINES),
                heading_weave_rate_deg_s: 0.5,
                ..base
            },
        }
    }
}

/// The sum of the sinusoids `comps` at `t`, deg.
pub(crate) fn sway(comps: &[SwayComponent], t: f64) -> f64 {
    comps
        .iter()
        .map(|c| c.amplitude_deg * (2.0 * PI * t / c.period_s + c.phase_rad).sin())
        .sum()
}

/// A generated log: one row per sample instant (before the recorder) and its truth.
pub struct Generated {
    /// One row per sample instant, in time order.
    pub rows: Vec<Row>,
    /// The truth of each row, in the same order.
    pub truth: Vec<RowTruth>,
}

/// Generates the log of `p`, every sample instant. Deterministic for a given `p`.
pub fn generate(p: &ScenarioParams) -> Generated {
    let samples = Samples::new(p);
    let n = samples.len();
    let mut rows = Vec::with_capacity(n);
    let mut truth = Vec::with_capacity(n);
    for (row, tr) in samples {
        rows.push(row);
        truth.push(tr);
    }
    Generated { rows, truth }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::samples::oscillation_rad;
    use crate::sim::ship_motion::{course_rate_deg_s, ShipMotionError, ShipMotionSettings};
    use estimator_core::units::{arcsec_to_rad, RAD_PER_DEG};

    #[test]
    fn parameters_without_scheme_or_recording_read_as_one_way_and_lossless() {
        let p = ScenarioParams::new(ScenarioKind::Paper, 2);
        let mut v = serde_json::to_value(&p).unwrap();
        for key in [
            "scheme",
            "drop_fraction",
            "outage_starts_s",
            "outage_duration_s",
            "time_offset_s",
            "time_jitter_s",
            "gap_every_s",
            "gap_rows",
        ] {
            assert!(
                v.as_object_mut().unwrap().remove(key).is_some(),
                "{key} written"
            );
        }
        let back: ScenarioParams = serde_json::from_value(v).unwrap();
        assert_eq!(back, p);
    }

    #[test]
    fn eq_2_follows_the_rotation_angle_applied() {
        let mut p = ScenarioParams::new(ScenarioKind::Turntable, 4);
        p.duration_s = 600.0;
        p.noise_arcsec = 0.0;
        p.low_frequency_deg = 0.0;
        for scheme in RotationScheme::ALL {
            p.scheme = scheme;
            let x = p.errors_arcsec.map(arcsec_to_rad);
            for (row, tr) in Samples::new(&p) {
                let rho = (p.rotation_phase_deg
                    + scheme.rho_rad(row.time_s, p.rotation_period_s).to_degrees())
                .rem_euclid(360.0);
                assert!(
                    (row.rotation_deg - rho).abs() < 1e-9
                        || (row.rotation_deg - rho).abs() > 360.0 - 1e-9,
                    "{} at {}",
                    scheme.name(),
                    row.time_s
                );
                let osc = oscillation_rad(
                    &x,
                    row.rotation_deg * RAD_PER_DEG,
                    row.platform_deg * RAD_PER_DEG,
                    row.latitude_deg * RAD_PER_DEG,
                );
                for a in 0..3 {
                    assert!(
                        (tr.oscillation_deg[a] - osc[a] / RAD_PER_DEG).abs() < 1e-12,
                        "{} at {}",
                        scheme.name(),
                        row.time_s
                    );
                }
            }
        }
    }

    #[test]
    fn period_error_and_angle_jitter_apply_to_every_scheme() {
        let mut p = ScenarioParams::new(ScenarioKind::Paper, 8);
        p.duration_s = 1000.0;
        for scheme in RotationScheme::ALL {
            p.scheme = scheme;
            p.mismatch = Mismatch {
                rotation_period_error: 0.01,
                ..Mismatch::default()
            };
            let true_period_s = 480.0 * 1.01;
            for (row, _) in Samples::new(&p) {
                let expected = (p.rotation_phase_deg
                    + scheme.rho_rad(row.time_s, true_period_s).to_degrees())
                .rem_euclid(360.0);
                let d = (row.rotation_deg - expected + 180.0).rem_euclid(360.0) - 180.0;
                assert!(d.abs() < 1e-9, "{} at {}", scheme.name(), row.time_s);
            }
            p.mismatch = Mismatch {
                rotation_jitter_deg: 0.05,
                ..Mismatch::default()
            };
            let dev: Vec<f64> = Samples::new(&p)
                .map(|(row, _)| {
                    let expected = (p.rotation_phase_deg
                        + scheme.rho_rad(row.time_s, 480.0).to_degrees())
                    .rem_euclid(360.0);
                    (row.rotation_deg - expected + 180.0).rem_euclid(360.0) - 180.0
                })
                .collect();
            let rms = (dev.iter().map(|d| d * d).sum::<f64>() / dev.len() as f64).sqrt();
            assert!((rms - 0.05).abs() < 0.005, "{}: {rms}", scheme.name());
        }
    }
    /// Generates `p` and `q` (the same scenario with some slow motion added) and checks, row by
    /// row, that they differ only in roll and pitch, by `roll(t)` and `pitch(t)`.
    fn differ_by(
        p: &ScenarioParams,
        q: &ScenarioParams,
        roll: impl Fn(f64) -> f64,
        pitch: impl Fn(f64) -> f64,
    ) {
        let (a, b) = (generate(p), generate(q));
        assert_eq!(a.rows.len(), b.rows.len());
        for (ra, rb) in a.rows.iter().zip(&b.rows) {
            let t = ra.time_s;
            assert_eq!(
                (ra.time_s, ra.rotation_deg, ra.platform_deg, ra.latitude_deg),
                (rb.time_s, rb.rotation_deg, rb.platform_deg, rb.latitude_deg)
            );
            assert_eq!(ra.heading_deg, rb.heading_deg, "heading at {t}");
            let (dr, dp) = (rb.roll_deg - ra.roll_deg, rb.pitch_deg - ra.pitch_deg);
            assert!(
                (dr - roll(t)).abs() < 1e-12,
                "roll at {t}: {dr} against {}",
                roll(t)
            );
            assert!(
                (dp - pitch(t)).abs() < 1e-12,
                "pitch at {t}: {dp} against {}",
                pitch(t)
            );
        }
        for (ta, tb) in a.truth.iter().zip(&b.truth) {
            assert_eq!(ta.oscillation_deg, tb.oscillation_deg);
            assert_eq!(ta.errors_arcsec, tb.errors_arcsec);
        }
    }

    #[test]
    fn slow_heel_and_trim_add_exactly_their_sinusoids_to_roll_and_pitch() {
        let mut p = ScenarioParams::new(ScenarioKind::Sea, 5);
        p.duration_s = 4000.0;
        let settings =
            ShipMotionSettings::new((&[0.3, 0.15], &[1200.0, 2500.0]), (&[0.1], &[1800.0]), 0.0)
                .unwrap();
        let mut q = p.clone();
        q.ship_motion = settings.motion(q.seed);
        let heel = q.ship_motion.slow_heel.clone();
        let trim = q.ship_motion.slow_trim.clone();
        assert_eq!(
            heel.iter()
                .map(|c| (c.amplitude_deg, c.period_s))
                .collect::<Vec<_>>(),
            vec![(0.3, 1200.0), (0.15, 2500.0)]
        );
        assert_eq!((trim[0].amplitude_deg, trim[0].period_s), (0.1, 1800.0));
        let phases: Vec<f64> = heel.iter().chain(&trim).map(|c| c.phase_rad).collect();
        assert!(
            phases.iter().all(|f| (0.0..2.0 * PI).contains(f)),
            "{phases:?}"
        );
        assert_eq!(
            settings.motion(5),
            q.ship_motion,
            "phases drawn from the seed"
        );
        assert_ne!(settings.motion(6).slow_heel[0].phase_rad, heel[0].phase_rad);
        let wave =
            |a: f64, period: f64, phase: f64, t: f64| a * (2.0 * PI * t / period + phase).sin();
        differ_by(
            &p,
            &q,
            |t| wave(0.3, 1200.0, heel[0].phase_rad, t) + wave(0.15, 2500.0, heel[1].phase_rad, t),
            |t| wave(0.1, 1800.0, trim[0].phase_rad, t),
        );
        // Trim alone: the heel is the same without it, and the trim swings +-0.1 deg.
        let mut r = p.clone();
        r.ship_motion = ShipMotionSettings::new((&[], &[]), (&[0.1], &[1800.0]), 0.0)
            .unwrap()
            .motion(r.seed);
        assert_eq!(r.ship_motion.slow_trim, trim);
        let (a, b) = (generate(&p), generate(&r));
        let d: Vec<f64> = a
            .rows
            .iter()
            .zip(&b.rows)
            .map(|(x, y)| y.pitch_deg - x.pitch_deg)
            .collect();
        let (lo, hi) = d
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
        assert!(
            (hi - 0.1).abs() < 1e-5 && (lo + 0.1).abs() < 1e-5,
            "{lo} {hi}"
        );
    }

    #[test]
    fn heel_per_turn_rate_heels_outward_by_k_times_the_course_rate() {
        // The sea scenario weaves its heading at up to 0.5 deg/s (period 600 s); turns of 90 deg at
        // 0.5 deg/s at 7200 s (to starboard) and 10800 s (to port), 180 s each.
        let mut p = ScenarioParams::new(ScenarioKind::Sea, 2);
        p.duration_s = 11_500.0;
        p.mismatch.heel_in_turns_deg = 2.0;
        let mut q = p.clone();
        q.ship_motion.heel_per_turn_rate_deg_per_deg_s = 0.4;
        let course_rate = |t: f64| {
            let turn = if (7200.0..7380.0).contains(&t) {
                0.5
            } else if (10_800.0..10_980.0).contains(&t) {
                -0.5
            } else {
                0.0
            };
            0.5 * (2.0 * PI * t / 600.0).cos() + turn
        };
        differ_by(&p, &q, |t| -0.4 * course_rate(t), |_| 0.0);
        // Mid-turn to starboard, where the weave stands still: the ship heels to port.
        let t = 7200.0 + 150.0;
        assert!((course_rate(t) - 0.5).abs() < 1e-12);
        assert!((q.ship_motion.roll_pitch_deg(t, course_rate_deg_s(&q, t)).0 + 0.2).abs() < 1e-12);
        // The rate is the exact derivative of the slow heading (weave and turns, not the yaw
        // sway): central differences of the true heading without its sway, away from the turns'
        // corners.
        let mut smooth = p.clone();
        smooth.heading_sway.clear();
        let g = generate(&smooth);
        let heading: Vec<f64> = g.truth.iter().map(|tr| tr.true_attitude_deg[0]).collect();
        let corners = [7200.0, 7380.0, 10_800.0, 10_980.0];
        for k in 1..heading.len() - 1 {
            let t = k as f64;
            if corners.iter().any(|c| (t - c).abs() <= 1.0) {
                continue;
            }
            let numeric = (heading[k + 1] - heading[k - 1]) / 2.0;
            let rate = course_rate_deg_s(&smooth, t);
            assert!((rate - course_rate(t)).abs() < 1e-12, "at {t}");
            assert!(
                (numeric - rate).abs() < 1e-4,
                "at {t}: {numeric} against {rate}"
            );
        }
    }

    #[test]
    fn truth_files_without_ship_motion_read_as_none() {
        let p = ScenarioParams::new(ScenarioKind::Sea, 2);
        let mut v = serde_json::to_value(&p).unwrap();
        assert!(v.as_object_mut().unwrap().remove("ship_motion").is_some());
        let back: ScenarioParams = serde_json::from_value(v).unwrap();
        assert_eq!(back, p);
        assert!(back.ship_motion.is_none());
        // With motions: read back as written; an object with only some of them, the rest none.
        let mut q = p.clone();
        q.ship_motion = ShipMotionSettings::new((&[0.3], &[1200.0]), (&[0.1], &[1800.0]), 0.4)
            .unwrap()
            .motion(q.seed);
        let text = serde_json::to_string(&q).unwrap();
        assert_eq!(serde_json::from_str::<ScenarioParams>(&text).unwrap(), q);
        let mut v = serde_json::to_value(&q).unwrap();
        v["ship_motion"] = serde_json::json!({"heel_per_turn_rate_deg_per_deg_s": 0.4});
        let partial: ScenarioParams = serde_json::from_value(v).unwrap();
        assert_eq!(
            partial.ship_motion,
            ShipMotion {
                heel_per_turn_rate_deg_per_deg_s: 0.4,
                ..ShipMotion::default()
            }
        );
    }

    #[test]
    fn ship_motion_settings_are_checked() {
        let e = ShipMotionSettings::new((&[0.3, 0.1], &[1200.0]), (&[], &[]), 0.0).unwrap_err();
        assert_eq!(
            e,
            ShipMotionError::CountsDiffer {
                what: "slow-heel",
                amplitudes: 2,
                periods: 1
            }
        );
        assert!(
            e.to_string()
                .contains("--slow-heel-deg gives 2 amplitudes but --slow-heel-period-s 1 periods"),
            "{e}"
        );
        for period in [0.0, -600.0, f64::NAN, f64::INFINITY] {
            let e = ShipMotionSettings::new((&[], &[]), (&[0.1], &[period]), 0.0).unwrap_err();
            assert!(
                matches!(
                    e,
                    ShipMotionError::Period {
                        what: "slow-trim",
                        ..
                    }
                ),
                "{e:?}"
            );
        }
        let e = ShipMotionSettings::new((&[f64::NAN], &[60.0]), (&[], &[]), 0.0).unwrap_err();
        assert!(
            matches!(
                e,
                ShipMotionError::Amplitude {
                    what: "slow-heel",
                    ..
                }
            ),
            "{e:?}"
        );
        let e = ShipMotionSettings::new((&[], &[]), (&[], &[]), f64::INFINITY).unwrap_err();
        assert_eq!(e, ShipMotionError::HeelPerTurnRate(f64::INFINITY));
        let none = ShipMotionSettings::new((&[], &[]), (&[], &[]), 0.0).unwrap();
        assert!(none.motion(1).is_none());
    }
}
