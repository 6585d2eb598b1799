//! The estimator in a checkpoint image: [`Estimator::checkpoint`], [`Estimator::restore`] and
//! [`Estimator::from_checkpoint`], the parts in their order (the one place that knows them; the
//! header, CRC and the [`Stored`] trait are in [`crate::checkpoint`]), and the estimator's own
//! part.
//!
//! # The parts, in order
//! | part | type | file |
//! |---|---|---|
//! | configuration | [`Config`] | `config/checkpoint.rs` |
//! | the estimator's running state | [`Running`] | here |
//! | the sample grid | [`TimeGrid`] | `time_grid/checkpoint.rs` |
//! | the rotation monitor | [`RotationMonitor`] | `rotation_pattern/checkpoint.rs` |
//! | the fill-error estimate | `FillError` | `gap_fill/checkpoint.rs` |
//! | the method's filter | `MethodPart` | `methods/checkpoint.rs` |
//!
//! # The estimator's own part
//! Grid index (u32), the interval the grid's constants were fixed from (optional f64: absent
//! until samples are fed; the constants, [`Feed`], are derived from it again), gate open (flag),
//! the last rotation fault (u8: 0 none, else the [`Status::code`](crate::Status::code) of that
//! fault) and the sample time it began at (f64, zero without a fault), the sway monitor (see
//! `sway_gate/checkpoint.rs`), rejected counts ([`RejectReason::ALL`] x u32), counters (accepted,
//! filled, window restarts, clock steps, changes detected, samples in model mismatch: u32 each),
//! the last change of the errors declared
//! (optional: the sample time it was declared at and the time the residuals showed it from, f64
//! each, and the errors learned again, a u8 with bits 0-3 for x1..x4).
//!
//! Checked: flags and codes; the feed interval positive and finite; the fault's time finite (a
//! time stamp); a change's times finite and at least one error learned again, no other bit set.

use super::{Estimator, Feed};
use crate::checkpoint::image::{seal, verified_image, write_header};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{ensure, CheckpointError, Part, Stored, CRC_LEN, HEADER_LEN};
use crate::config::checkpoint::ConfigContext;
use crate::config::Config;
use crate::gap_fill::checkpoint::FillError;
use crate::methods::checkpoint::MethodPart;
use crate::output::{Counters, ErrorChange, RejectCounts, Status};
use crate::rotation_pattern::{RotationFault, RotationMonitor};
use crate::sample::RejectReason;
use crate::sway_gate::SwayMonitor;
use crate::time_grid::TimeGrid;

/// Where the parts end: the configuration, the running state, the grid, the rotation monitor,
/// the fill error, the method.
const PARTS_END: usize = HEADER_LEN
    + Config::LEN
    + Running::LEN
    + TimeGrid::LEN
    + RotationMonitor::LEN
    + FillError::LEN
    + MethodPart::LEN;

/// Bytes of a checkpoint image, whatever the ring capacity: the header, the parts, zero padding
/// to a multiple of 4 (so that a flash with 4-byte writes takes it as it is) and the CRC (the
/// length with `f32` and with the `f64` feature is pinned by `checkpoint::tests::image_length`).
pub const CHECKPOINT_LEN: usize = PARTS_END.div_ceil(4) * 4 + CRC_LEN;

impl<const CAP: usize> Estimator<CAP> {
    /// Bytes of a checkpoint image ([`CHECKPOINT_LEN`], the same for every capacity).
    pub const CHECKPOINT_LEN: usize = CHECKPOINT_LEN;

    /// Writes what a restart keeps (see [`crate::checkpoint`]) into `buf[..CHECKPOINT_LEN]`;
    /// returns the bytes written. A shorter buffer is refused and left as it is.
    pub fn checkpoint(&self, buf: &mut [u8]) -> Result<usize, CheckpointError> {
        let available = buf.len();
        let Some(image) = buf.get_mut(..CHECKPOINT_LEN) else {
            return Err(CheckpointError::BufferTooSmall {
                needed: CHECKPOINT_LEN,
                available,
            });
        };
        image.fill(0);
        let mut w = Writer::new(image, 0);
        write_header(&mut w, self.config.method);
        self.config.write(&mut w);
        Running::of(self).write(&mut w);
        self.run.grid.write(&mut w);
        // Without its sample history, which a restored monitor forgets (so that an image restored
        // and written again is the same image).
        let mut rotation = self.run.rotation;
        rotation.restart();
        rotation.write(&mut w);
        self.run.filler.fill_error().write(&mut w);
        self.method.learned().write(&mut w);
        debug_assert_eq!(w.pos(), PARTS_END);
        seal(image);
        Ok(CHECKPOINT_LEN)
    }

