//! The gap filler part ([`GapFiller`]): the fill-error estimate (the delay line is not kept).
//!
//! Checked: the error estimates within `[0, ((L + 1) 90 deg)^2]` (L = 3.06, the Lebesgue constant
//! of the 10-point prediction of [`crate::gap_fill`]), at most [`FILL_ERROR_SAMPLES`] samples
//! averaged.

use super::{GapFiller, FILL_ERROR_SAMPLES};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within_non_negative, CheckpointError, Part, R};
use crate::sample::MAX_TILT_RAD;
use crate::Real;

/// Largest roll or pitch of a filled sample, rad: the Lagrange fill of [`crate::gap_fill`] from
/// any set of present neighbours within 5 samples on each side (at least one on each side) has
/// weights whose absolute values sum to at most 30 (its Lebesgue constant, worst for the nodes
/// -5..-2 and 5), and every neighbour is within 90 deg; 32 times 90 deg bounds it with margin.
pub(crate) const MAX_FILLED_TILT_RAD: Real = 32.0 * MAX_TILT_RAD;

/// Largest mean square prediction error, rad^2: a prediction from 10 neighbours within 90 deg with
/// weights summing to 3.06 in absolute value, minus a sample within 90 deg: within 4.1 x 90 deg.
const MAX_FILL_ERROR_RAD2: Real = (4.1 * MAX_TILT_RAD) * (4.1 * MAX_TILT_RAD);

impl GapFiller {
    /// Bytes of the part.
    pub(crate) const CHECKPOINT_LEN: usize = 5 + 4 + 2 * R + 4;

    /// Writes the part: the fill-error estimate (the delay line is not kept: after a restore the
    /// filler starts with the next sample).
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        let f = self;
        w.option(f.newest, 0, |w, v| w.u32(v));
        w.u32(f.next);
        w.real(f.roll_error_rad2);
        w.real(f.pitch_error_rad2);
        w.u32(f.error_samples);
    }

    /// Reads and checks the part; with `dst`, also writes it there.
    pub(crate) fn read_checkpoint(r: &mut Reader<'_>, dst: Option<&mut GapFiller>) -> Result<(), CheckpointError> {
        const P: Part = Part::DelayLine;
        let _newest = r.option(P, |r| Ok(r.u32()))?;
        let _next = r.u32();
        let roll_error_rad2 = r.real();
        let pitch_error_rad2 = r.real();
        let error_samples = r.u32();
        ensure(
            within_non_negative(roll_error_rad2, MAX_FILL_ERROR_RAD2)
                && within_non_negative(pitch_error_rad2, MAX_FILL_ERROR_RAD2)
                && error_samples <= FILL_ERROR_SAMPLES,
            CheckpointError::InvalidValue(Part::FillError),
        )?;
        if let Some(f) = dst {
            f.clear();
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
        let tampered =
            |edit: &dyn Fn(&mut GapFiller)| tampered_part(&image, GAP_FILL_OFFSET, read, edit, GapFiller::write_checkpoint);
        refused(&tampered(&|f| f.roll_error_rad2 = -1e-9), InvalidValue(Part::FillError));
        refused(&tampered(&|f| f.error_samples = 257), InvalidValue(Part::FillError));
    }

}
