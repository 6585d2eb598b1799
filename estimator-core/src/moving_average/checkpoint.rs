//! The moving-average windows: the windowed method's [`CorrelationWindow`] and the paper
//! method's [`WindowAverage`].
//!
//! Their layout, and where a window's entries sit in its ring slots: the module doc of
//! [`crate::checkpoint`].
//!
//! Checked: the length between 1 and `CAP` and, once the period is known, equal to what it gives
//! ([`WindowLayout::for_period`] for the correlation window, the period up to `CAP` for the plain
//! one); the fill count at most the length; the head equal to the fill count while the window
//! fills, below the length once it is full; every stored value, in the window or not, within the
//! fixed-point range; the running sums equal to the exact sums of the entries in the window. For
//! the bin being filled: fewer samples than a bin, all zero when empty, and each sum within its
//! samples' ranges.

use super::{Bin, CorrelationWindow, Entry, WindowLayout};
#[cfg(feature = "paper-method")]
use super::{WindowAverage, MAX_MAGNITUDE};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, CheckpointError, Part, R};
use crate::correlation::{CorrelationSums, QuantizedSample, FULL_WEIGHT, SUMS};
use crate::gap_fill::checkpoint::MAX_FILLED_TILT_RAD;
use crate::installation::Angles;
use crate::rotation_pattern::checkpoint::MAX_PERIOD_SAMPLES;
use crate::sample::{MAX_TILT_RAD, MAX_WRAPPED_ANGLE_RAD};
use crate::Real;

/// Bytes of one ring entry of a correlation window.
const ENTRY_LEN: usize = 2 * 4 + 10 * 2 + 2;
/// Bytes of the bin being filled.
const BIN_LEN: usize = 4 + 11 * R + 4;

/// Bytes of a correlation window of `cap` entries.
pub(crate) const fn correlation_window_len(cap: usize) -> usize {
    4 * 4 + (4 + SUMS * 8 + 4) + BIN_LEN + cap * ENTRY_LEN
}

/// Bytes of a plain window of `ch` channels and `cap` entries.
pub(crate) const fn window_average_len(ch: usize, cap: usize) -> usize {
    3 * 4 + ch * 8 + cap * ch * 4
}

/// The head of a window of `filled` of `len` entries stored from slot 0 (the layout in [`crate::checkpoint`]).
fn head_from_slot_0(filled: usize, len: usize) -> usize {
    if filled < len {
        filled
    } else {
        0
    }
}

/// The slot of the `i`-th oldest entry of a window stored with `head` (the layout in [`crate::checkpoint`]).
fn slot_of(i: usize, head: usize, filled: usize, len: usize) -> usize {
    if filled < len {
        i
    } else {
        (head + i) % len
    }
}

/// Whether the length, head and fill count of a window of `CAP` entries agree.
fn indices_ok(len: usize, head: usize, filled: usize, cap: usize) -> bool {
    (1..=cap).contains(&len) && filled <= len && if filled < len { head == filled } else { head < len }
}

/// The largest fixed-point counts of an attitude and of a sine or cosine.
fn quantized_bounds() -> (i32, i16) {
    let ones = Angles { sin_rho: 2.0, cos_rho: 2.0, sin_rho_s: 2.0, cos_rho_s: 2.0, sin_lat: 2.0, cos_lat: 2.0 };
    let q = QuantizedSample::new(Real::MAX, Real::MAX, &ones, &[2.0; 4]);
    (q.roll, q.sin_rho)
}

