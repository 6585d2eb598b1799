//! The traditional baseline in a checkpoint image: updates (u32), then the Kalman filter (`x` 4
//! `R`, `P` 16 `R`). It has no window: a restart loses nothing of it.
//!
//! Checked: the Kalman filter (see [`crate::kalman`]).

use super::Traditional;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{CheckpointError, Stored};
use crate::kalman::ConstantStateKalman;
use crate::Real;

/// Read with the largest variance allowed (see [`crate::checkpoint::MAX_VARIANCE`]).
impl Stored for Traditional {
    const LEN: usize = 4 + ConstantStateKalman::<Real, 4>::LEN;
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        w.u32(self.updates);
        self.kf.write(w);
    }

    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Traditional, CheckpointError> {
        let updates = r.u32();
        let kf = ConstantStateKalman::read(r, max_variance)?;
        Ok(Traditional { kf, updates })
    }
}
