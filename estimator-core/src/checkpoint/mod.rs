//! Checkpoint and restore: the whole estimator state as a fixed-size, versioned, CRC-protected
//! byte image, so that a restarted firmware continues exactly where it stopped.
//!
//! [`Estimator::checkpoint`] writes the image into a caller-provided buffer of at least
//! [`Estimator::CHECKPOINT_LEN`] bytes ([`CHECKPOINT_LEN`] for the default capacity of
//! [`DEFAULT_CAPACITY`] = 720 entries: **23 384 bytes** with `f32`, 24 416 with the `f64`
//! feature; a multiple of 4, so that a NOR flash with 4-byte writes takes it as it is).
//! [`Estimator::restore`] reads one back. Restoring an image into a fresh estimator and continuing
//! gives outputs bit-identical to the uninterrupted run, whatever the phase of the cut: the sample
//! interval being learned, the rotation period being detected, the pattern's features being
//! learned, filled gaps waiting in the delay line, a bin half filled, a fault, holding, estimating
//! (`tests/checkpoint_roundtrip.rs`).
//!
//! The image carries the configuration; restoring replaces the estimator's configuration with the
//! image's (which must pass [`Config::check`] for this `CAP`).
//!
//! # Validation
//! Restore checks, in this order, and returns the first failure as a [`CheckpointError`]: magic,
//! version, float width, ring capacity, the length in the header, the CRC-32 over everything
//! before it; then every field, part by part:
//! - the configuration must pass [`Config::check`];
//! - every float is finite and within its range (the bounds are in each part's codec: angles
//!   within what [`crate::Sample::check`] lets through, the latitude below 90 deg, ratios and
//!   variances non-negative, Kalman states within [`MAX_STATE`], variances within
//!   [`MAX_VARIANCE`] or four times the prior, residual means within [`MAX_RESIDUAL`]), so that
//!   every output of the restored estimator is finite;
//! - every covariance is exactly symmetric and positive definite (Cholesky);
//! - every window is consistent: length and bin equal to what the rotation period gives (once it
//!   is known), head and fill count in range, every stored entry within the fixed-point range, a
//!   bin being filled holding fewer samples than a bin, and the running sums equal to the exact
//!   sums recomputed from the stored entries ([`crate::correlation::CorrelationSums::add`] over
//!   the entries in the window);
//! - indices in range (reference angles, directions, the delay line's slots and its next index);
//! - flags 0 or 1, codes known, every unused byte zero (an absent optional value, the padding).
//!
//! Nothing is written before all of this has passed, so on any error the estimator is untouched;
//! then the state is written in place (see [`Estimator::restore`]: no second estimator on the
//! stack).
//!
//! # Versions
//! [`VERSION`] is the only version read. An image of another version is refused with
//! [`CheckpointError::Version`]: version 1 and 2 images (written before the sample grid, the
//! rotation pattern monitor and the gap filler, with a pinned period and a 480-entry ring) and
//! version 3 images (without the windowed method's learned noise scale and random walk) hold
//! too little to continue from, and must be discarded; the estimator then starts afresh.
//!
//! # Layout
//! Little-endian; `R` = bytes of [`Real`] (4, or 8 with the `f64` feature). An optional value is a
//! flag byte (0 absent, 1 present) followed by the value, all zero when absent.
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 4 | magic `b"RIEC"` |
//! | 4 | 2 | version ([`VERSION`]) |
//! | 6 | 1 | `R` |
//! | 7 | 1 | method code ([`Method`] `as u8`) |
//! | 8 | 4 | `CAP` |
//! | 12 | 4 | total length including the CRC (= `CHECKPOINT_LEN`) |
//! | 16 | [`COMMON_LEN`] | the common part: configuration, estimator, sample grid, rotation monitor, gap filler |
//! | [`METHOD_OFFSET`] | `method_len(CAP)` | the method's state, zero-padded to the longest method and to a multiple of 4 |
//! | `CHECKPOINT_LEN - 4` | 4 | CRC-32 ([`crc32`]) of all bytes before it |
//!
//! # Parts
//! Each part's fields, in order (the checks on them are summarised above). Each part is written
//! and read next to its type, in the `checkpoint.rs` of the type's module (`time_grid/`,
//! `rotation_pattern/`, `gap_fill/`, `moving_average/`, `kalman/`, `methods/windowed/`, ...), so
//! that the type's fields stay private; that file lists the part's checks in full. This module
//! keeps the format: the header and CRC (`image.rs`), the byte reader and writer (`wire.rs`), the
//! errors and the bounds.
//!
//! - **Configuration** (22 + 8 `R` bytes): `rotation_period_s` (optional f64),
//!   `sample_interval_s` (optional f64), `prior_sigma_rad`, `measurement_sigma_rad`,
//!   `drift_rad_per_sqrt_s`, `traditional_sigma_rad`, `traditional_drift_rad_per_sqrt_s`,
//!   `sway_gate_rad`, `converged_sigma_rad`, `rotation_period_tolerance` (`R` each),
//!   `max_filled_gap_samples` (u32).
//! - **Estimator** (64 + 3 `R` bytes): grid index (u32), the interval the grid's constants were
//!   fixed from (optional f64: absent until samples are fed), gate open (flag), latitude
//!   (`R`; its sine and cosine are recomputed), status of the newest sample the window took
//!   ([`Status::code`](crate::Status::code), u8), the last rotation fault (u8: 0 none, else the
//!   [`Status::code`](crate::Status::code) of that fault) and the sample time it began at (f64, zero
//!   without a fault), sway monitor (mean `R`, mean square `R`, samples u32), rejected counts
//!   ([`RejectReason::ALL`](crate::RejectReason::ALL) x u32), counters (accepted, filled, window
//!   restarts, clock steps: u32 each).
//! - **Sample grid** (103 bytes): interval (optional f64), pinned (flag), the previous accepted
//!   stamp (optional f64), the learning steps ([`LEARNING_STEPS`](crate::time_grid::LEARNING_STEPS) x
//!   f64), steps learned (u32), mean one-interval step (f64), steps in that mean (u32), clock steps
//!   (u32).
//! - **Rotation monitor** (129 + 4 `R` bytes): period (optional u32, samples), pinned (flag),
//!   features (optional: direction i8, reverses flag, longest dwell u32), reference angles (optional
//!   `R`), side of each reference angle ([`LEVELS`](crate::rotation_pattern::LEVELS) x i8), last pass
//!   of each reference angle and direction ([`LEVELS`](crate::rotation_pattern::LEVELS) x 2 optional
//!   u32), the timing pass (optional: reference angle u8, direction u8), previous sample (optional:
//!   index u32, rotation angle `R`), short mean increment `R`, its steps u32, the cycle being learned
//!   (start: optional u32, net rotation `R`), dwell run u32, longest dwell u32, first direction i8,
//!   reversed flag.
//! - **Gap filler** (13 + 2 `R` + 16 (7 + 11 `R`) bytes): the newest index (optional u32), the next
//!   index to pass on (u32), the mean square prediction error of roll and of pitch (`R` each),
//!   samples averaged (u32), then the [`SLOTS`](crate::gap_fill::SLOTS) slots (each an optional
//!   [`GridSample`](crate::gap_fill::GridSample): index u32, roll, pitch, rotation, rotation minus
//!   platform, latitude, then the trigonometry sin rho, cos rho, sin(rho - s), cos(rho - s), sin L,
//!   cos L, all `R`, and the fill weight u16).
//! - **Method part**, by method (`method_len(CAP)` is the longest: the windowed method's for any
//!   ring of more than 16 entries; `methods/checkpoint.rs` has its exact length):
//!   - windowed: updates u32, window entries since the last update u32, Kalman filter (`x` 4 `R`,
//!     `P` 16 `R` row-major), residual means 4 `R`, the pair the next update takes (u8: 0 pitch,
//!     1 roll), residuals averaged per pair 2 x u32, channel gains 4 `R`, the per-product variances
//!     of the pitch and roll channels 2 `R`, the long means of the residual means 4 `R` and of
//!     their powers 4 `R`, the residual means in the long averages per pair 2 x u32, the noise
//!     scale and the drift share per pair 2 + 2 `R`, the reference's low-pass (started flag, then three
//!     stages of 4 `R`, all zero before it starts), a correlation window (entries of 30 bytes:
//!     roll, pitch i32, six sines and cosines, four low-passed references i16, fill weight u16);
//!   - paper: updates u32, samples u32, start time f64, integrals 4 x i64, four Kalman filters (`x`
//!     3 f64, `P` 9 f64 each), a plain window of 4 channels;
//!   - traditional: updates u32, Kalman filter (`x` 4 `R`, `P` 16 `R`).
//! - A **correlation window** is: length, head, fill count, samples per bin (u32 each); the running
//!   sums (count u32, 28 x i64, fill weight u32); the bin being filled (samples u32; sums of roll,
//!   pitch and latitude; the first sample's rotation angle and the sum of the offsets from it; the
//!   same for rotation minus platform: 7 `R`; fill weight u32); then the `CAP` ring entries, each
//!   roll and pitch (i32), sin rho, cos rho, sin(rho - s), cos(rho - s), sin L, cos L and the four
//!   low-passed references (i16) and its fill weight (u16). The window's entries, oldest first, are
//!   the `filled` slots from slot `head` on (wrapping at the length) once it is full, the first
//!   `filled` slots while it fills; this writer puts the oldest in slot 0 and zeros in the spare
//!   slots, and the reader ignores what spare slots hold (older writers left stale entries there)
//!   beyond checking its range.
//! - A **plain window** is: length, head, fill count (u32 each), the running sums (`CH` x i64),
//!   then the ring, `CAP` x `CH` x i32 (slot-major), its entries placed as in a correlation window.

