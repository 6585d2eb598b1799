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
//!     encode_frame, FrameAccumulator, Request, Response, SampleMsg, MAX_REQUEST_ENCODED,
//!     MAX_RESPONSE_ENCODED, PROTOCOL_VERSION,
//! };
//!
//! // Host: a sample at 100 s (rotation 45 deg, platform 0 deg, latitude 30 deg, heading 10 deg,
//! // roll 1 deg, pitch -0.5 deg) becomes one frame.
//! let sample = Sample::from_degrees(100.0, 45.0, 0.0, 30.0, 10.0, 1.0, -0.5);
//! let request = Request::Sample(SampleMsg::from(&sample));
//! let mut frame = [0u8; MAX_FRAME];
//! let n = encode_frame(&request, &mut frame)?;
//!
//! // Firmware: the bytes arrive one at a time; the frame's closing 0x00 yields the request.
//! let mut rx = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
//! let mut received = None;
//! for &byte in &frame[..n] {
//!     if let Some(result) = rx.push_decode::<Request>(byte) {
//!         received = Some(result?); // a bad frame would be a `FrameError` here
//!     }
//! }
//! assert_eq!(received, Some(request));
//! // The firmware's core gets the very sample the host built, bit for bit.
//! if let Some(Request::Sample(msg)) = received {
//!     assert_eq!(Sample::from(&msg), sample);
//! }
//!
//! // Firmware to host: the boot announcement, 7 bytes on the wire.
//! let ready = Response::Ready { protocol_version: PROTOCOL_VERSION };
//! let n = encode_frame(&ready, &mut frame)?;
//! assert_eq!(frame[..n], [0x00, 0x05, 0x03, 0x04, 0xd8, 0x08, 0x00]);
//! let mut host_rx = FrameAccumulator::<MAX_RESPONSE_ENCODED>::new();
//! let responses = frame[..n]
//!     .iter()
//!     .filter_map(|&byte| host_rx.push_decode::<Response>(byte))
//!     .collect::<Result<Vec<_>, _>>()?;
//! assert_eq!(responses, [ready]);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
#![no_std]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing, clippy::panic)]

#[cfg(test)]
extern crate std;

pub mod accumulator;
pub mod blocking_writer;
#[cfg(test)]
mod cobs_reference;
pub mod crc;
pub mod frame;
pub mod message;

pub use accumulator::FrameAccumulator;
pub use blocking_writer::BlockingWriter;
pub use frame::{decode_frame, encode_frame, EncodeError, FrameError};
pub use message::{Counters, EstimateMsg, RejectedReply, Request, Response, SampleMsg, StatusReply, StepReply};

/// Version of this protocol, reported in [`StatusReply::protocol_version`]. 4: status code 9
/// (the estimator detecting the sample interval or the rotation pattern), the third counter of
/// `Status` counts filled samples, `Reset` erases the checkpoint slots; 5: status code 10 (a
/// change of the installation errors declared) (docs/link-protocol.md, Versioning).
pub const PROTOCOL_VERSION: u8 = 5;

/// Largest COBS-encoded request the firmware accepts (without the two 0x00 delimiters). The largest
/// request, a sample, encodes to 36 bytes; anything longer than this is counted as oversized.
pub const MAX_REQUEST_ENCODED: usize = 64;

/// Largest COBS-encoded response (without the delimiters); the largest response encodes to far less.
pub const MAX_RESPONSE_ENCODED: usize = 192;

/// Largest message (postcard bytes, before the CRC) this crate encodes.
pub const MAX_MESSAGE: usize = 160;
