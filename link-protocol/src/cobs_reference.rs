//! Test-only: the `cobs` crate, as [`crate::frame`] uses it, against a reference COBS codec (the
//! textbook algorithm this crate used to carry, kept here as the oracle). The encoder must give the
//! same bytes for every message size the protocol uses (the wire format does not change), and the
//! strict decoder must accept and refuse exactly what the reference decoder does.

use std::vec::Vec;

use crate::frame::{cobs_decode_strict, encode_frame, MAX_FRAME};
use crate::message::{Request, Response, SampleMsg};
use crate::MAX_MESSAGE;

/// Reference encoder: groups `code, code-1 bytes`; a group with `code < 0xFF` stands for its bytes
/// and a 0x00, except the last group, whose 0x00 is dropped. A full group (`code == 0xFF`) is always
/// followed by another group, so 254 non-zero bytes at the end give a final `0x01`.
fn reference_encode(data: &[u8]) -> Vec<u8> {
    let mut out = std::vec![0u8];
    let mut code_at = 0usize;
    let mut code: u8 = 1;
    for &byte in data {
        if byte == 0 {
            out[code_at] = code;
            code_at = out.len();
            out.push(0);
            code = 1;
        } else {
            out.push(byte);
            code += 1;
            if code == 0xFF {
                out[code_at] = code;
                code_at = out.len();
                out.push(0);
                code = 1;
            }
        }
    }
    out[code_at] = code;
    out
}

/// Reference strict decoder: `None` for an empty frame, a 0x00 anywhere, or a group running past
/// the end of the frame.
fn reference_decode(frame: &[u8]) -> Option<Vec<u8>> {
    if frame.is_empty() {
        return None;
    }
    let mut out = Vec::new();
    let mut read = 0usize;
    while read < frame.len() {
        let code = frame[read];
        if code == 0 {
            return None;
        }
        read += 1;
        let run = code as usize - 1;
        if read + run > frame.len() {
            return None;
        }
        for &byte in &frame[read..read + run] {
            if byte == 0 {
                return None;
            }
            out.push(byte);
        }
        read += run;
        if code != 0xFF && read < frame.len() {
            out.push(0);
        }
    }
    Some(out)
}

fn crate_encode(data: &[u8]) -> Vec<u8> {
    let mut out = std::vec![0u8; cobs::max_encoding_length(data.len())];
    let n = cobs::try_encode(data, &mut out).unwrap();
    out.truncate(n);
    out
}

fn strict_decode(frame: &[u8]) -> Option<Vec<u8>> {
    let mut buf = frame.to_vec();
    let n = cobs_decode_strict(&mut buf).ok()?;
    buf.truncate(n);
    Some(buf)
}

/// Data of `len` bytes in several shapes: no zero, all zero, a zero every `k` bytes, random.
fn patterns(len: usize) -> Vec<Vec<u8>> {
    let mut shapes = std::vec![std::vec![0xABu8; len], std::vec![0u8; len]];
    for k in [2usize, 3, 7, 97] {
        shapes.push((0..len).map(|i| if i % k == 0 { 0 } else { (i % 251) as u8 + 1 }).collect());
    }
    let mut x: u32 = 0x9E37_79B9 ^ len as u32;
    shapes.push(
        (0..len)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                if x % 8 == 0 {
                    0
                } else {
                    (x >> 8) as u8
                }
            })
            .collect(),
    );
    shapes
}

#[test]
fn encoder_bytes_equal_the_reference_for_every_message_size() {
    // A frame's data is a message (at least 1 byte, at most MAX_MESSAGE) and its 2-byte CRC.
    for len in 1..=MAX_MESSAGE + 2 {
        for data in patterns(len) {
            assert_eq!(crate_encode(&data), reference_encode(&data), "len {len}: {data:02x?}");
        }
    }
}

