//! Test-only: the wire format pinned by golden frames, as postcard pins its own.
//!
//! - The COBS step against the published examples of Cheshire and Baker's algorithm (IEEE/ACM
//!   Transactions on Networking 7(2), 1999), encoded by the `cobs` crate as [`crate::frame`] uses
//!   it and decoded by its strict decoder.
//! - Whole frames of real messages (postcard, CRC-16, COBS, delimiters) as exact bytes: a change
//!   of any message's layout, the CRC or the framing fails here until [`crate::PROTOCOL_VERSION`]
//!   is bumped and the frames below are made again (`cargo test -p link-protocol golden --
//!   --nocapture` prints the new ones).

use std::vec::Vec;

use crate::frame::{cobs_decode_strict, decode_frame, encode_frame, MAX_FRAME};
use crate::message::{Numbered, Request, Response, SampleMsg, UNNUMBERED};

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

fn frame<T: serde::Serialize>(m: &T) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode_frame(m, &mut out).unwrap();
    out[..n].to_vec()
}

fn hex(bytes: &[u8]) -> std::string::String {
    bytes.iter().map(|b| std::format!("{b:02x}")).collect()
}

/// `1, 2, ..., n` as bytes (the published examples' long runs).
fn counting(from: u8, to: u8) -> Vec<u8> {
    (from..=to).collect()
}

#[test]
fn cobs_matches_the_published_examples_both_ways() {
    let long_runs: Vec<(Vec<u8>, Vec<u8>)> = std::vec![
        // 01..FE: one full group, no empty group after it.
        (
            counting(0x01, 0xFE),
            [std::vec![0xFF], counting(0x01, 0xFE)].concat(),
        ),
        // 00 01..FE
        (
            [std::vec![0x00], counting(0x01, 0xFE)].concat(),
            [std::vec![0x01, 0xFF], counting(0x01, 0xFE)].concat(),
        ),
        // 01..FF: the full group, then a group for the last byte.
        (
            counting(0x01, 0xFF),
            [std::vec![0xFF], counting(0x01, 0xFE), std::vec![0x02, 0xFF]].concat(),
        ),
        // 02..FF 00
        (
            [counting(0x02, 0xFF), std::vec![0x00]].concat(),
            [std::vec![0xFF], counting(0x02, 0xFF), std::vec![0x01, 0x01]].concat(),
        ),
        // 03..FF 00 01
        (
            [counting(0x03, 0xFF), std::vec![0x00, 0x01]].concat(),
            [std::vec![0xFE], counting(0x03, 0xFF), std::vec![0x02, 0x01]].concat(),
        ),
    ];
    let short: [(&[u8], &[u8]); 5] = [
        (&[0x00], &[0x01, 0x01]),
        (&[0x00, 0x00], &[0x01, 0x01, 0x01]),
        (&[0x00, 0x11, 0x00], &[0x01, 0x02, 0x11, 0x01]),
        (&[0x11, 0x22, 0x00, 0x33], &[0x03, 0x11, 0x22, 0x02, 0x33]),
        (&[0x11, 0x22, 0x33, 0x44], &[0x05, 0x11, 0x22, 0x33, 0x44]),
    ];
    let examples = short
        .iter()
        .map(|(d, e)| (d.to_vec(), e.to_vec()))
        .chain(long_runs);
    let mut n = 0;
    for (data, encoded) in examples {
        assert_eq!(crate_encode(&data), encoded, "encoding {}", hex(&data));
        assert_eq!(
            strict_decode(&encoded),
            Some(data.clone()),
            "decoding {}",
            hex(&encoded)
        );
        n += 1;
    }
    assert_eq!(n, 10);
    // 11 00 00 00 (the last published short example).
    assert_eq!(
        crate_encode(&[0x11, 0x00, 0x00, 0x00]),
        [0x02, 0x11, 0x01, 0x01, 0x01]
    );
}

/// The frames of real messages, exact bytes (hex, delimiters included).
fn golden() -> [(&'static str, Vec<u8>, &'static str); 6] {
    let sample = SampleMsg::from(&estimator_core::Sample::from_degrees(
        86_399.0, 359.0, -3.0, 61.5, 271.0, -9.5, 4.25,
    ));
    [
        (
            "sample, seq 7",
            frame(&Numbered {
                seq: 7,
                message: Request::Sample(sample),
            }),
            GOLDEN_SAMPLE,
        ),
        (
            "navigation-rate sample, seq 9",
            frame(&Numbered {
                seq: 9,
                message: Request::NavSample(sample),
            }),
            GOLDEN_NAV_SAMPLE,
        ),
        (
            "reset, seq 8",
            frame(&Numbered {
                seq: 8,
                message: Request::Reset,
            }),
            GOLDEN_RESET,
        ),
        (
            "read status, seq 300",
            frame(&Numbered {
                seq: 300,
                message: Request::ReadStatus,
            }),
            GOLDEN_READ_STATUS,
        ),
        (
            "ready",
            frame(&Numbered {
                seq: UNNUMBERED,
                message: Response::Ready {
                    protocol_version: crate::PROTOCOL_VERSION,
                },
            }),
            GOLDEN_READY,
        ),
        (
            "seq 0xFFFF_FFFF",
            frame(&Numbered {
                seq: u32::MAX,
                message: Request::Reset,
            }),
            GOLDEN_LAST_SEQ,
        ),
    ]
}

