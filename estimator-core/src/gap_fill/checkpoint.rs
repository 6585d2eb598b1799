//! The gap filler in a checkpoint image: only its fill-error estimate, the mean square
//! prediction error of roll and of pitch (`R` each) and the samples averaged (u32). The delay
//! line is not kept: after a restart it fills with the next samples, as after any long gap.
//!
//! Checked: the error estimates within `[0, ((L + 1) 90 deg)^2]` (L = 3.06, the Lebesgue constant
//! of the 10-point prediction of [`crate::gap_fill`]), at most [`FILL_ERROR_SAMPLES`] samples
//! averaged.

use super::{GapFiller, FILL_ERROR_SAMPLES};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within_non_negative, CheckpointError, Part, Stored, R};
use crate::sample::MAX_TILT_RAD;
use crate::Real;

/// Largest mean square prediction error, rad^2: a prediction from 10 neighbours within 90 deg with
/// weights summing to 3.06 in absolute value, minus a sample within 90 deg: within 4.1 x 90 deg.
const MAX_FILL_ERROR_RAD2: Real = (4.1 * MAX_TILT_RAD) * (4.1 * MAX_TILT_RAD);

/// What a restart keeps of the gap filler: its measured fill error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FillError {
    roll_rad2: Real,
    pitch_rad2: Real,
    samples: u32,
}

impl GapFiller {
    /// The fill-error estimate.
    pub(crate) fn fill_error(&self) -> FillError {
        FillError {
            roll_rad2: self.roll_error_rad2,
            pitch_rad2: self.pitch_error_rad2,
            samples: self.error_samples,
        }
    }

    /// Takes over a fill-error estimate (into an empty filler, at restore).
    pub(crate) fn keep_fill_error(&mut self, e: FillError) {
        self.roll_error_rad2 = e.roll_rad2;
        self.pitch_error_rad2 = e.pitch_rad2;
        self.error_samples = e.samples;
    }
}

impl Stored for FillError {
    const LEN: usize = 2 * R + 4;
    type Context<'a> = ();

    fn write(&self, w: &mut Writer<'_>) {
        w.real(self.roll_rad2);
        w.real(self.pitch_rad2);
        w.u32(self.samples);
    }

    fn read(r: &mut Reader<'_>, (): ()) -> Result<FillError, CheckpointError> {
        let e = FillError {
            roll_rad2: r.real(),
            pitch_rad2: r.real(),
            samples: r.u32(),
        };
        ensure(
            within_non_negative(e.roll_rad2, MAX_FILL_ERROR_RAD2)
                && within_non_negative(e.pitch_rad2, MAX_FILL_ERROR_RAD2)
                && e.samples <= FILL_ERROR_SAMPLES,
            CheckpointError::InvalidValue(Part::FillError),
        )?;
        Ok(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{running, written_and_read};
    use crate::config::Method;

    #[test]
    fn a_tampered_fill_error_is_refused_with_a_typed_error() {
        let est = running(Method::Windowed);
        let e = est.filler_for_test().fill_error();
        // What the tampering reaches: a measured fill error.
        assert!(e.samples > 0 && e.roll_rad2 > 0.0);
        assert_eq!(written_and_read(&e, ()), Ok(e));
        let refused = Err(CheckpointError::InvalidValue(Part::FillError));
        assert_eq!(
            written_and_read(
                &FillError {
                    roll_rad2: -1e-9,
                    ..e
                },
                ()
            ),
            refused
        );
        assert_eq!(
            written_and_read(
                &FillError {
                    pitch_rad2: Real::NAN,
                    ..e
                },
                ()
            ),
            refused
        );
        assert_eq!(
            written_and_read(
                &FillError {
                    samples: FILL_ERROR_SAMPLES + 1,
                    ..e
                },
                ()
            ),
            refused
        );
    }
}
