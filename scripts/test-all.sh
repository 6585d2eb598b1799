#!/usr/bin/env bash
# Runs every test of the project on a fresh machine, installing what is missing first:
#   1. the thumbv7em-none-eabihf Rust target, flip-link (the firmware's linker, cargo install),
#      qemu-system-arm and GNU time (apt), if absent;
#   2. `cargo test --workspace --release`: estimator-core, link-protocol, host-sim (including the
#      QEMU end-to-end tests, which build the firmware for both boards themselves: mps2-an386 and
#      the STM32F405 on QEMU's netduinoplus2);
#   3. estimator-core again with the `f64` feature (the precision comparison's other side);
#   4. the firmware build for the target: mps2-an386 with and without its checkpoint feature, and
#      the STM32F405 (their budgets are checked by host-sim's qemu_budgets test);
#   5. clippy on the firmware (each board) and the link code, which deny every panicking construct;
#   6. the 30-day replay's peak memory (scripts/memory-30day.sh: at most 64 MB, GNU time);
#   7. that the tests left no trace: `git status --porcelain` at the end equals the one at the start.
# Usage: bash scripts/test-all.sh
set -euo pipefail
cd "$(dirname "$0")/.."

log() { printf '\n== %s\n' "$*"; }

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
# The firmware's linker (.cargo/config.toml): puts the stack below the statics.
if ! command -v flip-link >/dev/null 2>&1; then
    cargo install --locked flip-link
fi
MISSING=""
if ! command -v qemu-system-arm >/dev/null 2>&1; then MISSING="$MISSING qemu-system-arm"; fi
if [ ! -x /usr/bin/time ]; then MISSING="$MISSING time"; fi
if [ -n "$MISSING" ]; then
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
    $SUDO apt-get update -q
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q $MISSING
fi
qemu-system-arm --version | head -n 1
cargo --version

log "every crate's tests (release): estimator-core, link-protocol, host-sim (with the QEMU end-to-end tests), firmware (empty on the host)"
cargo test --workspace --release

log "estimator-core with f64"
cargo test --release -p estimator-core --features f64

log "firmware build for thumbv7em-none-eabihf (mps2-an386 default, without its checkpoint feature; STM32F405)"
cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware --no-default-features --features board-mps2-an386
cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware --no-default-features --features board-stm32f405
cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware

log "no panicking path on the link: clippy's deny(unwrap_used, expect_used, indexing_slicing, panic)"
# The firmware, link-protocol and estimator-core deny these lints in their sources; only clippy
# enforces them, so it runs here (warnings of other lints do not fail the run).
cargo clippy -p firmware -p link-protocol --target thumbv7em-none-eabihf --profile firmware
cargo clippy -p firmware --target thumbv7em-none-eabihf --profile firmware --no-default-features --features board-stm32f405

log "peak memory of a 30-day replay"
bash scripts/memory-30day.sh

log "the tests left no trace in the checkout"
STATUS_AFTER="$(git_status)"
if [ "$STATUS_BEFORE" != "$STATUS_AFTER" ]; then
    echo "git status changed during the tests:"
    diff <(printf '%s\n' "$STATUS_BEFORE") <(printf '%s\n' "$STATUS_AFTER") || true
    exit 1
fi
echo "git status unchanged"
