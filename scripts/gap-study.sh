#!/usr/bin/env bash
# Regular gaps and random loss: ours (windowed) against the traditional baseline on every rotation
# scheme (continuous, reversed, reciprocating, four-position, eight-position), for each gap length
# (rows lost in a row) and gap period, on the paper and sea scenarios, with 1 % of rows also lost
# at random. Writes one markdown section per gap pattern, each holding `host-sim compare`'s table
# per scheme with the command that made it. Nothing is pinned: the estimator learns the rotation
# period and the sample interval from each lossy log.
#
# Usage: bash scripts/gap-study.sh [SEEDS] [DURATION_S] [OUT.md]
#   SEEDS       seeds per line (default 3)
#   DURATION_S  log length (default 45001)
#   OUT.md      output file (default target/gap-study.md); also printed
# Gap lengths and periods: ROWS="1 2 3 4 6 10" EVERY="60 120 300" (the defaults).
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-3}"
duration="${2:-45001}"
out="${3:-target/gap-study.md}"
rows_list="${ROWS:-1 2 3 4 6 10}"
every_list="${EVERY:-60 120 300}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
mkdir -p "$(dirname "$out")"
{
    printf '# Regular gaps and random loss\n\n'
    printf 'Scenarios: paper, sea; %s seeds per line; logs of %s s; 1 %% of rows lost at random on top of the gaps.\n' "$seeds" "$duration"
    for every in $every_list; do
        for rows in $rows_list; do
            lost=$(awk -v r="$rows" -v e="$every" 'BEGIN { printf "%.1f", 100 * (r / e + 0.01 * (1 - r / e)) }')
            printf '\n## %s rows lost every %s s, plus 1 %% at random (%s %% of rows)\n\n' "$rows" "$every" "$lost"
            "$bin" compare --scenarios paper,sea --seeds "$seeds" --duration "$duration" --schemes all \
                --methods windowed,traditional --gap-every "$every" --gap-rows "$rows" --drop-fraction 0.01
        done
    done
} | tee "$out"
echo "written to $out" >&2
