//! The learned installation errors as a small record that every later version reads.
//!
//! A checkpoint ([`crate::checkpoint`]) holds the whole state and is refused by a build of another
//! format version: after a software update the estimator would start from nothing and compensate
//! nothing for its first period. This record holds only what compensation needs, the estimate and
//! its 1-sigma and the time it was taken, in a layout that is never changed, only extended: a
//! later version reads its first fields whatever it appends. A build that refuses the checkpoint
//! starts from the record instead, as from known values ([`crate::Config::prior`]).
//!
//! # Layout (little-endian, [`LEARNED_LEN`] bytes in version 1)
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 4 | magic [`LEARNED_MAGIC`], `RILE` |
//! | 4 | 2 | layout version (1); a later version keeps every field below where it is |
//! | 6 | 2 | length of the whole record, CRC included (52 in version 1; more when a later version appends fields before the CRC) |
//! | 8 | 8 | time of the estimate's last sample, s (f64) |
//! | 16 | 16 | x1..x4, rad (f32 each) |
//! | 32 | 16 | their 1-sigma, rad (f32 each) |
//! | length - 4 | 4 | CRC-32 ([`crate::checkpoint::crc32`]) of every byte before it |
//!
//! Read back, the 1-sigma becomes at least [`LEARNED_MIN_SIGMA_RAD`]: the build that reads the
//! record may weigh the log otherwise than the one that wrote it, and the errors may have moved
//! while the software was updated; a 1-sigma of a few hundredths of an arcsecond would hold the
//! new filter to the old estimate for hours.

use crate::checkpoint::crc32;
use crate::config::Prior;
use crate::Real;

/// First four bytes of a record.
pub const LEARNED_MAGIC: [u8; 4] = *b"RILE";
/// The layout version this build writes.
pub const LEARNED_VERSION: u16 = 1;
/// Bytes of a record of version 1, the shortest a reader accepts.
pub const LEARNED_LEN: usize = 52;
/// The smallest 1-sigma a record is read back with, rad (1 arcsec).
pub const LEARNED_MIN_SIGMA_RAD: Real = (1.0 / crate::units::ARCSEC_PER_RAD) as Real;

/// The estimate a record holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearnedErrors {
    /// Time of the last sample the estimate had seen, s.
    pub time_s: f64,
    /// x1..x4, rad.
    pub x_rad: [f32; 4],
    /// Their 1-sigma, rad.
    pub sigma_rad: [f32; 4],
}

/// Why bytes are not a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LearnedError {
    /// Fewer bytes than the record says it has, or than a record of version 1.
    TooShort,
    /// The bytes do not start with [`LEARNED_MAGIC`].
    NotARecord,
    /// Version 0, or a length below [`LEARNED_LEN`]: no layout this build knows.
    UnknownLayout,
    /// The CRC does not match: a damaged record.
    Crc,
    /// A value out of its bounds: a time or an error not finite, an error beyond 1 rad, a 1-sigma
    /// not positive.
    InvalidValue,
}

impl core::fmt::Display for LearnedError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            LearnedError::TooShort => "learned-errors record: too short",
            LearnedError::NotARecord => "learned-errors record: no record (wrong magic)",
            LearnedError::UnknownLayout => "learned-errors record: unknown layout",
            LearnedError::Crc => "learned-errors record: CRC mismatch (damaged)",
            LearnedError::InvalidValue => "learned-errors record: a value out of its bounds",
        })
    }
}

impl core::error::Error for LearnedError {}

impl LearnedErrors {
    /// The record, version [`LEARNED_VERSION`].
    pub fn encode(&self) -> [u8; LEARNED_LEN] {
        let mut b = [0u8; LEARNED_LEN];
        b[..4].copy_from_slice(&LEARNED_MAGIC);
        b[4..6].copy_from_slice(&LEARNED_VERSION.to_le_bytes());
        b[6..8].copy_from_slice(&(LEARNED_LEN as u16).to_le_bytes());
        b[8..16].copy_from_slice(&self.time_s.to_le_bytes());
        for i in 0..4 {
            b[16 + 4 * i..20 + 4 * i].copy_from_slice(&self.x_rad[i].to_le_bytes());
            b[32 + 4 * i..36 + 4 * i].copy_from_slice(&self.sigma_rad[i].to_le_bytes());
        }
        let crc = crc32(&b[..LEARNED_LEN - 4]);
        b[LEARNED_LEN - 4..].copy_from_slice(&crc.to_le_bytes());
        b
    }

