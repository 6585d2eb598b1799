#!/usr/bin/env bash
# Runs every test of the project on a fresh machine, installing what is missing first:
#   1. the thumbv7em-none-eabihf Rust target, flip-link (the firmware's linker, cargo install),
#      qemu-system-arm, GNU time, and the ARM C toolchain with newlib (gcc-arm-none-eabi,
#      libnewlib-arm-none-eabi) for the C examples (apt), if absent;
#   2. `cargo test --workspace --release` (the target's builds of step 4 and the C library run
#      meanwhile in the background): estimator-core, estimator-ffi (the C library: its API,
#      and that the checked-in C header is the one its sources generate), link-protocol, the
#      firmware's library on the host (the checkpoint store, receive rings, the STM32F405's receive
#      timeline), host-sim (including the QEMU end-to-end tests, which build the firmware for both
#      boards themselves: mps2-an386 and the STM32F405 on QEMU's netduinoplus2, and the watchdog
#      test's build);
#   3. estimator-core again with the `f64` feature (the precision comparison's other side): its unit
#      tests, the identification against known errors and the checkpoints, which the feature
#      changes (float width, state size, image length); link-protocol without the `test-hang`
#      feature that host-sim's tests turn on (the production wire, where `Hang` is a bad frame);
#   4. the firmware build for the target: mps2-an386 with and without its checkpoint feature, and
#      the STM32F405 (their budgets are checked by host-sim's qemu_budgets test);
#   5. the gates: `cargo fmt --all --check`; clippy with -D warnings on the host (every crate, all
#      targets, in release) and on the firmware (each board), the link code and the C library, which deny every
#      panicking construct (the workspace's lints, `[workspace.lints]`, apply to every crate);
#      the API docs, `RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --release` (a broken
#      intra-doc link, or an undocumented public item of a library crate, fails);
#   5b. the C examples: examples/c/replay.c on a short log with every kind of bad row, built with
#      the host's cc and with arm-none-eabi-gcc for a Cortex-M4F run in QEMU, both estimates
#      CSVs byte-identical to `host-sim estimate`'s (scripts/c-example.sh); the 1 Hz navigation
#      loop examples/c/nav_loop.c in QEMU (scripts/c-nav-loop.sh);
#   6. the 30-day replay's peak memory (scripts/memory-30day.sh: at most 64 MB, GNU time);
#   7. that the tests left no trace: `git status --porcelain` at the end equals the one at the start.
# Usage: bash scripts/test-all.sh
set -euo pipefail
cd "$(dirname "$0")/.."
# Nothing reads the terminal: cargo's compiler probes (`rustc -`) and every tool get an empty
# standard input, whatever the caller's is.
exec < /dev/null

log() { printf "\n== %s (at %d s)\n" "$*" "$SECONDS"; }

# Tests leave no trace: what git sees now must be what it sees at the end.
git_status() { git status --porcelain --untracked-files=all 2>/dev/null || true; }
STATUS_BEFORE="$(git_status)"

log "toolchain"
if ! rustup target list --installed | grep -qx thumbv7em-none-eabihf; then
    rustup target add thumbv7em-none-eabihf
fi
if ! cargo clippy --version >/dev/null 2>&1; then
    rustup component add clippy
fi
if ! cargo fmt --version >/dev/null 2>&1; then
    rustup component add rustfmt
fi
# The firmware's linker (.cargo/config.toml): puts the stack below the statics.
if ! command -v flip-link >/dev/null 2>&1; then
    cargo install --locked flip-link
fi
MISSING=""
if ! command -v qemu-system-arm >/dev/null 2>&1; then MISSING="$MISSING qemu-system-arm"; fi
if [ ! -x /usr/bin/time ]; then MISSING="$MISSING time"; fi
if ! command -v arm-none-eabi-gcc >/dev/null 2>&1 || [ ! -f /usr/lib/arm-none-eabi/newlib/rdimon.specs ]; then
    MISSING="$MISSING gcc-arm-none-eabi libnewlib-arm-none-eabi"
fi
if [ -n "$MISSING" ]; then
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
    $SUDO apt-get update -q
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q $MISSING
fi
qemu-system-arm --version | head -n 1
arm-none-eabi-gcc --version | head -n 1
cargo --version

