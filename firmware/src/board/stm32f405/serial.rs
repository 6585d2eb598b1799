//! The link's serial port: USART1 (PA9 TX, PA10 RX, alternate function 7), 115200 8N1, through
//! stm32f4xx-hal, as `embedded_io::{Read, Write}` for `link.rs`.
//!
//! - Transmit: blocking. The HAL's `embedded_io::Write` returns `Ok(0)` when TXE is clear on entry
//!   (then `write_all` would panic); [`BlockingWriter`] retries until the byte is taken. QEMU's
//!   USART never raises the TXE interrupt, so transmission does not use it.
//! - Receive: the HAL's `embedded_hal_nb::serial::Read`. While nothing has arrived the core sleeps
//!   in WFI: the RXNE interrupt is enabled in the USART and the NVIC but masked by PRIMASK, so it
//!   wakes the core without running a handler (none exists). A receive error (overrun, framing,
//!   noise, parity) is returned as the read's error: `link.rs` drops the byte and the frame's CRC
//!   rejects the frame.

use embedded_hal_nb::serial::Read as _;
use link_protocol::BlockingWriter;
use stm32f4xx_hal::gpio::{PA10, PA9};
use stm32f4xx_hal::nb;
use stm32f4xx_hal::pac::{self, Interrupt, USART1};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::serial::{config::InvalidConfig, Error, Rx, RxListen, Serial, Tx};

const BAUD: u32 = 115_200;

/// USART1, split into its receiver and its (blocking) transmitter.
pub struct Uart {
    rx: Rx<USART1, u8>,
    tx: BlockingWriter<Tx<USART1, u8>>,
}

impl Uart {
    /// Configures the pins and USART1 (8N1 is the HAL's default) and enables the receiver, after
    /// which no byte sent to it is lost.
    pub fn init(usart: pac::USART1, tx_pin: PA9, rx_pin: PA10, rcc: &mut Rcc) -> Result<Uart, InvalidConfig> {
        let serial: Serial<USART1, u8> = usart.serial((tx_pin, rx_pin), BAUD.bps(), rcc)?;
        let (tx, mut rx) = serial.split();
        rx.listen();
        // SAFETY: PRIMASK stays set (Board::init), so the interrupt only wakes WFI.
        unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::USART1) };
        Ok(Uart {
            rx,
            tx: BlockingWriter::new(tx),
        })
    }

    /// The next byte, sleeping until one arrives.
    fn read_byte(&mut self) -> Result<u8, Error> {
        loop {
            match self.rx.read() {
                Ok(byte) => {
                    // Reading DR cleared RXNE; clear the latched interrupt too, so the next WFI
                    // sleeps (it is pended again at once if another byte is already waiting).
                    cortex_m::peripheral::NVIC::unpend(Interrupt::USART1);
                    return Ok(byte);
                }
                Err(nb::Error::WouldBlock) => cortex_m::asm::wfi(),
                Err(nb::Error::Other(e)) => {
                    cortex_m::peripheral::NVIC::unpend(Interrupt::USART1);
                    return Err(e);
                }
            }
        }
    }

    fn rx_ready(&self) -> bool {
        // SAFETY: a read of USART1's status register, which has no side effect.
        unsafe { (*USART1::ptr()).sr().read().rxne().bit_is_set() }
    }
}


impl embedded_io::ErrorType for Uart {
    type Error = Error;
}

impl embedded_io::Read for Uart {
    /// Blocks until at least one byte has arrived, then takes what is already there.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            if n > 0 && !self.rx_ready() {
                break;
            }
            match self.read_byte() {
                Ok(byte) => *slot = byte,
                Err(e) if n == 0 => return Err(e),
                // The bytes already read are returned; the bad one is dropped all the same.
                Err(_) => break,
            }
            n += 1;
        }
        Ok(n)
    }
}

impl embedded_io::Write for Uart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        self.tx.write(buf)
    }

    /// Waits until the last byte has left the shift register (TC).
    fn flush(&mut self) -> Result<(), Error> {
        self.tx.flush()
    }
}
