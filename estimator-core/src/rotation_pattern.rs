//! The rotation pattern: its period learned from the rotation angle, and its health judged against
//! what was learned.
//!
//! The moving average of eq (11) blocks the rotation harmonics when its window spans one period of
//! the pattern, whatever the pattern: one-way either way, reciprocating, multi-position
//! stop-and-go with or without reversals. Nothing here assumes a constant rate.
//!
//! # Period
//! Pinned by [`crate::Config::rotation_period_s`], or detected: a repeating pattern passes every
//! angle it reaches once per period in each direction it turns, so the time between two passes of
//! one reference angle in the same direction (1 deg of hysteresis) is the period. Of the eight
//! reference angles around the first angle seen ([`LEVEL_OFFSETS_DEG`]), two lie [`NEAR_LEVEL_DEG`]
//! either side of it, so that a one-way rotation's period is known within a period and
//! `NEAR_LEVEL_DEG / 360` (the first estimate is due within 1.25 periods:
//! [`crate::methods::windowed::start`]); six lie at 67.5, 112.5, ..., 292.5 deg, none on a dwell of
//! a scheme that stops at multiples of 45 deg. Across lost rows the angle is continuous: a pass is
//! placed where the angle, interpolated linearly, crossed the reference, and rates and dwells count
//! the lost samples; only a gap the window cannot bridge ([`crate::estimator`]) restarts the
//! timings.
//!
//! # Shape and health
//! Over the cycle after the period is known, with the rate averaged over the last [`SHORT_STEPS`]:
//! the longest dwell, whether it turns both ways, its net direction. Then a sample is a
//! [`RotationFault`] when the rotation no longer repeats its pattern: stopped for longer than the
//! longest dwell (plus an eighth and 2 samples), [`RotationFault::Stopped`]; turning against its
//! direction when the pattern never does, [`RotationFault::Reversed`] (a whole period the other
//! way is a new pattern); two passes of the reference more than `rotation_period_tolerance` plus a
//! sample off the period, or none for that long, [`RotationFault::RateMismatch`] (the pattern is
//! detected anew; a pinned period is kept). A pattern's own dwells and reversals are not faults.
//! The thresholds and their reasons: docs/real-logs.md, "The rotation pattern".

pub(crate) mod checkpoint;

use crate::math::wrap_pi;
use crate::Real;

/// Reference angles watched for passes.
pub const LEVELS: usize = 8;
/// Samples in the short mean of the rotation increment.
pub const SHORT_STEPS: u32 = 4;
const PI: Real = core::f64::consts::PI as Real;
/// The first reference angles either side of the first angle seen, deg: clear of the hysteresis
/// and of the jitter of a dwell there, and passed within 1.4 % of a period by a one-way rotation.
pub const NEAR_LEVEL_DEG: f64 = 5.0;

/// The reference angles from the first angle seen, deg, in `[0, 360)`: [`NEAR_LEVEL_DEG`] ahead,
/// six 45 deg apart from 67.5 deg, and [`NEAR_LEVEL_DEG`] behind.
pub const LEVEL_OFFSETS_DEG: [f64; LEVELS] = [
    NEAR_LEVEL_DEG,
    67.5,
    112.5,
    157.5,
    202.5,
    247.5,
    292.5,
    360.0 - NEAR_LEVEL_DEG,
];

/// The angle the monitor keeps (its checkpoint too) as where its references are: 22.5 deg from
/// the first angle seen, on the 45 deg grid of six of the eight references ([`LEVEL_OFFSETS_DEG`],
/// 67.5 to 292.5 deg). Part of the checkpoint's format: a checkpoint image holds the kept angle,
/// and the references are placed from it by these offsets.
const BASE_DEG: f64 = 22.5;

/// [`LEVEL_OFFSETS_DEG`] in rad from the kept angle ([`BASE_DEG`]), each in `[0, 2 pi)`.
const LEVEL_FROM_BASE_RAD: [Real; LEVELS] = {
    let mut out = [0.0; LEVELS];
    let mut m = 0;
    while m < LEVELS {
        let mut deg = LEVEL_OFFSETS_DEG[m] - BASE_DEG;
        if deg < 0.0 {
            deg += 360.0;
        }
        out[m] = (deg * core::f64::consts::PI / 180.0) as Real;
        m += 1;
    }
    out
};

