//! The estimator in the caller's memory: set up, one step a sample, read back.
//!
//! The caller provides a block of at least `RINS_ESTIMATOR_SIZE` bytes aligned to
//! `RINS_ESTIMATOR_ALIGN` (a static array, a member of its own state, or a heap block: the
//! library never allocates). `rins_estimator_init` builds the estimator in it and marks it; every
//! other call checks that mark, so a handle to memory that was never set up is refused with
//! `RINS_ERROR_NOT_INITIALISED` instead of being read as an estimator. The block holds no pointer
//! and no other resource: there is nothing to free.

use crate::config::RinsConfig;
use crate::error::{code, RinsError};
use crate::output::{RinsAttitude, RinsEstimate, RinsOutput, RinsSample};
use crate::pointer;
use core::ffi::c_void;
use core::mem::{align_of, size_of, MaybeUninit};
use estimator_core::{CompensateError, Estimator, Sample};

/// Bytes of memory an estimator needs, on every target (32- and 64-bit): at least
/// `rins_estimator_size()`, which is this build's exact figure. The library does not build
/// where its estimator would not fit.
pub const RINS_ESTIMATOR_SIZE: usize = 33_792;
/// Alignment of the estimator's memory, bytes (it holds `double`s).
pub const RINS_ESTIMATOR_ALIGN: usize = 8;

/// An estimator in memory the caller provides. Opaque: C code holds a pointer to it, the
/// handle `rins_estimator_init` returns.
pub struct RinsEstimator {
    /// [`MAGIC`] once set up by [`rins_estimator_init`].
    magic: u64,
    estimator: Estimator,
}

const MAGIC: u64 = u64::from_le_bytes(*b"RINS-EST");

// The header's constants hold on every target the library is built for.
const _: () = assert!(size_of::<RinsEstimator>() <= RINS_ESTIMATOR_SIZE);
const _: () = assert!(align_of::<RinsEstimator>() <= RINS_ESTIMATOR_ALIGN);

/// The estimator behind a handle: checked (null, alignment) and set up by
/// [`rins_estimator_init`].
///
/// # Safety
/// `handle` is null or points to at least `size_of::<RinsEstimator>()` readable bytes that
/// nothing writes while the reference lives.
pub(crate) unsafe fn from_handle<'a>(
    handle: *const RinsEstimator,
) -> Result<&'a Estimator, RinsError> {
    pointer::check(handle)?;
    // SAFETY: checked; the mark is read as a plain integer, whatever the memory holds.
    let magic = unsafe { core::ptr::addr_of!((*handle).magic).read() };
    if magic != MAGIC {
        return Err(RinsError::NotInitialised);
    }
    // SAFETY: marked: `rins_estimator_init` wrote an estimator there.
    Ok(unsafe { &(*handle).estimator })
}

/// [`from_handle`], to change.
///
/// # Safety
/// As for [`from_handle`], and nothing else reads or writes the memory while the reference lives.
pub(crate) unsafe fn from_handle_mut<'a>(
    handle: *mut RinsEstimator,
) -> Result<&'a mut Estimator, RinsError> {
    // SAFETY: the caller's promise.
    unsafe { from_handle(handle) }?;
    // SAFETY: checked and marked above; exclusive by the caller's promise.
    Ok(unsafe { &mut (*handle).estimator })
}

/// Bytes this build's estimator takes (at most `RINS_ESTIMATOR_SIZE`).
#[no_mangle]
pub extern "C" fn rins_estimator_size() -> usize {
    size_of::<RinsEstimator>()
}

/// Builds a fresh estimator with `*config` in `memory` (`size` bytes, aligned to
/// `RINS_ESTIMATOR_ALIGN`) and stores its handle in `*estimator`. On any error nothing is
/// written: `RINS_ERROR_NULL_POINTER`, `RINS_ERROR_MISALIGNED`, `RINS_ERROR_BUFFER_TOO_SMALL`
/// (`size` below `rins_estimator_size()`), `RINS_ERROR_INVALID_CONFIG` (see
/// `rins_config_check`). Calling it again on the same memory starts afresh.
///
/// # Safety
/// `memory` is null or points to `size` writable bytes that nothing else uses while the
/// estimator lives; `config` is null or points to a readable `RinsConfig`; `estimator` is null
/// or points to a writable handle.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_init(
    memory: *mut c_void,
    size: usize,
    config: *const RinsConfig,
    estimator: *mut *mut RinsEstimator,
) -> RinsError {
    // SAFETY: the caller's promises.
    code(unsafe { init(memory, size, config, estimator) })
}

