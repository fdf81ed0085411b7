#!/usr/bin/env bash
# Where a study's steps go: the steps of each phase, from the study's own `--json` report (no
# timing, so the counts are the same on any machine). A step of a method costs its force
# evaluations per step (explicit Euler 1, midpoint 2, RK4 4, ...); a linear probe's power step
# costs two steps of the method (central differences).
#
# Usage: scripts/study-steps.sh REPORT.json
#   REPORT.json: the output of `springlab study stability SCENE --json`,
#   `springlab advise SCENE --json` or `springlab study resolution SCENE --json`.
set -euo pipefail
if [[ $# -ne 1 ]]; then
    echo "usage: $0 REPORT.json" >&2
    exit 2
fi
report="$1"
if jq -e 'has("methods")' "$report" > /dev/null; then
    # study stability: per method, linear probes (power steps), confirmation runs (passing and
    # failing), the usable-dt search's fit and check runs.
    jq -r '
      ["method", "probes", "confirm-pass", "confirm-fail", "usable-fit", "usable-check"],
      (.methods[] | [
        .method,
        ([.probes[].steps] | add // 0),
        ([.confirmations[] | select(.passed) | .steps] | add // 0),
        ([.confirmations[] | select(.passed | not) | .steps] | add // 0),
        ([(.usable.runs // [])[] | select(.role == "fit") | .steps] | add // 0),
        ([(.usable.runs // [])[] | select(.role == "check") | .steps] | add // 0)
      ]),
      ["stiffest state", "\(.stiffest_state.samples) samples of ω_max at dt = \(.stiffest_state.dt) s"]
      | @tsv' "$report" | column -t -s $'\t'
elif jq -e 'has("candidates")' "$report" > /dev/null; then
    # advise: the reference chain (RK4 halvings), the candidates, the verifications.
    jq -r '
      .time as $t |
      ["phase", "runs", "steps"],
      ["reference chain (\(.reference.method))", (.reference.chain | length),
       ([.reference.chain[][0] | $t / . | round] | add)],
      ["candidates", (.candidates | length), ([.candidates[].steps] | add // 0)],
      ["verifications: confirmation at 1.5 dt", (.verifications | length),
       ([.verifications[].stability.steps] | add // 0)]
      | @tsv' "$report" | column -t -s $'\t'
elif jq -e 'has("runs")' "$report" > /dev/null; then
    # study resolution: one run per level and spring kinds, and the time-step check.
    # The time-step check (the base level again at dt / 2) is not listed: twice the base's steps.
    jq -r '
      ["level", "kinds", "springs", "steps", "force evaluations"],
      (.runs[] | [.n, .kinds, .springs, .run.steps, .run.force_evals])
      | @tsv' "$report" | column -t -s $'\t'
else
    echo "$report: not a report of study stability, advise or study resolution" >&2
    exit 1
fi
