//! The gap filler part ([`GapFiller`]): the delay line of received samples waiting for their
//! neighbours, and the fill-error estimate.
//!
//! Checked: a sample in slot `k` has an index `k` modulo [`SLOTS`] and lies within the
//! [`SLOTS`] indices up to the newest; the newest index's slot holds it; fewer than
//! [`NEIGHBOURS`] samples wait between the next index and the newest (so the delay line moves on
//! at the next sample); an empty delay line has every slot empty; a waiting sample is a received
//! one (fill weight 0) whose values pass [`crate::Sample::check`]'s ranges (roll and pitch
//! within 90 deg, angles within 360 deg, latitude below 90 deg) and whose sines and cosines lie
//! within +-1 (plus [`TRIG_MARGIN`]); the error estimates within `[0, ((L + 1) 90 deg)^2]` (L =
//! 3.06, the Lebesgue constant of the 10-point prediction of [`crate::gap_fill`]), at most
//! [`FILL_ERROR_SAMPLES`] samples averaged.

use super::{GapFiller, GridSample, FILL_ERROR_SAMPLES, NEIGHBOURS, SLOTS};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, within_non_negative, CheckpointError, Part, R};
use crate::installation::Angles;
use crate::sample::{MAX_TILT_RAD, MAX_WRAPPED_ANGLE_RAD};
use crate::Real;

/// Bytes of one grid sample.
const GRID_SAMPLE_LEN: usize = 4 + 11 * R + 2;

/// How far a stored sine or cosine may lie beyond +-1 (rounding of [`crate::math::sin_cos`]).
const TRIG_MARGIN: Real = 1.0 / 1024.0;

/// Largest roll or pitch of a filled sample, rad: the Lagrange fill of [`crate::gap_fill`] from
/// any set of present neighbours within 5 samples on each side (at least one on each side) has
/// weights whose absolute values sum to at most 30 (its Lebesgue constant, worst for the nodes
/// -5..-2 and 5), and every neighbour is within 90 deg; 32 times 90 deg bounds it with margin.
pub(crate) const MAX_FILLED_TILT_RAD: Real = 32.0 * MAX_TILT_RAD;

/// Largest mean square prediction error, rad^2: a prediction from 10 neighbours within 90 deg with
/// weights summing to 3.06 in absolute value, minus a sample within 90 deg: within 4.1 x 90 deg.
const MAX_FILL_ERROR_RAD2: Real = (4.1 * MAX_TILT_RAD) * (4.1 * MAX_TILT_RAD);

const ZERO_ANGLES: Angles = Angles { sin_rho: 0.0, cos_rho: 0.0, sin_rho_s: 0.0, cos_rho_s: 0.0, sin_lat: 0.0, cos_lat: 0.0 };
const ZERO_SAMPLE: GridSample = GridSample {
    index: 0,
    roll_rad: 0.0,
    pitch_rad: 0.0,
    rotation_rad: 0.0,
    rotation_minus_platform_rad: 0.0,
    latitude_rad: 0.0,
    angles: ZERO_ANGLES,
    fill_weight: 0,
};

fn write_sample(w: &mut Writer<'_>, s: GridSample) {
    w.u32(s.index);
    for v in [s.roll_rad, s.pitch_rad, s.rotation_rad, s.rotation_minus_platform_rad, s.latitude_rad] {
        w.real(v);
    }
    let a = &s.angles;
    for v in [a.sin_rho, a.cos_rho, a.sin_rho_s, a.cos_rho_s, a.sin_lat, a.cos_lat] {
        w.real(v);
    }
    w.u16(s.fill_weight);
}

fn read_sample(r: &mut Reader<'_>) -> GridSample {
    GridSample {
        index: r.u32(),
        roll_rad: r.real(),
        pitch_rad: r.real(),
        rotation_rad: r.real(),
        rotation_minus_platform_rad: r.real(),
        latitude_rad: r.real(),
        angles: Angles {
            sin_rho: r.real(),
            cos_rho: r.real(),
            sin_rho_s: r.real(),
            cos_rho_s: r.real(),
            sin_lat: r.real(),
            cos_lat: r.real(),
        },
        fill_weight: r.u16(),
    }
}

/// Whether a received sample's values are in range.
fn received_in_range(s: &GridSample) -> bool {
    let a = &s.angles;
    let trig = [a.sin_rho, a.cos_rho, a.sin_rho_s, a.cos_rho_s, a.sin_lat, a.cos_lat];
    s.fill_weight == 0
        && within(s.roll_rad, MAX_TILT_RAD)
        && within(s.pitch_rad, MAX_TILT_RAD)
        && within(s.rotation_rad, MAX_WRAPPED_ANGLE_RAD)
        && within(s.rotation_minus_platform_rad, MAX_WRAPPED_ANGLE_RAD)
        && within(s.latitude_rad, MAX_TILT_RAD)
        && s.latitude_rad.abs() < MAX_TILT_RAD
        && trig.iter().all(|v| within(*v, 1.0 + TRIG_MARGIN))
}

