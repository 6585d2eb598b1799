//! # link-protocol
//!
//! The frames between the host (`host-sim stream`, or a navigation computer's driver) and the
//! estimator firmware. Shared, `no_std`, no allocator: the firmware and the host use this very
//! crate, so both ends encode and decode every byte the same way.
//!
//! One frame on the wire, in both directions (byte-for-byte description in
//! docs/link-protocol.md):
//!
//! ```text
//! 0x00 | COBS( postcard(message) | CRC-16/IBM-3740(postcard(message)) little-endian ) | 0x00
//! ```
//!
//! - [`message`]: the request and response types (postcard-serialised with serde);
//! - [`crc`]: the CRC-16 over the message bytes;
//! - [`frame`]: one message to one frame and back, with every way a frame can be bad (COBS from
//!   the `cobs` crate, decoded strictly: a truncated group or a 0x00 inside is an error);
//! - [`accumulator`]: the bounded streaming receiver: splits the byte stream at 0x00, detects
//!   oversized frames, resynchronises on the next 0x00;
//! - [`blocking_writer`]: a serial transmitter wrapper that never returns `Ok(0)`, so that
//!   `embedded_io::Write::write_all` of a frame cannot panic on a busy USART.
//!
//! ## Example: one request and one response, byte by byte
//!
//! ```
//! use estimator_core::Sample;
//! use link_protocol::frame::MAX_FRAME;
//! use link_protocol::{
//!     encode_frame, FrameAccumulator, Numbered, Request, Response, SampleMsg, MAX_REQUEST_ENCODED,
//!     MAX_RESPONSE_ENCODED, PROTOCOL_VERSION, UNNUMBERED,
//! };
//!
//! // Host: its 7th request, a sample at 100 s (rotation 45 deg, platform 0 deg, latitude 30 deg,
//! // heading 10 deg, roll 1 deg, pitch -0.5 deg), becomes one frame.
//! let sample = Sample::from_degrees(100.0, 45.0, 0.0, 30.0, 10.0, 1.0, -0.5);
//! let request = Numbered { seq: 7, message: Request::Sample(SampleMsg::from(&sample)) };
//! let mut frame = [0u8; MAX_FRAME];
//! let n = encode_frame(&request, &mut frame)?;
//!
//! // Firmware: the bytes arrive one at a time; the frame's closing 0x00 yields the request.
//! let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
//! let mut received = None;
//! for &byte in &frame[..n] {
//!     if let Some(result) = rx.push_decode::<Numbered<Request>>(byte) {
//!         received = Some(result?); // a bad frame would be a `FrameError` here
//!     }
//! }
//! assert_eq!(received, Some(request));
//! // The firmware's core gets the very sample the host built, bit for bit; its answer will
//! // carry the number 7.
//! if let Some(Numbered { seq: 7, message: Request::Sample(msg) }) = received {
//!     assert_eq!(Sample::from(&msg), sample);
//! }
//!
//! // Firmware to host: the boot announcement, unnumbered, 8 bytes on the wire.
//! let ready = Numbered { seq: UNNUMBERED, message: Response::Ready { protocol_version: PROTOCOL_VERSION } };
//! let n = encode_frame(&ready, &mut frame)?;
//! assert_eq!(frame[..n], [0x00, 0x01, 0x05, 0x03, 0x07, 0x28, 0xe9, 0x00]);
//! let mut host_rx = FrameAccumulator::<MAX_RESPONSE_ENCODED>::new();
//! let responses = frame[..n]
//!     .iter()
//!     .filter_map(|&byte| host_rx.push_decode::<Numbered<Response>>(byte))
//!     .collect::<Result<Vec<_>, _>>()?;
//! assert_eq!(responses, [ready]);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
#![warn(missing_docs)]
#![no_std]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::indexing_slicing,
        clippy::panic
    )
)]

#[cfg(test)]
extern crate std;

pub mod accumulator;
pub mod blocking_writer;
pub mod crc;
pub mod frame;
#[cfg(test)]
mod golden_frames;
pub mod message;

pub use accumulator::FrameAccumulator;
pub use blocking_writer::BlockingWriter;
pub use frame::{decode_frame, encode_frame, encode_response_frame, EncodeError, FrameError};
pub use message::{
    BinOutcome, ClockSource, Counters, EstimateMsg, HealthMsg, LinkCounters, NavReply, Numbered,
    RejectedReply, Request, ResetCause, Response, SampleMsg, StatusReply, StepReply, UNNUMBERED,
};

/// Version of this protocol, reported in [`StatusReply::protocol_version`]. 5: every frame's
/// message is [`Numbered`] (a sequence number before it), `Status` appends the receive path's
/// [`LinkCounters`], the reset cause and the clock source, and the request `Hang` (variant 3, test
/// builds only; 4 from protocol 7) exists, and `Step`'s status may be 10 (a change of the installation errors
/// declared) (docs/link-protocol.md, Versioning). 6: `Step` appends the output's latched alarms
/// and residuals' level ([`HealthMsg`]). 7: the request `NavSample` (variant 3: a sample at the
/// navigation rate, binned by the firmware) and its answer `Nav` ([`NavReply`], response variant
/// 4); the test builds' `Hang` moves to request variant 4.
pub const PROTOCOL_VERSION: u8 = 7;

/// Largest COBS-encoded request the firmware accepts (without the two 0x00 delimiters). The largest
/// request, a sample, encodes to 36 bytes; anything longer than this is counted as oversized.
pub const MAX_REQUEST_ENCODED: usize = 64;

/// Longest sample request frame on the wire, both 0x00 delimiters included: a sequence number of
/// 5 bytes, the 33-byte sample and the CRC, COBS-encoded (one code byte more) between the
/// delimiters. Receive buffers are sized in these.
pub const MAX_SAMPLE_FRAME: usize = 43;

/// Largest COBS-encoded response (without the delimiters); the largest response encodes to far less.
pub const MAX_RESPONSE_ENCODED: usize = 256;

/// Largest message (postcard bytes, before the CRC) this crate encodes.
pub const MAX_MESSAGE: usize = 224;
