//! Why the last reset happened, when only the firmware itself can know (a watchdog about to reset
//! the chip, a clock failure it reset for): a word pair in RAM that no start-up code touches
//! (cortex-m-rt's `.uninit` section: neither zeroed nor initialised, and below the painted
//! stack), written just before the reset and read once at the next boot. A magic number tells a
//! real mark from power-on garbage.

use core::sync::atomic::{AtomicU32, Ordering};

use link_protocol::ResetCause;

const MAGIC: u32 = 0x5249_4E53; // "RINS"

/// The magic word and the cause's code. The initialiser is never loaded (`.uninit` is a NOLOAD
/// section): at boot the words hold what the previous run left, or power-on garbage; any bit
/// pattern is a valid word.
#[link_section = ".uninit.RINS_RESET_MARK"]
static MARK: [AtomicU32; 2] = [AtomicU32::new(0), AtomicU32::new(0)];

/// Leaves `cause` for the next boot.
pub fn set(cause: ResetCause) {
    MARK[1].store(cause as u32, Ordering::SeqCst);
    MARK[0].store(MAGIC, Ordering::SeqCst);
}

/// The cause left by the previous run, if it left one; clears it.
pub fn take() -> Option<ResetCause> {
    let magic = MARK[0].swap(0, Ordering::SeqCst);
    let code = MARK[1].swap(0, Ordering::SeqCst);
    if magic != MAGIC {
        return None;
    }
    u8::try_from(code)
        .ok()
        .and_then(|c| ResetCause::try_from(c).ok())
}
