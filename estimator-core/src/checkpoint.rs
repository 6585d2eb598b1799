//! Checkpoint and restore: the whole estimator state as a fixed-size, versioned, CRC-protected
//! byte image, so a restarted firmware can continue exactly where it stopped.
//!
//! [`Estimator::checkpoint`] writes the image into a caller-provided buffer of at least
//! [`Estimator::CHECKPOINT_LEN`] bytes ([`CHECKPOINT_LEN`] for the default capacity of 480:
//! **13 796 bytes** with `f32`, 13 988 with the `f64` feature; four 4 KiB flash pages).
//! [`Estimator::restore`] reads one back. Restoring an image into a fresh estimator and
//! continuing gives outputs bit-identical to the uninterrupted run (tested in
//! `tests/checkpoint_roundtrip.rs` for many random cut points and all three methods).
//!
//! # Validation
//! Restore checks, in this order, and returns the first failure as a [`CheckpointError`]:
//! magic, version, float width, ring capacity, the length in the header, the CRC-32 over
//! everything before it; then every field: the configuration must pass [`Config::check`] (which
//! also bounds the squares of its sigmas and the samples bridged per step), every
//! float must be finite (and in range where it has one: the previous sample must pass
//! [`Sample::check`], monitor ratios non-negative, Kalman states within [`MAX_STATE`], variances
//! within [`MAX_VARIANCE`] or four times the prior, residual means within [`MAX_RESIDUAL`], channel
//! gains 0 or at least one fixed-point count, so that every output of the restored estimator is
//! finite), every covariance exactly symmetric and positive definite (Cholesky), every moving-average window consistent (length equal to the configured
//! period, head and fill count in range, every stored value within the fixed-point range and each
//! running sum equal to the exact sum of the stored samples), flags 0 or 1, unused bytes zero.
//! Nothing is written before all of this has passed, so on any error the running estimator is
//! untouched; then the state is written in place (see [`Estimator::restore`]: no second estimator
//! on the stack).
//!
//! The image carries the configuration; restoring replaces the estimator's configuration with the
//! image's (it must pass [`Config::check`] for this `CAP`).
//!
//! # Layout (little-endian; `R` = bytes of [`Real`]: 4, or 8 with the `f64` feature)
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 4 | magic `b"RIEC"` |
//! | 4 | 2 | version ([`VERSION`]) |
//! | 6 | 1 | `R` |
//! | 7 | 1 | method code ([`Method::code`]) |
//! | 8 | 4 | `CAP` |
//! | 12 | 4 | total length including the CRC (= `CHECKPOINT_LEN`) |
//! | 16 | [`COMMON_LEN`] | common part, below |
//! | [`METHOD_OFFSET`] | `method_len(CAP)` | the method's state, zero-padded to the longest method |
//! | `CHECKPOINT_LEN - 4` | 4 | CRC-32 (IEEE 802.3, reflected, as zlib's `crc32`) of all bytes before it |
//!
//! Common part, in order: config (`rotation_period_samples` u32, `sample_interval_s` f64,
//! `prior_sigma_rad`, `measurement_sigma_rad`, `drift_rad_per_sqrt_s`, `traditional_sigma_rad`,
//! `traditional_drift_rad_per_sqrt_s`, `sway_gate_rad`, `converged_sigma_rad`,
//! `rotation_step_tolerance`, `rotation_period_tolerance` as `R`, `max_bridged_gap_samples` u32);
//! previous sample (flag u8, `time_s` f64, rotation, platform, latitude, heading, roll, pitch as `R`;
//! all zero when there is none); `rotation_continuous` u8; `gate_open` u8; the cached latitude `R`
//! (its sine and cosine are recomputed); rotation monitor (direction i8, steps u32, short rate
//! ratio `R`, mean rate ratio `R`); sway
//! monitor (mean `R`, mean square `R`, samples u32); rejected counts 5 x u32; accepted, bridged,
//! window restarts u32.
//!
//! Method part: **windowed**: updates u32, Kalman `x` 4 `R`, `P` 16 `R` (row-major), residual
//! means 4 `R`, residual count u32, channel gains 4 `R`, window.
//! **paper**: updates u32, samples u32, start time f64, integrals 4 x i64, four Kalman filters
//! (`x` 3 f64, `P` 9 f64 each), window. **traditional**: updates u32, Kalman `x` 4 `R`, `P` 16 `R`.
//! A window is: length u32, head u32, filled u32, running sums `CH` x i64, the ring `CAP` x `CH`
//! x i32 (slot-major).

use crate::config::{Config, ConfigError, Method};
use crate::estimator::{Estimator, RejectCounts, RotationMonitor, SwayMonitor};
use crate::kalman::ConstantStateKalman;
use crate::methods::windowed::CHANNELS;
#[cfg(feature = "paper-method")]
use crate::methods::Paper;
use crate::methods::{MethodState, Traditional, Windowed};
use crate::moving_average::{WindowAverage, MAX_MAGNITUDE};
use crate::sample::{Attitude, Sample};
use crate::math::sin_cos;
use crate::Real;
use nalgebra::RealField;

/// First four bytes of every image.
pub const MAGIC: [u8; 4] = *b"RIEC";
/// Format version written and the only one accepted.
pub const VERSION: u16 = 2;
/// Bytes of the header.
pub const HEADER_LEN: usize = 16;
/// Bytes of the CRC at the end.
pub const CRC_LEN: usize = 4;

