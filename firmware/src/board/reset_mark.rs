//! Why the last reset happened, when only the firmware itself can know (a watchdog about to reset
//! the chip, a clock failure it reset for): a word pair in RAM that no start-up code touches
//! (cortex-m-rt's `.uninit` section: neither zeroed nor initialised, and below the painted
//! stack), written just before the reset and read once at the next boot. A magic number tells a
//! real mark from power-on garbage.

use core::mem::MaybeUninit;
use core::ptr::{addr_of_mut, read_volatile, write_volatile};

use link_protocol::ResetCause;

const MAGIC: u32 = 0x5249_4E53; // "RINS"

#[link_section = ".uninit.RINS_RESET_MARK"]
static mut MARK: MaybeUninit<[u32; 2]> = MaybeUninit::uninit();

/// Leaves `cause` for the next boot.
pub fn set(cause: ResetCause) {
    // SAFETY: plain words in RAM; an interrupt handler about to reset is the only other writer.
    unsafe { write_volatile(addr_of_mut!(MARK).cast::<[u32; 2]>(), [MAGIC, cause as u32]) };
}

/// The cause left by the previous run, if it left one; clears it.
pub fn take() -> Option<ResetCause> {
    // SAFETY: any bit pattern is a valid pair of words (read as integers, checked below).
    let [magic, code] = unsafe { read_volatile(addr_of_mut!(MARK).cast::<[u32; 2]>()) };
    // SAFETY: as above.
    unsafe { write_volatile(addr_of_mut!(MARK).cast::<[u32; 2]>(), [0, 0]) };
    if magic != MAGIC {
        return None;
    }
    u8::try_from(code)
        .ok()
        .and_then(|c| ResetCause::try_from(c).ok())
}
