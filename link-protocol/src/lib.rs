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
pub use frame::{decode_frame, encode_frame, EncodeError, FrameError, UnknownFrameErrorCode};
pub use message::{Counters, EstimateMsg, RejectedReply, Request, Response, SampleMsg, StatusReply, StepReply};

/// Version of this protocol, reported in [`StatusReply::protocol_version`]. 4: status code 9
/// (the estimator detecting the sample interval or the rotation pattern), the third counter of
/// `Status` counts filled samples, `Reset` erases the checkpoint slots (docs/link-protocol.md,
/// Versioning).
pub const PROTOCOL_VERSION: u8 = 4;

/// Largest COBS-encoded request the firmware accepts (without the two 0x00 delimiters). The largest
/// request, a sample, encodes to 36 bytes; anything longer than this is counted as oversized.
pub const MAX_REQUEST_ENCODED: usize = 64;

/// Largest COBS-encoded response (without the delimiters); the largest response encodes to far less.
pub const MAX_RESPONSE_ENCODED: usize = 192;

/// Largest message (postcard bytes, before the CRC) this crate encodes.
pub const MAX_MESSAGE: usize = 160;
