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
use estimator_core::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Earth radius for the latitude drift of a moving ship, m.
const EARTH_RADIUS_M: f64 = 6_371_000.0;

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

/// Course change of each turn of [`Mismatch::heel_in_turns_deg`], deg.
pub const TURN_DEG: f64 = 90.0;
/// Rate of turn, deg/s (a turn takes 180 s).
pub const TURN_RATE_DEG_S: f64 = 0.5;
/// Time from one turn's start to the next's, s.
pub const TURN_EVERY_S: f64 = 3600.0;
/// Start of the first turn, s: two hours in, once the estimator has settled (a turn before that
/// costs it accuracy for hours: docs/uncertainty.md).
pub const FIRST_TURN_S: f64 = 2.0 * TURN_EVERY_S;
/// Time the heel takes to build up and to die away at the start and the end of a turn, s.
pub const TURN_HEEL_RAMP_S: f64 = 20.0;

/// Where the ship's turns of [`Mismatch::heel_in_turns_deg`] stand at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TurnState {
    /// Heading changed by the turns so far, deg.
    pub heading_deg: f64,
    /// Heel of the turn under way, deg (outward: a turn to starboard heels to port, negative).
    pub heel_deg: f64,
    /// Rate of the heading change, deg/s: the exact derivative of `heading_deg` (+-
    /// [`TURN_RATE_DEG_S`] while a turn is under way, 0 between turns).
    pub rate_deg_s: f64,
}

/// The ship's turns at `t` (none when `heel_deg` is 0: the turns come with their heel).
pub fn turns(heel_deg: f64, t: f64) -> TurnState {
    if heel_deg == 0.0 {
        return TurnState::default();
    }
    if t < FIRST_TURN_S {
        return TurnState::default();
    }
    let k = ((t - FIRST_TURN_S) / TURN_EVERY_S).floor();
    let into = t - FIRST_TURN_S - k * TURN_EVERY_S;
    let duration = TURN_DEG / TURN_RATE_DEG_S;
    // Turns alternate: to starboard (heading up), then back to port.
    let starboard = (k as i64) % 2 == 0;
    let before = if starboard { 0.0 } else { TURN_DEG };
    // The heading changes at a constant rate (no ramp): its derivative is the rate inside the
    // turn and 0 outside; only the heel ramps in and out.
    let (turned, heel, rate) = if into >= duration {
        (TURN_DEG, 0.0, 0.0)
    } else {
        let ramp = |u: f64| 0.5 - 0.5 * (PI * (u / TURN_HEEL_RAMP_S).clamp(0.0, 1.0)).cos();
        (
            TURN_RATE_DEG_S * into,
            heel_deg * ramp(into).min(ramp(duration - into)),
            TURN_RATE_DEG_S,
        )
    };
    // Outward: a turn to starboard heels the ship to port (roll < 0).
    if starboard {
        TurnState {
            heading_deg: before + turned,
            heel_deg: -heel,
            rate_deg_s: rate,
        }
    } else {
        TurnState {
            heading_deg: before - turned,
            heel_deg: heel,
            rate_deg_s: -rate,
        }
    }
}

/// Period of the ship's slow heading weave ([`ScenarioParams::heading_weave_rate_deg_s`]), s.
pub const WEAVE_PERIOD_S: f64 = 600.0;

/// The slow heading weave at `t`: `(heading, rate)`, deg and deg/s. The heading is
/// `R P / (2 pi) sin(2 pi t / P)` for a peak rate `R` and period `P` = [`WEAVE_PERIOD_S`]; the rate
/// its exact derivative, `R cos(2 pi t / P)`.
pub fn weave(peak_rate_deg_s: f64, t: f64) -> (f64, f64) {
    if peak_rate_deg_s > 0.0 {
        let w = 2.0 * PI * t / WEAVE_PERIOD_S;
        (
            peak_rate_deg_s * WEAVE_PERIOD_S / (2.0 * PI) * w.sin(),
            peak_rate_deg_s * w.cos(),
        )
    } else {
        (0.0, 0.0)
    }
}

