//! Puts the board's memory map (`boards/BOARD/memory.x`, by the board feature) on the link path as
//! `board-memory.x`, which the repository's `memory.x` includes (cortex-m-rt's `link.x` includes
//! `memory.x`, and the linker finds the one in the workspace root first), and links with `link.x`
//! and `defmt.x`. Set per crate, not through RUSTFLAGS, which CI
//! may replace.
//!
//! Also fixes two build-time settings, each checked here so that a bad value fails the build with a
//! message:
//! - the checkpoint interval: `RINS_CHECKPOINT_INTERVAL_S` (whole seconds of sample time, 1 to
//!   86400; default 300), written to `OUT_DIR/checkpoint_interval.rs` for the library's
//!   `checkpoint_store.rs` (for the host too: `host-sim flash-life` takes its default from it);
//! - the STM32F405's crystal: `RINS_HSE_HZ` (the HSE frequency in Hz, 4 to 26 MHz as the part
//!   allows; default 8 MHz), written to `OUT_DIR/board_clock.rs` for `board/stm32f405.rs`.
use std::path::PathBuf;

/// The checkpoint interval's environment variable, its default and its bounds, s.
const INTERVAL_VAR: &str = "RINS_CHECKPOINT_INTERVAL_S";
const INTERVAL_DEFAULT_S: u32 = 300;
const INTERVAL_RANGE_S: std::ops::RangeInclusive<u32> = 1..=86_400;
/// The STM32F405's HSE crystal: variable, default and the part's range (datasheet: 4 to 26 MHz).
const HSE_VAR: &str = "RINS_HSE_HZ";
const HSE_DEFAULT_HZ: u32 = 8_000_000;
const HSE_RANGE_HZ: std::ops::RangeInclusive<u32> = 4_000_000..=26_000_000;

/// The whole number in `var`, or `default` if unset; fails the build if out of `range`.
fn setting(var: &str, default: u32, range: std::ops::RangeInclusive<u32>, what: &str) -> u32 {
    println!("cargo:rerun-if-env-changed={var}");
    let Some(value) = std::env::var_os(var) else {
        return default;
    };
    let parsed = value.to_str().and_then(|v| v.trim().parse::<u32>().ok());
    match parsed {
        Some(s) if range.contains(&s) => s,
        _ => {
            eprintln!(
                "{var}={value:?}: {what} must be whole {} to {}",
                range.start(),
                range.end()
            );
            std::process::exit(1);
        }
    }
}

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let interval_s = setting(
        INTERVAL_VAR,
        INTERVAL_DEFAULT_S,
        INTERVAL_RANGE_S,
        "the checkpoint interval, seconds,",
    );
    let interval = format!(
        "/// Seconds of sample time between checkpoints (`{INTERVAL_VAR}` at build time, default {INTERVAL_DEFAULT_S}).\n\
         pub const CHECKPOINT_INTERVAL_S: u32 = {interval_s};\n"
    );
    std::fs::write(out.join("checkpoint_interval.rs"), interval)
        .expect("write checkpoint_interval.rs");
    println!("cargo:rerun-if-changed=build.rs");
    // On the host (`cargo test --workspace`, host-sim) only the library is used: nothing to link.
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let hse_hz = setting(
        HSE_VAR,
        HSE_DEFAULT_HZ,
        HSE_RANGE_HZ,
        "the HSE crystal frequency, Hz,",
    );
    let clock = format!(
        "/// The HSE crystal's frequency, Hz (`{HSE_VAR}` at build time, default {HSE_DEFAULT_HZ}).\n\
         pub const HSE_HZ: u32 = {hse_hz};\n"
    );
    std::fs::write(out.join("board_clock.rs"), clock).expect("write board_clock.rs");
    let manifest = PathBuf::from(
        std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"),
    );
    let boards = [
        (
            "CARGO_FEATURE_BOARD_MPS2_AN386",
            manifest.join("boards").join("mps2-an386").join("memory.x"),
        ),
        (
            "CARGO_FEATURE_BOARD_STM32F405",
            manifest.join("boards").join("stm32f405").join("memory.x"),
        ),
    ];
    let selected: Vec<&PathBuf> = boards
        .iter()
        .filter(|(feature, _)| std::env::var_os(feature).is_some())
        .map(|(_, memory_x)| memory_x)
        .collect();
    let [memory_x] = selected[..] else {
        eprintln!(
            "select exactly one board feature: board-mps2-an386 (the default) or, with --no-default-features, board-stm32f405"
        );
        std::process::exit(1);
    };
    std::fs::copy(memory_x, out.join("board-memory.x")).expect("copy the board's memory.x");
    // The same include also when the linker does not run in the workspace root.
    let root_memory_x = manifest.join("..").join("memory.x");
    std::fs::copy(&root_memory_x, out.join("memory.x"))
        .expect("copy memory.x from the repository root");
    println!("cargo:rerun-if-changed={}", root_memory_x.display());
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