    /// Continues from the image in `buf` (which may be longer than the image): the
    /// configuration, the filter and what was learned are the image's; the window, the gap
    /// filler's delay line and the references' low-pass start empty, as after a long gap, so the
    /// estimate is reported at once and [`Status::Holding`] says that the window is refilling. On
    /// any error the estimator is left exactly as it was.
    ///
    /// The image is read twice: the first pass reads and checks every part and keeps none; once
    /// all have passed, the estimator is reset in place to the image's configuration
    /// ([`Estimator::reset`]'s way) and the second pass reads each part again and hands it over.
    /// So at most one part (a few hundred bytes) is on the stack at a time, and no second
    /// estimator passes through it (a change of method builds that method's state by value: see
    /// [`crate::methods::MethodState::reset`]): the firmware restores at start-up within its
    /// 4 KiB of stack.
    pub fn restore(&mut self, buf: &[u8]) -> Result<(), CheckpointError> {
        let (image, method) = verified_image(buf)?;
        let config = read_parts::<CAP>(image, method, None)?;
        // The same bytes pass the same checks again, so this cannot fail half-way.
        self.reinit(config)
            .map_err(CheckpointError::InvalidConfig)?;
        read_parts(image, method, Some(self)).map(|_| ())
    }

    /// A new estimator from a checkpoint image (see [`Estimator::restore`]). Builds the estimator
    /// by value: for hosts, not for a microcontroller's stack.
    pub fn from_checkpoint(buf: &[u8]) -> Result<Self, CheckpointError> {
        let (image, method) = verified_image(buf)?;
        let config = read_parts::<CAP>(image, method, None)?;
        let mut est = Estimator::<CAP>::new(config).map_err(CheckpointError::InvalidConfig)?;
        read_parts(image, method, Some(&mut est))?;
        Ok(est)
    }
}

/// Reads and checks every part of a verified image whose header names `method`, in order, and
/// returns its configuration. With `target` (an estimator already reset to that configuration),
/// also hands each part over as it is read: the window, delay line and references' low-pass stay
/// empty and the rotation monitor forgets its sample history, as after a long gap.
#[inline(never)]
fn read_parts<const CAP: usize>(
    image: &[u8],
    method: crate::config::Method,
    mut target: Option<&mut Estimator<CAP>>,
) -> Result<Config, CheckpointError> {
    let mut r = Reader::new(image, HEADER_LEN);
    let config = Config::read(
        &mut r,
        ConfigContext {
            method,
            capacity: CAP,
        },
    )?;
    let running = Running::read(&mut r, ())?;
    if let Some(e) = target.as_deref_mut() {
        running.apply(e);
    }
    let grid = TimeGrid::read(&mut r, &config)?;
    if let Some(e) = target.as_deref_mut() {
        e.run.grid = grid;
    }
    let period = read_rotation(&mut r, &config, target.as_deref_mut())?;
    let fill = FillError::read(&mut r, ())?;
    if let Some(e) = target.as_deref_mut() {
        e.run.filler.keep_fill_error(fill);
    }
    read_method_part(&mut r, &config, target, period)?;
    let padding_start = r.pos();
    r.skip(CHECKPOINT_LEN - CRC_LEN - padding_start);
    r.zeros_since(padding_start, Part::Padding)?;
    Ok(config)
}

/// The rotation monitor's part, handed over to `target` when given; returns the period it knows,
/// samples. Out of line, as [`read_method_part`].
#[inline(never)]
fn read_rotation<const CAP: usize>(
    r: &mut Reader<'_>,
    config: &Config,
    target: Option<&mut Estimator<CAP>>,
) -> Result<Option<u32>, CheckpointError> {
    let mut rotation = RotationMonitor::read(r, config)?;
    rotation.restart();
    let period = rotation.period_samples();
    if let Some(e) = target {
        e.run.rotation = rotation;
    }
    Ok(period)
}