/// Largest magnitude a restored Kalman state may have (rad, or correlation units for the paper's
/// bias states). Every measurement is a window mean of values clamped to +-2 and the states are
/// installation errors of arcseconds to degrees, so no running estimator comes near; the bound keeps
/// a crafted image with a finite but huge state (which would overflow the outputs, or turn
/// infinite when the paper's `f64` states are narrowed to `f32`) from being accepted. Found by the
/// `checkpoint_restore` fuzz target.
pub const MAX_STATE: f64 = 1e3;
/// Largest magnitude of a restored residual mean of the windowed method: a residual is a window
/// mean (|m| <= 2) minus `H x` (|H x| <= 4 [`MAX_STATE`]).
pub const MAX_RESIDUAL: f64 = 1e4;
/// Largest restored variance, unless the configured prior is larger: `max(1e12, 4 prior^2)`. The
/// covariance starts at `prior^2` and a measurement update never increases it; only the (tiny)
/// random walk does.
pub const MAX_VARIANCE: f64 = 1e12;



fn max_variance(config: &Config) -> f64 {
    let prior = config.prior_sigma_rad as f64;
    MAX_VARIANCE.max(4.0 * prior * prior)
}

const R: usize = core::mem::size_of::<Real>();
const CONFIG_LEN: usize = 4 + 8 + 9 * R + 4;
const PREVIOUS_LEN: usize = 1 + 8 + 6 * R;
/// Bytes of the common part (configuration, previous sample, monitors, counters).
pub const COMMON_LEN: usize = CONFIG_LEN + PREVIOUS_LEN + 2 + R + (1 + 4 + 2 * R) + (2 * R + 4) + 5 * 4 + 3 * 4;
/// Offset of the method part.
pub const METHOD_OFFSET: usize = HEADER_LEN + COMMON_LEN;

const fn kalman_len(scalar_bytes: usize, n: usize) -> usize {
    scalar_bytes * (n + n * n)
}
const fn window_len(ch: usize, cap: usize) -> usize {
    3 * 4 + ch * 8 + cap * ch * 4
}
const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}
/// Bytes of the method part for ring capacity `cap`: the longest of the three methods.
pub const fn method_len(cap: usize) -> usize {
    let windowed = 4 + kalman_len(R, 4) + 4 * R + 4 + 4 * R + window_len(CHANNELS, cap);
    let paper = 4 + 4 + 8 + 4 * 8 + 4 * kalman_len(8, 3) + window_len(4, cap);
    let traditional = 4 + kalman_len(R, 4);
    max(windowed, max(paper, traditional))
}
/// Total image length for ring capacity `cap`.
pub const fn checkpoint_len(cap: usize) -> usize {
    METHOD_OFFSET + method_len(cap) + CRC_LEN
}
/// Image length for the default capacity (480): 13 796 bytes with `f32`.
pub const CHECKPOINT_LEN: usize = checkpoint_len(480);

/// A part of the image, named in errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    Config,
    PreviousSample,
    Flags,
    Latitude,
    RotationMonitor,
    SwayMonitor,
    KalmanState,
    KalmanCovariance,
    WindowIndices,
    WindowSamples,
    WindowSums,
    PaperIntegrals,
    PaperStartTime,
    Residuals,
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
    /// A version other than [`VERSION`].
    UnsupportedVersion(u16),
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
    /// A value is NaN, infinite or out of its range.
    InvalidValue(Part),
    /// A covariance is not exactly symmetric or not positive definite.
    NotPositiveDefinite(Part),
    /// Values that must agree do not (window indices, running sums, flags, padding).
    Inconsistent(Part),
}

impl core::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CheckpointError::BufferTooSmall { needed, available } => {
                write!(f, "checkpoint needs {needed} bytes, buffer has {available}")
            }
            CheckpointError::BadMagic => write!(f, "not a checkpoint (bad magic)"),
            CheckpointError::UnsupportedVersion(v) => write!(f, "unsupported checkpoint version {v}"),
            CheckpointError::RealWidthMismatch(b) => write!(f, "checkpoint written with {b}-byte floats"),
            CheckpointError::CapacityMismatch(c) => write!(f, "checkpoint written for capacity {c}"),
            CheckpointError::LengthMismatch { expected, found } => {
                write!(f, "checkpoint length {found}, expected {expected}")
            }
            CheckpointError::CrcMismatch { stored, computed } => {
                write!(f, "checkpoint CRC {stored:08x} does not match content ({computed:08x})")
            }
            CheckpointError::UnknownMethod(c) => write!(f, "unknown method code {c}"),
            CheckpointError::InvalidConfig(e) => write!(f, "invalid configuration: {e:?}"),
            CheckpointError::InvalidValue(p) => write!(f, "{p:?}: value not finite or out of range"),
            CheckpointError::NotPositiveDefinite(p) => {
                write!(f, "{p:?}: covariance not symmetric positive definite")
            }
            CheckpointError::Inconsistent(p) => write!(f, "{p:?}: inconsistent values"),
        }
    }
}

const fn crc32_nibble_table() -> [u32; 16] {
    let mut table = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 4 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
}
const CRC32_TABLE: [u32; 16] = crc32_nibble_table();

/// CRC-32 (IEEE 802.3, reflected, init and final xor `0xFFFFFFFF`: zlib's `crc32`), with a
/// 16-entry table (64 bytes of flash). `crc32(b"123456789") == 0xCBF43926`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        c = CRC32_TABLE[(c & 0xF) as usize] ^ (c >> 4);
        c = CRC32_TABLE[(c & 0xF) as usize] ^ (c >> 4);
    }
    !c
}