/// [`BASE_DEG`] in rad.
const BASE_RAD: Real = (BASE_DEG * core::f64::consts::PI / 180.0) as Real;

/// Hysteresis of a pass, rad (1 deg).
pub const PASS_HYSTERESIS_RAD: Real = 0.017_453_292;

/// Why the rotation is not healthy (on the link and in checkpoints, as part of its [`crate::Status`]
/// code).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RotationFault {
    /// Stopped for longer than the pattern's longest dwell.
    Stopped,
    /// Turning the other way, in a pattern that never does.
    Reversed,
    /// The pattern no longer repeats at its period.
    RateMismatch,
}

/// The shape of a learned pattern, for people.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternKind {
    /// One way, without stops.
    OneWay,
    /// Both ways, without stops.
    Reciprocating,
    /// One way, stopping at positions.
    StopAndGo,
    /// Both ways, stopping at positions.
    StopAndGoReciprocating,
}

impl PatternKind {
    /// Short name used in files and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            PatternKind::OneWay => "one-way",
            PatternKind::Reciprocating => "reciprocating",
            PatternKind::StopAndGo => "stop-and-go",
            PatternKind::StopAndGoReciprocating => "stop-and-go reciprocating",
        }
    }
}

/// What one sample told the monitor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternEvent {
    /// Nothing new.
    None,
    /// The period has just become known, in samples: the window is to be set to it.
    PeriodKnown(u32),
}

/// Features learned over one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Features {
    /// +1 or -1: the net direction of a one-way pattern; 0 for a pattern that comes back.
    pub direction: i8,
    /// Whether the pattern turns both ways.
    pub reverses: bool,
    /// Longest dwell, samples.
    pub longest_dwell_samples: u32,
}

impl Features {
    /// The pattern's kind.
    pub fn kind(&self) -> PatternKind {
        match (
            self.reverses,
            self.longest_dwell_samples > dwell_threshold_samples(),
        ) {
            (false, false) => PatternKind::OneWay,
            (true, false) => PatternKind::Reciprocating,
            (false, true) => PatternKind::StopAndGo,
            (true, true) => PatternKind::StopAndGoReciprocating,
        }
    }
}

/// Dwells up to this long are the slowing of a turnaround or jitter, not stops of a stop-and-go
/// scheme (for the pattern's name only).
const fn dwell_threshold_samples() -> u32 {
    3
}

/// Bounds the monitor works within, from the configuration and the sample interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Shortest period accepted, samples.
    pub min_period_samples: u32,
    /// Longest period accepted, samples.
    pub max_period_samples: u32,
    /// Largest relative deviation of the time between two passes from the period.
    pub period_tolerance: Real,
}

/// Whether a pass `elapsed` samples after the previous one is on time: within the tolerance plus
/// one sample (a pass is timed to the sample).
fn pass_on_time(elapsed: u32, period: u32, limits: &Limits) -> bool {
    (elapsed as Real - period as Real).abs() <= limits.period_tolerance * period as Real + 1.0
}