/// The ship's slow motions on an ordinary day, beyond the wave-frequency sway: wind heel, fuel
/// and loading shift the roll and the pitch over tens of minutes, and the ship heels in its
/// course changes. They are part of the TRUE attitude of eq (3), not errors: the estimator must
/// cancel them. All off by default (truth files without them: none).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShipMotion {
    /// Slow heel (roll, deg): sinusoids `amplitude_deg sin(2 pi t / period_s + phase_rad)` added
    /// to the roll (phases drawn from the seed).
    #[serde(default)]
    pub slow_heel: Vec<SwayComponent>,
    /// Slow trim (pitch, deg), of the same form, added to the pitch.
    #[serde(default)]
    pub slow_trim: Vec<SwayComponent>,
    /// Heel per rate of turn of the course, deg of heel per deg/s: the ship heels outward by this
    /// much times the rate of its course (the slow heading weave and the turns of
    /// [`Mismatch::heel_in_turns_deg`], not the wave-frequency yaw sway): roll +=
    /// `-K * rate_deg_s` (a turn to starboard, heading increasing, heels to port). 0: none.
    #[serde(default)]
    pub heel_per_turn_rate_deg_per_deg_s: f64,
}

impl ShipMotion {
    /// Whether any of the slow motions is on.
    pub fn is_none(&self) -> bool {
        self.slow_heel.is_empty()
            && self.slow_trim.is_empty()
            && self.heel_per_turn_rate_deg_per_deg_s == 0.0
    }

    /// What the slow motions add to the true attitude at `t`, deg: `(roll, pitch)`;
    /// `course_rate_deg_s` is the rate of the ship's course then ([`course_rate_deg_s`]).
    pub fn roll_pitch_deg(&self, t: f64, course_rate_deg_s: f64) -> (f64, f64) {
        (
            sway(&self.slow_heel, t) - self.heel_per_turn_rate_deg_per_deg_s * course_rate_deg_s,
            sway(&self.slow_trim, t),
        )
    }
}

/// The ship's slow motions as asked for: amplitudes and periods; the phases are drawn per seed
/// ([`ShipMotionSettings::motion`]), so each run of a study has its own.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShipMotionSettings {
    /// Slow heel components: (amplitude deg, period s).
    pub slow_heel: Vec<(f64, f64)>,
    /// Slow trim components: (amplitude deg, period s).
    pub slow_trim: Vec<(f64, f64)>,
    /// [`ShipMotion::heel_per_turn_rate_deg_per_deg_s`], deg per deg/s.
    pub heel_per_turn_rate_deg_per_deg_s: f64,
}

/// Why the ship's slow motions asked for cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShipMotionError {
    /// A list of amplitudes and its list of periods differ in length.
    #[error("--{what}-deg gives {amplitudes} amplitudes but --{what}-period-s {periods} periods: give one period per amplitude")]
    CountsDiffer {
        /// The motion, as its options name it: `slow-heel` or `slow-trim`.
        what: &'static str,
        /// Amplitudes given.
        amplitudes: usize,
        /// Periods given.
        periods: usize,
    },
    /// An amplitude that is not a finite number.
    #[error("--{what}-deg: every amplitude must be a finite number of degrees, got {value}")]
    Amplitude {
        /// The motion, as its options name it: `slow-heel` or `slow-trim`.
        what: &'static str,
        /// The amplitude, deg.
        value: f64,
    },
    /// A period that is not a finite positive number.
    #[error(
        "--{what}-period-s: every period must be a finite number of seconds above 0, got {value}"
    )]
    Period {
        /// The motion, as its options name it: `slow-heel` or `slow-trim`.
        what: &'static str,
        /// The period, s.
        value: f64,
    },
    /// A heel per turn rate that is not finite.
    #[error(
        "--heel-per-turn-rate must be a finite number (deg of heel per deg/s of turn), got {0}"
    )]
    HeelPerTurnRate(f64),
}

