//! The link's serial port: USART1 (PA9 TX, PA10 RX, alternate function 7), 115200 8N1, set up
//! through stm32f4xx-hal. Receive never depends on the main loop being free:
//!
//! | | silicon | QEMU netduinoplus2 |
//! |---|---|---|
//! | receive | DMA2 stream 2 channel 4 (RM0090 table 43: USART1_RX) in circular mode into [`DMA_RX_BUFFER_BYTES`] of SRAM; the USART's idle-line interrupt wakes the main loop after each frame | the RXNE interrupt into the interrupt ring (QEMU models no DMA) |
//! | transmit | DMA2 stream 7 channel 4 (USART1_TX) from a 256-byte buffer: `write` starts it and returns | blocking (QEMU's TXE interrupt never fires) through [`BlockingWriter`] |
//! | errors | overrun, framing and noise flags counted by the USART1 interrupt (EIE in DMA mode) | the same flags, read with each byte |
//!
//! Why DMA on silicon: the one flash bank stalls every instruction fetch while a sector erases
//! (up to 4 s, datasheet DS8626), interrupt handlers included, and the USART holds one byte (a
//! second overruns it, RM0090 30.6.1). The DMA keeps writing to SRAM meanwhile. The ring's reader
//! is `firmware::dma_ring` (host-tested against a simulated DMA and the chip's timeline).

use core::ptr::read_volatile;

use firmware::dma_ring::{snapshot, DmaFlags, DmaRing, DmaStream};
use firmware::rx_stats::{LineErrors, RxStats};
use firmware::{Received, DMA_RX_BUFFER_BYTES};
use link_protocol::{BlockingWriter, LinkCounters};
use static_cell::ConstStaticCell;
use stm32f4xx_hal::dma::config::Priority;
use stm32f4xx_hal::dma::traits::{Stream, StreamISR};
use stm32f4xx_hal::dma::{DmaChannel, DmaDataSize, DmaDirection, StreamX, StreamsTuple};
use stm32f4xx_hal::gpio::{PA10, PA9};
use stm32f4xx_hal::pac::{self, Interrupt, DMA2, USART1};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::serial::{config::InvalidConfig, Error, RxListen, Serial, Tx};

use super::super::interrupt_rx::{self, RingReceiver};
use super::Environment;

const BAUD: u32 = 115_200;
/// The transmit DMA's buffer: more than the longest frame (182 bytes).
const TX_BUFFER_BYTES: usize = 256;

/// The circular receive buffer the DMA writes (SRAM1, which DMA2 reaches; not the CCM).
static DMA_RX_BUFFER: ConstStaticCell<[u8; DMA_RX_BUFFER_BYTES]> =
    ConstStaticCell::new([0; DMA_RX_BUFFER_BYTES]);
/// What the transmit DMA sends from.
static DMA_TX_BUFFER: ConstStaticCell<[u8; TX_BUFFER_BYTES]> =
    ConstStaticCell::new([0; TX_BUFFER_BYTES]);
/// The DMA path's error counters (the USART1 interrupt counts line errors into them).
static DMA_STATS: RxStats = RxStats::new();

/// USART1's receiving end.
pub enum Receiver {
    Dma(DmaReceiver),
    Interrupt(RingReceiver),
}

/// USART1's transmitting end.
pub enum Transmitter {
    Dma(DmaTransmitter),
    Blocking(BlockingWriter<Tx<USART1, u8>>),
}

/// Sets up the pins, USART1 (8N1 is the HAL's default) and, on silicon, the DMA streams; enables
/// receiving, after which no byte sent to the board is lost.
pub fn init(
    environment: Environment,
    usart: pac::USART1,
    dma2: DMA2,
    tx_pin: PA9,
    rx_pin: PA10,
    rcc: &mut Rcc,
) -> Result<Option<(Transmitter, Receiver)>, InvalidConfig> {
    let serial: Serial<USART1, u8> = usart.serial((tx_pin, rx_pin), BAUD.bps(), rcc)?;
    let (tx, mut rx) = serial.split();
    let ends = match environment {
        Environment::Qemu => {
            let Some(ring) = interrupt_rx::init() else {
                return Ok(None);
            };
            rx.listen();
            (
                Transmitter::Blocking(BlockingWriter::new(tx)),
                Receiver::Interrupt(ring),
            )
        }
        Environment::Silicon => {
            let (Some(rx_buffer), Some(tx_buffer)) =
                (DMA_RX_BUFFER.try_take(), DMA_TX_BUFFER.try_take())
            else {
                return Ok(None);
            };
            // From here on only the DMA writes the receive buffer, and it is read through this
            // pointer only (volatile).
            let rx_buffer: *const u8 = rx_buffer.as_mut_ptr();
            let streams = StreamsTuple::new(dma2, rcc);
            let rx_stream = start_rx_dma(streams.2, rx_buffer);
            let tx_stream = prepare_tx_dma(streams.7, tx_buffer.as_ptr());
            rx.listen_idle();
            // SAFETY: USART1's CR3, owned by this setup: DMA for both directions, and the error
            // interrupt (overrun, framing, noise flags while the DMA reads the data register).
            unsafe {
                (*USART1::ptr())
                    .cr3()
                    .modify(|_, w| w.dmar().set_bit().dmat().set_bit().eie().set_bit());
            }
            (
                Transmitter::Dma(DmaTransmitter {
                    stream: tx_stream,
                    buffer: tx_buffer,
                }),
                Receiver::Dma(DmaReceiver {
                    ring: DmaRing::new(),
                    stream: RxStream(rx_stream),
                    buffer: rx_buffer,
                }),
            )
        }
    };
    // SAFETY: the handler's ring (QEMU) or counters (silicon) are in place.
    unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::USART1) };
    Ok(Some(ends))
}