/// Floats as they go into the image.
trait Wire: Copy {
    fn put(self, w: &mut Writer<'_>);
    fn get(r: &mut Reader<'_>) -> Self;
    fn finite(self) -> bool;
    fn to_f64(self) -> f64;
}

impl Wire for f32 {
    fn put(self, w: &mut Writer<'_>) {
        w.bytes(&self.to_le_bytes());
    }
    fn get(r: &mut Reader<'_>) -> Self {
        f32::from_le_bytes(r.array())
    }
    fn finite(self) -> bool {
        self.is_finite()
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl Wire for f64 {
    fn put(self, w: &mut Writer<'_>) {
        w.bytes(&self.to_le_bytes());
    }
    fn get(r: &mut Reader<'_>) -> Self {
        f64::from_le_bytes(r.array())
    }
    fn finite(self) -> bool {
        self.is_finite()
    }
    fn to_f64(self) -> f64 {
        self
    }
}

/// Sequential writer. Writes past the end are dropped (the image length is computed from the same
/// layout, so none happen; a test checks that the writer ends exactly at the CRC).
struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        if let Some(dst) = self.buf.get_mut(self.pos..self.pos + b.len()) {
            dst.copy_from_slice(b);
        }
        self.pos += b.len();
    }
    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn usize(&mut self, v: usize) {
        self.u32(u32::try_from(v).unwrap_or(u32::MAX));
    }
    fn i64(&mut self, v: i64) {
        self.bytes(&v.to_le_bytes());
    }
    fn real<T: Wire>(&mut self, v: T) {
        v.put(self);
    }
    fn kalman<T: Wire + RealField, const N: usize>(&mut self, kf: &ConstantStateKalman<T, N>) {
        for i in 0..N {
            self.real(kf.x[i]);
        }
        for i in 0..N {
            for j in 0..N {
                self.real(kf.p[(i, j)]);
            }
        }
    }
    fn window<const CH: usize, const CAP: usize>(&mut self, w: &WindowAverage<CH, CAP>) {
        self.usize(w.len);
        self.usize(w.head);
        self.usize(w.filled);
        for s in w.sums {
            self.i64(s);
        }
        for slot in &w.ring {
            for v in slot {
                self.bytes(&v.to_le_bytes());
            }
        }
    }
}

/// Sequential reader over an image whose length has been checked. Reads past the end give zeros
/// (cannot happen after the length check; the parse then fails on a later check at worst).
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl Reader<'_> {
    fn array<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(src) = self.buf.get(self.pos..self.pos + N) {
            out.copy_from_slice(src);
        }
        self.pos += N;
        out
    }
    fn u8(&mut self) -> u8 {
        self.array::<1>()[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.array())
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.array())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.array())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.array())
    }
    fn real<T: Wire>(&mut self) -> T {
        T::get(self)
    }
    fn flag(&mut self) -> Result<bool, CheckpointError> {
        match self.u8() {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(CheckpointError::Inconsistent(Part::Flags)),
        }
    }
    /// A finite `Real`.
    fn finite(&mut self, part: Part) -> Result<Real, CheckpointError> {
        let v: Real = self.real();
        if v.is_finite() {
            Ok(v)
        } else {
            Err(CheckpointError::InvalidValue(part))
        }
    }
    /// A Kalman filter: states within [`MAX_STATE`], variances within `max_variance`, covariance
    /// symmetric positive definite.
    fn kalman<T: Wire + RealField, const N: usize>(
        &mut self,
        kf: &mut ConstantStateKalman<T, N>,
        max_variance: f64,
    ) -> Result<(), CheckpointError> {
        for i in 0..N {
            let v: T = self.real();
            if !(v.finite() && v.to_f64().abs() <= MAX_STATE) {
                return Err(CheckpointError::InvalidValue(Part::KalmanState));
            }
            kf.x[i] = v;
        }
        for i in 0..N {
            for j in 0..N {
                let v: T = self.real();
                if !(v.finite() && (i != j || v.to_f64() <= max_variance)) {
                    return Err(CheckpointError::InvalidValue(Part::KalmanCovariance));
                }
                kf.p[(i, j)] = v;
            }
        }
        if !kf.covariance_is_spd() {
            return Err(CheckpointError::NotPositiveDefinite(Part::KalmanCovariance));
        }
        Ok(())
    }
    /// A moving-average window, checked as it streams past (indices, every stored value within
    /// the fixed-point range, each running sum equal to the exact sum of its samples); with `dst`,
    /// also written into it.
    fn window<const CH: usize, const CAP: usize>(
        &mut self,
        mut dst: Option<&mut WindowAverage<CH, CAP>>,
        expected_len: usize,
    ) -> Result<(), CheckpointError> {
        let len = self.u32() as usize;
        let head = self.u32() as usize;
        let filled = self.u32() as usize;
        let indices_ok = len == expected_len
            && len <= CAP
            && filled <= len
            && if filled < len { head == filled } else { head < len };
        if !indices_ok {
            return Err(CheckpointError::Inconsistent(Part::WindowIndices));
        }
        let mut sums = [0i64; CH];
        for s in sums.iter_mut() {
            *s = self.i64();
        }
        let bound = WindowAverage::<CH, CAP>::quantize(MAX_MAGNITUDE);
        let mut direct = [0i64; CH];
        for k in 0..CAP {
            for ch in 0..CH {
                let v = self.i32();
                if v > bound || v < -bound {
                    return Err(CheckpointError::InvalidValue(Part::WindowSamples));
                }
                if k < filled {
                    direct[ch] += i64::from(v);
                }
                if let Some(w) = dst.as_deref_mut() {
                    w.ring[k][ch] = v;
                }
            }
        }
        if direct != sums {
            return Err(CheckpointError::Inconsistent(Part::WindowSums));
        }
        if let Some(w) = dst {
            w.sums = sums;
            w.len = len;
            w.head = head;
            w.filled = filled;
        }
        Ok(())
    }
}

