#!/usr/bin/env bash
# The controller counts and ignores malformed and hostile messages, and keeps running.
# usage: hostile_messages.sh BIN_DIR TEST_BIN_DIR SCENE WORK_DIR
set -euo pipefail
bin=$1 test_bin=$2 scene=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
state=HOSTILE_STATE_$$
"$bin/gausstrack-controller" --scene "$scene" --state-channel "$state" --command-channel HOSTILE_COMMAND_$$ \
  > "$work/controller.log" 2>&1 &
controller=$!
trap 'kill $controller 2>/dev/null || true' EXIT
sleep 0.5
"$test_bin/lcm_hostile_publisher" "$state"
sleep 0.3
kill -TERM $controller
wait $controller
cat "$work/controller.log"
grep -q "1 commands published (0 failed solves), 0 states superseded by a newer one, 1 plant runs, 6 messages rejected" "$work/controller.log"
