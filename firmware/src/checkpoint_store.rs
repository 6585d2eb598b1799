//! The estimator's checkpoint in two alternating flash slots (any `embedded_storage` NOR flash).
//!
//! Slot `i` starts at `i * slot_bytes(ERASE_SIZE)` (header and image rounded up to whole erase
//! blocks, so that erasing one slot never touches the other): a 16-byte header (magic `RCKP`, sequence number u32 LE,
//! the checkpointed sample's `time_s` f64 LE), then the core's checkpoint image
//! (`Estimator::CHECKPOINT_LEN` bytes, with its own magic, version and CRC-32). A save erases the
//! slot that does not hold the newest image, writes the image, and writes the header last. A power
//! cut at any point of a save leaves that slot without a valid header or with an image that fails
//! the core's checks, and the other slot, untouched, still holds the last good image. At boot the
//! slots are tried newest first; the first one the core restores wins.
//!
//! [`CheckpointStore::invalidate`] (the host's `Reset`) erases the header block of both slots, the
//! older first: a power cut in between leaves at most the newest image, i.e. the state as it was
//! before the reset was asked for (which was then not answered), never an older one. Once it
//! returns, no image is left to restore: a later power cut cannot bring the forgotten state back.

use embedded_storage::nor_flash::NorFlash;
use estimator_core::Estimator;

const MAGIC: [u8; 4] = *b"RCKP";
const HEADER_BYTES: usize = 16;
/// Bytes of one checkpoint image.
pub const IMAGE_BYTES: usize = <Estimator>::CHECKPOINT_LEN;
/// One slot on a flash of `erase_size` erase blocks: header and image, rounded up to whole blocks.
pub const fn slot_bytes(erase_size: usize) -> usize {
    (HEADER_BYTES + IMAGE_BYTES).div_ceil(erase_size) * erase_size
}

/// A slot's header.
#[derive(Clone, Copy)]
struct Header {
    sequence: u32,
    time_s: f64,
}

/// Why a save or an invalidation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum StoreError {
    /// The core could not write its checkpoint image.
    Checkpoint,
    /// The flash refused an erase or a write.
    Flash,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            StoreError::Checkpoint => "the estimator could not write its checkpoint image",
            StoreError::Flash => "the flash refused an erase or a write",
        })
    }
}

impl core::error::Error for StoreError {}

/// The two slots on a flash.
pub struct CheckpointStore<F> {
    flash: F,
    /// Sequence number and slot of the newest valid image, if any.
    newest: Option<(u32, usize)>,
    /// Images written since boot.
    pub saved: u32,
    /// Time of the newest image saved or restored.
    pub time_s: Option<f64>,
}

impl<F: NorFlash> CheckpointStore<F> {
    /// Bytes of one slot on this flash.
    const SLOT_BYTES: usize = slot_bytes(F::ERASE_SIZE);

    pub fn new(flash: F) -> Self {
        CheckpointStore {
            flash,
            newest: None,
            saved: 0,
            time_s: None,
        }
    }

    fn header(&mut self, slot: usize) -> Option<Header> {
        let mut bytes = [0u8; HEADER_BYTES];
        self.flash.read((slot * Self::SLOT_BYTES) as u32, &mut bytes).ok()?;
        let (magic, rest) = bytes.split_first_chunk::<4>()?;
        let (sequence, rest) = rest.split_first_chunk::<4>()?;
        let (time, _) = rest.split_first_chunk::<8>()?;
        (*magic == MAGIC).then(|| Header {
            sequence: u32::from_le_bytes(*sequence),
            time_s: f64::from_le_bytes(*time),
        })
    }

    /// Restores the newest image the core accepts; returns its time. `image` is scratch space.
    pub fn restore(&mut self, estimator: &mut Estimator, image: &mut [u8; IMAGE_BYTES]) -> Option<f64> {
        let mut slots = [(0usize, self.header(0)), (1usize, self.header(1))];
        if let [(_, Some(a)), (_, Some(b))] = &slots {
            if b.sequence > a.sequence {
                slots.swap(0, 1);
            }
        }
        for (slot, header) in slots {
            let Some(header) = header else { continue };
            if self
                .flash
                .read((slot * Self::SLOT_BYTES + HEADER_BYTES) as u32, image)
                .is_err()
            {
                continue;
            }
            if estimator.restore(image).is_ok() {
                self.newest = Some((header.sequence, slot));
                self.time_s = Some(header.time_s);
                return Some(header.time_s);
            }
        }
        None
    }

    /// Makes both slots invalid (their first erase block, which holds the header, erased), the
    /// older slot first. On success nothing is left to restore and the next save starts afresh in
    /// slot 0; on a flash error the store still describes what the flash may hold.
    pub fn invalidate(&mut self) -> Result<(), StoreError> {
        let newest_slot = self.newest.map_or(1, |(_, slot)| slot);
        for slot in [1 - newest_slot, newest_slot] {
            let base = (slot * Self::SLOT_BYTES) as u32;
            let header_block = F::ERASE_SIZE.max(HEADER_BYTES) as u32;
            self.flash
                .erase(base, base + header_block)
                .map_err(|_| StoreError::Flash)?;
        }
        self.newest = None;
        self.time_s = None;
        Ok(())
    }

    /// Saves the estimator's state, taken at the sample of `time_s`, into the older slot.
    pub fn save(
        &mut self,
        estimator: &Estimator,
        time_s: f64,
        image: &mut [u8; IMAGE_BYTES],
    ) -> Result<(), StoreError> {
        estimator.checkpoint(image).map_err(|_| StoreError::Checkpoint)?;
        let (sequence, slot) = match self.newest {
            Some((s, slot)) => (s.wrapping_add(1), 1 - slot),
            None => (1, 0),
        };
        let base = (slot * Self::SLOT_BYTES) as u32;
        self.flash
            .erase(base, base + Self::SLOT_BYTES as u32)
            .map_err(|_| StoreError::Flash)?;
        self.flash
            .write(base + HEADER_BYTES as u32, image)
            .map_err(|_| StoreError::Flash)?;
        let mut header = [0u8; HEADER_BYTES];
        let (magic, rest) = header.split_at_mut(4);
        magic.copy_from_slice(&MAGIC);
        let (seq, rest) = rest.split_at_mut(4);
        seq.copy_from_slice(&sequence.to_le_bytes());
        if let Some(t) = rest.get_mut(..8) {
            t.copy_from_slice(&time_s.to_le_bytes());
        }
        self.flash.write(base, &header).map_err(|_| StoreError::Flash)?;
        self.newest = Some((sequence, slot));
        self.saved = self.saved.saturating_add(1);
        self.time_s = Some(time_s);
        Ok(())
    }
}
