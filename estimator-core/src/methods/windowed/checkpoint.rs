//! The windowed method in a checkpoint image: what it learned, not its window. In order: updates
//! (u32), the Kalman filter (`x` 5 `R`, `P` 25 `R` row-major: x1..x4 and the heel in turns), the
//! pair the next update takes (u8: 0 pitch, 1 roll), each pair's part (pitch, then roll: below),
//! the roll pair's share of the covariance (its upper triangle, 15 `R`, row by row), a flag
//! byte (bits 0-1: the first windows' weights ([`super::start`]): 0 not in their bumps, 1 in them
//! with no estimate held yet, 2 in them with the estimate of the last bump's end held; bit 2: the
//! ship has turned), the estimate the errors are learned again against after a change, or, in
//! the bumps, the one held (5 `R`; its 1-sigma is the reported one), and the change detector's
//! part (`change/checkpoint.rs`).
//!
//! A pair's part ([`Pair`]'s kept fields): its residual means (2 `R`), residuals averaged (u32),
//! the long means of the residual means (2 `R`), their recent-weighted means (2 `R`) and the long
//! means of their powers (2 `R`), the residual means in
//! the long averages (u32), the noise scale and the drift share (2 `R`), the channel gains
//! (2 `R`), the per-product variance (`R`), the reported 1-sigma of its errors (2 `R`), a flag byte
//! (bits 0-1: each channel's residual mean beyond the check's bound; bit 2: learning its errors
//! again after a change), the learned spread of each channel's residual (2 `R`) and the residuals
//! learned into it (u32).
//!
//! The window, the low-pass of its references, the entries since the last update, the
//! detector's blocks and the batches of the long-run noise scale ([`super::long_run`]) are not
//! kept: the next period of samples refills them (the window restarts, as after a long gap). The
//! state the detector goes back to while a change builds up is the restored one.
//!
//! Checked: the Kalman filter (see [`crate::kalman`]); residual means and their long means within
//! [`MAX_RESIDUAL`] (the recent-weighted ones too); gains within `[0, 4]` (a gain is the magnitude of a window mean of products
//! of sines and cosines, minus a product of two such means); the per-product variances within
//! [`MAX_PRODUCT_VARIANCE_RAD2`]; powers and noise scales within [`MAX_NOISE_SCALE`]; drift shares
//! within `[0, 1]`; the pair 0 or 1; the reported 1-sigma finite and not negative; the roll
//! pair's share finite, its diagonal not negative; the flag byte's bits 0-1 not both set and no
//! other bit but 2; the estimate learned against within [`MAX_STATE`]; the spreads within
//! [`MAX_RESIDUAL`]^2. The bumps begin again at the next full window after a restore, the estimate
//! held meanwhile (an image with bits 0-1 zero reports the filter's estimate).

use super::change::checkpoint::BlockVariance;
use super::pair::Pair;
use super::start::StartTaper;
use super::Windowed;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{
    all_within, ensure, CheckpointError, Part, Stored, MAX_RESIDUAL, MAX_STATE, R,
};
use crate::correlation::STATES;
use crate::kalman::ConstantStateKalman;
use crate::Real;

/// Largest residual power and noise scale restored: a residual mean of [`MAX_RESIDUAL`] over the
/// smallest standard error (about a 1e-7 rad product sigma averaged over one window), squared,
/// is far below; anything larger is a crafted image.
const MAX_NOISE_SCALE: Real = 1.0e30;

/// Largest per-product variance restored, rad^2: a 1 rad measurement sigma plus the window mean
/// of the fill variances (each below (4.1 x 90 deg)^2, times the saturated fill weight).
const MAX_PRODUCT_VARIANCE_RAD2: Real = 1.0e7;

/// What a restart keeps of the windowed method (the fields of [`Windowed`] of the same names; the
/// period during which the status says the errors changed is not kept, nor the change detector's
/// last block of each pair).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Learned {
    updates: u32,
    kf: ConstantStateKalman<Real, STATES>,
    next_pair: u8,
    pairs: [Pair; 2],
    roll_share: [[Real; STATES]; STATES],
    turning: bool,
    held_x_rad: [Real; STATES],
    change: BlockVariance,
    start: StartTaper,
}

/// What a restart keeps of a pair: all but the change detector's block in progress and the
/// long-run batches.
fn kept(p: &Pair) -> Pair {
    Pair {
        block_held: Pair::UNCONFIGURED.block_held,
        last_block: Pair::UNCONFIGURED.last_block,
        long_run: Pair::UNCONFIGURED.long_run,
        ..*p
    }
}