impl<const CAP: usize> CorrelationWindow<CAP> {
    /// Writes the window.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        let win = self;
        let filled = win.ring.len();
        w.usize(win.len);
        w.usize(head_from_slot_0(filled, win.len));
        w.usize(filled);
        w.u32(win.bin);
        w.u32(win.sums.count);
        for s in win.sums.sums {
            w.i64(s);
        }
        w.u32(win.sums.fill_weight);
        let b = &win.partial;
        w.u32(b.count);
        for v in [
            b.roll_rad,
            b.pitch_rad,
            b.latitude_rad,
            b.rotation0_rad,
            b.rotation_offset_rad,
            b.rotation_minus_platform0_rad,
            b.rotation_minus_platform_offset_rad,
            b.reference[0],
            b.reference[1],
            b.reference[2],
            b.reference[3],
        ] {
            w.real(v);
        }
        w.u32(b.fill_weight);
        let spare = core::iter::repeat_n(Entry::default(), CAP - filled);
        for entry in win.ring.iter().copied().chain(spare) {
            let (q, weight) = (entry.sample, entry.fill_weight);
            w.i32(q.roll);
            w.i32(q.pitch);
            for v in [q.sin_rho, q.cos_rho, q.sin_rho_s, q.cos_rho_s, q.sin_lat, q.cos_lat] {
                w.i16(v);
            }
            for v in q.reference {
                w.i16(v);
            }
            w.u16(weight);
        }
    }

    /// Reads and checks a correlation window; `expected`: `(bin, len)` the known period gives. With
    /// `dst`, also writes it there, entry by entry.
    pub(crate) fn read_checkpoint(
        r: &mut Reader<'_>,
        mut dst: Option<&mut Self>,
        expected: Option<(u32, usize)>,
    ) -> Result<(), CheckpointError> {
        let len = r.u32() as usize;
        let head = r.u32() as usize;
        let filled = r.u32() as usize;
        let bin = r.u32();
        let consistent = indices_ok(len, head, filled, CAP)
            && (1..=MAX_PERIOD_SAMPLES).contains(&bin)
            && expected.is_none_or(|e| e == (bin, len));
        ensure(consistent, CheckpointError::Inconsistent(Part::WindowIndices))?;
        let mut sums = CorrelationSums { count: r.u32(), sums: [0; SUMS], fill_weight: 0, weight: 0 };
        for s in sums.sums.iter_mut() {
            *s = r.i64();
        }
        sums.fill_weight = r.u32();
        sums.weight = sums.count * u32::from(FULL_WEIGHT);
        let partial = read_bin(r, bin)?;

        let (max_attitude, max_trig) = quantized_bounds();
        let ring_start = r.pos();
        for _ in 0..CAP {
            let q = read_entry(r).sample;
            let [c0, c1, c2, c3] = q.reference;
            let trig = [q.sin_rho, q.cos_rho, q.sin_rho_s, q.cos_rho_s, q.sin_lat, q.cos_lat, c0, c1, c2, c3];
            let in_range = q.roll.unsigned_abs() <= max_attitude.unsigned_abs()
                && q.pitch.unsigned_abs() <= max_attitude.unsigned_abs()
                && trig.iter().all(|v| v.unsigned_abs() <= max_trig.unsigned_abs());
            ensure(in_range, CheckpointError::InvalidValue(Part::WindowEntries))?;
        }
        let ring_end = r.pos();
        // The entries in the window, oldest first, straight from the image (no `CAP`-sized copy on
        // the stack).
        let mut direct = CorrelationSums::default();
        if let Some(win) = dst.as_deref_mut() {
            win.ring.clear();
        }
        for i in 0..filled {
            r.seek(ring_start + slot_of(i, head, filled, len) * ENTRY_LEN);
            let entry = read_entry(r);
            direct.add(&{ entry.sample }, entry.fill_weight, entry.weight);
            if let Some(win) = dst.as_deref_mut() {
                // At most `len <= CAP` entries: there is room.
                let _ = win.ring.push_back(entry);
            }
        }
        r.seek(ring_end);
        ensure(direct == sums, CheckpointError::Inconsistent(Part::WindowSums))?;
        if let Some(win) = dst {
            win.len = len;
            win.bin = bin;
            win.sums = sums;
            win.partial = partial;
        }
        Ok(())
    }
}

/// One ring slot of a correlation window.
fn read_entry(r: &mut Reader<'_>) -> Entry {
    let sample = QuantizedSample {
        roll: r.i32(),
        pitch: r.i32(),
        sin_rho: r.i16(),
        cos_rho: r.i16(),
        sin_rho_s: r.i16(),
        cos_rho_s: r.i16(),
        sin_lat: r.i16(),
        cos_lat: r.i16(),
        reference: [r.i16(), r.i16(), r.i16(), r.i16()],
    };
    Entry { sample, fill_weight: r.u16(), number: 0, weight: FULL_WEIGHT }
}

