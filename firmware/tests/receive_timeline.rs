//! The STM32F405's receive path against the chip's own timeline, on the host.
//!
//! A navigation computer sends one numbered sample frame a second at 115200 baud 8N1 (86.8 us a
//! byte). The firmware's main loop takes each frame, steps the estimator, answers, and every 60 s
//! saves a checkpoint. Modelled at the datasheet's worst case (STM32F405 datasheet DS8626, flash
//! characteristics; reference manual RM0090, section 3 (embedded flash) and 30 (USART)):
//!
//! - a save erases one 128 KiB sector first, 4 s maximum at x8 parallelism (what stm32f4xx-hal
//!   uses), then programs 2,560 bytes at 100 us maximum each (byte accesses at x8): 4.256 s in
//!   which any fetch from flash stalls, so the CPU runs nothing, interrupt handlers included (one
//!   flash bank);
//! - a step: 5,000 instructions (the budget the QEMU tests hold it to) at 2 cycles each at
//!   168 MHz: 60 us;
//! - an answer: sent blocking, the longest there is (the status answer, 182 bytes on the wire:
//!   15.8 ms), as if the transmitter kept the CPU busy (it does not on silicon, where the answer
//!   goes out by DMA; this is the worst case);
//! - the USART has no FIFO: a byte that completes while the previous is still in the data
//!   register is lost and sets ORE.
//!
//! The DMA path (`dma_ring.rs`, the silicon's) receives every byte through every stall: every
//! frame arrives, in order, and the buffer never fills past half (the reader's contract). The
//! interrupt path (the RXNE handler and ring used under QEMU) is modelled on the same timeline to
//! show why silicon needs the DMA: its handler cannot run while the flash stalls the CPU, and the
//! frames sent meanwhile are lost.

use estimator_core::Sample;
use firmware::dma_ring::{snapshot, DmaFlags, DmaRing, DmaStream};
use firmware::interrupt_ring::InterruptRing;
use firmware::request_receiver::RequestReceiver;
use firmware::rx_stats::{LineErrors, RxStats};
use firmware::watchdog::{iwdg_timeout_range_ms, STM32F405_IWDG_TIMEOUT_MS};
use firmware::{DMA_RX_BUFFER_BYTES, INTERRUPT_RX_RING_ENTRIES};
use link_protocol::frame::MAX_FRAME;
use link_protocol::{encode_frame, Numbered, Request, SampleMsg};

/// One byte at 115200 baud, 8N1 (10 bits), ns.
const BYTE_NS: u64 = 1_000_000_000 * 10 / 115_200;
/// One sample frame a second.
const FRAME_PERIOD_NS: u64 = 1_000_000_000;
/// A checkpoint every 60 s of samples, each erasing a sector first (the worst case).
const SAVE_EVERY_FRAMES: u32 = 60;
/// 128 KiB sector erase, x8, maximum (DS8626).
const ERASE_MAX_NS: u64 = 4_000_000_000;
/// A save's programming: 2,560 bytes at 100 us maximum each (DS8626, x8).
const PROGRAM_MAX_NS: u64 = 2_560 * 100_000;
/// A step: 5,000 instructions at 2 cycles each, 168 MHz.
const STEP_NS: u64 = 5_000 * 2 * 1_000_000_000 / 168_000_000;
/// The longest answer (182 bytes on the wire) sent blocking.
const ANSWER_NS: u64 = 182 * BYTE_NS;

/// Frames of the sender, in order: (seq, bytes).
fn frames(count: u32) -> Vec<Vec<u8>> {
    (1..=count)
        .map(|seq| {
            let s = Sample::from_degrees(
                f64::from(seq),
                f64::from(seq) * 0.5,
                1.0,
                30.0,
                10.0,
                2.0,
                -1.0,
            );
            let mut out = [0u8; MAX_FRAME];
            let n = encode_frame(
                &Numbered {
                    seq,
                    message: Request::Sample(SampleMsg::from(&s)),
                },
                &mut out,
            )
            .unwrap();
            out[..n].to_vec()
        })
        .collect()
}

/// Every byte on the line with the time its stop bit ends, ns.
fn line(frames: &[Vec<u8>]) -> Vec<(u64, u8)> {
    let mut out = Vec::new();
    for (i, f) in frames.iter().enumerate() {
        let start = i as u64 * FRAME_PERIOD_NS;
        for (j, &b) in f.iter().enumerate() {
            out.push((start + (j as u64 + 1) * BYTE_NS, b));
        }
    }
    out
}

/// When the CPU stalls on flash: a save after the answer to every `SAVE_EVERY_FRAMES`th frame.
/// The main loop, given a frame completed at `t`, is busy until the returned time; `stalled` gets
/// the save's interval.
fn serve(t: u64, seq: u32, stalls: &mut Vec<(u64, u64)>) -> u64 {
    let mut t = t + STEP_NS + ANSWER_NS;
    if seq.is_multiple_of(SAVE_EVERY_FRAMES) {
        stalls.push((t, t + ERASE_MAX_NS + PROGRAM_MAX_NS));
        t += ERASE_MAX_NS + PROGRAM_MAX_NS;
    }
    t
}