impl<const CAP: usize> Windowed<CAP> {
    /// What a restart keeps.
    pub(crate) fn learned(&self) -> Learned {
        Learned {
            updates: self.updates,
            kf: self.kf.clone(),
            next_pair: self.next_pair,
            pairs: [kept(&self.pairs[0]), kept(&self.pairs[1])],
            roll_share: self.roll_share,
            turning: self.turning,
            held_x_rad: self.held_x_rad,
            change: self.change.learned(),
            // What the image says of the weights: in the bumps or not, and whether one ended.
            start: match self.start {
                StartTaper::Bumps { held, .. } | StartTaper::Restarted { held } => {
                    StartTaper::Restarted { held }
                }
                _ => StartTaper::Fresh,
            },
        }
    }

    /// Takes over what a restart keeps (into a fresh state, at restore); the window stays empty.
    pub(crate) fn keep_learned(&mut self, l: Learned) {
        self.updates = l.updates;
        self.kf = l.kf;
        self.next_pair = l.next_pair;
        self.pairs = l.pairs;
        self.roll_share = l.roll_share;
        self.turning = l.turning;
        self.held_x_rad = l.held_x_rad;
        self.change.keep_learned(l.change);
        // The window restarts: bumps begun go on at its next full window.
        self.start = l.start;
        self.report = self.estimate_now();
        // What the detector goes back to, should a change build up before the next block.
        self.keep_clean_state();
    }
}

/// The entries of the upper triangle of a `STATES` x `STATES` matrix.
const UPPER: usize = STATES * (STATES + 1) / 2;

/// A pair's kept fields (see the module doc).
impl Stored for Pair {
    const LEN: usize =
        2 * R + 4 + 2 * R + 2 * R + 2 * R + 4 + 2 * R + 2 * R + R + 2 * R + 1 + 2 * R + 4;
    type Context<'a> = ();

    fn write(&self, w: &mut Writer<'_>) {
        let s = &self.stats;
        for v in s.mean_rad {
            w.real(v);
        }
        w.u32(s.count);
        for v in s
            .mean_long_rad
            .into_iter()
            .chain(s.mean_recent_rad)
            .chain(s.power)
        {
            w.real(v);
        }
        w.u32(s.long_count);
        for v in [s.noise_scale, s.drift_share]
            .into_iter()
            .chain(self.gains)
            .chain([self.product_variance_rad2])
            .chain(self.reported_sigma_rad)
        {
            w.real(v);
        }
        w.u8(u8::from(self.mismatch[0])
            | u8::from(self.mismatch[1]) << 1
            | u8::from(self.relearning) << 2);
        for v in self.spread_rad2 {
            w.real(v);
        }
        w.u32(self.spread_count);
    }

    fn read(r: &mut Reader<'_>, _: ()) -> Result<Pair, CheckpointError> {
        let mut p = Pair::UNCONFIGURED;
        let s = &mut p.stats;
        s.mean_rad = [r.real(), r.real()];
        s.count = r.u32();
        s.mean_long_rad = [r.real(), r.real()];
        s.mean_recent_rad = [r.real(), r.real()];
        s.power = [r.real(), r.real()];
        s.long_count = r.u32();
        s.noise_scale = r.real();
        s.drift_share = r.real();
        p.gains = [r.real(), r.real()];
        p.product_variance_rad2 = r.real();
        p.reported_sigma_rad = [r.real(), r.real()];
        let bits = r.u8();
        ensure(bits < 8, CheckpointError::InvalidValue(Part::Residuals))?;
        p.mismatch = [bits & 1 != 0, bits & 2 != 0];
        p.relearning = bits & 4 != 0;
        p.spread_rad2 = [r.real(), r.real()];
        p.spread_count = r.u32();
        ensure(
            residuals_in_range(&p),
            CheckpointError::InvalidValue(Part::Residuals),
        )?;
        Ok(p)
    }
}

/// Read with the largest variance allowed (see [`crate::checkpoint::MAX_VARIANCE`]).
impl Stored for Learned {
    const LEN: usize = 4
        + ConstantStateKalman::<Real, STATES>::LEN
        + 1
        + 2 * Pair::LEN
        + UPPER * R
        + 1
        + STATES * R
        + BlockVariance::LEN;
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        w.u32(self.updates);
        self.kf.write(w);
        w.u8(self.next_pair);
        for p in &self.pairs {
            p.write(w);
        }
        for j in 0..STATES {
            for k in j..STATES {
                w.real(self.roll_share[j][k]);
            }
        }
        let start = match self.start {
            StartTaper::Restarted { held } => 1 + u8::from(held),
            _ => 0,
        };
        w.u8(start | u8::from(self.turning) << 2);
        for v in self.held_x_rad {
            w.real(v);
        }
        self.change.write(w);
    }

    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Learned, CheckpointError> {
        let updates = r.u32();
        let kf = ConstantStateKalman::read(r, max_variance)?;
        // One value built in place, then its later fields read into it: a second `Learned`
        // made from this one (`..m`) would take its size again on the restore's stack.
        let mut m = Learned {
            updates,
            kf,
            next_pair: r.u8(),
            pairs: [Pair::UNCONFIGURED; 2],
            roll_share: [[0.0; STATES]; STATES],
            turning: false,
            held_x_rad: [0.0; STATES],
            change: BlockVariance::default(),
            start: StartTaper::Fresh,
        };
        ensure(
            m.next_pair <= 1,
            CheckpointError::InvalidValue(Part::Residuals),
        )?;
        for p in &mut m.pairs {
            *p = Pair::read(r, ())?;
        }
        for j in 0..STATES {
            for k in j..STATES {
                m.roll_share[j][k] = r.real();
            }
        }
        ensure(
            share_in_range(&m.roll_share),
            CheckpointError::InvalidValue(Part::Residuals),
        )?;
        let bits = r.u8();
        m.start = match bits & 3 {
            0 => StartTaper::Fresh,
            1 => StartTaper::Restarted { held: false },
            2 => StartTaper::Restarted { held: true },
            _ => return Err(CheckpointError::InvalidValue(Part::Residuals)),
        };
        ensure(bits < 8, CheckpointError::InvalidValue(Part::Residuals))?;
        m.turning = bits & 4 != 0;
        for v in &mut m.held_x_rad {
            *v = r.real();
        }
        m.change = BlockVariance::read(r, ())?;
        let state = MAX_STATE as Real;
        ensure(
            all_within(&m.held_x_rad, -state, state),
            CheckpointError::InvalidValue(Part::ChangeDetector),
        )?;
        Ok(m)
    }
}