/// The grid index at which a pass between the sample `k` and the one `steps` later (across lost
/// rows) happened, by linear interpolation of the angle from the reference: the first index at or
/// after the moment the angle crossed the hysteresis threshold it crossed (`+` for a pass upwards,
/// `dir` 0; `-` downwards), which is the index a received row there would have given for a
/// rotation at a steady rate. `d_prev` and `d` are the angles from the reference at `k` and now.
fn pass_across_gap(k: u32, steps: u32, d_prev: Real, d: Real, dir: usize) -> u32 {
    let mut d_prev = d_prev;
    if d_prev < -PI {
        d_prev += 2.0 * PI;
    }
    let threshold = if dir == 0 {
        PASS_HYSTERESIS_RAD
    } else {
        -PASS_HYSTERESIS_RAD
    };
    let span = d - d_prev;
    let f = if span != 0.0 {
        ((threshold - d_prev) / span).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = f * steps as Real;
    let whole = x as u32;
    let after = if (whole as Real) < x {
        whole + 1
    } else {
        whole
    };
    k.wrapping_add(after.clamp(1, steps))
}

/// The rotation monitor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationMonitor {
    /// The period, samples, once pinned or detected.
    period_samples: Option<u32>,
    /// Whether the period was pinned by the configuration.
    pinned: bool,
    /// Features, once a whole cycle has been watched with the period known.
    features: Option<Features>,
    /// Where the reference angles are: the first angle seen plus [`BASE_DEG`], rad (set at the
    /// first sample).
    levels_rad: Option<Real>,
    /// Per reference angle: -1 below, +1 above, 0 far (more than 90 deg away).
    level_side: [i8; LEVELS],
    /// Per reference angle and direction (0 up, 1 down): sample index of the last pass.
    last_pass: [[Option<u32>; 2]; LEVELS],
    /// The reference angle and direction whose passes time the period (once known).
    timing_pass: Option<(u8, u8)>,
    /// The previous sample's rotation angle and index.
    previous: Option<(u32, Real)>,
    /// Short mean of the increment, rad per sample.
    short_increment_rad: Real,
    short_steps: u32,
    /// Learning a cycle: its start index, net rotation, dwell run, longest dwell, first direction,
    /// whether it reversed.
    learn_start: Option<u32>,
    learn_rotation_rad: Real,
    dwell_run: u32,
    learn_longest_dwell: u32,
    learn_first_direction: i8,
    learn_reversed: bool,
    /// Samples in a row turning against a one-way pattern.
    reversed_run: u32,
}

impl RotationMonitor {
    /// The rotation period in samples, pinned or detected; `None` while it is being detected.
    pub fn period_samples(&self) -> Option<u32> {
        self.period_samples
    }

    /// The learned features of the rotation pattern; `None` until a cycle has been learned.
    pub fn features(&self) -> Option<Features> {
        self.features
    }

    /// A monitor with the period pinned (in samples) or to be detected.
    pub const fn new(pinned_period_samples: Option<u32>) -> RotationMonitor {
        RotationMonitor {
            period_samples: pinned_period_samples,
            pinned: pinned_period_samples.is_some(),
            features: None,
            levels_rad: None,
            level_side: [0; LEVELS],
            last_pass: [[None; 2]; LEVELS],
            timing_pass: None,
            previous: None,
            short_increment_rad: 0.0,
            short_steps: 0,
            learn_start: None,
            learn_rotation_rad: 0.0,
            dwell_run: 0,
            learn_longest_dwell: 0,
            learn_first_direction: 0,
            learn_reversed: false,
            reversed_run: 0,
        }
    }

    /// Forgets the sample history (after a gap the window cannot bridge): the next sample starts
    /// new increments and new pass timings; what was learned stays.
    pub fn restart(&mut self) {
        self.previous = None;
        self.short_steps = 0;
        self.short_increment_rad = 0.0;
        self.dwell_run = 0;
        self.level_side = [0; LEVELS];
        self.last_pass = [[None; 2]; LEVELS];
        if self.features.is_none() {
            // A cycle being learned must be whole.
            self.learn_start = None;
        }
    }

    /// After a fault: the pass timings start again (a stop shifts the pattern's phase); the short
    /// mean and the dwell run go on, so a stop stays a stop until the rotation moves again.
    pub fn after_fault(&mut self) {
        self.level_side = [0; LEVELS];
        self.last_pass = [[None; 2]; LEVELS];
    }

    /// Forgets the pattern (a pinned period stays) and detects it anew. Out of line: one copy for
    /// its three callers.
    #[inline(never)]
    fn forget(&mut self) {
        let pinned = if self.pinned {
            self.period_samples
        } else {
            None
        };
        *self = RotationMonitor::new(pinned);
    }

