//! The traditional baseline's state in a checkpoint image (its layout: the module doc of
//! [`crate::checkpoint`]).
//!
//! Checked: the Kalman filter (see [`crate::kalman`]).

use super::Traditional;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::CheckpointError;
use crate::kalman::ConstantStateKalman;
use crate::Real;

impl Traditional {
    /// Bytes of the state.
    pub(crate) const CHECKPOINT_LEN: usize = 4 + ConstantStateKalman::<Real, 4>::CHECKPOINT_LEN;

    /// Writes the state.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        w.u32(self.updates);
        self.kf.write_checkpoint(w);
    }

    /// Reads and checks the state with variances up to `max_variance`. With `dst`, also writes
    /// it there.
    pub(crate) fn read_checkpoint(r: &mut Reader<'_>, dst: Option<&mut Self>, max_variance: f64) -> Result<(), CheckpointError> {
        let updates = r.u32();
        let kf = ConstantStateKalman::read_checkpoint(r, max_variance)?;
        if let Some(m) = dst {
            m.updates = updates;
            m.kf = kf;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::checkpoint::tests::{image_of, refused, reseal, running};
    use crate::checkpoint::{CheckpointError, Part, METHOD_OFFSET, R};
    use crate::config::Method;
    use crate::Real;

    #[test]
    fn a_tampered_traditional_state_is_refused() {
        // x2 of the filter, after the update count, set to infinity.
        let mut b = image_of(&running(Method::Traditional));
        let x2 = METHOD_OFFSET + 4 + R;
        b[x2..x2 + R].copy_from_slice(&Real::INFINITY.to_le_bytes());
        reseal(&mut b);
        refused(&b, CheckpointError::InvalidValue(Part::KalmanState));
    }
}