/// Whether a pair's residual statistics are finite and within their bounds. Out of line: less
/// flash than written into the reader (the restore's stack is the same either way).
#[inline(never)]
fn residuals_in_range(p: &Pair) -> bool {
    let residual = MAX_RESIDUAL as Real;
    let s = &p.stats;
    all_within(&s.mean_rad, -residual, residual)
        && all_within(&p.gains, 0.0, 4.0)
        && all_within(&[p.product_variance_rad2], 0.0, MAX_PRODUCT_VARIANCE_RAD2)
        && all_within(&s.mean_long_rad, -residual, residual)
        && all_within(&s.mean_recent_rad, -residual, residual)
        && all_within(&s.power, 0.0, MAX_NOISE_SCALE)
        && all_within(&[s.noise_scale], 0.0, MAX_NOISE_SCALE)
        && all_within(&[s.drift_share], 0.0, 1.0)
        && all_within(&p.reported_sigma_rad, 0.0, Real::MAX)
        && all_within(&p.spread_rad2, 0.0, residual * residual)
}

/// Whether the roll pair's share of the covariance is finite with a diagonal that is not negative.
#[inline(never)]
fn share_in_range(info: &[[Real; STATES]; STATES]) -> bool {
    (0..STATES).all(|j| all_within(&info[j], -Real::MAX, Real::MAX) && info[j][j] >= 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{running, written_and_read};
    use crate::config::Method;
    use crate::methods::MethodState;
    use CheckpointError::*;

    #[test]
    fn a_tampered_windowed_state_is_refused_with_a_typed_error() {
        let est = running(Method::Windowed);
        let MethodState::Windowed(m) = est.method_for_test() else {
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
            with(&|m| m.pairs[1].gains[1] = -0.5),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.pairs[0].gains[1] = Real::NAN),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.next_pair = 2),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.pairs[0].stats.drift_share = 1.5),
            Err(InvalidValue(Part::Residuals))
        );
        // Regression, fuzz target `checkpoint_restore`: finite but absurd residuals and gains
        // (a flipped top byte) were accepted and overflowed the outputs.
        assert_eq!(
            with(&|m| m.pairs[1].stats.mean_rad[0] = 1e30),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.pairs[0].gains[0] = 1e30),
            Err(InvalidValue(Part::Residuals))
        );
        // A zero gain (a window whose reference does not move) is a state the estimator can be in.
        assert!(with(&|m| m.pairs[1].gains[1] = 0.0).is_ok());
        // What the report and the change detector keep.
        assert_eq!(
            with(&|m| m.pairs[0].reported_sigma_rad[1] = -1e-6),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.pairs[1].reported_sigma_rad[0] = Real::INFINITY),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.pairs[0].spread_rad2[0] = -1e-9),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.held_x_rad[3] = 1e9),
            Err(InvalidValue(Part::ChangeDetector))
        );
        assert!(with(&|m| m.pairs[0].relearning = true).is_ok());
        assert_eq!(
            with(&|m| m.roll_share[2][2] = -1.0),
            Err(InvalidValue(Part::Residuals))
        );
        // In the first windows' bumps, with an estimate held (flag bits 6-7).
        assert_eq!(
            with(&|m| m.start = StartTaper::Restarted { held: true }).map(|m| m.start),
            Ok(StartTaper::Restarted { held: true })
        );
        // The Kalman filter's checks (see `kalman/checkpoint.rs`) apply to the method's.
        assert_eq!(
            with(&|m| m.kf = ConstantStateKalman::new([Real::NAN; STATES])),
            Err(InvalidValue(Part::KalmanCovariance))
        );
    }
}
