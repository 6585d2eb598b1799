#!/usr/bin/env bash
# Rotation schemes and recorder losses: every method on every rotation scheme (continuous, reversed,
# reciprocating, four-position, eight-position) at rotation periods of 360, 480 and 720 s, then
# under recorder effects (2 % random loss + three 60 s outages + 20 ms stamp jitter on Unix-time
# stamps; 5 % loss on the reciprocating scheme; a row every 2 s; 10 Hz). Writes one markdown section
# per condition, each holding `host-sim compare`'s table per scheme with the command that made it.
# The estimator learns the rotation period and the sample interval from each log (nothing is
# pinned): what the tables show includes the detection.
#
# Usage: bash scripts/scheme-study.sh [SEEDS] [DURATION_S] [OUT.md]
#   SEEDS       seeds per line (default 5)
#   DURATION_S  log length (default: each scenario's own; e.g. 3000 for a quick look)
#   OUT.md      output file (default target/scheme-study.md); also printed
# Scenarios: SCENARIOS=paper,turntable,sea (default sea).
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-5}"
duration="${2:-}"
out="${3:-target/scheme-study.md}"
scenarios="${SCENARIOS:-sea}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
common=(--scenarios "$scenarios" --seeds "$seeds")
if [ -n "$duration" ]; then
    common+=(--duration "$duration")
fi
mkdir -p "$(dirname "$out")"
{
    printf '# Rotation schemes and recorder losses\n\n'
    printf 'Scenarios: %s; %s seeds per line; log length: %s.\n' "$scenarios" "$seeds" "${duration:-the scenario default}"
    section() {
        printf '\n## %s\n\n' "$1"
        shift
        "$bin" compare "${common[@]}" "$@"
    }
    for period in 360 480 720; do
        section "rotation period ${period} s, every row, exact stamps" --schemes all --rotation-period "$period"
    done
    section "2 % random loss, three 60 s outages, stamps in Unix time with 20 ms jitter" \
        --schemes all --drop-fraction 0.02 --outages 3 --time-offset 1.7e9 --time-jitter 0.02
    section "5 % random loss, reciprocating" --schemes reciprocating --drop-fraction 0.05
    section "a row every 2 s" --schemes all --sample-interval 2
    section "10 Hz (a row every 0.1 s)" --schemes all --sample-interval 0.1
} | tee "$out"
echo "written to $out" >&2
