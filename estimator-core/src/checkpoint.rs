//! Checkpoint and restore: what a restarted firmware needs to go on estimating, as a small,
//! versioned, CRC-protected byte image.
//!
//! # What is kept
//! What took hours to learn and cannot be seen again: the filter and what it learned of its noise
//! and of the errors' drift, the sample grid, the rotation pattern, the fill error, the run's
//! health, the counters and the last sample's time. Not what the next samples rebuild within one
//! period: the window, the gap filler's delay line, the references' low-pass. So a restored
//! estimator goes on as after a long gap: the estimate from the first sample on,
//! [`crate::Status::Holding`] while the window refills, updates again one period later.
//! [`Estimator::checkpoint`] writes the image into a buffer of [`CHECKPOINT_LEN`] bytes (the same
//! for every ring capacity); [`Estimator::restore`] reads one back.
//!
//! # Validation
//! Restore checks magic, version, float width, length, CRC-32 and method code, then each part as
//! it is read: the configuration passes [`Config::check`]; every float is finite and within its
//! bound ([`MAX_STATE`], [`MAX_VARIANCE`], [`MAX_RESIDUAL`], the angles [`crate::Sample::check`]
//! lets through), so every output is finite; every covariance is exactly symmetric and positive
//! definite; the parts agree with each other and the configuration; flags are 0 or 1, codes known,
//! unused bytes zero. Every part is read into a value on the stack before anything is written, so
//! on any [`CheckpointError`] the estimator is untouched. An image of another [`VERSION`] is
//! refused; the firmware then starts from the learned errors' record ([`crate::learned`]).
//!
//! # Layout
//! Little-endian; `R` = bytes of [`Real`]; an optional value is a flag byte (0 absent, 1 present)
//! and the value, all zero when absent. The header: magic `b"RIEC"` (4 bytes), [`VERSION`] (2),
//! `R` (1), the method code ([`Method`] `as u8`, 1), the total length with the CRC (4); then the
//! parts in the order and with the lengths listed once in `estimator/checkpoint.rs`, each written,
//! read and checked next to its type by its `Stored` implementation (`checkpoint.rs` in the type's
//! folder); zero padding to a multiple of 4; the CRC-32 ([`crc32`]) of every byte before it.
//! `tests.rs` pins a golden image: a change of the format fails until [`VERSION`] is bumped.
//!
//! This module is the format only (the header and CRC: `image.rs`; the byte reader and writer:
//! `wire.rs`; the errors, the bounds and `Stored`: here); it knows no part. What a restart costs,
//! the parts in full and the tests: docs/reliability.md, "Checkpoint and restore".

pub(crate) mod image;
#[cfg(test)]
pub(crate) mod tests;
pub(crate) mod wire;

#[cfg(doc)]
use crate::config::{Config, Method};
pub use crate::estimator::checkpoint::CHECKPOINT_LEN;
#[cfg(doc)]
use crate::estimator::Estimator;
use crate::Real;
use wire::{Reader, Writer};

/// First four bytes of every image.
pub const MAGIC: [u8; 4] = *b"RIEC";
/// Format version written and the only one read.
pub const VERSION: u16 = 9;
/// Bytes of the header.
pub const HEADER_LEN: usize = 12;
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

