//! The firmware's end of the link's receive path, from received bytes to numbered requests: the
//! frame accumulator of `link-protocol` (COBS, CRC, postcard), the holes the receive buffer reports
//! ([`Received::Gap`]: the frame they cut is dropped), and the sequence numbers (lost requests).

use link_protocol::{FrameAccumulator, FrameError, Numbered, Request, MAX_REQUEST_ENCODED};

use crate::sequence::SequenceTracker;
use crate::Received;

/// Bytes in, numbered requests (or why a frame was dropped) out.
#[derive(Default)]
pub struct RequestReceiver {
    frames: FrameAccumulator<MAX_REQUEST_ENCODED>,
    sequence: SequenceTracker,
}

impl RequestReceiver {
    /// No byte received yet, no sequence number seen.
    pub const fn new() -> Self {
        RequestReceiver {
            frames: FrameAccumulator::new(),
            sequence: SequenceTracker::new(),
        }
    }

    /// Takes one received item; at a frame's end returns its request or why it was dropped. A gap
    /// drops the frame in progress (its bytes after the gap then end as one bad frame, counted by
    /// the caller like any other).
    pub fn push(&mut self, item: Received) -> Option<Result<Numbered<Request>, FrameError>> {
        match item {
            Received::Gap => {
                self.frames.discard();
                None
            }
            Received::Byte(byte) => {
                let result = self.frames.push_request(byte)?;
                if let Ok(request) = &result {
                    self.sequence.observe(request.seq);
                }
                Some(result)
            }
        }
    }

    /// Numbered requests that never arrived intact, since boot.
    pub fn lost_frames(&self) -> u32 {
        self.sequence.lost()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::Sample;
    use link_protocol::frame::MAX_FRAME;
    use link_protocol::{encode_frame, SampleMsg};
    use std::vec::Vec;

    fn frame(seq: u32) -> Vec<u8> {
        let sample = Sample::from_degrees(f64::from(seq), 1.0, 2.0, 30.0, 4.0, 0.5, -0.5);
        let mut out = [0u8; MAX_FRAME];
        let n = encode_frame(
            &Numbered {
                seq,
                message: Request::Sample(SampleMsg::from(&sample)),
            },
            &mut out,
        )
        .unwrap();
        out[..n].to_vec()
    }

    fn feed(
        rx: &mut RequestReceiver,
        items: impl IntoIterator<Item = Received>,
    ) -> Vec<Result<u32, FrameError>> {
        items
            .into_iter()
            .filter_map(|i| rx.push(i))
            .map(|r| r.map(|n| n.seq))
            .collect()
    }

    fn bytes(b: &[u8]) -> Vec<Received> {
        b.iter().map(|&b| Received::Byte(b)).collect()
    }

    #[test]
    fn a_gap_drops_the_frame_it_cuts_and_the_lost_number_is_counted() {
        let mut rx = RequestReceiver::new();
        let (f1, f2, f3) = (frame(1), frame(2), frame(3));
        let mut items = bytes(&f1);
        // Frame 2 cut in the middle by a gap: its tail ends as one bad frame.
        items.extend(bytes(&f2[..10]));
        items.push(Received::Gap);
        items.extend(bytes(&f2[25..]));
        items.extend(bytes(&f3));
        let got = feed(&mut rx, items);
        assert_eq!(got.len(), 3, "{got:?}");
        assert_eq!(got[0], Ok(1));
        assert!(got[1].is_err());
        assert_eq!(got[2], Ok(3));
        assert_eq!(rx.lost_frames(), 1);
    }

    #[test]
    fn a_gap_between_frames_loses_nothing() {
        let mut rx = RequestReceiver::new();
        let mut items = bytes(&frame(1));
        items.push(Received::Gap);
        items.extend(bytes(&frame(2)));
        assert_eq!(feed(&mut rx, items), [Ok(1), Ok(2)]);
        assert_eq!(rx.lost_frames(), 0);
    }
}
