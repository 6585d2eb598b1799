//! The defmt global logger of the one STM32F405 image: RTT on silicon (channel "defmt", read by a
//! debug probe: `probe-rs run` decodes it), semihosting under QEMU (QEMU's stdout, as on
//! mps2-an386). defmt allows one global logger per image and defmt-rtt and defmt-semihosting each
//! are one, so this logger owns the encoder and sends each frame's bytes to RTT (rtt-target's
//! channel) or to semihosting (the `semihosting` crate's stdout), by [`super::environment`].
//! Neither path is touched in the other environment: semihosting on silicon without a debugger
//! would halt the core on its breakpoint instruction.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

use rtt_target::{rtt_init, ChannelMode, UpChannel};
use semihosting::io::{Stdout, Write as _};

use super::Environment;

#[defmt::global_logger]
struct Logger;

/// Bytes of the RTT buffer: a few boot lines at 168 MHz before a probe attaches.
const RTT_BUFFER_BYTES: usize = 1024;

struct State {
    /// Set between `acquire` and `release`.
    taken: AtomicBool,
    /// Set while a nested `acquire` (a fault inside a log call) is being ignored.
    nested: AtomicBool,
    cs_restore: UnsafeCell<critical_section::RestoreState>,
    encoder: UnsafeCell<defmt::Encoder>,
    sink: UnsafeCell<Sink>,
}

/// Where the bytes go, opened on the first log call.
enum Sink {
    Unopened,
    Rtt(UpChannel),
    Semihosting(Stdout),
    Nowhere,
}

// SAFETY: every access to the cells happens inside the critical section taken in `acquire`.
unsafe impl Sync for State {}

static STATE: State = State {
    taken: AtomicBool::new(false),
    nested: AtomicBool::new(false),
    cs_restore: UnsafeCell::new(critical_section::RestoreState::invalid()),
    encoder: UnsafeCell::new(defmt::Encoder::new()),
    sink: UnsafeCell::new(Sink::Unopened),
};

/// The RTT control block and its one up channel. Called at most once (rtt_init! must be).
fn open_rtt() -> UpChannel {
    let channels = rtt_init! {
        up: {
            0: {
                size: RTT_BUFFER_BYTES,
                mode: ChannelMode::NoBlockSkip,
                name: "defmt"
            }
        }
    };
    channels.up.0
}

fn sink_write(sink: &mut Sink, bytes: &[u8]) {
    match sink {
        Sink::Rtt(channel) => {
            channel.write(bytes);
        }
        Sink::Semihosting(stdout) => {
            let _ = stdout.write_all(bytes);
        }
        Sink::Unopened | Sink::Nowhere => {}
    }
}

unsafe impl defmt::Logger for Logger {
    fn acquire() {
        // SAFETY: paired with the `release` in `Logger::release`.
        let restore = unsafe { critical_section::acquire() };
        if STATE.taken.load(Ordering::Relaxed) {
            // A fault while a frame was being written: drop the nested frame, keep the outer one.
            STATE.nested.store(true, Ordering::Relaxed);
            // SAFETY: releases the critical section just acquired.
            unsafe { critical_section::release(restore) };
            return;
        }
        STATE.taken.store(true, Ordering::Relaxed);
        // SAFETY: inside the critical section, and the logger is not taken.
        unsafe {
            STATE.cs_restore.get().write(restore);
            let sink = &mut *STATE.sink.get();
            if matches!(sink, Sink::Unopened) {
                *sink = match super::environment() {
                    Environment::Silicon => Sink::Rtt(open_rtt()),
                    Environment::Qemu => {
                        semihosting::io::stdout().map_or(Sink::Nowhere, Sink::Semihosting)
                    }
                };
            }
            let encoder = &mut *STATE.encoder.get();
            encoder.start_frame(|b| sink_write(sink, b));
        }
    }

    unsafe fn flush() {}

    unsafe fn release() {
        if STATE.nested.swap(false, Ordering::Relaxed) || !STATE.taken.load(Ordering::Relaxed) {
            return;
        }
        // SAFETY: inside the critical section taken by `acquire`.
        unsafe {
            let sink = &mut *STATE.sink.get();
            let encoder = &mut *STATE.encoder.get();
            encoder.end_frame(|b| sink_write(sink, b));
            let restore = STATE.cs_restore.get().read();
            STATE.taken.store(false, Ordering::Relaxed);
            critical_section::release(restore);
        }
    }

    unsafe fn write(bytes: &[u8]) {
        if STATE.nested.load(Ordering::Relaxed) || !STATE.taken.load(Ordering::Relaxed) {
            return;
        }
        // SAFETY: inside the critical section taken by `acquire`.
        unsafe {
            let sink = &mut *STATE.sink.get();
            let encoder = &mut *STATE.encoder.get();
            encoder.write(bytes, |b| sink_write(sink, b));
        }
    }
}
