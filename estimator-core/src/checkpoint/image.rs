//! The whole image: [`Estimator::checkpoint`], [`Estimator::restore`] and
//! [`Estimator::from_checkpoint`], the header, the CRC, and the order of the parts.

use super::wire::{Reader, Writer};
use super::{
    checkpoint_len, config, crc32, ensure, gap_fill, method_of, methods, rotation, running, time_grid, CheckpointError,
    Part, CRC_LEN, HEADER_LEN, MAGIC, METHOD_OFFSET, R, VERSION,
};
use crate::config::Config;
use crate::estimator::Estimator;

impl<const CAP: usize> Estimator<CAP> {
    /// Bytes of a checkpoint image of this estimator (23 384 for the default capacity of 720
    /// with `f32`; see [`super::checkpoint_len`]).
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
        w.bytes(&MAGIC);
        w.u16(VERSION);
        w.u8(R as u8);
        w.u8(self.config.method as u8);
        w.usize(CAP);
        w.usize(len);
        config::write(&mut w, &self.config);
        running::write(&mut w, self);
        time_grid::write(&mut w, &self.grid);
        rotation::write(&mut w, &self.rotation);
        gap_fill::write(&mut w, &self.filler);
        let mut w = Writer::new(image, METHOD_OFFSET);
        methods::write(&mut w, &self.method);
        let crc = crc32(image.get(..len - CRC_LEN).unwrap_or(&[]));
        if let Some(dst) = image.get_mut(len - CRC_LEN..) {
            dst.copy_from_slice(&crc.to_le_bytes());
        }
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
        let (image, method) = verified_image::<CAP>(buf)?;
        read_state::<CAP>(image, method, None)?;
        // The same bytes pass the same checks again, so this cannot fail half-way.
        read_state(image, method, Some(self)).map(|_| ())
    }

    /// A new estimator from a checkpoint image (see [`Estimator::restore`]). Builds the estimator
    /// by value: for hosts, not for a microcontroller's stack.
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
    let mut r = Reader::new(header, 0);
    ensure(r.array::<4>() == MAGIC, CheckpointError::BadMagic)?;
    let found = r.u16();
    ensure(found == VERSION, CheckpointError::Version { found, expected: VERSION })?;
    let real_bytes = r.u8();
    ensure(usize::from(real_bytes) == R, CheckpointError::RealWidthMismatch(real_bytes))?;
    let method_code = r.u8();
    let capacity = r.u32();
    ensure(capacity as usize == CAP, CheckpointError::CapacityMismatch(capacity))?;
    let found = r.u32() as usize;
    ensure(found == len, CheckpointError::LengthMismatch { expected: len, found })?;
    let Some(image) = buf.get(..len) else {
        return Err(CheckpointError::BufferTooSmall { needed: len, available: buf.len() });
    };
    let stored = u32::from_le_bytes(Reader::new(image, len - CRC_LEN).array());
    let computed = crc32(image.get(..len - CRC_LEN).unwrap_or(&[]));
    ensure(stored == computed, CheckpointError::CrcMismatch { stored, computed })?;
    Ok((image, method_code))
}

/// Reads and checks every part of a verified image (see the module doc) and returns its
/// configuration. With `target`, also writes the state into it, after resetting it in place to
/// that configuration; without, stores nothing. The checks are the same either way, so a target
/// is written only by a pass that cannot fail once a pass without one has succeeded.
fn read_state<const CAP: usize>(
    image: &[u8],
    method_code: u8,
    mut target: Option<&mut Estimator<CAP>>,
) -> Result<Config, CheckpointError> {
    let method = method_of(method_code)?;
    let mut r = Reader::new(image, HEADER_LEN);
    let config = config::read::<CAP>(&mut r, method)?;
    let running = running::read(&mut r)?;
    let grid = time_grid::read(&mut r, &config)?;
    let rotation = rotation::read(&mut r, &config)?;
    if let Some(est) = target.as_deref_mut() {
        est.reinit(config).map_err(CheckpointError::InvalidConfig)?;
        running.apply(est);
        est.grid = grid;
        est.rotation = rotation;
    }
    gap_fill::read(&mut r, target.as_deref_mut().map(|est| &mut est.filler))?;
    r.seek(METHOD_OFFSET);
    // After `reinit` the target's method state is the image's method's.
    methods::read(&mut r, &config, rotation.period_samples, target.map(|est| &mut est.method))?;
    let padding_start = r.pos();
    r.seek(image.len() - CRC_LEN);
    r.zeros_since(padding_start, Part::Padding)?;
    Ok(config)
}
