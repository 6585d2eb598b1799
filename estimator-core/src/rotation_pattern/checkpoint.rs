//! The rotation monitor part ([`RotationMonitor`]): the period, the learned features and
//! everything the monitor times passes and learns a cycle with: period (optional u32, samples),
//! pinned (flag), features (optional: direction i8, reverses flag, longest dwell u32), reference
//! angles (optional `R`), side of each reference angle ([`LEVELS`] x i8), last pass of each
//! reference angle and direction ([`LEVELS`] x 2 optional u32), the timing pass (optional:
//! reference angle u8, direction u8), previous sample (optional: index u32, rotation angle `R`),
//! short mean increment `R`, its steps u32, the cycle being learned (start: optional u32, net
//! rotation `R`), dwell run u32, longest dwell u32, first direction i8, reversed flag, reversed
//! run u32. A restored monitor forgets its sample history ([`RotationMonitor::restart`], as after
//! any long gap): what it learned stays.
//!
//! Checked: a period between 2 and [`MAX_PERIOD_SAMPLES`] samples; pinned only with a period the
//! configuration pins; directions and sides -1, 0 or 1; the timing pass naming one of the
//! [`LEVELS`] reference angles and one of two directions; the angles within the range
//! [`crate::Sample::check`] allows (360 deg), the mean increment too (a mean of wrapped
//! increments), the net rotation of the cycle being learned within `4 MAX_PERIOD_SAMPLES` rad (at
//! most pi per sample over one period); at most [`SHORT_STEPS`] steps in the short mean.

use super::{Features, RotationMonitor, LEVELS, SHORT_STEPS};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, within, CheckpointError, Part, Stored, R};
use crate::config::Config;
use crate::sample::MAX_WRAPPED_ANGLE_RAD;
use crate::Real;

/// Longest period accepted, samples: 2^24, above any period of the allowed range (at most 3600 s)
/// at any sample rate a RINS logs at (4.6 kHz), and small enough that no count derived from it
/// overflows.
pub(crate) const MAX_PERIOD_SAMPLES: u32 = 1 << 24;

impl Stored for RotationMonitor {
    const LEN: usize = 5
        + 1
        + 7
        + (1 + R)
        + LEVELS
        + LEVELS * 2 * 5
        + 3
        + (5 + R)
        + R
        + 4
        + 5
        + R
        + 4
        + 4
        + 1
        + 1
        + 4;
    type Context<'a> = &'a Config;

    fn write(&self, w: &mut Writer<'_>) {
        let m = self;
        w.option(m.period_samples, 0, |w, v| w.u32(v));
        w.flag(m.pinned);
        w.option(m.features, Features::default(), |w, f| {
            w.i8(f.direction);
            w.flag(f.reverses);
            w.u32(f.longest_dwell_samples);
        });
        w.option(m.levels_rad, 0.0, |w, v| w.real(v));
        for side in m.level_side {
            w.i8(side);
        }
        for passes in m.last_pass {
            for pass in passes {
                w.option(pass, 0, |w, v| w.u32(v));
            }
        }
        w.option(m.timing_pass, (0, 0), |w, (level, dir)| {
            w.u8(level);
            w.u8(dir);
        });
        w.option(m.previous, (0, 0.0), |w, (index, rho)| {
            w.u32(index);
            w.real(rho);
        });
        w.real(m.short_increment_rad);
        w.u32(m.short_steps);
        w.option(m.learn_start, 0, |w, v| w.u32(v));
        w.real(m.learn_rotation_rad);
        w.u32(m.dwell_run);
        w.u32(m.learn_longest_dwell);
        w.i8(m.learn_first_direction);
        w.flag(m.learn_reversed);
        w.u32(m.reversed_run);
    }

