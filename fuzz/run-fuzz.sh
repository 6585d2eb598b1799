#!/usr/bin/env bash
# Runs every fuzz target for SECONDS each (default 300), one after the other, on one core.
# Needs a nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`). Corpora grow in
# fuzz/corpus/<target>/ (seeded from fuzz/seeds/<target>/); crashes land in fuzz/artifacts/<target>/.
set -euo pipefail
cd "$(dirname "$0")"
SECONDS_EACH="${1:-300}"
for target in ${TARGETS:-core_step checkpoint_restore frame_decoder log_csv}; do
    mkdir -p "corpus/$target"
    if [ -d "seeds/$target" ]; then cp -n seeds/$target/* "corpus/$target/" 2>/dev/null || true; fi
    echo "== $target for ${SECONDS_EACH}s"
    cargo +nightly fuzz run "$target" "corpus/$target" -- -max_total_time="$SECONDS_EACH" -rss_limit_mb=2048 -print_final_stats=1 2>&1 | tail -n 25
done
