#!/usr/bin/env bash
# Lock-step over LCM reproduces the offline gausstrack-sim of the same sampled-data scene:
# every sample of every column agrees to 1e-12 (relative to 1 + |value|).
# usage: lockstep_matches_offline.sh BIN_DIR SCENE WORK_DIR
set -euo pipefail
bin=$1 scene=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
sets=(--set control.mode=sampled --set control.rate=100 --set "tracking.stabilization={zeta: 1.0, omega: 20.0}")
# Channels unique to this run, so that parallel tests do not hear each other.
state=LOCKSTEP_STATE_$$ command=LOCKSTEP_COMMAND_$$

"$bin/gausstrack-controller" --scene "$scene" "${sets[@]}" --state-channel "$state" --command-channel "$command" \
  > "$work/controller.log" 2>&1 &
controller=$!
trap 'kill $controller 2>/dev/null || true' EXIT
sleep 0.5
"$bin/gausstrack-plant" --scene "$scene" "${sets[@]}" --lockstep --timeout-ms 5000 --out "$work/lockstep" \
  --state-channel "$state" --command-channel "$command"
kill -TERM $controller
wait $controller
cat "$work/controller.log"
grep -q "1000 commands published, 0 messages rejected" "$work/controller.log"

"$bin/gausstrack-sim" "$scene" "${sets[@]}" --out "$work/offline"

paste -d, "$work/lockstep/trajectory.csv" "$work/offline/trajectory.csv" | awk -F, '
  NR == 1 { n = NF / 2; for (i = 1; i <= n; ++i) if ($i != $(i + n)) { print "header differs"; exit 1 }; next }
  {
    for (i = 1; i <= n; ++i) {
      a = $i; b = $(i + n); d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b
      r = d / (1 + s); if (r > worst) worst = r
    }
    rows++
  }
  END {
    printf "lock-step vs offline: %d samples, worst relative difference %.3g\n", rows, worst
    if (rows != 1001 || worst > 1e-12) exit 1
  }'
