//! A model of a board's NOR flash on the host, behind the same `embedded_storage` traits the
//! firmware's store uses: what `host-sim flash-life` runs the store on, and what the power-cut
//! tests cut.
//!
//! NOR semantics: an erase sets a whole sector to 0xFF; programming can only clear bits (the new
//! content is the old AND the data). It counts erases per sector, bytes programmed and the
//! programs that asked for a 1 where the flash holds a 0 (which NOR cannot do: the store must
//! never ask; programming zeros again over a torn unit is fine), and it can cut the
//! power at its n-th operation: an erase of a sector, or the programming of one program unit (a
//! byte on the STM32F405, whose HAL programs at x8; a word elsewhere). The operation the cut lands
//! in is left torn (an erase with a random part of its bytes erased, a unit with a random part of
//! its bits cleared), and every operation after it fails, as on a board whose supply is gone.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use firmware::flash_layout::FlashLayout;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// What the model counted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlashCounts {
    /// Erases of each sector.
    pub erases: Vec<u64>,
    /// Bytes programmed.
    pub programmed_bytes: u64,
    /// Program units that asked for a bit set where the flash held it cleared: data NOR flash
    /// cannot hold, which the store must never write (must stay 0).
    pub impossible_writes: u64,
    /// Operations (sector erases and program units) so far.
    pub operations: u64,
}

/// A flash of `SECTOR`-byte sectors and `WORD`-byte writes (the constants of the board's
/// `NorFlash`), programmed `unit` bytes at a time.
#[derive(Clone, Debug)]
pub struct FlashModel<const SECTOR: usize, const WORD: usize> {
    bytes: Vec<u8>,
    unit: usize,
    counts: FlashCounts,
    /// The operation the power is cut at (`counts.operations` when it starts), if any.
    cut_at: Option<u64>,
    powered: bool,
    rng: ChaCha8Rng,
}

impl<const SECTOR: usize, const WORD: usize> FlashModel<SECTOR, WORD> {
    /// An erased flash of `sectors` sectors, programmed `unit` bytes at a time.
    pub fn new(sectors: usize, unit: usize) -> Self {
        FlashModel {
            bytes: vec![0xFF; sectors * SECTOR],
            unit: unit.clamp(1, WORD),
            counts: FlashCounts {
                erases: vec![0; sectors],
                ..FlashCounts::default()
            },
            cut_at: None,
            powered: true,
            rng: ChaCha8Rng::seed_from_u64(0x0F1A_5400),
        }
    }

    /// The board's flash: its sector count, and units of a byte where its program is byte-wise.
    pub fn for_layout(layout: &FlashLayout) -> Self {
        assert_eq!(
            layout.sector_bytes as usize, SECTOR,
            "{}: the model's sector size",
            layout.board
        );
        let unit = if layout.byte_program_s.is_some() {
            1
        } else {
            WORD
        };
        Self::new(layout.sectors as usize, unit)
    }

    /// What was counted.
    pub fn counts(&self) -> &FlashCounts {
        &self.counts
    }

    /// The content.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Cuts the power at operation `at` (counted from the start), tearing it; `None`: never.
    pub fn cut_power_at(&mut self, at: Option<u64>, seed: u64) {
        self.cut_at = at;
        self.rng = ChaCha8Rng::seed_from_u64(seed);
    }

    /// Power back (after a cut): every operation works again; nothing else changes.
    pub fn power_on(&mut self) {
        self.powered = true;
        self.cut_at = None;
    }

    /// Whether the power was cut.
    pub fn was_cut(&self) -> bool {
        !self.powered
    }

    /// Starts an operation: false (and the power gone) if it is the one the power is cut at.
    fn operation(&mut self) -> Result<bool, NorFlashErrorKind> {
        if !self.powered {
            return Err(NorFlashErrorKind::Other);
        }
        let torn = self.cut_at == Some(self.counts.operations);
        self.counts.operations += 1;
        if torn {
            self.powered = false;
        }
        Ok(!torn)
    }

