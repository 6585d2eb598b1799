//! Text as `host-sim` writes and reads it: the estimates CSV's header and rows (formatted by the
//! core's [`estimator_core::estimates_csv`], the code `host-sim` runs, so a C program's file is
//! byte-identical to `host-sim estimate`'s) and the log's numbers (read by the same function
//! `host-sim`'s reader uses, so the estimator gets the same bits). C's `printf` and `strtod`
//! promise neither.

use crate::error::RinsError;
use crate::output::{RinsOutput, RinsStatus};
use crate::pointer;
use core::ffi::c_char;
use core::fmt::{self, Write};
use core::ptr::addr_of;
use estimator_core::estimates_csv::{write_output, write_rejected, HEADER, MAX_ROW_LEN};
use estimator_core::{Attitude, Estimate, Health, Output, Real};

/// Bytes of a buffer that holds any row of the estimates CSV, with its line end and the
/// terminating NUL (a row is about 190 bytes; the widest possible, of extreme values, 1,467).
pub const RINS_ROW_MAX_LEN: usize = MAX_ROW_LEN;

/// Writes into a byte buffer; refuses what does not fit.
struct Bytes<'a> {
    buffer: &'a mut [u8],
    len: usize,
}

impl Write for Bytes<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len.checked_add(s.len()).ok_or(fmt::Error)?;
        let target = self.buffer.get_mut(self.len..end).ok_or(fmt::Error)?;
        target.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Writes one line with `write` into `buffer` (`capacity` bytes), then a line end and a NUL, and
/// its length without the NUL into `*written`. Too small: `RINS_ERROR_BUFFER_TOO_SMALL`, the
/// buffer holds an empty string (if it has a byte at all).
///
/// # Safety
/// `buffer` is null or points to `capacity` writable bytes; `written` is null or points to a
/// writable `size_t`.
unsafe fn write_line(
    buffer: *mut c_char,
    capacity: usize,
    written: *mut usize,
    write: impl FnOnce(&mut Bytes) -> fmt::Result,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            pointer::check(written.cast_const()),
            pointer::bytes_mut(buffer.cast::<u8>(), capacity),
        )
    };
    let buffer = match checked {
        (Ok(()), Ok(buffer)) => buffer,
        (Err(e), _) | (_, Err(e)) => return e,
    };
    let mut line = Bytes { buffer, len: 0 };
    match write(&mut line).and_then(|()| line.write_str("\n\0")) {
        Ok(()) => {
            // SAFETY: checked above; writable by the caller's promise.
            unsafe { written.write(line.len - 1) };
            RinsError::Ok
        }
        Err(fmt::Error) => {
            if let Some(first) = line.buffer.first_mut() {
                *first = 0;
            }
            RinsError::BufferTooSmall
        }
    }
}

/// Writes the estimates CSV's header line (`time_s,x1_arcsec,...`, then `\n` and a NUL) into
/// `buffer` (`capacity` bytes) and its length without the NUL into `*written`.
///
/// # Safety
/// `buffer` is null or points to `capacity` writable bytes; `written` is null or points to a
/// writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn rins_format_header(
    buffer: *mut c_char,
    capacity: usize,
    written: *mut usize,
) -> RinsError {
    // SAFETY: the caller's promises.
    unsafe { write_line(buffer, capacity, written, |w| w.write_str(HEADER)) }
}

/// Writes the estimates CSV row of a step's output (accepted or rejected), then `\n` and a NUL,
/// into `buffer` (`capacity` bytes; `RINS_ROW_MAX_LEN` always suffices) and its length without
/// the NUL into `*written`: the row `host-sim estimate` writes for the same sample, byte for
/// byte. `RINS_ERROR_INVALID_ARGUMENT` for an output whose `status` or `has_estimate` no step
/// wrote.
///
/// # Safety
/// `output` is null or points to a readable `RinsOutput`; `buffer` is null or points to
/// `capacity` writable bytes; `written` is null or points to a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn rins_format_row(
    output: *const RinsOutput,
    buffer: *mut c_char,
    capacity: usize,
    written: *mut usize,
) -> RinsError {
    // SAFETY: the caller's promise.
    let row = match unsafe { read_output(output) } {
        Ok(row) => row,
        Err(e) => return e,
    };
    // SAFETY: the caller's promises.
    unsafe {
        write_line(buffer, capacity, written, |w| match row.status.to_core() {
            Ok(status) => write_output(
                w,
                &Output {
                    time_s: row.time_s,
                    status,
                    estimate: row.estimate,
                    corrected: row.corrected,
                    health: row.health,
                },
            ),
            Err(reason) => write_rejected(w, row.time_s, reason, row.estimate.as_ref()),
        })
    }
}

