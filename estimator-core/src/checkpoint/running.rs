//! The estimator's own running state: the grid index, whether samples are being fed, the gate,
//! the cached latitude, the status, the last fault, the sway monitor and the counters.
//! Of the grid's constants ([`Feed`]) only the interval they were fixed from is stored; restore
//! derives them from it again.
//!
//! Checked: flags and codes; the latitude below 90 deg (it is a sample's, which
//! [`crate::Sample::check`] bounds); the feed interval positive and finite; the fault's time finite
//! (a time stamp); the sway mean within 2 rad and its mean square within `[0, 4]` rad^2 (averages
//! of roll within 90 deg).

use super::wire::{Reader, Writer};
use super::{ensure, within, within_non_negative, CheckpointError, Part, R};
use crate::estimator::{Estimator, Feed};
use crate::output::{Counters, RejectCounts, Status};
use crate::rotation_pattern::RotationFault;
use crate::sway_gate::SwayMonitor;
use crate::math::sin_cos;
use crate::sample::{RejectReason, MAX_TILT_RAD};
use crate::Real;

/// Bytes of the part.
pub(super) const LEN: usize = 4 + (1 + 8) + 1 + R + 1 + 1 + 8 + (2 * R + 4) + RejectReason::ALL.len() * 4 + 4 * 4;

/// The part, read and checked.
#[derive(Clone, Copy)]
pub(super) struct Running {
    index: u32,
    feed_interval_s: Option<f64>,
    gate_open: bool,
    latitude_rad: Real,
    window_status: Status,
    fault: Option<(RotationFault, f64)>,
    sway: SwayMonitor,
    rejected: RejectCounts,
    counters: Counters,
}

pub(super) fn write<const CAP: usize>(w: &mut Writer<'_>, e: &Estimator<CAP>) {
    w.u32(e.index);
    w.option(e.feed.map(|f| f.interval_s), 0.0, |w, v| w.f64(v));
    w.flag(e.gate_open);
    w.real(e.latitude_trig.0);
    w.u8(e.window_status.code());
    match e.fault {
        Some((fault, since_s)) => {
            w.u8(Status::RotationFault(fault).code());
            w.f64(since_s);
        }
        None => {
            w.u8(0);
            w.f64(0.0);
        }
    }
    w.real(e.sway.mean_rad);
    w.real(e.sway.mean_square_rad2);
    w.u32(e.sway.samples);
    for n in e.rejected.0 {
        w.u32(n);
    }
    let c = &e.counters;
    for n in [c.accepted, c.filled, c.window_restarts, c.clock_steps] {
        w.u32(n);
    }
}

pub(super) fn read(r: &mut Reader<'_>) -> Result<Running, CheckpointError> {
    let index = r.u32();
    let feed_interval_s = r.option(Part::Estimator, |r| Ok(r.f64()))?;
    // The interval the grid's constants were fixed from: positive and finite.
    ensure(feed_interval_s.is_none_or(|d| d.is_finite() && d > 0.0), CheckpointError::InvalidValue(Part::Estimator))?;
    let gate_open = r.flag(Part::Estimator)?;
    let latitude_rad = r.real();
    ensure(latitude_rad.is_finite() && latitude_rad.abs() < MAX_TILT_RAD, CheckpointError::InvalidValue(Part::Latitude))?;
    let window_status = Status::try_from(r.u8()).map_err(|_| CheckpointError::InvalidValue(Part::Status))?;
    let fault_code = r.u8();
    let since_start = r.pos();
    let since_s = r.f64();
    let fault = match (fault_code, Status::try_from(fault_code).ok()) {
        (0, _) => {
            r.zeros_since(since_start, Part::Fault)?;
            None
        }
        (_, Some(Status::RotationFault(fault))) => {
            ensure(since_s.is_finite(), CheckpointError::InvalidValue(Part::Fault))?;
            Some((fault, since_s))
        }
        _ => return Err(CheckpointError::InvalidValue(Part::Fault)),
    };
    let sway = SwayMonitor { mean_rad: r.real(), mean_square_rad2: r.real(), samples: r.u32() };
    ensure(
        within(sway.mean_rad, 2.0) && within_non_negative(sway.mean_square_rad2, 4.0),
        CheckpointError::InvalidValue(Part::SwayMonitor),
    )?;
    let rejected = RejectCounts(core::array::from_fn(|_| r.u32()));
    let counters = Counters { accepted: r.u32(), filled: r.u32(), window_restarts: r.u32(), clock_steps: r.u32() };
    Ok(Running { index, feed_interval_s, gate_open, latitude_rad, window_status, fault, sway, rejected, counters })
}

impl Running {
    /// Writes the part into an estimator (after it has been reset to the image's configuration).
    pub(super) fn apply<const CAP: usize>(&self, e: &mut Estimator<CAP>) {
        e.index = self.index;
        // The constants are derived from the interval alone, exactly as when they were fixed.
        e.feed = self.feed_interval_s.map(|d| Feed::new(d, &e.config));
        e.gate_open = self.gate_open;
        let (sin_lat, cos_lat) = sin_cos(self.latitude_rad);
        e.latitude_trig = (self.latitude_rad, sin_lat, cos_lat);
        e.window_status = self.window_status;
        e.fault = self.fault;
        e.sway = self.sway;
        e.rejected = self.rejected;
        e.counters = self.counters;
    }
}
