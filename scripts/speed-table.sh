#!/usr/bin/env bash
# The README's speed table, measured: springlab on one thread and on all threads against a C++
# reference of the peer workloads (docs/workloads.md), the three interleaved in every round so
# that all see the same machine load. Writes the table between the `speed-table` markers of
# README.md and docs/performance.md (with the CPU's name, its cores, the load and the ceiling),
# and fails without writing when a checksum disagrees.
#
# Usage: scripts/speed-table.sh [-n ROUNDS] [-r REPEATS] [-p] CPP_BINARY
#   CPP_BINARY   a program that, run as `CPP_BINARY WORKLOAD --reps R`, prints one line
#                `RESULT ... steps_per_s=S ... cx=X cy=Y cz=Z E=E ...` (median of R runs)
#   ROUNDS       rounds (default 5); the programs' order rotates from round to round
#   REPEATS      timed runs of N steps per program and round, their median kept (default 3)
#   -p           print the table only; write nothing
# springlab is $SPRINGLAB, else target/release/springlab (built when missing).
#
# Each cell is the median over the rounds of springlab's steps/s over the reference's in the same
# round; the ceiling is springlab's fastest spring kernel on data in the first-level cache, in
# springs per second per thread (`springlab bench`).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

rounds=5 repeats=3 print_only=0
while getopts "n:r:ph" opt; do
    case "$opt" in
        n) rounds="$OPTARG" ;;
        r) repeats="$OPTARG" ;;
        p) print_only=1 ;;
        *) sed -n '2,19p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
cpp="${1:-}"
if [ -z "$cpp" ] || [ ! -x "$cpp" ]; then
    echo "speed-table: expected the C++ reference binary as the argument (got '${cpp}')" >&2
    exit 2
fi
case "$rounds$repeats" in *[!0-9]*|"") echo "speed-table: -n and -r take whole numbers" >&2; exit 2 ;; esac
workloads=(jelly-se jelly-rk4 cloth128-se rope-se rope-verlet)
springlab="${SPRINGLAB:-target/release/springlab}"
if [ ! -x "$springlab" ]; then
    cargo build --release --bin springlab >&2
fi

cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//; s/  */ /g')
cores=$(nproc)
simd=$(grep -qw avx512f /proc/cpuinfo && echo "AVX-512" || (grep -qw avx2 /proc/cpuinfo && echo "AVX2" || echo "no AVX2"))
load_before=$(cut -d' ' -f1 /proc/loadavg)
results=$(mktemp)
trap 'rm -f "$results"' EXIT

# shellcheck source=bench-runs.sh
. "$(dirname "$0")/bench-runs.sh"
compare() { # ROUND WORKLOAD COLUMN "springlab" "cpp": prints the ratio, records it
    echo "$1 $2 $3 $4 $5" | awk -v out="$results" '{
        ok = "ok"
        for (i = 0; i < 4; i++) {
            a = $(5 + i); b = $(10 + i); d = a - b; if (d < 0) d = -d
            m = (a < 0 ? -a : a); n = (b < 0 ? -b : b); if (n > m) m = n
            if (d > 1e-12 && d > 1e-8 * m) ok = "MISMATCH"
        }
        printf "%-6s %-12s %-8s %14.0f %14.0f %7.2fx  %s\n", $1, $2, $3, $4, $9, $4 / $9, ok
        print $2, $3, $4 / $9, ok >> out }'
}

printf '%-6s %-12s %-8s %14s %14s %8s  %s\n' round workload threads "springlab /s" "C++ /s" ratio checksum >&2
for ((round = 1; round <= rounds; round++)); do
    for w in "${workloads[@]}"; do
        case $((round % 3)) in
            1) one=$(SPRINGLAB_THREADS=1 springlab_run "$w"); all=$(SPRINGLAB_THREADS="$cores" springlab_run "$w"); c=$(cpp_run "$w") ;;
            2) c=$(cpp_run "$w"); one=$(SPRINGLAB_THREADS=1 springlab_run "$w"); all=$(SPRINGLAB_THREADS="$cores" springlab_run "$w") ;;
            *) all=$(SPRINGLAB_THREADS="$cores" springlab_run "$w"); c=$(cpp_run "$w"); one=$(SPRINGLAB_THREADS=1 springlab_run "$w") ;;
        esac
        compare "$round" "$w" 1 "$one" "$c" >&2
        compare "$round" "$w" all "$all" "$c" >&2
    done
done
if grep -q MISMATCH "$results"; then
    echo "speed-table: a checksum disagrees (see the rounds above); nothing written" >&2
    exit 1
fi
load_after=$(cut -d' ' -f1 /proc/loadavg)
ceiling=$(SPRINGLAB_THREADS=1 "$springlab" bench rope-se --json --repeats 1 --budget 0 --force |
    awk '{ match($0, /"per_thread":[^,]*/); s = substr($0, RSTART + 13, RLENGTH - 13)
           match($0, /"kernel":"[^"]*"/); k = substr($0, RSTART + 10, RLENGTH - 11)
           printf "%.2g springs/s per thread (%s kernel)", s, k }')

median() { # WORKLOAD COLUMN
    awk -v w="$1" -v t="$2" '$1 == w && $2 == t { print $3 }' "$results" | sort -g | awk '
        { r[NR] = $1 } END {
            m = (NR % 2) ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2
            printf "%.2f× (%.2f – %.2f)", m, r[1], r[NR] }'
}
table=$(
    echo "springlab's steps/s over the C++ reference's (single-threaded), median of $rounds interleaved rounds (lowest – highest), checksums equal in every round; $cpu, $cores cores, $simd; load average $load_before → $load_after; ceiling $ceiling. The first column, one thread against one, compares the code; the second is springlab on all $cores threads against the reference's one."
    echo
    echo "| workload | 1 thread (\`SPRINGLAB_THREADS=1\`) | all $cores threads |"
    echo "| --- | --- | --- |"
    for w in "${workloads[@]}"; do
        echo "| $w | $(median "$w" 1) | $(median "$w" all) |"
    done
)
echo "$table"
[ "$print_only" = 1 ] && exit 0

for file in README.md docs/performance.md; do
    if ! grep -q '^<!-- speed-table -->$' "$file" || ! grep -q '^<!-- /speed-table -->$' "$file"; then
        echo "speed-table: $file has no <!-- speed-table --> … <!-- /speed-table --> lines" >&2
        exit 1
    fi
    TABLE="$table" awk '
        /^<!-- speed-table -->$/ { print; print ENVIRON["TABLE"]; skip = 1; next }
        /^<!-- \/speed-table -->$/ { skip = 0 }
        !skip { print }' "$file" > "$file.new"
    mv "$file.new" "$file"
done
echo "speed-table: wrote README.md and docs/performance.md" >&2
