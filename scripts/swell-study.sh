#!/usr/bin/env bash
# Rows lost at a cadence against a sea with few or many spectral lines: ours (windowed) on the sea
# scenario, whose sway is a sum of sinusoids (`--sway-lines`, 40 by default). When rows are lost
# at a cadence that divides the rotation period, the weights of the window's sums repeat every
# period, and a sway line that stays in step with that pattern leaves the same remainder in every
# window: a bias the residuals cannot show. The same patterns on a control cadence that does not
# divide the period (110 s) show the difference. Writes `host-sim compare`'s table per pattern and
# number of lines, with the command that made it.
#
# Usage: bash scripts/swell-study.sh [SEEDS] [DURATION_S] [OUT.md]
#   SEEDS       seeds per line (default 3)
#   DURATION_S  log length (default 45001)
#   OUT.md      output file (default target/swell-study.md); also printed
# Lines per spectrum: LINES="default 2000 10000" ("default" is the scenario's own draw of 40);
# about 10 minutes on 2 cores, mostly the 10,000-line seas.
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-3}"
duration="${2:-45001}"
out="${3:-target/swell-study.md}"
lines_list="${LINES:-default 2000 10000}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
mkdir -p "$(dirname "$out")"
# pattern: rows lost, every (s), rotation period (s), schemes
patterns=(
    "4 120 480 continuous,four-position"
    "2 120 480 reciprocating,eight-position"
    "3 90 360 four-position,eight-position"
    "4 110 480 continuous,four-position"
)
{
    printf '# Rows lost at a cadence, on a sea of few or many lines\n\n'
    printf 'Sea scenario; %s seeds per line; logs of %s s; 1 %% of rows lost at random on top of the gaps;\n' "$seeds" "$duration"
    printf 'sway of %s lines per spectrum ("default": the scenario'"'"'s own 40). Made by\n' "$lines_list"
    printf '`bash scripts/swell-study.sh %s %s`; what it shows: [uncertainty.md](uncertainty.md#rows-lost-at-a-cadence).\n' "$seeds" "$duration"
    for pattern in "${patterns[@]}"; do
        read -r rows every period schemes <<<"$pattern"
        for lines in $lines_list; do
            if [ "$lines" = default ]; then
                sway=()
                name="the scenario's 40 lines"
            else
                sway=(--sway-lines "$lines")
                name="$lines lines"
            fi
            printf '\n## %s rows lost every %s s at a %s s rotation, sway of %s\n\n' "$rows" "$every" "$period" "$name"
            "$bin" compare --scenarios sea --seeds "$seeds" --duration "$duration" --schemes "$schemes" \
                --methods windowed --rotation-period "$period" --gap-every "$every" --gap-rows "$rows" \
                --drop-fraction 0.01 "${sway[@]}"
        done
    done
} | tee "$out"
echo "written to $out" >&2