    /// Reads a record of any version from the start of `bytes` (which may go on past it), and
    /// returns it with its length; nothing else is read.
    pub fn decode(bytes: &[u8]) -> Result<(LearnedErrors, usize), LearnedError> {
        let word = |o: usize| -> Option<[u8; 4]> { bytes.get(o..o + 4)?.try_into().ok() };
        let head = word(0).zip(word(4)).ok_or(LearnedError::TooShort)?;
        if head.0 != LEARNED_MAGIC {
            return Err(LearnedError::NotARecord);
        }
        let version = u16::from_le_bytes([head.1[0], head.1[1]]);
        let len = usize::from(u16::from_le_bytes([head.1[2], head.1[3]]));
        if version == 0 || len < LEARNED_LEN {
            return Err(LearnedError::UnknownLayout);
        }
        let body = bytes.get(..len - 4).ok_or(LearnedError::TooShort)?;
        let crc = word(len - 4).ok_or(LearnedError::TooShort)?;
        if crc32(body) != u32::from_le_bytes(crc) {
            return Err(LearnedError::Crc);
        }
        // Every word below lies within the CRC-checked body (`len` is at least `LEARNED_LEN`).
        let f32_at = |o: usize| f32::from_le_bytes(word(o).unwrap_or([0xFF; 4]));
        let (lo, hi) = (word(8).unwrap_or_default(), word(12).unwrap_or_default());
        let time_s = f64::from_bits(
            u64::from(u32::from_le_bytes(lo)) | (u64::from(u32::from_le_bytes(hi)) << 32),
        );
        let learned = LearnedErrors {
            time_s,
            x_rad: [f32_at(16), f32_at(20), f32_at(24), f32_at(28)],
            sigma_rad: [f32_at(32), f32_at(36), f32_at(40), f32_at(44)],
        };
        let valid = time_s.is_finite()
            && learned.x_rad.iter().all(|x| x.abs() <= 1.0)
            && learned.sigma_rad.iter().all(|s| *s > 0.0 && s.is_finite());
        if !valid {
            return Err(LearnedError::InvalidValue);
        }
        Ok((learned, len))
    }

    /// The record as known values for a configuration whose prior 1-sigma is `max_sigma_rad`:
    /// each 1-sigma at least [`LEARNED_MIN_SIGMA_RAD`] and at most `max_sigma_rad`.
    pub fn prior(&self, max_sigma_rad: Real) -> Prior {
        Prior {
            x_rad: self.x_rad.map(|x| x as Real),
            sigma_rad: self
                .sigma_rad
                .map(|s| (s as Real).max(LEARNED_MIN_SIGMA_RAD).min(max_sigma_rad)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::arcsec_to_rad;

    fn record() -> LearnedErrors {
        LearnedErrors {
            time_s: 45_000.0,
            x_rad: [9.7e-4, -7.3e-4, 1.45e-3, -1.2e-3],
            sigma_rad: [2e-7, 2e-7, 2.5e-7, 2.5e-7],
        }
    }

    /// A record reads back as written; every byte cut short, any flipped bit, another magic or an
    /// unknown layout is refused by name.
    #[test]
    fn a_record_reads_back_and_damage_is_refused() {
        let r = record();
        let bytes = r.encode();
        assert_eq!(LearnedErrors::decode(&bytes), Ok((r, LEARNED_LEN)));
        for cut in 0..LEARNED_LEN {
            assert_eq!(
                LearnedErrors::decode(&bytes[..cut]),
                Err(LearnedError::TooShort),
                "{cut}"
            );
        }
        for byte in 8..LEARNED_LEN {
            let mut b = bytes;
            b[byte] ^= 0x10;
            assert_eq!(LearnedErrors::decode(&b), Err(LearnedError::Crc), "{byte}");
        }
        let mut b = bytes;
        b[0] = b'X';
        assert_eq!(LearnedErrors::decode(&b), Err(LearnedError::NotARecord));
        let mut b = bytes;
        b[4] = 0;
        assert_eq!(LearnedErrors::decode(&b), Err(LearnedError::UnknownLayout));
        let nan = LearnedErrors {
            time_s: f64::NAN,
            ..r
        };
        assert_eq!(
            LearnedErrors::decode(&nan.encode()),
            Err(LearnedError::InvalidValue)
        );
    }

    /// A later version that appends a field (and says its longer length) is read for the fields
    /// this version knows; what follows a record is left alone.
    #[test]
    fn a_later_layout_is_read_for_the_fields_it_keeps() {
        let r = record();
        let v1 = r.encode();
        let mut v2 = std::vec::Vec::from(&v1[..LEARNED_LEN - 4]);
        v2[4..6].copy_from_slice(&2u16.to_le_bytes());
        v2[6..8].copy_from_slice(&((LEARNED_LEN + 8) as u16).to_le_bytes());
        v2.extend_from_slice(&1.5f64.to_le_bytes());
        let crc = crc32(&v2);
        v2.extend_from_slice(&crc.to_le_bytes());
        v2.extend_from_slice(b"a checkpoint follows");
        assert_eq!(LearnedErrors::decode(&v2), Ok((r, LEARNED_LEN + 8)));
    }

    /// Read back as known values, a 1-sigma of hundredths of an arcsecond becomes 1 arcsec.
    #[test]
    fn the_prior_of_a_record_is_at_least_an_arcsecond() {
        let p = record().prior(arcsec_to_rad(1000.0) as Real);
        assert_eq!(p.x_rad, record().x_rad.map(|x| x as Real));
        assert!(p.sigma_rad.iter().all(|s| *s == LEARNED_MIN_SIGMA_RAD));
    }
}
