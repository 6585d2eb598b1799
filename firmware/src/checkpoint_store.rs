//! The estimator's checkpoints on the board's flash, and when to save one.
//!
//! # The store
//! A key-value log of the `sequential-storage` crate ([`MapStorage`]) over every sector the board
//! gives it ([`crate::flash_layout`]), with one key: each save appends one item, the learned
//! errors' record ([`estimator_core::learned`], 52 bytes, a layout every later version reads)
//! followed by the core's checkpoint image ([`Estimator::checkpoint`], 900 bytes with its own
//! magic, version and CRC-32), and a restore reads the newest. A build that refuses the image
//! (another format version: a software update) starts from the record instead
//! ([`Restored::Learned`]), so that compensation goes on across the update; an item without a
//! record (an older build's) is the image alone. Pages (sectors) are used in turn: a sector is erased only when the
//! log has gone round to it, so every sector is erased once per `sectors x items a sector holds`
//! saves (wear levelling), and a save that does not open a new sector only programs (no erase).
//!
//! Power-fail safety is the crate's design: an item carries a CRC of its header and one of its
//! data, and is valid only once both are written; a page's state is in its first and last word;
//! an operation that finds a torn item or page repairs the log before it goes on. The crate
//! assumes that an interrupted erase leaves a sector erased from its start up to some byte; a
//! real sector erase is one operation on the whole sector, and a cut leaves its bytes in no such
//! order (ST's EEPROM-emulation note for the STM32F4, AN3969, re-erases at start-up any page whose
//! header says erased but whose content is not). So [`CheckpointStore::new`] does the same before
//! the crate sees the flash ([`re_erase_torn_sectors`]). A cut at any point of a save therefore
//! leaves the newest complete image, or the one before it (tested at every erase and every
//! programmed unit by `host-sim/tests/replay/store_power_fail.rs`, on a model of the flash that tears the
//! operation the cut lands in, bits and bytes at random). The core checks every restored image
//! again (its CRC and every value), so a torn or foreign image is refused, never half-restored.
//!
//! [`CheckpointStore::invalidate`] (the host's `Reset`) appends an empty item: the newest value is
//! then "nothing", which a restore reports as [`Restored::Forgotten`], so that no later power cut
//! can bring the forgotten state back; it costs a small write, not an erase of the region.
//!
//! # When to save
//! [`SaveSchedule`]: every `interval_s` of sample time (300 s by default, `RINS_CHECKPOINT_INTERVAL_S`
//! at build time), counted from the first sample after boot, and at once after the time stamps jump
//! by more than the interval either way (a clock step back must not stop the saves). A power cut
//! then costs the filter updates since the last save and one period of updates while the window
//! refills (docs/firmware.md measures what that is worth).

use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_futures::block_on;
use embedded_storage::nor_flash::NorFlash;
use estimator_core::checkpoint::{CheckpointError, CHECKPOINT_LEN};
use estimator_core::learned::{LearnedErrors, LEARNED_LEN, LEARNED_MAGIC};
use estimator_core::Estimator;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

// `CHECKPOINT_INTERVAL_S`: 300 s, or `RINS_CHECKPOINT_INTERVAL_S` when the firmware was built
// (checked and written by build.rs).
include!(concat!(env!("OUT_DIR"), "/checkpoint_interval.rs"));

/// The map's one key.
const CHECKPOINT_KEY: u8 = 0;

/// Bytes of an item: the learned errors' record and the checkpoint image.
pub const ITEM_BYTES: usize = LEARNED_LEN + CHECKPOINT_LEN;

/// Bytes of the store's working buffer: the key and an item, rounded up to the largest flash
/// word `sequential-storage` supports (32 bytes).
pub const BUFFER_BYTES: usize = (1 + ITEM_BYTES).div_ceil(32) * 32;

