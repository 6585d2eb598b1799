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
//! One request and one response, byte by byte, from the host's frame to the firmware's
//! message and back: the example of [`encode_frame`].
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