pub(crate) mod image;
#[cfg(test)]
pub(crate) mod tests;
pub(crate) mod wire;

use crate::config::{Config, ConfigError};
#[cfg(doc)]
use crate::config::Method;
use crate::estimator::DEFAULT_CAPACITY;
#[cfg(doc)]
use crate::estimator::Estimator;
use crate::gap_fill::GapFiller;
use crate::rotation_pattern::RotationMonitor;
use crate::time_grid::TimeGrid;
use crate::Real;

/// First four bytes of every image.
pub const MAGIC: [u8; 4] = *b"RIEC";
/// Format version written and the only one read.
pub const VERSION: u16 = 4;
/// Bytes of the header.
pub const HEADER_LEN: usize = 16;
/// Bytes of the CRC at the end.
pub const CRC_LEN: usize = 4;

/// Largest magnitude a restored Kalman state may have (rad, or correlation units for the paper's
/// bias states). Every measurement is a window mean of values clamped to +-2 and the states are
/// installation errors of arcseconds to degrees, so no running estimator comes near; the bound keeps
/// a crafted image with a finite but huge state (which would overflow the outputs, or turn
/// infinite when the paper's `f64` states are narrowed to `f32`) from being accepted.
pub const MAX_STATE: f64 = 1e3;
/// Largest magnitude of a restored residual mean of the windowed method: a residual is a window
/// mean (|m| <= 2) minus `H x` (|H x| <= 8 [`MAX_STATE`]).
pub const MAX_RESIDUAL: f64 = 1e4;
/// Largest restored variance, unless the configured prior is larger: `max(1e12, 4 prior^2)`. The
/// covariance starts at `prior^2` and a measurement update never increases it; only the (tiny)
/// random walk does.
pub const MAX_VARIANCE: f64 = 1e12;

