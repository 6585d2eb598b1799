//! The windowed method in a checkpoint image: what it learned, not its window. In order: updates
//! (u32), the Kalman filter (`x` 4 `R`, `P` 16 `R` row-major), residual means (4 `R`), the pair the
//! next update takes (u8: 0 pitch, 1 roll), residuals averaged per pair (2 x u32), channel gains
//! (4 `R`), the per-product variances of the pitch and roll channels (2 `R`), the long means of
//! the residual means (4 `R`) and of their powers (4 `R`), the residual means in the long
//! averages per pair (2 x u32), the noise scale and the drift share per pair (2 + 2 `R`); then
//! what the report and the change detector need: each error's reported 1-sigma (4 `R`), a flag
//! byte (bits 0-3: each channel's residual mean beyond the check's bound; bits 4-5: the pitch and
//! roll pair learning their errors again after a change; bits 6-7: the first windows' weights
//! ([`super::start`]): 0 not in their bumps, 1 in them with no estimate held yet, 2 in them with
//! the estimate of the last bump's end held), the estimate they are learned against, or, in the
//! bumps, the one held (4 `R`; its 1-sigma is the reported one), the learned spread of each
//! channel's residual (4 `R`) and the residuals learned into it per pair (2 x u32), and the change
//! detector's part (`change/checkpoint.rs`). The window, the
//! low-pass of its references, the entries since the last update and the detector's blocks are
//! not kept: the next period of samples refills them (the window restarts, as after a long gap).
//! The state the detector goes back to while a change builds up is the restored one.
//!
//! Checked: the Kalman filter (see [`crate::kalman`]); residual means and their long means within
//! [`MAX_RESIDUAL`]; gains within `[0, 4]` (a gain is the magnitude of a window mean of products
//! of sines and cosines, minus a product of two such means); the per-product variances within
//! [`MAX_PRODUCT_VARIANCE_RAD2`]; powers and noise scales within [`MAX_NOISE_SCALE`]; drift shares
//! within `[0, 1]`; the pair 0 or 1; the reported 1-sigma finite and not negative; the flag
//! byte's bits 6-7 not both set; the estimate learned against within [`MAX_STATE`]; the spreads
//! within [`MAX_RESIDUAL`]^2. The bumps begin again at the next full window after a restore, the
//! estimate held meanwhile (an image of before the bumps has bits 6-7 zero: the filter's estimate
//! is reported, as then).

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
    held_x_rad: [Real; STATES],
    change: BlockVariance,
    start: StartTaper,
}

/// What a restart keeps of a pair: all but the change detector's block in progress.
fn kept(p: &Pair) -> Pair {
    Pair {
        block_held: Pair::UNCONFIGURED.block_held,
        last_block: Pair::UNCONFIGURED.last_block,
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
        self.held_x_rad = l.held_x_rad;
        self.change.keep_learned(l.change);
        // The window restarts: bumps begun go on at its next full window.
        self.start = l.start;
        self.report = self.estimate_now();
        // What the detector goes back to, should a change build up before the next block.
        self.keep_clean_state();
    }
}

