#!/usr/bin/env bash
# Records the two studies whose results lesson 8 and docs/studies.md quote into docs/studies/.
# tests/lesson8.rs checks every number lesson 8 quotes against these files and re-runs their
# cheapest rows to check that the files still match the code; tests/recorded_numbers.rs checks
# docs/studies.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --bin springlab
bin=target/release/springlab
mkdir -p docs/studies
# The levels lesson 8's table shows (the default stops one level above the scene's n = 25).
"$bin" study resolution cloth-sphere --n 9,13,17,25,35,49 --json > docs/studies/resolution-cloth-sphere.json
# The advice is recorded with the exact spring kernel (AVX2 or portable, the same bits on every
# x86-64 machine); tests/recorded_numbers.rs re-runs its recommendation with that kernel.
SPRINGLAB_KERNEL=exact "$bin" advise jelly-bowl --tolerance 0.01 --json > docs/studies/advise-jelly-bowl.json
echo "recorded docs/studies/resolution-cloth-sphere.json and docs/studies/advise-jelly-bowl.json"
