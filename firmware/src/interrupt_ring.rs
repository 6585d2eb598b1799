//! The receive ring filled by a UART's receive interrupt: a `heapless` single-producer,
//! single-consumer queue between the interrupt handler (the producer, [`RingWriter`]) and the main
//! loop (the consumer, [`RingReader`]). Used where the receive interrupt can always run when a byte
//! arrives: mps2-an386 (QEMU), and the STM32F405 under QEMU, which models no DMA. (On STM32F405
//! silicon the CPU, and so any interrupt handler in flash, stalls while the flash erases or
//! programs; there the DMA ring of `dma_ring.rs` receives instead.)
//!
//! Each entry is the byte and, in bit 8, whether bytes were lost just before it (the ring was full
//! when they arrived), so the reader knows exactly where the stream has a hole and drops only the
//! frame that the hole cuts.

use heapless::spsc::{Consumer, Producer, Queue};

use crate::rx_stats::{LineErrors, RxStats};
use crate::Received;

/// Bit 8 of an entry: bytes were lost between the previous entry and this one.
const GAP_BEFORE: u16 = 1 << 8;

/// The ring's storage: `N - 1` entries (heapless keeps one slot free). Put it in a `static`.
pub struct InterruptRing<const N: usize> {
    queue: Queue<u16, N>,
}

impl<const N: usize> Default for InterruptRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> InterruptRing<N> {
    /// Bytes the ring holds.
    pub const CAPACITY: usize = N - 1;

    /// An empty ring.
    pub const fn new() -> Self {
        InterruptRing {
            queue: Queue::new(),
        }
    }

    /// The interrupt handler's end and the main loop's end, both counting into `stats`.
    pub fn split<'a>(&'a mut self, stats: &'a RxStats) -> (RingWriter<'a>, RingReader<'a>) {
        let (producer, consumer) = self.queue.split();
        (
            RingWriter {
                producer,
                stats,
                gap: false,
            },
            RingReader {
                consumer,
                pending: None,
            },
        )
    }
}

/// The interrupt handler's end of the ring.
pub struct RingWriter<'a> {
    producer: Producer<'a, u16>,
    stats: &'a RxStats,
    /// Bytes were dropped since the last one that went in.
    gap: bool,
}

impl RingWriter<'_> {
    /// One received byte and what the UART flagged with it. A byte that does not fit is dropped
    /// and counted as a buffer overrun; the next byte that fits carries the gap mark. A UART
    /// overrun also marks a gap (the UART itself lost a byte before this one).
    pub fn push(&mut self, byte: u8, errors: LineErrors) {
        self.stats.count_line_errors(errors);
        let gap = self.gap || errors.overrun;
        let entry = u16::from(byte) | if gap { GAP_BEFORE } else { 0 };
        if self.producer.enqueue(entry).is_ok() {
            self.gap = false;
            self.stats.note_fill(self.producer.len());
        } else {
            if !self.gap {
                // One overflow counted per run of dropped bytes.
                self.stats.count_buffer_overrun();
            }
            self.gap = true;
        }
    }
}

/// The main loop's end of the ring.
pub struct RingReader<'a> {
    consumer: Consumer<'a, u16>,
    /// The byte after a gap, once the gap has been reported.
    pending: Option<u8>,
}

impl Iterator for RingReader<'_> {
    type Item = Received;

    /// The next received byte (after a [`Received::Gap`] if bytes were lost before it), or `None`
    /// if nothing is waiting (more may come later).
    fn next(&mut self) -> Option<Received> {
        if let Some(byte) = self.pending.take() {
            return Some(Received::Byte(byte));
        }
        let entry = self.consumer.dequeue()?;
        let byte = (entry & 0xFF) as u8;
        if entry & GAP_BEFORE != 0 {
            self.pending = Some(byte);
            return Some(Received::Gap);
        }
        Some(Received::Byte(byte))
    }
}

impl RingReader<'_> {
    /// Whether nothing is waiting.
    pub fn is_empty(&self) -> bool {
        self.pending.is_none() && self.consumer.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn drain(reader: &mut RingReader<'_>) -> Vec<Received> {
        reader.by_ref().collect()
    }

    #[test]
    fn bytes_come_out_in_order_and_the_peak_is_recorded() {
        let stats = RxStats::new();
        let mut ring = InterruptRing::<8>::new();
        let (mut w, mut r) = ring.split(&stats);
        for b in [1u8, 2, 3] {
            w.push(b, LineErrors::default());
        }
        assert_eq!(
            drain(&mut r),
            [Received::Byte(1), Received::Byte(2), Received::Byte(3)]
        );
        w.push(4, LineErrors::default());
        assert_eq!(drain(&mut r), [Received::Byte(4)]);
        let c = stats.snapshot(InterruptRing::<8>::CAPACITY, 0);
        assert_eq!(
            (c.rx_peak_bytes, c.buffer_overruns, c.rx_buffer_bytes),
            (3, 0, 7)
        );
    }

    #[test]
    fn a_full_ring_drops_bytes_counts_one_overrun_and_marks_the_gap_where_it_is() {
        let stats = RxStats::new();
        let mut ring = InterruptRing::<4>::new();
        let (mut w, mut r) = ring.split(&stats);
        for b in 10u8..16 {
            w.push(b, LineErrors::default());
        }
        // 3 fit, 13..15 dropped; then room again.
        assert_eq!(
            drain(&mut r),
            [Received::Byte(10), Received::Byte(11), Received::Byte(12)]
        );
        w.push(16, LineErrors::default());
        w.push(17, LineErrors::default());
        assert_eq!(
            drain(&mut r),
            [Received::Gap, Received::Byte(16), Received::Byte(17)]
        );
        assert_eq!(stats.snapshot(3, 0).buffer_overruns, 1);
    }

    #[test]
    fn a_uart_overrun_is_counted_and_marks_a_gap() {
        let stats = RxStats::new();
        let mut ring = InterruptRing::<8>::new();
        let (mut w, mut r) = ring.split(&stats);
        w.push(1, LineErrors::default());
        w.push(
            2,
            LineErrors {
                overrun: true,
                framing: false,
                noise: false,
            },
        );
        w.push(
            3,
            LineErrors {
                overrun: false,
                framing: true,
                noise: true,
            },
        );
        assert_eq!(
            drain(&mut r),
            [
                Received::Byte(1),
                Received::Gap,
                Received::Byte(2),
                Received::Byte(3)
            ]
        );
        let c = stats.snapshot(7, 0);
        assert_eq!(
            (c.uart_overruns, c.framing_errors, c.noise_errors),
            (1, 1, 1)
        );
    }
}
