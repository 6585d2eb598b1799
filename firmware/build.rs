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
//!   allows; default 8 MHz), written to `OUT_DIR/board_clock.rs` for `board/stm32f405.rs`;
//! - the estimator's configuration beyond the defaults, written to `OUT_DIR/estimator_config.rs`
//!   for the library's `estimator_config.rs`: `RINS_ANGLE_LATENCY_MS` (how long before each
//!   sample's time its rotation angle was read, whole milliseconds 0 to 1000; default 0) and known
//!   values of the installation errors, `RINS_PRIOR_ARCSEC` (`x1,x2,x3,x4`) with
//!   `RINS_PRIOR_SIGMA_ARCSEC` (one 1-sigma or four, each above 0 and at most 1000 arcsec; both or
//!   neither).
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

/// The comma-separated numbers in `var` (`None` if unset); fails the build on anything else.
fn numbers(var: &str) -> Option<Vec<f64>> {
    println!("cargo:rerun-if-env-changed={var}");
    let value = std::env::var_os(var)?;
    let parsed: Option<Vec<f64>> = value.to_str().and_then(|v| {
        v.split(',')
            .map(|x| x.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect()
    });
    match parsed {
        Some(v) => Some(v),
        None => {
            eprintln!("{var}={value:?}: comma-separated finite numbers expected");
            std::process::exit(1);
        }
    }
}

/// The estimator's settings beyond the defaults (see the module doc), as Rust source.
fn estimator_config() -> String {
    let latency_ms = setting(
        "RINS_ANGLE_LATENCY_MS",
        0,
        0..=1000,
        "the rotation angle's latency, milliseconds,",
    );
    let prior = match (
        numbers("RINS_PRIOR_ARCSEC"),
        numbers("RINS_PRIOR_SIGMA_ARCSEC"),
    ) {
        (None, None) => "None".to_string(),
        (Some(x), Some(s)) => {
            let sigma = match s.as_slice() {
                [one] => vec![*one; 4],
                _ => s.clone(),
            };
            let ok = x.len() == 4
                && x.iter().all(|v| v.abs() <= 200_000.0)
                && sigma.len() == 4
                && sigma.iter().all(|v| *v > 0.0 && *v <= 1000.0);
            if !ok {
                eprintln!(
                    "RINS_PRIOR_ARCSEC={x:?} RINS_PRIOR_SIGMA_ARCSEC={s:?}: four values x1..x4 in arcsec and one 1-sigma or four, each above 0 and at most 1000 arcsec"
                );
                std::process::exit(1);
            }
            format!(
                "Some(([{:?}, {:?}, {:?}, {:?}], [{:?}, {:?}, {:?}, {:?}]))",
                x[0], x[1], x[2], x[3], sigma[0], sigma[1], sigma[2], sigma[3]
            )
        }
        _ => {
            eprintln!(
                "RINS_PRIOR_ARCSEC and RINS_PRIOR_SIGMA_ARCSEC go together: set both or neither"
            );
            std::process::exit(1);
        }
    };
    format!(
        "/// How long before each sample's time its rotation angle was read, s (`RINS_ANGLE_LATENCY_MS` at build time, default 0).\n\
         pub const ANGLE_LATENCY_S: f64 = {:?};\n\
         /// Known values of x1..x4 and their 1-sigma, arcsec (`RINS_PRIOR_ARCSEC`, `RINS_PRIOR_SIGMA_ARCSEC` at build time; default none).\n\
         pub const PRIOR_ARCSEC: Option<([f64; 4], [f64; 4])> = {prior};\n",
        f64::from(latency_ms) / 1000.0
    )
}

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::write(out.join("estimator_config.rs"), estimator_config())
        .expect("write estimator_config.rs");
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