/// One part of the image: how many bytes it takes, how it is written, how it is read back and
/// checked. Implemented next to each stored type, so that the type's fields stay private.
pub(crate) trait Stored: Sized {
    /// Bytes [`Stored::write`] writes (a test checks it for every part).
    const LEN: usize;
    /// What reading the part needs to know (the configuration, the ring capacity, a bound).
    type Context<'a>: Copy;
    /// Writes the part at the writer's position.
    fn write(&self, w: &mut Writer<'_>);
    /// Reads the part at the reader's position and checks every value of it.
    fn read(r: &mut Reader<'_>, context: Self::Context<'_>) -> Result<Self, CheckpointError>;
}

/// The CRC-32/ISO-HDLC four bits at a time: entry `n` is `n` taken through four steps of the
/// reflected polynomial `0xEDB88320` (see [`crc32`]).
const CRC32_NIBBLES: [u32; 16] = {
    let mut table = [0u32; 16];
    let mut n = 0;
    while n < 16 {
        let mut c = n as u32;
        let mut bit = 0;
        while bit < 4 {
            c = if c & 1 == 1 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            bit += 1;
        }
        table[n] = c;
        n += 1;
    }
    table
};

/// The CRC-32 the image ends with, of `bytes`: IEEE 802.3, reflected, init and final xor
/// `0xFFFFFFFF` (zlib's `crc32`, the catalogue's CRC-32/ISO-HDLC); `crc32(b"123456789") ==
/// 0xCBF43926`. Four bits at a time from a 16-entry table: the firmware computes it once per
/// checkpoint and once per restore, where a byte's table (256 entries) or the code of a bit at a
/// time, which the compiler unrolls, would take several times its flash (docs/firmware.md).
pub fn crc32(bytes: &[u8]) -> u32 {
    // The CRC is linear: four steps of `c` are those of its low four bits (the table) and of the
    // rest, which the steps only shift.
    let nibble = |c: u32| (c >> 4) ^ CRC32_NIBBLES.get((c & 0xF) as usize).copied().unwrap_or(0);
    let mut c = !0u32;
    for b in bytes {
        c = nibble(nibble(c ^ u32::from(*b)));
    }
    !c
}

/// A part of the image, named in errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The configuration.
    Config,
    /// The estimator's own running state: the grid index, the feed interval, the gate flag.
    Estimator,
    /// The last rotation fault and its time.
    Fault,
    /// The sway monitor of the start gate.
    SwayMonitor,
    /// The sample grid: interval, stamps, learning steps.
    TimeGrid,
    /// The rotation monitor: period, reference angles, the cycle being learned.
    RotationMonitor,
    /// The learned features of the rotation pattern.
    Features,
    /// The gap filler's fill-error estimate.
    FillError,
    /// A Kalman filter's states.
    KalmanState,
    /// A Kalman filter's covariance.
    KalmanCovariance,
    /// The windowed method's residual means, gains and what it learned of noise and drift.
    Residuals,
    /// The windowed method's change detector: what it learned of its block means, the errors being
    /// learned again and the estimate they are learned against.
    ChangeDetector,
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
    BufferTooSmall {
        /// Bytes the image (or, on restore, its header) takes.
        needed: usize,
        /// Bytes in the buffer.
        available: usize,
    },
    /// The first four bytes are not [`MAGIC`].
    BadMagic,
    /// The image has another format version than this firmware's [`VERSION`] (see the module
    /// doc: an older image must be discarded).
    Version {
        /// The image's format version.
        found: u16,
        /// The format version this firmware reads, [`VERSION`].
        expected: u16,
    },
    /// Written with another float width (`f32` vs `f64` feature); the value is the image's bytes.
    RealWidthMismatch(u8),
    /// The header's length is not [`CHECKPOINT_LEN`].
    LengthMismatch {
        /// The image length this build writes and reads, [`CHECKPOINT_LEN`], bytes.
        expected: usize,
        /// The length in the image's header, bytes.
        found: usize,
    },
    /// The CRC-32 does not match the content.
    CrcMismatch {
        /// The CRC-32 at the end of the image.
        stored: u32,
        /// The CRC-32 of the image's bytes before it ([`crc32`]).
        computed: u32,
    },
    /// The method code is unknown.
    UnknownMethod(u8),
    /// The configuration does not pass [`Config::check`].
    InvalidConfig(crate::config::ConfigError),
    /// A value is NaN, infinite or out of its range, a flag is not 0 or 1, a code is unknown.
    InvalidValue(Part),
    /// A covariance is not exactly symmetric or not positive definite.
    NotPositiveDefinite(Part),
    /// Values that must agree do not (a pinned value and the configuration).
    Inconsistent(Part),
    /// A byte that must be zero (an absent optional value, padding) is not.
    UnusedNotZero(Part),
}

impl core::fmt::Display for Part {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Part::Config => "configuration",
            Part::Estimator => "estimator state",
            Part::Fault => "rotation fault",
            Part::SwayMonitor => "sway monitor",
            Part::TimeGrid => "sample grid",
            Part::RotationMonitor => "rotation monitor",
            Part::Features => "rotation pattern features",
            Part::FillError => "gap filler fill error",
            Part::KalmanState => "Kalman state",
            Part::KalmanCovariance => "Kalman covariance",
            Part::Residuals => "residual means and gains",
            Part::ChangeDetector => "change detector",
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
            CheckpointError::LengthMismatch { expected, found } => {
                write!(f, "checkpoint image length {found}, expected {expected}")
            }
            CheckpointError::CrcMismatch { stored, computed } => {
                write!(f, "checkpoint CRC {stored:08x} does not match the content ({computed:08x})")
            }
            CheckpointError::UnknownMethod(c) => write!(f, "checkpoint image has unknown method code {c}"),
            CheckpointError::InvalidConfig(e) => write!(f, "checkpoint image has an invalid configuration: {e}"),
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

/// Whether every value of `values` is finite and within `[lo, hi]`. Out of line: the windowed
/// method's reader checks ten arrays, and its checks inlined and unrolled grow the STM32F405's
/// image (by how much: docs/firmware.md, "Measured figures", the table of builds).
#[inline(never)]
pub(crate) fn all_within(values: &[Real], lo: Real, hi: Real) -> bool {
    values.iter().all(|v| v.is_finite() && *v >= lo && *v <= hi)
}

/// Whether `v` is finite and within `[0, bound]`.
pub(crate) fn within_non_negative(v: Real, bound: Real) -> bool {
    v.is_finite() && (0.0..=bound).contains(&v)
}