/// The method's part (the filter and what it learned), handed over to `target` when given, with
/// the window set to `period` when the interval is known. Out of line: the part (the largest, over
/// a kilobyte) is on the stack only while it is read, not for the whole of [`read_parts`] (the
/// start-up's 4 KiB of stack).
#[inline(never)]
fn read_method_part<const CAP: usize>(
    r: &mut Reader<'_>,
    config: &Config,
    target: Option<&mut Estimator<CAP>>,
    period: Option<u32>,
) -> Result<(), CheckpointError> {
    let method_part = MethodPart::read(r, config)?;
    if let Some(e) = target {
        e.method.keep_learned(method_part);
        match (e.run.feed, period) {
            (Some(_), Some(p)) => e.method.configure(p),
            (Some(feed), None) => e
                .method
                .expect_period(super::feed::expected_period_samples(feed.interval_s)),
            (None, _) => {}
        }
        e.run.window_status = if period.is_some() {
            Status::WarmingUp
        } else {
            Status::DetectingPattern
        };
    }
    Ok(())
}

/// The estimator's own running state (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Running {
    index: u32,
    feed_interval_s: Option<f64>,
    gate_open: bool,
    fault: Option<(RotationFault, f64)>,
    sway: SwayMonitor,
    rejected: RejectCounts,
    counters: Counters,
    error_change: Option<ErrorChange>,
}

impl Running {
    /// Hands the part over to an estimator reset to the image's configuration.
    fn apply<const CAP: usize>(&self, e: &mut Estimator<CAP>) {
        e.run.index = self.index;
        // The constants are derived from the interval alone, exactly as when they were fixed.
        e.run.feed = self.feed_interval_s.map(|d| Feed::new(d, &e.config));
        e.run.gate_open = self.gate_open;
        e.run.fault = self.fault;
        e.run.sway = self.sway;
        e.run.rejected = self.rejected;
        e.run.counters = self.counters;
        e.run.error_change = self.error_change;
    }

    fn of<const CAP: usize>(e: &Estimator<CAP>) -> Running {
        Running {
            index: e.run.index,
            feed_interval_s: e.run.feed.map(|f| f.interval_s),
            gate_open: e.run.gate_open,
            fault: e.run.fault,
            sway: e.run.sway,
            rejected: e.run.rejected,
            counters: e.run.counters,
            error_change: e.run.error_change,
        }
    }
}

impl Stored for Running {
    const LEN: usize = 4
        + (1 + 8)
        + 1
        + 1
        + 8
        + SwayMonitor::LEN
        + RejectReason::ALL.len() * 4
        + 6 * 4
        + (1 + 8 + 8 + 1);
    type Context<'a> = ();

    fn write(&self, w: &mut Writer<'_>) {
        w.u32(self.index);
        w.option(self.feed_interval_s, 0.0, |w, v| w.f64(v));
        w.flag(self.gate_open);
        match self.fault {
            Some((fault, since_s)) => {
                w.u8(Status::RotationFault(fault).code());
                w.f64(since_s);
            }
            None => {
                w.u8(0);
                w.f64(0.0);
            }
        }
        self.sway.write(w);
        for n in self.rejected.0 {
            w.u32(n);
        }
        let c = &self.counters;
        for n in [
            c.accepted,
            c.filled,
            c.window_restarts,
            c.clock_steps,
            c.changes_detected,
            c.mismatch_samples,
        ] {
            w.u32(n);
        }
        let zero = ErrorChange {
            detected_s: 0.0,
            seen_since_s: 0.0,
            relearned: [false; 4],
        };
        w.option(self.error_change, zero, |w, c| {
            w.f64(c.detected_s);
            w.f64(c.seen_since_s);
            w.u8(c
                .relearned
                .iter()
                .enumerate()
                .fold(0, |b, (i, f)| b | (u8::from(*f) << i)));
        });
    }

