#!/usr/bin/env bash
# Attitude at the navigation rate: the same scenario and seed generated at 1 Hz and at 200 Hz
# (`generate --sample-interval 0.005`); the 1 Hz log estimated as it is, the 200 Hz log with
# `estimate --bin-interval-s 1` (each second of rows averaged into one sample). For each scenario
# and seed, prints the worst absolute error over x1..x4 at 2,000, 10,000 s and at the end of
# each, the time from which every error stays within 1 arcsec, and the largest 1-sigma at the end.
# docs/interface.md ("Attitude at the navigation rate") quotes it.
# Usage: bash scripts/nav-rate-study.sh [SEEDS] [DURATION_S]   (default 3 20000; a 200 Hz log of
# 20,000 s is 4 million rows, 480 MB, written to a temporary directory one at a time)
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-3}"
duration="${2:-20000}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# x1..x4 of a truth file, comma-separated.
truth() { tr -d ' \n' < "$1" | grep -o '"x_arcsec":\[[^]]*\]' | sed 's/.*\[//; s/\]//'; }

# "worst@2000 / worst@10000 / worst@end | within-1-arcsec-from | largest final sigma" of an
# estimates CSV against the truth x1..x4 ($2).
judge() {
    awk -F, -v x="$2" -v end="$3" '
        BEGIN { split(x, t, ","); n = split("2000 10000", at, " "); at[++n] = end; from = "" }
        FNR == 1 { next }
        $2 != "" {
            worst = 0
            for (i = 1; i <= 4; i++) { e = $(i + 1) - t[i]; if (e < 0) e = -e; if (e > worst) worst = e }
            for (k = 1; k <= n; k++) if ($1 <= at[k]) w[k] = worst
            if (worst > 1) from = ""; else if (from == "") from = $1
            sigma = 0
            for (i = 6; i <= 9; i++) if ($i > sigma) sigma = $i
        }
        END {
            for (k = 1; k <= n; k++) s[k] = (k in w) ? sprintf("%.2f", w[k]) : "-"
            printf "%s / %s / %s | %s | %.3f", s[1], s[2], s[3], (from == "" ? "never" : sprintf("%.0f s", from)), sigma
        }' "$1"
}

echo "| scenario | seed | 1 Hz: worst error at 2,000 / 10,000 / ${duration} s (arcsec) | 1 Hz: within 1 arcsec from | 1 Hz: largest 1-sigma at the end | 200 Hz binned to 1 s: worst error at 2,000 / 10,000 / ${duration} s | 200 Hz binned: within 1 arcsec from | 200 Hz binned: largest 1-sigma at the end |"
echo "|---|---|---|---|---|---|---|---|"
for scenario in paper sea; do
    for seed in $(seq 1 "$seeds"); do
        "$bin" generate --scenario "$scenario" --seed "$seed" --duration "$duration" --out "$dir/one.csv" >/dev/null
        "$bin" estimate "$dir/one.csv" --out "$dir/one.est.csv" >/dev/null
        "$bin" generate --scenario "$scenario" --seed "$seed" --duration "$duration" --sample-interval 0.005 --out "$dir/nav.csv" >/dev/null
        # The errors are judged here: without its truth file `estimate` does not regenerate the
        # 4 million rows of the scenario in memory.
        rm -f "$dir/nav.truth.json"
        "$bin" estimate "$dir/nav.csv" --bin-interval-s 1 --out "$dir/nav.est.csv" >/dev/null
        rm -f "$dir/nav.csv"
        x=$(truth "$dir/one.truth.json")
        echo "| $scenario | $seed | $(judge "$dir/one.est.csv" "$x" "$duration") | $(judge "$dir/nav.est.csv" "$x" "$duration") |"
    done
done
