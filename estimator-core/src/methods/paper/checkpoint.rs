//! The paper's method in a checkpoint image: what a restart keeps of it, not its window. In
//! order: updates (u32), samples integrated (u32), the start time (f64), the four integrals of
//! eq (8) (4 x i64), the four Kalman filters (`x` 3 f64, `P` 9 f64 each). The moving average of
//! eq (11) refills after a restart (eq 8's integrals go on).
//!
//! Checked: the start time finite; the integrals within the fixed-point range times the samples
//! integrated; the Kalman filters (see [`crate::kalman`]).

use super::Paper;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, CheckpointError, Part, Stored};
use crate::kalman::ConstantStateKalman;
use crate::moving_average::{WindowAverage, MAX_MAGNITUDE};

/// What a restart keeps of the paper's method (the fields of [`Paper`] of the same names).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Learned {
    updates: u32,
    samples: u32,
    start_time_s: f64,
    integrals: [i64; 4],
    kf: [ConstantStateKalman<f64, 3>; 4],
}

impl<const CAP: usize> Paper<CAP> {
    /// What a restart keeps.
    pub(crate) fn learned(&self) -> Learned {
        Learned {
            updates: self.updates,
            samples: self.samples,
            start_time_s: self.start_time_s,
            integrals: self.integrals,
            kf: self.kf.clone(),
        }
    }

    /// Takes over what a restart keeps (into a fresh state, at restore); the window stays empty.
    pub(crate) fn keep_learned(&mut self, l: Learned) {
        self.updates = l.updates;
        self.samples = l.samples;
        self.start_time_s = l.start_time_s;
        self.integrals = l.integrals;
        self.kf = l.kf;
    }
}

/// Read with the largest variance allowed (see [`crate::checkpoint::MAX_VARIANCE`]).
impl Stored for Learned {
    const LEN: usize = super::super::checkpoint::PAPER_LEN;
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        w.u32(self.updates);
        w.u32(self.samples);
        w.f64(self.start_time_s);
        for v in self.integrals {
            w.i64(v);
        }
        for kf in &self.kf {
            kf.write(w);
        }
    }

    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Learned, CheckpointError> {
        let updates = r.u32();
        let samples = r.u32();
        let start_time_s = r.f64();
        ensure(
            start_time_s.is_finite(),
            CheckpointError::InvalidValue(Part::PaperStartTime),
        )?;
        // The ring capacity does not matter to the quantization.
        let bound = i64::from(WindowAverage::<4, 1>::quantize(MAX_MAGNITUDE)) * i64::from(samples);
        let integrals: [i64; 4] = core::array::from_fn(|_| r.i64());
        ensure(
            integrals.iter().all(|v| (-bound..=bound).contains(v)),
            CheckpointError::InvalidValue(Part::PaperIntegrals),
        )?;
        let mut kf: [ConstantStateKalman<f64, 3>; 4] =
            core::array::from_fn(|_| ConstantStateKalman::new([0.0; 3]));
        for k in kf.iter_mut() {
            *k = ConstantStateKalman::read(r, max_variance)?;
        }
        Ok(Learned {
            updates,
            samples,
            start_time_s,
            integrals,
            kf,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{running, written_and_read};
    use crate::config::Method;
    use crate::methods::MethodState;
    use CheckpointError::*;

    #[test]
    fn a_tampered_paper_state_is_refused_with_a_typed_error() {
        let est = running(Method::Paper);
        let MethodState::Paper(m) = est.method_for_test() else {
            unreachable!()
        };
        let base = m.learned();
        let with = |edit: &dyn Fn(&mut Learned)| {
            let mut t = base.clone();
            edit(&mut t);
            written_and_read(&t, 1e12)
        };
        assert_eq!(with(&|_| {}), Ok(base.clone()));
        assert_eq!(
            with(&|m| m.start_time_s = f64::NAN),
            Err(InvalidValue(Part::PaperStartTime))
        );
        assert_eq!(
            with(&|m| m.integrals[1] = i64::MAX),
            Err(InvalidValue(Part::PaperIntegrals))
        );
        // Regression, fuzz target `checkpoint_restore`: the first filter's b2 state with its top
        // byte flipped (finite, ~1e300 in f64) was accepted, and the next update moved x1 beyond
        // f32 range. The Kalman filter's checks (see `kalman/checkpoint.rs`) refuse it.
        let kf = ConstantStateKalman::from_parts(
            [0.0, 0.0, 1e300],
            [[1e-6, 0.0, 0.0], [0.0, 1e-6, 0.0], [0.0, 0.0, 1e-6]],
        );
        assert_eq!(
            with(&|m| m.kf[0] = kf.clone()),
            Err(InvalidValue(Part::KalmanState))
        );
    }
}
