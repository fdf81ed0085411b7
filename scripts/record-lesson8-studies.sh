#!/usr/bin/env bash
# Records the two studies whose results lesson 8 quotes (each about three minutes on a 2-core
# machine) into docs/studies/. tests/lesson8.rs checks every number lesson 8 quotes against these
# files, and re-runs their cheapest rows to check that the files still match the code.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --bin springlab
bin=target/release/springlab
mkdir -p docs/studies
"$bin" study resolution cloth-sphere --json > docs/studies/resolution-cloth-sphere.json
"$bin" advise jelly-bowl --tolerance 0.01 --json > docs/studies/advise-jelly-bowl.json
echo "recorded docs/studies/resolution-cloth-sphere.json and docs/studies/advise-jelly-bowl.json"