/// USART1's data register, the DMA's peripheral address.
fn usart1_dr_address() -> u32 {
    // SAFETY: the address of a register, not a read.
    unsafe { (*USART1::ptr()).dr().as_ptr() as u32 }
}

fn start_rx_dma(mut stream: StreamX<DMA2, 2>, buffer: *const u8) -> StreamX<DMA2, 2> {
    stream.set_channel(DmaChannel::Channel4);
    stream.set_direction(DmaDirection::PeripheralToMemory);
    stream.set_peripheral_address(usart1_dr_address());
    stream.set_memory_address(buffer as u32);
    stream.set_number_of_transfers(DMA_RX_BUFFER_BYTES as u16);
    stream.set_memory_increment(true);
    stream.set_peripheral_increment(false);
    stream.set_circular_mode(true);
    stream.set_priority(Priority::VeryHigh);
    stream.clear_half_transfer();
    stream.clear_transfer_complete();
    // SAFETY: byte transfers from the data register into the static buffer, which only the DMA
    // writes and `DmaReceiver` reads (volatile); enabled once, never disabled.
    unsafe {
        stream.set_memory_size(DmaDataSize::Byte);
        stream.set_peripheral_size(DmaDataSize::Byte);
        stream.enable();
    }
    stream
}

fn prepare_tx_dma(mut stream: StreamX<DMA2, 7>, buffer: *const u8) -> StreamX<DMA2, 7> {
    stream.set_channel(DmaChannel::Channel4);
    stream.set_direction(DmaDirection::MemoryToPeripheral);
    stream.set_peripheral_address(usart1_dr_address());
    stream.set_memory_address(buffer as u32);
    stream.set_memory_increment(true);
    stream.set_peripheral_increment(false);
    stream.set_circular_mode(false);
    stream.set_priority(Priority::Medium);
    // SAFETY: byte transfers from the static buffer to the data register.
    unsafe {
        stream.set_memory_size(DmaDataSize::Byte);
        stream.set_peripheral_size(DmaDataSize::Byte);
    }
    stream
}

/// The receive stream's counter and flags, for the ring's reader.
pub struct RxStream(StreamX<DMA2, 2>);

impl DmaStream for RxStream {
    fn remaining(&self) -> u16 {
        self.0.number_of_transfers()
    }

    fn take_flags(&mut self) -> DmaFlags {
        let flags = DmaFlags {
            half: self.0.is_half_transfer(),
            complete: self.0.is_transfer_complete(),
        };
        // Cleared right after being read; `snapshot` makes sure no mark passed in between.
        if flags.half {
            self.0.clear_half_transfer();
        }
        if flags.complete {
            self.0.clear_transfer_complete();
        }
        flags
    }
}

/// The silicon's receive path: the DMA ring and its reader.
pub struct DmaReceiver {
    ring: DmaRing<DMA_RX_BUFFER_BYTES>,
    stream: RxStream,
    /// The start of the receive buffer, which the DMA writes.
    buffer: *const u8,
}

impl DmaReceiver {
    /// The byte at ring position `i` of the receive buffer that starts at `buffer`.
    fn byte_at(buffer: *const u8, i: usize) -> u8 {
        // SAFETY: `buffer` is the receive buffer's start; a volatile read of a byte the DMA has
        // written (`DmaRing` only asks for those); the index is below the buffer's length (the
        // ring's positions are modulo it).
        unsafe { read_volatile(buffer.add(i % DMA_RX_BUFFER_BYTES)) }
    }

    fn update(&mut self) {
        let s = snapshot::<DMA_RX_BUFFER_BYTES>(&mut self.stream);
        self.ring.update(s, &DMA_STATS);
    }
}

