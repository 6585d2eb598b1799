//! The host end of the link: numbered requests out, numbered responses in, over any byte stream
//! (QEMU's UART socket, a serial port). Framing is `link-protocol`'s, the same code the firmware
//! runs.
//!
//! A reader thread decodes the responses as they come and hands them over a channel, so that the
//! host can send without waiting for answers (`host-sim stream --push`) and still notice each
//! answer as soon as it arrives. Requests are numbered 1, 2, 3, ... in the order they are sent
//! (protocol 5); every answer carries its request's number.

use anyhow::bail;
use link_protocol::frame::MAX_FRAME;
use link_protocol::{
    encode_frame, FrameAccumulator, Numbered, Request, Response, MAX_RESPONSE_ENCODED,
};
use std::io::{ErrorKind, Read, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The reading end of a byte stream to the firmware.
pub trait PortReader: Read + Send {}
impl<T: Read + Send> PortReader for T {}
/// The writing end of a byte stream to the firmware.
pub trait PortWriter: Write + Send {}
impl<T: Write + Send> PortWriter for T {}

/// Frames over a port.
pub struct FirmwareLink {
    writer: Box<dyn PortWriter>,
    answers: Receiver<anyhow::Result<Numbered<Response>>>,
    stop: Arc<AtomicBool>,
    timeout: Duration,
    /// The number of the next request.
    next_seq: u32,
    /// Bytes sent so far.
    pub bytes_out: u64,
    bytes_in: Arc<AtomicU64>,
}

impl FirmwareLink {
    /// Two ends of one port: `reader` (whose reads may time out: a timeout is only a pause) and
    /// `writer`. A response not there `timeout` after it is awaited means a lost firmware.
    pub fn new(
        reader: Box<dyn PortReader>,
        writer: Box<dyn PortWriter>,
        timeout: Duration,
    ) -> Self {
        let (tx, answers) = mpsc::channel();
        let stop = Arc::new(AtomicBool::new(false));
        let bytes_in = Arc::new(AtomicU64::new(0));
        let (thread_stop, thread_bytes) = (stop.clone(), bytes_in.clone());
        std::thread::spawn(move || read_responses(reader, &tx, &thread_stop, &thread_bytes));
        FirmwareLink {
            writer,
            answers,
            stop,
            timeout,
            next_seq: 1,
            bytes_out: 0,
            bytes_in,
        }
    }

    /// Bytes received so far.
    pub fn bytes_in(&self) -> u64 {
        self.bytes_in.load(Ordering::Relaxed)
    }

    /// Sends raw bytes (fault injection, or a frame encoded elsewhere).
    pub fn send_raw(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.writer
            .write_all(bytes)
            .and_then(|()| self.writer.flush())
            .map_err(|e| port_error("cannot write to", &e))?;
        self.bytes_out += bytes.len() as u64;
        Ok(())
    }

    /// Sends one request frame with the next number; returns the number.
    pub fn send(&mut self, request: &Request) -> anyhow::Result<u32> {
        let seq = self.next_seq;
        self.next_seq = firmware_next_seq(seq);
        let mut frame = [0u8; MAX_FRAME];
        let n = encode_frame(
            &Numbered {
                seq,
                message: *request,
            },
            &mut frame,
        )
        .map_err(|e| anyhow::anyhow!("cannot encode {request:?}: {e:?}"))?;
        self.send_raw(&frame[..n])?;
        Ok(seq)
    }

    /// The next response with its number; errors if none comes within the timeout, the port
    /// closes, or a response frame is bad.
    pub fn receive_numbered(&mut self) -> anyhow::Result<Numbered<Response>> {
        match self.answers.recv_timeout(self.timeout) {
            Ok(answer) => answer,
            Err(RecvTimeoutError::Timeout) => {
                bail!("no response from the firmware (read timed out)")
            }
            Err(RecvTimeoutError::Disconnected) => bail!("the firmware's port closed"),
        }
    }

    /// The next response that arrives before `deadline`, if one does.
    pub fn receive_until(
        &mut self,
        deadline: Instant,
    ) -> anyhow::Result<Option<Numbered<Response>>> {
        let wait = deadline.saturating_duration_since(Instant::now());
        match self.answers.recv_timeout(wait) {
            Ok(answer) => answer.map(Some),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => bail!("the firmware's port closed"),
        }
    }

    /// The next response (its number dropped).
    pub fn receive(&mut self) -> anyhow::Result<Response> {
        Ok(self.receive_numbered()?.message)
    }

    /// Sends a request and waits for its answer: responses to earlier requests (late ones) are
    /// passed over; a `Ready` (the firmware restarted) is returned as it is.
    pub fn request(&mut self, request: &Request) -> anyhow::Result<Response> {
        let seq = self.send(request)?;
        loop {
            let answer = self.receive_numbered()?;
            if answer.seq == seq || matches!(answer.message, Response::Ready { .. }) {
                return Ok(answer.message);
            }
        }
    }
}

/// An error of the port, as a message without the `std::io::Error` in its chain: a port that hangs
/// up (a serial port's `BrokenPipe`, QEMU's socket closed) must not pass for a closed standard
/// output, which ends a run quietly with exit status 0.
fn port_error(what: &str, e: &std::io::Error) -> anyhow::Error {
    anyhow::anyhow!("{what} the firmware's port: {e}")
}

/// The number after `seq` (after `u32::MAX` comes 1: 0 is the unnumbered frame's).
fn firmware_next_seq(seq: u32) -> u32 {
    match seq.wrapping_add(1) {
        link_protocol::UNNUMBERED => 1,
        n => n,
    }
}

impl Drop for FirmwareLink {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// The reader thread: decodes every response and hands it over, until the port closes, fails, or
/// the link is dropped (seen at the next read, or read timeout, after it).
fn read_responses(
    mut reader: Box<dyn PortReader>,
    answers: &mpsc::Sender<anyhow::Result<Numbered<Response>>>,
    stop: &AtomicBool,
    bytes_in: &AtomicU64,
) {
    let mut rx = FrameAccumulator::<MAX_RESPONSE_ENCODED>::new();
    let mut buf = [0u8; 512];
    loop {
        let n = match reader.read(&mut buf) {
            Ok(0) => {
                let _ = answers.send(Err(anyhow::anyhow!("the firmware's port closed")));
                return;
            }
            Ok(n) => n,
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                continue;
            }
            Err(e) => {
                let _ = answers.send(Err(port_error("cannot read from", &e)));
                return;
            }
        };
        bytes_in.fetch_add(n as u64, Ordering::Relaxed);
        // Bytes that keep coming (noise on the line, no frame in them) do not keep it alive.
        if stop.load(Ordering::Relaxed) {
            return;
        }
        for &b in &buf[..n] {
            let item = match rx.push_decode::<Numbered<Response>>(b) {
                None => continue,
                Some(Ok(r)) => Ok(r),
                Some(Err(e)) => Err(anyhow::anyhow!("bad frame from the firmware: {}", e.name())),
            };
            if answers.send(item).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::net::UnixStream;

    #[test]
    fn a_port_that_hangs_up_is_an_error_not_a_closed_standard_output() {
        let (host_end, firmware_end) = UnixStream::pair().unwrap();
        drop(firmware_end);
        let reader = host_end.try_clone().unwrap();
        reader
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        let mut link =
            FirmwareLink::new(Box::new(reader), Box::new(host_end), Duration::from_secs(1));
        let e = link.send(&Request::ReadStatus).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("cannot write to the firmware's port: Broken pipe"),
            "{e}"
        );
        // `host-sim` ends quietly (exit status 0) on a broken pipe found in an error's chain.
        assert!(
            !e.chain()
                .any(|c| c.downcast_ref::<std::io::Error>().is_some()),
            "{e:?}"
        );
    }

    #[test]
    fn the_reader_thread_ends_when_the_link_is_dropped_though_noise_keeps_coming() {
        let (host_end, mut firmware_end) = UnixStream::pair().unwrap();
        let reader = host_end.try_clone().unwrap();
        reader
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        let link = FirmwareLink::new(Box::new(reader), Box::new(host_end), Duration::from_secs(1));
        drop(link);
        // Noise without a frame's end, with no pause: once the reader thread has ended, its end
        // of the port is closed and a write fails.
        firmware_end
            .set_write_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            match firmware_end.write(&[0x55; 64]) {
                Ok(_) => {}
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                // Reset when the reader's end was closed with bytes unread.
                Err(e) => {
                    assert!(
                        matches!(e.kind(), ErrorKind::BrokenPipe | ErrorKind::ConnectionReset),
                        "{e}"
                    );
                    break;
                }
            }
            assert!(
                Instant::now() < deadline,
                "the reader thread still reads 10 s after the link was dropped"
            );
        }
    }
}
