#!/usr/bin/env bash
# How well `host-sim commission` tells a log's conventions, on generated logs: for each scenario,
# log length and seed, the log as `generate` writes it and the same log rewritten into each variant
# (roll_deg negated, roll_deg and pitch_deg exchanged, rotation_deg negated or in radians, ...),
# each through `commission`. Prints one markdown row per scenario and length: the smallest ratio of
# a wrong fit's unexplained share to the right fit's (on the log as it is: the closest variant over
# the log; on a rewritten log: the log as it is over the right variant, and the closest other
# variant, its roll/pitch twin aside, over the right one), the same smallest ratio by the residual
# power alone and by the largest 1-sigma, the measurement powers (of the sign and exchange fits;
# of the other reading of the rotation's unit), and how the verdicts came out: the right variant
# (or `ok`) named alone; with its twin (roll-negated or pitch-negated); with another; undecided;
# a wrong one named.
# docs/interface.md quotes it.
# Usage: bash scripts/commission-study.sh [SEEDS] [LENGTHS_S] [SCENARIOS] [GENERATE OPTIONS...]
#   default: 20 "2000 2500 3000 4000" "sea paper"
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="${1:-20}"
lengths="${2:-2000 2500 3000 4000}"
scenarios="${3:-sea paper}"
shift $(($# < 3 ? $# : 3))
cargo build --release -q -p host-sim
bin=target/release/host-sim
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
variants="rotation-reversed roll-negated pitch-negated roll-pitch-swapped platform-reversed rotation-in-radians"

# rewrite VARIANT IN OUT: the log with one convention changed (generate's column order:
# time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg).
rewrite() {
    awk -F, -v OFS=, -v v="$1" '
        NR == 1 { print; next }
        v == "rotation-reversed" { $2 = sprintf("%.17g", -$2) }
        v == "roll-negated" { $6 = sprintf("%.17g", -$6) }
        v == "pitch-negated" { $7 = sprintf("%.17g", -$7) }
        v == "roll-pitch-swapped" { t = $6; $6 = $7; $7 = t }
        v == "platform-reversed" { $3 = sprintf("%.17g", -$3) }
        v == "rotation-in-radians" { $2 = sprintf("%.17g", $2 * 3.14159265358979324 / 180) }
        { print }' "$2" > "$3"
}

# measures LOG: "variant unexplained residual-power largest-sigma measurement-power" lines ("inf"
# for "-"), then "verdict ...".
measures() {
    "$bin" commission "$1" 2>/dev/null | awk -F'|' '
        function v(x) { gsub(/ /, "", x); return x == "-" ? "inf" : x }
        /^\| [a-z]/ && $2 !~ /variant/ { gsub(/ /, "", $2); print $2, v($5), v($4), v($8), v($3) }
        /^conventions: / { sub(/^conventions: /, ""); print "verdict", $0 }' || true
}

echo "| scenario | length (s) | seeds | unexplained share: log as it is, closest variant / log | rewritten: log / right variant | rewritten: closest other / right | residual power: smallest wrong / right | largest 1-sigma: smallest wrong / right | measurement power, sign and exchange fits: largest / smallest | measurement power, the other reading of the rotation's unit: largest share of the largest | verdicts: right alone / with its twin / with another / undecided / wrong (of $((seeds * 7)) per line) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for scenario in $scenarios; do
    for length in $lengths; do
        : > "$dir/ratios"
        for seed in $(seq 1 "$seeds"); do
            "$bin" generate --scenario "$scenario" --seed "$seed" --duration "$length" "$@" \
                --out "$dir/as-is.csv" >/dev/null
            rm -f "$dir/as-is.truth.json"
            for v in as-is $variants; do
                if [ "$v" != as-is ]; then
                    rewrite "$v" "$dir/as-is.csv" "$dir/$v.csv"
                fi
                measures "$dir/$v.csv" | awk -v right="$v" '
                    function ratio(a, b) { return a == "inf" ? "inf" : (b == "inf" ? 0 : a / b) }
                    # The smallest of m(w) / m(of) over the variants w that are neither "as-is" nor
                    # one of the skipped.
                    function closest(m, of, skip1, skip2,   w, low) {
                        low = "inf"
                        for (w in u) if (w != "as-is" && w != skip1 && w != skip2 && m[w] != "inf" && (low == "inf" || m[w] + 0 < low + 0)) low = m[w]
                        return ratio(low, m[of])
                    }
                    $1 == "verdict" { $1 = ""; verdict = substr($0, 2); next }
                    { u[$1] = $2; p[$1] = $3; s[$1] = $4; m[$1] = $5 }
                    END {
                        # Measurement powers: the largest over the smallest among the log as it is
                        # and the sign and exchange variants (on a log in degrees), and the other
                        # reading of the rotation unit over the largest.
                        if (right != "rotation-in-radians") {
                            hi = 0; lo = "inf"
                            for (w in m) if (w != "rotation-in-radians" && m[w] != "inf") {
                                if (m[w] + 0 > hi) hi = m[w] + 0
                                if (lo == "inf" || m[w] + 0 < lo + 0) lo = m[w]
                            }
                            printf "m-spread %s\n", (lo == "inf" || lo == 0 ? "inf" : hi / lo)
                            printf "m-unit %s\n", (m["rotation-in-radians"] == "inf" ? "inf" : m["rotation-in-radians"] / hi)
                        } else if (m["as-is"] != "inf") {
                            printf "m-unit %s\n", m["as-is"] / m["rotation-in-radians"]
                        }
                        twin = (right == "roll-negated") ? "pitch-negated" : (right == "pitch-negated") ? "roll-negated" : ""
                        if (right == "as-is") {
                            printf "u-clean %s\np-any %s\ns-any %s\n", closest(u, "as-is"), closest(p, "as-is"), closest(s, "as-is")
                            printf "verdict %s\n", (verdict == "ok" ? "alone" : (verdict == "undecided" ? "undecided" : "wrong"))
                        } else {
                            printf "u-log %s\nu-other %s\n", ratio(u["as-is"], u[right]), closest(u, right, right, twin)
                            printf "p-any %s\np-any %s\n", ratio(p["as-is"], p[right]), closest(p, right, right, twin)
                            printf "s-any %s\ns-any %s\n", ratio(s["as-is"], s[right]), closest(s, right, right, twin)
                            if (verdict == right) print "verdict alone"
                            else if (twin != "" && (verdict == right " or " twin || verdict == twin " or " right)) print "verdict twin"
                            else if (verdict == "undecided") print "verdict undecided"
                            else if (index(" or " verdict " or ", " or " right " or ")) print "verdict another"
                            else print "verdict wrong"
                        }
                    }' >> "$dir/ratios"
            done
        done
        awk -v s="$scenario" -v l="$length" -v n="$seeds" '
            function fmt(v) { return v == "" ? "-" : (v == "inf" ? "no fit" : sprintf("%.3g", v)) }
            $1 == "verdict" { count[$2]++; next }
            $1 == "m-spread" || $1 == "m-unit" { if ($2 != "inf" && (!($1 in high) || $2 + 0 > high[$1] + 0)) high[$1] = $2; next }
            !($1 in low) || (low[$1] == "inf" && $2 != "inf") || ($2 != "inf" && $2 + 0 < low[$1] + 0) { low[$1] = $2 }
            END {
                printf "| %s | %d | %d | %s | %s | %s | %s | %s | %s | %s | %d / %d / %d / %d / %d |\n", s, l, n, fmt(low["u-clean"]), fmt(low["u-log"]),
                    fmt(low["u-other"]), fmt(low["p-any"]), fmt(low["s-any"]), fmt(high["m-spread"]), fmt(high["m-unit"]),
                    count["alone"], count["twin"], count["another"], count["undecided"], count["wrong"]
            }' "$dir/ratios"
    done
done
echo
echo "\`bash scripts/commission-study.sh $seeds \"$lengths\" \"$scenarios\"${*:+ $*}\`"