impl GapFiller {
    /// Bytes of the part.
    pub(crate) const CHECKPOINT_LEN: usize = 5 + 4 + 2 * R + 4 + SLOTS * (1 + GRID_SAMPLE_LEN);

    /// Writes the part.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        let f = self;
        w.option(f.newest, 0, |w, v| w.u32(v));
        w.u32(f.next);
        w.real(f.roll_error_rad2);
        w.real(f.pitch_error_rad2);
        w.u32(f.error_samples);
        for slot in &f.slots {
            w.option(*slot, ZERO_SAMPLE, write_sample);
        }
    }

    /// Reads and checks the part; with `dst`, also writes it there, slot by slot (no copy of the
    /// delay line on the stack).
    pub(crate) fn read_checkpoint(r: &mut Reader<'_>, mut dst: Option<&mut GapFiller>) -> Result<(), CheckpointError> {
        const P: Part = Part::DelayLine;
        let newest = r.option(P, |r| Ok(r.u32()))?;
        let next = r.u32();
        ensure(newest.is_none_or(|n| n.wrapping_sub(next) < NEIGHBOURS as u32), CheckpointError::Inconsistent(P))?;
        let roll_error_rad2 = r.real();
        let pitch_error_rad2 = r.real();
        let error_samples = r.u32();
        ensure(
            within_non_negative(roll_error_rad2, MAX_FILL_ERROR_RAD2)
                && within_non_negative(pitch_error_rad2, MAX_FILL_ERROR_RAD2)
                && error_samples <= FILL_ERROR_SAMPLES,
            CheckpointError::InvalidValue(Part::FillError),
        )?;
        let mut holds_newest = false;
        for k in 0..SLOTS {
            let slot = r.option(P, |r| Ok(read_sample(r)))?;
            if let Some(s) = &slot {
                ensure(received_in_range(s), CheckpointError::InvalidValue(P))?;
                // Slot `k` holds one of the last `SLOTS` indices up to the newest, the one that is
                // `k` modulo `SLOTS`.
                let placed = newest.is_some_and(|n| n.wrapping_sub(s.index) < SLOTS as u32);
                ensure(placed && s.index as usize % SLOTS == k, CheckpointError::Inconsistent(P))?;
                holds_newest |= newest == Some(s.index);
            }
            if let Some(f) = dst.as_deref_mut() {
                f.slots[k] = slot;
            }
        }
        ensure(newest.is_none() || holds_newest, CheckpointError::Inconsistent(P))?;
        if let Some(f) = dst {
            f.newest = newest;
            f.next = next;
            f.roll_error_rad2 = roll_error_rad2;
            f.pitch_error_rad2 = pitch_error_rad2;
            f.error_samples = error_samples;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{image_of, refused, running, tampered_part};
    use crate::checkpoint::GAP_FILL_OFFSET;
    use crate::config::Method;
    use CheckpointError::*;

    #[test]
    fn a_tampered_delay_line_is_refused_with_a_typed_error() {
        let est = running(Method::Windowed);
        assert!(est.counters().filled > 0);
        let image = image_of(&est);
        let read = |r: &mut Reader<'_>| {
            let mut f = GapFiller::default();
            GapFiller::read_checkpoint(r, Some(&mut f)).unwrap();
            f
        };
        let base = read(&mut Reader::new(&image, GAP_FILL_OFFSET));
        // What the tampering reaches: a fill-error estimate and a waiting sample.
        assert!(base.error_samples > 0);
        let newest = base.newest.unwrap();
        let k = newest as usize % SLOTS;
        let tampered =
            |edit: &dyn Fn(&mut GapFiller)| tampered_part(&image, GAP_FILL_OFFSET, read, edit, GapFiller::write_checkpoint);
        refused(&tampered(&|f| f.slots[k].as_mut().unwrap().index += 1), Inconsistent(P));
        refused(&tampered(&|f| f.slots[k] = None), Inconsistent(P));
        refused(&tampered(&|f| f.slots[k].as_mut().unwrap().roll_rad = Real::NAN), InvalidValue(P));
        refused(&tampered(&|f| f.slots[k].as_mut().unwrap().angles.cos_rho = 1.5), InvalidValue(P));
        refused(&tampered(&|f| f.slots[k].as_mut().unwrap().fill_weight = 1), InvalidValue(P));
        refused(&tampered(&|f| f.next = newest.wrapping_sub(5)), Inconsistent(P));
        refused(&tampered(&|f| f.newest = None), Inconsistent(P));
        refused(&tampered(&|f| f.roll_error_rad2 = -1e-9), InvalidValue(Part::FillError));
        refused(&tampered(&|f| f.error_samples = 257), InvalidValue(Part::FillError));
    }

    const P: Part = Part::DelayLine;
}