    fn check(&self, offset: u32, len: usize, align: usize) -> Result<usize, NorFlashErrorKind> {
        let at = offset as usize;
        if !at.is_multiple_of(align) || !len.is_multiple_of(align) {
            return Err(NorFlashErrorKind::NotAligned);
        }
        if at + len > self.bytes.len() {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        Ok(at)
    }
}

impl<const SECTOR: usize, const WORD: usize> ErrorType for FlashModel<SECTOR, WORD> {
    type Error = NorFlashErrorKind;
}

impl<const SECTOR: usize, const WORD: usize> ReadNorFlash for FlashModel<SECTOR, WORD> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        if !self.powered {
            return Err(NorFlashErrorKind::Other);
        }
        let at = self.check(offset, bytes.len(), 1)?;
        bytes.copy_from_slice(&self.bytes[at..at + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl<const SECTOR: usize, const WORD: usize> NorFlash for FlashModel<SECTOR, WORD> {
    const WRITE_SIZE: usize = WORD;
    const ERASE_SIZE: usize = SECTOR;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), NorFlashErrorKind> {
        if to < from {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        let start = self.check(from, (to - from) as usize, SECTOR)?;
        for sector in (start..to as usize).step_by(SECTOR) {
            let whole = self.operation()?;
            self.counts.erases[sector / SECTOR] += 1;
            for b in &mut self.bytes[sector..sector + SECTOR] {
                if whole || self.rng.gen_bool(0.5) {
                    *b = 0xFF;
                }
            }
            if !whole {
                return Err(NorFlashErrorKind::Other);
            }
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), NorFlashErrorKind> {
        let start = self.check(offset, data.len(), WORD)?;
        for (k, chunk) in data.chunks(self.unit).enumerate() {
            let whole = self.operation()?;
            let at = start + k * self.unit;
            let old = &mut self.bytes[at..at + chunk.len()];
            if old.iter().zip(chunk).any(|(o, d)| *o & *d != *d) {
                self.counts.impossible_writes += 1;
            }
            for (b, d) in old.iter_mut().zip(chunk) {
                // A torn unit: a random part of the bits that were to be cleared are.
                let cleared = if whole {
                    !*d
                } else {
                    !*d & self.rng.r#gen::<u8>()
                };
                *b &= !cleared;
            }
            self.counts.programmed_bytes += chunk.len() as u64;
            if !whole {
                return Err(NorFlashErrorKind::Other);
            }
        }
        Ok(())
    }
}

/// The STM32F405's checkpoint flash as the firmware's store sees it (`board/stm32f405/flash.rs`:
/// 128 KiB sectors, 4-byte writes, programmed byte by byte).
pub type Stm32f405Flash = FlashModel<{ 128 * 1024 }, 4>;
/// mps2-an386's checkpoint flash as the firmware's store sees it (`board/semihosted_flash.rs`:
/// 4 KiB sectors, 4-byte writes).
pub type Mps2An386Flash = FlashModel<4096, 4>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nor_semantics_counts_and_a_torn_unit() {
        let mut f = FlashModel::<64, 4>::new(2, 1);
        f.write(0, &[0x0F, 0xF0, 0x00, 0xFF]).unwrap();
        f.write(0, &[0xFF, 0x0F, 0xFF, 0xFF]).unwrap();
        assert_eq!(&f.bytes()[..4], &[0x0F, 0x00, 0x00, 0xFF]);
        // 0xFF over 0x0F and 0x0F over 0xF0 ask for bits NOR cannot set; 0xFF over 0x00 too.
        assert_eq!(f.counts().impossible_writes, 3);
        f.erase(0, 64).unwrap();
        assert!(f.bytes()[..64].iter().all(|b| *b == 0xFF));
        assert_eq!(f.counts().erases, vec![1, 0]);
        assert_eq!(f.counts().operations, 9);
        assert_eq!(f.write(2, &[0; 4]), Err(NorFlashErrorKind::NotAligned));
        assert_eq!(f.erase(0, 32), Err(NorFlashErrorKind::NotAligned));
        // The power cut at the 11th operation: the second byte of this write.
        f.cut_power_at(Some(10), 7);
        assert_eq!(f.write(64, &[0, 0, 0, 0]), Err(NorFlashErrorKind::Other));
        assert!(f.was_cut());
        assert_eq!(f.bytes()[64], 0);
        assert!(
            f.bytes()[66..68].iter().all(|b| *b == 0xFF),
            "after the torn byte nothing is written"
        );
        assert_eq!(f.read(0, &mut [0; 4]), Err(NorFlashErrorKind::Other));
        f.power_on();
        assert!(f.read(0, &mut [0; 4]).is_ok());
    }
}
