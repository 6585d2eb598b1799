//! The link: numbered requests in, numbered responses out. The board receives in the background
//! (interrupt handler or DMA) into its buffer; this file takes the bytes from there
//! (`firmware::request_receiver`: frames, gaps, sequence numbers), sleeps when there are none,
//! and feeds the watchdog each time it wakes. Framing, CRC and message encoding are
//! `link-protocol`'s.

use embedded_io::Write;
use firmware::request_receiver::RequestReceiver;
use firmware::watchdog::Watchdog;
use link_protocol::frame::MAX_FRAME;
use link_protocol::{encode_response_frame, FrameError, LinkCounters, Numbered, Request, Response};

use super::board::{Receiver, Transmitter};

/// The serial port's two ends and the request decoder.
pub struct Link<W> {
    tx: Transmitter,
    rx: Receiver,
    requests: RequestReceiver,
    watchdog: W,
    frame: [u8; MAX_FRAME],
}

impl<W: Watchdog> Link<W> {
    pub fn new(tx: Transmitter, rx: Receiver, watchdog: W) -> Self {
        Link {
            tx,
            rx,
            requests: RequestReceiver::new(),
            watchdog,
            frame: [0; MAX_FRAME],
        }
    }

    /// Waits until a frame has ended; returns its numbered request or why it was dropped. Feeds
    /// the watchdog whenever it wakes (a byte, the line idle, or SysTick's tick): a main loop that
    /// comes back here is alive.
    pub fn receive(&mut self) -> Result<Numbered<Request>, FrameError> {
        loop {
            self.watchdog.feed();
            while let Some(item) = self.rx.next() {
                if let Some(result) = self.requests.push(item) {
                    return result;
                }
            }
            self.rx.wait();
        }
    }

    /// Hands one response frame, numbered `seq`, to the transmitter (which sends it in the
    /// background where the board can). Returns false if it could not be encoded or written.
    pub fn send(&mut self, seq: u32, response: &Response) -> bool {
        let Ok(n) = encode_response_frame(seq, response, &mut self.frame) else {
            return false;
        };
        match self.frame.get(..n) {
            Some(frame) => self.tx.write_all(frame).is_ok(),
            None => false,
        }
    }

    /// The receive path's counters, lost requests included.
    pub fn counters(&self) -> LinkCounters {
        self.rx.counters(self.requests.lost_frames())
    }
}