/// Reads and checks the bin being filled of a window of `bin` samples per entry.
fn read_bin(r: &mut Reader<'_>, bin: u32) -> Result<Bin, CheckpointError> {
    let start = r.pos();
    let b = Bin {
        number: 0,
        weight: 0.0,
        count: r.u32(),
        roll_rad: r.real(),
        pitch_rad: r.real(),
        latitude_rad: r.real(),
        rotation0_rad: r.real(),
        rotation_offset_rad: r.real(),
        rotation_minus_platform0_rad: r.real(),
        rotation_minus_platform_offset_rad: r.real(),
        reference: [r.real(), r.real(), r.real(), r.real()],
        fill_weight: r.u32(),
    };
    ensure(b.count < bin, CheckpointError::Inconsistent(Part::Bin))?;
    if b.count == 0 {
        r.zeros_since(start, Part::Bin)?;
        return Ok(b);
    }
    // Sums of `count` samples, each within its range; one more sample's worth covers rounding.
    let n = (b.count + 1) as Real;
    let max_weight = u32::from(u16::MAX);
    let in_range = within(b.roll_rad, n * MAX_FILLED_TILT_RAD)
        && within(b.pitch_rad, n * MAX_FILLED_TILT_RAD)
        && within(b.latitude_rad, n * MAX_TILT_RAD)
        && within(b.rotation0_rad, MAX_WRAPPED_ANGLE_RAD)
        && within(b.rotation_offset_rad, n * MAX_WRAPPED_ANGLE_RAD)
        && within(b.rotation_minus_platform0_rad, MAX_WRAPPED_ANGLE_RAD)
        && within(b.rotation_minus_platform_offset_rad, n * MAX_WRAPPED_ANGLE_RAD)
        && b.reference.iter().all(|c| within(*c, n))
        && u64::from(b.fill_weight) <= u64::from(b.count) * u64::from(max_weight);
    ensure(in_range, CheckpointError::InvalidValue(Part::Bin))?;
    Ok(b)
}

#[cfg(feature = "paper-method")]
impl<const CH: usize, const CAP: usize> WindowAverage<CH, CAP> {
    /// Writes the window.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        let win = self;
        let filled = win.ring.len();
        w.usize(win.len);
        w.usize(head_from_slot_0(filled, win.len));
        w.usize(filled);
        for s in win.sums {
            w.i64(s);
        }
        let spare = core::iter::repeat_n([0; CH], CAP - filled);
        for slot in win.ring.iter().copied().chain(spare) {
            for v in slot {
                w.i32(v);
            }
        }
    }

    /// Reads and checks a plain window; `expected_len`: the length the known period gives. With `dst`,
    /// also writes it there.
    pub(crate) fn read_checkpoint(
        r: &mut Reader<'_>,
        mut dst: Option<&mut Self>,
        expected_len: Option<usize>,
    ) -> Result<(), CheckpointError> {
        let len = r.u32() as usize;
        let head = r.u32() as usize;
        let filled = r.u32() as usize;
        let consistent = indices_ok(len, head, filled, CAP) && expected_len.is_none_or(|e| e == len);
        ensure(consistent, CheckpointError::Inconsistent(Part::WindowIndices))?;
        let mut sums = [0i64; CH];
        for s in sums.iter_mut() {
            *s = r.i64();
        }
        let bound = WindowAverage::<CH, CAP>::quantize(MAX_MAGNITUDE);
        let ring_start = r.pos();
        for _ in 0..CAP * CH {
            let v = r.i32();
            ensure((-bound..=bound).contains(&v), CheckpointError::InvalidValue(Part::WindowEntries))?;
        }
        let ring_end = r.pos();
        let mut direct = [0i64; CH];
        if let Some(win) = dst.as_deref_mut() {
            win.ring.clear();
        }
        for i in 0..filled {
            r.seek(ring_start + slot_of(i, head, filled, len) * CH * 4);
            let slot: [i32; CH] = core::array::from_fn(|_| r.i32());
            for ch in 0..CH {
                direct[ch] += i64::from(slot[ch]);
            }
            if let Some(win) = dst.as_deref_mut() {
                // At most `len <= CAP` samples: there is room.
                let _ = win.ring.push_back(slot);
            }
        }
        r.seek(ring_end);
        ensure(direct == sums, CheckpointError::Inconsistent(Part::WindowSums))?;
        if let Some(win) = dst {
            win.sums = sums;
            win.len = len;
        }
        Ok(())
    }
}

