#!/usr/bin/env bash
# Makes the picture the README shows from a report: `host-sim estimate --report` on a simulated
# sea trial (the sea scenario, 20000 s, 1 % of the rows lost, one 60 s outage, Unix time stamps),
# then copies the report's estimates plot (x1..x4 with their 1-sigma band and the truth).
# Usage: bash scripts/report-example.sh [OUT.png]   (default: docs/report-estimates.png)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-docs/report-estimates.png}"
cargo build --release -q -p host-sim
bin=target/release/host-sim
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
"$bin" generate --scenario sea --duration 20000 --drop-fraction 0.01 --outages 1 --time-offset 1700000000 --out "$dir/trial.csv" >/dev/null
"$bin" estimate "$dir/trial.csv" --report "$dir/report" >/dev/null
cp "$dir/report/estimates.png" "$out"
echo "wrote $out"
