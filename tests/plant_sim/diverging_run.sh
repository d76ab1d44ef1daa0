#!/usr/bin/env bash
# gausstrack-sim on a plant that diverges (its ground spring softens: cubic stiffness -50, while
# the controller's model keeps +2): it must stop within the test's time limit, exit 1 with an
# error naming the time, and keep what it computed: trajectory rows, no NaN, "completed": false.
# usage: diverging_run.sh GAUSSTRACK_SIM SCENE OUT_DIR
set -uo pipefail
sim=$1 scene=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
"$sim" "$scene" --set plant.effects.4.stiffness=-50 --out "$out" 2> "$out/stderr.txt"
status=$?
cat "$out/stderr.txt"
set -e
[ "$status" -eq 1 ]
grep -q "error: .*t = " "$out/stderr.txt"
[ "$(wc -l < "$out/trajectory.csv")" -gt 2 ]
! grep -qi nan "$out/trajectory.csv"
grep -q '"completed": false' "$out/summary.json"
echo "diverging run stopped with its reason; $(($(wc -l < "$out/trajectory.csv") - 1)) samples kept"
