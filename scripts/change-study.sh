#!/usr/bin/env bash
# Changes of the installation errors, the full study (docs/uncertainty.md, "Changes of the errors",
# quotes its tables):
#   - steps of 20, 30, 50 and 150 arcsec of each error at 20,000 s of a sea log, one-way,
#     reciprocating and four-position rotation at 360, 480 and 720 s, 4 seeds a line: detected
#     once, when, every error within 10 arcsec of the new values from when, the 1-sigma's cover;
#   - no change declared: 200 runs each of the rough sea (latitudes 0-70 deg, roll up to 10 deg),
#     coloured noise of 20 arcsec, errors drifting 20 arcsec a day, heel in turns of 3 and 0.5 deg
#     (45,000 s each), and ten 30-day voyages clean and with drifting errors.
# The same assertions as the reduced runs of `cargo test --release -p host-sim --test cli
# error_changes`, at full size. Usage: bash scripts/change-study.sh
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
cargo test --release -q -p host-sim --test cli -- --ignored --nocapture --test-threads 1 error_changes::study_ 2>&1 \
    | grep -v '^running\|^test result\|^$'
echo "(bash scripts/change-study.sh: $(( $(date +%s) - start )) s)"