/// The log's cache: none (every operation reads the page states from flash; the region is small
/// and memory-mapped, so a save spends well under a millisecond reading).
type NoCache = Cache<Uncached, Uncached, Uncached, u8>;

/// Why the store could not save, restore or invalidate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum StoreError {
    /// The region is not whole sectors, or fewer than two.
    Region,
    /// The flash refused a read, an erase or a write.
    Flash,
    /// The log is damaged beyond what its repair can mend (the next save erases and goes on).
    Corrupted,
    /// The log is full: cannot happen with one key and at least two sectors.
    Full,
    /// `sequential-storage` reported a fault of its own logic or a buffer it could not use.
    Storage,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            StoreError::Region => "the checkpoint region is not at least two whole sectors",
            StoreError::Flash => "the flash refused a read, an erase or a write",
            StoreError::Corrupted => "the checkpoint log is corrupted beyond repair",
            StoreError::Full => "the checkpoint log is full",
            StoreError::Storage => "the checkpoint log reported an internal fault",
        })
    }
}

impl core::error::Error for StoreError {}

impl<E> From<sequential_storage::Error<E>> for StoreError {
    fn from(e: sequential_storage::Error<E>) -> Self {
        match e {
            sequential_storage::Error::Storage { .. } => StoreError::Flash,
            sequential_storage::Error::Corrupted { .. } => StoreError::Corrupted,
            sequential_storage::Error::FullStorage => StoreError::Full,
            _ => StoreError::Storage,
        }
    }
}

/// What a restore found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Restored {
    /// No checkpoint was ever saved (or the flash was erased).
    Nothing,
    /// The newest entry is an invalidation (a `Reset`): nothing to restore.
    Forgotten,
    /// The newest image, restored; the time of its last sample (`None` before any sample).
    Image {
        /// The time of the image's last sample, s (`None` before any sample).
        time_s: Option<f64>,
    },
    /// The newest image was refused by the core (another format version, a foreign image); the
    /// estimator is unchanged, and the next save replaces the image.
    Refused(CheckpointError),
    /// The newest image is of another format version (another build wrote it), and the estimator
    /// started from the learned errors saved with it ([`Estimator::start_from_learned`]): it
    /// reports them, and compensates with them, from the first sample. The time of the record's
    /// last sample and the version the image was refused for.
    Learned {
        /// The time of the record's last sample, s.
        time_s: f64,
        /// Why the core refused the image saved with the record.
        refused: CheckpointError,
    },
}

/// The store's working memory, which the caller provides (a static in the firmware, so that
/// neither buffer is on the stack): the log's item buffer and the image being saved.
pub struct StoreBuffers {
    item: [u8; BUFFER_BYTES],
    image: [u8; ITEM_BYTES],
}

impl StoreBuffers {
    /// Zeroed buffers (in a static: in .bss, no flash).
    pub const fn new() -> Self {
        StoreBuffers {
            item: [0; BUFFER_BYTES],
            image: [0; ITEM_BYTES],
        }
    }
}

impl Default for StoreBuffers {
    fn default() -> Self {
        Self::new()
    }
}

/// The checkpoint log on a flash `F` (the region is the whole of `F`), working in `buffers`.
pub struct CheckpointStore<'b, F: NorFlash> {
    map: MapStorage<u8, BlockingAsync<F>, NoCache>,
    buffers: &'b mut StoreBuffers,
    /// Images written since boot.
    saved: u32,
    /// Time of the last sample of the newest image saved or restored.
    time_s: Option<f64>,
    /// Sectors [`re_erase_torn_sectors`] erased again when the store was made.
    re_erased: u32,
}

