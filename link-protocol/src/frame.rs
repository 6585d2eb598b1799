//! One message to one frame and back.
//!
//! Frame = `0x00, COBS(message bytes, CRC-16 little-endian), 0x00`. The leading 0x00 closes any line
//! noise received before the frame as a (counted) bad frame of its own, so noise can never corrupt
//! the frame that follows it; the receiver ignores the empty frame between two delimiters.

use estimator_core::UnknownCode;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::crc::crc16;
use crate::MAX_MESSAGE;

/// Why a received frame was dropped. The code (`as u8`) is the frame's index in
/// [`crate::Counters::bad_frames`] and in docs/link-protocol.md's table; [`FrameError::name`] is
/// the kind's name there and in the host's reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum FrameError {
    /// More bytes than the receive buffer holds arrived before the next 0x00.
    Oversize = 0,
    /// Not valid COBS: a group runs past the end of the frame (truncated frame), or the frame is
    /// empty or has a 0x00 inside.
    Cobs = 1,
    /// Decodes to fewer than 3 bytes: no room for a message and its CRC.
    TooShort = 2,
    /// The CRC does not match the message bytes.
    Crc = 3,
    /// The CRC matches but the bytes are not exactly one known message.
    Message = 4,
}

impl FrameError {
    /// Every kind, in code order: `ALL[k as usize] == k`.
    pub const ALL: [FrameError; 5] = [
        FrameError::Oversize,
        FrameError::Cobs,
        FrameError::TooShort,
        FrameError::Crc,
        FrameError::Message,
    ];

    /// Number of kinds (for counters).
    pub const COUNT: usize = Self::ALL.len();

    /// Short machine-readable name of this kind.
    pub const fn name(&self) -> &'static str {
        match self {
            FrameError::Oversize => "oversize",
            FrameError::Cobs => "cobs",
            FrameError::TooShort => "too_short",
            FrameError::Crc => "crc",
            FrameError::Message => "message",
        }
    }
}

impl TryFrom<u8> for FrameError {
    type Error = UnknownCode;

    /// The kind of code `code`; the same convention as the core's code enums.
    fn try_from(code: u8) -> Result<Self, UnknownCode> {
        Self::ALL
            .into_iter()
            .find(|kind| *kind as u8 == code)
            .ok_or(UnknownCode {
                what: "bad-frame",
                code,
            })
    }
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FrameError::Oversize => "frame longer than the receive buffer",
            FrameError::Cobs => "frame is not valid COBS (truncated?)",
            FrameError::TooShort => "frame too short for a message and its CRC",
            FrameError::Crc => "frame CRC does not match",
            FrameError::Message => "frame CRC matches but the bytes are no known message",
        })
    }
}

impl core::error::Error for FrameError {}

/// Logged as its [`FrameError::name`].
#[cfg(feature = "defmt")]
impl defmt::Format for FrameError {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=str}", self.name());
    }
}

/// Why a message could not be encoded (a bug on the sending side, never caused by received data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The message does not fit in [`MAX_MESSAGE`] bytes.
    MessageTooLarge,
    /// The output buffer is too small for the frame.
    BufferTooSmall,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            EncodeError::MessageTooLarge => "message longer than MAX_MESSAGE bytes",
            EncodeError::BufferTooSmall => "output buffer too small for the frame",
        })
    }
}

impl core::error::Error for EncodeError {}

/// Largest frame, delimiters included, that [`encode_frame`] writes.
pub const MAX_FRAME: usize = cobs::max_encoding_length(MAX_MESSAGE + 2) + 2;