/// [`rins_estimator_init`] with `?`.
///
/// # Safety
/// As for [`rins_estimator_init`].
unsafe fn init(
    memory: *mut c_void,
    size: usize,
    config: *const RinsConfig,
    estimator: *mut *mut RinsEstimator,
) -> Result<(), RinsError> {
    pointer::check(estimator.cast_const())?;
    // SAFETY: the caller's promise.
    let config = unsafe { pointer::read(config) }?;
    let slot = memory.cast::<RinsEstimator>();
    pointer::check(slot.cast_const())?;
    if size < size_of::<RinsEstimator>() {
        return Err(RinsError::BufferTooSmall);
    }
    let config = config.to_core().map_err(|_| RinsError::InvalidConfig)?;
    // SAFETY: checked non-null, aligned and large enough; writable by the caller's promise, and
    // used by nothing else. The estimator is built in place (`Estimator::init_in`: nothing the
    // size of the state passes through the stack) and only then marked; the old content is not
    // read or dropped (it holds nothing to drop).
    unsafe {
        let field = core::ptr::addr_of_mut!((*slot).estimator).cast::<MaybeUninit<Estimator>>();
        Estimator::init_in(&mut *field, config).map_err(|_| RinsError::InvalidConfig)?;
        core::ptr::addr_of_mut!((*slot).magic).write(MAGIC);
        estimator.write(slot);
    }
    Ok(())
}

/// Processes one sample, once a sample. `RINS_ERROR_OK`: accepted, `*output` holds the status,
/// the estimate (if any yet) and the corrected attitude. `RINS_ERROR_SAMPLE_REJECTED`: refused
/// (a field NaN or out of range, a time that does not increase or is off the sample grid);
/// `*output` holds the reason (`status`, `rejected_field`) and the estimate held, and the
/// estimator is exactly as it was. Other errors write nothing.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no other call uses at the same
/// time; `sample` is null or points to a readable `RinsSample`; `output` is null or points to a
/// writable `RinsOutput`.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_step(
    estimator: *mut RinsEstimator,
    sample: *const RinsSample,
    output: *mut RinsOutput,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            from_handle_mut(estimator),
            pointer::read(sample),
            pointer::check(output.cast_const()),
        )
    };
    let (est, sample) = match checked {
        (Ok(est), Ok(sample), Ok(())) => (est, sample),
        (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => return e,
    };
    let (out, result) = match est.step(&Sample::from(&sample)) {
        Ok(out) => (RinsOutput::accepted(&out), RinsError::Ok),
        Err(e) => (
            RinsOutput::rejected(sample.time_s, &e, est.estimate().as_ref(), &est.health()),
            RinsError::SampleRejected,
        ),
    };
    // SAFETY: checked above; writable by the caller's promise.
    unsafe { output.write(out) };
    result
}

/// The current estimate and its 1-sigma into `*estimate`; `RINS_ERROR_NO_ESTIMATE` (nothing
/// written) before the filter's first measurement.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no call changes at the same
/// time; `estimate` is null or points to a writable `RinsEstimate`.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_estimate(
    estimator: *const RinsEstimator,
    estimate: *mut RinsEstimate,
) -> RinsError {
    // SAFETY: the caller's promise.
    let est = match unsafe { estimator_ref_and_check(estimator, estimate) } {
        Ok(est) => est,
        Err(e) => return e,
    };
    match est.estimate() {
        // SAFETY: checked; writable by the caller's promise.
        Some(e) => code(unsafe { pointer::write(estimate, RinsEstimate::from(&e)) }),
        None => RinsError::NoEstimate,
    }
}

