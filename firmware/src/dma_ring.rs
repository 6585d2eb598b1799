//! The reader of a circular DMA receive buffer: the STM32F405's USART1 receive path on silicon.
//!
//! The DMA stream writes every received byte into a buffer of `N` bytes, wrapping at its end, with
//! no help from the CPU: it keeps receiving while the CPU is stalled on a flash erase (RM0090: the
//! DMA reaches SRAM over its own bus-matrix path; the CPU's fetches from flash wait for the flash).
//! The CPU learns how far the DMA has written from the stream's counter (NDTR: transfers left
//! before the wrap), and whether it has passed the buffer's middle (HTIF) or its end (TCIF) since
//! the last look. This file turns those into bytes and a reliable overrun detection:
//!
//! - the write position is `N - NDTR` (NDTR reloads to `N` at the wrap);
//! - between two looks the DMA moved `d = (w_now - w_before) mod N` bytes, plus a whole number of
//!   laps `k` that the counter cannot show. A move of `d` passes the half-way mark and the end in
//!   a pattern the reader computes; a lap passes both. So whenever a flag is set that `d` does not
//!   explain, `k >= 1`: the DMA overwrote bytes the reader had not read (an overrun). For
//!   `d <= N/2` the move passes at most one mark, so every lap is seen. (For `d > N/2` both flags
//!   are expected and a lap cannot be told apart: the buffer is sized so that more than half of it
//!   never arrives between two looks (docs/firmware.md, the one-second budget), and the frames' CRC
//!   and sequence numbers still catch a lap there.)
//! - the unread bytes plus `d` exceeding `N` is an overrun too (the DMA caught up with the reader).
//!
//! On an overrun every unread byte is dropped (some were overwritten, and which is unknowable),
//! the reader continues at the DMA's position, counts one buffer overrun and reports a
//! [`Received::Gap`], so the link drops the frame the hole cuts.
//!
//! [`snapshot`] reads the stream consistently: counter, flags (cleared as read), counter again; if
//! the DMA crossed a mark in between, it reads again. So the flags of a snapshot are exactly the
//! marks passed between the two snapshots' counters.

use crate::rx_stats::RxStats;
use crate::Received;

/// The DMA stream's half-transfer and transfer-complete flags, read and cleared together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DmaFlags {
    /// HTIF: the DMA wrote the byte before the buffer's middle.
    pub half: bool,
    /// TCIF: the DMA wrote the buffer's last byte and wrapped to its start.
    pub complete: bool,
}

/// What the reader needs of the DMA stream (the board's registers, or a test's simulated DMA).
pub trait DmaStream {
    /// NDTR: transfers left before the wrap (`N` right after it).
    fn remaining(&self) -> u16;
    /// HTIF and TCIF since the last call, cleared.
    fn take_flags(&mut self) -> DmaFlags;
}

/// The stream's state at one moment: counter and the flags since the previous snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DmaSnapshot {
    /// The stream's transfer counter (NDTR): bytes left before it wraps.
    pub remaining: u16,
    /// The half- and full-transfer flags since the previous snapshot.
    pub flags: DmaFlags,
}

/// Reads the counter, takes the flags, reads the counter again; repeats (up to 4 times) while the
/// DMA crossed the middle or the end of the buffer in between, so that the flags belong exactly to
/// the counter returned.
pub fn snapshot<const N: usize>(stream: &mut impl DmaStream) -> DmaSnapshot {
    let mut flags = DmaFlags::default();
    let mut remaining = stream.remaining();
    for _ in 0..4 {
        let before = position::<N>(remaining);
        let taken = stream.take_flags();
        flags.half |= taken.half;
        flags.complete |= taken.complete;
        remaining = stream.remaining();
        let after = position::<N>(remaining);
        if after >= before && (after < N / 2) == (before < N / 2) {
            break;
        }
    }
    DmaSnapshot { remaining, flags }
}

/// The DMA's write position for a counter value.
fn position<const N: usize>(remaining: u16) -> usize {
    (N - usize::from(remaining).min(N)) % N
}

/// The reader's side of a circular DMA buffer of `N` bytes (`N` even, at most 65535).
pub struct DmaRing<const N: usize> {
    /// Next byte to read.
    read: usize,
    /// The DMA's write position at the last snapshot.
    write: usize,
    /// Bytes written and not yet read (up to `N`).
    unread: usize,
    /// A gap to report before the next byte.
    gap: bool,
}

impl<const N: usize> Default for DmaRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> DmaRing<N> {
    #[allow(clippy::manual_is_multiple_of)] // is_multiple_of needs Rust 1.87; the workspace says 1.85
    const CHECK: () = assert!(N >= 4 && N % 2 == 0 && N <= u16::MAX as usize);

