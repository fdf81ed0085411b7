#!/usr/bin/env bash
# Plays every step of every built-in lesson in a real sixel terminal (xterm -ti vt340, 120×40,
# under Xvfb), runs it for WAIT seconds and keeps a picture of its two status lines (method, dt
# and view; running, t, steps per frame, real-time factor, steps/s, frames/s); at the end the
# pictures are stacked into OUT/all.png, one step under the other in lesson order, to read.
# A step that asks a prediction first gets answer 1 (the run waits for an answer).
#
# Usage: scripts/lesson-sweep.sh [-w WAIT] [-o OUT] [LESSON...]
#   WAIT     seconds each step runs (default 8)
#   OUT      folder for the pictures (default /tmp/springlab-sweep)
#   LESSON   lesson numbers (default: every lesson `springlab lessons` lists)
# Needs Debian's xvfb, xterm, xdotool, x11-apps, x11-utils and imagemagick; uses display :99 (started when
# nothing answers there); springlab from $SPRINGLAB, else target/release/springlab.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

wait_s=8 out=/tmp/springlab-sweep
while getopts "w:o:h" opt; do
    case "$opt" in
        w) wait_s="$OPTARG" ;;
        o) out="$OPTARG" ;;
        *) sed -n '2,14p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
for tool in Xvfb xterm xdotool xwd xdpyinfo convert; do
    command -v "$tool" >/dev/null || { echo "lesson-sweep: needs $tool (see the usage)" >&2; exit 2; }
done
springlab="$(realpath "${SPRINGLAB:-target/release/springlab}")"
[ -x "$springlab" ] || { echo "lesson-sweep: no $springlab (cargo build --release)" >&2; exit 2; }

export DISPLAY=:99
if ! xdpyinfo >/dev/null 2>&1; then
    Xvfb :99 -screen 0 1600x1000x24 >/dev/null 2>&1 &
    sleep 1
fi
mkdir -p "$out"
rm -f "$out"/step-*.png "$out/all.png"
data=$(mktemp -d)
trap 'pkill -x xterm 2>/dev/null || true; rm -rf "$data"' EXIT

# "N. Title (name, S steps): ..." → "N S"
mapfile -t lessons < <("$springlab" lessons | sed -n 's/^ *\([0-9]*\)\. .*(.*, \([0-9]*\) steps).*/\1 \2/p')
# Steps with a prediction: "lesson step" from the lessons' front matter.
predicts=$(for f in lessons/*.md; do
    n=$(basename "$f" | sed 's/^0*\([0-9]*\)-.*/\1/')
    awk -v n="$n" '/^\+\+\+ step/ {s++} /^predict *=/ {print n, s}' "$f"
done)

for entry in "${lessons[@]}"; do
    read -r lesson count <<<"$entry"
    if [ $# -gt 0 ] && [[ " $* " != *" $lesson "* ]]; then continue; fi
    for ((step = 1; step <= count; step++)); do
        pkill -x xterm 2>/dev/null || true
        sleep 0.5
        xterm -ti vt340 -xrm 'XTerm*numColorRegisters: 256' -geometry 120x40+0+0 \
            -fa 'DejaVu Sans Mono' -fs 10 \
            -e env SPRINGLAB_DATA_DIR="$data" "$springlab" lesson "$lesson" --no-save &
        sleep 2.5
        xdotool mousemove 300 300 click 1
        for ((i = 1; i < step; i++)); do xdotool key n; sleep 0.7; done
        if grep -qx "$lesson $step" <<<"$predicts"; then xdotool key 1; sleep 0.7; fi
        xdotool key space
        sleep "$wait_s"
        xwd -root -silent | convert xwd:- -crop 960x38+0+630 "$out/step-$lesson-$step.png"
        echo "lesson $lesson step $step: $out/step-$lesson-$step.png"
    done
done
pkill -x xterm 2>/dev/null || true
convert $(ls "$out"/step-*.png | sort -V) -append "$out/all.png"
echo "all steps: $out/all.png"
