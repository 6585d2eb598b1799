#!/usr/bin/env bash
# Peak memory of `host-sim estimate` replaying a 30-day log (2,592,000 rows, about 200 MB of CSV)
# with its accuracy table (a minimal truth file beside it) and its report (`--report`: plots and
# report.html): the estimator reads and writes as it goes and the report keeps a bounded record,
# so the peak must not grow with the log. Fails above 64 MB (LIMIT_MB to change it).
# Measured with GNU time's "Maximum resident set size" (`/usr/bin/time -v`).
# Usage: bash scripts/memory-30day.sh
# HOST_SIM=PATH runs that host-sim binary instead of building one (the test command passes the one
# its `cargo test --workspace --release` built: `cargo build -p host-sim` alone resolves the
# workspace's features differently and would build host-sim and two of its crates again).
set -euo pipefail
cd "$(dirname "$0")/.."
LIMIT_MB="${LIMIT_MB:-64}"

if [ ! -x /usr/bin/time ]; then
    echo "/usr/bin/time (GNU time) is missing: apt-get install -y time" >&2
    exit 1
fi
if [ -n "${HOST_SIM:-}" ]; then
    BIN="$HOST_SIM"
else
    cargo build --release -q -p host-sim
    BIN="${CARGO_TARGET_DIR:-target}/release/host-sim"
fi
DIR="$(mktemp -d)"
trap 'rm -rf "$DIR"' EXIT

"$BIN" generate --scenario paper --duration 2592000 --out "$DIR/trial.csv"
# The survey's errors only (the generated truth file would regenerate the whole scenario in memory).
echo '{"x_arcsec": [200, -150, 300, -250]}' > "$DIR/trial.truth.json"
/usr/bin/time -v "$BIN" estimate "$DIR/trial.csv" --out "$DIR/trial.estimates.csv" --report "$DIR/report" > "$DIR/summary.txt" 2> "$DIR/time.txt"
head -n 1 "$DIR/summary.txt"
grep -A 6 '^accuracy against the truth' "$DIR/summary.txt" || true
rows="$(($(wc -l < "$DIR/trial.estimates.csv") - 1))"
peak_kb="$(awk -F': ' '/Maximum resident set size/ {print $2}' "$DIR/time.txt")"
wall="$(awk -F': ' '/Elapsed \(wall clock\) time/ {print $2}' "$DIR/time.txt")"
echo "30-day replay: $rows estimates rows, peak resident memory $((peak_kb / 1024)) MB ($peak_kb KB), wall $wall"
if [ "$rows" -ne 2592000 ]; then
    echo "expected 2592000 estimates rows" >&2
    exit 1
fi
if [ ! -s "$DIR/report/report.html" ]; then
    echo "no report written" >&2
    exit 1
fi
if [ "$peak_kb" -gt $((LIMIT_MB * 1024)) ]; then
    echo "peak memory above $LIMIT_MB MB" >&2
    exit 1
fi
