//! The sway monitor ([`SwayMonitor`]) in a checkpoint image, within the estimator's own part:
//! mean, mean square (`R` each), samples (u32).
//!
//! Checked: the mean within 2 rad and the mean square within `[0, 4]` rad^2 (averages of roll
//! within 90 deg).

use super::SwayMonitor;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, within_non_negative, CheckpointError, Part, Stored, R};

impl Stored for SwayMonitor {
    const LEN: usize = 2 * R + 4;
    type Context<'a> = ();

    fn write(&self, w: &mut Writer<'_>) {
        w.real(self.mean_rad);
        w.real(self.mean_square_rad2);
        w.u32(self.samples);
    }

    fn read(r: &mut Reader<'_>, (): ()) -> Result<Self, CheckpointError> {
        let sway = SwayMonitor {
            mean_rad: r.real(),
            mean_square_rad2: r.real(),
            samples: r.u32(),
        };
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
    use crate::checkpoint::tests::written_and_read;
    use crate::Real;

    #[test]
    fn a_tampered_sway_monitor_is_refused_with_a_typed_error() {
        let mut m = SwayMonitor::default();
        for k in 0..100 {
            m.observe(0.03 * libm::sinf(k as f32 * 0.7) as Real);
        }
        assert_eq!(written_and_read(&m, ()), Ok(m));
        let refused = CheckpointError::InvalidValue(Part::SwayMonitor);
        assert_eq!(
            written_and_read(
                &SwayMonitor {
                    mean_square_rad2: Real::NAN,
                    ..m
                },
                ()
            ),
            Err(refused)
        );
        assert_eq!(
            written_and_read(
                &SwayMonitor {
                    mean_square_rad2: -1e-3,
                    ..m
                },
                ()
            ),
            Err(refused)
        );
        assert_eq!(
            written_and_read(&SwayMonitor { mean_rad: 2.5, ..m }, ()),
            Err(refused)
        );
    }
}
