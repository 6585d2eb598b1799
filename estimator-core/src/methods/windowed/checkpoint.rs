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
use super::start::StartTaper;
use super::Windowed;
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{
    all_within, ensure, CheckpointError, Part, Stored, MAX_RESIDUAL, MAX_STATE, R,
};
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
/// period during which the status says the errors changed is not kept).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Learned {
    updates: u32,
    kf: ConstantStateKalman<Real, 4>,
    residual_mean: [Real; 4],
    next_pair: u8,
    residual_count: [u32; 2],
    gains: [Real; 4],
    product_variance_rad2: [Real; 2],
    residual_mean_long: [Real; 4],
    residual_power: [Real; 4],
    long_count: [u32; 2],
    noise_scale: [Real; 2],
    drift_share: [Real; 2],
    reported_sigma_rad: [Real; 4],
    channel_mismatch: [bool; 4],
    relearning: [bool; 2],
    held_x_rad: [Real; 4],
    spread_rad2: [Real; 4],
    spread_count: [u32; 2],
    change: BlockVariance,
    start: StartTaper,
}

impl<const CAP: usize> Windowed<CAP> {
    /// What a restart keeps.
    pub(crate) fn learned(&self) -> Learned {
        Learned {
            updates: self.updates,
            kf: self.kf.clone(),
            residual_mean: self.residual_mean,
            next_pair: self.next_pair,
            residual_count: self.residual_count,
            gains: self.gains,
            product_variance_rad2: self.product_variance_rad2,
            residual_mean_long: self.residual_mean_long,
            residual_power: self.residual_power,
            long_count: self.long_count,
            noise_scale: self.noise_scale,
            drift_share: self.drift_share,
            reported_sigma_rad: self.reported_sigma_rad,
            channel_mismatch: self.channel_mismatch,
            relearning: self.relearning,
            held_x_rad: self.held_x_rad,
            spread_rad2: self.spread_rad2,
            spread_count: self.spread_count,
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
        self.residual_mean = l.residual_mean;
        self.next_pair = l.next_pair;
        self.residual_count = l.residual_count;
        self.gains = l.gains;
        self.product_variance_rad2 = l.product_variance_rad2;
        self.residual_mean_long = l.residual_mean_long;
        self.residual_power = l.residual_power;
        self.long_count = l.long_count;
        self.noise_scale = l.noise_scale;
        self.drift_share = l.drift_share;
        self.reported_sigma_rad = l.reported_sigma_rad;
        self.channel_mismatch = l.channel_mismatch;
        self.relearning = l.relearning;
        self.held_x_rad = l.held_x_rad;
        self.spread_rad2 = l.spread_rad2;
        self.spread_count = l.spread_count;
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
        + ConstantStateKalman::<Real, 4>::LEN
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
        + 4 * R
        + 4 * R
        + 8
        + BlockVariance::LEN;
    type Context<'a> = f64;

    fn write(&self, w: &mut Writer<'_>) {
        let m = self;
        w.u32(m.updates);
        m.kf.write(w);
        for v in m.residual_mean {
            w.real(v);
        }
        w.u8(m.next_pair);
        for c in m.residual_count {
            w.u32(c);
        }
        for v in m.gains.into_iter().chain(m.product_variance_rad2) {
            w.real(v);
        }
        for v in m.residual_mean_long.into_iter().chain(m.residual_power) {
            w.real(v);
        }
        for c in m.long_count {
            w.u32(c);
        }
        for v in m
            .noise_scale
            .into_iter()
            .chain(m.drift_share)
            .chain(m.reported_sigma_rad)
        {
            w.real(v);
        }
        let bits = m
            .channel_mismatch
            .iter()
            .chain(&m.relearning)
            .enumerate()
            .fold(0u8, |b, (i, f)| b | (u8::from(*f) << i));
        let start = match m.start {
            StartTaper::Restarted { held } => 1 + u8::from(held),
            _ => 0,
        };
        w.u8(bits | start << 6);
        for v in m.held_x_rad.into_iter().chain(m.spread_rad2) {
            w.real(v);
        }
        for c in m.spread_count {
            w.u32(c);
        }
        m.change.write(w);
    }

    fn read(r: &mut Reader<'_>, max_variance: f64) -> Result<Learned, CheckpointError> {
        let updates = r.u32();
        let kf = ConstantStateKalman::read(r, max_variance)?;
        let residual_mean: [Real; 4] = core::array::from_fn(|_| r.real());
        let next_pair = r.u8();
        ensure(
            next_pair <= 1,
            CheckpointError::InvalidValue(Part::Residuals),
        )?;
        // One value built in place, then its later fields read into it: a second `Learned`
        // made from this one (`..m`) took its size again on the restore's stack.
        let mut m = Learned {
            updates,
            kf,
            residual_mean,
            next_pair,
            residual_count: [r.u32(), r.u32()],
            gains: core::array::from_fn(|_| r.real()),
            product_variance_rad2: core::array::from_fn(|_| r.real()),
            residual_mean_long: core::array::from_fn(|_| r.real()),
            residual_power: core::array::from_fn(|_| r.real()),
            long_count: [r.u32(), r.u32()],
            noise_scale: core::array::from_fn(|_| r.real()),
            drift_share: core::array::from_fn(|_| r.real()),
            reported_sigma_rad: core::array::from_fn(|_| r.real()),
            channel_mismatch: [false; 4],
            relearning: [false; 2],
            held_x_rad: [0.0; 4],
            spread_rad2: [0.0; 4],
            spread_count: [0; 2],
            change: BlockVariance::default(),
            start: StartTaper::Fresh,
        };
        let bits = r.u8();
        m.channel_mismatch = core::array::from_fn(|i| bits & (1 << i) != 0);
        m.relearning = core::array::from_fn(|i| bits & (1 << (4 + i)) != 0);
        for v in m.held_x_rad.iter_mut().chain(&mut m.spread_rad2) {
            *v = r.real();
        }
        m.spread_count = [r.u32(), r.u32()];
        m.change = BlockVariance::read(r, ())?;
        m.start = match bits >> 6 {
            0 => StartTaper::Fresh,
            1 => StartTaper::Restarted { held: false },
            2 => StartTaper::Restarted { held: true },
            _ => return Err(CheckpointError::InvalidValue(Part::Residuals)),
        };
        ensure(
            residuals_in_range(&m),
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

/// Whether the residual statistics of `m` are finite and within their bounds. Out of line: 48 bytes
/// less flash than written into the reader above (the restore's stack is the same either way).
#[inline(never)]
fn residuals_in_range(m: &Learned) -> bool {
    let residual = MAX_RESIDUAL as Real;
    all_within(&m.residual_mean, -residual, residual)
        && all_within(&m.gains, 0.0, 4.0)
        && all_within(&m.product_variance_rad2, 0.0, MAX_PRODUCT_VARIANCE_RAD2)
        && all_within(&m.residual_mean_long, -residual, residual)
        && all_within(&m.residual_power, 0.0, MAX_NOISE_SCALE)
        && all_within(&m.noise_scale, 0.0, MAX_NOISE_SCALE)
        && all_within(&m.drift_share, 0.0, 1.0)
        && all_within(&m.reported_sigma_rad, 0.0, Real::MAX)
        && all_within(&m.spread_rad2, 0.0, residual * residual)
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
            with(&|m| m.gains[3] = -0.5),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.gains[1] = Real::NAN),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.next_pair = 2),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.drift_share[0] = 1.5),
            Err(InvalidValue(Part::Residuals))
        );
        // Regression, fuzz target `checkpoint_restore`: finite but absurd residuals and gains
        // (a flipped top byte) were accepted and overflowed the outputs.
        assert_eq!(
            with(&|m| m.residual_mean[2] = 1e30),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.gains[0] = 1e30),
            Err(InvalidValue(Part::Residuals))
        );
        // A zero gain (a window whose reference does not move) is a state the estimator can be in.
        assert!(with(&|m| m.gains[3] = 0.0).is_ok());
        // What the report and the change detector keep.
        assert_eq!(
            with(&|m| m.reported_sigma_rad[1] = -1e-6),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.reported_sigma_rad[2] = Real::INFINITY),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.spread_rad2[0] = -1e-9),
            Err(InvalidValue(Part::Residuals))
        );
        assert_eq!(
            with(&|m| m.held_x_rad[3] = 1e9),
            Err(InvalidValue(Part::ChangeDetector))
        );
        assert!(with(&|m| m.relearning = [true, false]).is_ok());
        // In the first windows' bumps, with an estimate held (flag bits 6-7).
        assert_eq!(
            with(&|m| m.start = StartTaper::Restarted { held: true }).map(|m| m.start),
            Ok(StartTaper::Restarted { held: true })
        );
        // The Kalman filter's checks (see `kalman/checkpoint.rs`) apply to the method's.
        assert_eq!(
            with(&|m| m.kf = ConstantStateKalman::new([Real::NAN; 4])),
            Err(InvalidValue(Part::KalmanCovariance))
        );
    }
}
