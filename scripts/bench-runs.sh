# Sourced by bench-vs-cpp.sh and speed-table.sh: one timed run of a workload, by springlab
# (`$springlab`, its threads from SPRINGLAB_THREADS as set by the caller) or by the C++
# reference (`$cpp`), `$repeats` repeats, printed as "steps/s cx cy cz E".

springlab_run() { # WORKLOAD -> "steps/s cx cy cz E"
    "$springlab" bench "$1" --json --repeats "$repeats" --budget 0 --force |
        awk '{
            match($0, /"steps_per_second":[^,]*/); s = substr($0, RSTART + 19, RLENGTH - 19)
            match($0, /"centroid":\[[^]]*\]/); c = substr($0, RSTART + 12, RLENGTH - 13); gsub(",", " ", c)
            match($0, /"energy":[^,]*/); e = substr($0, RSTART + 9, RLENGTH - 9)
            print s, c, e }'
}
cpp_run() { # WORKLOAD -> "steps/s cx cy cz E"
    "$cpp" "$1" --reps "$repeats" | awk '/^RESULT/ {
        for (i = 1; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
        print v["steps_per_s"], v["cx"], v["cy"], v["cz"], v["E"] }'
}
