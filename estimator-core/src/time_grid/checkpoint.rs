//! The sample grid part ([`TimeGrid`]): the interval as pinned or learned, the grid's phase and
//! how it follows the clock, and the learning stamps: interval (optional f64), pinned (flag), the
//! previous accepted stamp (optional f64), the base time (f64), the grid's interval (f32), the
//! last slot's and the last stamp's offsets from the base (f32 each), the learning stamps
//! ([`LEARNING_STAMPS`] x f32), stamps learned (u32), stamps tracked (u32), the residuals' mean
//! square (f32), the pending off-grid residual (f32), clock steps (u32).
//!
//! Checked: every value finite; the interval positive; pinned exactly when the configuration pins
//! the interval, and then equal to it; at most [`LEARNING_STAMPS`] stamps learned, the first at 0
//! and the others increasing, those not yet learned 0. Once the grid is known: its interval
//! positive and within a factor of 2 of the reported one, at most [`TRACKING_MEMORY`] and at least
//! 1 stamp tracked, the mean square not negative and below an interval squared, the pending
//! residual within an interval, the last stamp within an interval of its slot and the slot at most
//! [`REBASE_INTERVALS`] + 1 intervals past the base (the grid's own bounds). Before: the grid's
//! own values all 0.

use super::{TimeGrid, LEARNING_STAMPS, REBASE_INTERVALS, TRACKING_MEMORY};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, CheckpointError, Part, Stored};
use crate::config::Config;

impl Stored for TimeGrid {
    const LEN: usize = 9 + 1 + 9 + 8 + 4 + 4 + 4 + LEARNING_STAMPS * 4 + 4 + 4 + 4 + 4 + 4;
    type Context<'a> = &'a Config;

    fn write(&self, w: &mut Writer<'_>) {
        let g = self;
        w.option(g.interval_s, 0.0, |w, v| w.f64(v));
        w.flag(g.pinned);
        w.option(g.last_stamp_s, 0.0, |w, v| w.f64(v));
        w.f64(g.base_s);
        w.float(g.interval32_s);
        w.float(g.lead32_s);
        w.float(g.last_rel32_s);
        for v in g.stamps_s {
            w.float(v);
        }
        w.u32(g.learned);
        w.u32(g.tracked);
        w.float(g.mean_square32_s2);
        w.float(g.pending32_s);
        w.u32(g.clock_steps);
    }

    fn read(r: &mut Reader<'_>, config: &Config) -> Result<TimeGrid, CheckpointError> {
        let g = TimeGrid {
            interval_s: r.option(Part::TimeGrid, |r| Ok(r.f64()))?,
            pinned: r.flag(Part::TimeGrid)?,
            last_stamp_s: r.option(Part::TimeGrid, |r| Ok(r.f64()))?,
            base_s: r.f64(),
            interval32_s: r.float(),
            lead32_s: r.float(),
            last_rel32_s: r.float(),
            stamps_s: core::array::from_fn(|_| r.float()),
            learned: r.u32(),
            tracked: r.u32(),
            mean_square32_s2: r.float(),
            pending32_s: r.float(),
            clock_steps: r.u32(),
        };
        ensure(in_range(&g), CheckpointError::InvalidValue(Part::TimeGrid))?;
        let pinned_ok = match config.sample_interval_s {
            Some(pinned) => g.pinned && g.interval_s.map(f64::to_bits) == Some(pinned.to_bits()),
            None => !g.pinned,
        };
        ensure(pinned_ok, CheckpointError::Inconsistent(Part::TimeGrid))?;
        Ok(g)
    }
}

/// The range checks of the module doc. Out of line: the reader's stack stays small.
#[inline(never)]
fn in_range(g: &TimeGrid) -> bool {
    let finite = g.base_s.is_finite()
        && g.interval_s.is_none_or(|v| v.is_finite() && v > 0.0)
        && g.last_stamp_s.is_none_or(f64::is_finite)
        && [
            g.interval32_s,
            g.lead32_s,
            g.last_rel32_s,
            g.mean_square32_s2,
            g.pending32_s,
        ]
        .iter()
        .chain(g.stamps_s.iter())
        .all(|v| v.is_finite());
    if !finite || g.learned as usize > LEARNING_STAMPS {
        return false;
    }
    let n = g.learned as usize;
    let learning_ok = g.stamps_s[0] == 0.0
        && g.stamps_s[..n.max(1)].windows(2).all(|w| w[1] > w[0])
        && g.stamps_s[n.max(1)..].iter().all(|v| *v == 0.0);
    if !learning_ok {
        return false;
    }
    if n < LEARNING_STAMPS {
        return g.interval32_s == 0.0
            && g.lead32_s == 0.0
            && g.last_rel32_s == 0.0
            && g.tracked == 0
            && g.mean_square32_s2 == 0.0
            && g.pending32_s == 0.0;
    }
    let Some(reported) = g.interval_s else {
        return false;
    };
    let t = g.interval32_s;
    let ratio = f64::from(t) / reported;
    t > 0.0
        && (0.5..=2.0).contains(&ratio)
        && (1..=TRACKING_MEMORY).contains(&g.tracked)
        && g.mean_square32_s2 >= 0.0
        && g.mean_square32_s2 < t * t
        && g.pending32_s.abs() <= t
        && (g.last_rel32_s - g.lead32_s).abs() <= t
        && g.lead32_s.abs() <= (REBASE_INTERVALS + 1.0) * t
        && g.last_stamp_s.is_some()
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
        let invalid = Err(InvalidValue(Part::TimeGrid));
        assert_eq!(with(&|g| g.interval_s = Some(-1.0)), invalid);
        assert_eq!(with(&|g| g.last_stamp_s = Some(f64::INFINITY)), invalid);
        assert_eq!(with(&|g| g.base_s = f64::NAN), invalid);
        assert_eq!(with(&|g| g.stamps_s[3] = f32::NAN), invalid);
        assert_eq!(with(&|g| g.stamps_s[3] = g.stamps_s[2]), invalid);
        assert_eq!(with(&|g| g.stamps_s[0] = 0.5), invalid);
        assert_eq!(with(&|g| g.learned = LEARNING_STAMPS as u32 + 1), invalid);
        assert_eq!(with(&|g| g.interval32_s = 0.0), invalid);
        assert_eq!(with(&|g| g.interval32_s *= 3.0), invalid);
        assert_eq!(with(&|g| g.tracked = 0), invalid);
        assert_eq!(with(&|g| g.tracked = TRACKING_MEMORY + 1), invalid);
        assert_eq!(with(&|g| g.mean_square32_s2 = -1e-6), invalid);
        assert_eq!(with(&|g| g.mean_square32_s2 = 4.0), invalid);
        assert_eq!(with(&|g| g.pending32_s = 1.5), invalid);
        assert_eq!(with(&|g| g.last_rel32_s = g.lead32_s + 1.5), invalid);
        assert_eq!(with(&|g| g.lead32_s = 5000.0), invalid);
        // Still learning, with values only a known grid has.
        assert_eq!(with(&|g| g.learned = 5), invalid);
        // Pinned, while the configuration learns the interval.
        assert_eq!(
            with(&|g| g.pinned = true),
            Err(Inconsistent(Part::TimeGrid))
        );
    }
}
