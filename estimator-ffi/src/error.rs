//! What every function of the library returns.

use core::ffi::c_char;
use estimator_core::checkpoint::CheckpointError;

/// The result of a call: `RINS_ERROR_OK`, or why nothing was done. A function that returns an
/// error has changed nothing, except where its description says otherwise
/// (`rins_estimator_step` fills its output for a rejected sample too).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum RinsError {
    /// Done.
    Ok = 0,
    /// A pointer argument is null.
    NullPointer = 1,
    /// A pointer argument is not aligned for its type (the estimator's memory: to
    /// `RINS_ESTIMATOR_ALIGN`).
    Misaligned = 2,
    /// A buffer or memory block is smaller than the call needs (`RINS_ESTIMATOR_SIZE`,
    /// `RINS_CHECKPOINT_LEN`, `RINS_ROW_MAX_LEN`).
    BufferTooSmall = 3,
    /// The estimator handle was not set up by `rins_estimator_init`.
    NotInitialised = 4,
    /// The configuration is out of its bounds, or names a method this build does not have
    /// (`rins_config_check` says which parameter and why).
    InvalidConfig = 5,
    /// A struct passed in holds a value no call of the library writes there (an unknown status
    /// code, a `bool` that is neither 0 nor 1).
    InvalidArgument = 6,
    /// The estimator refused the sample (the output's status says why); its state is unchanged.
    SampleRejected = 7,
    /// There is no estimate yet.
    NoEstimate = 8,
    /// The checkpoint is not an intact image: no image at all, a CRC that does not match, or
    /// values out of their bounds. The estimator is unchanged.
    CheckpointCorrupt = 9,
    /// The checkpoint was written by another build: another format version, float width or
    /// image length, or a method this build does not have. The estimator is unchanged.
    CheckpointIncompatible = 10,
    /// The text is not a number as the log reader reads one.
    NotANumber = 11,
}

impl RinsError {
    /// Every error, in code order.
    pub(crate) const ALL: [RinsError; 12] = [
        RinsError::Ok,
        RinsError::NullPointer,
        RinsError::Misaligned,
        RinsError::BufferTooSmall,
        RinsError::NotInitialised,
        RinsError::InvalidConfig,
        RinsError::InvalidArgument,
        RinsError::SampleRejected,
        RinsError::NoEstimate,
        RinsError::CheckpointCorrupt,
        RinsError::CheckpointIncompatible,
        RinsError::NotANumber,
    ];

    /// The name in C, for messages.
    fn c_name(self) -> &'static core::ffi::CStr {
        match self {
            RinsError::Ok => c"RINS_ERROR_OK",
            RinsError::NullPointer => c"RINS_ERROR_NULL_POINTER",
            RinsError::Misaligned => c"RINS_ERROR_MISALIGNED",
            RinsError::BufferTooSmall => c"RINS_ERROR_BUFFER_TOO_SMALL",
            RinsError::NotInitialised => c"RINS_ERROR_NOT_INITIALISED",
            RinsError::InvalidConfig => c"RINS_ERROR_INVALID_CONFIG",
            RinsError::InvalidArgument => c"RINS_ERROR_INVALID_ARGUMENT",
            RinsError::SampleRejected => c"RINS_ERROR_SAMPLE_REJECTED",
            RinsError::NoEstimate => c"RINS_ERROR_NO_ESTIMATE",
            RinsError::CheckpointCorrupt => c"RINS_ERROR_CHECKPOINT_CORRUPT",
            RinsError::CheckpointIncompatible => c"RINS_ERROR_CHECKPOINT_INCOMPATIBLE",
            RinsError::NotANumber => c"RINS_ERROR_NOT_A_NUMBER",
        }
    }
}

/// The code of a call that returns `Result`.
pub(crate) fn code(result: Result<(), RinsError>) -> RinsError {
    match result {
        Ok(()) => RinsError::Ok,
        Err(e) => e,
    }
}

impl From<CheckpointError> for RinsError {
    fn from(e: CheckpointError) -> RinsError {
        use estimator_core::ConfigError;
        match e {
            CheckpointError::BufferTooSmall { .. } => RinsError::BufferTooSmall,
            CheckpointError::Version { .. }
            | CheckpointError::RealWidthMismatch(_)
            | CheckpointError::LengthMismatch { .. }
            | CheckpointError::UnknownMethod(_)
            | CheckpointError::InvalidConfig(ConfigError::MethodUnavailable) => {
                RinsError::CheckpointIncompatible
            }
            CheckpointError::BadMagic
            | CheckpointError::CrcMismatch { .. }
            | CheckpointError::InvalidConfig(_)
            | CheckpointError::InvalidValue(_)
            | CheckpointError::NotPositiveDefinite(_)
            | CheckpointError::Inconsistent(_)
            | CheckpointError::UnusedNotZero(_) => RinsError::CheckpointCorrupt,
        }
    }
}

/// The name of an error code as the header spells it (`"RINS_ERROR_BUFFER_TOO_SMALL"`), a
/// NUL-terminated string the library keeps; `"RINS_ERROR_UNKNOWN"` for a code that is none of
/// `RinsError`'s.
#[no_mangle]
pub extern "C" fn rins_error_name(error: u32) -> *const c_char {
    RinsError::ALL
        .iter()
        .find(|e| **e as u32 == error)
        .map_or(c"RINS_ERROR_UNKNOWN", |e| e.c_name())
        .as_ptr()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use core::ffi::CStr;

    #[test]
    fn codes_are_in_order_and_names_follow_the_header() {
        for (i, e) in RinsError::ALL.iter().enumerate() {
            assert_eq!(*e as u32, i as u32);
            // SAFETY: the library's own NUL-terminated strings.
            let name = unsafe { CStr::from_ptr(rins_error_name(*e as u32)) }
                .to_str()
                .unwrap();
            assert!(name.starts_with("RINS_ERROR_"), "{name}");
            let expected: std::string::String = std::format!("{e:?}")
                .chars()
                .flat_map(|c| {
                    if c.is_uppercase() {
                        std::vec!['_', c]
                    } else {
                        std::vec![c.to_ascii_uppercase()]
                    }
                })
                .collect();
            assert_eq!(name, std::format!("RINS_ERROR{expected}"));
        }
        // SAFETY: as above.
        let unknown = unsafe { CStr::from_ptr(rins_error_name(12)) };
        assert_eq!(unknown.to_str().unwrap(), "RINS_ERROR_UNKNOWN");
    }
}