impl ShipMotionSettings {
    /// The settings of the two lists of each slow motion (amplitudes deg, periods s) and the heel
    /// per turn rate, checked: as many periods as amplitudes, every value finite, periods above 0.
    pub fn new(
        slow_heel: (&[f64], &[f64]),
        slow_trim: (&[f64], &[f64]),
        heel_per_turn_rate_deg_per_deg_s: f64,
    ) -> Result<ShipMotionSettings, ShipMotionError> {
        fn pairs(
            what: &'static str,
            (amplitudes, periods): (&[f64], &[f64]),
        ) -> Result<Vec<(f64, f64)>, ShipMotionError> {
            if amplitudes.len() != periods.len() {
                return Err(ShipMotionError::CountsDiffer {
                    what,
                    amplitudes: amplitudes.len(),
                    periods: periods.len(),
                });
            }
            if let Some(&value) = amplitudes.iter().find(|a| !a.is_finite()) {
                return Err(ShipMotionError::Amplitude { what, value });
            }
            if let Some(&value) = periods.iter().find(|p| !(p.is_finite() && **p > 0.0)) {
                return Err(ShipMotionError::Period { what, value });
            }
            Ok(amplitudes
                .iter()
                .copied()
                .zip(periods.iter().copied())
                .collect())
        }
        if !heel_per_turn_rate_deg_per_deg_s.is_finite() {
            return Err(ShipMotionError::HeelPerTurnRate(
                heel_per_turn_rate_deg_per_deg_s,
            ));
        }
        Ok(ShipMotionSettings {
            slow_heel: pairs("slow-heel", slow_heel)?,
            slow_trim: pairs("slow-trim", slow_trim)?,
            heel_per_turn_rate_deg_per_deg_s,
        })
    }

    /// The motions of a log of `seed`: each component's phase drawn uniformly in [0, 2 pi) from
    /// the seed (the heel's and the trim's from streams of their own, so adding a trim leaves the
    /// heel as it was). Deterministic; the generator's other random draws are untouched.
    pub fn motion(&self, seed: u64) -> ShipMotion {
        let draw = |salt: u64, items: &[(f64, f64)]| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ salt);
            sway_set(&mut rng, items)
        };
        ShipMotion {
            slow_heel: draw(0x510_4EE1, &self.slow_heel),
            slow_trim: draw(0x510_7819, &self.slow_trim),
            heel_per_turn_rate_deg_per_deg_s: self.heel_per_turn_rate_deg_per_deg_s,
        }
    }
}

/// Rate of the ship's course at `t`, deg/s: the exact derivative of its slow heading, the weave
/// ([`weave`]) plus the turns ([`turns`]); the wave-frequency yaw sway is not part of it.
pub fn course_rate_deg_s(p: &ScenarioParams, t: f64) -> f64 {
    weave(p.heading_weave_rate_deg_s, t).1 + turns(p.mismatch.heel_in_turns_deg, t).rate_deg_s
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

fn sway_set(rng: &mut ChaCha8Rng, items: &[(f64, f64)]) -> Vec<SwayComponent> {
    items
        .iter()
        .map(|&(amplitude_deg, period_s)| SwayComponent {
            amplitude_deg,
            period_s,
            phase_rad: rng.gen_range(0.0..2.0 * PI),
        })
        .collect()
}

/// Irregular sway from a Pierson-Moskowitz-shaped spectrum between `min_period_s` and
/// `max_period_s` peaking at `peak_period_s`: 40 components with random phases, scaled so the
/// significant amplitude (2 x RMS) is `significant_deg`.
fn wave_spectrum(
    rng: &mut ChaCha8Rng,
    significant_deg: f64,
    peak_period_s: f64,
    min_period_s: f64,
    max_period_s: f64,
) -> Vec<SwayComponent> {
    let n = 40;
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
                roll_sway: wave_spectrum(
                    &mut rng,
                    6.0 * 2.0 / std::f64::consts::SQRT_2,
                    10.0,
                    6.0,
                    14.0,
                ),
                pitch_sway: wave_spectrum(
                    &mut rng,
                    1.5 * 2.0 / std::f64::consts::SQRT_2,
                    9.0,
                    6.0,
                    14.0,
                ),
                heading_sway: wave_spectrum(&mut rng, 0.5, 10.0, 6.0, 14.0),
                heading_weave_rate_deg_s: 0.5,
                ..base
            },
        }
    }
}

/// Eq (2) in f64: (heading, roll, pitch) errors in rad for errors `x` in rad.
pub fn oscillation_rad(x: &[f64; 4], rho: f64, s: f64, lat: f64) -> [f64; 3] {
    let (sl, cl) = lat.sin_cos();
    let (sr, cr) = rho.sin_cos();
    let (srs, crs) = (rho - s).sin_cos();
    [
        -x[0] * cl * crs - x[1] * cl * srs - x[2] * sl * sr + x[3] * sl * cr,
        -x[0] * sl * crs - x[1] * sl * srs + x[2] * cl * sr - x[3] * cl * cr,
        x[0] * srs - x[1] * crs,
    ]
}