/// Bytes of a [`Real`].
pub(crate) const R: usize = core::mem::size_of::<Real>();

/// Offset of the estimator's own part (after the header and the configuration).
pub(crate) const RUNNING_OFFSET: usize = HEADER_LEN + Config::CHECKPOINT_LEN;
/// Offset of the sample grid part.
pub(crate) const TIME_GRID_OFFSET: usize = RUNNING_OFFSET + crate::estimator::checkpoint::RUNNING_LEN;
/// Offset of the rotation monitor part.
pub(crate) const ROTATION_OFFSET: usize = TIME_GRID_OFFSET + TimeGrid::CHECKPOINT_LEN;
/// Offset of the gap filler part.
pub(crate) const GAP_FILL_OFFSET: usize = ROTATION_OFFSET + RotationMonitor::CHECKPOINT_LEN;

/// Bytes of the common part (configuration, estimator, sample grid, rotation monitor, gap filler).
pub const COMMON_LEN: usize = GAP_FILL_OFFSET + GapFiller::CHECKPOINT_LEN - HEADER_LEN;
/// Offset of the method part.
pub const METHOD_OFFSET: usize = HEADER_LEN + COMMON_LEN;

/// Bytes of the method part for ring capacity `cap`: the longest of the three methods.
pub const fn method_len(cap: usize) -> usize {
    crate::methods::checkpoint::max_len(cap)
}