    fn read(r: &mut Reader<'_>, config: &Config) -> Result<RotationMonitor, CheckpointError> {
        const P: Part = Part::RotationMonitor;
        let invalid = CheckpointError::InvalidValue(P);
        let direction = |d: i8| (-1..=1).contains(&d);
        let period_samples = r.option(P, |r| Ok(r.u32()))?;
        let pinned = r.flag(P)?;
        let features = r.option(Part::Features, |r| {
            Ok(Features {
                direction: r.i8(),
                reverses: r.flag(Part::Features)?,
                longest_dwell_samples: r.u32(),
            })
        })?;
        let levels_rad = r.option(P, |r| Ok(r.real()))?;
        let level_side: [i8; LEVELS] = core::array::from_fn(|_| r.i8());
        let mut last_pass = [[None; 2]; LEVELS];
        for passes in last_pass.iter_mut() {
            for pass in passes.iter_mut() {
                *pass = r.option(P, |r| Ok(r.u32()))?;
            }
        }
        let timing_pass = r.option(P, |r| Ok((r.u8(), r.u8())))?;
        let previous = r.option(P, |r| Ok((r.u32(), r.real())))?;
        let m = RotationMonitor {
            period_samples,
            pinned,
            features,
            levels_rad,
            level_side,
            last_pass,
            timing_pass,
            previous,
            short_increment_rad: r.real(),
            short_steps: r.u32(),
            learn_start: r.option(P, |r| Ok(r.u32()))?,
            learn_rotation_rad: r.real(),
            dwell_run: r.u32(),
            learn_longest_dwell: r.u32(),
            learn_first_direction: r.i8(),
            learn_reversed: r.flag(P)?,
            reversed_run: r.u32(),
        };
        ensure(
            m.period_samples
                .is_none_or(|p| (2..=MAX_PERIOD_SAMPLES).contains(&p)),
            invalid,
        )?;
        ensure(
            !m.pinned || (m.period_samples.is_some() && config.rotation_period_s.is_some()),
            CheckpointError::Inconsistent(P),
        )?;
        ensure(
            m.features.is_none_or(|f| direction(f.direction)),
            CheckpointError::InvalidValue(Part::Features),
        )?;
        let angle = |v: Real| within(v, MAX_WRAPPED_ANGLE_RAD);
        ensure(
            m.levels_rad.is_none_or(angle) && m.previous.is_none_or(|(_, rho)| angle(rho)),
            invalid,
        )?;
        ensure(
            m.level_side.iter().all(|s| direction(*s)) && direction(m.learn_first_direction),
            invalid,
        )?;
        ensure(
            m.timing_pass
                .is_none_or(|(level, dir)| usize::from(level) < LEVELS && dir < 2),
            invalid,
        )?;
        ensure(
            angle(m.short_increment_rad) && m.short_steps <= SHORT_STEPS,
            invalid,
        )?;
        ensure(
            within(m.learn_rotation_rad, 4.0 * MAX_PERIOD_SAMPLES as Real),
            invalid,
        )?;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{running, written_and_read};
    use crate::config::Method;
    use CheckpointError::*;

    const P: Part = Part::RotationMonitor;

    #[test]
    fn a_tampered_rotation_monitor_is_refused_with_a_typed_error() {
        let est = running(Method::Windowed);
        let config = Config::with_method(Method::Windowed);
        // What the tampering reaches: the monitor has learned the pattern and times passes.
        let m = est.rotation_for_test();
        assert!(m.features.is_some() && m.timing_pass.is_some() && m.period_samples == Some(120));
        let with = |edit: &dyn Fn(&mut RotationMonitor)| {
            let mut t = m;
            edit(&mut t);
            written_and_read(&t, &config)
        };
        assert_eq!(with(&|_| {}), Ok(m));
        assert_eq!(
            with(&|m| m.timing_pass = Some((8, 0))),
            Err(InvalidValue(P))
        );
        assert_eq!(
            with(&|m| m.timing_pass = Some((1, 2))),
            Err(InvalidValue(P))
        );
        assert_eq!(with(&|m| m.level_side[2] = 2), Err(InvalidValue(P)));
        assert_eq!(with(&|m| m.period_samples = Some(1)), Err(InvalidValue(P)));
        assert_eq!(with(&|m| m.short_steps = 5), Err(InvalidValue(P)));
        assert_eq!(
            with(&|m| m.levels_rad = Some(Real::NAN)),
            Err(InvalidValue(P))
        );
        assert_eq!(with(&|m| m.previous = Some((3, 7.0))), Err(InvalidValue(P)));
        // Pinned, while the configuration detects the period.
        assert_eq!(with(&|m| m.pinned = true), Err(Inconsistent(P)));
        let bad_direction = |m: &mut RotationMonitor| {
            if let Some(f) = &mut m.features {
                f.direction = 3;
            }
        };
        assert_eq!(with(&bad_direction), Err(InvalidValue(Part::Features)));
    }
}
