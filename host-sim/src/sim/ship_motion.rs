//! The ship's slow motions on an ordinary day, true attitude of eq (3) the estimator must cancel:
//! the turns with their heel ([`turns`]), the slow heading weave ([`weave`]), and the slow heel and
//! trim and the heel per rate of turn ([`ShipMotion`], drawn per seed from
//! [`ShipMotionSettings`]).

use crate::sim::scenario::{sway, sway_set, ScenarioParams, SwayComponent};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Course change of each turn of [`Mismatch::heel_in_turns_deg`], deg.
///
/// [`Mismatch::heel_in_turns_deg`]: crate::sim::scenario::Mismatch::heel_in_turns_deg
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
///
/// [`Mismatch::heel_in_turns_deg`]: crate::sim::scenario::Mismatch::heel_in_turns_deg
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
    ///
    /// [`Mismatch::heel_in_turns_deg`]: crate::sim::scenario::Mismatch::heel_in_turns_deg
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