impl<const CAP: usize> Estimator<CAP> {
    /// Bytes of a checkpoint image of this estimator (13 796 for `CAP` = 480 with `f32`).
    pub const CHECKPOINT_LEN: usize = checkpoint_len(CAP);

    /// Writes the whole state into `buf[..CHECKPOINT_LEN]`; returns the bytes written.
    pub fn checkpoint(&self, buf: &mut [u8]) -> Result<usize, CheckpointError> {
        let len = Self::CHECKPOINT_LEN;
        let available = buf.len();
        let Some(image) = buf.get_mut(..len) else {
            return Err(CheckpointError::BufferTooSmall { needed: len, available });
        };
        image.fill(0);
        let mut w = Writer { buf: image, pos: 0 };
        w.bytes(&MAGIC);
        w.bytes(&VERSION.to_le_bytes());
        w.u8(R as u8);
        w.u8(self.config.method.code());
        w.usize(CAP);
        w.usize(len);

        let c = &self.config;
        w.usize(c.rotation_period_samples);
        w.bytes(&c.sample_interval_s.to_le_bytes());
        for v in [
            c.prior_sigma_rad,
            c.measurement_sigma_rad,
            c.drift_rad_per_sqrt_s,
            c.traditional_sigma_rad,
            c.traditional_drift_rad_per_sqrt_s,
            c.sway_gate_rad,
            c.converged_sigma_rad,
            c.rotation_step_tolerance,
            c.rotation_period_tolerance,
        ] {
            w.real(v);
        }
        w.u32(c.max_bridged_gap_samples);

        match &self.previous {
            Some(s) => {
                w.u8(1);
                w.bytes(&s.time_s.to_le_bytes());
                for v in [
                    s.rotation_rad,
                    s.platform_rad,
                    s.latitude_rad,
                    s.attitude.heading_rad,
                    s.attitude.roll_rad,
                    s.attitude.pitch_rad,
                ] {
                    w.real(v);
                }
            }
            None => {
                w.u8(0);
                w.pos += 8 + 6 * R;
            }
        }
        w.u8(u8::from(self.rotation_continuous));
        w.u8(u8::from(self.gate_open));
        w.real(self.latitude_trig.0);
        w.bytes(&self.rotation.direction.to_le_bytes());
        w.u32(self.rotation.steps);
        w.real(self.rotation.short_rate_ratio);
        w.real(self.rotation.mean_rate_ratio);
        w.real(self.sway.mean_rad);
        w.real(self.sway.mean_square_rad2);
        w.u32(self.sway.samples);
        for n in self.rejected.0 {
            w.u32(n);
        }
        w.u32(self.accepted);
        w.u32(self.bridged);
        w.u32(self.window_restarts);

        match &self.method {
            MethodState::Windowed(m) => {
                w.u32(m.updates);
                w.kalman(&m.kf);
                for v in m.residual_mean {
                    w.real(v);
                }
                w.u32(m.residual_count);
                for v in m.gains {
                    w.real(v);
                }
                w.window(&m.window);
            }
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => {
                w.u32(m.updates);
                w.u32(m.samples);
                w.bytes(&m.start_time_s.to_le_bytes());
                for v in m.integrals {
                    w.i64(v);
                }
                for kf in &m.kf {
                    w.kalman(kf);
                }
                w.window(&m.window);
            }
            MethodState::Traditional(m) => {
                w.u32(m.updates);
                w.kalman(&m.kf);
            }
        }
        let crc = crc32(image.get(..len - CRC_LEN).unwrap_or(&[]));
        if let Some(dst) = image.get_mut(len - CRC_LEN..) {
            dst.copy_from_slice(&crc.to_le_bytes());
        }
        Ok(len)
    }

    /// Replaces the whole state (configuration included) with the image in `buf` (which may be
    /// longer than the image). On any error the estimator is left exactly as it was.
    ///
    /// Works in place, in two passes over the image: the first checks every field and stores only
    /// what it must compare (the running sums, one small Kalman filter at a time); the second, once
    /// everything has passed, resets the estimator in place ([`Estimator::reset`]'s way) and reads
    /// the same bytes straight into it. No second estimator is built, so restoring needs about a
    /// kilobyte of stack instead of the estimator's size (13.8 KB) several times over, which is what
    /// lets the firmware restore at boot on a microcontroller's stack.
    pub fn restore(&mut self, buf: &[u8]) -> Result<(), CheckpointError> {
        let (image, method) = verified_image::<CAP>(buf)?;
        read_state::<CAP>(image, method, None)?;
        // The same bytes pass the same checks again, so this cannot fail half-way.
        read_state(image, method, Some(self)).map(|_| ())
    }

    /// A new estimator from a checkpoint image (see [`Estimator::restore`]).
    pub fn from_checkpoint(buf: &[u8]) -> Result<Self, CheckpointError> {
        let (image, method) = verified_image::<CAP>(buf)?;
        let config = read_state::<CAP>(image, method, None)?;
        let mut est = Estimator::<CAP>::new(config).map_err(CheckpointError::InvalidConfig)?;
        read_state(image, method, Some(&mut est))?;
        Ok(est)
    }
}

