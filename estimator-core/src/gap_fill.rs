//! Lost samples: short gaps filled from their neighbours, so that the moving average still cancels
//! the sway.
//!
//! # Why fill, and why not linearly
//! The window mean of eq (11) cancels the ship's sway (degrees) only because it sums the sway over
//! whole sway periods. A lost sample takes one sway value out of that sum: leaving it out biases
//! the window's correlation by about `A c / N` (A the sway amplitude, c the reference, N the window),
//! tens of arcsec for a 3 deg sway, and a log that loses 2 % of its rows at random never has a
//! complete window. Filling the sample with an interpolation of its neighbours leaves only the
//! interpolation error in the sum. Linear interpolation leaves about half the amplitude of a 6 s
//! sway sampled at 1 s; a cubic through four neighbours 17 %; the Lagrange polynomial through the
//! [`NEIGHBOURS`] present samples on each side (10 points) 0.4 % at a 6 s period and 0.03 % at
//! 8 s for one lost sample (2 % and 0.15 % for two lost in a row, 10 % and 0.8 % for three): the
//! sway is far below the Nyquist frequency of a 1 s log, and a polynomial of high order through
//! many neighbours is a good band-limited interpolator there. Only roll and pitch are filled this
//! way; the angles, which move slowly and at a steady rate, are interpolated linearly (the short
//! way round), and the filled reference is used both in the measurement and in its row, so an
//! error in it is no bias.
//!
//! Gaps of more than `max_filled_gap_samples` (3 by default) are not filled: the window restarts
//! and holds over them (a 60 s outage cannot be interpolated across a 6 s sway).
//!
//! # What a filled sample costs: the 1-sigma
//! Each filled sample carries its interpolation error into the sums. Its size depends on the sway
//! spectrum, so it is measured as the data come: every present sample whose [`NEIGHBOURS`]
//! neighbours on each side are present is also predicted from them as if it were lost, and the
//! mean square of that prediction error (over the last [`FILL_ERROR_SAMPLES`] samples) is the
//! variance of a filled single sample. A sample filled with fewer neighbours (two or three lost in
//! a row, or other losses nearby) is worse by the ratios of the interpolation errors
//! ([`MISSING_NEIGHBOUR_VARIANCE_FACTOR`], one factor per lost neighbour). The window counts these
//! variances, and the filter's measurement variance is raised by their mean over the window (see
//! [`crate::methods::windowed`]).
//!
//! # Delay
//! A sample is passed on once its [`NEIGHBOURS`] successors have arrived (or are known to be
//! lost): the window runs [`NEIGHBOURS`] samples behind the input. The output of a step is that of
//! the newest sample passed on; its attitude is corrected with the current estimate at once.

pub(crate) mod checkpoint;

use crate::installation::Angles;
use crate::math::{sin_cos, wrap_pi};
use crate::Real;

/// Present samples used on each side of a lost one.
pub const NEIGHBOURS: usize = 5;
/// Longest gap that can ever be filled (the configuration may choose less).
pub const MAX_FILLABLE_GAP: u32 = 3;
/// Slots of the delay line: the neighbours on both sides of the longest fillable gap, rounded up.
pub const SLOTS: usize = 16;
/// Samples over which the prediction error of present samples is averaged.
pub const FILL_ERROR_SAMPLES: u32 = 256;
/// The prediction error is measured at every this many grid indices.
pub const FILL_ERROR_EVERY: u32 = 4;
/// How much each further lost neighbour at distance 1..=5 raises the variance of a filled sample
/// (squared ratios of the interpolation errors of a 6 s sway at 1 s, rounded up: one neighbour
/// fewer at distance 1 makes the error 8.7 times larger, at 5 only 2 times).
pub const MISSING_NEIGHBOUR_VARIANCE_FACTOR: [u32; NEIGHBOURS] = [76, 20, 10, 6, 4];

/// One sample on the grid, as the window takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSample {
    /// Index on the sample grid.
    pub index: u32,
    pub roll_rad: Real,
    pub pitch_rad: Real,
    pub rotation_rad: Real,
    /// Rotation minus platform angle, rad.
    pub rotation_minus_platform_rad: Real,
    pub latitude_rad: Real,
    /// Trigonometry of the angles.
    pub angles: Angles,
    /// 0 for a received sample; for a filled one, its variance in units of a filled single
    /// sample's ([`MISSING_NEIGHBOUR_VARIANCE_FACTOR`]), saturating.
    pub fill_weight: u16,
}

