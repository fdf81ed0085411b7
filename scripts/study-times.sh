#!/usr/bin/env bash
# Times the five studies a user waits for (issue 29: each should end within 10 s on a 2-core
# machine), one after another: wall and CPU seconds of each, with the load average before and
# after and the CPU's name, so that two builds are compared in one session.
#
# Usage: scripts/study-times.sh [-o DIR]
#   -o DIR   also keep each command's printed table in DIR (timings blanked, see below), to diff
#            the tables of two builds: `diff -r DIR_A DIR_B` must print nothing.
# springlab is $SPRINGLAB, else target/release/springlab (built when missing).
#
# The tables carry timings (the stability table's last line, the wall column of advise and of
# study resolution, advise's "s in all"); the kept copies have them replaced by `T`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=""
while getopts "o:" opt; do
    case "$opt" in
        o) out="$OPTARG" ;;
        *) echo "usage: $0 [-o DIR]" >&2; exit 2 ;;
    esac
done
bin="${SPRINGLAB:-target/release/springlab}"
if [[ ! -x "$bin" ]]; then
    cargo build --release --bin springlab
fi
if [[ -n "$out" ]]; then
    mkdir -p "$out"
fi
commands=(
    "study stability jelly-bowl"
    "study stability cube-plane"
    "study stability cloth-spheres"
    "advise jelly-bowl --tolerance 0.01"
    "study resolution cloth-sphere"
)
cpu="$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ *//' || true)"
echo "springlab: $bin; CPU: ${cpu:-unknown}, $(nproc) threads; SPRINGLAB_THREADS=${SPRINGLAB_THREADS:-unset}"
printf '%-40s %10s %10s  %s\n' "command" "wall (s)" "CPU (s)" "load average before → after"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
for c in "${commands[@]}"; do
    before="$(cut -d' ' -f1-3 /proc/loadavg)"
    read -r -a words <<< "$c"
    # bash's `time` keyword: real and user + system seconds of the command and its threads.
    TIMEFORMAT='%R %U %S'
    { time "$bin" "${words[@]}" > "$scratch/table" 2> "$scratch/err"; } 2> "$scratch/time" || {
        echo "failed: springlab $c" >&2
        cat "$scratch/err" >&2
        exit 1
    }
    read -r wall user sys < "$scratch/time"
    after="$(cut -d' ' -f1-3 /proc/loadavg)"
    printf '%-40s %10.2f %10.2f  %s → %s\n' "$c" "$wall" "$(awk "BEGIN { print $user + $sys }")" "$before" "$after"
    if [[ -n "$out" ]]; then
        name="$(echo "$c" | tr ' ' '_' | tr -d -- '-' )"
        # Timings are the only numbers printed with exactly two decimals (or one, before
        # "s in all"); signed percentages and the other columns have more or a sign. The
        # padding before a timing goes with it (a wall time of 10 s is one column wider).
        sed -E -e 's/(^|[ (]) *[0-9]+\.[0-9]{2}( |$)/\1T\2/g' \
            -e 's/(^|[ (]) *[0-9]+\.[0-9]{2}( |$)/\1T\2/g' \
            -e 's/, [0-9.]+ s in all$/, T s in all/' \
            "$scratch/table" > "$out/$name.txt"
    fi
done