/// Checks the header (magic, version, float width, capacity, length) and the CRC; returns the
/// image (`buf[..CHECKPOINT_LEN]`) and the method code of its header.
fn verified_image<const CAP: usize>(buf: &[u8]) -> Result<(&[u8], u8), CheckpointError> {
    let len = checkpoint_len(CAP);
    let Some(header) = buf.get(..HEADER_LEN) else {
        return Err(CheckpointError::BufferTooSmall { needed: HEADER_LEN, available: buf.len() });
    };
    let mut r = Reader { buf: header, pos: 0 };
    if r.array::<4>() != MAGIC {
        return Err(CheckpointError::BadMagic);
    }
    let version = u16::from_le_bytes(r.array());
    if version != VERSION {
        return Err(CheckpointError::UnsupportedVersion(version));
    }
    let real_bytes = r.u8();
    if real_bytes as usize != R {
        return Err(CheckpointError::RealWidthMismatch(real_bytes));
    }
    let method_code = r.u8();
    let capacity = r.u32();
    if capacity as usize != CAP {
        return Err(CheckpointError::CapacityMismatch(capacity));
    }
    let found = r.u32() as usize;
    if found != len {
        return Err(CheckpointError::LengthMismatch { expected: len, found });
    }
    let Some(image) = buf.get(..len) else {
        return Err(CheckpointError::BufferTooSmall { needed: len, available: buf.len() });
    };
    let stored = u32::from_le_bytes(Reader { buf: image, pos: len - CRC_LEN }.array());
    let computed = crc32(image.get(..len - CRC_LEN).unwrap_or(&[]));
    if stored != computed {
        return Err(CheckpointError::CrcMismatch { stored, computed });
    }
    Ok((image, method_code))
}

/// Reads and checks every field of a verified image (see the module doc) and returns its
/// configuration. With `target`, also writes the state into it, after resetting it in place to
/// that configuration; without, stores nothing. The checks are the same either way, so a target
/// is written only by a pass that cannot fail once a pass without one has succeeded.
fn read_state<const CAP: usize>(
    image: &[u8],
    method_code: u8,
    mut target: Option<&mut Estimator<CAP>>,
) -> Result<Config, CheckpointError> {
    let method = Method::from_code(method_code).ok_or(CheckpointError::UnknownMethod(method_code))?;
    let mut r = Reader { buf: image, pos: HEADER_LEN };
    let rotation_period_samples = r.u32() as usize;
    let sample_interval_s = r.f64();
    let mut reals = [0.0 as Real; 9];
    for v in reals.iter_mut() {
        *v = r.real();
    }
    let config = Config {
        method,
        rotation_period_samples,
        sample_interval_s,
        prior_sigma_rad: reals[0],
        measurement_sigma_rad: reals[1],
        drift_rad_per_sqrt_s: reals[2],
        traditional_sigma_rad: reals[3],
        traditional_drift_rad_per_sqrt_s: reals[4],
        sway_gate_rad: reals[5],
        converged_sigma_rad: reals[6],
        rotation_step_tolerance: reals[7],
        rotation_period_tolerance: reals[8],
        max_bridged_gap_samples: r.u32(),
    };
    config.check(CAP).map_err(CheckpointError::InvalidConfig)?;

    let previous = match r.u8() {
        0 => {
            let start = r.pos;
            r.pos += 8 + 6 * R;
            if image.get(start..r.pos).is_none_or(|b| b.iter().any(|v| *v != 0)) {
                return Err(CheckpointError::Inconsistent(Part::PreviousSample));
            }
            None
        }
        1 => {
            let time_s = r.f64();
            let v: [Real; 6] = core::array::from_fn(|_| r.real());
            let s = Sample {
                time_s,
                rotation_rad: v[0],
                platform_rad: v[1],
                latitude_rad: v[2],
                attitude: Attitude { heading_rad: v[3], roll_rad: v[4], pitch_rad: v[5] },
            };
            if s.check().is_err() {
                return Err(CheckpointError::InvalidValue(Part::PreviousSample));
            }
            Some(s)
        }
        _ => return Err(CheckpointError::Inconsistent(Part::Flags)),
    };
    let rotation_continuous = r.flag()?;
    let gate_open = r.flag()?;
    let latitude_rad = r.finite(Part::Latitude)?;
    let direction = i8::from_le_bytes(r.array());
    let steps = r.u32();
    let short_rate_ratio = r.finite(Part::RotationMonitor)?;
    let mean_rate_ratio = r.finite(Part::RotationMonitor)?;
    // A ratio is an increment (at most pi after wrapping) over the nominal 2 pi / W: |ratio| <= W/2.
    let max_ratio = rotation_period_samples as Real;
    if !(-1..=1).contains(&direction) || !(0.0..=max_ratio).contains(&mean_rate_ratio) || short_rate_ratio.abs() > max_ratio {
        return Err(CheckpointError::InvalidValue(Part::RotationMonitor));
    }
    let mean_rad = r.finite(Part::SwayMonitor)?;
    let mean_square_rad2 = r.finite(Part::SwayMonitor)?;
    let sway = SwayMonitor { mean_rad, mean_square_rad2, samples: r.u32() };
    let rejected = RejectCounts(core::array::from_fn(|_| r.u32()));
    let (accepted, bridged, window_restarts) = (r.u32(), r.u32(), r.u32());
    if let Some(est) = target.as_deref_mut() {
        est.reinit(config).map_err(CheckpointError::InvalidConfig)?;
        est.previous = previous;
        est.rotation_continuous = rotation_continuous;
        est.gate_open = gate_open;
        let (sin_lat, cos_lat) = sin_cos(latitude_rad);
        est.latitude_trig = (latitude_rad, sin_lat, cos_lat);
        est.rotation = RotationMonitor { direction, steps, short_rate_ratio, mean_rate_ratio };
        est.sway = sway;
        est.rejected = rejected;
        est.accepted = accepted;
        est.bridged = bridged;
        est.window_restarts = window_restarts;
    }

    r.pos = METHOD_OFFSET;
    let period = config.rotation_period_samples;
    let max_variance = max_variance(&config);
    // After `reinit` the target's method state is the image's.
    let state = target.map(|est| &mut est.method);
    match method {
        Method::Windowed => {
            let dst = match state {
                Some(MethodState::Windowed(m)) => Some(m),
                _ => None,
            };
            read_windowed(&mut r, dst, period, max_variance)?;
        }
        #[cfg(feature = "paper-method")]
        Method::Paper => {
            let dst = match state {
                Some(MethodState::Paper(m)) => Some(m),
                _ => None,
            };
            read_paper(&mut r, dst, period, max_variance)?;
        }
        // Not reached: `Config::check` above refused it.
        #[cfg(not(feature = "paper-method"))]
        Method::Paper => return Err(CheckpointError::InvalidConfig(ConfigError::MethodUnavailable)),
        Method::Traditional => {
            let dst = match state {
                Some(MethodState::Traditional(m)) => Some(m),
                _ => None,
            };
            read_traditional(&mut r, dst, max_variance)?;
        }
    }
    if image.get(r.pos..image.len() - CRC_LEN).is_none_or(|b| b.iter().any(|v| *v != 0)) {
        return Err(CheckpointError::Inconsistent(Part::Padding));
    }
    Ok(config)
}

