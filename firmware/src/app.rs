//! The program on the target: the board, the link, the service loop, the stack painting and the
//! fault handlers, one file each, and the entry point that wires them together, announces `Ready`
//! on the link and runs the loop. Compiled only for the target (`target_os = "none"`).

mod board;
mod fault;
mod link;
mod service;
mod stack;

use cortex_m_rt::entry;
use estimator_core::Estimator;
#[cfg(feature = "checkpoint")]
use firmware::checkpoint_store::{StoreBuffers, CHECKPOINT_INTERVAL_S};
#[cfg(feature = "test-hang")]
use link_protocol::{Numbered, Request};
use link_protocol::{Response, UNNUMBERED};
#[cfg(feature = "checkpoint")]
use static_cell::ConstStaticCell;
use static_cell::StaticCell;

/// The estimator's state: in .bss, uninitialised, and made there in place by
/// `Estimator::init_in`, so that none of it passes through the stack.
static ESTIMATOR: StaticCell<Estimator> = StaticCell::new();

/// The checkpoint store's buffers (an image and the log's item), off the stack.
#[cfg(feature = "checkpoint")]
static STORE_BUFFERS: ConstStaticCell<StoreBuffers> = ConstStaticCell::new(StoreBuffers::new());

/// The watchdog test's build (feature `test-hang`): the main loop stops for good, as a firmware
/// bug would stop it (here: waiting for an event that never comes); interrupts go on, the watchdog
/// is no longer fed and must reset the chip.
#[cfg(feature = "test-hang")]
fn hang() -> ! {
    defmt::warn!("Hang received: the main loop stops (test build); the watchdog must reset");
    loop {
        cortex_m::asm::wfi();
    }
}

#[entry]
fn main() -> ! {
    stack::paint();
    let Some(board) = board::Board::init() else {
        defmt::error!("board already initialised");
        board::fatal()
    };
    // `main` runs once: the cells are taken here for the first and only time.
    let Some(slot) = ESTIMATOR.try_uninit() else {
        defmt::error!("estimator already taken");
        board::fatal()
    };
    let Ok(estimator) = Estimator::init_in(slot, firmware::estimator_config::config()) else {
        defmt::error!("the build's configuration rejected by the core");
        board::fatal()
    };
    // The checkpoint store on the board's flash, and the newest checkpoint restored from it.
    #[cfg(feature = "checkpoint")]
    let Some(buffers) = STORE_BUFFERS.try_take() else {
        defmt::error!("checkpoint buffers already taken");
        board::fatal()
    };
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
    serve(&mut link, &mut service)
}

/// The service loop: one request in, one answer out, for ever; a bad frame is counted and
/// answered by nothing. Inlined into `main`, whose frame lives for ever.
#[inline(always)]
fn serve<W: firmware::watchdog::Watchdog>(
    link: &mut link::Link<W>,
    service: &mut service::Service<'_>,
) -> ! {
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
