#!/usr/bin/env bash
# Implicit Euler's large steps against semi-implicit Euler's small ones on the 2022 cloth with
# four spheres: `springlab run cloth-spheres` for 3 simulated seconds, implicit Euler at
# dt = 0.005 s and semi-implicit Euler at dt = 1e-4 s, interleaved (ROUNDS rounds, default 5), the
# wall time of each run from its JSON report. Prints each round and the median of the ratio.
#
# Usage: scripts/implicit-vs-se.sh [ROUNDS]   (springlab from $SPRINGLAB, else target/release/springlab)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
rounds="${1:-5}"
case "$rounds" in *[!0-9]*|"") echo "implicit-vs-se: ROUNDS is a whole number" >&2; exit 2 ;; esac
springlab="${SPRINGLAB:-target/release/springlab}"
[ -x "$springlab" ] || cargo build --release --bin springlab >&2
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
wall() { # METHOD DT -> "wall_seconds mean_cg_iterations"
    "$springlab" run cloth-spheres --method "$1" --dt "$2" --time 3 --json --force |
        awk '{ match($0, /"wall_seconds":[^,}]*/); w = substr($0, RSTART + 15, RLENGTH - 15)
               it = "-"; if (match($0, /"iterations_mean":[^,}]*/)) it = substr($0, RSTART + 18, RLENGTH - 18)
               print w, it }'
}
printf '%-6s %22s %22s %8s %14s\n' round "implicit, dt 0.005 (s)" "semi-impl., dt 1e-4 (s)" ratio "CG iter./solve"
ratios=()
for ((r = 1; r <= rounds; r++)); do
    if ((r % 2)); then read -r ti it < <(wall implicit-euler 0.005); read -r ts _ < <(wall semi-implicit-euler 1e-4)
    else read -r ts _ < <(wall semi-implicit-euler 1e-4); read -r ti it < <(wall implicit-euler 0.005); fi
    ratio=$(awk -v a="$ts" -v b="$ti" 'BEGIN { printf "%.2f", a / b }')
    ratios+=("$ratio")
    printf '%-6s %22.3f %22.3f %7sx %14s\n' "$r" "$ti" "$ts" "$ratio" "$it"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%s\n' "${ratios[@]}" | sort -g | awk '{ r[NR] = $1 } END {
    m = (NR % 2) ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2
    printf "median: implicit Euler %.2fx faster than semi-implicit Euler (%.2f – %.2f)\n", m, r[1], r[NR] }'
