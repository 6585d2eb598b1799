//! The estimator in a checkpoint image: [`Estimator::checkpoint`], [`Estimator::restore`] and
//! [`Estimator::from_checkpoint`], the order of the parts (the header, CRC and layout are in
//! [`crate::checkpoint`]), and the estimator's own part.
//!
//! The estimator's own part is its running state: the grid index, whether samples are being fed, the gate,
//! the cached latitude, the status, the last fault, the sway monitor and the counters.
//! Of the grid's constants ([`Feed`]) only the interval they were fixed from is stored; restore
//! derives them from it again.
//!
//! Checked: flags and codes; the latitude below 90 deg (it is a sample's, which
//! [`crate::Sample::check`] bounds); the feed interval positive and finite; the fault's time finite
//! (a time stamp); the sway monitor (see `sway_gate/checkpoint.rs`).

use super::{Estimator, Feed};
use crate::checkpoint::image::{seal, verified_image, write_header};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{checkpoint_len, ensure, CheckpointError, Part, CRC_LEN, HEADER_LEN, METHOD_OFFSET, R};
use crate::config::{Config, Method};
use crate::gap_fill::GapFiller;
use crate::methods::MethodState;
use crate::rotation_pattern::RotationMonitor;
use crate::time_grid::TimeGrid;
use crate::output::{Counters, RejectCounts, Status};
use crate::rotation_pattern::RotationFault;
use crate::sway_gate::SwayMonitor;
use crate::math::sin_cos;
use crate::sample::{RejectReason, MAX_TILT_RAD};
use crate::Real;

impl<const CAP: usize> Estimator<CAP> {
    /// Bytes of a checkpoint image of this estimator (23 384 for the default capacity of 720
    /// with `f32`; see [`crate::checkpoint::checkpoint_len`]).
    pub const CHECKPOINT_LEN: usize = checkpoint_len(CAP);

    /// Writes the whole state into `buf[..CHECKPOINT_LEN]`; returns the bytes written. A shorter
    /// buffer is refused and left as it is.
    pub fn checkpoint(&self, buf: &mut [u8]) -> Result<usize, CheckpointError> {
        let len = Self::CHECKPOINT_LEN;
        let available = buf.len();
        let Some(image) = buf.get_mut(..len) else {
            return Err(CheckpointError::BufferTooSmall { needed: len, available });
        };
        image.fill(0);
        let mut w = Writer::new(image, 0);
        write_header(&mut w, self.config.method, CAP, len);
        self.config.write_checkpoint(&mut w);
        write_running(&mut w, self);
        self.grid.write_checkpoint(&mut w);
        self.rotation.write_checkpoint(&mut w);
        self.filler.write_checkpoint(&mut w);
        let mut w = Writer::new(image, METHOD_OFFSET);
        self.method.write_checkpoint(&mut w);
        seal(image);
        Ok(len)
    }

    /// Replaces the whole state (configuration included) with the image in `buf` (which may be
    /// longer than the image). On any error the estimator is left exactly as it was.
    ///
    /// Works in place, in two passes over the image: the first checks every field and keeps only
    /// what it must compare (the running sums, one small part at a time); the second, once
    /// everything has passed, resets the estimator in place ([`Estimator::reset`]'s way) and reads
    /// the same bytes straight into it, part by part, the delay line slot by slot and the rings
    /// entry by entry. No second estimator, ring or delay line passes through the stack, which is
    /// what lets the firmware restore at boot on a microcontroller's stack. (Resetting to another
    /// method than the running one builds that method's state by value: see
    /// [`crate::methods::MethodState::reset`].)
    pub fn restore(&mut self, buf: &[u8]) -> Result<(), CheckpointError> {
        let (image, method) = verified_image(buf, CAP)?;
        read_state::<CAP>(image, method, None)?;
        // The same bytes pass the same checks again, so this cannot fail half-way.
        read_state(image, method, Some(self)).map(|_| ())
    }

    /// A new estimator from a checkpoint image (see [`Estimator::restore`]). Builds the estimator
    /// by value: for hosts, not for a microcontroller's stack.
    pub fn from_checkpoint(buf: &[u8]) -> Result<Self, CheckpointError> {
        let (image, method) = verified_image(buf, CAP)?;
        let config = read_state::<CAP>(image, method, None)?;
        let mut est = Estimator::<CAP>::new(config).map_err(CheckpointError::InvalidConfig)?;
        read_state(image, method, Some(&mut est))?;
        Ok(est)
    }
}