/// Writes `0x00, COBS(postcard(message), CRC-16 LE), 0x00` to `out`; returns the frame's length.
///
/// # Example: one request and one response, byte by byte
///
/// ```
/// use estimator_core::Sample;
/// use link_protocol::frame::MAX_FRAME;
/// use link_protocol::{
///     encode_frame, FrameAccumulator, Numbered, Request, Response, SampleMsg, MAX_REQUEST_ENCODED,
///     MAX_RESPONSE_ENCODED, PROTOCOL_VERSION, UNNUMBERED,
/// };
///
/// // Host: its 7th request, a sample at 100 s (rotation 45 deg, platform 0 deg, latitude 30 deg,
/// // heading 10 deg, roll 1 deg, pitch -0.5 deg), becomes one frame.
/// let sample = Sample::from_degrees(100.0, 45.0, 0.0, 30.0, 10.0, 1.0, -0.5);
/// let request = Numbered { seq: 7, message: Request::Sample(SampleMsg::from(&sample)) };
/// let mut frame = [0u8; MAX_FRAME];
/// let n = encode_frame(&request, &mut frame)?;
///
/// // Firmware: the bytes arrive one at a time; the frame's closing 0x00 yields the request.
/// let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
/// let mut received = None;
/// for &byte in &frame[..n] {
///     if let Some(result) = rx.push_decode::<Numbered<Request>>(byte) {
///         received = Some(result?); // a bad frame would be a `FrameError` here
///     }
/// }
/// assert_eq!(received, Some(request));
/// // The firmware's core gets the very sample the host built, bit for bit; its answer will
/// // carry the number 7.
/// if let Some(Numbered { seq: 7, message: Request::Sample(msg) }) = received {
///     assert_eq!(Sample::from(&msg), sample);
/// }
///
/// // Firmware to host: the boot announcement, unnumbered, 8 bytes on the wire.
/// let ready = Numbered { seq: UNNUMBERED, message: Response::Ready { protocol_version: PROTOCOL_VERSION } };
/// let n = encode_frame(&ready, &mut frame)?;
/// assert_eq!(frame[..n], [0x00, 0x01, 0x05, 0x03, 0x07, 0x28, 0xe9, 0x00]);
/// let mut host_rx = FrameAccumulator::<MAX_RESPONSE_ENCODED>::new();
/// let responses = frame[..n]
///     .iter()
///     .filter_map(|&byte| host_rx.push_decode::<Numbered<Response>>(byte))
///     .collect::<Result<Vec<_>, _>>()?;
/// assert_eq!(responses, [ready]);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
pub fn encode_frame<T: Serialize>(message: &T, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_MESSAGE + 2];
    let n = {
        let body = raw
            .get_mut(..MAX_MESSAGE)
            .ok_or(EncodeError::MessageTooLarge)?;
        postcard::to_slice(message, body)
            .map_err(|_| EncodeError::MessageTooLarge)?
            .len()
    };
    let crc = crc16(raw.get(..n).ok_or(EncodeError::MessageTooLarge)?).to_le_bytes();
    raw.get_mut(n..n + 2)
        .ok_or(EncodeError::MessageTooLarge)?
        .copy_from_slice(&crc);
    let data = raw.get(..n + 2).ok_or(EncodeError::MessageTooLarge)?;
    *out.first_mut().ok_or(EncodeError::BufferTooSmall)? = 0;
    let body = out.get_mut(1..).ok_or(EncodeError::BufferTooSmall)?;
    // `try_encode` can return a length one past the end of `body` when only the last code byte
    // does not fit (it skips that write); the closing 0x00 at `m + 1` then lies past the end of
    // `out`, so the check below turns that case into `BufferTooSmall` too.
    let m = cobs::try_encode(data, body).map_err(|_| EncodeError::BufferTooSmall)?;
    *out.get_mut(m + 1).ok_or(EncodeError::BufferTooSmall)? = 0;
    Ok(m + 2)
}

/// [`encode_frame`] of a numbered response, compiled here once (not generic): the firmware's one
/// encoder, built with this crate's optimisation (size, in the firmware's profile) rather than
/// inlined into the caller.
#[inline(never)]
pub fn encode_response_frame(
    seq: u32,
    response: &crate::message::Response,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    encode_frame(
        &crate::message::Numbered {
            seq,
            message: *response,
        },
        out,
    )
}

/// COBS-decodes a received frame (without its 0x00 delimiters) in place; returns the decoded
/// length. Strict: an empty frame, a group whose code byte points past the end of the frame (a
/// truncated frame) and a 0x00 anywhere in the frame are errors, never a shorter message.
///
/// The `cobs` crate's decoder rejects the first two itself, but it stops at the first 0x00 and
/// returns the bytes decoded before it (`[0x00]` decodes to an empty message, `[0x02, 0x11, 0x00,
/// 0x05]` to `[0x11]`). The [`crate::FrameAccumulator`] never passes a 0x00 on, but
/// [`decode_frame`] is public, so such a frame is refused here before the crate sees it.
pub(crate) fn cobs_decode_strict(encoded: &mut [u8]) -> Result<usize, FrameError> {
    if encoded.contains(&0) {
        return Err(FrameError::Cobs);
    }
    cobs::decode_in_place(encoded).map_err(|_| FrameError::Cobs)
}

