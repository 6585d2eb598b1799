//! The link: frames in and out over the board's serial port (any `embedded_io::Read + Write`).
//! Framing, CRC and message encoding are `link-protocol`'s; this file only moves bytes.

use embedded_io::{Read, Write};
use link_protocol::frame::MAX_FRAME;
use link_protocol::{encode_frame, FrameAccumulator, FrameError, Request, Response, MAX_REQUEST_ENCODED};

/// The serial port with a bounded receive buffer.
pub struct Link<U> {
    port: U,
    rx: FrameAccumulator<MAX_REQUEST_ENCODED>,
    tx: [u8; MAX_FRAME],
}

impl<U: Read + Write> Link<U> {
    pub fn new(port: U) -> Self {
        Link {
            port,
            rx: FrameAccumulator::new(),
            tx: [0; MAX_FRAME],
        }
    }

    /// Blocks until a frame has ended; returns its request or why it was dropped. A read error of
    /// the port drops the byte; the frame's CRC then rejects the frame.
    pub fn receive(&mut self) -> Result<Request, FrameError> {
        let mut byte = [0u8; 1];
        loop {
            if !matches!(self.port.read(&mut byte), Ok(1)) {
                continue;
            }
            if let Some(result) = self.rx.push_decode::<Request>(byte[0]) {
                return result;
            }
        }
    }

    /// Sends one response frame. Returns false if it could not be encoded or written.
    pub fn send(&mut self, response: &Response) -> bool {
        let Ok(n) = encode_frame(response, &mut self.tx) else {
            return false;
        };
        match self.tx.get(..n) {
            Some(frame) => self.port.write_all(frame).is_ok() && self.port.flush().is_ok(),
            None => false,
        }
    }
}
