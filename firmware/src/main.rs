//! RINS installation-error estimator firmware (Cortex-M4F).
//!
//! Thin layers, one file each:
//! - [`board`]: the hardware (UART as `embedded_io`, the cost counter, logging, fatal exit), one
//!   module per board, chosen by a cargo feature (`board-mps2-an386`, `board-stm32f405`);
//! - [`link`]: frames in and out (the codec itself is the `link-protocol` crate);
//! - [`service`]: request in, `estimator-core` step, response out, checkpoints when due;
//! - [`stack`]: stack painting for the high-water mark; [`fault`]: panic and hard-fault handlers.
//!
//! The checkpoint store itself is hardware-free and lives in the crate's library
//! (`firmware::checkpoint_store`, tested on the host).
//!
//! This file wires them together, announces `Ready` on the link and runs the loop. The protocol is
//! in docs/link-protocol.md.
//!
//! Built for any other target (as `cargo test --workspace` does on the host), the crate is an
//! empty program that says where it runs; nothing of the firmware is compiled.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
mod fault;
#[cfg(target_os = "none")]
mod link;
#[cfg(target_os = "none")]
mod service;
#[cfg(target_os = "none")]
mod stack;

#[cfg(target_os = "none")]
use core::mem::MaybeUninit;
#[cfg(target_os = "none")]
use cortex_m_rt::entry;
#[cfg(target_os = "none")]
use estimator_core::Estimator;
#[cfg(all(target_os = "none", feature = "checkpoint"))]
use firmware::checkpoint_store::{StoreBuffers, CHECKPOINT_INTERVAL_S};
#[cfg(all(target_os = "none", feature = "test-hang"))]
use link_protocol::{Numbered, Request};
#[cfg(target_os = "none")]
use link_protocol::{Response, UNNUMBERED};

/// The watchdog test's build (feature `test-hang`): the main loop stops for good, as a firmware
/// bug would stop it (here: waiting for an event that never comes); interrupts go on, the watchdog
/// is no longer fed and must reset the chip.
#[cfg(all(target_os = "none", feature = "test-hang"))]
fn hang() -> ! {
    defmt::warn!("Hang received: the main loop stops (test build); the watchdog must reset");
    loop {
        cortex_m::asm::wfi();
    }
}

/// On the host: the firmware is not built; say how to build it.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("the firmware runs on thumbv7em-none-eabihf: cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware");
    std::process::exit(2);
}

#[cfg(target_os = "none")]
#[entry]
fn main() -> ! {
    stack::paint();
    let Some(board) = board::Board::init() else {
        defmt::error!("board already initialised");
        board::fatal()
    };
    // The estimator's state lives in .bss (uninitialised) and is made there, in place: nothing of
    // its 23.6 KB passes through the stack.
    static mut ESTIMATOR: MaybeUninit<Estimator> = MaybeUninit::uninit();
    // SAFETY: `main` runs once and is the only code that names ESTIMATOR.
    let slot = unsafe { &mut *core::ptr::addr_of_mut!(ESTIMATOR) };
    let Ok(estimator) = Estimator::init_in(slot, firmware::estimator_config::config()) else {
        defmt::error!("the build's configuration rejected by the core");
        board::fatal()
    };
    // The checkpoint store on the board's flash, and the newest checkpoint restored from it. Its
    // buffers (an image and the log's item) are a static too, off the stack.
    #[cfg(feature = "checkpoint")]
    static mut STORE_BUFFERS: StoreBuffers = StoreBuffers::new();
    #[cfg(feature = "checkpoint")]
    // SAFETY: `main` runs once and is the only code that names STORE_BUFFERS.
    let buffers = unsafe { &mut *core::ptr::addr_of_mut!(STORE_BUFFERS) };
    #[cfg(feature = "checkpoint")]
    let watchdog = board.watchdog;
    #[cfg(feature = "checkpoint")]
    let persistence = board.flash.and_then(|flash| {
        // The store feeds the watchdog before every erase block and write (`FedFlash`).
        service::Persistence::open(
            firmware::watchdog::FedFlash::new(flash, watchdog),
            buffers,
            estimator,
        )
    });
    #[cfg(feature = "checkpoint")]
    defmt::info!(
        "checkpoint every {=u32} s of sample time",
        CHECKPOINT_INTERVAL_S
    );
    #[cfg(not(feature = "checkpoint"))]
    let persistence = None;
    let boot_stack_peak_bytes = stack::peak_bytes();
    // Paint again: from here on the high-water mark is the service loop's own.
    stack::paint();
    defmt::info!(
        "estimator firmware up: protocol {=u8}, estimator state {=usize} bytes, stack {=u32} bytes, {=u32} used by the start-up",
        link_protocol::PROTOCOL_VERSION,
        core::mem::size_of::<Estimator>(),
        stack::size_bytes(),
        boot_stack_peak_bytes
    );
    let mut link = link::Link::new(board.tx, board.rx, board.watchdog);
    // The host sends nothing before this: a serial port drops bytes that arrive before it is
    // enabled (QEMU's STM32 USART does), and the start-up above can take a while.
    if !link.send(
        UNNUMBERED,
        &Response::Ready {
            protocol_version: link_protocol::PROTOCOL_VERSION,
        },
    ) {
        defmt::error!("Ready could not be sent");
    }
    let mut service = service::Service::new(
        estimator,
        board.cost,
        boot_stack_peak_bytes,
        persistence,
        board.reset_cause,
        board.clock_source,
    );
    loop {
        match link.receive() {
            #[cfg(feature = "test-hang")]
            Ok(Numbered {
                message: Request::Hang,
                ..
            }) => hang(),
            Ok(request) => {
                if let Some(response) = service.handle(&request.message, link.counters()) {
                    if !link.send(request.seq, &response) {
                        defmt::error!("response could not be sent");
                    }
                }
            }
            Err(error) => {
                service.count_bad_frame(error);
                defmt::warn!("bad frame: {}", error);
            }
        }
    }
}