/// The delay line and the fill-error monitor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GapFiller {
    /// Slot `index % SLOTS`: the sample of that index, if received.
    slots: [Option<GridSample>; SLOTS],
    /// The newest index received, once any.
    newest: Option<u32>,
    /// The next index to pass on.
    next: u32,
    /// Mean square prediction error of present roll and pitch samples, rad^2, and samples averaged.
    roll_error_rad2: Real,
    pitch_error_rad2: Real,
    error_samples: u32,
}

/// Weights of the 10-point Lagrange prediction of the middle of `-5..=5` (without 0), at nodes
/// -5..-1, 1..5: `w_j = prod_{m != j} m / (m - j)`, exact rationals (denominator 126), computed
/// once at build time.
const SYMMETRIC_WEIGHTS: [Real; 2 * NEIGHBOURS] = {
    let nodes: [i64; 2 * NEIGHBOURS] = [-5, -4, -3, -2, -1, 1, 2, 3, 4, 5];
    let mut w = [0.0; 2 * NEIGHBOURS];
    let mut j = 0;
    while j < 2 * NEIGHBOURS {
        let (mut num, mut den) = (1i64, 1i64);
        let mut m = 0;
        while m < 2 * NEIGHBOURS {
            if m != j {
                num *= -nodes[m];
                den *= nodes[j] - nodes[m];
            }
            m += 1;
        }
        w[j] = (num as f64 / den as f64) as Real;
        j += 1;
    }
    w
};

/// Lagrange weights at 0 for the first `n` integer nodes (all distinct and non-zero).
fn lagrange_at_zero(nodes: &[i32; 2 * NEIGHBOURS], n: usize) -> [Real; 2 * NEIGHBOURS] {
    let mut w = [0.0; 2 * NEIGHBOURS];
    for i in 0..n {
        let mut num: Real = 1.0;
        let mut den: Real = 1.0;
        for m in 0..n {
            if m != i {
                num *= -(nodes[m] as Real);
                den *= (nodes[i] - nodes[m]) as Real;
            }
        }
        w[i] = num / den;
    }
    w
}

impl Default for GapFiller {
    fn default() -> Self {
        GapFiller::new()
    }
}

impl GapFiller {
    /// An empty delay line, no fill error measured yet.
    pub const fn new() -> Self {
        GapFiller {
            slots: [None; SLOTS],
            newest: None,
            next: 0,
            roll_error_rad2: 0.0,
            pitch_error_rad2: 0.0,
            error_samples: 0,
        }
    }
}

/// The error variance of one filled sample, measured online, of roll and of pitch.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FillVariance {
    pub roll_rad2: Real,
    pub pitch_rad2: Real,
}

impl GapFiller {
    /// Forgets every pending sample (the fill-error estimate stays: it belongs to the sea state).
    pub fn clear(&mut self) {
        self.slots = [None; SLOTS];
        self.newest = None;
    }

    /// The variance of a filled single sample of roll and of pitch (0 until measured).
    pub fn single_fill_variance(&self) -> FillVariance {
        FillVariance {
            roll_rad2: self.roll_error_rad2,
            pitch_rad2: self.pitch_error_rad2,
        }
    }

    /// Takes a received sample `intervals` after the previous one (which the caller has judged
    /// fillable: at most [`MAX_FILLABLE_GAP`] lost) and passes on, through `emit`, every sample
    /// whose neighbours are now known, in index order. Returns how many were passed on.
    pub fn push(&mut self, sample: GridSample, emit: &mut impl FnMut(&GridSample)) -> u32 {
        if self.newest.is_none() {
            self.next = sample.index;
        }
        // Lost samples between the previous one and this one leave their slots empty.
        if let Some(newest) = self.newest {
            let mut k = newest.wrapping_add(1);
            while k != sample.index {
                self.slots[k as usize % SLOTS] = None;
                k = k.wrapping_add(1);
            }
        }
        self.slots[sample.index as usize % SLOTS] = Some(sample);
        self.newest = Some(sample.index);
        let mut emitted = 0;
        while sample.index.wrapping_sub(self.next) as usize >= NEIGHBOURS
            && sample.index.wrapping_sub(self.next) < SLOTS as u32
        {
            let k = self.next;
            let out = match self.slots[k as usize % SLOTS] {
                Some(s) => {
                    self.measure_fill_error(&s);
                    Some(s)
                }
                None => self.fill(k),
            };
            if let Some(s) = out {
                emit(&s);
                emitted += 1;
            }
            self.next = k.wrapping_add(1);
        }
        emitted
    }

