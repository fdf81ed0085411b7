#!/usr/bin/env bash
# springlab against a C++ reference of the peer workloads (docs/workloads.md), interleaved in one
# run, so that both see the same machine load. Prints each round and the median ratio per
# workload, and fails when a checksum disagrees.
#
# Usage: scripts/bench-vs-cpp.sh [-n ROUNDS] [-r REPEATS] CPP_BINARY [WORKLOAD...]
#        (or CPP_BINARY from $MASSSPRING_CPP; springlab from $SPRINGLAB, else target/release/springlab)
#   CPP_BINARY   a program that, run as `CPP_BINARY WORKLOAD --reps R`, prints one line
#                `RESULT ... steps_per_s=S ... cx=X cy=Y cz=Z E=E ...` (median of R runs of N steps)
#   ROUNDS       rounds (default 5); each round runs every workload once per program, the order of
#                the two programs alternating from round to round
#   REPEATS      timed runs of N steps per program and round, their median reported (default 3)
#   WORKLOAD     default: jelly-se jelly-rk4 cloth128-se rope-se rope-verlet
#
# The ratio is springlab's steps/s over the reference's, per round; the summary is the median over
# the rounds (and the lowest and highest). Checksums (centroid and energy after N steps) must agree
# to 1e-8 relative (absolute floor 1e-12), the tolerance of docs/workloads.md.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

rounds=5 repeats=3
while getopts "n:r:h" opt; do
    case "$opt" in
        n) rounds="$OPTARG" ;;
        r) repeats="$OPTARG" ;;
        *) sed -n '2,18p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
cpp="${1:-${MASSSPRING_CPP:-}}"
[ $# -gt 0 ] && shift
if [ -z "$cpp" ] || [ ! -x "$cpp" ]; then
    echo "bench-vs-cpp: expected the C++ reference binary as the first argument or in \$MASSSPRING_CPP (got '${cpp}')" >&2
    exit 2
fi
case "$rounds$repeats" in *[!0-9]*|"") echo "bench-vs-cpp: -n and -r take whole numbers" >&2; exit 2 ;; esac
workloads=("$@")
[ ${#workloads[@]} -eq 0 ] && workloads=(jelly-se jelly-rk4 cloth128-se rope-se rope-verlet)
springlab="${SPRINGLAB:-target/release/springlab}"
if [ ! -x "$springlab" ]; then
    echo "bench-vs-cpp: building $springlab (cargo build --release)" >&2
    cargo build --release --bin springlab >&2
fi

echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $(nproc) cores,$(grep -qw avx512f /proc/cpuinfo && echo ' AVX-512,' || true) springlab threads: ${SPRINGLAB_THREADS:-all}"
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
results=$(mktemp)
trap 'rm -f "$results"' EXIT

# shellcheck source=bench-runs.sh
. "$(dirname "$0")/bench-runs.sh"

printf '%-6s %-12s %14s %14s %8s  %s\n' round workload "springlab /s" "C++ /s" ratio checksum
for ((round = 1; round <= rounds; round++)); do
    for w in "${workloads[@]}"; do
        if ((round % 2)); then s=$(springlab_run "$w"); c=$(cpp_run "$w")
        else c=$(cpp_run "$w"); s=$(springlab_run "$w"); fi
        echo "$round $w $s $c" | awk -v out="$results" '{
            ok = "ok"; worst = 0
            for (i = 0; i < 4; i++) {
                a = $(4 + i); b = $(9 + i); d = a - b; if (d < 0) d = -d
                m = (a < 0 ? -a : a); n = (b < 0 ? -b : b); if (n > m) m = n
                r = (m > 0 ? d / m : 0); if (r > worst) worst = r
                if (d > 1e-12 && d > 1e-8 * m) ok = "MISMATCH"
            }
            printf "%-6s %-12s %14.0f %14.0f %7.2fx  %s (%.1e)\n", $1, $2, $3, $8, $3 / $8, ok, worst
            print $2, $3 / $8, ok >> out }'
    done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "median ratio springlab / C++ over $rounds rounds (lowest – highest):"
for w in "${workloads[@]}"; do
    awk -v w="$w" '$1 == w { print $2 }' "$results" | sort -g | awk -v w="$w" '
        { r[NR] = $1 } END {
            m = (NR % 2) ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2
            printf "  %-12s %6.2fx  (%.2f – %.2f)\n", w, m, r[1], r[NR] }'
done
if grep -q MISMATCH "$results"; then
    echo "bench-vs-cpp: a checksum disagrees (see the table)" >&2
    exit 1
fi
