//! The receive path's error counters, shared between the code that receives (an interrupt
//! handler, or the DMA ring's reader) and the main loop that reports them: atomics, so that
//! neither side needs a critical section. They count since boot and saturate.

use core::sync::atomic::{AtomicU32, Ordering};

use link_protocol::LinkCounters;

/// What a UART's status register said about one received byte (or about the line since the last
/// byte): each flag is one error to count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineErrors {
    /// A byte completed while the previous one was still in the data register: the UART lost
    /// one (or more) bytes (STM32 ORE, CMSDK RX overrun).
    pub overrun: bool,
    /// No stop bit where one belongs (STM32 FE).
    pub framing: bool,
    /// The samples of a bit disagreed (STM32 NF).
    pub noise: bool,
}

/// Counters of the receive path (lost frames are counted by the link, from the sequence numbers).
pub struct RxStats {
    uart_overruns: AtomicU32,
    buffer_overruns: AtomicU32,
    framing_errors: AtomicU32,
    noise_errors: AtomicU32,
    peak_bytes: AtomicU32,
}

impl Default for RxStats {
    fn default() -> Self {
        Self::new()
    }
}

fn saturating_increment(counter: &AtomicU32) {
    // A read-modify-write that stops at u32::MAX; only one writer per counter (the receiver).
    let now = counter.load(Ordering::Relaxed);
    counter.store(now.saturating_add(1), Ordering::Relaxed);
}

impl RxStats {
    /// Every counter at zero.
    pub const fn new() -> Self {
        RxStats {
            uart_overruns: AtomicU32::new(0),
            buffer_overruns: AtomicU32::new(0),
            framing_errors: AtomicU32::new(0),
            noise_errors: AtomicU32::new(0),
            peak_bytes: AtomicU32::new(0),
        }
    }

    /// Counts the errors the UART flagged.
    pub fn count_line_errors(&self, errors: LineErrors) {
        if errors.overrun {
            saturating_increment(&self.uart_overruns);
        }
        if errors.framing {
            saturating_increment(&self.framing_errors);
        }
        if errors.noise {
            saturating_increment(&self.noise_errors);
        }
    }

    /// Counts one overflow of the receive buffer (bytes lost before the firmware read them).
    pub fn count_buffer_overrun(&self) {
        saturating_increment(&self.buffer_overruns);
    }

    /// Records that `bytes` were waiting in the buffer at once.
    pub fn note_fill(&self, bytes: usize) {
        let bytes = u32::try_from(bytes).unwrap_or(u32::MAX);
        if bytes > self.peak_bytes.load(Ordering::Relaxed) {
            self.peak_bytes.store(bytes, Ordering::Relaxed);
        }
    }

    /// The counters as the link reports them; `lost_frames` is the link's own.
    pub fn snapshot(&self, rx_buffer_bytes: usize, lost_frames: u32) -> LinkCounters {
        LinkCounters {
            lost_frames,
            uart_overruns: self.uart_overruns.load(Ordering::Relaxed),
            buffer_overruns: self.buffer_overruns.load(Ordering::Relaxed),
            framing_errors: self.framing_errors.load(Ordering::Relaxed),
            noise_errors: self.noise_errors.load(Ordering::Relaxed),
            rx_buffer_bytes: u32::try_from(rx_buffer_bytes).unwrap_or(u32::MAX),
            rx_peak_bytes: self.peak_bytes.load(Ordering::Relaxed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_flag_counts_once_and_the_peak_keeps_the_largest_fill() {
        let s = RxStats::new();
        s.count_line_errors(LineErrors {
            overrun: true,
            framing: false,
            noise: true,
        });
        s.count_line_errors(LineErrors {
            overrun: true,
            framing: true,
            noise: false,
        });
        s.count_line_errors(LineErrors::default());
        s.count_buffer_overrun();
        s.note_fill(40);
        s.note_fill(400);
        s.note_fill(4);
        let c = s.snapshot(2048, 3);
        assert_eq!(
            c,
            LinkCounters {
                lost_frames: 3,
                uart_overruns: 2,
                buffer_overruns: 1,
                framing_errors: 1,
                noise_errors: 1,
                rx_buffer_bytes: 2048,
                rx_peak_bytes: 400,
            }
        );
    }

    #[test]
    fn counters_saturate() {
        let s = RxStats::new();
        s.uart_overruns.store(u32::MAX, Ordering::Relaxed);
        s.count_line_errors(LineErrors {
            overrun: true,
            ..LineErrors::default()
        });
        assert_eq!(s.snapshot(1, 0).uart_overruns, u32::MAX);
    }
}