fn sway(comps: &[SwayComponent], t: f64) -> f64 {
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

/// The rows of a scenario and their truth, one sample instant at a time (`k * sample_interval_s`,
/// `k = 0, 1, ...` while below `duration_s`).
pub struct Samples<'a> {
    p: &'a ScenarioParams,
    rng: ChaCha8Rng,
    white: Normal<f64>,
    jitter: Normal<f64>,
    lf: Vec<[f64; 5]>,
    w_lf: f64,
    gm_sigma: f64,
    gm_a: f64,
    gm_drive: Normal<f64>,
    gm: [f64; 3],
    /// True rotation period (nominal with the period error), s.
    period_s: f64,
    north_rate_rad_s: f64,
    /// The roll and pitch the rotating gyro bias has tilted the attitude by so far, rad.
    gyro_tilt_rad: [f64; 2],
    k: usize,
    n: usize,
}

impl<'a> Samples<'a> {
    /// The rows of `p`, from its first sample instant.
    pub fn new(p: &'a ScenarioParams) -> Samples<'a> {
        let mut rng =
            ChaCha8Rng::seed_from_u64(p.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xA77_17D3);
        let white = Normal::new(0.0, arcsec_to_rad(p.noise_arcsec).max(0.0))
            .unwrap_or(Normal::new(0.0, 0.0).unwrap());
        let jitter = Normal::new(0.0, (p.mismatch.rotation_jitter_deg * RAD_PER_DEG).max(0.0))
            .unwrap_or(Normal::new(0.0, 0.0).unwrap());
        // Eq (5) coefficients per axis (heading, roll, pitch): random directions with norm = amplitude.
        let lf_amp = p.low_frequency_deg * RAD_PER_DEG;
        let lf: Vec<[f64; 5]> = (0..3)
            .map(|_| {
                let v: [f64; 5] = core::array::from_fn(|_| rng.gen_range(-1.0..1.0));
                let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt().max(1e-9);
                core::array::from_fn(|i| v[i] / norm * lf_amp)
            })
            .collect();
        let w_lf = EARTH_RATE_RAD_PER_S * (1.0 + p.mismatch.low_frequency_rate_error);
        let gm_tau = 60.0;
        let gm_sigma = arcsec_to_rad(p.mismatch.coloured_noise_arcsec);
        let gm_a = (-p.sample_interval_s / gm_tau).exp();
        let gm_drive = Normal::new(0.0, (gm_sigma * (1.0 - gm_a * gm_a).sqrt()).max(0.0))
            .unwrap_or(Normal::new(0.0, 0.0).unwrap());
        let mut gm = [0.0f64; 3];
        if gm_sigma > 0.0 {
            let init = Normal::new(0.0, gm_sigma).unwrap_or(Normal::new(0.0, 0.0).unwrap());
            for g in &mut gm {
                *g = init.sample(&mut rng);
            }
        }
        Samples {
            p,
            rng,
            white,
            jitter,
            lf,
            w_lf,
            gm_sigma,
            gm_a,
            gm_drive,
            gm,
            period_s: p.rotation_period_s * (1.0 + p.mismatch.rotation_period_error),
            north_rate_rad_s: p.speed_m_s * (p.course_deg * RAD_PER_DEG).cos() / EARTH_RADIUS_M,
            gyro_tilt_rad: [0.0; 2],
            k: 0,
            n: (p.duration_s / p.sample_interval_s).floor() as usize,
        }
    }

    /// Number of rows still to come.
    pub fn len(&self) -> usize {
        self.n - self.k
    }

    /// Whether no rows are left to come.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Iterator for Samples<'_> {
    type Item = (Row, RowTruth);

    fn next(&mut self) -> Option<(Row, RowTruth)> {
        if self.k >= self.n {
            return None;
        }
        let p = self.p;
        let t = self.k as f64 * p.sample_interval_s;
        self.k += 1;
        let drift = p.mismatch.error_drift_arcsec_per_day * t / 86_400.0;
        let base = match p.errors_step {
            Some(step) if t >= step.at_s => step.errors_after_arcsec,
            _ => p.errors_arcsec,
        };
        let x_arcsec: [f64; 4] = core::array::from_fn(|i| base[i] + drift);
        let x: [f64; 4] = core::array::from_fn(|i| arcsec_to_rad(x_arcsec[i]));
        // The angle actually applied: the scheme at the true period, plus the angle jitter. Eq (2)
        // is evaluated at it and the log reports it.
        let jitter = self.jitter.sample(&mut self.rng);
        let rho = p.rotation_phase_deg * RAD_PER_DEG + p.scheme.rho_rad(t, self.period_s) + jitter;
        // What the log reports: the angle measured the latency before, off by the encoder's zero.
        let logged_rho =
            if p.mismatch.angle_latency_s == 0.0 && p.mismatch.encoder_offset_deg == 0.0 {
                rho
            } else {
                p.rotation_phase_deg * RAD_PER_DEG
                    + p.scheme
                        .rho_rad(t - p.mismatch.angle_latency_s, self.period_s)
                    + jitter
                    + p.mismatch.encoder_offset_deg * RAD_PER_DEG
            };
        let gyro_tilt = self.gyro_tilt_rad;
        if p.mismatch.rotating_gyro_bias_deg_h != 0.0 {
            let b_rad_s = p.mismatch.rotating_gyro_bias_deg_h * RAD_PER_DEG / 3600.0;
            self.gyro_tilt_rad[0] += b_rad_s * rho.cos() * p.sample_interval_s;
            self.gyro_tilt_rad[1] += b_rad_s * rho.sin() * p.sample_interval_s;
        }
        let s = p.platform_phase_deg * RAD_PER_DEG + EARTH_RATE_RAD_PER_S * t;
        let lat = p.latitude_deg * RAD_PER_DEG + self.north_rate_rad_s * t;
        let (weave_deg, weave_rate_deg_s) = weave(p.heading_weave_rate_deg_s, t);
        let turn = turns(p.mismatch.heel_in_turns_deg, t);
        let mut true_att = [
            p.heading_deg + weave_deg + turn.heading_deg + sway(&p.heading_sway, t),
            sway(&p.roll_sway, t) + turn.heel_deg,
            sway(&p.pitch_sway, t),
        ];
        if !p.ship_motion.is_none() {
            let (roll_deg, pitch_deg) = p
                .ship_motion
                .roll_pitch_deg(t, weave_rate_deg_s + turn.rate_deg_s);
            true_att[1] += roll_deg;
            true_att[2] += pitch_deg;
        }
        let osc = oscillation_rad(&x, rho, s, lat);
        let we = self.w_lf * t;
        let mut out = [0.0; 3];
        for axis in 0..3 {
            let a = &self.lf[axis];
            let low = a[0]
                + a[1] * we.sin()
                + a[2] * we.cos()
                + a[3] * (2.0 * we).sin()
                + a[4] * (2.0 * we).cos();
            if self.gm_sigma > 0.0 {
                self.gm[axis] = self.gm_a * self.gm[axis] + self.gm_drive.sample(&mut self.rng);
            }
            let tilt = match axis {
                1 => gyro_tilt[0],
                2 => gyro_tilt[1],
                _ => 0.0,
            };
            let err_rad = osc[axis] + low + self.white.sample(&mut self.rng) + self.gm[axis] + tilt;
            out[axis] = true_att[axis] + err_rad / RAD_PER_DEG;
        }
        let row = Row {
            time_s: t,
            rotation_deg: (logged_rho / RAD_PER_DEG).rem_euclid(360.0),
            platform_deg: (s / RAD_PER_DEG).rem_euclid(360.0),
            latitude_deg: lat / RAD_PER_DEG,
            heading_deg: out[0].rem_euclid(360.0),
            roll_deg: out[1],
            pitch_deg: out[2],
        };
        let truth = RowTruth {
            true_attitude_deg: true_att,
            oscillation_deg: [
                osc[0] / RAD_PER_DEG,
                osc[1] / RAD_PER_DEG,
                osc[2] / RAD_PER_DEG,
            ],
            errors_arcsec: x_arcsec,
        };
        Some((row, truth))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.len(), Some(self.len()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
