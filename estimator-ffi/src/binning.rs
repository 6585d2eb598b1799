//! Attitude at up to 200 Hz into the estimator's grid: a binner averages the samples as they come
//! into bins of the grid interval (`estimator_core::binning`, docs/interface.md) and hands back one
//! averaged sample a bin, for `rins_estimator_step`. In the caller's memory (`RinsBinner`, a plain
//! struct of `RINS_BINNER_SIZE` bytes), no allocation.

use crate::error::RinsError;
use crate::output::RinsSample;
use crate::pointer;
use estimator_core::binning::Binner;
use estimator_core::Sample;

/// A binner in memory the caller provides (a static, a member of its own state, a local):
/// opaque, set up by `rins_binner_init`.
#[derive(Clone, Copy)]
#[repr(C)]
pub struct RinsBinner {
    /// The binner's state, and a mark that `rins_binner_init` set it up.
    pub opaque: [u64; 32],
}

/// Bytes of a `RinsBinner`.
pub const RINS_BINNER_SIZE: usize = core::mem::size_of::<RinsBinner>();

/// What `RinsBinner::opaque` holds.
#[repr(C)]
struct Slot {
    magic: u64,
    binner: Binner,
}

const MAGIC: u64 = u64::from_le_bytes(*b"RINS-BIN");

const _: () = assert!(core::mem::size_of::<Slot>() <= RINS_BINNER_SIZE);
const _: () = assert!(core::mem::align_of::<Slot>() <= core::mem::align_of::<RinsBinner>());

/// The binner behind `binner`, checked (null, alignment, set up).
///
/// # Safety
/// `binner` is null or points to a `RinsBinner` that nothing else uses while the reference lives.
unsafe fn binner_mut<'a>(binner: *mut RinsBinner) -> Result<&'a mut Binner, RinsError> {
    pointer::check(binner.cast_const())?;
    let slot = binner.cast::<Slot>();
    // SAFETY: checked; the mark is read as a plain integer, whatever the memory holds.
    if unsafe { core::ptr::addr_of!((*slot).magic).read() } != MAGIC {
        return Err(RinsError::NotInitialised);
    }
    // SAFETY: marked: `rins_binner_init` wrote a binner there; exclusive by the caller's promise.
    Ok(unsafe { &mut (*slot).binner })
}

/// The core's sample as the C side's, in degrees: what `rins_estimator_step` turns back into the
/// same sample (`host-sim estimate --bin-interval-s` makes the same round trip).
fn in_degrees(s: &Sample) -> RinsSample {
    let [time_s, rotation_deg, platform_deg, latitude_deg, heading_deg, roll_deg, pitch_deg] =
        s.to_degrees();
    RinsSample {
        time_s,
        rotation_deg,
        platform_deg,
        latitude_deg,
        heading_deg,
        roll_deg,
        pitch_deg,
    }
}

/// Sets up `*binner` for bins of `bin_interval_s` (0.1 to 10 s, the estimator's grid interval;
/// bins aligned to its multiples). `RINS_ERROR_INVALID_CONFIG` for an interval out of range;
/// nothing written on any error. Calling it again starts afresh.
///
/// # Safety
/// `binner` is null or points to a writable `RinsBinner`.
#[no_mangle]
pub unsafe extern "C" fn rins_binner_init(
    binner: *mut RinsBinner,
    bin_interval_s: f64,
) -> RinsError {
    if let Err(e) = pointer::check(binner.cast_const()) {
        return e;
    }
    let Ok(b) = Binner::new(bin_interval_s) else {
        return RinsError::InvalidConfig;
    };
    // SAFETY: checked non-null and aligned; `Slot` fits (asserted above).
    unsafe {
        binner.cast::<Slot>().write(Slot {
            magic: MAGIC,
            binner: b,
        })
    };
    RinsError::Ok
}

/// Takes one attitude sample (at any rate, up to 200 Hz). When it opens a later bin, the average
/// of the bin before it (stamped at the bin's centre) goes into `*binned` and `*ready` is true:
/// step the estimator with it. Otherwise `*ready` is false and `*binned` is not written.
/// `RINS_ERROR_SAMPLE_REJECTED` for a field a step would refuse or a time not after the last
/// one: the binner is unchanged, `*ready` false.
///
/// # Safety
/// `binner` is null or a `RinsBinner` set up by `rins_binner_init` that no other call uses at the
/// same time; `sample` is null or points to a readable `RinsSample`; `binned` and `ready` are null
/// or point to a writable `RinsSample` and `bool`.
#[no_mangle]
pub unsafe extern "C" fn rins_binner_push(
    binner: *mut RinsBinner,
    sample: *const RinsSample,
    binned: *mut RinsSample,
    ready: *mut bool,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            binner_mut(binner),
            pointer::read(sample),
            pointer::check(binned.cast_const()),
            pointer::check(ready.cast_const()),
        )
    };
    let (b, sample) = match checked {
        (Ok(b), Ok(s), Ok(()), Ok(())) => (b, s),
        (Err(e), _, _, _) | (_, Err(e), _, _) | (_, _, Err(e), _) | (_, _, _, Err(e)) => return e,
    };
    let (result, done) = match b.push(&Sample::from(&sample)) {
        Ok(done) => (RinsError::Ok, done),
        Err(_) => (RinsError::SampleRejected, None),
    };
    // SAFETY: checked above; writable by the caller's promise.
    unsafe {
        if let Some(s) = done {
            binned.write(in_degrees(&s));
        }
        ready.write(done.is_some());
    }
    result
}

/// The average of the bin being filled, if it holds a sample (at the end of a log): into
/// `*binned`, `*ready` true; otherwise `*ready` false. The binner is then empty.
///
/// # Safety
/// As for `rins_binner_push`.
#[no_mangle]
pub unsafe extern "C" fn rins_binner_finish(
    binner: *mut RinsBinner,
    binned: *mut RinsSample,
    ready: *mut bool,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            binner_mut(binner),
            pointer::check(binned.cast_const()),
            pointer::check(ready.cast_const()),
        )
    };
    let b = match checked {
        (Ok(b), Ok(()), Ok(())) => b,
        (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => return e,
    };
    let done = b.finish();
    // SAFETY: checked above; writable by the caller's promise.
    unsafe {
        if let Some(s) = done {
            binned.write(in_degrees(&s));
        }
        ready.write(done.is_some());
    }
    RinsError::Ok
}