fn read_windowed<const CAP: usize>(
    r: &mut Reader<'_>,
    mut dst: Option<&mut Windowed<CAP>>,
    period: usize,
    max_variance: f64,
) -> Result<(), CheckpointError> {
    let updates = r.u32();
    let mut kf = ConstantStateKalman::new([0.0; 4]);
    r.kalman(&mut kf, max_variance)?;
    let mut residual_mean = [0.0; 4];
    for v in residual_mean.iter_mut() {
        *v = r.finite(Part::Residuals)?;
        if f64::from(v.abs()) > MAX_RESIDUAL {
            return Err(CheckpointError::InvalidValue(Part::Residuals));
        }
    }
    let residual_count = r.u32();
    // A gain is 0.5 or 0.5 times a window mean of quantized cos L: 0, or at least one count
    // (2^-30) over at most CAP samples. Anything between 0 and that would blow the widened
    // 1-sigma (residual / gain) up to infinity.
    let min_gain = 0.25 / (crate::moving_average::COUNTS_PER_UNIT as f64 * CAP as f64);
    let mut gains = [0.0; 4];
    for v in gains.iter_mut() {
        *v = r.finite(Part::Residuals)?;
        let g = f64::from(*v);
        if !(g == 0.0 || (min_gain..=1.0).contains(&g)) {
            return Err(CheckpointError::InvalidValue(Part::Residuals));
        }
    }
    r.window(dst.as_deref_mut().map(|m| &mut m.window), period)?;
    if let Some(m) = dst {
        m.updates = updates;
        m.kf = kf;
        m.residual_mean = residual_mean;
        m.residual_count = residual_count;
        m.gains = gains;
    }
    Ok(())
}

#[cfg(feature = "paper-method")]
fn read_paper<const CAP: usize>(
    r: &mut Reader<'_>,
    mut dst: Option<&mut Paper<CAP>>,
    period: usize,
    max_variance: f64,
) -> Result<(), CheckpointError> {
    let updates = r.u32();
    let samples = r.u32();
    let start_time_s = r.f64();
    if !start_time_s.is_finite() {
        return Err(CheckpointError::InvalidValue(Part::PaperStartTime));
    }
    let bound = i64::from(WindowAverage::<4, CAP>::quantize(MAX_MAGNITUDE)) * i64::from(samples);
    let mut integrals = [0i64; 4];
    for v in integrals.iter_mut() {
        *v = r.i64();
        if *v > bound || *v < -bound {
            return Err(CheckpointError::InvalidValue(Part::PaperIntegrals));
        }
    }
    let mut kfs: [ConstantStateKalman<f64, 3>; 4] = core::array::from_fn(|_| ConstantStateKalman::new([0.0; 3]));
    for kf in kfs.iter_mut() {
        r.kalman(kf, max_variance)?;
    }
    r.window(dst.as_deref_mut().map(|m| &mut m.window), period)?;
    if let Some(m) = dst {
        m.updates = updates;
        m.samples = samples;
        m.start_time_s = start_time_s;
        m.integrals = integrals;
        m.kf = kfs;
    }
    Ok(())
}

