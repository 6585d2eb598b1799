//! Bytes in and out of the image: a sequential little-endian writer and reader.
//!
//! The writer drops bytes past the end and the reader reads zeros past the end: the image length
//! is computed from the same layout, so neither happens (a test checks that the writer ends
//! exactly where the layout says each part ends), and a reader that ran past the end would fail a
//! later check at worst, never panic.

use super::{CheckpointError, Part};
use crate::Real;
use nalgebra::RealField;

/// Sequential writer into a zero-filled image.
pub(crate) struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl<'a> Writer<'a> {
    /// A writer at `pos` of `buf`.
    pub(crate) fn new(buf: &'a mut [u8], pos: usize) -> Self {
        Writer { buf, pos }
    }

    /// Bytes written so far, from the start of the buffer.
    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    /// Moves on by `n` bytes, leaving them as they are (zero in a fresh image).
    pub(crate) fn skip(&mut self, n: usize) {
        self.pos += n;
    }

    pub(crate) fn bytes(&mut self, b: &[u8]) {
        if let Some(dst) = self.buf.get_mut(self.pos..self.pos + b.len()) {
            dst.copy_from_slice(b);
        }
        self.pos += b.len();
    }
    pub(crate) fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    pub(crate) fn i8(&mut self, v: i8) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn flag(&mut self, v: bool) {
        self.u8(u8::from(v));
    }
    pub(crate) fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    /// A `usize` that fits in 32 bits (lengths and indices of windows of at most `CAP` entries).
    pub(crate) fn usize(&mut self, v: usize) {
        self.u32(u32::try_from(v).unwrap_or(u32::MAX));
    }
    #[cfg_attr(not(feature = "paper-method"), allow(dead_code))]
    pub(crate) fn i64(&mut self, v: i64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f64(&mut self, v: f64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn real(&mut self, v: Real) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn float<T: Float>(&mut self, v: T) {
        v.put(self);
    }

    /// An optional value: a flag byte, then `put(value)`, or `put(zero)` when absent (`zero` must
    /// write only zero bytes, which the reader checks).
    pub(crate) fn option<T>(&mut self, v: Option<T>, zero: T, put: impl FnOnce(&mut Self, T)) {
        self.flag(v.is_some());
        put(self, v.unwrap_or(zero));
    }
}

/// Sequential reader over an image whose length has been checked.
pub(crate) struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// A reader at `pos` of `buf`.
    pub(crate) fn new(buf: &'a [u8], pos: usize) -> Self {
        Reader { buf, pos }
    }

    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    /// Moves on by `n` bytes without reading them.
    pub(crate) fn skip(&mut self, n: usize) {
        self.pos += n;
    }

    pub(crate) fn array<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(src) = self.buf.get(self.pos..self.pos + N) {
            out.copy_from_slice(src);
        }
        self.pos += N;
        out
    }
    #[inline(never)]
    pub(crate) fn u8(&mut self) -> u8 {
        self.array::<1>()[0]
    }
    #[inline(never)]
    pub(crate) fn i8(&mut self) -> i8 {
        i8::from_le_bytes(self.array())
    }
    #[inline(never)]
    pub(crate) fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.array())
    }
    #[inline(never)]
    pub(crate) fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.array())
    }
    #[cfg_attr(not(feature = "paper-method"), allow(dead_code))]
    #[inline(never)]
    pub(crate) fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.array())
    }
    #[inline(never)]
    pub(crate) fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.array())
    }
    #[inline(never)]
    pub(crate) fn real(&mut self) -> Real {
        Real::from_le_bytes(self.array())
    }
    pub(crate) fn float<T: Float>(&mut self) -> T {
        T::get(self)
    }

    /// A flag byte: 0 or 1, anything else is an invalid value of `part`.
    pub(crate) fn flag(&mut self, part: Part) -> Result<bool, CheckpointError> {
        match self.u8() {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(CheckpointError::InvalidValue(part)),
        }
    }

    /// An optional value written by [`Writer::option`]: the flag, then `get` reads the value (as
    /// stored, unchecked); when the flag says absent, every byte `get` read must be zero.
    pub(crate) fn option<T>(
        &mut self,
        part: Part,
        get: impl FnOnce(&mut Self) -> Result<T, CheckpointError>,
    ) -> Result<Option<T>, CheckpointError> {
        let present = self.flag(part)?;
        let start = self.pos;
        let value = get(self)?;
        if present {
            return Ok(Some(value));
        }
        self.zeros_since(start, part)?;
        Ok(None)
    }

    /// Every byte from `start` to the current position is zero, or [`CheckpointError::UnusedNotZero`].
    pub(crate) fn zeros_since(&self, start: usize, part: Part) -> Result<(), CheckpointError> {
        match self.buf.get(start..self.pos) {
            Some(b) if b.iter().all(|v| *v == 0) => Ok(()),
            _ => Err(CheckpointError::UnusedNotZero(part)),
        }
    }
}

/// The floats a Kalman filter is kept in (`Real`, and `f64` for the paper's filters).
pub(crate) trait Float: Copy + RealField {
    fn put(self, w: &mut Writer<'_>);
    fn get(r: &mut Reader<'_>) -> Self;
    fn to_f64(self) -> f64;
}

impl Float for f32 {
    fn put(self, w: &mut Writer<'_>) {
        w.bytes(&self.to_le_bytes());
    }
    fn get(r: &mut Reader<'_>) -> Self {
        f32::from_le_bytes(r.array())
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl Float for f64 {
    fn put(self, w: &mut Writer<'_>) {
        w.f64(self);
    }
    fn get(r: &mut Reader<'_>) -> Self {
        r.f64()
    }
    fn to_f64(self) -> f64 {
        self
    }
}
