#!/usr/bin/env bash
# `springlab run` against `springlab bench`: each peer workload (docs/workloads.md) beside the
# course scene that does the same work, timed in one interleaved run, on one thread
# (SPRINGLAB_THREADS=1) and on all threads; prints steps/s of both and run/bench, for `run`
# as it is by default (with its energy accounting, which the bench does not do) and with
# `--no-accounting` (the bench's work, and the scene's collision response).
#
# Usage: scripts/run-vs-bench.sh [-n ROUNDS] [WORKLOAD...]
#   ROUNDS     rounds (default 3); each round times the bench and the run of every workload at
#              1 thread and all threads, the best of the rounds is kept
#   WORKLOAD   jelly-se jelly-rk4 cloth128-se rope-se rope-verlet (default: all five)
# springlab is $SPRINGLAB, else target/release/springlab (built when missing).
#
# The scene of each workload: the same particle count, springs, method, dt and steps; the
# bench's contact rule is its own (docs/workloads.md), the scene's the course collider:
#   jelly-se, jelly-rk4  cube-plane, a 10×10×10 cube of edge 0.9 m, k = 2000 N/m, k_d = 10 N·s/m,
#                        dropped 1 m onto its plane (lands at about 0.45 s and stays), 1 s
#   cloth128-se          cloth-sphere, 128×128, k = 5000 N/m, k_d = 0.02 N·s/m, two corners
#                        pinned, draped over its sphere from the start, 5000 steps of 2.5e-5 s
#   rope-se              rope, 64 nodes over 1 m, k = 50 000 N/m, k_d = 1 N·s/m, 10 000 steps
#   rope-verlet          rope, 64 nodes, k = 0, Verlet with 20 projections, 10 000 steps
# run's steps/s is its steps over its `wall_seconds` (the stepping, as bench times it).
# The accounting's share of a step is the difference of the two run columns.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

rounds=3
while getopts "n:h" opt; do
    case "$opt" in
        n) rounds="$OPTARG" ;;
        *) sed -n '2,21p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
case "$rounds" in *[!0-9]*|"") echo "run-vs-bench: -n takes a whole number" >&2; exit 2 ;; esac
workloads=("$@")
[ ${#workloads[@]} -gt 0 ] || workloads=(jelly-se jelly-rk4 cloth128-se rope-se rope-verlet)
springlab="${SPRINGLAB:-target/release/springlab}"
if [ ! -x "$springlab" ]; then
    cargo build --release --bin springlab >&2
fi

scene_of() { # WORKLOAD -> the run's arguments
    local rope="rope --set nodes=64 --set start=[0,1,0] --set end=[1,1,0] --set mass=0.015625"
    case "$1" in
        jelly-se|jelly-rk4)
            local m=semi-implicit-euler
            [ "$1" = jelly-rk4 ] && m=rk4
            echo "cube-plane --set n=10 --set edge=0.9 --set damping=10 --set friction=0" \
                "--set offset=[0,-0.9,0] --method $m --dt 1e-4 --time 1" ;;
        cloth128-se)
            echo "cloth-sphere --set n=128 --set stiffness=5000 --set damping=0.02 --set drag=0" \
                "--set mass=0.00006103515625 --set pinned=[1,2] --method semi-implicit-euler" \
                "--dt 2.5e-5 --time 0.125" ;;
        rope-se)
            echo "$rope --set stiffness=50000 --set damping=1 --method semi-implicit-euler" \
                "--dt 1e-4 --time 1" ;;
        rope-verlet)
            echo "$rope --set stiffness=0 --set iterations=20 --set verlet_damping=0" \
                "--method verlet --dt 1e-3 --time 10" ;;
        *) echo "run-vs-bench: unknown workload $1" >&2; exit 2 ;;
    esac
}
bench_rate() { # WORKLOAD -> steps/s
    "$springlab" bench "$1" --json --repeats 3 --budget 0 --force |
        grep -o '"steps_per_second":[^,}]*' | head -1 | cut -d: -f2
}
run_rate() { # WORKLOAD [FLAG] -> steps/s
    # shellcheck disable=SC2046
    "$springlab" run $(scene_of "$1") --json --force ${2:+"$2"} |
        awk '{ match($0, /"steps":[^,]*/); s = substr($0, RSTART + 8, RLENGTH - 8)
               match($0, /"wall_seconds":[^,]*/); w = substr($0, RSTART + 15, RLENGTH - 15)
               printf "%.1f\n", s / w }'
}
best() { awk -v a="$1" -v b="$2" 'BEGIN { print (b == "" || a > b) ? a : b }'; }

all=$(nproc)
declare -A rate
for ((round = 1; round <= rounds; round++)); do
    for w in "${workloads[@]}"; do
        for t in 1 "$all"; do
            b=$(SPRINGLAB_THREADS=$t bench_rate "$w")
            r=$(SPRINGLAB_THREADS=$t run_rate "$w")
            q=$(SPRINGLAB_THREADS=$t run_rate "$w" --no-accounting)
            rate[$w,$t,b]=$(best "$b" "${rate[$w,$t,b]:-}")
            rate[$w,$t,r]=$(best "$r" "${rate[$w,$t,r]:-}")
            rate[$w,$t,q]=$(best "$q" "${rate[$w,$t,q]:-}")
        done
    done
done

echo "load $(cut -d' ' -f1-3 /proc/loadavg), $rounds rounds, best of each"
printf '%-12s %7s %12s %12s %7s %14s %7s\n' workload threads bench run run/bench \
    "no accounting" "/bench"
percent() { awk -v b="$1" -v r="$2" 'BEGIN { print 100 * r / b }'; }
for w in "${workloads[@]}"; do
    for t in 1 "$all"; do
        b=${rate[$w,$t,b]} r=${rate[$w,$t,r]} q=${rate[$w,$t,q]}
        printf '%-12s %7s %12.0f %12.0f %6.1f%% %14.0f %6.1f%%\n' "$w" "$t" "$b" "$r" \
            "$(percent "$b" "$r")" "$q" "$(percent "$b" "$q")"
    done
done