    fn read(r: &mut Reader<'_>, (): ()) -> Result<Running, CheckpointError> {
        let index = r.u32();
        let feed_interval_s = r.option(Part::Estimator, |r| Ok(r.f64()))?;
        // The interval the grid's constants were fixed from: positive and finite.
        ensure(
            feed_interval_s.is_none_or(|d| d.is_finite() && d > 0.0),
            CheckpointError::InvalidValue(Part::Estimator),
        )?;
        let gate_open = r.flag(Part::Estimator)?;
        let fault_code = r.u8();
        let since_start = r.pos();
        let since_s = r.f64();
        let fault = match (fault_code, Status::try_from(fault_code).ok()) {
            (0, _) => {
                r.zeros_since(since_start, Part::Fault)?;
                None
            }
            (_, Some(Status::RotationFault(fault))) => {
                ensure(
                    since_s.is_finite(),
                    CheckpointError::InvalidValue(Part::Fault),
                )?;
                Some((fault, since_s))
            }
            _ => return Err(CheckpointError::InvalidValue(Part::Fault)),
        };
        let sway = SwayMonitor::read(r, ())?;
        let rejected = RejectCounts(core::array::from_fn(|_| r.u32()));
        let counters = Counters {
            accepted: r.u32(),
            filled: r.u32(),
            window_restarts: r.u32(),
            clock_steps: r.u32(),
            changes_detected: r.u32(),
            mismatch_samples: r.u32(),
        };
        let error_change = r.option(Part::Estimator, |r| Ok((r.f64(), r.f64(), r.u8())))?;
        if let Some((detected_s, seen_since_s, bits)) = error_change {
            let ok =
                detected_s.is_finite() && seen_since_s.is_finite() && bits != 0 && bits & 0xF0 == 0;
            ensure(ok, CheckpointError::InvalidValue(Part::Estimator))?;
        }
        let error_change = error_change.map(|(detected_s, seen_since_s, bits)| ErrorChange {
            detected_s,
            seen_since_s,
            relearned: core::array::from_fn(|i| bits & (1 << i) != 0),
        });
        Ok(Running {
            index,
            feed_interval_s,
            gate_open,
            fault,
            sway,
            rejected,
            counters,
            error_change,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::{image_of, refused, reseal, running, written_and_read, Est};
    use crate::config::Method;

    /// The methods of this build.
    const METHODS: &[Method] = if cfg!(feature = "paper-method") {
        &[Method::Windowed, Method::Paper, Method::Traditional]
    } else {
        &[Method::Windowed, Method::Traditional]
    };

    #[test]
    fn every_part_writes_its_length_and_every_method_round_trips() {
        for &method in METHODS {
            let est = running(method);
            let config = est.config;
            assert_eq!(
                written_and_read(
                    &config,
                    ConfigContext {
                        method,
                        capacity: 64
                    }
                ),
                Ok(config)
            );
            assert_eq!(
                written_and_read(&Running::of(&est), ()),
                Ok(Running::of(&est))
            );
            assert_eq!(written_and_read(&est.run.grid, &config), Ok(est.run.grid));
            assert_eq!(
                written_and_read(&est.run.rotation, &config),
                Ok(est.run.rotation)
            );
            assert_eq!(
                written_and_read(&est.run.filler.fill_error(), ()),
                Ok(est.run.filler.fill_error())
            );
            assert_eq!(
                written_and_read(&est.method.learned(), &config),
                Ok(est.method.learned())
            );

            // The whole image: what the restored estimator holds, it writes again byte for byte.
            let image = image_of(&est);
            let back = Est::from_checkpoint(&image).unwrap();
            assert_eq!(image_of(&back), image, "{method:?}");
            assert_eq!(back.estimate(), est.estimate(), "{method:?}");
            assert_eq!(back.counters(), est.counters());
        }
    }

    #[test]
    fn a_tampered_running_part_is_refused_with_a_typed_error() {
        use CheckpointError::*;
        let base = Running::of(&running(Method::Windowed));
        let with = |edit: &dyn Fn(&mut Running)| {
            let mut t = base;
            edit(&mut t);
            written_and_read(&t, ())
        };
        assert_eq!(
            with(&|r| r.feed_interval_s = Some(0.0)),
            Err(InvalidValue(Part::Estimator))
        );
        assert_eq!(
            with(&|r| r.fault = Some((RotationFault::Stopped, f64::NAN))),
            Err(InvalidValue(Part::Fault))
        );
        assert!(with(&|r| r.fault = Some((RotationFault::Stopped, -1.0))).is_ok());
        assert!(with(&|r| r.fault = Some((RotationFault::Reversed, 12.0))).is_ok());
        let change = ErrorChange {
            detected_s: 30_000.0,
            seen_since_s: 28_800.0,
            relearned: [true, false, false, true],
        };
        assert_eq!(
            with(&|r| r.error_change = Some(change)).map(|r| r.error_change),
            Ok(Some(change))
        );
        let no_error = ErrorChange {
            relearned: [false; 4],
            ..change
        };
        assert_eq!(
            with(&|r| r.error_change = Some(no_error)),
            Err(InvalidValue(Part::Estimator))
        );
        let no_time = ErrorChange {
            detected_s: f64::INFINITY,
            ..change
        };
        assert_eq!(
            with(&|r| r.error_change = Some(no_time)),
            Err(InvalidValue(Part::Estimator))
        );

        // Bytes no value can hold, in a whole image: the feed interval's flag, the fault's code
        // and a time without a fault.
        let image = image_of(&running(Method::Windowed));
        let at = HEADER_LEN + Config::LEN;
        let edit = |offset: usize, v: u8| {
            let mut b = image.clone();
            b[at + offset] = v;
            reseal(&mut b);
            b
        };
        refused(&edit(4, 2), InvalidValue(Part::Estimator));
        refused(&edit(14, 4), InvalidValue(Part::Fault));
        refused(&edit(14, 0x10), InvalidValue(Part::Fault));
        refused(&edit(15, 1), UnusedNotZero(Part::Fault));
    }

    #[test]
    fn a_configuration_the_estimator_cannot_run_is_refused() {
        use crate::config::{Bound, ConfigError};
        use crate::Real;
        use CheckpointError::InvalidConfig;
        let config = running(Method::Windowed).config;
        let cx = ConfigContext {
            method: Method::Windowed,
            capacity: 64,
        };
        let with = |edit: &dyn Fn(&mut Config)| {
            let mut c = config;
            edit(&mut c);
            written_and_read(&c, cx)
        };
        let param = |name: &'static str, value: f64, bound: Bound| {
            Err(InvalidConfig(ConfigError::Parameter { name, value, bound }))
        };
        assert_eq!(
            with(&|c| c.measurement_sigma_rad = -1.0),
            param("measurement_sigma_rad", -1.0, Bound::Positive)
        );
        assert_eq!(
            with(&|c| c.max_filled_gap_samples = 4),
            param("max_filled_gap_samples", 4.0, Bound::AtMost(3.0))
        );
        // Regressions, fuzz target `checkpoint_restore`: a flipped exponent made the traditional
        // random walk 1e26 rad/sqrt(s), whose square is infinite in f32; a sigma whose square
        // underflows; a flipped top byte of the gap bridged made one step work for minutes.
        let huge = 2.0 * Real::MAX.sqrt();
        let bound = Bound::AtMost(1.0 / libm::sqrt(crate::config::SAMPLE_INTERVAL_RANGE_S.1));
        assert_eq!(
            with(&|c| c.traditional_drift_rad_per_sqrt_s = huge),
            param("traditional_drift_rad_per_sqrt_s", huge as f64, bound)
        );
        let tiny = (if crate::checkpoint::R == 4 {
            1e-30
        } else {
            1e-200
        }) as Real;
        assert_eq!(
            with(&|c| c.measurement_sigma_rad = tiny),
            param(
                "measurement_sigma_rad",
                tiny as f64,
                Bound::SquareUnderflows
            )
        );
        assert_eq!(
            with(&|c| c.max_filled_gap_samples = 0x6c00_0000),
            param(
                "max_filled_gap_samples",
                f64::from(0x6c00_0000u32),
                Bound::AtMost(3.0)
            )
        );
        assert_eq!(
            with(&|c| c.rotation_period_s = Some(10.0)),
            Err(InvalidConfig(ConfigError::RotationPeriod { value_s: 10.0 }))
        );
        assert_eq!(
            with(&|c| c.sample_interval_s = Some(f64::NAN)),
            Err(InvalidConfig(ConfigError::SampleInterval {
                value_s: f64::NAN
            }))
        );
        // An absent pinned period with a non-zero value.
        let mut b = image_of(&running(Method::Windowed));
        assert_eq!(b[HEADER_LEN], 0);
        b[HEADER_LEN + 3] = 1;
        reseal(&mut b);
        refused(&b, CheckpointError::UnusedNotZero(Part::Config));
    }
}
