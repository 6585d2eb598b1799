//! Panics and hard faults: log what happened (defmt), then [`super::board::fatal`] (exit under
//! QEMU, reset on a board). Nothing that arrives on the link is meant to get here: the receive,
//! decode, step and reply path has no unwrap, expect or indexing (denied by clippy in `main.rs`).

use core::panic::PanicInfo;
use cortex_m_rt::{exception, ExceptionFrame};

use super::board;

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    match info.location() {
        Some(l) => defmt::error!("panic at {=str}:{=u32}", l.file(), l.line()),
        None => defmt::error!("panic"),
    }
    board::fatal()
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    defmt::error!(
        "hard fault: pc {=u32:#010x} lr {=u32:#010x}",
        frame.pc(),
        frame.lr()
    );
    board::fatal()
}