    /// Passes on every pending received sample (before a gap that cannot be filled, after which
    /// the window restarts), then forgets them.
    pub fn flush(&mut self, emit: &mut impl FnMut(&GridSample)) -> u32 {
        let mut emitted = 0;
        if let Some(newest) = self.newest {
            let mut k = self.next;
            while newest.wrapping_sub(k) < SLOTS as u32 {
                if let Some(s) = self.slots[k as usize % SLOTS] {
                    emit(&s);
                    emitted += 1;
                }
                if k == newest {
                    break;
                }
                k = k.wrapping_add(1);
            }
        }
        self.clear();
        emitted
    }

    /// The sample at `index` (inside the delay line) if received.
    fn at(&self, index: u32) -> Option<&GridSample> {
        self.slots[index as usize % SLOTS]
            .as_ref()
            .filter(|s| s.index == index)
    }

    /// Predicts a present sample from its 10 neighbours, when all are present, and averages the
    /// squared prediction error. Every [`FILL_ERROR_EVERY`]th index only: the mean square of a sea
    /// state needs no more, and the step's cost stays low.
    fn measure_fill_error(&mut self, s: &GridSample) {
        if !s.index.is_multiple_of(FILL_ERROR_EVERY) {
            return;
        }
        let mut roll = 0.0;
        let mut pitch = 0.0;
        let w = &SYMMETRIC_WEIGHTS;
        for i in 0..2 * NEIGHBOURS {
            let offset = if i < NEIGHBOURS {
                i as i32 - NEIGHBOURS as i32
            } else {
                i as i32 - NEIGHBOURS as i32 + 1
            };
            let Some(n) = self.at(s.index.wrapping_add(offset as u32)) else {
                return;
            };
            roll += w[i] * n.roll_rad;
            pitch += w[i] * n.pitch_rad;
        }
        self.error_samples = (self.error_samples + 1).min(FILL_ERROR_SAMPLES);
        let a = 1.0 / self.error_samples as Real;
        let (er, ep) = (roll - s.roll_rad, pitch - s.pitch_rad);
        self.roll_error_rad2 += a * (er * er - self.roll_error_rad2);
        self.pitch_error_rad2 += a * (ep * ep - self.pitch_error_rad2);
    }

    /// Fills the lost sample `index` from the present samples within [`NEIGHBOURS`] on each side.
    fn fill(&self, index: u32) -> Option<GridSample> {
        let mut nodes = [0i32; 2 * NEIGHBOURS];
        let mut values = [(0.0, 0.0); 2 * NEIGHBOURS];
        let mut n = 0;
        let mut before: Option<(i32, &GridSample)> = None;
        let mut after: Option<(i32, &GridSample)> = None;
        let mut weight = 1u32;
        for offset in -(NEIGHBOURS as i32)..=(NEIGHBOURS as i32) {
            if offset == 0 {
                continue;
            }
            let Some(s) = self.at(index.wrapping_add(offset as u32)) else {
                let factor = MISSING_NEIGHBOUR_VARIANCE_FACTOR[offset.unsigned_abs() as usize - 1];
                weight = weight.saturating_mul(factor);
                continue;
            };
            {
                nodes[n] = offset;
                values[n] = (s.roll_rad, s.pitch_rad);
                n += 1;
                if offset < 0 {
                    before = Some((offset, s));
                } else if after.is_none() {
                    after = Some((offset, s));
                }
            }
        }
        let ((ob, b), (oa, a)) = (before?, after?);
        let w = lagrange_at_zero(&nodes, n);
        let (mut roll, mut pitch) = (0.0, 0.0);
        for i in 0..n {
            roll += w[i] * values[i].0;
            pitch += w[i] * values[i].1;
        }
        // Angles linearly, the short way round, between the nearest present samples.
        let f = (-ob) as Real / (oa - ob) as Real;
        let ang = |x: Real, y: Real| wrap_pi(x + wrap_pi(y - x) * f);
        let rotation_rad = ang(b.rotation_rad, a.rotation_rad);
        let rotation_minus_platform_rad =
            ang(b.rotation_minus_platform_rad, a.rotation_minus_platform_rad);
        let latitude_rad = b.latitude_rad + (a.latitude_rad - b.latitude_rad) * f;
        let lat = if latitude_rad == b.latitude_rad {
            (b.angles.sin_lat, b.angles.cos_lat)
        } else {
            sin_cos(latitude_rad)
        };
        let weight = weight.min(u32::from(u16::MAX)) as u16;
        Some(GridSample {
            index,
            roll_rad: roll,
            pitch_rad: pitch,
            rotation_rad,
            rotation_minus_platform_rad,
            latitude_rad,
            angles: Angles::from_rotation(rotation_rad, rotation_minus_platform_rad, lat),
            fill_weight: weight,
        })
    }
}