/// The DMA stream in circular mode, written by the line whatever the CPU does.
struct Dma {
    buffer: Vec<u8>,
    remaining: u16,
    flags: DmaFlags,
}

impl Dma {
    fn new() -> Dma {
        Dma {
            buffer: vec![0; DMA_RX_BUFFER_BYTES],
            remaining: DMA_RX_BUFFER_BYTES as u16,
            flags: DmaFlags::default(),
        }
    }

    fn write(&mut self, byte: u8) {
        let n = DMA_RX_BUFFER_BYTES;
        self.buffer[n - usize::from(self.remaining)] = byte;
        self.remaining -= 1;
        if usize::from(self.remaining) == n / 2 {
            self.flags.half = true;
        }
        if self.remaining == 0 {
            self.flags.complete = true;
            self.remaining = n as u16;
        }
    }
}

impl DmaStream for Dma {
    fn remaining(&self) -> u16 {
        self.remaining
    }
    fn take_flags(&mut self) -> DmaFlags {
        std::mem::take(&mut self.flags)
    }
}

/// What one run received.
struct Outcome {
    seqs: Vec<u32>,
    lost_frames: u32,
    stats: link_protocol::LinkCounters,
    bad_frames: usize,
    stalls: Vec<(u64, u64)>,
}

/// The silicon's path: DMA into the ring, read by the main loop whenever it is free.
fn run_dma(count: u32) -> Outcome {
    let frames = frames(count);
    let line = line(&frames);
    let stats = RxStats::new();
    let mut dma = Dma::new();
    let mut ring = DmaRing::<DMA_RX_BUFFER_BYTES>::new();
    let mut receiver = RequestReceiver::new();
    let (mut seqs, mut bad_frames, mut stalls) = (Vec::new(), 0, Vec::new());
    let mut next = 0; // next byte of the line to reach the DMA
    let mut t = 0u64;
    loop {
        // Everything on the line up to now is in the buffer, whatever the CPU did meanwhile.
        while next < line.len() && line[next].0 <= t {
            dma.write(line[next].1);
            next += 1;
        }
        ring.update(snapshot::<DMA_RX_BUFFER_BYTES>(&mut dma), &stats);
        let buffer = dma.buffer.clone();
        let mut served = None;
        while let Some(item) = ring.next(|i| buffer[i]) {
            match receiver.push(item) {
                Some(Ok(request)) => {
                    seqs.push(request.seq);
                    served = Some(request.seq);
                    break;
                }
                Some(Err(_)) => bad_frames += 1,
                None => {}
            }
        }
        match served {
            Some(seq) => t = serve(t, seq, &mut stalls),
            None if ring.unread() > 0 => {}
            None if next == line.len() => break,
            // Asleep until the line goes idle after the next byte (USART IDLE), or the next byte
            // if that is sooner to model: wake at the next byte's arrival.
            None => t = t.max(line[next].0),
        }
    }
    Outcome {
        seqs,
        lost_frames: receiver.lost_frames(),
        stats: stats.snapshot(DMA_RX_BUFFER_BYTES, receiver.lost_frames()),
        bad_frames,
        stalls,
    }
}

/// The interrupt path on the same timeline: the USART's one data register, read by the RXNE
/// handler as soon as the CPU can run it (not during a flash stall), into the ring.
fn run_interrupt(count: u32) -> Outcome {
    let frames = frames(count);
    let line = line(&frames);
    let stats = RxStats::new();
    let mut storage = InterruptRing::<INTERRUPT_RX_RING_ENTRIES>::new();
    let (mut writer, mut reader) = storage.split(&stats);
    let mut receiver = RequestReceiver::new();
    let (mut seqs, mut bad_frames, mut stalls) = (Vec::new(), 0, Vec::new());
    // The data register: the byte waiting in it, and whether a later byte overran it.
    let mut data_register: Option<u8> = None;
    let mut overrun = false;
    let mut next = 0;
    let mut t = 0u64;
    let in_stall = |stalls: &[(u64, u64)], at: u64| stalls.iter().any(|&(a, b)| a <= at && at < b);
    loop {
        while next < line.len() && line[next].0 <= t {
            let (at, byte) = line[next];
            // The handler runs at once unless the CPU is stalled on flash at that moment; a stall
            // that ended before `at` has already let the handler empty the register.
            if !in_stall(&stalls, at) {
                if let Some(waiting) = data_register.take() {
                    writer.push(
                        waiting,
                        LineErrors {
                            overrun: std::mem::take(&mut overrun),
                            ..LineErrors::default()
                        },
                    );
                }
            }
            if data_register.is_some() {
                overrun = true;
            } else {
                data_register = Some(byte);
            }
            if !in_stall(&stalls, at) {
                if let Some(waiting) = data_register.take() {
                    writer.push(
                        waiting,
                        LineErrors {
                            overrun: std::mem::take(&mut overrun),
                            ..LineErrors::default()
                        },
                    );
                }
            }
            next += 1;
        }
        if !in_stall(&stalls, t) {
            if let Some(waiting) = data_register.take() {
                writer.push(
                    waiting,
                    LineErrors {
                        overrun: std::mem::take(&mut overrun),
                        ..LineErrors::default()
                    },
                );
            }
        }
        let mut served = None;
        for item in reader.by_ref() {
            match receiver.push(item) {
                Some(Ok(request)) => {
                    seqs.push(request.seq);
                    served = Some(request.seq);
                    break;
                }
                Some(Err(_)) => bad_frames += 1,
                None => {}
            }
        }
        match served {
            Some(seq) => t = serve(t, seq, &mut stalls),
            None if !reader.is_empty() || data_register.is_some() => {}
            None if next == line.len() => break,
            None => t = t.max(line[next].0),
        }
    }
    Outcome {
        seqs,
        lost_frames: receiver.lost_frames(),
        stats: stats.snapshot(INTERRUPT_RX_RING_ENTRIES - 1, receiver.lost_frames()),
        bad_frames,
        stalls,
    }
}

