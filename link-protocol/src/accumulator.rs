//! The streaming receiver: bytes in, frames out, in a fixed buffer.
//!
//! Every 0x00 ends a frame. Bytes beyond the buffer's capacity are dropped and the frame they belong
//! to is reported as [`FrameError::Oversize`] when its 0x00 arrives; the next frame starts clean.
//! An empty frame (two 0x00 in a row) is not a frame and is not reported. Nothing here can panic.

use serde::de::DeserializeOwned;

use crate::frame::{decode_frame, FrameError};

/// Receive buffer of `N` bytes.
pub struct FrameAccumulator<const N: usize> {
    /// The bytes of the frame being received; after its 0x00, the frame just ended (lent out by
    /// [`Self::push`]) until the next byte arrives.
    frame: heapless::Vec<u8, N>,
    /// `frame` holds an ended frame: the next byte starts a new one.
    ended: bool,
    /// More than `N` bytes have arrived since the last 0x00.
    oversize: bool,
}

impl<const N: usize> Default for FrameAccumulator<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FrameAccumulator<N> {
    /// An empty receiver.
    pub const fn new() -> Self {
        FrameAccumulator {
            frame: heapless::Vec::new(),
            ended: false,
            oversize: false,
        }
    }

    /// Takes one byte. At a frame's end returns its COBS bytes (without delimiters), or
    /// `Err(Oversize)`; `None` otherwise.
    pub fn push(&mut self, byte: u8) -> Option<Result<&mut [u8], FrameError>> {
        if core::mem::take(&mut self.ended) {
            self.frame.clear();
        }
        if byte == 0 {
            if core::mem::take(&mut self.oversize) {
                self.frame.clear();
                return Some(Err(FrameError::Oversize));
            }
            if self.frame.is_empty() {
                return None;
            }
            self.ended = true;
            return Some(Ok(self.frame.as_mut_slice()));
        }
        if !self.oversize && self.frame.push(byte).is_err() {
            self.oversize = true;
        }
        None
    }

    /// Takes one byte; at a frame's end returns the decoded message or why the frame was bad.
    pub fn push_decode<T: DeserializeOwned>(&mut self, byte: u8) -> Option<Result<T, FrameError>> {
        self.push(byte)
            .map(|frame| frame.and_then(|bytes| decode_frame(bytes)))
    }

    /// Drops the frame being received (its bytes were cut by a hole in the stream); the bytes up
    /// to the next 0x00 then form a frame of their own.
    pub fn discard(&mut self) {
        self.frame.clear();
        self.ended = false;
        self.oversize = false;
    }

    /// Bytes of the frame being received so far.
    pub fn pending(&self) -> usize {
        if self.ended {
            0
        } else {
            self.frame.len()
        }
    }
}

impl FrameAccumulator<{ crate::MAX_REQUEST_ENCODED }> {
    /// [`Self::push_decode`] of a numbered request, compiled here once (not generic): the
    /// firmware's one decoder, built with this crate's optimisation (size, in the firmware's
    /// profile) rather than inlined into the caller.
    #[inline(never)]
    pub fn push_request(
        &mut self,
        byte: u8,
    ) -> Option<Result<crate::message::Numbered<crate::message::Request>, FrameError>> {
        self.push_decode(byte)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{encode_frame, MAX_FRAME};
    use crate::message::{Request, SampleMsg};
    use crate::MAX_REQUEST_ENCODED;
    use estimator_core::Sample;
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::vec::Vec;

    type Rx = FrameAccumulator<MAX_REQUEST_ENCODED>;

    fn frame(r: &Request) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode_frame(r, &mut out).unwrap();
        out[..n].to_vec()
    }

    fn sample(t: f64) -> Request {
        Request::Sample(SampleMsg::from(&Sample::from_degrees(
            t,
            t * 0.75,
            3.0,
            30.0,
            1.0,
            0.5,
            -0.5,
        )))
    }

    fn feed(rx: &mut Rx, bytes: &[u8]) -> Vec<Result<Request, FrameError>> {
        bytes
            .iter()
            .filter_map(|b| rx.push_decode::<Request>(*b))
            .collect()
    }

    #[test]
    fn back_to_back_frames_come_out_in_order() {
        let mut rx = Rx::new();
        let mut stream = Vec::new();
        let sent: Vec<Request> = (0..50)
            .map(|i| sample(i as f64))
            .chain([Request::Reset, Request::ReadStatus])
            .collect();
        for r in &sent {
            stream.extend(frame(r));
        }
        let got: Vec<Request> = feed(&mut rx, &stream)
            .into_iter()
            .map(|r| r.unwrap())
            .collect();
        assert_eq!(got, sent);
    }

    #[test]
    fn byte_at_a_time_split_anywhere_gives_the_same_frames() {
        let f = frame(&sample(7.0));
        for split in 0..f.len() {
            let mut rx = Rx::new();
            let mut got = feed(&mut rx, &f[..split]);
            got.extend(feed(&mut rx, &f[split..]));
            assert_eq!(got, std::vec![Ok(sample(7.0))]);
        }
    }