/// Applies the current estimate to one attitude sample without stepping the estimator, for
/// attitude that comes faster than the estimator's grid (100-200 Hz): `*attitude` receives the
/// sample's heading, roll and pitch with eq (2)'s oscillation removed, rad (heading in
/// [-pi, pi]), exactly as `rins_estimator_step` corrects a sample it steps (bit for bit, for the
/// same sample and estimate). The sample's time is not used. `RINS_ERROR_NO_ESTIMATE` before the
/// filter's first measurement and `RINS_ERROR_SAMPLE_REJECTED` for a field a step would refuse
/// (NaN, infinite, out of range) write nothing; the estimator is never changed, so a program may
/// call it from a faster loop than the step's as long as no step runs at the same time.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no call changes at the same
/// time; `sample` is null or points to a readable `RinsSample`; `attitude` is null or points to a
/// writable `RinsAttitude`.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_compensate(
    estimator: *const RinsEstimator,
    sample: *const RinsSample,
    attitude: *mut RinsAttitude,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            estimator_ref_and_check(estimator, attitude),
            pointer::read(sample),
        )
    };
    let (est, sample) = match checked {
        (Ok(est), Ok(sample)) => (est, sample),
        (Err(e), _) | (_, Err(e)) => return e,
    };
    match est.compensate(&Sample::from(&sample)) {
        // SAFETY: checked; writable by the caller's promise.
        Ok(a) => code(unsafe { pointer::write(attitude, RinsAttitude::from(&a)) }),
        Err(CompensateError::NoEstimate) => RinsError::NoEstimate,
        Err(CompensateError::Rejected(_)) => RinsError::SampleRejected,
    }
}

/// What the estimator has counted since it was set up or reset (each saturates at 2^32 - 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct RinsCounters {
    /// Samples accepted.
    pub accepted: u32,
    /// Samples rejected (every reason; rejections are not cleared by `rins_estimator_reset`).
    pub rejected: u32,
    /// Lost samples filled from their neighbours.
    pub filled: u32,
    /// Restarts of the moving average (gaps too long to fill, clock steps, rotation faults).
    pub window_restarts: u32,
    /// Clock jumps and steps backwards in the time stamps.
    pub clock_steps: u32,
    /// Samples rejected, by reason, in the order of the `RINS_STATUS_REJECTED_...` codes (index =
    /// code - 128): non-finite, latitude out of range, angle out of range, time not increasing,
    /// irregular time step.
    pub rejected_by_reason: [u32; 5],
    /// Changes of the installation errors declared (`RINS_STATUS_ERRORS_CHANGED`).
    pub changes_detected: u32,
    /// Samples whose status was `RINS_STATUS_MODEL_MISMATCH`.
    pub mismatch_samples: u32,
}

/// The estimator's counters into `*counters`.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no call changes at the same
/// time; `counters` is null or points to a writable `RinsCounters`.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_counters(
    estimator: *const RinsEstimator,
    counters: *mut RinsCounters,
) -> RinsError {
    // SAFETY: the caller's promise.
    let est = match unsafe { estimator_ref_and_check(estimator, counters) } {
        Ok(est) => est,
        Err(e) => return e,
    };
    let c = est.counters();
    let value = RinsCounters {
        accepted: c.accepted,
        rejected: est.rejected().total(),
        filled: c.filled,
        window_restarts: c.window_restarts,
        clock_steps: c.clock_steps,
        rejected_by_reason: est.rejected().0,
        changes_detected: c.changes_detected,
        mismatch_samples: c.mismatch_samples,
    };
    // SAFETY: checked; writable by the caller's promise.
    code(unsafe { pointer::write(counters, value) })
}

/// Forgets everything learnt (sample interval, rotation pattern, window, filter), as after
/// `rins_estimator_init` with the same configuration; keeps the rejection count. For a RINS
/// whose installation has changed.
///
/// # Safety
/// `estimator` is null or a handle from `rins_estimator_init` that no other call uses at the same
/// time.
#[no_mangle]
pub unsafe extern "C" fn rins_estimator_reset(estimator: *mut RinsEstimator) -> RinsError {
    // SAFETY: the caller's promise.
    match unsafe { from_handle_mut(estimator) } {
        Ok(est) => {
            est.reset();
            RinsError::Ok
        }
        Err(e) => e,
    }
}

/// The estimator behind `handle` after checking the out-pointer `out` too.
///
/// # Safety
/// As for [`from_handle`].
unsafe fn estimator_ref_and_check<'a, T>(
    handle: *const RinsEstimator,
    out: *mut T,
) -> Result<&'a Estimator, RinsError> {
    // SAFETY: the caller's promise.
    let est = unsafe { from_handle(handle) }?;
    pointer::check(out.cast_const())?;
    Ok(est)
}
