#!/usr/bin/env bash
# The CPU time of every rustc run of a build, one line per crate ("user sys wall crate kind"),
# for builds on a busy machine, where the wall times of `--timings` say little:
#
#   RUSTC_CPU_LOG=$PWD/rustc-cpu.log RUSTC_WRAPPER=$PWD/scripts/rustc-cpu.sh \
#       CARGO_TARGET_DIR=$PWD/target-cpu cargo build --release
#   sort -rn rustc-cpu.log | head -30
#
# Cargo runs it as `rustc-cpu.sh RUSTC ARGS...`. Needs GNU time (`/usr/bin/time`).
set -euo pipefail
log=${RUSTC_CPU_LOG:?set RUSTC_CPU_LOG to the log file (an absolute path)}
rustc=$1
shift
name="?" kind="?" prev=""
for a in "$@"; do
    case $prev in
        --crate-name) name=$a ;;
        --crate-type) kind=$a ;;
    esac
    [ "$a" = --test ] && kind=test
    prev=$a
done
exec /usr/bin/time -a -o "$log" -f "%U %S %e $name $kind" "$rustc" "$@"
