//! A serial transmitter that blocks until it has taken at least one byte, for HALs whose
//! `embedded_io::Write::write` returns `Ok(0)` when the transmit register is still full.
//!
//! `embedded_io::Write::write` must block until it can take at least one byte and may return
//! `Ok(0)` only for an empty buffer. stm32f4xx-hal 0.23's USART transmitter returns `Ok(0)` when
//! TXE (transmit data register empty) is clear on entry, which on silicon happens whenever a byte
//! is still shifting out (87 us a byte at 115200 baud), and `embedded_io::Write::write_all` then
//! panics ("write() returned Ok(0)"). QEMU's USART model hides it: its TXE always reads set.
//! [`BlockingWriter`] retries such a write until the register takes a byte, so `write` never
//! returns `Ok(0)` for a non-empty buffer and `write_all` is safe. It lives here, not in the
//! firmware's board module, so that the host can test it (`cargo test -p link-protocol`).

use embedded_io::{Error, ErrorKind, ErrorType, Write};

/// Wraps a transmitter whose `write` may return `Ok(0)` (or an [`ErrorKind::Interrupted`] error)
/// while it is not ready; such results are retried until it accepts a byte. Every other error is
/// returned unchanged.
pub struct BlockingWriter<W> {
    inner: W,
}

impl<W> BlockingWriter<W> {
    /// Wraps the transmitter `inner`.
    pub fn new(inner: W) -> Self {
        BlockingWriter { inner }
    }

    /// The wrapped transmitter.
    pub fn inner_mut(&mut self) -> &mut W {
        &mut self.inner
    }
}

impl<W: ErrorType> ErrorType for BlockingWriter<W> {
    type Error = W::Error;
}

impl<W: Write> Write for BlockingWriter<W> {
    /// Writes at least one byte of a non-empty `buf`, waiting (spinning) for the transmitter.
    fn write(&mut self, buf: &[u8]) -> Result<usize, W::Error> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            match self.inner.write(buf) {
                Ok(0) => core::hint::spin_loop(),
                Err(e) if e.kind() == ErrorKind::Interrupted => core::hint::spin_loop(),
                other => return other,
            }
        }
    }

    fn flush(&mut self) -> Result<(), W::Error> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[derive(Debug, Clone, Copy, PartialEq)]
    enum MockError {
        Interrupted,
        Broken,
    }

    impl Error for MockError {
        fn kind(&self) -> ErrorKind {
            match self {
                MockError::Interrupted => ErrorKind::Interrupted,
                MockError::Broken => ErrorKind::Other,
            }
        }
    }

    /// A USART as stm32f4xx-hal drives it: before each byte, `busy` polls find TXE clear and
    /// `write` returns `Ok(0)` (or `Interrupted`, every third poll); then it takes one byte.
    struct MockUsart {
        busy: u32,
        polls_left: u32,
        sent: Vec<u8>,
        writes: u32,
        fail_at_byte: Option<usize>,
    }

    impl MockUsart {
        fn new(busy: u32) -> Self {
            MockUsart {
                busy,
                polls_left: busy,
                sent: Vec::new(),
                writes: 0,
                fail_at_byte: None,
            }
        }
    }

    impl ErrorType for MockUsart {
        type Error = MockError;
    }

    impl Write for MockUsart {
        fn write(&mut self, buf: &[u8]) -> Result<usize, MockError> {
            self.writes += 1;
            if self.fail_at_byte == Some(self.sent.len()) {
                return Err(MockError::Broken);
            }
            if self.polls_left > 0 {
                self.polls_left -= 1;
                return if self.polls_left % 3 == 2 {
                    Err(MockError::Interrupted)
                } else {
                    Ok(0)
                };
            }
            self.polls_left = self.busy;
            self.sent.push(buf[0]);
            Ok(1)
        }

        fn flush(&mut self) -> Result<(), MockError> {
            Ok(())
        }
    }

    #[test]
    fn write_all_through_a_busy_transmitter_sends_every_byte_in_order() {
        let frame: Vec<u8> = (0..=255u8).collect();
        let mut w = BlockingWriter::new(MockUsart::new(5));
        w.write_all(&frame).unwrap();
        w.flush().unwrap();
        assert_eq!(w.inner_mut().sent, frame);
        assert_eq!(
            w.inner_mut().writes,
            256 * 6,
            "five busy polls, then the byte, for each byte"
        );
    }

    #[test]
    fn write_never_returns_zero_for_a_non_empty_buffer() {
        let mut w = BlockingWriter::new(MockUsart::new(2));
        for _ in 0..10 {
            assert_eq!(w.write(b"abc"), Ok(1));
        }
        assert_eq!(w.write(&[]), Ok(0), "an empty buffer is the one Ok(0)");
    }

    #[test]
    fn the_bare_transmitter_makes_write_all_panic() {
        // The pitfall the wrapper exists for: embedded-io's write_all panics on Ok(0).
        let result = std::panic::catch_unwind(|| {
            let mut bare = MockUsart::new(1);
            let _ = bare.write_all(b"frame");
        });
        assert!(
            result.is_err(),
            "write_all over a transmitter that returns Ok(0) panics"
        );
    }

    #[test]
    fn other_errors_come_back_unchanged() {
        let mut usart = MockUsart::new(1);
        usart.fail_at_byte = Some(3);
        let mut w = BlockingWriter::new(usart);
        assert_eq!(w.write_all(b"abcdef"), Err(MockError::Broken));
        assert_eq!(w.inner_mut().sent, b"abc");
    }
}
