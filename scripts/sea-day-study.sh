#!/usr/bin/env bash
# A ship's ordinary day: ours (windowed) against the traditional baseline on the sea scenario with
# slow heel and trim, heel in turns, logs stamped on receipt and rows lost at a cadence that
# divides the rotation period, on every rotation scheme where it matters and at 360, 480 and 720 s.
# Each line is `host-sim compare`'s table (worst error at 2000, 20000 and 45000 s, time to
# 10 arcsec and staying, rows beyond 2 and 3 sigma, the largest |error| / 1-sigma) with the command
# that made it. Nothing is pinned: the estimator learns the period and the interval from each log.
#
# Usage: bash scripts/sea-day-study.sh [SEEDS] [DURATION_S] [OUT.md]
#   SEEDS       seeds per line (default 3)
#   DURATION_S  log length (default 45001)
#   OUT.md      output file (default target/sea-day-study.md); also printed
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-3}"
duration="${2:-45001}"
out="${3:-target/sea-day-study.md}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
mkdir -p "$(dirname "$out")"

line() {
    local title="$1"
    shift
    printf '\n## %s\n\n' "$title"
    "$bin" compare --scenarios sea --seeds "$seeds" --duration "$duration" \
        --methods windowed,traditional "$@"
}

{
    printf '# A ship'"'"'s ordinary day\n\n'
    printf 'Sea scenario; %s seeds per line; logs of %s s; `bash scripts/sea-day-study.sh %s %s`.\n' \
        "$seeds" "$duration" "$seeds" "$duration"
    printf 'Rows beyond 2 / 3 sigma: share of the rows after the first estimate on which some error lies beyond 2 (3) times its reported 1-sigma, pooled over the seeds; largest error/sigma: over every row of every seed.\n'

    printf '\n# Slow heel and trim\n'
    line "Heel 0.1 deg at 600 s" --slow-heel-deg 0.1 --slow-heel-period-s 600
    line "Heel 0.3 deg at 1200 s" --slow-heel-deg 0.3 --slow-heel-period-s 1200
    line "Heel 0.5 deg at 900 s" --slow-heel-deg 0.5 --slow-heel-period-s 900
    line "Heel 0.5 deg at 3000 s" --slow-heel-deg 0.5 --slow-heel-period-s 3000
    line "Trim 0.1 deg at 1800 s" --slow-trim-deg 0.1 --slow-trim-period-s 1800
    line "Heel 0.3 deg at 1200 s and 0.15 deg at 2500 s, trim 0.1 deg at 1800 s, every scheme" \
        --slow-heel-deg 0.3,0.15 --slow-heel-period-s 1200,2500 \
        --slow-trim-deg 0.1 --slow-trim-period-s 1800 --schemes all
    for period in 360 720; do
        line "Heel 0.3 deg at 1200 s and 0.15 deg at 2500 s, trim 0.1 deg at 1800 s, rotation period $period s" \
            --slow-heel-deg 0.3,0.15 --slow-heel-period-s 1200,2500 \
            --slow-trim-deg 0.1 --slow-trim-period-s 1800 --rotation-period "$period"
    done

    printf '\n# Heel in turns\n'
    for heel in 0.5 1 3; do
        line "Heel in turns $heel deg (90 deg course changes at 0.5 deg/s every hour from 2 h)" \
            --heel-in-turns-deg "$heel"
    done
    for k in 2 6; do
        line "Heel of $k deg per deg/s of turn rate (the course weave)" --heel-per-turn-rate "$k"
    done
    line "Heel in turns 3 deg, every scheme" --heel-in-turns-deg 3 --schemes all

    printf '\n# Logs stamped on receipt\n'
    for jitter in 0.1 0.15 0.3 0.45; do
        line "Stamps jittered by up to +-$jitter s, 1 s rows" --time-jitter "$jitter"
    done
    line "Stamps jittered by up to +-0.45 s and 2 % of rows lost" --time-jitter 0.45 --drop-fraction 0.02
    line "Stamps jittered by up to +-0.045 s, 10 Hz rows" --time-jitter 0.045 --sample-interval 0.1

    printf '\n# Rows lost at a cadence that divides the rotation period\n'
    for every in 60 90 120; do
        line "3 rows lost every $every s, rotation period 360 s, every scheme" \
            --gap-every "$every" --gap-rows 3 --rotation-period 360 --schemes all
    done
    line "10 rows lost every 120 s plus 1 % at random, rotation period 480 s, every scheme" \
        --gap-every 120 --gap-rows 10 --drop-fraction 0.01 --schemes all
    line "3 rows lost every 90 s, rotation period 720 s" --gap-every 90 --gap-rows 3 --rotation-period 720
} | tee "$out"
echo "written to $out" >&2