fn read_traditional(r: &mut Reader<'_>, dst: Option<&mut Traditional>, max_variance: f64) -> Result<(), CheckpointError> {
    let updates = r.u32();
    let mut kf = ConstantStateKalman::new([0.0; 4]);
    r.kalman(&mut kf, max_variance)?;
    if let Some(m) = dst {
        m.updates = updates;
        m.kf = kf;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Bound, Method};
    use crate::units::{arcsec_to_rad, RAD_PER_DEG};
    use std::vec;
    use std::vec::Vec;

    #[test]
    fn crc32_matches_the_standard_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn default_image_is_13796_bytes_with_f32() {
        #[cfg(not(feature = "f64"))]
        assert_eq!(CHECKPOINT_LEN, 13_796);
        #[cfg(feature = "f64")]
        assert_eq!(CHECKPOINT_LEN, 13_988);
        assert_eq!(Estimator::<480>::CHECKPOINT_LEN, CHECKPOINT_LEN);
    }

    /// A deterministic sample: sway plus eq (2)'s oscillation for known errors, at 40 deg.
    fn sample(k: u32) -> Sample {
        let t = k as f64;
        let rho = 2.0 * core::f64::consts::PI * t / 48.0;
        let x = [200.0, -150.0, 300.0, -250.0].map(|a| arcsec_to_rad(a) as Real);
        let angles = crate::installation::Angles::new(
            crate::math::wrap_pi(rho as Real),
            0.5,
            sin_cos((40.0 * RAD_PER_DEG) as Real),
        );
        let d = angles.oscillation(&x);
        Sample {
            time_s: t,
            rotation_rad: crate::math::wrap_pi(rho as Real),
            platform_rad: 0.5,
            latitude_rad: (40.0 * RAD_PER_DEG) as Real,
            attitude: Attitude {
                heading_rad: 0.2 + d.heading_rad,
                roll_rad: 0.05 * libm::sinf(t as f32) as Real + d.roll_rad,
                pitch_rad: 0.02 * libm::sinf(0.7 * t as f32) as Real + d.pitch_rad,
            },
        }
    }

    fn running(method: Method) -> Estimator<64> {
        let config = Config { rotation_period_samples: 48, ..Config::with_method(method) };
        let mut est = Estimator::<64>::new(config).unwrap();
        for k in 0..200 {
            est.step(&sample(k)).unwrap();
        }
        assert!(est.estimate().is_some());
        est
    }

    fn image_of<const CAP: usize>(est: &Estimator<CAP>) -> Vec<u8> {
        let mut buf = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
        assert_eq!(est.checkpoint(&mut buf), Ok(buf.len()));
        buf
    }

    /// Writes an estimator whose state was tampered with (the CRC is then valid), restores it into
    /// a running one, and checks the error and that the running one did not change.
    fn rejects(tampered: &Estimator<64>, expected: CheckpointError) {
        let buf = image_of(tampered);
        let mut target = running(Method::Windowed);
        let before = target.clone();
        assert_eq!(target.restore(&buf), Err(expected));
        assert_eq!(target, before);
    }

    #[test]
    fn writer_fills_exactly_the_image_for_every_method() {
        for method in [Method::Windowed, Method::Paper, Method::Traditional] {
            let est = running(method);
            let buf = image_of(&est);
            let back = Estimator::<64>::from_checkpoint(&buf).unwrap();
            assert_eq!(back, est, "{method:?}");
            assert_eq!(crc32(&buf[..buf.len() - 4]), u32::from_le_bytes(buf[buf.len() - 4..].try_into().unwrap()));
        }
        // The windowed method is the longest: it ends exactly at the CRC.
        assert_eq!(METHOD_OFFSET + 4 + kalman_len(R, 4) + 8 * R + 4 + window_len(CHANNELS, 64), checkpoint_len(64) - 4);
    }

    #[test]
    fn tampered_states_are_refused_with_a_typed_error() {
        let base = running(Method::Windowed);
        let with_windowed = |f: &dyn Fn(&mut Windowed<64>)| {
            let mut e = base.clone();
            if let MethodState::Windowed(m) = &mut e.method {
                f(m);
            }
            e
        };
        rejects(&with_windowed(&|m| m.kf.x[2] = Real::NAN), CheckpointError::InvalidValue(Part::KalmanState));
        rejects(
            &with_windowed(&|m| m.kf.p[(3, 3)] = Real::INFINITY),
            CheckpointError::InvalidValue(Part::KalmanCovariance),
        );
        rejects(
            &with_windowed(&|m| m.kf.p[(0, 1)] += 1e-12),
            CheckpointError::NotPositiveDefinite(Part::KalmanCovariance),
        );
        rejects(
            &with_windowed(&|m| m.kf.p[(2, 2)] = -m.kf.p[(2, 2)]),
            CheckpointError::NotPositiveDefinite(Part::KalmanCovariance),
        );
        rejects(&with_windowed(&|m| m.window.sums[3] += 1), CheckpointError::Inconsistent(Part::WindowSums));
        rejects(&with_windowed(&|m| m.window.head = 48), CheckpointError::Inconsistent(Part::WindowIndices));
        rejects(&with_windowed(&|m| m.window.len = 47), CheckpointError::Inconsistent(Part::WindowIndices));
        rejects(
            &with_windowed(&|m| {
                m.window.filled = 10;
                m.window.head = 11;
            }),
            CheckpointError::Inconsistent(Part::WindowIndices),
        );
        rejects(
            &with_windowed(&|m| {
                m.window.ring[5][0] = i32::MAX;
                m.window.sums[0] += i64::from(i32::MAX);
            }),
            CheckpointError::InvalidValue(Part::WindowSamples),
        );

        let mut e = base.clone();
        e.config.measurement_sigma_rad = -1.0;
        rejects(&e, CheckpointError::InvalidConfig(ConfigError::Parameter { name: "measurement_sigma_rad", value: -1.0, bound: Bound::Positive }));
        // Regression, fuzz target `checkpoint_restore` (crash-76b5517c...): a flipped exponent made
        // the traditional random walk 1e26 rad/sqrt(s), whose square is infinite in f32.
        let mut e = base.clone();
        e.config.traditional_drift_rad_per_sqrt_s = 2.0 * Real::MAX.sqrt();
        let value = e.config.traditional_drift_rad_per_sqrt_s as f64;
        rejects(&e, CheckpointError::InvalidConfig(ConfigError::Parameter { name: "traditional_drift_rad_per_sqrt_s", value, bound: Bound::AtMost(1.0) }));
        let mut e = base.clone();
        e.config.measurement_sigma_rad = (if R == 4 { 1e-30 } else { 1e-200 }) as Real;
        let value = e.config.measurement_sigma_rad as f64;
        rejects(&e, CheckpointError::InvalidConfig(ConfigError::Parameter { name: "measurement_sigma_rad", value, bound: Bound::SquareUnderflows }));
        // Regression, fuzz target `checkpoint_restore` (slow-unit-4b0caebd..., slow-unit-91df4c6c...):
        // max_bridged_gap_samples with a flipped top byte (1.8e9) made one step bridge for minutes.
        let mut e = base.clone();
        e.config.max_bridged_gap_samples = 0x6c00_0000;
        let value = e.config.max_bridged_gap_samples as f64;
        let bound = Bound::AtMost(e.config.rotation_period_samples as f64);
        rejects(&e, CheckpointError::InvalidConfig(ConfigError::Parameter { name: "max_bridged_gap_samples", value, bound }));
        let mut e = base.clone();
        e.config.max_bridged_gap_samples = 48;
        assert_eq!(Estimator::<64>::from_checkpoint(&image_of(&e)).map(|b| b == e), Ok(true));
        let mut e = base.clone();
        e.config.rotation_period_samples = 65;
        rejects(&e, CheckpointError::InvalidConfig(ConfigError::RotationPeriod { samples: 65, capacity: 64 }));
        let mut e = base.clone();
        if let Some(p) = &mut e.previous {
            p.attitude.roll_rad = Real::NAN;
        }
        rejects(&e, CheckpointError::InvalidValue(Part::PreviousSample));
        let mut e = base.clone();
        e.latitude_trig.0 = Real::INFINITY;
        rejects(&e, CheckpointError::InvalidValue(Part::Latitude));
        let mut e = base.clone();
        e.rotation.direction = 3;
        rejects(&e, CheckpointError::InvalidValue(Part::RotationMonitor));
        let mut e = base.clone();
        e.sway.mean_square_rad2 = Real::NAN;
        rejects(&e, CheckpointError::InvalidValue(Part::SwayMonitor));

        let mut e = running(Method::Paper);
        if let MethodState::Paper(m) = &mut e.method {
            m.kf[2].p[(1, 2)] = 2.0 * m.kf[2].p[(1, 2)] + 1.0;
        }
        rejects(&e, CheckpointError::NotPositiveDefinite(Part::KalmanCovariance));
        let mut e = running(Method::Paper);
        if let MethodState::Paper(m) = &mut e.method {
            m.start_time_s = f64::NAN;
        }
        rejects(&e, CheckpointError::InvalidValue(Part::PaperStartTime));
        let mut e = running(Method::Paper);
        if let MethodState::Paper(m) = &mut e.method {
            m.integrals[1] = i64::MAX;
        }
        rejects(&e, CheckpointError::InvalidValue(Part::PaperIntegrals));
    }

    /// Regression, fuzz target `checkpoint_restore` (crash-daa82956...): an image of a paper-method
    /// estimator whose first filter's b2 state had its top byte flipped (finite, ~1e300 in f64) was
    /// accepted; the next update moved x1 beyond f32 range and the output was infinite/NaN.
    #[test]
    fn regression_fuzz_huge_finite_states_are_refused() {
        let mut e = running(Method::Paper);
        if let MethodState::Paper(m) = &mut e.method {
            m.kf[0].x[2] = 1e300;
        }
        rejects(&e, CheckpointError::InvalidValue(Part::KalmanState));
        let mut e = running(Method::Paper);
        if let MethodState::Paper(m) = &mut e.method {
            m.kf[1].p[(0, 0)] = 1e200;
        }
        rejects(&e, CheckpointError::InvalidValue(Part::KalmanCovariance));
        let base = running(Method::Windowed);
        let with_windowed = |f: &dyn Fn(&mut Windowed<64>)| {
            let mut e = base.clone();
            if let MethodState::Windowed(m) = &mut e.method {
                f(m);
            }
            e
        };
        rejects(&with_windowed(&|m| m.kf.x[0] = 1e30), CheckpointError::InvalidValue(Part::KalmanState));
        rejects(&with_windowed(&|m| m.residual_mean[2] = 1e30), CheckpointError::InvalidValue(Part::Residuals));
        rejects(&with_windowed(&|m| m.gains[3] = 1e-30), CheckpointError::InvalidValue(Part::Residuals));
        rejects(&with_windowed(&|m| m.gains[3] = -0.5), CheckpointError::InvalidValue(Part::Residuals));
        // A zero gain (what a window entirely at |L| = 90 deg - 1 ulp could give in f64) is a state
        // the running estimator can be in, so it restores.
        let e = with_windowed(&|m| m.gains[3] = 0.0);
        let buf = image_of(&e);
        assert_eq!(Estimator::<64>::from_checkpoint(&buf).map(|b| b == e), Ok(true));
    }

    #[test]
    fn bad_flag_and_nonzero_padding_are_refused() {
        let est = running(Method::Traditional);
        let mut target = running(Method::Windowed);
        let before = target.clone();
        let reseal = |buf: &mut Vec<u8>| {
            let n = buf.len();
            let crc = crc32(&buf[..n - 4]);
            buf[n - 4..].copy_from_slice(&crc.to_le_bytes());
        };
        // Padding after the traditional method's state.
        let mut buf = image_of(&est);
        let n = buf.len();
        buf[n - 10] = 1;
        reseal(&mut buf);
        assert_eq!(target.restore(&buf), Err(CheckpointError::Inconsistent(Part::Padding)));
        // gate_open flag (after config and previous sample) set to 2.
        let mut buf = image_of(&est);
        buf[HEADER_LEN + CONFIG_LEN + PREVIOUS_LEN + 1] = 2;
        reseal(&mut buf);
        assert_eq!(target.restore(&buf), Err(CheckpointError::Inconsistent(Part::Flags)));
        // Unknown method code.
        let mut buf = image_of(&est);
        buf[7] = 9;
        reseal(&mut buf);
        assert_eq!(target.restore(&buf), Err(CheckpointError::UnknownMethod(9)));
        assert_eq!(target, before);
        // And the genuine image restores, method and all.
        target.restore(&image_of(&est)).unwrap();
        assert_eq!(target, est);
    }
}