impl<'b, F: NorFlash> CheckpointStore<'b, F> {
    /// The store over all of `flash`, or [`StoreError::Region`] if it is not at least two whole
    /// sectors. Sectors a cut erase left torn are erased again first (see
    /// [`re_erase_torn_sectors`]).
    pub fn new(mut flash: F, buffers: &'b mut StoreBuffers) -> Result<Self, StoreError> {
        let end = u32::try_from(flash.capacity()).map_err(|_| StoreError::Region)?;
        let config =
            MapConfig::<BlockingAsync<F>>::try_new(0..end).map_err(|_| StoreError::Region)?;
        let re_erased = re_erase_torn_sectors(&mut flash)?;
        Ok(CheckpointStore {
            map: MapStorage::new(BlockingAsync::new(flash), config, Cache::new_uncached()),
            buffers,
            saved: 0,
            time_s: None,
            re_erased,
        })
    }

    /// Sectors erased again when the store was made, because a power cut had torn their erase.
    pub fn re_erased(&self) -> u32 {
        self.re_erased
    }

    /// Images saved since boot.
    pub fn saved(&self) -> u32 {
        self.saved
    }

    /// Time of the last sample of the newest image saved or restored, s.
    pub fn time_s(&self) -> Option<f64> {
        self.time_s
    }

    /// Restores the newest image into `estimator` (see [`Restored`]); on anything but
    /// [`Restored::Image`] the estimator is unchanged.
    pub fn restore<const CAP: usize>(
        &mut self,
        estimator: &mut Estimator<CAP>,
    ) -> Result<Restored, StoreError> {
        let found = block_on(
            self.map
                .fetch_item::<&[u8]>(&mut self.buffers.item, &CHECKPOINT_KEY),
        )?;
        let restored = match found {
            None => Restored::Nothing,
            Some([]) => Restored::Forgotten,
            Some(item) => restore_item(estimator, item),
        };
        self.time_s = match restored {
            Restored::Image { time_s } => time_s,
            _ => None,
        };
        Ok(restored)
    }

    /// Appends the estimator's learned errors and image to the log (the record only while there is
    /// an estimate; an item without one is the image alone).
    pub fn save<const CAP: usize>(&mut self, estimator: &Estimator<CAP>) -> Result<(), StoreError> {
        let StoreBuffers { item, image } = &mut *self.buffers;
        // The record in front (when there is an estimate), the image after it: `image` holds
        // both (`ITEM_BYTES`).
        let (record, rest) = image.split_at_mut(LEARNED_LEN);
        let written = match estimator.learned_errors() {
            Some(learned) => {
                record.copy_from_slice(&learned.encode());
                LEARNED_LEN
                    + estimator
                        .checkpoint(rest)
                        .map_err(|_| StoreError::Storage)?
            }
            None => estimator
                .checkpoint(image)
                .map_err(|_| StoreError::Storage)?,
        };
        let saved = image.get(..written).ok_or(StoreError::Storage)?;
        block_on(self.map.store_item::<&[u8]>(item, &CHECKPOINT_KEY, &saved))?;
        self.saved = self.saved.saturating_add(1);
        self.time_s = estimator.last_sample_time_s();
        Ok(())
    }

    /// Appends `item` as it stands: a learned-errors record and an image of any build, or an image
    /// alone ([`restore_item`] reads either). [`CheckpointStore::save`] builds the item from an
    /// estimator; a tool that moves a store from one build to another, or a test that plays
    /// another build, writes one directly. At most [`ITEM_BYTES`] bytes.
    pub fn save_item(&mut self, item: &[u8]) -> Result<(), StoreError> {
        let image = self
            .buffers
            .image
            .get_mut(..item.len())
            .ok_or(StoreError::Storage)?;
        image.copy_from_slice(item);
        let StoreBuffers {
            item: buffer,
            image,
        } = &mut *self.buffers;
        let saved = image.get(..item.len()).ok_or(StoreError::Storage)?;
        block_on(
            self.map
                .store_item::<&[u8]>(buffer, &CHECKPOINT_KEY, &saved),
        )?;
        self.saved = self.saved.saturating_add(1);
        Ok(())
    }

