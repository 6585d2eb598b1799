//! The reference low-pass ([`ReferenceFilter`]) in a checkpoint image, within the windowed
//! method's part (the layout: the module doc of [`crate::checkpoint`]).
//!
//! Checked: the flag 0 or 1, every stage output within +-1 (low-passed sines and cosines), the
//! stages zero before it starts. Its errors name the windowed method's
//! [`Part::Residuals`], the part it belongs to.

use super::ReferenceFilter;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, CheckpointError, Part, R};
use crate::Real;

impl ReferenceFilter {
    /// Bytes of the filter in an image.
    pub(crate) const CHECKPOINT_LEN: usize = 1 + 12 * R;

    /// Writes the filter.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        w.flag(self.started);
        for stage in self.stages {
            for v in stage {
                w.real(v);
            }
        }
    }

    /// Reads and checks the filter.
    pub(crate) fn read_checkpoint(r: &mut Reader<'_>) -> Result<Self, CheckpointError> {
        let start = r.pos();
        let started = r.flag(Part::Residuals)?;
        let stages: [[Real; 4]; 3] = core::array::from_fn(|_| core::array::from_fn(|_| r.real()));
        if !started {
            r.zeros_since(start, Part::Residuals)?;
        }
        ensure(stages.iter().flatten().all(|c| within(*c, 1.0)), CheckpointError::InvalidValue(Part::Residuals))?;
        Ok(ReferenceFilter { stages, started })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn written_and_read(f: &ReferenceFilter) -> Result<ReferenceFilter, CheckpointError> {
        let mut buf = [0u8; ReferenceFilter::CHECKPOINT_LEN];
        f.write_checkpoint(&mut Writer::new(&mut buf, 0));
        ReferenceFilter::read_checkpoint(&mut Reader::new(&buf, 0))
    }

    #[test]
    fn a_tampered_reference_filter_is_refused_with_a_typed_error() {
        let started = ReferenceFilter { stages: [[0.5, -0.25, 1.0, -1.0]; 3], started: true };
        assert_eq!(written_and_read(&started), Ok(started));
        assert_eq!(written_and_read(&ReferenceFilter::default()), Ok(ReferenceFilter::default()));
        let mut beyond = started;
        beyond.stages[1][2] = 1.5;
        assert_eq!(written_and_read(&beyond), Err(CheckpointError::InvalidValue(Part::Residuals)));
        // Not started, but stages written.
        let stale = ReferenceFilter { started: false, ..started };
        assert_eq!(written_and_read(&stale), Err(CheckpointError::UnusedNotZero(Part::Residuals)));
    }
}