log "every crate's tests (release): estimator-core, estimator-ffi, link-protocol, firmware (its library on the host), host-sim (with the QEMU end-to-end tests)"
# Meanwhile, the builds for the target (their own lock in target/, and mostly one core each: fat
# LTO into one codegen unit): the firmware for each board, as the QEMU tests and step 4 build it
# (mps2-an386 with and without checkpoints, its watchdog test's build, the STM32F405), and the C
# library. The QEMU tests and the C examples then find them built.
THUMB_LOG="$(mktemp)"
(
    set -e
    firmware() { cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware "$@"; }
    firmware
    firmware --no-default-features --features board-stm32f405
    firmware --features test-hang
    firmware --no-default-features --features board-mps2-an386
    cargo build -p estimator-ffi --target thumbv7em-none-eabihf --profile firmware
) > "$THUMB_LOG" 2>&1 &
THUMB_BUILDS=$!
cargo test --workspace --release --no-run
if ! wait "$THUMB_BUILDS"; then
    cat "$THUMB_LOG"
    echo "building for thumbv7em-none-eabihf failed" >&2
    exit 1
fi
rm -f "$THUMB_LOG"
log "running them"
cargo test --workspace --release

# Meanwhile, clippy on the target's builds (the firmware for each board, the link and the C library;
# their own lock in target/, as in step 2): the gates below wait for them.
THUMB_LINT_LOG="$(mktemp)"
(
    set -e
    cargo clippy -p firmware -p link-protocol --target thumbv7em-none-eabihf --profile firmware -- -D warnings
    cargo clippy -p firmware --target thumbv7em-none-eabihf --profile firmware --no-default-features --features board-stm32f405 -- -D warnings
    cargo clippy -p estimator-ffi --target thumbv7em-none-eabihf --profile firmware -- -D warnings
) > "$THUMB_LINT_LOG" 2>&1 &
THUMB_LINTS=$!

log "estimator-core with f64: its unit tests, the identification and the checkpoints (what the feature changes)"
cargo test --release -p estimator-core --features f64 --lib --test identification --test checkpoint_roundtrip
log "link-protocol without its test-hang feature (the workspace's tests turn it on): Hang's bytes are a bad frame"
cargo test --release -p link-protocol

log "firmware build for thumbv7em-none-eabihf (mps2-an386 default, without its checkpoint feature; STM32F405)"
# Built in step 2's background; these find them built (the default image again after the QEMU
# tests' build with another checkpoint interval).
cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware --no-default-features --features board-mps2-an386
cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware --no-default-features --features board-stm32f405
cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware

log "gates: rustfmt, clippy with every warning an error (host, all targets; the firmware for each board, the link and the C library for the target), and the API docs"
# Clippy also enforces what the firmware, link-protocol, estimator-ffi and estimator-core deny in
# their sources: unwrap_used, expect_used, indexing_slicing, panic (no panicking path on the link or
# through the C API); the workspace's [workspace.lints] apply to every crate.
cargo fmt --all --check
# In release: the proc-macros and build scripts are those step 2 built. The `bench` feature brings
# host-sim's benchmarks (and criterion) in, which the test build leaves out.
cargo clippy --workspace --all-targets --release --features host-sim/bench -- -D warnings
# The target's clippy, started after step 2 (the firmware for each board, the link and the C library).
if ! wait "$THUMB_LINTS"; then
    cat "$THUMB_LINT_LOG"
    echo "clippy for thumbv7em-none-eabihf failed" >&2
    exit 1
fi
cat "$THUMB_LINT_LOG"
rm -f "$THUMB_LINT_LOG"
# Every library crate has #![warn(missing_docs)]; with -D warnings an undocumented public item or a
# link that does not resolve fails here. In release: the dependencies' metadata are those the
# host's clippy just checked (in the dev profile they would all be checked again).
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --release