/// What a row shows of a [`RinsOutput`].
struct Row {
    time_s: f64,
    status: RinsStatus,
    estimate: Option<Estimate>,
    corrected: Attitude,
    health: Health,
}

/// Reads the `RinsOutput` at `output` field by field, its enum and `bool` as the integers the C
/// side may have put there (checked before they become Rust values).
///
/// # Safety
/// `output` is null or points to a readable `RinsOutput`.
unsafe fn read_output(output: *const RinsOutput) -> Result<Row, RinsError> {
    pointer::check(output)?;
    // SAFETY: checked non-null and aligned, readable by the caller's promise; every field is
    // read as a type valid for any bit pattern (`RinsEstimate` holds `f32`s only).
    let (time_s, status, has_estimate, estimate, corrected, health) = unsafe {
        (
            addr_of!((*output).time_s).read(),
            addr_of!((*output).status).cast::<u32>().read(),
            addr_of!((*output).has_estimate).cast::<u8>().read(),
            addr_of!((*output).estimate).read(),
            [
                addr_of!((*output).heading_corrected_rad).read(),
                addr_of!((*output).roll_corrected_rad).read(),
                addr_of!((*output).pitch_corrected_rad).read(),
            ],
            addr_of!((*output).health).read(),
        )
    };
    let status = RinsStatus::from_code(status).ok_or(RinsError::InvalidArgument)?;
    let estimate = match has_estimate {
        0 => None,
        1 => Some(Estimate::from(&estimate)),
        _ => return Err(RinsError::InvalidArgument),
    };
    let [heading, roll, pitch] = corrected.map(|v| v as Real);
    Ok(Row {
        time_s,
        status,
        estimate,
        corrected: Attitude {
            heading_rad: heading,
            roll_rad: roll,
            pitch_rad: pitch,
        },
        health: Health::from(&health),
    })
}

/// Reads a number of the attitude log from the `len` bytes at `text` (no NUL needed) into
/// `*value`, exactly as `host-sim`'s log reader does: spaces around it ignored; decimal or
/// scientific (`-1.5`, `1e-3`, `+2`, `.5`); `nan`, `inf`, `infinity` in any case for the
/// non-finite values (which the estimator then rejects). `RINS_ERROR_NOT_A_NUMBER` for anything
/// else, a blank cell included (nothing written).
///
/// # Safety
/// `text` is null or points to `len` readable bytes; `value` is null or points to a writable
/// `double`.
#[no_mangle]
pub unsafe extern "C" fn rins_parse_number(
    text: *const c_char,
    len: usize,
    value: *mut f64,
) -> RinsError {
    // SAFETY: the caller's promises.
    let checked = unsafe {
        (
            pointer::bytes(text.cast::<u8>(), len),
            pointer::check(value.cast_const()),
        )
    };
    let text = match checked {
        (Ok(text), Ok(())) => text,
        (Err(e), _) | (_, Err(e)) => return e,
    };
    match core::str::from_utf8(text.trim_ascii())
        .ok()
        .and_then(|t| t.parse::<f64>().ok())
    {
        Some(number) => {
            // SAFETY: checked above; writable by the caller's promise.
            unsafe { value.write(number) };
            RinsError::Ok
        }
        None => RinsError::NotANumber,
    }
}