/// 10 minutes of frames: 10 saves, each at the erase's and the programming's maximum.
const FRAMES: u32 = 600;

#[test]
fn the_dma_path_receives_every_frame_through_every_worst_case_flash_stall() {
    let out = run_dma(FRAMES);
    assert_eq!(out.stalls.len(), (FRAMES / SAVE_EVERY_FRAMES) as usize);
    assert_eq!(
        out.seqs,
        (1..=FRAMES).collect::<Vec<_>>(),
        "every frame, in order"
    );
    assert_eq!((out.lost_frames, out.bad_frames), (0, 0));
    assert_eq!(out.stats.buffer_overruns, 0);
    // The most that waited at once: the frames sent during a stall (4.26 s: 5 frames) and no more
    // than half the buffer, the reader's contract.
    let frame_bytes = frames(1)[0].len() as u32;
    println!(
        "DMA ring: peak {} bytes waiting ({} frames of {frame_bytes} bytes) of {DMA_RX_BUFFER_BYTES}",
        out.stats.rx_peak_bytes,
        out.stats.rx_peak_bytes as f64 / frame_bytes as f64
    );
    assert!(
        out.stats.rx_peak_bytes >= 4 * frame_bytes,
        "the stalls must have let frames queue up"
    );
    assert!(out.stats.rx_peak_bytes as usize <= DMA_RX_BUFFER_BYTES / 2);
}

#[test]
fn the_iwdg_outlasts_the_longest_stall_at_the_fastest_lsi() {
    let (shortest_ms, longest_ms) = iwdg_timeout_range_ms(STM32F405_IWDG_TIMEOUT_MS);
    assert_eq!((shortest_ms, longest_ms), (6_808, 18_823));
    let stall_ms = (STEP_NS + ANSWER_NS + ERASE_MAX_NS + PROGRAM_MAX_NS) / 1_000_000;
    assert_eq!(stall_ms, 4_271);
    assert!(u64::from(shortest_ms) > stall_ms);
}

#[test]
fn the_interrupt_path_would_lose_the_frames_sent_during_a_flash_stall_on_silicon() {
    let out = run_interrupt(FRAMES);
    // Each stall of 4.26 s swallows the 4 frames sent in it (all but the first byte of the first,
    // which waits in the data register); the last save comes after the last frame.
    println!(
        "interrupt path on silicon's timeline: {} of {FRAMES} frames received, {} lost, {} UART overruns, {} bad frames",
        out.seqs.len(),
        out.lost_frames,
        out.stats.uart_overruns,
        out.bad_frames
    );
    assert_eq!(out.lost_frames, 4 * (out.stalls.len() as u32 - 1));
    assert_eq!(out.seqs.len() as u32 + out.lost_frames, FRAMES);
    assert_eq!(
        out.stats.uart_overruns,
        out.stalls.len() as u32 - 1,
        "one ORE a stall"
    );
}

#[test]
fn without_stalls_the_interrupt_path_receives_every_frame() {
    // The same timeline with saves never due: what QEMU's machines give the interrupt path.
    let frames_count = SAVE_EVERY_FRAMES - 1;
    let out = run_interrupt(frames_count);
    assert!(out.stalls.is_empty());
    assert_eq!(out.seqs, (1..=frames_count).collect::<Vec<_>>());
    assert_eq!(
        (
            out.lost_frames,
            out.stats.uart_overruns,
            out.stats.buffer_overruns
        ),
        (0, 0, 0)
    );
}
