//! Checks of the pointers a C caller passes, before anything is read or written through them.

use crate::error::RinsError;

/// `pointer` is not null and aligned for `T`: it may be read or written as a `T` (the caller
/// promises it points to one).
pub(crate) fn check<T>(pointer: *const T) -> Result<(), RinsError> {
    if pointer.is_null() {
        Err(RinsError::NullPointer)
    } else if !pointer.is_aligned() {
        Err(RinsError::Misaligned)
    } else {
        Ok(())
    }
}

/// Reads the `T` at `pointer` after [`check`]. `T` must be valid for any bit pattern (numbers
/// only: the C side may have written anything).
///
/// # Safety
/// `pointer`, if not null, points to readable memory of `size_of::<T>()` bytes.
pub(crate) unsafe fn read<T: Copy>(pointer: *const T) -> Result<T, RinsError> {
    check(pointer)?;
    // SAFETY: checked non-null and aligned; readable by the caller's promise.
    Ok(unsafe { pointer.read() })
}

/// Writes `value` to `pointer` after [`check`] (the old value is not read or dropped).
///
/// # Safety
/// `pointer`, if not null, points to writable memory of `size_of::<T>()` bytes.
pub(crate) unsafe fn write<T>(pointer: *mut T, value: T) -> Result<(), RinsError> {
    check(pointer.cast_const())?;
    // SAFETY: checked non-null and aligned; writable by the caller's promise.
    unsafe { pointer.write(value) };
    Ok(())
}

/// The `len` bytes at `pointer` (any alignment). A null pointer is refused unless `len` is 0.
///
/// # Safety
/// `pointer`, if not null, points to `len` readable bytes that nothing writes while the slice
/// lives.
pub(crate) unsafe fn bytes<'a>(pointer: *const u8, len: usize) -> Result<&'a [u8], RinsError> {
    if pointer.is_null() {
        return if len == 0 {
            Ok(&[])
        } else {
            Err(RinsError::NullPointer)
        };
    }
    // SAFETY: non-null, `u8` needs no alignment, `len` readable bytes by the caller's promise.
    Ok(unsafe { core::slice::from_raw_parts(pointer, len) })
}

/// The `len` bytes at `pointer` to write (any alignment). A null pointer is refused.
///
/// # Safety
/// `pointer`, if not null, points to `len` writable bytes that nothing else reads or writes
/// while the slice lives.
pub(crate) unsafe fn bytes_mut<'a>(
    pointer: *mut u8,
    len: usize,
) -> Result<&'a mut [u8], RinsError> {
    if pointer.is_null() {
        return Err(RinsError::NullPointer);
    }
    // SAFETY: non-null, `u8` needs no alignment, `len` writable bytes by the caller's promise.
    Ok(unsafe { core::slice::from_raw_parts_mut(pointer, len) })
}
