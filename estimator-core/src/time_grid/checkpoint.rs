//! The sample grid part ([`TimeGrid`]): the interval as pinned or learned, and what it is learned
//! and refined from: interval (optional f64), pinned (flag), the previous accepted stamp, i.e.
//! the time of the last sample (optional f64), the learning steps ([`LEARNING_STEPS`] x f64),
//! steps learned (u32), mean one-interval step (f64), steps in that mean (u32), clock steps (u32).
//!
//! Checked: the interval positive and finite; pinned exactly when the configuration pins the
//! interval, and then equal to it; the stamp finite; every learning step and the refinement's sum
//! finite and not negative (they are positive time steps, or 0 before the first); at most
//! [`LEARNING_STEPS`] steps learned and fewer than [`REFINEMENT_STEPS`] in the refinement block
//! being collected (the grid's own bounds).

use super::{TimeGrid, LEARNING_STEPS, REFINEMENT_STEPS};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, CheckpointError, Part, Stored};
use crate::config::Config;

impl Stored for TimeGrid {
    const LEN: usize = 9 + 1 + 9 + LEARNING_STEPS * 8 + 4 + 8 + 4 + 4;
    type Context<'a> = &'a Config;

    fn write(&self, w: &mut Writer<'_>) {
        let g = self;
        w.option(g.interval_s, 0.0, |w, v| w.f64(v));
        w.flag(g.pinned);
        w.option(g.last_stamp_s, 0.0, |w, v| w.f64(v));
        for v in g.learning_steps {
            w.f64(v);
        }
        w.u32(g.learned);
        w.f64(g.step_sum_s);
        w.u32(g.steps);
        w.u32(g.clock_steps);
    }

    fn read(r: &mut Reader<'_>, config: &Config) -> Result<TimeGrid, CheckpointError> {
        let invalid = CheckpointError::InvalidValue(Part::TimeGrid);
        let g = TimeGrid {
            interval_s: r.option(Part::TimeGrid, |r| Ok(r.f64()))?,
            pinned: r.flag(Part::TimeGrid)?,
            last_stamp_s: r.option(Part::TimeGrid, |r| Ok(r.f64()))?,
            learning_steps: core::array::from_fn(|_| r.f64()),
            learned: r.u32(),
            step_sum_s: r.f64(),
            steps: r.u32(),
            clock_steps: r.u32(),
        };
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        ensure(
            g.interval_s.is_none_or(|v| v.is_finite() && v > 0.0),
            invalid,
        )?;
        ensure(g.last_stamp_s.is_none_or(f64::is_finite), invalid)?;
        ensure(
            g.learning_steps.iter().all(|v| non_negative(*v)) && non_negative(g.step_sum_s),
            invalid,
        )?;
        ensure(
            g.learned as usize <= LEARNING_STEPS && g.steps < REFINEMENT_STEPS,
            invalid,
        )?;
        let pinned_ok = match config.sample_interval_s {
            Some(pinned) => g.pinned && g.interval_s.map(f64::to_bits) == Some(pinned.to_bits()),
            None => !g.pinned,
        };
        ensure(pinned_ok, CheckpointError::Inconsistent(Part::TimeGrid))?;
        Ok(g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{running, written_and_read};
    use crate::config::Method;
    use CheckpointError::*;

    #[test]
    fn a_tampered_grid_is_refused_with_a_typed_error() {
        let est = running(Method::Windowed);
        let config = Config::with_method(Method::Windowed);
        let with = |edit: &dyn Fn(&mut TimeGrid)| {
            let mut g = est.grid_for_test();
            edit(&mut g);
            written_and_read(&g, &config)
        };
        assert_eq!(with(&|_| {}), Ok(est.grid_for_test()));
        assert_eq!(
            with(&|g| g.interval_s = Some(-1.0)),
            Err(InvalidValue(Part::TimeGrid))
        );
        assert_eq!(
            with(&|g| g.last_stamp_s = Some(f64::INFINITY)),
            Err(InvalidValue(Part::TimeGrid))
        );
        assert_eq!(
            with(&|g| g.learning_steps[3] = f64::NAN),
            Err(InvalidValue(Part::TimeGrid))
        );
        assert_eq!(with(&|g| g.learned = 9), Err(InvalidValue(Part::TimeGrid)));
        // Pinned, while the configuration learns the interval.
        assert_eq!(
            with(&|g| g.pinned = true),
            Err(Inconsistent(Part::TimeGrid))
        );
    }
}