    #[test]
    fn garbage_before_a_frame_is_one_bad_frame_and_the_frame_survives() {
        let mut rx = Rx::new();
        let mut stream = std::vec![0x13, 0x99, 0xFF, 0x42, 0x07];
        stream.extend(frame(&sample(1.0)));
        let got = feed(&mut rx, &stream);
        assert_eq!(got.len(), 2);
        assert!(got[0].is_err());
        assert_eq!(got[1], Ok(sample(1.0)));
    }

    #[test]
    fn truncated_frame_is_counted_and_the_next_frame_survives() {
        let full = frame(&sample(2.0));
        for cut in 2..full.len() - 1 {
            let mut rx = Rx::new();
            let mut stream = full[..cut].to_vec();
            stream.extend(frame(&sample(3.0)));
            let got = feed(&mut rx, &stream);
            assert_eq!(got.len(), 2, "cut {cut}");
            assert!(
                matches!(
                    got[0],
                    Err(FrameError::Cobs | FrameError::TooShort | FrameError::Crc)
                ),
                "cut {cut}: {:?}",
                got[0]
            );
            assert_eq!(got[1], Ok(sample(3.0)));
        }
    }

    #[test]
    fn oversized_frame_is_reported_once_and_resyncs() {
        let mut rx = Rx::new();
        let mut stream = std::vec![0u8];
        stream.extend(core::iter::repeat_n(0x5A, 1000));
        stream.extend(frame(&sample(4.0)));
        let got = feed(&mut rx, &stream);
        assert_eq!(got, std::vec![Err(FrameError::Oversize), Ok(sample(4.0))]);
        // Exactly the capacity is still a frame (a bad one here), one more byte is oversize.
        let mut rx = Rx::new();
        let mut at_cap = std::vec![0x5Au8; MAX_REQUEST_ENCODED];
        at_cap.push(0);
        assert_ne!(feed(&mut rx, &at_cap), std::vec![Err(FrameError::Oversize)]);
        let mut over = std::vec![0x5Au8; MAX_REQUEST_ENCODED + 1];
        over.push(0);
        assert_eq!(feed(&mut rx, &over), std::vec![Err(FrameError::Oversize)]);
    }

    #[test]
    fn corrupted_crc_is_reported_as_crc() {
        let mut rx = Rx::new();
        let mut f = frame(&sample(5.0));
        // Flip a bit of a data byte that is not a COBS code byte and stays non-zero.
        let i = f.len() / 2;
        f[i] ^= 0x10;
        if f[i] == 0 {
            f[i] = 0x33;
        }
        let got = feed(&mut rx, &f);
        assert_eq!(got.len(), 1);
        assert!(matches!(got[0], Err(FrameError::Crc | FrameError::Cobs)));
    }

    #[test]
    fn pending_counts_the_bytes_of_the_frame_in_progress_only() {
        let mut rx = Rx::new();
        let f = frame(&Request::Reset);
        assert_eq!(f, [0x00, 0x04, 0x01, 0xd1, 0xf1, 0x00]);
        for (i, b) in f[..5].iter().enumerate() {
            assert!(rx.push(*b).is_none());
            assert_eq!(rx.pending(), i, "after {} bytes", i + 1);
        }
        assert_eq!(
            rx.push(0).map(|r| r.map(|bytes| bytes.to_vec())),
            Some(Ok(f[1..5].to_vec()))
        );
        assert_eq!(rx.pending(), 0);
        assert!(rx.push(0x02).is_none());
        assert_eq!(rx.pending(), 1, "a new frame starts after the ended one");
    }

    #[test]
    fn discard_drops_the_frame_in_progress_only() {
        let mut rx = Rx::new();
        let f = frame(&sample(6.0));
        assert!(feed(&mut rx, &f[..20]).is_empty());
        rx.discard();
        assert_eq!(rx.pending(), 0);
        // The rest of the cut frame is one bad frame; the next frame is whole.
        let mut stream = f[20..].to_vec();
        stream.extend(frame(&sample(7.0)));
        let got = feed(&mut rx, &stream);
        assert_eq!(got.len(), 2);
        assert!(got[0].is_err());
        assert_eq!(got[1], Ok(sample(7.0)));
    }

    #[test]
    fn empty_frames_are_ignored() {
        let mut rx = Rx::new();
        assert!(feed(&mut rx, &[0, 0, 0, 0]).is_empty());
    }

    #[test]
    fn random_bytes_never_panic() {
        let mut rx = Rx::new();
        let mut rng = ChaCha8Rng::seed_from_u64(0x1234_5678);
        for _ in 0..200_000 {
            let x = rng.next_u32();
            let b = if x.is_multiple_of(17) {
                0
            } else {
                (x >> 8) as u8
            };
            let _ = rx.push_decode::<Request>(b);
        }
    }
}