/// Reads and checks every part of a verified image (see [`crate::checkpoint`]) whose header names
/// `method`, and returns its configuration. With `target`, also writes the state into it, after
/// resetting it in place to that configuration; without, stores nothing. The checks are the same
/// either way, so a target is written only by a pass that cannot fail once a pass without one has
/// succeeded.
fn read_state<const CAP: usize>(
    image: &[u8],
    method: Method,
    mut target: Option<&mut Estimator<CAP>>,
) -> Result<Config, CheckpointError> {
    let mut r = Reader::new(image, HEADER_LEN);
    let config = Config::read_checkpoint::<CAP>(&mut r, method)?;
    let running = read_running(&mut r)?;
    let grid = TimeGrid::read_checkpoint(&mut r, &config)?;
    let rotation = RotationMonitor::read_checkpoint(&mut r, &config)?;
    let period_samples = rotation.period_samples();
    if let Some(est) = target.as_deref_mut() {
        est.reinit(config).map_err(CheckpointError::InvalidConfig)?;
        running.apply(est);
        est.grid = grid;
        est.rotation = rotation;
    }
    GapFiller::read_checkpoint(&mut r, target.as_deref_mut().map(|est| &mut est.filler))?;
    r.seek(METHOD_OFFSET);
    // After `reinit` the target's method state is the image's method's.
    MethodState::read_checkpoint(&mut r, &config, period_samples, target.map(|est| &mut est.method))?;
    let padding_start = r.pos();
    r.seek(image.len() - CRC_LEN);
    r.zeros_since(padding_start, Part::Padding)?;
    Ok(config)
}

/// Bytes of the part.
pub(crate) const RUNNING_LEN: usize = 4 + (1 + 8) + 1 + R + 1 + 1 + 8 + SwayMonitor::CHECKPOINT_LEN + RejectReason::ALL.len() * 4 + 4 * 4;

/// The part, read and checked.
#[derive(Clone, Copy)]
struct Running {
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

fn write_running<const CAP: usize>(w: &mut Writer<'_>, e: &Estimator<CAP>) {
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
    e.sway.write_checkpoint(w);
    for n in e.rejected.0 {
        w.u32(n);
    }
    let c = &e.counters;
    for n in [c.accepted, c.filled, c.window_restarts, c.clock_steps] {
        w.u32(n);
    }
}

fn read_running(r: &mut Reader<'_>) -> Result<Running, CheckpointError> {
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
    let sway = SwayMonitor::read_checkpoint(r)?;
    let rejected = RejectCounts(core::array::from_fn(|_| r.u32()));
    let counters = Counters { accepted: r.u32(), filled: r.u32(), window_restarts: r.u32(), clock_steps: r.u32() };
    Ok(Running { index, feed_interval_s, gate_open, latitude_rad, window_status, fault, sway, rejected, counters })
}

impl Running {
    /// Writes the part into an estimator (after it has been reset to the image's configuration).
    fn apply<const CAP: usize>(&self, e: &mut Estimator<CAP>) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{image_of, refused, running, Est};
    use crate::checkpoint::{crc32, method_len, GAP_FILL_OFFSET, ROTATION_OFFSET, RUNNING_OFFSET, TIME_GRID_OFFSET};
    use crate::config::{Bound, ConfigError};
    use crate::methods::checkpoint::written_len;
    use std::vec;

    /// The methods of this build.
    const METHODS: &[Method] = if cfg!(feature = "paper-method") {
        &[Method::Windowed, Method::Paper, Method::Traditional]
    } else {
        &[Method::Windowed, Method::Traditional]
    };