    /// A reader for a DMA that starts at the buffer's start (NDTR = `N`).
    pub const fn new() -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::CHECK;
        DmaRing {
            read: 0,
            write: 0,
            unread: 0,
            gap: false,
        }
    }

    /// Takes in a snapshot of the stream: the bytes it wrote since the last one become readable,
    /// or, on an overrun, everything unread is dropped and counted.
    pub fn update(&mut self, snapshot: DmaSnapshot, stats: &RxStats) {
        let now = position::<N>(snapshot.remaining);
        let moved = (now + N - self.write) % N;
        let end = self.write + moved;
        let passes = |mark: usize| self.write < mark && mark <= end;
        let passes_half = passes(N / 2) || passes(N + N / 2);
        let passes_end = passes(N) || passes(2 * N);
        let lapped =
            (snapshot.flags.half && !passes_half) || (snapshot.flags.complete && !passes_end);
        self.write = now;
        if lapped || self.unread + moved > N {
            stats.count_buffer_overrun();
            self.read = now;
            self.unread = 0;
            self.gap = true;
            return;
        }
        self.unread += moved;
        stats.note_fill(self.unread);
    }

    /// The next byte read so far (after a [`Received::Gap`] where bytes were lost), or `None` when
    /// every byte up to the last snapshot has been read. `byte_at(i)` reads the buffer's byte `i`
    /// (volatile, on the target: the DMA writes it).
    pub fn next(&mut self, byte_at: impl Fn(usize) -> u8) -> Option<Received> {
        if self.unread == 0 {
            return None;
        }
        if core::mem::take(&mut self.gap) {
            return Some(Received::Gap);
        }
        let byte = byte_at(self.read);
        self.read = (self.read + 1) % N;
        self.unread -= 1;
        Some(Received::Byte(byte))
    }

    /// Bytes known to be waiting.
    pub fn unread(&self) -> usize {
        self.unread
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// A DMA stream in circular mode over an `N`-byte buffer, written one byte at a time, with
    /// RM0090's counter and flags.
    struct SimulatedDma<const N: usize> {
        buffer: [u8; N],
        remaining: u16,
        flags: DmaFlags,
    }

    impl<const N: usize> SimulatedDma<N> {
        fn new() -> Self {
            SimulatedDma {
                buffer: [0; N],
                remaining: N as u16,
                flags: DmaFlags::default(),
            }
        }

        fn write(&mut self, byte: u8) {
            let at = N - usize::from(self.remaining);
            self.buffer[at] = byte;
            self.remaining -= 1;
            if usize::from(self.remaining) == N / 2 {
                self.flags.half = true;
            }
            if self.remaining == 0 {
                self.flags.complete = true;
                self.remaining = N as u16;
            }
        }
    }

    impl<const N: usize> DmaStream for SimulatedDma<N> {
        fn remaining(&self) -> u16 {
            self.remaining
        }
        fn take_flags(&mut self) -> DmaFlags {
            core::mem::take(&mut self.flags)
        }
    }

    fn read_all<const N: usize>(
        ring: &mut DmaRing<N>,
        dma: &mut SimulatedDma<N>,
        stats: &RxStats,
    ) -> Vec<Received> {
        ring.update(snapshot::<N>(dma), stats);
        let buffer = dma.buffer;
        core::iter::from_fn(|| ring.next(|i| buffer[i])).collect()
    }

    fn bytes(range: core::ops::Range<u32>) -> Vec<Received> {
        range.map(|i| Received::Byte(i as u8)).collect()
    }

    #[test]
    fn bytes_come_out_in_order_across_many_wraps_for_every_chunk_size() {
        for chunk in [1u32, 3, 7, 15, 16, 17, 31] {
            let stats = RxStats::new();
            let mut dma = SimulatedDma::<32>::new();
            let mut ring = DmaRing::<32>::new();
            let mut got = Vec::new();
            for start in (0..1000).step_by(chunk as usize) {
                for i in start..start + chunk {
                    dma.write(i as u8);
                }
                got.extend(read_all(&mut ring, &mut dma, &stats));
            }
            let total = (1000u32).div_ceil(chunk) * chunk;
            assert_eq!(got, bytes(0..total), "chunk {chunk}");
            assert_eq!(stats.snapshot(32, 0).buffer_overruns, 0, "chunk {chunk}");
            assert_eq!(stats.snapshot(32, 0).rx_peak_bytes, chunk, "chunk {chunk}");
        }
    }

    #[test]
    fn n_bytes_between_two_looks_cannot_be_told_from_a_lap_and_count_as_an_overrun() {
        let stats = RxStats::new();
        let mut dma = SimulatedDma::<16>::new();
        let mut ring = DmaRing::<16>::new();
        for i in 0..5 {
            dma.write(i);
        }
        assert_eq!(read_all(&mut ring, &mut dma, &stats), bytes(0..5));
        // Exactly N bytes between two looks: the counter shows no move (d = 0) and both marks
        // were passed, as after N + 1 or 2 N bytes: the reader cannot tell, so it is an overrun.
        for i in 5..21 {
            dma.write(i);
        }
        let got = read_all(&mut ring, &mut dma, &stats);
        assert_eq!(got, []);
        assert_eq!(stats.snapshot(16, 0).buffer_overruns, 1);
        // The gap shows with the next byte.
        dma.write(21);
        assert_eq!(
            read_all(&mut ring, &mut dma, &stats),
            [Received::Gap, Received::Byte(21)]
        );
    }

    #[test]
    fn the_dma_catching_up_with_a_slow_reader_is_an_overrun() {
        let stats = RxStats::new();
        let mut dma = SimulatedDma::<16>::new();
        let mut ring = DmaRing::<16>::new();
        // 6 bytes written and seen, none read.
        for i in 0..6 {
            dma.write(i);
        }
        ring.update(snapshot::<16>(&mut dma), &stats);
        assert_eq!(ring.unread(), 6);
        // 8 more (d = 8 <= N/2, one mark passed, consistent flags) fit: 14 unread.
        for i in 6..14 {
            dma.write(i);
        }
        ring.update(snapshot::<16>(&mut dma), &stats);
        assert_eq!(ring.unread(), 14);
        assert_eq!(stats.snapshot(16, 0).buffer_overruns, 0);
        // 3 more: 17 > 16, the oldest byte was overwritten.
        for i in 14..17 {
            dma.write(i);
        }
        let got = read_all(&mut ring, &mut dma, &stats);
        assert_eq!(got, []);
        assert_eq!(stats.snapshot(16, 0).buffer_overruns, 1);
        for i in 17..20 {
            dma.write(i);
        }
        let mut expected = std::vec![Received::Gap];
        expected.extend(bytes(17..20));
        assert_eq!(read_all(&mut ring, &mut dma, &stats), expected);
    }

    #[test]
    fn every_lap_between_two_looks_is_detected_when_less_than_half_moved() {
        // For each start position and each move d <= N/2, one extra lap is always detected, and
        // no lap never is.
        const N: usize = 16;
        for start in 0..N {
            for d in 0..=N / 2 {
                for laps in 0..=2 {
                    let stats = RxStats::new();
                    let mut dma = SimulatedDma::<N>::new();
                    let mut ring = DmaRing::<N>::new();
                    for i in 0..start {
                        dma.write(i as u8);
                    }
                    let _ = read_all(&mut ring, &mut dma, &stats);
                    for i in 0..d + laps * N {
                        dma.write(i as u8);
                    }
                    let got = read_all(&mut ring, &mut dma, &stats);
                    let overruns = stats.snapshot(N, 0).buffer_overruns;
                    if laps == 0 {
                        assert_eq!((overruns, got.len()), (0, d), "start {start} d {d}");
                    } else {
                        assert_eq!(
                            (overruns, got.len()),
                            (1, 0),
                            "start {start} d {d} laps {laps}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn more_than_half_between_two_looks_without_a_lap_is_read_whole() {
        let stats = RxStats::new();
        let mut dma = SimulatedDma::<16>::new();
        let mut ring = DmaRing::<16>::new();
        for i in 0..3 {
            dma.write(i);
        }
        let _ = read_all(&mut ring, &mut dma, &stats);
        for i in 3..15 {
            dma.write(i);
        }
        assert_eq!(read_all(&mut ring, &mut dma, &stats), bytes(3..15));
        assert_eq!(stats.snapshot(16, 0).buffer_overruns, 0);
    }

    /// A stream whose counter moves between the two readings of a snapshot: the DMA writes a byte
    /// while the CPU reads the registers.
    struct RacingDma {
        dma: SimulatedDma<16>,
        /// Write one byte before each `take_flags` while this is above zero.
        writes_while_reading: usize,
    }

    impl DmaStream for RacingDma {
        fn remaining(&self) -> u16 {
            self.dma.remaining()
        }
        fn take_flags(&mut self) -> DmaFlags {
            let flags = self.dma.take_flags();
            if self.writes_while_reading > 0 {
                self.writes_while_reading -= 1;
                self.dma.write(0xEE);
            }
            flags
        }
    }

    #[test]
    fn a_mark_crossed_while_the_registers_are_read_is_read_again_not_taken_for_a_lap() {
        let stats = RxStats::new();
        let mut racing = RacingDma {
            dma: SimulatedDma::new(),
            writes_while_reading: 0,
        };
        let mut ring = DmaRing::<16>::new();
        for i in 0..7 {
            racing.dma.write(i);
        }
        ring.update(snapshot::<16>(&mut racing), &stats);
        // The 8th byte (the one that sets HTIF) lands between the flags and the second counter.
        racing.writes_while_reading = 1;
        let s = snapshot::<16>(&mut racing);
        assert_eq!((s.remaining, s.flags.half), (8, true));
        ring.update(s, &stats);
        assert_eq!(ring.unread(), 8);
        assert_eq!(stats.snapshot(16, 0).buffer_overruns, 0);
    }
}
