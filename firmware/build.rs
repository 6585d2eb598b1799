//! Puts the repository's `memory.x` (the board's memory map) where cortex-m-rt's `link.x` finds it,
//! and links with `link.x` and `defmt.x`. Set per crate, not through RUSTFLAGS, which CI may replace.
//!
//! Also fixes the checkpoint interval: `RINS_CHECKPOINT_INTERVAL_S` at build time (whole seconds of
//! sample time, 1 to 86400; default 60), checked here so that a bad value fails the build with a
//! message, and written to `OUT_DIR/checkpoint_interval.rs` for `service.rs`.
use std::path::PathBuf;

/// The checkpoint interval's environment variable, its default and its bounds, s.
const INTERVAL_VAR: &str = "RINS_CHECKPOINT_INTERVAL_S";
const INTERVAL_DEFAULT_S: u32 = 60;
const INTERVAL_RANGE_S: std::ops::RangeInclusive<u32> = 1..=86_400;

fn checkpoint_interval_s() -> u32 {
    let Some(value) = std::env::var_os(INTERVAL_VAR) else {
        return INTERVAL_DEFAULT_S;
    };
    let parsed = value.to_str().and_then(|v| v.trim().parse::<u32>().ok());
    match parsed {
        Some(s) if INTERVAL_RANGE_S.contains(&s) => s,
        _ => {
            eprintln!(
                "{INTERVAL_VAR}={value:?}: the checkpoint interval must be whole seconds from {} to {}",
                INTERVAL_RANGE_S.start(),
                INTERVAL_RANGE_S.end()
            );
            std::process::exit(1);
        }
    }
}

fn main() {
    // On the host (`cargo test --workspace`) the crate is an empty program: nothing to link.
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-env-changed={INTERVAL_VAR}");
    let interval = format!(
        "/// Seconds of sample time between checkpoints (`{INTERVAL_VAR}` at build time, default {INTERVAL_DEFAULT_S}).\n\
         pub const CHECKPOINT_INTERVAL_S: u32 = {};\n",
        checkpoint_interval_s()
    );
    std::fs::write(out.join("checkpoint_interval.rs"), interval).expect("write checkpoint_interval.rs");
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let memory_x = manifest.join("..").join("memory.x");
    std::fs::copy(&memory_x, out.join("memory.x")).expect("copy memory.x from the repository root");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
