//! The sway monitor ([`SwayMonitor`]) in a checkpoint image, within the estimator's own part (the
//! layout: the module doc of [`crate::checkpoint`]).
//!
//! Checked: the mean within 2 rad and the mean square within `[0, 4]` rad^2 (averages of roll
//! within 90 deg).

use super::SwayMonitor;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, within_non_negative, CheckpointError, Part, R};
#[cfg(test)]
use crate::Real;

impl SwayMonitor {
    /// Bytes of the monitor in an image.
    pub(crate) const CHECKPOINT_LEN: usize = 2 * R + 4;

    /// Writes the monitor.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        w.real(self.mean_rad);
        w.real(self.mean_square_rad2);
        w.u32(self.samples);
    }

    /// Reads and checks the monitor.
    pub(crate) fn read_checkpoint(r: &mut Reader<'_>) -> Result<Self, CheckpointError> {
        let sway = SwayMonitor { mean_rad: r.real(), mean_square_rad2: r.real(), samples: r.u32() };
        ensure(
            within(sway.mean_rad, 2.0) && within_non_negative(sway.mean_square_rad2, 4.0),
            CheckpointError::InvalidValue(Part::SwayMonitor),
        )?;
        Ok(sway)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn written_and_read(m: &SwayMonitor) -> Result<SwayMonitor, CheckpointError> {
        let mut buf = [0u8; SwayMonitor::CHECKPOINT_LEN];
        m.write_checkpoint(&mut Writer::new(&mut buf, 0));
        SwayMonitor::read_checkpoint(&mut Reader::new(&buf, 0))
    }

    #[test]
    fn a_tampered_sway_monitor_is_refused_with_a_typed_error() {
        let mut m = SwayMonitor::default();
        for k in 0..100 {
            m.observe(0.03 * libm::sinf(k as f32 * 0.7) as Real);
        }
        assert_eq!(written_and_read(&m), Ok(m));
        let refused = CheckpointError::InvalidValue(Part::SwayMonitor);
        assert_eq!(written_and_read(&SwayMonitor { mean_square_rad2: Real::NAN, ..m }), Err(refused));
        assert_eq!(written_and_read(&SwayMonitor { mean_square_rad2: -1e-3, ..m }), Err(refused));
        assert_eq!(written_and_read(&SwayMonitor { mean_rad: 2.5, ..m }), Err(refused));
    }
}