/// Total image length for ring capacity `cap`: header, common part, method part, padding to a
/// multiple of 4, CRC.
pub const fn checkpoint_len(cap: usize) -> usize {
    (METHOD_OFFSET + method_len(cap)).div_ceil(4) * 4 + CRC_LEN
}

/// Image length for the default capacity ([`DEFAULT_CAPACITY`]): 23 384 bytes with `f32`.
pub const CHECKPOINT_LEN: usize = checkpoint_len(DEFAULT_CAPACITY);

/// The CRC-32/ISO-HDLC without a table (see [`crc32`]).
static CRC32: crc::Crc<u32, crc::NoTable> = crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);

/// The CRC-32 the image ends with, of `bytes`: IEEE 802.3, reflected, init and final xor `0xFFFFFFFF` (zlib's
/// `crc32`, the catalogue's CRC-32/ISO-HDLC); `crc32(b"123456789") == 0xCBF43926`.
///
/// Bit by bit (`NoTable`), chosen by flash: the code and data of this function for the Cortex-M4F
/// take 1,608 bytes without a table, 2,066 with `Table<1>` (a 1 KiB table) and 17,744 with
/// `Table<16>` (16 KiB), for a computation the firmware makes once per checkpoint and once per
/// restore. Measured with `cargo build -p estimator-core --target thumbv7em-none-eabihf --release
/// --no-default-features` and `llvm-nm -S --size-sort -C
/// target/thumbv7em-none-eabihf/release/libestimator_core.rlib | grep -i crc` (the sizes of
/// `crc32`, the `CRC32` static and the `crc` crate's functions it instantiates).
pub fn crc32(bytes: &[u8]) -> u32 {
    CRC32.checksum(bytes)
}

/// A part of the image, named in errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The configuration.
    Config,
    /// The grid index, the feed interval and the gate flag.
    Estimator,
    /// The cached latitude.
    Latitude,
    /// The status of the newest sample the window took.
    Status,
    /// The last rotation fault and its time.
    Fault,
    /// The sway monitor of the start gate.
    SwayMonitor,
    /// The sample grid: interval, stamps, learning steps.
    TimeGrid,
    /// The rotation monitor: period, reference angles, passes, short mean, the cycle being learned.
    RotationMonitor,
    /// The learned features of the rotation pattern.
    Features,
    /// The gap filler's delay line: its slots and indices.
    DelayLine,
    /// The gap filler's fill-error estimate.
    FillError,
    /// A Kalman filter's states.
    KalmanState,
    /// A Kalman filter's covariance.
    KalmanCovariance,
    /// A window's length, bin, head and fill count.
    WindowIndices,
    /// A window's stored entries.
    WindowEntries,
    /// A window's running sums.
    WindowSums,
    /// The bin being filled.
    Bin,
    /// The windowed method's residual means and channel gains.
    Residuals,
    /// The paper method's integrals.
    PaperIntegrals,
    /// The paper method's start time.
    PaperStartTime,
    /// The bytes after the method's state.
    Padding,
}

/// Why a checkpoint could not be written or restored. Restore leaves the estimator untouched on
/// every one of these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckpointError {
    /// The buffer is shorter than the image.
    BufferTooSmall { needed: usize, available: usize },
    /// The first four bytes are not [`MAGIC`].
    BadMagic,
    /// The image has another format version than this firmware's [`VERSION`] (see the module
    /// doc: an older image must be discarded).
    Version { found: u16, expected: u16 },
    /// Written with another float width (`f32` vs `f64` feature); the value is the image's bytes.
    RealWidthMismatch(u8),
    /// Written by an estimator of another ring capacity; the value is the image's.
    CapacityMismatch(u32),
    /// The header's length is not this estimator's `CHECKPOINT_LEN`.
    LengthMismatch { expected: usize, found: usize },
    /// The CRC-32 does not match the content.
    CrcMismatch { stored: u32, computed: u32 },
    /// The method code is unknown.
    UnknownMethod(u8),
    /// The configuration does not pass [`Config::check`].
    InvalidConfig(ConfigError),
    /// A value is NaN, infinite or out of its range, a flag is not 0 or 1, a code is unknown.
    InvalidValue(Part),
    /// A covariance is not exactly symmetric or not positive definite.
    NotPositiveDefinite(Part),
    /// Values that must agree do not (window indices and running sums, delay-line slots).
    Inconsistent(Part),
    /// A byte that must be zero (an absent optional value, padding) is not.
    UnusedNotZero(Part),
}

