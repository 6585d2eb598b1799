//! Bins: when one period holds more samples than the ring's capacity (a 10 Hz log, a long
//! period), consecutive samples are averaged into bins, each one entry of the window.
//!
//! [`WindowLayout::for_period`] chooses the bin: the smallest that divides the period into at most
//! the ring's capacity of entries, so that the window spans exactly one period; when none does
//! within twice the smallest possible bin, that smallest bin and the nearest whole number of
//! entries. A bin sums roll, pitch, latitude, the references and the rates of turn, and the
//! angles as offsets from its first sample (so that a bin across +-pi averages the short way
//! round), each weighted by the sample's weight; its entry is their weighted mean, of the mean
//! weight of its samples (a lost sample counts 0). Averaging within a bin slightly low-passes the
//! sway (it helps) and the oscillation of eq (2) (a relative error of about
//! `(w_r b dt)^2 / 24`). What bins cost in accuracy is measured in docs/real-logs.md (Bins).

use super::{CorrelationWindow, FillCode, Pushed};
use crate::correlation::{QuantizedSample, References, FULL_WEIGHT};
use crate::gap_fill::GridSample;
use crate::installation::Angles;
use crate::math::{round, sin_cos, wrap_pi};
use crate::Real;

/// A bin being filled: the sums of its samples' values times their weights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bin {
    /// Samples in the bin.
    pub count: u32,
    /// The bin's number.
    pub number: u32,
    /// Sum of the samples' weights (a full weight counts 1).
    pub weight: Real,
    /// Sum of roll, rad.
    pub roll_rad: Real,
    /// Sum of pitch, rad.
    pub pitch_rad: Real,
    /// Sum of latitude, rad.
    pub latitude_rad: Real,
    /// Sum of the low-passed references.
    pub reference: [Real; 4],
    /// Sum of the rates of turn, in units of [`crate::correlation::TURN_RATE_UNIT_RAD_S`].
    pub turn_rate: Real,
    /// Sum of the turn channel's references, in the same units.
    pub turn_reference: Real,
    /// The first sample's rotation angle, rad.
    pub rotation0_rad: Real,
    /// Sum of the rotation angles' offsets from `rotation0_rad`, rad.
    pub rotation_offset_rad: Real,
    /// The first sample's rotation-minus-platform angle, rad.
    pub rotation_minus_platform0_rad: Real,
    /// Sum of the rotation-minus-platform angles' offsets from `rotation_minus_platform0_rad`, rad.
    pub rotation_minus_platform_offset_rad: Real,
    /// Sum of the samples' fill weights (unweighted, see [`crate::gap_fill`]).
    pub fill_weight: u32,
}

impl Bin {
    /// Nothing in it.
    pub const ZERO: Bin = Bin {
        number: 0,
        weight: 0.0,
        count: 0,
        roll_rad: 0.0,
        pitch_rad: 0.0,
        latitude_rad: 0.0,
        reference: [0.0; 4],
        turn_rate: 0.0,
        turn_reference: 0.0,
        rotation0_rad: 0.0,
        rotation_offset_rad: 0.0,
        rotation_minus_platform0_rad: 0.0,
        rotation_minus_platform_offset_rad: 0.0,
        fill_weight: 0,
    };
}

/// How one period is held by the window: samples per entry and entries in a full window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WindowLayout {
    /// Samples per entry (1 without bins).
    pub samples_per_entry: u32,
    /// Entries in a full window.
    pub entries: usize,
}

impl WindowLayout {
    /// How a period of `period_samples` is held by a ring of `capacity` entries. One sample per
    /// entry when the period fits; otherwise the smallest bin that divides the period into at most
    /// `capacity` entries, or, when none does within twice the smallest possible bin, that
    /// smallest bin and the nearest whole number of entries.
    pub fn for_period(period_samples: u32, capacity: usize) -> WindowLayout {
        let capacity = capacity.max(2) as u32;
        let period = period_samples.max(2);
        if period <= capacity {
            return WindowLayout {
                samples_per_entry: 1,
                entries: period as usize,
            };
        }
        // At least 1 (the period is over the capacity), said so: no division by zero below.
        let smallest = period.div_ceil(capacity).max(1);
        for bin in smallest..=2 * smallest {
            if period.is_multiple_of(bin) && period / bin <= capacity {
                return WindowLayout {
                    samples_per_entry: bin,
                    entries: (period / bin) as usize,
                };
            }
        }
        let entries = ((period + smallest / 2) / smallest).clamp(2, capacity);
        WindowLayout {
            samples_per_entry: smallest,
            entries: entries as usize,
        }
    }
}