#[test]
fn frames_of_real_messages_equal_the_reference() {
    let sample = SampleMsg::from(&estimator_core::Sample::from_degrees(86_399.0, 359.0, -3.0, 61.5, 271.0, -9.5, 4.25));
    let frames = [
        frame(&Request::Sample(sample)),
        frame(&Request::Reset),
        frame(&Request::ReadStatus),
        frame(&Response::Ready {
            protocol_version: crate::PROTOCOL_VERSION,
        }),
    ];
    for f in frames {
        let body = &f[1..f.len() - 1];
        let data = reference_decode(body).unwrap();
        assert_eq!(reference_encode(&data), body);
        assert_eq!(strict_decode(body), Some(data));
    }
}

fn frame<T: serde::Serialize>(m: &T) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode_frame(m, &mut out).unwrap();
    out[..n].to_vec()
}

#[test]
fn decoder_agrees_with_the_reference_on_every_short_frame() {
    let alphabet = [0x00u8, 0x01, 0x02, 0x03, 0x04, 0x05, 0x11, 0xFE, 0xFF];
    let mut frames: Vec<Vec<u8>> = std::vec![Vec::new()];
    for len in 1..=4 {
        let mut index = std::vec![0usize; len];
        loop {
            frames.push(index.iter().map(|&i| alphabet[i]).collect());
            let mut k = 0;
            while k < len {
                index[k] += 1;
                if index[k] < alphabet.len() {
                    break;
                }
                index[k] = 0;
                k += 1;
            }
            if k == len {
                break;
            }
        }
    }
    assert_eq!(frames.len(), 1 + 9 + 81 + 729 + 6561);
    for f in &frames {
        assert_eq!(strict_decode(f), reference_decode(f), "{f:02x?}");
    }
}

#[test]
fn decoder_agrees_with_the_reference_on_cut_and_damaged_frames() {
    let mut checked = 0;
    for len in [1usize, 2, 3, 35, 100, MAX_MESSAGE + 2] {
        for data in patterns(len) {
            let enc = reference_encode(&data);
            assert_eq!(strict_decode(&enc), Some(data.clone()));
            for cut in 0..enc.len() {
                assert_eq!(strict_decode(&enc[..cut]), reference_decode(&enc[..cut]), "cut {cut}");
                checked += 1;
            }
            for at in 0..enc.len() {
                for value in [0x00u8, 0x01, 0x02, 0x7F, 0xFF] {
                    let mut bad = enc.clone();
                    bad[at] = value;
                    assert_eq!(strict_decode(&bad), reference_decode(&bad), "{value:#04x} at {at}");
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 10_000);
}

/// Beyond the protocol's sizes the encoders differ in one place: 254 non-zero bytes at the end. The
/// crate ends the encoding with the full group, the reference adds an empty group `0x01`; both are
/// valid COBS and decode to the same data. No frame reaches it: a frame's data is at most
/// `MAX_MESSAGE + 2` bytes, fewer than 254.
#[test]
fn a_run_of_254_at_the_end_is_the_one_difference_and_both_forms_decode() {
    const { assert!(MAX_MESSAGE + 2 < 254) };
    for len in [254usize, 508] {
        let data = std::vec![0xABu8; len];
        let ours = crate_encode(&data);
        let reference = reference_encode(&data);
        assert_eq!(&reference[..ours.len()], &ours[..]);
        assert_eq!(&reference[ours.len()..], [0x01]);
        assert_eq!(strict_decode(&ours), Some(data.clone()));
        assert_eq!(strict_decode(&reference), Some(data));
    }
    for len in [253usize, 255, 300] {
        let data = std::vec![0xABu8; len];
        assert_eq!(crate_encode(&data), reference_encode(&data), "len {len}");
    }
}

/// Why [`cobs_decode_strict`] checks for 0x00 itself: the crate alone decodes up to the first 0x00.
#[test]
fn the_crate_alone_would_read_a_frame_with_a_zero_inside_as_a_shorter_message() {
    let mut frame = [0x02u8, 0x11, 0x00, 0x05];
    assert_eq!(cobs::decode_in_place(&mut frame), Ok(1));
    assert_eq!(cobs::decode_in_place(&mut [0x00]), Ok(0));
    assert_eq!(strict_decode(&[0x02, 0x11, 0x00, 0x05]), None);
    assert_eq!(strict_decode(&[0x00]), None);
}