/// Writes a message into `buffer`, cut to fit, NUL-terminated (nothing if it has no byte).
pub(crate) fn write_message(buffer: &mut [u8], message: fmt::Arguments) {
    /// Keeps what fits before the last byte, which stays for the NUL.
    struct Cut<'a> {
        buffer: &'a mut [u8],
        len: usize,
    }
    impl Write for Cut<'_> {
        fn write_str(&mut self, s: &str) -> fmt::Result {
            for &b in s.as_bytes() {
                if self.len + 1 >= self.buffer.len() {
                    break;
                }
                if let Some(slot) = self.buffer.get_mut(self.len) {
                    *slot = b;
                    self.len += 1;
                }
            }
            Ok(())
        }
    }
    let mut cut = Cut { buffer, len: 0 };
    let _ = cut.write_fmt(message);
    let end = cut.len;
    if let Some(nul) = cut.buffer.get_mut(end) {
        *nul = 0;
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use crate::output::{RinsEstimate, RinsField, RinsHealth};
    use core::ffi::CStr;
    use core::ptr::{null, null_mut};

    fn parse(text: &str) -> Result<f64, RinsError> {
        let mut v = -7.0;
        // SAFETY: a readable text and a writable double.
        match unsafe { rins_parse_number(text.as_ptr().cast(), text.len(), &mut v) } {
            RinsError::Ok => Ok(v),
            e => {
                assert_eq!(v, -7.0, "an error writes nothing");
                Err(e)
            }
        }
    }

    #[test]
    fn numbers_are_read_as_the_log_reader_reads_them() {
        for text in [
            "0",
            "1e1",
            "2.5E-1",
            "-0.13011853224744133",
            " 30.05153316395367 ",
            "+2",
            ".5",
            "5.",
            "1e400",
            "4.9e-324",
        ] {
            assert_eq!(
                parse(text).unwrap().to_bits(),
                text.trim().parse::<f64>().unwrap().to_bits(),
                "{text}"
            );
        }
        assert!(parse("nan").unwrap().is_nan() && parse("NaN").unwrap().is_nan());
        assert_eq!(parse("-inf"), Ok(f64::NEG_INFINITY));
        assert_eq!(parse("Infinity"), Ok(f64::INFINITY));
        for bad in ["", "   ", "x2", "1,5", "0x10", "1e", "--1", "1 2"] {
            assert_eq!(parse(bad), Err(RinsError::NotANumber), "{bad:?}");
        }
        let mut v = 0.0;
        // SAFETY: nulls are refused; a null text of length 0 is an empty text.
        unsafe {
            assert_eq!(rins_parse_number(null(), 3, &mut v), RinsError::NullPointer);
            assert_eq!(rins_parse_number(null(), 0, &mut v), RinsError::NotANumber);
            assert_eq!(
                rins_parse_number(c"1".as_ptr(), 1, null_mut()),
                RinsError::NullPointer
            );
        }
    }

    fn row(output: &RinsOutput, capacity: usize) -> (RinsError, std::string::String, usize) {
        let mut buffer = std::vec![0x55u8; capacity];
        let mut written = usize::MAX;
        // SAFETY: a readable output, `capacity` writable bytes, a writable size.
        let e =
            unsafe { rins_format_row(output, buffer.as_mut_ptr().cast(), capacity, &mut written) };
        let text = CStr::from_bytes_until_nul(&buffer)
            .map(|c| c.to_str().unwrap().into())
            .unwrap_or_default();
        (e, text, written)
    }

    fn accepted() -> RinsOutput {
        RinsOutput {
            time_s: 1.0,
            status: RinsStatus::Estimating,
            rejected_field: RinsField::None,
            has_estimate: true,
            estimate: RinsEstimate {
                x_rad: [1e-3, -1e-3, 2e-3, -2e-3],
                sigma_rad: [1e-5; 4],
            },
            heading_corrected_rad: 0.5,
            roll_corrected_rad: -0.01,
            pitch_corrected_rad: 0.02,
            health: RinsHealth {
                changes_detected: 1,
                last_change_s: 7200.0,
                window_restarts: 2,
                rejected: 3,
                mismatch_s: 40.0,
                residual_rad: [1e-6, 2e-6],
                noise_scale: [1.0, 1.5],
            },
        }
    }

    #[test]
    fn rows_are_the_cores_with_line_end_and_nul() {
        let out = accepted();
        let mut expected = std::string::String::new();
        let core = Output {
            time_s: 1.0,
            status: estimator_core::Status::Estimating,
            estimate: out.estimate(),
            corrected: out.corrected(),
            health: estimator_core::Health::from(&out.health),
        };
        write_output(&mut expected, &core).unwrap();
        expected.push('\n');
        let (e, text, written) = row(&out, RINS_ROW_MAX_LEN);
        assert_eq!(
            (e, text.as_str(), written),
            (RinsError::Ok, expected.as_str(), expected.len())
        );
        // Rejected: the held estimate and the reason, no corrected attitude.
        let rejected = RinsOutput {
            status: RinsStatus::RejectedTimeNotIncreasing,
            heading_corrected_rad: f32::NAN,
            ..out
        };
        let (e, text, _) = row(&rejected, RINS_ROW_MAX_LEN);
        assert_eq!(e, RinsError::Ok);
        assert!(
            text.starts_with("1.000000,206.2648,")
                && text.ends_with(",rejected_time_not_increasing,,,,,,,,,,,,\n"),
            "{text}"
        );
        // One byte short: refused, an empty string left.
        let (e, text, written) = row(&out, expected.len());
        assert_eq!(
            (e, text.as_str(), written),
            (RinsError::BufferTooSmall, "", usize::MAX)
        );
        assert_eq!(row(&out, expected.len() + 1).0, RinsError::Ok);
    }

    #[test]
    fn an_output_no_step_wrote_is_refused() {
        let out = accepted();
        let mut raw = core::mem::MaybeUninit::new(out);
        // The first code after the core's statuses, which no status has.
        let unused = estimator_core::Status::ALL.len() as u32;
        // SAFETY: an integer over the enum field, as C code may write; the memory is never read
        // as a `RinsOutput` value, only through `rins_format_row`, which reads it as an integer.
        unsafe {
            core::ptr::addr_of_mut!((*raw.as_mut_ptr()).status)
                .cast::<u32>()
                .write(unused)
        };
        let mut buffer = [0u8; RINS_ROW_MAX_LEN];
        let mut written = 0;
        // SAFETY: readable, writable.
        let e = unsafe {
            rins_format_row(
                raw.as_ptr(),
                buffer.as_mut_ptr().cast(),
                buffer.len(),
                &mut written,
            )
        };
        assert_eq!(e, RinsError::InvalidArgument);
        let mut raw = core::mem::MaybeUninit::new(out);
        // SAFETY: as above, a byte that is no `bool`.
        unsafe {
            core::ptr::addr_of_mut!((*raw.as_mut_ptr()).has_estimate)
                .cast::<u8>()
                .write(2)
        };
        // SAFETY: as above.
        let e = unsafe {
            rins_format_row(
                raw.as_ptr(),
                buffer.as_mut_ptr().cast(),
                buffer.len(),
                &mut written,
            )
        };
        assert_eq!(e, RinsError::InvalidArgument);
        // SAFETY: nulls are refused.
        unsafe {
            assert_eq!(
                rins_format_row(null(), null_mut(), 0, &mut written),
                RinsError::NullPointer
            );
            assert_eq!(
                rins_format_row(&out, null_mut(), 10, &mut written),
                RinsError::NullPointer
            );
        }
    }

    #[test]
    fn the_header_is_the_cores() {
        let mut buffer = [0u8; 400];
        let mut written = 0;
        // SAFETY: 400 writable bytes, a writable size.
        assert_eq!(
            unsafe { rins_format_header(buffer.as_mut_ptr().cast(), buffer.len(), &mut written) },
            RinsError::Ok
        );
        assert_eq!(&buffer[..written], std::format!("{HEADER}\n").as_bytes());
        assert_eq!(buffer[written], 0);
    }

    #[test]
    fn messages_are_cut_to_fit_and_terminated() {
        let mut buffer = [0x55u8; 6];
        write_message(&mut buffer, format_args!("{}", "abcdefgh"));
        assert_eq!(&buffer, b"abcde\0");
        write_message(&mut [], format_args!("x"));
    }
}