impl<const CAP: usize> CorrelationWindow<CAP> {
    /// [`CorrelationWindow::push`] with bins of `self.bin` samples: adds the sample to the bin
    /// being filled, and turns the bin into an entry when it is full or when the sample belongs to
    /// the next bin (the rest of the bin was lost).
    // Called once, on the step's path.
    #[inline(always)]
    pub(super) fn push_to_bin(
        &mut self,
        s: &GridSample,
        reference: &References,
        turn_rate: Real,
        weight: u8,
    ) -> Pushed {
        // Bins lie at whole multiples of the bin on the grid, wherever the window starts: a log
        // whose grid is learned a few stamps later (jittered stamps) bins its samples alike.
        let origin = *self
            .origin
            .get_or_insert(s.index - s.index % self.bin.max(1));
        let number = s.index.wrapping_sub(origin) / self.bin;
        let mut out = Pushed {
            completed: false,
            removed: 0,
        };
        if self.partial.count > 0 && self.partial.number != number {
            // The rest of the bin was lost: the bin is what it has.
            out = self.close_bin();
        }
        let w = Real::from(weight.min(FULL_WEIGHT)) * (1.0 / FULL_WEIGHT as Real);
        let b = &mut self.partial;
        if b.count == 0 {
            *b = Bin {
                number,
                rotation0_rad: s.rotation_rad,
                rotation_minus_platform0_rad: s.rotation_minus_platform_rad,
                ..Bin::default()
            };
        }
        b.count += 1;
        b.weight += w;
        b.roll_rad += w * s.roll_rad;
        b.pitch_rad += w * s.pitch_rad;
        b.latitude_rad += w * s.latitude_rad;
        for ch in 0..4 {
            b.reference[ch] += w * reference.channels[ch];
        }
        b.turn_rate += w * turn_rate;
        b.turn_reference += w * reference.turn;
        b.rotation_offset_rad += w * wrap_pi(s.rotation_rad - b.rotation0_rad);
        b.rotation_minus_platform_offset_rad +=
            w * wrap_pi(s.rotation_minus_platform_rad - b.rotation_minus_platform0_rad);
        b.fill_weight += u32::from(s.fill_weight);
        if b.count >= self.bin {
            let closed = self.close_bin();
            out = Pushed {
                completed: out.completed || closed.completed,
                removed: out.removed + closed.removed,
            };
        }
        out
    }
    /// Turns the bin being filled into an entry (none when all its samples had weight 0).
    fn close_bin(&mut self) -> Pushed {
        let b = self.partial;
        self.partial = Bin::default();
        if !(b.weight > 0.0) {
            return Pushed {
                completed: false,
                removed: 0,
            };
        }
        let n = b.weight;
        let rotation = wrap_pi(b.rotation0_rad + b.rotation_offset_rad / n);
        let rotation_minus_platform =
            wrap_pi(b.rotation_minus_platform0_rad + b.rotation_minus_platform_offset_rad / n);
        let angles = Angles::from_rotation(
            rotation,
            rotation_minus_platform,
            sin_cos(b.latitude_rad / n),
        );
        let q = QuantizedSample::new(
            b.roll_rad / n,
            b.pitch_rad / n,
            &angles,
            &References {
                channels: b.reference.map(|r| r / n),
                turn: b.turn_reference / n,
            },
            b.turn_rate / n,
        );
        let fill = FillCode::of(b.fill_weight);
        // The bin's weight: the mean of its samples' (lost samples count 0).
        let weight =
            round(n * FULL_WEIGHT as Real / self.bin as Real).clamp(0.0, FULL_WEIGHT as Real) as u8;
        let removed = self.push_entry(b.number, q, fill, weight);
        Pushed {
            completed: true,
            removed,
        }
    }
}