log "the C library: examples/c/replay.c on the host and on a Cortex-M4F in QEMU, byte-identical to host-sim estimate"
# A 1500 s sea log with Unix stamps, jitter and lost rows, then everything a trial's export may
# hold: comments, a byte-order mark, \r\n line ends, a blank line, spaces around cells, an
# unreadable cell, a truncated row, a repeated row and a NaN (rejected by the estimator).
C_DIR="$(mktemp -d)"
target/release/host-sim generate --scenario sea --duration 1500 --drop-fraction 0.01 --time-offset 1.7e9 \
    --time-jitter 0.02 --out "$C_DIR/clean.csv" > /dev/null
awk 'BEGIN { ORS = "\r\n" }
    function cell(k, v,   f, n, i) { n = split($0, f, ","); f[k] = v; $0 = f[1]; for (i = 2; i <= n; i++) $0 = $0 "," f[i] }
    NR == 1 { print "# exported by the trial recorder"; print ""; printf "\xef\xbb\xbf"; print; next }
    NR == 300 { print "# operator: heading reference changed" }
    NR == 400 { cell(6, "x") }
    NR == 500 { print prev }
    NR == 600 { cell(6, "nan") }
    NR == 700 { print "   " }
    NR == 800 { gsub(/,/, " , ") }
    NR == 900 { $0 = substr($0, 1, 40) }
    { print; prev = $0 }' "$C_DIR/clean.csv" > "$C_DIR/trial.csv"
target/release/host-sim estimate "$C_DIR/trial.csv" --out "$C_DIR/host-sim.csv" > /dev/null
bash scripts/c-example.sh "$C_DIR/trial.csv" "$C_DIR/c-host.csv"
bash scripts/c-example.sh --qemu "$C_DIR/trial.csv" "$C_DIR/c-qemu.csv"
# The comparison covers estimates and rejected rows, not only the warm-up.
grep -q ',rejected_non_finite,' "$C_DIR/host-sim.csv" && grep -Eq ',(estimating|converged),' "$C_DIR/host-sim.csv"
cmp "$C_DIR/host-sim.csv" "$C_DIR/c-host.csv"
cmp "$C_DIR/host-sim.csv" "$C_DIR/c-qemu.csv"
echo "host and Cortex-M4F (QEMU): $(($(wc -l < "$C_DIR/c-qemu.csv") - 1)) rows, byte-identical to host-sim estimate"
# The same log with its time in milliseconds, ';' separators and header names in capitals with
# spaces; and in ISO 8601 UTC (some rows with an offset) with tab separators.
awk -v MODE=ms -f scripts/log-time-variants.awk "$C_DIR/clean.csv" > "$C_DIR/ms.csv"
awk -v MODE=utc -f scripts/log-time-variants.awk "$C_DIR/clean.csv" > "$C_DIR/utc.csv"
for variant in ms utc; do
    target/release/host-sim estimate "$C_DIR/$variant.csv" --out "$C_DIR/$variant.host-sim.csv" > /dev/null
    bash scripts/c-example.sh "$C_DIR/$variant.csv" "$C_DIR/$variant.c-host.csv"
    cmp "$C_DIR/$variant.host-sim.csv" "$C_DIR/$variant.c-host.csv"
done
bash scripts/c-example.sh --qemu "$C_DIR/utc.csv" "$C_DIR/utc.c-qemu.csv"
cmp "$C_DIR/utc.host-sim.csv" "$C_DIR/utc.c-qemu.csv"
grep -Eq ',(estimating|converged),' "$C_DIR/utc.c-qemu.csv"
echo "time_ms with ';' and time_utc with tabs: host and Cortex-M4F byte-identical to host-sim estimate"
rm -rf "$C_DIR"
# The 1 Hz navigation loop of docs/c-api.md on the Cortex-M4F: finds known errors within 1 arcsec
# through a power cut and a restored checkpoint; prints the library's flash, RAM and stack.
bash scripts/c-nav-loop.sh

log "peak memory of a 30-day replay"
HOST_SIM=target/release/host-sim bash scripts/memory-30day.sh

log "the tests left no trace in the checkout"
STATUS_AFTER="$(git_status)"
if [ "$STATUS_BEFORE" != "$STATUS_AFTER" ]; then
    echo "git status changed during the tests:"
    diff <(printf '%s\n' "$STATUS_BEFORE") <(printf '%s\n' "$STATUS_AFTER") || true
    exit 1
fi
echo "git status unchanged"
echo "every test passed in $SECONDS s"