const GOLDEN_SAMPLE: &str =
    "000207010101011ff017f54035fa8ebc507756bd6f64893ff2d3c6bf1fc929bed8e9973d0b6a00";
const GOLDEN_NAV_SAMPLE: &str =
    "000309030101011ff017f54035fa8ebc507756bd6f64893ff2d3c6bf1fc929bed8e9973d5f3500";
const GOLDEN_RESET: &str = "00050801878400";
const GOLDEN_READ_STATUS: &str = "0006ac0202414200";
const GOLDEN_READY: &str = "000105030728e900";
const GOLDEN_LAST_SEQ: &str = "0009ffffffff0f01df8400";

#[test]
fn golden_frames_are_the_bytes_of_protocol_version_7() {
    assert_eq!(
        crate::PROTOCOL_VERSION,
        7,
        "a new protocol version needs new golden frames (see this module's doc)"
    );
    let frames = golden();
    for (what, bytes, _) in &frames {
        std::println!("{what}: {}", hex(bytes));
    }
    for (what, bytes, golden) in frames {
        assert_eq!(hex(&bytes), golden, "{what}");
    }
}

#[test]
fn golden_frames_decode_and_every_cut_of_them_is_refused() {
    let decoded: Vec<Numbered<Request>> = golden()
        .into_iter()
        .filter(|(what, ..)| *what != "ready")
        .map(|(_, bytes, _)| decode_frame(&mut bytes[1..bytes.len() - 1].to_vec()).unwrap())
        .collect();
    assert_eq!(
        decoded.iter().map(|m| m.seq).collect::<Vec<_>>(),
        [7, 9, 8, 300, u32::MAX]
    );
    assert!(matches!(decoded[1].message, Request::NavSample(_)));
    assert_eq!(decoded[2].message, Request::Reset);
    for (what, bytes, _) in golden() {
        let body = &bytes[1..bytes.len() - 1];
        for cut in 0..body.len() {
            assert!(
                decode_frame::<Numbered<Request>>(&mut body[..cut].to_vec()).is_err(),
                "{what} cut at {cut}"
            );
            assert!(
                decode_frame::<Numbered<Response>>(&mut body[..cut].to_vec()).is_err(),
                "{what} cut at {cut}"
            );
        }
    }
}

/// 254 non-zero bytes at the end: the crate ends the encoding with the full group; the textbook
/// form adds an empty group `0x01`. Both are valid COBS and decode to the same data. No frame
/// reaches it: a frame's data is at most `MAX_MESSAGE + 2` bytes, fewer than 254.
#[test]
fn a_run_of_254_at_the_end_decodes_in_both_forms() {
    const { assert!(crate::MAX_MESSAGE + 2 < 254) };
    let data = std::vec![0xABu8; 254];
    let ours = crate_encode(&data);
    assert_eq!(ours, [std::vec![0xFF], data.clone()].concat());
    assert_eq!(strict_decode(&ours), Some(data.clone()));
    assert_eq!(
        strict_decode(&[ours.as_slice(), &[0x01]].concat()),
        Some(data)
    );
}

/// Why [`cobs_decode_strict`] checks for 0x00 itself: the crate alone decodes up to the first 0x00.
#[test]
fn the_crate_alone_would_read_a_frame_with_a_zero_inside_as_a_shorter_message() {
    let mut frame = [0x02u8, 0x11, 0x00, 0x05];
    assert_eq!(cobs::decode_in_place(&mut frame), Ok(1));
    assert_eq!(cobs::decode_in_place(&mut [0x00]), Ok(0));
    assert_eq!(strict_decode(&[0x02, 0x11, 0x00, 0x05]), None);
    assert_eq!(strict_decode(&[0x00]), None);
    // A truncated group (code 0x05, three bytes after it) and an empty frame.
    assert_eq!(strict_decode(&[0x05, 0x11, 0x22, 0x33]), None);
    assert_eq!(strict_decode(&[]), None);
}
