//! The host end of the link: requests out, responses in, over any byte stream (QEMU's UART socket,
//! a serial port). Framing is `link-protocol`'s, the same code the firmware runs.

use anyhow::{bail, Context};
use link_protocol::frame::MAX_FRAME;
use link_protocol::{encode_frame, FrameAccumulator, Request, Response, MAX_RESPONSE_ENCODED};
use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};

/// A byte stream to the firmware.
pub trait Port: Read + Write + Send {}
impl<T: Read + Write + Send> Port for T {}

/// Frames over a [`Port`].
pub struct FirmwareLink {
    port: Box<dyn Port>,
    rx: FrameAccumulator<MAX_RESPONSE_ENCODED>,
    received: VecDeque<Response>,
    /// Bytes sent and received so far.
    pub bytes_out: u64,
    pub bytes_in: u64,
}

impl FirmwareLink {
    /// Wraps a port whose reads time out (a read that times out is a lost firmware).
    pub fn new(port: Box<dyn Port>) -> Self {
        FirmwareLink {
            port,
            rx: FrameAccumulator::new(),
            received: VecDeque::new(),
            bytes_out: 0,
            bytes_in: 0,
        }
    }

    /// Sends raw bytes (fault injection, or a frame encoded elsewhere).
    pub fn send_raw(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.port
            .write_all(bytes)
            .context("cannot write to the firmware's port")?;
        self.port.flush().context("cannot write to the firmware's port")?;
        self.bytes_out += bytes.len() as u64;
        Ok(())
    }

    /// Sends one request frame.
    pub fn send(&mut self, request: &Request) -> anyhow::Result<()> {
        let mut frame = [0u8; MAX_FRAME];
        let n = encode_frame(request, &mut frame).map_err(|e| anyhow::anyhow!("cannot encode {request:?}: {e:?}"))?;
        self.send_raw(&frame[..n])
    }

    /// The next response; errors if the port times out, closes, or a response frame is bad.
    pub fn receive(&mut self) -> anyhow::Result<Response> {
        let mut buf = [0u8; 512];
        loop {
            if let Some(r) = self.received.pop_front() {
                return Ok(r);
            }
            let n = match self.port.read(&mut buf) {
                Ok(0) => bail!("the firmware's port closed"),
                Ok(n) => n,
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => {
                    bail!("no response from the firmware (read timed out)")
                }
                Err(e) => return Err(e).context("cannot read from the firmware's port"),
            };
            self.bytes_in += n as u64;
            for &b in &buf[..n] {
                match self.rx.push_decode::<Response>(b) {
                    None => {}
                    Some(Ok(r)) => self.received.push_back(r),
                    Some(Err(e)) => bail!("bad frame from the firmware: {}", e.name()),
                }
            }
        }
    }

    /// Sends a request and waits for its response.
    pub fn request(&mut self, request: &Request) -> anyhow::Result<Response> {
        self.send(request)?;
        self.receive()
    }
}
