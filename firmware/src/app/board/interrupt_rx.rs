//! The receive ring filled by a UART's receive interrupt handler, shared by the boards that
//! receive that way (mps2-an386; the STM32F405 under QEMU): the ring and its counters are statics,
//! the handler's end is kept here for the handler ([`push`]), the main loop's end is the
//! [`RingReceiver`] that [`init`] returns.

use core::cell::RefCell;

use cortex_m::interrupt::Mutex;
use static_cell::ConstStaticCell;

use firmware::interrupt_ring::{InterruptRing, RingReader, RingWriter};
use firmware::rx_stats::{LineErrors, RxStats};
use firmware::{Received, INTERRUPT_RX_RING_ENTRIES};
use link_protocol::LinkCounters;

static STATS: RxStats = RxStats::new();
/// The ring, taken once by [`init`].
static RING: ConstStaticCell<InterruptRing<INTERRUPT_RX_RING_ENTRIES>> =
    ConstStaticCell::new(InterruptRing::new());
/// The handler's end of the ring; `None` until [`init`].
static WRITER: Mutex<RefCell<Option<RingWriter<'static>>>> = Mutex::new(RefCell::new(None));

/// Splits the ring: its writer for the receive interrupt handler, its reader returned. Call once,
/// before the receive interrupt is enabled (returns `None` if called again).
pub fn init() -> Option<RingReceiver> {
    let ring = RING.try_take()?;
    let (writer, reader) = ring.split(&STATS);
    cortex_m::interrupt::free(|cs| WRITER.borrow(cs).replace(Some(writer)));
    Some(RingReceiver { reader })
}

/// One received byte and its errors, from the receive interrupt handler (the ring's one
/// producer); dropped before [`init`].
pub fn push(byte: u8, errors: LineErrors) {
    cortex_m::interrupt::free(|cs| {
        if let Ok(mut writer) = WRITER.borrow(cs).try_borrow_mut() {
            if let Some(writer) = writer.as_mut() {
                writer.push(byte, errors);
            }
        }
    });
}

/// The main loop's end of the receive ring.
pub struct RingReceiver {
    reader: RingReader<'static>,
}

impl RingReceiver {
    /// The next received item, if any (never blocks).
    pub fn next(&mut self) -> Option<Received> {
        self.reader.next()
    }

    /// Sleeps (WFI) until an interrupt: a byte, or SysTick's tick. Interrupts are masked between
    /// the check for a waiting byte and the WFI, so a byte that arrives in between wakes it.
    pub fn wait(&mut self) {
        cortex_m::interrupt::disable();
        if self.reader.is_empty() {
            cortex_m::asm::wfi();
        }
        // SAFETY: re-enables what was enabled before; the firmware runs with interrupts on.
        unsafe { cortex_m::interrupt::enable() };
    }

    /// The receive path's counters; `lost_frames` from the link's sequence numbers.
    pub fn counters(&self, lost_frames: u32) -> LinkCounters {
        STATS.snapshot(
            InterruptRing::<INTERRUPT_RX_RING_ENTRIES>::CAPACITY,
            lost_frames,
        )
    }
}