    /// Appends an invalidation: once it returns, no image is left to restore, whatever power cut
    /// follows. On a flash error the older image may still be restored.
    pub fn invalidate(&mut self) -> Result<(), StoreError> {
        block_on(
            self.map
                .store_item::<&[u8]>(&mut self.buffers.item, &CHECKPOINT_KEY, &&[][..]),
        )?;
        self.time_s = None;
        Ok(())
    }
}

/// What an item of the log restores into `estimator`: the item is the learned errors' record (of
/// any layout version) followed by a checkpoint image, or an image alone (an older build's). The
/// image restored, [`Restored::Image`]; refused as another build's (another format version, float
/// width or image length, a method this build lacks) with a record beside it, the estimator
/// started from the record, [`Restored::Learned`]; otherwise [`Restored::Refused`], the estimator
/// unchanged.
pub fn restore_item<const CAP: usize>(estimator: &mut Estimator<CAP>, item: &[u8]) -> Restored {
    // The record first (any version's layout), the image after it; an item that does
    // not start with a record is an image alone.
    let learned = item
        .starts_with(&LEARNED_MAGIC)
        .then(|| LearnedErrors::decode(item).ok())
        .flatten();
    let image = match learned {
        Some((_, len)) => item.get(len..).unwrap_or(&[]),
        None => item,
    };
    match (estimator.restore(image), learned) {
        (Ok(()), _) => Restored::Image {
            time_s: estimator.last_sample_time_s(),
        },
        (
            Err(
                refused @ (CheckpointError::Version { .. }
                | CheckpointError::RealWidthMismatch(_)
                | CheckpointError::LengthMismatch { .. }
                | CheckpointError::UnknownMethod(_)),
            ),
            Some((record, _)),
        ) if estimator.start_from_learned(&record).is_ok() => Restored::Learned {
            time_s: record.time_s,
            refused,
        },
        (Err(e), _) => Restored::Refused(e),
    }
}

/// Whether a page-state byte of `sequential-storage` is marked: at least half its bits cleared
/// (the crate's own rule, which tolerates a stray bit flip).
fn marked(byte: u8) -> bool {
    byte.count_zeros() >= 4
}

/// Erases again the sectors a power cut left half-erased, and returns how many. The log keeps a
/// sector's state in its first and last byte (marked: at least four of its bits programmed): both unmarked is an erased ("open")
/// sector, first marked and last unmarked the one being filled ("partial"). The log erases a
/// sector only just after it has marked the sector before it partial, so a torn erase shows as
/// - an "open" sector with any byte not erased: erased again (whatever else it holds is a torn
///   remnant of data the log had given up);
/// - a "partial" sector right after another "partial" one: the later is the torn one (the log
///   has one partial sector, and the one it was erasing follows it), erased again.
///
/// Any other damage (a sector whose last byte is marked) is the crate's to repair. Reads the whole
/// region (memory-mapped on the STM32F405: about a millisecond a sector), at start-up only.
pub fn re_erase_torn_sectors<F: NorFlash>(flash: &mut F) -> Result<u32, StoreError> {
    let sector = F::ERASE_SIZE;
    let sectors = flash.capacity() / sector.max(1);
    // Whether the sector before (and the first) is a "partial" one, once checked.
    let mut previous_partial = false;
    let mut first_partial = false;
    let mut re_erased = 0;
    let mut edge = [0u8; 1];
    for i in 0..sectors {
        let base = (i * sector) as u32;
        flash.read(base, &mut edge).map_err(|_| StoreError::Flash)?;
        let first = marked(edge[0]);
        flash
            .read(base + sector as u32 - 1, &mut edge)
            .map_err(|_| StoreError::Flash)?;
        let last = marked(edge[0]);
        let is_partial = first && !last;
        let torn = match (first, last) {
            (false, false) => !erased(flash, base, sector)?,
            (true, false) => previous_partial,
            _ => false,
        };
        if i == 0 {
            first_partial = is_partial;
        }
        if torn {
            flash
                .erase(base, base + sector as u32)
                .map_err(|_| StoreError::Flash)?;
            re_erased += 1;
        }
        previous_partial = is_partial && !torn;
    }
    // The sectors are used in a ring: the first follows the last.
    if sectors > 1 && first_partial && previous_partial {
        flash
            .erase(0, sector as u32)
            .map_err(|_| StoreError::Flash)?;
        re_erased += 1;
    }
    Ok(re_erased)
}

