//! The frame around the parts: the header, written and verified, and the CRC that seals the
//! image (the layout is in the module doc of [`crate::checkpoint`]).

use super::wire::{Reader, Writer};
use super::{
    crc32, ensure, CheckpointError, CHECKPOINT_LEN, CRC_LEN, HEADER_LEN, MAGIC, R, VERSION,
};
use crate::config::Method;

/// Writes the header of an image of an estimator running `method`.
pub(crate) fn write_header(w: &mut Writer<'_>, method: Method) {
    w.bytes(&MAGIC);
    w.u16(VERSION);
    w.u8(R as u8);
    w.u8(method as u8);
    w.usize(CHECKPOINT_LEN);
}

/// Writes the CRC of everything before it into the last [`CRC_LEN`] bytes of `image`.
pub(crate) fn seal(image: &mut [u8]) {
    let len = image.len();
    let crc = crc32(image.get(..len - CRC_LEN).unwrap_or(&[]));
    if let Some(dst) = image.get_mut(len - CRC_LEN..) {
        dst.copy_from_slice(&crc.to_le_bytes());
    }
}

/// Checks the header of an image (magic, version, float width, length), the CRC and the method
/// code; returns the image (`buf[..CHECKPOINT_LEN]`) and its method.
pub(crate) fn verified_image(buf: &[u8]) -> Result<(&[u8], Method), CheckpointError> {
    let len = CHECKPOINT_LEN;
    let Some(header) = buf.get(..HEADER_LEN) else {
        return Err(CheckpointError::BufferTooSmall {
            needed: HEADER_LEN,
            available: buf.len(),
        });
    };
    let mut r = Reader::new(header, 0);
    ensure(r.array::<4>() == MAGIC, CheckpointError::BadMagic)?;
    let found = r.u16();
    ensure(
        found == VERSION,
        CheckpointError::Version {
            found,
            expected: VERSION,
        },
    )?;
    let real_bytes = r.u8();
    ensure(
        usize::from(real_bytes) == R,
        CheckpointError::RealWidthMismatch(real_bytes),
    )?;
    let method_code = r.u8();
    let found = r.u32() as usize;
    ensure(
        found == len,
        CheckpointError::LengthMismatch {
            expected: len,
            found,
        },
    )?;
    let Some(image) = buf.get(..len) else {
        return Err(CheckpointError::BufferTooSmall {
            needed: len,
            available: buf.len(),
        });
    };
    let stored = u32::from_le_bytes(Reader::new(image, len - CRC_LEN).array());
    let computed = crc32(image.get(..len - CRC_LEN).unwrap_or(&[]));
    ensure(
        stored == computed,
        CheckpointError::CrcMismatch { stored, computed },
    )?;
    let method =
        Method::try_from(method_code).map_err(|_| CheckpointError::UnknownMethod(method_code))?;
    Ok((image, method))
}
