//! Puts the repository's `memory.x` (the board's memory map) where cortex-m-rt's `link.x` finds it,
//! and links with `link.x` and `defmt.x`. Set per crate, not through RUSTFLAGS, which CI may replace.
use std::path::PathBuf;

fn main() {
    // On the host (`cargo test --workspace`) the crate is an empty program: nothing to link.
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let memory_x = manifest.join("..").join("memory.x");
    std::fs::copy(&memory_x, out.join("memory.x")).expect("copy memory.x from the repository root");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
