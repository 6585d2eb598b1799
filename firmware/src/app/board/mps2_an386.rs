//! ARM MPS2+ AN386 (Cortex-M4F, 25 MHz) as QEMU emulates it (`-machine mps2-an386`).
//!
//! - UART0: CMSDK APB UART at 0x4000_4000, 115200 baud from the 25 MHz peripheral clock.
//!   Receive: the RX interrupt (IRQ 0) moves each byte into the receive ring (`interrupt_rx.rs`)
//!   as it arrives, whatever the main loop is doing. Transmit: interrupt-driven too (IRQ 1, raised
//!   when the one-byte transmit buffer empties): `write` queues the bytes and returns; the handler
//!   feeds them to the UART. The UART's RX overrun flag is counted (QEMU holds input back while a
//!   byte waits, so it never overruns there).
//! - Watchdog: the CMSDK APB watchdog at 0x4000_8000 (WDOGCLK 25 MHz), which QEMU models: its
//!   interrupt (the NMI on this board) after [`WATCHDOG_TIMEOUT_CYCLES`] unfed, the reset after as
//!   many again. The NMI leaves the cause for the next boot (`reset_mark.rs`).
//! - Cost counter: SysTick on the core clock, free-running over 24 bits; its wrap interrupt wakes
//!   the main loop every 0.67 s so that it feeds the watchdog while no byte arrives. Under QEMU
//!   with `-icount shift=0` one tick is exactly 40 instructions.
//! - Logs: defmt over semihosting (QEMU's stdout). Fatal errors: semihosting exit with status 1.
//! - Flash for checkpoints: the host file `rins-flash.bin` in QEMU's working directory
//!   ([`Flash`], `semihosted_flash.rs`), laid out as `firmware::flash_layout::MPS2_AN386` (64
//!   sectors of 4 KiB), each 256-byte page written in the STM32F405's time (4.1 ms of core clock).
//!
//! Interrupts are dispatched by number from cortex-m-rt's `DefaultHandler` (this board has no
//! peripheral access crate, so no vector table of named handlers).

use core::cell::RefCell;
use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};

use cortex_m::interrupt::Mutex;
use cortex_m_rt::exception;
use defmt_semihosting as _;
use firmware::rx_stats::LineErrors;
use firmware::watchdog::Watchdog;
use heapless::spsc::{Consumer, Producer, Queue};
use link_protocol::{ClockSource, ResetCause};
use static_cell::ConstStaticCell;

pub use super::interrupt_rx::RingReceiver as Receiver;
pub use super::systick_cost::CostCounter;

/// The checkpoint flash: the semihosted file, as big as the board's checkpoint region.
pub type Flash = super::semihosted_flash::SemihostedFlash<
    { firmware::flash_layout::MPS2_AN386.region_bytes() as usize },
>;

/// Core (and SysTick) clock, Hz.
pub const CORE_CLOCK_HZ: u32 = 25_000_000;
const UART_CLOCK_HZ: u32 = 25_000_000;
const BAUD: u32 = 115_200;

const UART0_BASE: usize = 0x4000_4000;
const UART_DATA: usize = 0x00;
const UART_STATE: usize = 0x04;
const UART_CTRL: usize = 0x08;
const UART_INTSTATUS: usize = 0x0C;
const UART_BAUDDIV: usize = 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_RX_OVERRUN: u32 = 1 << 3;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_TX_INT_EN: u32 = 1 << 2;
const CTRL_RX_INT_EN: u32 = 1 << 3;
const INTSTATUS_TX: u32 = 1 << 0;
const INTSTATUS_RX: u32 = 1 << 1;
/// UART0's interrupts on this board (QEMU hw/arm/mps2.c: RX = IRQ 0, TX = IRQ 1).
const UART0_RX_IRQ: i16 = 0;
const UART0_TX_IRQ: i16 = 1;

const WATCHDOG_BASE: usize = 0x4000_8000;
const WDOG_LOAD: usize = 0x000;
const WDOG_CONTROL: usize = 0x008;
const WDOG_INTCLR: usize = 0x00C;
const WDOG_LOCK: usize = 0xC00;
const WDOG_UNLOCK_KEY: u32 = 0x1ACC_E551;
const WDOG_CONTROL_INTEN: u32 = 1 << 0;
const WDOG_CONTROL_RESEN: u32 = 1 << 1;
/// Cycles of WDOGCLK (25 MHz) from a feed to the watchdog's interrupt, and again to the reset:
/// 1 s and 2 s. The main loop feeds at least every 0.67 s (SysTick's wrap), and the longest thing
/// it does here (a checkpoint into the host file) takes a few ms of core clock.
pub const WATCHDOG_TIMEOUT_CYCLES: u32 = 25_000_000;