/// Decodes one received frame (the bytes between two 0x00, COBS-encoded; decoded in place).
pub fn decode_frame<T: DeserializeOwned>(encoded: &mut [u8]) -> Result<T, FrameError> {
    let n = cobs_decode_strict(encoded)?;
    if n < 3 {
        return Err(FrameError::TooShort);
    }
    let data = encoded.get(..n).ok_or(FrameError::Cobs)?;
    let (body, crc) = data.split_at(n - 2);
    let received = u16::from_le_bytes([
        *crc.first().ok_or(FrameError::TooShort)?,
        *crc.get(1).ok_or(FrameError::TooShort)?,
    ]);
    if crc16(body) != received {
        return Err(FrameError::Crc);
    }
    match postcard::take_from_bytes::<T>(body) {
        Ok((message, [])) => Ok(message),
        _ => Err(FrameError::Message),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::*;
    use crate::{MAX_REQUEST_ENCODED, MAX_RESPONSE_ENCODED, MAX_SAMPLE_FRAME};
    use estimator_core::{Output, Sample, Status};
    use std::vec::Vec;

    pub(crate) fn frame_of<T: Serialize>(m: &T) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode_frame(m, &mut out).unwrap();
        out[..n].to_vec()
    }

    fn body(frame: &[u8]) -> Vec<u8> {
        assert_eq!(frame[0], 0);
        assert_eq!(*frame.last().unwrap(), 0);
        let inner = frame[1..frame.len() - 1].to_vec();
        assert!(!inner.contains(&0));
        inner
    }

    fn sample() -> SampleMsg {
        SampleMsg::from(&Sample::from_degrees(
            49_999.0, 123.4, -56.7, 30.0, 10.0, 2.9, -0.4,
        ))
    }

    fn step_reply() -> StepReply {
        let output = Output {
            time_s: 49_999.0,
            status: Status::Converged,
            estimate: Some(estimator_core::Estimate {
                x_rad: [1e-4, -2e-4, 3e-4, 4e-4],
                sigma_rad: [1e-6; 4],
            }),
            corrected: estimator_core::Attitude {
                heading_rad: 0.1,
                roll_rad: -0.01,
                pitch_rad: 0.02,
            },
            // Every field at its longest encoding.
            health: estimator_core::Health {
                changes_detected: u32::MAX,
                last_change_s: Some(1.5e9),
                window_restarts: u32::MAX,
                rejected: u32::MAX,
                mismatch_s: 4.0e10,
                residual_rad: Some([1e-5, 2e-5]),
                noise_scale: Some([1.5, 30.0]),
            },
        };
        let counters = Counters {
            bad_frames: [u32::MAX; 5],
            rejected_samples: [u32::MAX; 5],
        };
        StepReply::new(&output, 123, counters)
    }

    /// A status with every field at its longest encoding.
    fn longest_status() -> StatusReply {
        StatusReply {
            protocol_version: crate::PROTOCOL_VERSION,
            method: 0,
            counters: Counters {
                bad_frames: [u32::MAX; 5],
                rejected_samples: [u32::MAX; 5],
            },
            accepted: u32::MAX,
            filled: u32::MAX,
            window_restarts: u32::MAX,
            estimate: step_reply().estimate,
            cost_counter_hz: u32::MAX,
            boot_stack_peak_bytes: u32::MAX,
            stack_peak_bytes: u32::MAX,
            stack_size_bytes: u32::MAX,
            checkpoint_time_s: Some(12_345.0),
            checkpoints_saved: u32::MAX,
            link: LinkCounters {
                lost_frames: u32::MAX,
                uart_overruns: u32::MAX,
                buffer_overruns: u32::MAX,
                framing_errors: u32::MAX,
                noise_errors: u32::MAX,
                rx_buffer_bytes: u32::MAX,
                rx_peak_bytes: u32::MAX,
            },
            reset_cause: ResetCause::Watchdog as u8,
            clock_source: ClockSource::InternalFallback as u8,
        }
    }

    #[test]
    fn requests_and_responses_round_trip() {
        let requests = [
            Request::Sample(sample()),
            Request::Reset,
            Request::ReadStatus,
            Request::NavSample(sample()),
            #[cfg(feature = "test-hang")]
            Request::Hang,
        ];
        for r in requests {
            for seq in [UNNUMBERED, 1, u32::MAX] {
                let numbered = Numbered { seq, message: r };
                let mut inner = body(&frame_of(&numbered));
                assert!(inner.len() <= MAX_REQUEST_ENCODED);
                assert_eq!(decode_frame::<Numbered<Request>>(&mut inner), Ok(numbered));
            }
        }
        let rejected = RejectedReply::new(
            3.0,
            &estimator_core::SampleError::NonFinite(estimator_core::Field::Roll),
            u32::MAX,
            Counters::default(),
        );
        for r in [
            Response::Step(step_reply()),
            Response::Rejected(rejected),
            Response::Status(longest_status()),
            Response::Ready {
                protocol_version: crate::PROTOCOL_VERSION,
            },
            // The longest answer: a navigation sample that completed a bin.
            Response::Nav(NavReply {
                time_s: -1.0e300,
                corrected_rad: Some([1.0e30; 3]),
                bin: BinOutcome::Step(step_reply()),
                cost_ticks: u32::MAX,
            }),
            Response::Nav(NavReply {
                time_s: 0.5,
                corrected_rad: None,
                bin: BinOutcome::Rejected(rejected),
                cost_ticks: 0,
            }),
            Response::Nav(NavReply {
                time_s: 0.25,
                corrected_rad: None,
                bin: BinOutcome::Open,
                cost_ticks: 7,
            }),
        ] {
            let numbered = Numbered {
                seq: u32::MAX,
                message: r,
            };
            let mut inner = body(&frame_of(&numbered));
            assert!(inner.len() <= MAX_RESPONSE_ENCODED, "{} bytes", inner.len());
            assert_eq!(decode_frame::<Numbered<Response>>(&mut inner), Ok(numbered));
        }
    }

    #[test]
    fn step_reply_rebuilds_the_same_output() {
        let r = step_reply();
        let o = r.output().unwrap();
        assert_eq!(StepReply::new(&o, r.step_cost_ticks, r.counters), r);
    }

    #[test]
    fn nan_payloads_travel_unchanged() {
        let mut s = sample();
        s.roll_rad = f32::from_bits(0x7fc0_1234);
        let mut inner = body(&frame_of(&Request::Sample(s)));
        match decode_frame::<Request>(&mut inner) {
            Ok(Request::Sample(m)) => assert_eq!(m.roll_rad.to_bits(), 0x7fc0_1234),
            other => panic!("{other:?}"),
        }
    }

    /// Pins the wire layout documented in docs/link-protocol.md.
    #[test]
    fn request_layout_is_as_documented() {
        let m = SampleMsg {
            time_s: 1.0,
            rotation_rad: 2.0,
            platform_rad: 0.0,
            latitude_rad: 0.5,
            heading_rad: -1.0,
            roll_rad: 0.25,
            pitch_rad: 0.125,
        };
        let mut raw = [0u8; 64];
        let bytes = postcard::to_slice(&Request::Sample(m), &mut raw)
            .unwrap()
            .to_vec();
        let mut expect = std::vec![0u8];
        expect.extend_from_slice(&1.0f64.to_le_bytes());
        for v in [2.0f32, 0.0, 0.5, -1.0, 0.25, 0.125] {
            expect.extend_from_slice(&v.to_le_bytes());
        }
        assert_eq!(bytes, expect);
        assert_eq!(bytes.len(), 33);
        // A numbered message is its sequence number (varint), then the message.
        let numbered = postcard::to_slice(
            &Numbered {
                seq: 300,
                message: Request::Sample(m),
            },
            &mut raw,
        )
        .unwrap()
        .to_vec();
        assert_eq!(numbered[..2], [0xac, 0x02]);
        assert_eq!(numbered[2..], expect[..]);
        // The examples of docs/link-protocol.md, byte for byte.
        let sample_frame = [
            0x00, 0x02, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x03, 0xf0, 0x3f, 0x01, 0x01,
            0x02, 0x40, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x02, 0x3f, 0x01, 0x03, 0x80, 0xbf,
            0x01, 0x03, 0x80, 0x3e, 0x01, 0x01, 0x04, 0x3e, 0xd9, 0xe4, 0x00,
        ];
        assert_eq!(
            frame_of(&Numbered {
                seq: 1,
                message: Request::Sample(m)
            }),
            sample_frame.to_vec()
        );
        assert_eq!(
            frame_of(&Numbered {
                seq: 2,
                message: Request::Reset
            }),
            [0x00, 0x05, 0x02, 0x01, 0x4c, 0x6b, 0x00].to_vec()
        );
        assert_eq!(
            frame_of(&Numbered {
                seq: 3,
                message: Request::ReadStatus
            }),
            [0x00, 0x05, 0x03, 0x02, 0x1e, 0x68, 0x00].to_vec()
        );
        // `Hang`, number 300: decoded only with the `test-hang` feature, a bad message without.
        let hang = [0x00, 0x06, 0xac, 0x02, 0x04, 0x87, 0x22, 0x00];
        #[cfg(feature = "test-hang")]
        assert_eq!(
            frame_of(&Numbered {
                seq: 300,
                message: Request::Hang
            }),
            hang.to_vec()
        );
        #[cfg(not(feature = "test-hang"))]
        assert_eq!(
            decode_frame::<Numbered<Request>>(&mut body(&hang)),
            Err(FrameError::Message)
        );
        // The firmware's boot announcement (protocol 7), unnumbered: M = 00 03 07.
        let ready = Numbered {
            seq: UNNUMBERED,
            message: Response::Ready {
                protocol_version: crate::PROTOCOL_VERSION,
            },
        };
        let bytes = postcard::to_slice(&ready, &mut raw).unwrap().to_vec();
        assert_eq!(bytes, [0x00, 0x03, 0x07]);
        assert_eq!(crate::crc::crc16(&bytes), 0xe928);
        assert_eq!(
            frame_of(&ready),
            [0x00, 0x01, 0x05, 0x03, 0x07, 0x28, 0xe9, 0x00].to_vec()
        );
        // No sample frame is longer than 43 bytes: 5 + 33 + 2 bytes COBS-encoded into at most 41.
        assert!(
            frame_of(&Numbered {
                seq: u32::MAX,
                message: Request::Sample(sample())
            })
            .len()
                <= MAX_SAMPLE_FRAME
        );
        assert_eq!(MAX_SAMPLE_FRAME, 43);
    }

    /// The longest status and step answers fit the host's receive buffer, as the docs say.
    #[test]
    fn the_longest_answers_are_as_documented() {
        let mut raw = [0u8; 300];
        let status = Numbered {
            seq: u32::MAX,
            message: Response::Status(longest_status()),
        };
        assert_eq!(postcard::to_slice(&status, &mut raw).unwrap().len(), 177);
        let step = Numbered {
            seq: u32::MAX,
            message: Response::Step(step_reply()),
        };
        assert_eq!(postcard::to_slice(&step, &mut raw).unwrap().len(), 161);
        assert!(frame_of(&status).len() - 2 <= MAX_RESPONSE_ENCODED);
    }

    #[test]
    fn corrupted_crc_is_detected_for_every_single_bit_flip() {
        let frame = frame_of(&Request::Sample(sample()));
        let mut raw = [0u8; 64];
        let msg = postcard::to_slice(&Request::Sample(sample()), &mut raw)
            .unwrap()
            .to_vec();
        let crc = crate::crc::crc16(&msg).to_le_bytes();
        let mut data = msg.clone();
        data.extend_from_slice(&crc);
        for bit in 0..data.len() * 8 {
            let mut bad = data.clone();
            bad[bit / 8] ^= 1 << (bit % 8);
            let mut enc = std::vec![0u8; 64];
            let n = cobs::try_encode(&bad, &mut enc).unwrap();
            assert_eq!(
                decode_frame::<Request>(&mut enc[..n]),
                Err(FrameError::Crc),
                "bit {bit}"
            );
        }
        assert!(frame.len() > 3);
    }

    #[test]
    fn short_frames_and_unknown_messages() {
        for data in [&[0x01u8][..], &[0x01, 0x02]] {
            let mut enc = std::vec![0u8; 8];
            let n = cobs::try_encode(data, &mut enc).unwrap();
            assert_eq!(
                decode_frame::<Request>(&mut enc[..n]),
                Err(FrameError::TooShort)
            );
        }
        // Unknown variant 7, and a valid Reset followed by a stray byte: CRC fine, message wrong.
        for msg in [&[0x07u8][..], &[0x01, 0x55]] {
            let mut data = msg.to_vec();
            data.extend_from_slice(&crate::crc::crc16(msg).to_le_bytes());
            let mut enc = std::vec![0u8; 8];
            let n = cobs::try_encode(&data, &mut enc).unwrap();
            assert_eq!(
                decode_frame::<Request>(&mut enc[..n]),
                Err(FrameError::Message)
            );
        }
    }

    #[test]
    fn encoding_into_a_small_buffer_is_an_error() {
        let mut out = [0u8; 10];
        assert_eq!(
            encode_frame(&Request::Sample(sample()), &mut out),
            Err(EncodeError::BufferTooSmall)
        );
        // Every length short of the frame, including the one that lacks only the last code byte
        // (which the COBS encoder alone does not report), is an error; the exact length is enough.
        let requests = [
            Request::Sample(sample()),
            Request::Reset,
            Request::ReadStatus,
        ];
        for r in requests {
            let full = frame_of(&r);
            for len in 0..full.len() {
                let mut out = std::vec![0u8; len];
                assert_eq!(
                    encode_frame(&r, &mut out),
                    Err(EncodeError::BufferTooSmall),
                    "{r:?} in {len}"
                );
            }
            let mut out = std::vec![0u8; full.len()];
            assert_eq!(encode_frame(&r, &mut out), Ok(full.len()));
            assert_eq!(out, full);
        }
    }

    #[test]
    fn frame_error_codes_are_the_documented_indices_and_round_trip() {
        // docs/link-protocol.md's table: index, kind.
        let table = [
            (0u8, "oversize"),
            (1, "cobs"),
            (2, "too_short"),
            (3, "crc"),
            (4, "message"),
        ];
        assert_eq!(FrameError::COUNT, table.len());
        for (kind, (code, name)) in FrameError::ALL.into_iter().zip(table) {
            assert_eq!(kind as u8, code);
            assert_eq!(kind.name(), name);
            assert_eq!(FrameError::try_from(code), Ok(kind));
        }
        for code in FrameError::COUNT as u8..=u8::MAX {
            assert_eq!(
                FrameError::try_from(code),
                Err(UnknownCode {
                    what: "bad-frame",
                    code
                })
            );
        }
    }

    #[test]
    fn errors_display_a_sentence() {
        use std::string::ToString;
        for kind in FrameError::ALL {
            let text = kind.to_string();
            assert!(text.starts_with("frame "), "{text}");
        }
        assert_eq!(
            EncodeError::BufferTooSmall.to_string(),
            "output buffer too small for the frame"
        );
        assert_eq!(
            FrameError::try_from(9).unwrap_err().to_string(),
            "9 is not a known bad-frame code"
        );
        let boxed: std::boxed::Box<dyn core::error::Error> = std::boxed::Box::new(FrameError::Crc);
        assert_eq!(boxed.to_string(), "frame CRC does not match");
    }

    #[test]
    fn truncated_groups_are_cobs_errors_never_short_messages() {
        // One group of 7: every cut leaves a group that runs past the end of the frame.
        let mut enc = [0u8; 8];
        let n = cobs::try_encode(&[1, 2, 3, 4, 5, 6], &mut enc).unwrap();
        assert_eq!(&enc[..n], [0x07, 1, 2, 3, 4, 5, 6]);
        for cut in 1..n {
            let mut part = enc[..cut].to_vec();
            assert_eq!(
                cobs_decode_strict(&mut part),
                Err(FrameError::Cobs),
                "cut at {cut}"
            );
        }
        assert_eq!(cobs_decode_strict(&mut []), Err(FrameError::Cobs));
        // A frame of one group (a bare Ready message) cut anywhere.
        let ready = body(&frame_of(&Response::Ready {
            protocol_version: crate::PROTOCOL_VERSION,
        }));
        assert_eq!(ready, [0x05, 0x03, 0x07, 0xbb, 0x38]);
        for cut in 0..ready.len() {
            let mut part = ready[..cut].to_vec();
            assert_eq!(
                decode_frame::<Response>(&mut part),
                Err(FrameError::Cobs),
                "cut at {cut}"
            );
        }
    }

    #[test]
    fn a_zero_byte_inside_a_frame_is_a_cobs_error() {
        for frame in [
            &[0x02u8, 0x00][..],
            &[0x00],
            &[0x01, 0x00, 0x05],
            &[0x02, 0x11, 0x00, 0x05],
        ] {
            let mut f = frame.to_vec();
            assert_eq!(
                cobs_decode_strict(&mut f),
                Err(FrameError::Cobs),
                "{frame:02x?}"
            );
        }
        // A whole, valid frame followed by a 0x00 and more bytes is refused, not read up to the 0x00.
        for r in [Request::Sample(sample()), Request::Reset] {
            let mut inner = body(&frame_of(&r));
            inner.extend_from_slice(&[0x00, 0x01]);
            assert_eq!(decode_frame::<Request>(&mut inner), Err(FrameError::Cobs));
        }
    }
}