/// Whether the sector at `base` reads as erased throughout.
fn erased<F: NorFlash>(flash: &mut F, base: u32, sector: usize) -> Result<bool, StoreError> {
    let mut chunk = [0u8; 256];
    let mut at = 0;
    while at < sector {
        let n = chunk.len().min(sector - at);
        let part = chunk.get_mut(..n).ok_or(StoreError::Region)?;
        flash
            .read(base + at as u32, part)
            .map_err(|_| StoreError::Flash)?;
        if part.iter().any(|b| *b != 0xFF) {
            return Ok(false);
        }
        at += n;
    }
    Ok(true)
}

/// When the next checkpoint is due, from the samples' time stamps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SaveSchedule {
    interval_s: f64,
    /// Time of the last save, or of the first sample before any.
    last_s: Option<f64>,
}

impl SaveSchedule {
    /// A save every `interval_s` of sample time, the first `interval_s` after `last_saved_s` (the
    /// restored checkpoint's last sample), or after the first sample if `None`.
    pub const fn new(interval_s: f64, last_saved_s: Option<f64>) -> Self {
        SaveSchedule {
            interval_s,
            last_s: last_saved_s,
        }
    }

    /// Whether a checkpoint is due after the sample at `time_s` (and if so, counts it as saved):
    /// `interval_s` after the last save, or after the first sample seen; at once when the stamps
    /// jumped by more than the interval, forwards or back.
    pub fn due(&mut self, time_s: f64) -> bool {
        // Due unless the time since the last save is known to be shorter than the interval (a
        // NaN, which the core never gives, counts as due rather than never again).
        let due = match self.last_s {
            None => false,
            Some(last) => {
                (time_s - last).abs().partial_cmp(&self.interval_s)
                    != Some(core::cmp::Ordering::Less)
            }
        };
        if due || self.last_s.is_none() {
            self.last_s = Some(time_s);
        }
        due
    }

    /// Starts counting again from the next sample (after a `Reset`).
    pub fn restart(&mut self) {
        self.last_s = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saves_every_interval_and_after_any_jump_of_the_clock() {
        let mut s = SaveSchedule::new(300.0, None);
        let times = [
            100.0,
            101.0,
            399.0,
            400.0,
            401.0,
            700.0,
            650.0,
            100.0,
            101.0,
            1e9,
            f64::NAN,
            5.0,
        ];
        let due = times.map(|t| s.due(t));
        // 400: 300 s after the first sample; 700: 300 s after that; 100: 600 s back; 1e9: forwards;
        // NaN (never given by the core, which rejects it) and the sample after it: saved, rather
        // than never again.
        let expected = [
            false, false, false, true, false, true, false, true, false, true, true, true,
        ];
        assert_eq!(due, expected);
        s.restart();
        assert!(!s.due(1e9 + 5.0), "after a restart the count starts again");
        assert!(s.due(1e9 + 305.0));
        // After a restore: 300 s after the checkpoint's last sample, however late the first
        // sample after boot comes.
        let mut s = SaveSchedule::new(300.0, Some(1000.0));
        assert_eq!(
            [1200.0, 1299.0, 1300.0, 1400.0].map(|t| s.due(t)),
            [false, false, true, false]
        );
        let mut s = SaveSchedule::new(300.0, Some(1000.0));
        assert!(
            s.due(1500.0),
            "an outage longer than the interval: a save with the first sample"
        );
    }
}