/// Read with the largest variance allowed (see [`crate::checkpoint::MAX_VARIANCE`]).
impl Stored for Learned {
    const LEN: usize = 4
        + ConstantStateKalman::<Real, STATES>::LEN
        + 4 * R
        + 1
        + 8
        + 4 * R
        + 2 * R
        + 8 * R
        + 8
        + 4 * R
        + 4 * R
        + 1
        + STATES * R
        + 4 * R
        + 8
        + BlockVariance::LEN;
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        // Each quantity for both pairs (channels 0-3, pairs 0-1) before the next.
        let [p, q] = &self.pairs;
        w.u32(self.updates);
        self.kf.write(w);
        for v in p.stats.mean_rad.into_iter().chain(q.stats.mean_rad) {
            w.real(v);
        }
        w.u8(self.next_pair);
        w.u32(p.stats.count);
        w.u32(q.stats.count);
        for v in p.gains.into_iter().chain(q.gains) {
            w.real(v);
        }
        w.real(p.product_variance_rad2);
        w.real(q.product_variance_rad2);
        for v in p
            .stats
            .mean_long_rad
            .into_iter()
            .chain(q.stats.mean_long_rad)
        {
            w.real(v);
        }
        for v in p.stats.power.into_iter().chain(q.stats.power) {
            w.real(v);
        }
        w.u32(p.stats.long_count);
        w.u32(q.stats.long_count);
        for v in [
            p.stats.noise_scale,
            q.stats.noise_scale,
            p.stats.drift_share,
            q.stats.drift_share,
        ] {
            w.real(v);
        }
        for v in p.reported_sigma_rad.into_iter().chain(q.reported_sigma_rad) {
            w.real(v);
        }
        let bits = p
            .mismatch
            .iter()
            .chain(&q.mismatch)
            .chain([&p.relearning, &q.relearning])
            .enumerate()
            .fold(0u8, |b, (i, f)| b | (u8::from(*f) << i));
        let start = match self.start {
            StartTaper::Restarted { held } => 1 + u8::from(held),
            _ => 0,
        };
        w.u8(bits | start << 6);
        for v in self
            .held_x_rad
            .into_iter()
            .chain(p.spread_rad2)
            .chain(q.spread_rad2)
        {
            w.real(v);
        }
        w.u32(p.spread_count);
        w.u32(q.spread_count);
        self.change.write(w);
    }

    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Learned, CheckpointError> {
        let updates = r.u32();
        let kf = ConstantStateKalman::read(r, max_variance)?;
        // One value built in place, then its later fields read into it: a second `Learned`
        // made from this one (`..m`) took its size again on the restore's stack.
        let mut m = Learned {
            updates,
            kf,
            next_pair: 0,
            pairs: [Pair::UNCONFIGURED; 2],
            held_x_rad: [0.0; STATES],
            change: BlockVariance::default(),
            start: StartTaper::Fresh,
        };
        let [p, q] = &mut m.pairs;
        for v in p.stats.mean_rad.iter_mut().chain(&mut q.stats.mean_rad) {
            *v = r.real();
        }
        m.next_pair = r.u8();
        ensure(
            m.next_pair <= 1,
            CheckpointError::InvalidValue(Part::Residuals),
        )?;
        p.stats.count = r.u32();
        q.stats.count = r.u32();
        for v in p.gains.iter_mut().chain(&mut q.gains) {
            *v = r.real();
        }
        p.product_variance_rad2 = r.real();
        q.product_variance_rad2 = r.real();
        for v in p
            .stats
            .mean_long_rad
            .iter_mut()
            .chain(&mut q.stats.mean_long_rad)
        {
            *v = r.real();
        }
        for v in p.stats.power.iter_mut().chain(&mut q.stats.power) {
            *v = r.real();
        }
        p.stats.long_count = r.u32();
        q.stats.long_count = r.u32();
        p.stats.noise_scale = r.real();
        q.stats.noise_scale = r.real();
        p.stats.drift_share = r.real();
        q.stats.drift_share = r.real();
        for v in p
            .reported_sigma_rad
            .iter_mut()
            .chain(&mut q.reported_sigma_rad)
        {
            *v = r.real();
        }
        let bits = r.u8();
        p.mismatch = core::array::from_fn(|i| bits & (1 << i) != 0);
        q.mismatch = core::array::from_fn(|i| bits & (1 << (2 + i)) != 0);
        p.relearning = bits & (1 << 4) != 0;
        q.relearning = bits & (1 << 5) != 0;
        for v in m
            .held_x_rad
            .iter_mut()
            .chain(&mut p.spread_rad2)
            .chain(&mut q.spread_rad2)
        {
            *v = r.real();
        }
        p.spread_count = r.u32();
        q.spread_count = r.u32();
        m.change = BlockVariance::read(r, ())?;
        m.start = match bits >> 6 {
            0 => StartTaper::Fresh,
            1 => StartTaper::Restarted { held: false },
            2 => StartTaper::Restarted { held: true },
            _ => return Err(CheckpointError::InvalidValue(Part::Residuals)),
        };
        ensure(
            m.pairs.iter().all(residuals_in_range),
            CheckpointError::InvalidValue(Part::Residuals),
        )?;
        let state = MAX_STATE as Real;
        ensure(
            all_within(&m.held_x_rad, -state, state),
            CheckpointError::InvalidValue(Part::ChangeDetector),
        )?;
        Ok(m)
    }
}

/// Whether the residual statistics of a pair are finite and within their bounds. Out of line: 48
/// bytes less flash than written into the reader above (the restore's stack is the same either
/// way).
#[inline(never)]
fn residuals_in_range(p: &Pair) -> bool {
    let residual = MAX_RESIDUAL as Real;
    let s = &p.stats;
    all_within(&s.mean_rad, -residual, residual)
        && all_within(&p.gains, 0.0, 4.0)
        && all_within(&[p.product_variance_rad2], 0.0, MAX_PRODUCT_VARIANCE_RAD2)
        && all_within(&s.mean_long_rad, -residual, residual)
        && all_within(&s.power, 0.0, MAX_NOISE_SCALE)
        && all_within(&[s.noise_scale], 0.0, MAX_NOISE_SCALE)
        && all_within(&[s.drift_share], 0.0, 1.0)
        && all_within(&p.reported_sigma_rad, 0.0, Real::MAX)
        && all_within(&p.spread_rad2, 0.0, residual * residual)
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
