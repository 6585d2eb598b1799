//! Checkpoints: what a restarted estimator needs to go on, as a small, versioned, CRC-protected
//! image in the caller's buffer (for flash, EEPROM or a file), and back. The image's layout is the
//! core's (`estimator_core::checkpoint`); the firmware writes the same images.

use crate::error::RinsError;
use crate::estimator::{from_handle, from_handle_mut, RinsEstimator};
use crate::pointer;
use estimator_core::Estimator;

/// Bytes of a checkpoint image: the buffer `rins_estimator_checkpoint` needs.
pub const RINS_CHECKPOINT_LEN: usize = <Estimator>::CHECKPOINT_LEN;

/// Writes what a restart needs (the configuration, the filter and what it learned of noise and
/// drift, the sample interval and rotation pattern, health, counters, the last sample's time;
/// not the one-period window, which the next samples refill) into `buffer` (`capacity` bytes, at
/// least `RINS_CHECKPOINT_LEN`) and the image's length into `*written`.
/// `RINS_ERROR_BUFFER_TOO_SMALL` leaves the buffer as it was. The estimator is not changed.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no call changes at the same
/// time; `buffer` is null or points to `capacity` writable bytes; `written` is null or points to a
/// writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_checkpoint(
    estimator: *const RinsEstimator,
    buffer: *mut u8,
    capacity: usize,
    written: *mut usize,
) -> RinsError {
    // SAFETY: the caller's promises.
    let (est, buffer) = match unsafe { estimator_and_output(estimator, buffer, capacity, written) }
    {
        Ok(checked) => checked,
        Err(e) => return e,
    };
    match est.checkpoint(buffer) {
        Ok(len) => {
            // SAFETY: checked above; writable by the caller's promise.
            unsafe { written.write(len) };
            RinsError::Ok
        }
        Err(e) => RinsError::from(e),
    }
}

/// Replaces the estimator's state (its configuration included) with the image in `buffer`
/// (`len` bytes, as `rins_estimator_checkpoint` wrote them; a longer buffer is fine). The estimate
/// and its 1-sigma are reported again from the next sample on, with `RINS_STATUS_HOLDING` while
/// the window refills (one rotation period), as after a long gap. Every part of the image is
/// checked before anything is changed: on `RINS_ERROR_CHECKPOINT_CORRUPT`,
/// `RINS_ERROR_CHECKPOINT_INCOMPATIBLE` or `RINS_ERROR_BUFFER_TOO_SMALL` the estimator is exactly
/// as it was, so a program at boot sets up a fresh estimator, tries to restore, and runs on either
/// way.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no other call uses at the same
/// time; `buffer` is null or points to `len` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_restore(
    estimator: *mut RinsEstimator,
    buffer: *const u8,
    len: usize,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe { (from_handle_mut(estimator), pointer::bytes(buffer, len)) };
    let (est, image) = match checked {
        (Ok(est), Ok(image)) => (est, image),
        (Err(e), _) | (_, Err(e)) => return e,
    };
    match est.restore(image) {
        Ok(()) => RinsError::Ok,
        Err(e) => RinsError::from(e),
    }
}

/// Bytes of a learned-errors record: the buffer `rins_estimator_learned` needs.
pub const RINS_LEARNED_LEN: usize = estimator_core::learned::LEARNED_LEN;

/// Writes the learned errors (the estimate, its 1-sigma and the last sample's time) as a small
/// record whose layout every later version of the library reads (`docs/interface.md`), into
/// `buffer` (`capacity` bytes, at least `RINS_LEARNED_LEN`), and its length into `*written`. Save it
/// beside the checkpoint: a later build that refuses the checkpoint (another format version)
/// starts from it with `rins_estimator_start_from_learned`. `RINS_ERROR_NO_ESTIMATE` before the
/// first estimate and `RINS_ERROR_BUFFER_TOO_SMALL` write nothing. The estimator is not changed.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no call changes at the same
/// time; `buffer` is null or points to `capacity` writable bytes; `written` is null or points to a
/// writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_learned(
    estimator: *const RinsEstimator,
    buffer: *mut u8,
    capacity: usize,
    written: *mut usize,
) -> RinsError {
    // SAFETY: the caller's promises.
    let (est, buffer) = match unsafe { estimator_and_output(estimator, buffer, capacity, written) }
    {
        Ok(checked) => checked,
        Err(e) => return e,
    };
    let Some(learned) = est.learned_errors() else {
        return RinsError::NoEstimate;
    };
    let Some(out) = buffer.get_mut(..RINS_LEARNED_LEN) else {
        return RinsError::BufferTooSmall;
    };
    out.copy_from_slice(&learned.encode());
    // SAFETY: checked above; writable by the caller's promise.
    unsafe { written.write(RINS_LEARNED_LEN) };
    RinsError::Ok
}

/// Starts the estimator afresh from a learned-errors record (`len` bytes at `buffer`, as
/// `rins_estimator_learned` of this or an earlier version wrote it): as from known values, the
/// record's estimate is reported, and compensates the attitude, from the next sample, with a
/// 1-sigma of at least 1 arcsec, and the log refines it; everything else learned is forgotten (as
/// `rins_estimator_reset`). For a program whose `rins_estimator_restore` refused its checkpoint
/// with `RINS_ERROR_CHECKPOINT_INCOMPATIBLE` after a software update.
/// `RINS_ERROR_CHECKPOINT_CORRUPT` (not a record, damaged, values out of bounds) changes nothing.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no other call uses at the same
/// time; `buffer` is null or points to `len` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_start_from_learned(
    estimator: *mut RinsEstimator,
    buffer: *const u8,
    len: usize,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe { (from_handle_mut(estimator), pointer::bytes(buffer, len)) };
    let (est, bytes) = match checked {
        (Ok(est), Ok(bytes)) => (est, bytes),
        (Err(e), _) | (_, Err(e)) => return e,
    };
    let Ok((learned, _)) = estimator_core::learned::LearnedErrors::decode(bytes) else {
        return RinsError::CheckpointCorrupt;
    };
    match est.start_from_learned(&learned) {
        Ok(()) => RinsError::Ok,
        Err(_) => RinsError::CheckpointCorrupt,
    }
}

/// The estimator and the output buffer of a call that writes bytes out (a checkpoint, the learned
/// errors), every pointer checked; of several errors, the estimator's first, then `written`'s,
/// then the buffer's.
///
/// # Safety
/// The calls' promises: `estimator` is null or a live handle no call changes meanwhile; `buffer`
/// is null or points to `capacity` writable bytes; `written` is null or points to a `size_t`.
unsafe fn estimator_and_output<'a>(
    estimator: *const RinsEstimator,
    buffer: *mut u8,
    capacity: usize,
    written: *mut usize,
) -> Result<(&'a Estimator, &'a mut [u8]), RinsError> {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            from_handle(estimator),
            pointer::check(written.cast_const()),
            pointer::bytes_mut(buffer, capacity),
        )
    };
    match checked {
        (Ok(est), Ok(()), Ok(buffer)) => Ok((est, buffer)),
        (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => Err(e),
    }
}
