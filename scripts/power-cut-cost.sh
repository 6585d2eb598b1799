#!/usr/bin/env bash
# What a power cut costs in accuracy, with the firmware's default checkpoints (every 300 s of sample
# time). The worst case: the board loses power just before a save, 300 s after the last one, and
# stays off for OUTAGE s while the navigation computer keeps sending. On restart it restores the
# checkpoint of time T and sees rows again from T + 300 + OUTAGE on: the same as
# `host-sim estimate --restart-at T` on the log without the rows in (T, T + 300 + OUTAGE].
# For cuts at several times of the sea scenario (45,000 s, seeds 1-3), prints the largest error
# difference from the uncut run, over x1..x4, at the end of the log, and the largest error of the
# cut run against the truth from the restart to the end, beside the uncut run's over the same rows.
# docs/firmware.md quotes it.
# Usage: bash scripts/power-cut-cost.sh [OUTAGE_S]   (default 200)
set -euo pipefail
cd "$(dirname "$0")/.."
outage="${1:-200}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "| seed | cut at (s) | rows lost (s) | end: largest difference from the uncut run (arcsec) | largest error after the restart: cut / uncut (arcsec) |"
echo "|---|---|---|---|---|"
for seed in 1 2 3; do
    "$bin" generate --scenario sea --seed "$seed" --duration 45000 --out "$dir/sea.csv" >/dev/null
    "$bin" estimate "$dir/sea.csv" --out "$dir/uncut.csv" >/dev/null
    for t in 1500 5000 20000 40000; do
        gone=$((t + 300 + outage))
        awk -F, -v a="$t" -v b="$gone" 'NR == 1 || $1 <= a || $1 > b' "$dir/sea.csv" > "$dir/cut.csv"
        "$bin" estimate "$dir/cut.csv" --restart-at "$t" --out "$dir/cut.estimates.csv" >/dev/null
        # x1..x4 are columns 2-5 (arcsec); the truth is the scenario's.
        awk -F, -v t="$t" -v gone="$gone" -v seed="$seed" -v lost=$((300 + outage)) '
            BEGIN { x[1] = 200; x[2] = -150; x[3] = 300; x[4] = -250 }
            FNR == 1 { file++; next }
            file == 1 { for (i = 1; i <= 4; i++) u[$1, i] = $(i + 1); last_u = $1; next }
            {
                for (i = 1; i <= 4; i++) {
                    c[i] = $(i + 1)
                    if ($1 > gone && $(i + 1) != "") {
                        e = $(i + 1) - x[i]; if (e < 0) e = -e; if (e > worst_cut) worst_cut = e
                        e = u[$1, i] - x[i]; if (e < 0) e = -e; if (e > worst_uncut) worst_uncut = e
                    }
                }
                last = $1
            }
            END {
                for (i = 1; i <= 4; i++) { d = c[i] - u[last, i]; if (d < 0) d = -d; if (d > end) end = d }
                printf "| %d | %d | %d | %.3f | %.2f / %.2f |\n", seed, t, lost, end, worst_cut, worst_uncut
            }' "$dir/uncut.csv" "$dir/cut.estimates.csv"
    done
done