/// Bytes queued for transmission (more than the longest frame, 182 bytes).
const TX_QUEUE_ENTRIES: usize = 256;

/// The board's parts.
pub struct Board {
    pub tx: Transmitter,
    pub rx: Receiver,
    pub cost: CostCounter,
    /// Non-volatile storage for checkpoints; `None` without the `checkpoint` feature or if the
    /// host file cannot be opened.
    #[cfg_attr(not(feature = "checkpoint"), allow(dead_code))]
    pub flash: Option<Flash>,
    pub watchdog: BoardWatchdog,
    pub reset_cause: ResetCause,
    pub clock_source: ClockSource,
}

impl Board {
    /// Sets up the UART, its interrupts, the cost counter and the watchdog. Call once.
    pub fn init() -> Option<Board> {
        let peripherals = cortex_m::Peripherals::take()?;
        cortex_m::interrupt::disable();
        let reset_cause = super::reset_mark::take().unwrap_or(ResetCause::PowerOn);
        let rx = super::interrupt_rx::init()?;
        let tx = Transmitter::init()?;
        let watchdog = BoardWatchdog::start();
        // SAFETY: the rings' ends are in place; the handlers below may run from now on.
        unsafe {
            uart_init();
            cortex_m::peripheral::NVIC::unmask(Irq(UART0_RX_IRQ));
            cortex_m::peripheral::NVIC::unmask(Irq(UART0_TX_IRQ));
            cortex_m::interrupt::enable();
        }
        defmt::info!("mps2-an386: reset cause {}", reset_cause);
        Some(Board {
            tx,
            rx,
            cost: CostCounter::init(peripherals.SYST, CORE_CLOCK_HZ, true),
            flash: if cfg!(feature = "checkpoint") {
                Flash::open(CORE_CLOCK_HZ)
            } else {
                None
            },
            watchdog,
            reset_cause,
            clock_source: ClockSource::Fixed,
        })
    }
}

/// An interrupt number for the NVIC.
#[derive(Clone, Copy)]
struct Irq(i16);

// SAFETY: the numbers are this board's interrupt lines.
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0 as u16
    }
}

/// # Safety
/// Once, from `Board::init`.
unsafe fn uart_init() {
    // SAFETY: UART0's registers, set up once here.
    unsafe {
        reg_write(UART_BAUDDIV, UART_CLOCK_HZ / BAUD);
        reg_write(
            UART_CTRL,
            CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN | CTRL_TX_INT_EN,
        );
        reg_write(UART_INTSTATUS, INTSTATUS_TX | INTSTATUS_RX);
        // One dummy read: QEMU wakes its chardev only when DATA is read, so without it the first
        // input byte waits for QEMU's next poll of the socket (docs/firmware.md, "What QEMU
        // proves and what it does not").
        let _ = reg_read(UART_DATA);
    }
}

/// UART0's receive interrupt: every byte waiting goes into the ring. The interrupt is cleared
/// first: a byte that arrives after the last look raises it again.
fn uart_rx_interrupt() {
    // SAFETY: UART0's registers; this handler is the only reader of DATA.
    unsafe {
        reg_write(UART_INTSTATUS, INTSTATUS_RX);
        loop {
            let state = reg_read(UART_STATE);
            if state & STATE_RX_FULL == 0 {
                break;
            }
            let byte = reg_read(UART_DATA) as u8;
            let overrun = state & STATE_RX_OVERRUN != 0;
            if overrun {
                // Write 1 to clear.
                reg_write(UART_STATE, STATE_RX_OVERRUN);
            }
            super::interrupt_rx::push(
                byte,
                LineErrors {
                    overrun,
                    ..LineErrors::default()
                },
            );
        }
    }
}

/// The transmit queue, taken once by `Transmitter::init`.
static TX_QUEUE: ConstStaticCell<Queue<u8, TX_QUEUE_ENTRIES>> = ConstStaticCell::new(Queue::new());
/// The transmit interrupt handler's end of the queue; `None` until `Transmitter::init`.
static TX_CONSUMER: Mutex<RefCell<Option<Consumer<'static, u8>>>> = Mutex::new(RefCell::new(None));

