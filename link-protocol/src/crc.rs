//! The frame check: CRC-16/IBM-3740 (also known as CRC-16/CCITT-FALSE: polynomial 0x1021,
//! initial value 0xFFFF, no reflection, no final XOR; check value 0x29B1 for "123456789").
//!
//! 16 bits keep request frames short (every byte is a byte time of the UART: 87 us at 115200
//! baud; under QEMU: docs/link-protocol.md). Over the frames of this protocol (at most 160
//! message bytes) it detects every error of up to 3 bits and every burst of up to 16 bits; a
//! random frame passes with probability 2^-16, and must then still decode as a message and pass
//! the estimator's sample checks.

use crc::{Crc, CRC_16_IBM_3740};

const CRC16: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

/// CRC of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    CRC16.checksum(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_of_the_catalogue() {
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }
}