    /// Watches one sample (index on the sample grid, rotation angle): the rotation's rate, the
    /// passes of the reference angles (which time the period), and, once the pattern is known,
    /// its health; while it is being learned, the learning.
    pub fn observe(
        &mut self,
        index: u32,
        rotation_rad: Real,
        limits: &Limits,
    ) -> Result<PatternEvent, RotationFault> {
        let base = *self
            .levels_rad
            .get_or_insert(wrap_pi(rotation_rad + BASE_RAD));
        let previous = self.previous.replace((index, rotation_rad));
        let (steps, increment) = self.track_rate(previous, index, rotation_rad);
        let event = self.watch_passes(previous, steps, index, rotation_rad, base, limits)?;
        if let PatternEvent::PeriodKnown(_) = event {
            self.learn_start = None;
        }
        let Some(period) = self.period_samples else {
            return Ok(event);
        };
        // In the step's float type: no software f64 division a sample.
        let nominal = 2.0 * PI / period as Real;
        let still = self.short_steps > 0 && self.short_increment_rad.abs() < 0.25 * nominal;
        self.dwell_run = if still {
            self.dwell_run.saturating_add(steps)
        } else {
            0
        };
        let Some(features) = self.features else {
            self.learn(index, increment, nominal, period);
            return Ok(event);
        };
        self.check_health(&features, index, period, nominal, limits)?;
        Ok(event)
    }

    /// The samples since the previous one (more than 1 across lost rows) and the rotation over
    /// them, wrapped (`None` for the first sample): the angle is continuous between the rows that
    /// are there. Updates the short mean of the rotation per sample.
    #[inline(always)]
    fn track_rate(
        &mut self,
        previous: Option<(u32, Real)>,
        index: u32,
        rotation_rad: Real,
    ) -> (u32, Option<Real>) {
        let (steps, increment) = match previous {
            Some((k, rho)) if index.wrapping_sub(k) >= 1 => {
                (index.wrapping_sub(k), Some(wrap_pi(rotation_rad - rho)))
            }
            _ => (1, None),
        };
        if let Some(inc) = increment {
            self.short_steps = (self.short_steps + 1).min(SHORT_STEPS);
            let per_step = if steps == 1 { inc } else { inc / steps as Real };
            self.short_increment_rad +=
                (per_step - self.short_increment_rad) / self.short_steps as Real;
        }
        (steps, increment)
    }

    /// The passes of the reference angles ([`LEVEL_OFFSETS_DEG`]; `base` the kept angle): the first
    /// two passes of one reference the same way give the period; once it is known, only the
    /// reference that times it is watched, and a pass off time forgets the pattern. A pass inside
    /// a run of lost rows is placed by interpolation across it.
    #[inline(always)]
    fn watch_passes(
        &mut self,
        previous: Option<(u32, Real)>,
        steps: u32,
        index: u32,
        rotation_rad: Real,
        base: Real,
        limits: &Limits,
    ) -> Result<PatternEvent, RotationFault> {
        let mut event = PatternEvent::None;
        // The angle from the kept angle, once wrapped; from each reference by subtracting its
        // offset (in [0, 2 pi)) and wrapping with one comparison (no division on the step's
        // path).
        let d0 = wrap_pi(rotation_rad - base);
        let watched = match (self.period_samples, self.timing_pass) {
            (Some(_), Some((level, _))) => {
                // Within the references (as it always is), said so: no bounds check below.
                let level = usize::from(level).min(LEVELS - 1);
                level..level + 1
            }
            _ => 0..LEVELS,
        };
        for m in watched {
            let mut d = d0 - LEVEL_FROM_BASE_RAD[m];
            if d < -PI {
                d += 2.0 * PI;
            }
            let old = self.level_side[m];
            let side = if d.abs() > 0.5 * PI {
                0
            } else if d < -PASS_HYSTERESIS_RAD {
                -1
            } else if d > PASS_HYSTERESIS_RAD {
                1
            } else {
                old
            };
            self.level_side[m] = side;
            let dir = match (old, side) {
                (-1, 1) => 0usize,
                (1, -1) => 1usize,
                _ => continue,
            };
            let pass = match previous {
                Some((k, rho)) if steps > 1 => pass_across_gap(
                    k,
                    steps,
                    wrap_pi(rho - base) - LEVEL_FROM_BASE_RAD[m],
                    d,
                    dir,
                ),
                _ => index,
            };
            let last = self.last_pass[m][dir].replace(pass);
            match (self.period_samples, last) {
                (None, Some(k)) => {
                    let period = pass.wrapping_sub(k);
                    if period >= limits.min_period_samples && period <= limits.max_period_samples {
                        self.period_samples = Some(period);
                        self.timing_pass = Some((m as u8, dir as u8));
                        event = PatternEvent::PeriodKnown(period);
                    }
                }
                (Some(period), Some(k))
                    if self.timing_pass == Some((m as u8, dir as u8))
                        && self.features.is_some()
                        && !pass_on_time(pass.wrapping_sub(k), period, limits) =>
                {
                    self.forget();
                    return Err(RotationFault::RateMismatch);
                }
                (Some(_), _) if self.timing_pass.is_none() => {
                    self.timing_pass = Some((m as u8, dir as u8))
                }
                _ => {}
            }
        }
        Ok(event)
    }

