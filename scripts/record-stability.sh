#!/usr/bin/env bash
# Records the stability study of the scenes docs/stability.md tabulates into docs/studies/
# (minutes a scene: the confirmation runs). tests/doc_numbers.rs checks that the page's table is
# these recordings (on a mismatch it prints the table to put between the page's markers), re-runs
# the rope's study and recomputes every scene's damped theory to check that they still hold.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --bin springlab
bin=target/release/springlab
mkdir -p docs/studies
for scene in rope cube-plane jelly-bowl cloth-spheres; do
    "$bin" study stability "$scene" --no-usable --json > "docs/studies/stability-$scene.json"
    echo "recorded docs/studies/stability-$scene.json"
done
