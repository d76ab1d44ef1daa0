#!/usr/bin/env bash
# Any scene over LCM in lock-step equals its offline run: gausstrack-run --lockstep (controller
# and plant as two processes, the controller reading only the scene's tracking section) against
# gausstrack-sim with the same sampled control; every column of every sample agrees to 1e-12
# relative, and every period has its command.
# usage: lockstep_scene.sh BIN_DIR SCENE WORK_DIR RATE_HZ DURATION_S
set -euo pipefail
bin=$1 scene=$2 work=$3 rate=$4 duration=$5
rm -rf "$work" && mkdir -p "$work"
"$bin/gausstrack-run" "$scene" --rate "$rate" --duration "$duration" --lockstep --timeout-ms 5000 \
  --out "$work/lockstep" --channel-prefix "LS$$" --no-plots > "$work/run.log"
"$bin/gausstrack-sim" "$scene" --set control.mode=sampled --set "control.rate=$rate" --set "duration=$duration" \
  --out "$work/offline" > "$work/offline.log"
paste -d, "$work/lockstep/trajectory.csv" "$work/offline/trajectory.csv" | awk -F, '
  NR == 1 { n = NF / 2; for (i = 1; i <= n; ++i) if ($i != $(i + n)) { print "header differs"; exit 1 }; next }
  {
    for (i = 1; i <= n; ++i) {
      if ($i ~ /nan|inf/ || $(i + n) ~ /nan|inf/) { print "non-finite value in row " NR; exit 1 }
      a = $i; b = $(i + n); d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b
      r = d / (1 + s); if (r > worst) worst = r
    }
    rows++
  }
  END {
    printf "lock-step vs offline: %d samples of %d columns, worst relative difference %.3g\n", rows, n, worst
    if (rows < 2 || worst > 1e-12) exit 1
  }'
/usr/bin/python3 - "$work/lockstep/summary.json" "$rate" "$duration" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
periods = round(float(sys.argv[2]) * float(sys.argv[3]))
assert s["completed"], s
assert s["states_published"] == periods and s["commands_applied"] == periods, s
assert s["commands_missing"] == 0 and s["commands_failed"] == 0 and s["messages_rejected"] == 0, s
print(f"{periods} periods, each with its command; max tracking error {s['max_tracking_error']:.3g}")
PY
