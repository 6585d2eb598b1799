#!/usr/bin/env bash
# Robustness study: every method on the sea scenario with, in turn, each effect that eq (2)
# does not contain. Prints one markdown table per effect (`host-sim compare` output).
# Usage: bash scripts/mismatch-study.sh [SEEDS]   (default 5 seeds per line)
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-5}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
run() {
    printf '\n### %s\n\n' "$1"
    shift
    "$bin" compare --scenarios sea --seeds "$seeds" "$@"
}
run "none (eq 2 holds)"
run "rotation period 0.5 % off (--period-error 0.005)" --period-error 0.005
run "rotation jitter 0.05 deg (--rotation-jitter-deg 0.05)" --rotation-jitter-deg 0.05
run "errors drifting 20 arcsec/day (--error-drift-arcsec-per-day 20)" --error-drift-arcsec-per-day 20
run "low-frequency errors 20 % off Earth rate (--lowfreq-rate-error 0.2)" --lowfreq-rate-error 0.2
run "coloured noise 20 arcsec, 60 s (--coloured-noise-arcsec 20)" --coloured-noise-arcsec 20