impl core::fmt::Display for Part {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Part::Config => "configuration",
            Part::Estimator => "estimator state",
            Part::Latitude => "latitude",
            Part::Status => "status",
            Part::Fault => "rotation fault",
            Part::SwayMonitor => "sway monitor",
            Part::TimeGrid => "sample grid",
            Part::RotationMonitor => "rotation monitor",
            Part::Features => "rotation pattern features",
            Part::DelayLine => "gap filler delay line",
            Part::FillError => "gap filler fill error",
            Part::KalmanState => "Kalman state",
            Part::KalmanCovariance => "Kalman covariance",
            Part::WindowIndices => "window indices",
            Part::WindowEntries => "window entries",
            Part::WindowSums => "window running sums",
            Part::Bin => "bin being filled",
            Part::Residuals => "residual means and gains",
            Part::PaperIntegrals => "paper method integrals",
            Part::PaperStartTime => "paper method start time",
            Part::Padding => "padding",
        })
    }
}

impl core::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CheckpointError::BufferTooSmall { needed, available } => {
                write!(f, "checkpoint needs {needed} bytes, buffer has {available}")
            }
            CheckpointError::BadMagic => write!(f, "not a checkpoint image (bad magic)"),
            CheckpointError::Version { found, expected } if found < expected => write!(
                f,
                "checkpoint image of format version {found} was written by an older firmware \
                 (this one reads version {expected}); it must be discarded and estimation starts afresh"
            ),
            CheckpointError::Version { found, expected } => write!(
                f,
                "checkpoint image of format version {found} was written by a newer firmware \
                 (this one reads version {expected})"
            ),
            CheckpointError::RealWidthMismatch(b) => {
                write!(f, "checkpoint image written with {b}-byte floats, this build uses {R}")
            }
            CheckpointError::CapacityMismatch(c) => {
                write!(f, "checkpoint image written for a ring capacity of {c} entries")
            }
            CheckpointError::LengthMismatch { expected, found } => {
                write!(f, "checkpoint image length {found}, expected {expected}")
            }
            CheckpointError::CrcMismatch { stored, computed } => {
                write!(f, "checkpoint CRC {stored:08x} does not match the content ({computed:08x})")
            }
            CheckpointError::UnknownMethod(c) => write!(f, "checkpoint image has unknown method code {c}"),
            CheckpointError::InvalidConfig(e) => write!(f, "checkpoint image has an invalid configuration: {e:?}"),
            CheckpointError::InvalidValue(p) => write!(f, "checkpoint {p}: value not finite, out of range or unknown"),
            CheckpointError::NotPositiveDefinite(p) => {
                write!(f, "checkpoint {p}: covariance not symmetric positive definite")
            }
            CheckpointError::Inconsistent(p) => write!(f, "checkpoint {p}: inconsistent values"),
            CheckpointError::UnusedNotZero(p) => write!(f, "checkpoint {p}: unused bytes not zero"),
        }
    }
}

impl core::error::Error for CheckpointError {}

/// `Ok` when `ok`, else `err`.
pub(crate) fn ensure(ok: bool, err: CheckpointError) -> Result<(), CheckpointError> {
    if ok {
        Ok(())
    } else {
        Err(err)
    }
}

/// Whether `v` is finite and within `[-bound, bound]`.
pub(crate) fn within(v: Real, bound: Real) -> bool {
    v.is_finite() && v.abs() <= bound
}

/// Whether `v` is finite and within `[0, bound]`.
pub(crate) fn within_non_negative(v: Real, bound: Real) -> bool {
    v.is_finite() && (0.0..=bound).contains(&v)
}
