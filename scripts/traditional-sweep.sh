#!/bin/bash
# Sweep of the traditional baseline's tuning on a 2-day paper-scenario log (the tables in docs/results.md).
# usage: [SCENARIO=paper] [SEED=1] bash scripts/traditional-sweep.sh [WORKDIR]
#        (needs python3; builds host-sim --release)
# Prints markdown rows: sigma deg | drift arcsec/sqrt(s) | % error x1..x4 at 45000 s | max | at 172799 s | max
set -euo pipefail
W=${1:-/tmp/traditional-sweep}
mkdir -p "$W"
cargo build --release -q -p host-sim
HS=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')/release/host-sim
"$HS" generate --scenario "${SCENARIO:-paper}" --seed "${SEED:-1}" --out "$W/sweep.csv" > /dev/null
for sig in 0.0028 0.01 0.1 0.5 2.1213 5 20; do
  for drift in 0 0.01 0.1 1 10; do
    "$HS" estimate "$W/sweep.csv" --method traditional --traditional-sigma-deg $sig \
      --traditional-drift-arcsec-per-sqrt-s $drift --out "$W/est.csv" > /dev/null
    python3 - "$W" $sig $drift <<'PY'
import csv, json, sys
w, sig, drift = sys.argv[1:4]
t = json.load(open(f"{w}/sweep.truth.json"))["x_arcsec"]
rows = {float(r["time_s"]): r for r in csv.DictReader(open(f"{w}/est.csv"))}
pct = lambda r: [abs(float(r[f"x{i+1}_arcsec"]) - t[i]) / abs(t[i]) * 100 for i in range(4)]
a, b = pct(rows[min(45000.0, max(rows))]), pct(rows[max(rows)])
f = lambda v: " / ".join(f"{x:.1f}" for x in v)
print(f"| {sig} | {drift} | {f(a)} | {max(a):.1f} | {f(b)} | {max(b):.1f} |")
PY
  done
done