    /// The rotation against its learned pattern: the timing pass overdue (a stop if the rotation
    /// dwells, else another rate: the pattern is forgotten), a dwell longer than the pattern's
    /// longest, or a turn the other way in a pattern that never reverses (for a whole period: a
    /// new pattern).
    #[inline(always)]
    fn check_health(
        &mut self,
        features: &Features,
        index: u32,
        period: u32,
        nominal: Real,
        limits: &Limits,
    ) -> Result<(), RotationFault> {
        if let Some((m, dir)) = self.timing_pass {
            let last = self
                .last_pass
                .get(usize::from(m))
                .and_then(|passes| passes.get(usize::from(dir)));
            if let Some(&Some(k)) = last {
                if index.wrapping_sub(k) > period
                    && !pass_on_time(index.wrapping_sub(k), period, limits)
                {
                    if self.dwell_run > 0 {
                        // Late because it has stopped: a stop, judged below, not a new period.
                        self.after_fault();
                        return Err(RotationFault::Stopped);
                    }
                    self.forget();
                    return Err(RotationFault::RateMismatch);
                }
            }
        }
        let longest = features.longest_dwell_samples;
        if self.dwell_run > longest + longest / 8 + 2 {
            return Err(RotationFault::Stopped);
        }
        let reversed = !features.reverses
            && self.short_steps > 0
            && self.short_increment_rad * Real::from(features.direction) < -0.5 * nominal;
        self.reversed_run = if reversed {
            self.reversed_run.saturating_add(1)
        } else {
            0
        };
        if reversed {
            if self.reversed_run > period {
                // A whole period the other way: a new pattern, not a reversal.
                self.forget();
            }
            return Err(RotationFault::Reversed);
        }
        Ok(())
    }

    /// Learns the features over one whole cycle of consecutive samples.
    fn learn(&mut self, index: u32, increment: Option<Real>, nominal: Real, period: u32) {
        let Some(start) = self.learn_start else {
            self.learn_start = Some(index);
            self.learn_rotation_rad = 0.0;
            self.learn_longest_dwell = 0;
            self.learn_first_direction = 0;
            self.learn_reversed = false;
            return;
        };
        let Some(inc) = increment else {
            // After a gap the window cannot bridge: start the cycle again.
            self.learn_start = None;
            return;
        };
        self.learn_rotation_rad += inc;
        self.learn_longest_dwell = self.learn_longest_dwell.max(self.dwell_run);
        let s = self.short_increment_rad;
        if self.learn_first_direction == 0 && s.abs() > 0.5 * nominal {
            self.learn_first_direction = if s > 0.0 { 1 } else { -1 };
        } else if self.learn_first_direction != 0
            && s * Real::from(self.learn_first_direction) < -0.5 * nominal
        {
            self.learn_reversed = true;
        }
        if index.wrapping_sub(start) >= period {
            let net = self.learn_rotation_rad;
            let direction = if self.learn_reversed && net.abs() < 0.5 * PI {
                0
            } else if net >= 0.0 {
                1
            } else {
                -1
            };
            self.features = Some(Features {
                direction,
                reverses: self.learn_reversed,
                longest_dwell_samples: self.learn_longest_dwell,
            });
        }
    }
}