    #[test]
    fn every_part_ends_where_the_layout_says_and_every_method_round_trips() {
        for &method in METHODS {
            let est = running(method);
            let mut buf = vec![0u8; Est::CHECKPOINT_LEN];
            let mut w = Writer::new(&mut buf, HEADER_LEN);
            est.config.write_checkpoint(&mut w);
            assert_eq!(w.pos(), RUNNING_OFFSET);
            write_running(&mut w, &est);
            assert_eq!(w.pos(), TIME_GRID_OFFSET);
            est.grid.write_checkpoint(&mut w);
            assert_eq!(w.pos(), ROTATION_OFFSET);
            est.rotation.write_checkpoint(&mut w);
            assert_eq!(w.pos(), GAP_FILL_OFFSET);
            est.filler.write_checkpoint(&mut w);
            assert_eq!(w.pos(), METHOD_OFFSET);
            let mut w = Writer::new(&mut buf, METHOD_OFFSET);
            est.method.write_checkpoint(&mut w);
            assert_eq!(w.pos(), METHOD_OFFSET + written_len(method, 64), "{method:?}");
            assert!(w.pos() <= Est::CHECKPOINT_LEN - CRC_LEN);

            let image = image_of(&est);
            assert_eq!(crc32(&image[..image.len() - 4]), u32::from_le_bytes(image[image.len() - 4..].try_into().unwrap()));
            let back = Est::from_checkpoint(&image).unwrap();
            assert_eq!(back, est, "{method:?}");
        }
        // The windowed method is the longest for any ring of more than 16 entries.
        assert_eq!(method_len(64), written_len(Method::Windowed, 64));
        assert_eq!(method_len(960), written_len(Method::Windowed, 960));
    }

    /// An estimator changed by `f`, checkpointed (the CRC is then valid), must be refused with
    /// `expected`.
    fn rejects(tampered: &Est, expected: CheckpointError) {
        refused(&image_of(tampered), expected);
    }

    fn accepts(state: &Est) {
        assert_eq!(Est::from_checkpoint(&image_of(state)).as_ref(), Ok(state));
    }

    #[test]
    fn a_tampered_configuration_or_estimator_part_is_refused_with_a_typed_error() {
        use CheckpointError::*;
        let base = running(Method::Windowed);
        let with = |f: &dyn Fn(&mut Est)| {
            let mut e = base.clone();
            f(&mut e);
            e
        };
        let param = |name: &'static str, value: f64, bound: Bound| InvalidConfig(ConfigError::Parameter { name, value, bound });
        rejects(&with(&|e| e.config.measurement_sigma_rad = -1.0), param("measurement_sigma_rad", -1.0, Bound::Positive));
        rejects(&with(&|e| e.config.max_filled_gap_samples = 4), param("max_filled_gap_samples", 4.0, Bound::AtMost(3.0)));
        // Regressions, fuzz target `checkpoint_restore`: a flipped exponent made the traditional
        // random walk 1e26 rad/sqrt(s), whose square is infinite in f32; a sigma whose square
        // underflows; a flipped top byte of the gap bridged (filled, now) made one step work for minutes.
        let huge = 2.0 * Real::MAX.sqrt();
        let bound = Bound::AtMost(1.0 / libm::sqrt(crate::config::SAMPLE_INTERVAL_RANGE_S.1));
        rejects(&with(&|e| e.config.traditional_drift_rad_per_sqrt_s = huge), param("traditional_drift_rad_per_sqrt_s", huge as f64, bound));
        let tiny = (if R == 4 { 1e-30 } else { 1e-200 }) as Real;
        rejects(&with(&|e| e.config.measurement_sigma_rad = tiny), param("measurement_sigma_rad", tiny as f64, Bound::SquareUnderflows));
        rejects(&with(&|e| e.config.max_filled_gap_samples = 0x6c00_0000), param("max_filled_gap_samples", f64::from(0x6c00_0000u32), Bound::AtMost(3.0)));
        rejects(&with(&|e| e.config.rotation_period_s = Some(10.0)), InvalidConfig(ConfigError::RotationPeriod { value_s: 10.0 }));
        rejects(&with(&|e| e.config.sample_interval_s = Some(f64::NAN)), InvalidConfig(ConfigError::SampleInterval { value_s: f64::NAN }));

        rejects(&with(&|e| e.latitude_trig.0 = 1.6), InvalidValue(Part::Latitude));
        rejects(&with(&|e| e.fault = Some((RotationFault::Stopped, f64::NAN))), InvalidValue(Part::Fault));
        accepts(&with(&|e| e.fault = Some((RotationFault::Stopped, -1.0))));
        accepts(&with(&|e| e.fault = Some((RotationFault::Reversed, 12.0))));
    }
}
