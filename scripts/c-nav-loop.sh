#!/usr/bin/env bash
# Builds examples/c/nav_loop.c (the estimator in a 1 Hz navigation loop, with checkpoints and a
# power cut) for a Cortex-M4F with arm-none-eabi-gcc and newlib, runs it in QEMU mps2-an386, and
# prints what the C library adds to that firmware: its flash and static RAM, summed from the
# linker map over the sections taken from libestimator_ffi.a, and the program's deepest stack
# (measured at run time by examples/c/mps2-an386/startup.c). The run fails unless the loop finds
# the simulated installation errors within 1 arcsec. When `bash scripts/c-example.sh --qemu` has
# built replay.c, the same figures are printed for it (it also formats rows and reads numbers).
#
#   bash scripts/c-nav-loop.sh
#
# Needs what `scripts/c-example.sh --qemu` needs. The build goes to target/c-example/mps2-an386/.
set -euo pipefail
cd "$(dirname "$0")/.."

for tool in arm-none-eabi-gcc qemu-system-arm; do
    command -v "$tool" >/dev/null || { echo "error: $tool not found (apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm)" >&2; exit 2; }
done
cargo build -q -p estimator-ffi --target thumbv7em-none-eabihf --profile firmware
DIR=target/c-example/mps2-an386
mkdir -p "$DIR"
arm-none-eabi-gcc -std=c11 -O2 -Wall -Wextra -pedantic -Iestimator-ffi/include \
    -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 \
    -ffunction-sections -fdata-sections --specs=rdimon.specs -nostartfiles \
    -T examples/c/mps2-an386/link.ld -Wl,--gc-sections -Wl,-z,noexecstack -Wl,-Map="$DIR/nav_loop.map" \
    -o "$DIR/nav_loop.elf" examples/c/mps2-an386/startup.c examples/c/nav_loop.c \
    -lm -lc target/thumbv7em-none-eabihf/firmware/libestimator_ffi.a
timeout 300 qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -icount shift=0 -display none -monitor none -serial none \
    -semihosting-config enable=on,target=native -kernel "$DIR/nav_loop.elf" < /dev/null

# Bytes of the sections a linker map says were taken from libestimator_ffi.a: flash (code,
# constants, initial values of data) and RAM (data, zeroed data).
library_bytes() {
    awk '
        /^Linker script and memory map/ { on = 1; next }
        !on { next }
        /^ \.[^ ]+$/ { name = $1; next }
        /^ \.[^ ]+ +0x/ { name = $1; size = $3; file = $4 }
        /^ +0x[0-9a-f]+ +0x[0-9a-f]+ / { size = $2; file = $3 }
        name != "" && size != "" {
            if (file ~ /libestimator_ffi\.a/) {
                n = strtonum_(size)
                if (name ~ /^\.(text|rodata|ARM)/) flash += n
                else if (name ~ /^\.data/) { flash += n; ram += n }
                else if (name ~ /^\.bss/) ram += n
            }
            name = ""; size = ""
        }
        function strtonum_(h,   i, c, v) { v = 0; h = tolower(substr(h, 3)); for (i = 1; i <= length(h); i++) { c = index("0123456789abcdef", substr(h, i, 1)) - 1; v = v * 16 + c } return v }
        END { printf "%d %d\n", flash, ram }
    ' "$1"
}

for program in nav_loop replay; do
    [ -f "$DIR/$program.map" ] && [ -f "$DIR/$program.elf" ] || continue
    read -r flash ram < <(library_bytes "$DIR/$program.map")
    echo "$program.elf: the library adds $flash bytes of flash and $ram bytes of static RAM;" \
        "the whole program: $(arm-none-eabi-size -B "$DIR/$program.elf" | awk 'NR == 2 { printf "text %d, data %d, bss %d bytes", $1, $2, $3 }')"
    # Calls into Rust's panic machinery from the library's own code (core's float formatting and
    # parsing have their own, unreachable by construction): a bound or a divisor the optimiser
    # could not prove safe would leave one. There must be none: no panic path is reachable from
    # the C API.
    sites="$(arm-none-eabi-objdump -d -C "$DIR/$program.elf" \
        | awk '/^[0-9a-f]+ <.*>:$/ { fn = substr($0, index($0, "<")) } /bl.*<core::(panicking|slice::index)/ && fn !~ /^<+core::/ { n[fn]++; total++ }
               END { printf "%d", total; for (f in n) printf "; %s %d", f, n[f] }')"
    echo "  panic call sites in the library's code: $sites"
    if [ "${sites%%;*}" != 0 ]; then
        echo "error: $program.elf: the library's code can reach Rust's panic handler: $sites" >&2
        exit 1
    fi
done
