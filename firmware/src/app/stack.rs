//! Stack high-water mark by painting: at boot every free word of the stack region below the
//! current stack pointer (minus a margin for the painting function itself) is set to [`PAINT`];
//! later, the lowest word that no longer holds it is the deepest the stack has reached.
//!
//! The region is cortex-m-rt's: from `_stack_end` (the end of .bss) up to `_stack_start` (the top
//! of RAM, the initial stack pointer).

use core::ptr::{addr_of, read_volatile, write_volatile};

const PAINT: u32 = 0xA5A5_A5A5;
/// Bytes below the stack pointer left unpainted (the painting function's own frame is above SP).
const MARGIN: usize = 64;

extern "C" {
    static _stack_start: u32;
    static _stack_end: u32;
}

fn bottom() -> usize {
    addr_of!(_stack_end) as usize
}

fn top() -> usize {
    addr_of!(_stack_start) as usize
}

/// Paints the unused stack. Call first thing in `main`.
#[inline(never)]
pub fn paint() {
    let sp = cortex_m::register::msp::read() as usize;
    let end = sp.saturating_sub(MARGIN) & !3;
    let mut addr = (bottom() + 3) & !3;
    while addr < end {
        // SAFETY: between the end of .bss and below the live stack: memory nobody uses yet.
        unsafe { write_volatile(addr as *mut u32, PAINT) };
        addr += 4;
    }
}

/// Deepest stack use since boot, bytes.
pub fn peak_bytes() -> u32 {
    let mut addr = (bottom() + 3) & !3;
    let top = top();
    // SAFETY: reads words of the stack region, all of it RAM.
    while addr < top && unsafe { read_volatile(addr as *const u32) } == PAINT {
        addr += 4;
    }
    (top - addr) as u32
}

/// Size of the stack region, bytes.
pub fn size_bytes() -> u32 {
    (top() - bottom()) as u32
}
