//! Consistent Overhead Byte Stuffing: removes every 0x00 from a message so that 0x00 can delimit
//! frames. Encoded, the data becomes groups `code, code-1 bytes`; a group with `code < 0xFF` stands
//! for its bytes followed by a 0x00, except the last group, whose implied 0x00 is dropped. Overhead:
//! one byte per started 254 bytes.
//!
//! The decoder is strict: a 0x00 inside the data or a group whose declared length runs past the
//! end of the frame (a truncated frame) is an error, never a short message.

/// What is wrong with an encoded frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CobsError {
    /// A group runs past the end of the frame, or the frame is empty.
    Truncated,
    /// A 0x00 byte inside the frame (the receiver splits frames at 0x00, so only a caller that did
    /// not can see this).
    ZeroByte,
    /// The output buffer is too small.
    BufferTooSmall,
}

/// Largest encoded length of `len` data bytes.
pub const fn max_encoded_len(len: usize) -> usize {
    len + len / 254 + 1
}

/// Encodes `data` into `out`; returns the encoded length.
pub fn encode(data: &[u8], out: &mut [u8]) -> Result<usize, CobsError> {
    let mut code_at = 0usize;
    let mut write = 1usize;
    let mut code: u8 = 1;
    for &byte in data {
        if byte == 0 {
            put(out, code_at, code)?;
            code_at = write;
            write += 1;
            code = 1;
        } else {
            put(out, write, byte)?;
            write += 1;
            code += 1;
            if code == 0xFF {
                put(out, code_at, code)?;
                code_at = write;
                write += 1;
                code = 1;
            }
        }
    }
    put(out, code_at, code)?;
    Ok(write)
}

/// Decodes a frame (without its 0x00 delimiters) in place; returns the decoded length. Decoding
/// never writes ahead of where it reads, so the input buffer holds the message afterwards.
pub fn decode_in_place(frame: &mut [u8]) -> Result<usize, CobsError> {
    if frame.is_empty() {
        return Err(CobsError::Truncated);
    }
    let mut read = 0usize;
    let mut write = 0usize;
    while read < frame.len() {
        let code = get(frame, read)?;
        if code == 0 {
            return Err(CobsError::ZeroByte);
        }
        read += 1;
        let run = code as usize - 1;
        if read + run > frame.len() {
            return Err(CobsError::Truncated);
        }
        for _ in 0..run {
            let byte = get(frame, read)?;
            if byte == 0 {
                return Err(CobsError::ZeroByte);
            }
            put(frame, write, byte)?;
            read += 1;
            write += 1;
        }
        if code != 0xFF && read < frame.len() {
            put(frame, write, 0)?;
            write += 1;
        }
    }
    Ok(write)
}

fn put(buf: &mut [u8], at: usize, byte: u8) -> Result<(), CobsError> {
    match buf.get_mut(at) {
        Some(slot) => {
            *slot = byte;
            Ok(())
        }
        None => Err(CobsError::BufferTooSmall),
    }
}

fn get(buf: &[u8], at: usize) -> Result<u8, CobsError> {
    buf.get(at).copied().ok_or(CobsError::Truncated)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn round_trip(data: &[u8]) -> Vec<u8> {
        let mut out = std::vec![0u8; max_encoded_len(data.len())];
        let n = encode(data, &mut out).unwrap();
        out.truncate(n);
        assert!(!out.contains(&0), "encoded data contains 0x00: {out:?}");
        let mut dec = out.clone();
        let m = decode_in_place(&mut dec).unwrap();
        assert_eq!(&dec[..m], data);
        out
    }

    #[test]
    fn known_vectors_from_the_cobs_paper() {
        assert_eq!(round_trip(&[]), [0x01]);
        assert_eq!(round_trip(&[0x00]), [0x01, 0x01]);
        assert_eq!(round_trip(&[0x00, 0x00]), [0x01, 0x01, 0x01]);
        assert_eq!(round_trip(&[0x11, 0x22, 0x00, 0x33]), [0x03, 0x11, 0x22, 0x02, 0x33]);
        assert_eq!(round_trip(&[0x11, 0x00, 0x00, 0x00]), [0x02, 0x11, 0x01, 0x01, 0x01]);
    }

    #[test]
    fn round_trips_every_length_and_long_runs() {
        for len in 0..600usize {
            let data: Vec<u8> = (0..len)
                .map(|i| if i % 97 == 5 { 0 } else { (i % 251) as u8 + 1 })
                .collect();
            let enc = round_trip(&data);
            assert!(enc.len() <= max_encoded_len(len));
        }
        round_trip(&[0xAB; 254]);
        round_trip(&[0xAB; 255]);
        round_trip(&[0xAB; 508]);
    }

    #[test]
    fn truncated_groups_are_errors() {
        let mut enc = [0u8; 8];
        let n = encode(&[1, 2, 3, 4, 5, 6], &mut enc).unwrap();
        for cut in 1..n {
            let mut part = enc[..cut].to_vec();
            assert_eq!(decode_in_place(&mut part), Err(CobsError::Truncated), "cut at {cut}");
        }
        assert_eq!(decode_in_place(&mut []), Err(CobsError::Truncated));
    }

    #[test]
    fn zero_bytes_inside_are_errors() {
        assert_eq!(decode_in_place(&mut [0x02, 0x00]), Err(CobsError::ZeroByte));
        assert_eq!(decode_in_place(&mut [0x00]), Err(CobsError::ZeroByte));
    }

    #[test]
    fn small_output_buffer_is_an_error_not_a_panic() {
        let mut out = [0u8; 3];
        assert_eq!(encode(&[1, 2, 3, 4], &mut out), Err(CobsError::BufferTooSmall));
    }
}
