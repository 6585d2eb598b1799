#!/usr/bin/env bash
# Builds the C example examples/c/replay.c against the estimator's static library (estimator-ffi)
# and replays an attitude log through it: the estimates CSV it writes is byte for byte what
# `host-sim estimate LOG --out -` writes.
#
#   bash scripts/c-example.sh LOG OUT          # the host's `cc`, target/release/libestimator_ffi.a
#   bash scripts/c-example.sh --qemu LOG OUT   # arm-none-eabi-gcc + newlib for a Cortex-M4F, run in
#                                              # QEMU mps2-an386, standard streams over semihosting
#
# LOG is a plain CSV log (docs/log-format.md); OUT the estimates CSV to write. Warnings and the
# summary go to standard error; the exit status is replay's (0, or 1 for a log without a header).
# The builds go to target/c-example/{host,mps2-an386}/ (with the linker map of each, from which
# docs/c-api.md's flash and RAM figures are taken).
# Needs: cc; for --qemu the thumbv7em-none-eabihf Rust target, Debian's gcc-arm-none-eabi and
# libnewlib-arm-none-eabi, and qemu-system-arm (scripts/test-all.sh installs them when missing).
set -euo pipefail

usage() { echo "usage: bash scripts/c-example.sh [--qemu] LOG OUT" >&2; exit 2; }
QEMU=0
if [ "${1:-}" = "--qemu" ]; then QEMU=1; shift; fi
[ $# -eq 2 ] || usage
LOG="$(realpath "$1")"
OUT="$(realpath -m "$2")"
[ -f "$LOG" ] || { echo "error: $1: no such file" >&2; exit 2; }
[ "$LOG" != "$OUT" ] || { echo "error: OUT would overwrite the log" >&2; exit 2; }
cd "$(dirname "$0")/.."

CFLAGS=(-std=c11 -O2 -Wall -Wextra -pedantic -Iestimator-ffi/include)
if [ "$QEMU" = 0 ]; then
    # The header on its own compiles without a warning as C99 and, where there is a C++
    # compiler, as C++11.
    echo '#include "rins_estimator.h"' | cc -std=c99 -Wall -Wextra -pedantic -Werror -Iestimator-ffi/include -x c -fsyntax-only -
    if command -v c++ >/dev/null; then
        echo '#include "rins_estimator.h"' | c++ -std=c++11 -Wall -Wextra -pedantic -Werror -Iestimator-ffi/include -x c++ -fsyntax-only -
    fi
    cargo build -q -p estimator-ffi --release
    DIR=target/c-example/host
    mkdir -p "$DIR"
    # The libraries the static library needs on x86_64 Linux: std's panic runtime (see
    # estimator-ffi/src/lib.rs), as `rustc --print native-static-libs` lists them.
    cc "${CFLAGS[@]}" -Wl,-Map="$DIR/replay.map" -o "$DIR/replay" examples/c/replay.c \
        target/release/libestimator_ffi.a -lgcc_s -lutil -lrt -lpthread -lm -ldl -lc
    "$DIR/replay" < "$LOG" > "$OUT"
else
    for tool in arm-none-eabi-gcc qemu-system-arm; do
        command -v "$tool" >/dev/null || { echo "error: $tool not found (apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm)" >&2; exit 2; }
    done
    # The firmware profile: the firmware's own optimisation, LTO and panic = abort.
    cargo build -q -p estimator-ffi --target thumbv7em-none-eabihf --profile firmware
    DIR=target/c-example/mps2-an386
    mkdir -p "$DIR"
    arm-none-eabi-gcc "${CFLAGS[@]}" -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 \
        -ffunction-sections -fdata-sections --specs=rdimon.specs -nostartfiles \
        -T examples/c/mps2-an386/link.ld -Wl,--gc-sections -Wl,-z,noexecstack -Wl,-Map="$DIR/replay.map" \
        -o "$DIR/replay.elf" examples/c/mps2-an386/startup.c examples/c/replay.c \
        -lm -lc target/thumbv7em-none-eabihf/firmware/libestimator_ffi.a
    # Semihosting gives the program QEMU's standard streams: the log in, the estimates out.
    timeout 600 qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -display none -monitor none -serial none \
        -semihosting-config enable=on,target=native -kernel "$DIR/replay.elf" < "$LOG" > "$OUT"
fi