impl Receiver {
    /// The next received item, if any (never blocks).
    pub fn next(&mut self) -> Option<Received> {
        match self {
            Receiver::Interrupt(r) => r.next(),
            Receiver::Dma(d) => {
                let buffer = d.buffer;
                if let Some(item) = d.ring.next(|i| DmaReceiver::byte_at(buffer, i)) {
                    return Some(item);
                }
                d.update();
                d.ring.next(|i| DmaReceiver::byte_at(buffer, i))
            }
        }
    }

    /// Sleeps (WFI) until something may have arrived: a byte (QEMU), the line going idle after a
    /// frame (silicon), or SysTick's tick (every 0.1 s at 168 MHz).
    pub fn wait(&mut self) {
        match self {
            Receiver::Interrupt(r) => r.wait(),
            Receiver::Dma(d) => {
                cortex_m::interrupt::disable();
                d.update();
                if d.ring.unread() == 0 {
                    cortex_m::asm::wfi();
                }
                // SAFETY: re-enables what was enabled before; the firmware runs with interrupts on.
                unsafe { cortex_m::interrupt::enable() };
            }
        }
    }

    /// The receive path's counters; `lost_frames` from the link's sequence numbers.
    pub fn counters(&self, lost_frames: u32) -> LinkCounters {
        match self {
            Receiver::Interrupt(r) => r.counters(lost_frames),
            Receiver::Dma(_) => DMA_STATS.snapshot(DMA_RX_BUFFER_BYTES, lost_frames),
        }
    }
}

/// The silicon's transmitter: one DMA transfer per write.
pub struct DmaTransmitter {
    stream: StreamX<DMA2, 7>,
    /// What the stream sends from: filled only while the stream is idle.
    buffer: &'static mut [u8; TX_BUFFER_BYTES],
}

impl DmaTransmitter {
    fn wait_idle(&self) {
        while self.stream.is_enabled() {
            core::hint::spin_loop();
        }
    }
}

impl embedded_io::ErrorType for Transmitter {
    type Error = Error;
}

impl embedded_io::Write for Transmitter {
    /// Blocking under QEMU. On silicon: waits for the previous transfer to end (an answer of
    /// 182 bytes takes 15.8 ms), copies what fits into the DMA's buffer and starts it.
    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        match self {
            Transmitter::Blocking(tx) => tx.write(buf),
            Transmitter::Dma(d) => {
                if buf.is_empty() {
                    return Ok(0);
                }
                d.wait_idle();
                let n = buf.len().min(TX_BUFFER_BYTES);
                // The stream is idle, so nothing reads the buffer while it is filled.
                if let (Some(to), Some(from)) = (d.buffer.get_mut(..n), buf.get(..n)) {
                    to.copy_from_slice(from);
                }
                // Every flag of stream 7 cleared in one write to DMA2_HIFCR (bits 22 and 24-27:
                // FIFO error, direct mode error, transfer error, half transfer, complete;
                // RM0090 10.5.4), as the stream must be before it is enabled again.
                // SAFETY: a write-1-to-clear register; the bits are stream 7's only.
                unsafe { (*DMA2::ptr()).hifcr().write(|w| w.bits(0x0F40_0000)) };
                d.stream.set_number_of_transfers(n as u16);
                // SAFETY: the buffer holds the bytes to send; the stream sends them to USART1.
                unsafe { d.stream.enable() };
                Ok(n)
            }
        }
    }

    /// Waits until the last byte has been handed to the USART.
    fn flush(&mut self) -> Result<(), Error> {
        match self {
            Transmitter::Blocking(tx) => tx.flush(),
            Transmitter::Dma(d) => {
                d.wait_idle();
                Ok(())
            }
        }
    }
}

/// USART1's interrupt. Under QEMU: each received byte (RXNE) into the ring. On silicon: the
/// idle line (a frame has ended: it only wakes the main loop) and the error flags while the DMA
/// reads the data: counted, then cleared by reading SR then DR (DR only when the DMA has taken
/// the byte, RXNE clear, so that no byte is taken from it).
pub fn usart1_interrupt(environment: Environment) {
    // SAFETY: USART1's status and data registers; this handler is the only other reader of DR
    // than the DMA (silicon) and the only reader under QEMU.
    let usart = unsafe { &*USART1::ptr() };
    let sr = usart.sr().read();
    let errors = LineErrors {
        overrun: sr.ore().bit_is_set(),
        framing: sr.fe().bit_is_set(),
        noise: sr.nf().bit_is_set(),
    };
    match environment {
        Environment::Qemu => {
            if sr.rxne().bit_is_set() {
                let byte = usart.dr().read().dr().bits() as u8;
                interrupt_rx::push(byte, errors);
            }
        }
        Environment::Silicon => {
            DMA_STATS.count_line_errors(errors);
            let flagged =
                errors.overrun || errors.framing || errors.noise || sr.idle().bit_is_set();
            if flagged && sr.rxne().bit_is_clear() {
                let _ = usart.dr().read();
            }
        }
    }
}
