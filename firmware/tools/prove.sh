#!/usr/bin/env bash
# Proves the firmware end to end, on a machine with rustup's thumbv7em-none-eabihf
# target, qemu-system-arm and gcc:
#   1. builds the release ELF (`--profile firmware`) and prints its sizes;
#   2. runs link-protocol's unit tests (round trips, every fault kind);
#   3. runs the QEMU tests: link faults (qemu_faults), `--port` over a QEMU pty (qemu_port), power
#      cuts with checkpoints in flash (qemu_power_cut), the
#      20,000 s end-to-end runs byte-identical to `host-sim estimate` and within 10 arcsec of
#      truth, then a power cut, 200 s of lost rows and a resume (qemu_restart), a lossy pushed
#      log (qemu_e2e), flash/RAM/stack/step budgets (qemu_budgets);
#   4. cross-checks the step cost with an exact instruction count from a TCG plugin
#      (firmware/tools/stepcount.c) over a 6000 s stream of the paper's log, a 12000 s lossy
#      sea log (qemu_e2e's) and an 8000 s course weave with its heel learned, each sample sent
#      after the last answer.
# Every section runs; the script exits non-zero if any failed.
# Usage: bash firmware/tools/prove.sh
set -uo pipefail
cd "$(dirname "$0")/../.."
failed=()
section() { echo; echo "== $*"; }
run() { "$@" || failed+=("$*"); }

if ! command -v qemu-system-arm >/dev/null; then
  echo "qemu-system-arm is missing (Debian: apt-get install -y qemu-system-arm)" >&2
  exit 1
fi

section "release ELF: cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware"
ELF=target/thumbv7em-none-eabihf/firmware/firmware
run cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware
SIZE=$(command -v llvm-size || command -v arm-none-eabi-size || echo size)
"$SIZE" "$ELF" && "$SIZE" -A "$ELF" | grep -E '^\.(vector_table|text|rodata|data|bss|uninit) '
echo "(flash = text + data, static RAM = data + bss)"

section "link-protocol unit tests"
run cargo test -p link-protocol

section "QEMU tests (faults, serial-port path, power cuts, 20,000 s end to end and restart, budgets)"
run cargo test -p host-sim --release --no-fail-fast --test qemu -- qemu_faults qemu_port qemu_power_cut qemu_checkpoint_interval qemu_e2e qemu_restart qemu_budgets --nocapture --test-threads=1

section "exact step instruction count (TCG plugin firmware/tools/stepcount.c)"
WORK="$PWD/target/qemu-tests/plugin"   # absolute: host-sim runs QEMU in a scratch directory
mkdir -p "$WORK"
PLUGIN_API=1
qemu-system-arm --version | grep -q 'version [1-9][0-9]\.' && PLUGIN_API=2
run gcc -O2 -shared -fPIC -fvisibility=hidden -DPLUGIN_API=$PLUGIN_API -o "$WORK/libstepcount.so" firmware/tools/stepcount.c
OBJDUMP=$(command -v llvm-objdump || command -v arm-none-eabi-objdump)
# The call of the timed step for a sample (`Service::handle`; the navigation-rate path's call, in
# `Service::nav_sample`, comes later in the image): count from the `bl` to the instruction after it.
CALL=$("$OBJDUMP" -d -C "$ELF" | grep -E 'bl\s.*<firmware::app::service::step' | head -1 | awk '{print $1}' | tr -d ':')
if [ -z "$CALL" ]; then
  failed+=("find the call of firmware::app::service::step")
else
  START=$((16#$CALL)); END=$((START + 4))
  HOST_SIM=target/release/host-sim
  # The paper's log, every row; and the lossy log of qemu_e2e (a reciprocating sea log at a 360 s
  # period, 2 % of rows lost, jittered Unix stamps), one sample at a time.
  run "$HOST_SIM" generate --scenario paper --duration 6000 --out "$WORK/paper.csv"
  run "$HOST_SIM" generate --scenario sea --duration 12000 --scheme reciprocating --rotation-period 360 \
    --drop-fraction 0.02 --time-offset 1700000000 --time-jitter 0.02 --out "$WORK/lossy.csv"
  # A course weave whose heel the filter learns (its heel state in every roll update).
  run "$HOST_SIM" generate --scenario sea --duration 8000 --heel-per-turn-rate 6 --out "$WORK/weave.csv"
  for LOG in paper lossy weave; do
    rm -f "$WORK/stepcount.txt"
    HOST_SIM_QEMU_ARGS="-plugin $WORK/libstepcount.so,start=$START,end=$END,out=$WORK/stepcount.txt" \
      run "$HOST_SIM" stream --qemu "$ELF" "$WORK/$LOG.csv" --out "$WORK/stream.csv"
    if [ -s "$WORK/stepcount.txt" ]; then
      awk -v name="$LOG" '{printf "plugin, exact, %s log: %d steps, max %d instructions, mean %.1f instructions, min %d\n", name, $2, $6, $4 / $2, $8}' "$WORK/stepcount.txt"
    else
      failed+=("plugin count, $LOG log")
    fi
  done
fi

echo
if [ ${#failed[@]} -eq 0 ]; then
  echo "ALL PASSED"
else
  printf 'FAILED: %s\n' "${failed[@]}"
  exit 1
fi