/// UART0's transmit interrupt (the buffer emptied), or pended by [`Transmitter::write`]: the next
/// queued byte goes out.
fn uart_tx_interrupt() {
    // SAFETY: UART0's registers; this handler is the only writer of DATA.
    unsafe { reg_write(UART_INTSTATUS, INTSTATUS_TX) };
    cortex_m::interrupt::free(|cs| {
        let Ok(mut consumer) = TX_CONSUMER.borrow(cs).try_borrow_mut() else {
            return;
        };
        if let Some(queue) = consumer.as_mut() {
            // SAFETY: as above; this handler is the queue's one consumer.
            unsafe {
                if reg_read(UART_STATE) & STATE_TX_FULL == 0 {
                    if let Some(byte) = queue.dequeue() {
                        reg_write(UART_DATA, u32::from(byte));
                    }
                }
            }
        }
    });
}

/// UART0's transmitter: bytes are queued and sent by the transmit interrupt.
pub struct Transmitter {
    queue: Producer<'static, u8>,
}

impl Transmitter {
    fn init() -> Option<Transmitter> {
        let (producer, consumer) = TX_QUEUE.try_take()?.split();
        cortex_m::interrupt::free(|cs| TX_CONSUMER.borrow(cs).replace(Some(consumer)));
        Some(Transmitter { queue: producer })
    }
}

impl embedded_io::ErrorType for Transmitter {
    type Error = Infallible;
}

impl embedded_io::Write for Transmitter {
    /// Queues what fits (at least one byte: waits for room) and starts the transmit interrupt.
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        loop {
            let mut n = 0;
            for &byte in buf {
                if self.queue.enqueue(byte).is_err() {
                    break;
                }
                n += 1;
            }
            cortex_m::peripheral::NVIC::pend(Irq(UART0_TX_IRQ));
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            // Full: the handler is draining it; wait for its next interrupt and try again.
            cortex_m::asm::wfi();
        }
    }

    /// Waits until every queued byte has gone to the UART.
    fn flush(&mut self) -> Result<(), Infallible> {
        while !self.queue.is_empty() {
            cortex_m::peripheral::NVIC::pend(Irq(UART0_TX_IRQ));
            cortex_m::asm::wfi();
        }
        Ok(())
    }
}

/// The CMSDK watchdog (registers locked between accesses).
#[derive(Clone, Copy)]
pub struct BoardWatchdog;

impl BoardWatchdog {
    fn start() -> BoardWatchdog {
        // SAFETY: the watchdog's registers, unlocked for these writes only.
        unsafe {
            wdog_write(WDOG_LOCK, WDOG_UNLOCK_KEY);
            wdog_write(WDOG_LOAD, WATCHDOG_TIMEOUT_CYCLES);
            wdog_write(WDOG_CONTROL, WDOG_CONTROL_INTEN | WDOG_CONTROL_RESEN);
            wdog_write(WDOG_LOCK, 0);
        }
        BoardWatchdog
    }
}

impl Watchdog for BoardWatchdog {
    /// Clears the interrupt and reloads the counter.
    fn feed(&self) {
        // SAFETY: as in `start`; a write to INTCLR has no other effect.
        unsafe {
            wdog_write(WDOG_LOCK, WDOG_UNLOCK_KEY);
            wdog_write(WDOG_INTCLR, 1);
            wdog_write(WDOG_LOCK, 0);
        }
    }
}

/// The watchdog's interrupt: the main loop has not fed it for 1 s; the reset follows 1 s later
/// unless it is fed meanwhile. Leaves the cause for the next boot.
#[exception]
unsafe fn NonMaskableInt() {
    super::reset_mark::set(ResetCause::Watchdog);
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    match irqn {
        UART0_RX_IRQ => super::systick_cost::timed_interrupt(uart_rx_interrupt),
        UART0_TX_IRQ => super::systick_cost::timed_interrupt(uart_tx_interrupt),
        _ => {}
    }
}

unsafe fn reg_read(offset: usize) -> u32 {
    unsafe { read_volatile((UART0_BASE + offset) as *const u32) }
}

unsafe fn reg_write(offset: usize, value: u32) {
    unsafe { write_volatile((UART0_BASE + offset) as *mut u32, value) }
}

unsafe fn wdog_write(offset: usize, value: u32) {
    unsafe { write_volatile((WATCHDOG_BASE + offset) as *mut u32, value) }
}

/// After a panic or a fault has been logged: end the QEMU run with exit status 1.
pub fn fatal() -> ! {
    semihosting::process::exit(1)
}