/// `(bin, len)` of a correlation window for a known period.
pub(crate) fn expected_correlation<const CAP: usize>(period_samples: Option<u32>) -> Option<(u32, usize)> {
    period_samples.map(|p| {
        let layout = WindowLayout::for_period(p, CAP);
        (layout.samples_per_entry, layout.entries.clamp(1, CAP.max(1)))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{image_of, put_u32, refused, reseal, running, tampered_part, Est};
    use crate::checkpoint::METHOD_OFFSET;
    use crate::config::Method;
    use std::vec::Vec;
    use CheckpointError::*;

    /// Offset of the correlation window in a windowed estimator's image: the last thing written.
    const WINDOW_OFFSET: usize =
        METHOD_OFFSET + crate::methods::windowed::checkpoint::checkpoint_len(64) - correlation_window_len(64);
    /// From a correlation window's start to its first ring slot: indices, sums, the bin being filled.
    const RING_OFFSET: usize = 4 * 4 + (4 + SUMS * 8 + 4) + BIN_LEN;

    fn read_window(r: &mut Reader<'_>) -> CorrelationWindow<64> {
        let mut win = CorrelationWindow::new();
        CorrelationWindow::read_checkpoint(r, Some(&mut win), None).unwrap();
        win
    }

    #[test]
    fn a_tampered_correlation_window_is_refused_with_a_typed_error() {
        let base = running(Method::Windowed);
        let image = image_of(&base);
        // What the tampering reaches: bins of 2 samples over the 120 s period, a full window of
        // 60 entries in a ring of 64.
        let win = read_window(&mut Reader::new(&image, WINDOW_OFFSET));
        assert_eq!((win.bin, win.len, win.ring.len()), (2, 60, 60));
        let tampered = |edit: &dyn Fn(&mut CorrelationWindow<64>)| {
            tampered_part(&image, WINDOW_OFFSET, read_window, edit, CorrelationWindow::write_checkpoint)
        };
        refused(&tampered(&|w| w.sums.sums[3] += 1), Inconsistent(Part::WindowSums));
        refused(&tampered(&|w| w.sums.count += 1), Inconsistent(Part::WindowSums));
        refused(&tampered(&|w| w.sums.fill_weight += 1), Inconsistent(Part::WindowSums));
        let heavier = |w: &mut CorrelationWindow<64>| {
            if let Some(e) = w.ring.iter_mut().nth(7) {
                e.fill_weight += 1;
            }
        };
        refused(&tampered(&heavier), Inconsistent(Part::WindowSums));
        refused(&tampered(&|w| w.len -= 1), Inconsistent(Part::WindowIndices));
        refused(&tampered(&|w| w.bin = 3), Inconsistent(Part::WindowIndices));
        // An entry out of the fixed-point range, with sums that agree with it.
        let out_of_range = |w: &mut CorrelationWindow<64>| {
            let Some(e) = w.ring.iter_mut().nth(5) else { return };
            let mut q = e.sample;
            w.sums.subtract(&q, 0, FULL_WEIGHT);
            q.roll = i32::MAX;
            w.sums.add(&q, 0, FULL_WEIGHT);
            e.sample = q;
        };
        refused(&tampered(&out_of_range), InvalidValue(Part::WindowEntries));

        // The bin being filled.
        refused(&tampered(&|w| w.partial.count = 2), Inconsistent(Part::Bin));
        let empty_but_not_zero = |w: &mut CorrelationWindow<64>| {
            w.partial = Default::default();
            w.partial.roll_rad = 1e-3;
        };
        refused(&tampered(&empty_but_not_zero), UnusedNotZero(Part::Bin));
        let nan = |w: &mut CorrelationWindow<64>| {
            w.partial.count = 1;
            w.partial.pitch_rad = Real::NAN;
        };
        refused(&tampered(&nan), InvalidValue(Part::Bin));
        let too_heavy = |w: &mut CorrelationWindow<64>| {
            w.partial.count = 1;
            w.partial.fill_weight = 70_000;
        };
        refused(&tampered(&too_heavy), InvalidValue(Part::Bin));
    }

    #[test]
    fn the_ring_is_read_from_any_head_and_spare_slots_are_ignored_within_range() {
        let base = running(Method::Windowed);
        let image = image_of(&base);
        let at = WINDOW_OFFSET;
        // The window of 60 entries is full, written from slot 0 (head 0), in a ring of 64.
        assert_eq!(image[at..at + 16], [60u32, 0, 60, 2].map(u32::to_le_bytes).concat()[..]);
        let entry = |k: usize| at + RING_OFFSET + k * ENTRY_LEN;
        let tampered = |f: &dyn Fn(&mut Vec<u8>)| {
            let mut b = image.clone();
            f(&mut b);
            reseal(&mut b);
            b
        };
        // A full window's head must lie within it; a filling window's head is its fill count.
        refused(&tampered(&|b| put_u32(b, at + 4, 60)), Inconsistent(Part::WindowIndices));
        let filling = |b: &mut Vec<u8>| {
            put_u32(b, at + 4, 11);
            put_u32(b, at + 8, 10);
        };
        refused(&tampered(&filling), Inconsistent(Part::WindowIndices));
        // A spare slot out of range is refused; one in range (a stale entry, as an older writer
        // left them) is ignored.
        let spare_out_of_range = |b: &mut Vec<u8>| b[entry(63) + 16..entry(63) + 18].copy_from_slice(&16_385i16.to_le_bytes());
        refused(&tampered(&spare_out_of_range), InvalidValue(Part::WindowEntries));
        assert_eq!(Est::from_checkpoint(&tampered(&|b| put_u32(b, entry(63), 12345))).as_ref(), Ok(&base));
        // A ring stored rotated (oldest entry in slot 17, as an older writer left it) is the same window.
        let rotated = tampered(&|b| {
            let ring: Vec<u8> = b[entry(0)..entry(60)].to_vec();
            for k in 0..60 {
                let from = (k + 60 - 17) % 60;
                b[entry(k)..entry(k + 1)].copy_from_slice(&ring[from * ENTRY_LEN..(from + 1) * ENTRY_LEN]);
            }
            put_u32(b, at + 4, 17);
        });
        assert_eq!(Est::from_checkpoint(&rotated).as_ref(), Ok(&base));
    }

    #[cfg(feature = "paper-method")]
    #[test]
    fn a_tampered_plain_window_is_refused_with_a_typed_error() {
        const AVERAGE_OFFSET: usize =
            METHOD_OFFSET + crate::methods::checkpoint::paper_len(64) - window_average_len(4, 64);
        let image = image_of(&running(Method::Paper));
        let read = |r: &mut Reader<'_>| {
            let mut win = WindowAverage::<4, 64>::new(1);
            WindowAverage::read_checkpoint(r, Some(&mut win), None).unwrap();
            win
        };
        assert_eq!(read(&mut Reader::new(&image, AVERAGE_OFFSET)).len, 120.min(64));
        let tampered = |edit: &dyn Fn(&mut WindowAverage<4, 64>)| {
            tampered_part(&image, AVERAGE_OFFSET, read, edit, WindowAverage::write_checkpoint)
        };
        refused(&tampered(&|w| w.sums[0] += 1), Inconsistent(Part::WindowSums));
        refused(&tampered(&|w| w.len = 60), Inconsistent(Part::WindowIndices));
    }
}
