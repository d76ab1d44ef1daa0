#!/usr/bin/env bash
# gausstrack-sim on a run whose answers give the task row up (a singular-value floor far above
# D A^(-1/2)'s): the run completes and writes its data, but exits 1 saying that it did not track,
# in what share of the evaluations and with which warnings; its summary counts them.
# usage: untracked_run.sh GAUSSTRACK_SIM SCENE OUT_DIR
set -uo pipefail
sim=$1 scene=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
"$sim" "$scene" --set duration=0.5 --set tracking.min_singular_value=1e6 --out "$out" 2> "$out/stderr.txt"
status=$?
cat "$out/stderr.txt"
set -e
[ "$status" -eq 1 ]
grep -q "error: .*did not track: the task rows were not met in 100.0 % of the control evaluations" "$out/stderr.txt"
grep -q "near_singular" "$out/stderr.txt"
grep -q '"completed": true' "$out/summary.json"
grep -q '"rows_not_met_share": 1' "$out/summary.json"
[ "$(wc -l < "$out/trajectory.csv")" -gt 2 ]
echo "a run that did not track says so; its data is written"
