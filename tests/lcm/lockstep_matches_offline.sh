#!/usr/bin/env bash
# gausstrack-run --lockstep over LCM reproduces the offline gausstrack-sim of the same
# sampled-data scene: every sample of every column agrees to 1e-12 (relative to 1 + |value|).
# Its summary.json has the fields users read, its statistics add up, and its --log holds every
# state, command and both processes' loop_stats_t, exactly.
# usage: lockstep_matches_offline.sh BIN_DIR TEST_BIN_DIR SCENE WORK_DIR
set -euo pipefail
bin=$1 test_bin=$2 scene=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
sets=(--set "tracking.stabilization={zeta: 1.0, omega: 20.0}")
# Channels unique to this run, so that parallel tests do not hear each other.
"$bin/gausstrack-run" "$scene" --rate 100 --lockstep --timeout-ms 5000 "${sets[@]}" --out "$work/lockstep" \
  --channel-prefix "LOCKSTEP$$" --log "$work/run.lcmlog" --no-plots
"$bin/gausstrack-sim" "$scene" "${sets[@]}" --set control.mode=sampled --set control.rate=100 --out "$work/offline"

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

/usr/bin/python3 - "$work/lockstep/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for k in ("max_tracking_error", "rms_tracking_error", "deadline_misses", "states_published", "commands_applied",
          "commands_missing", "messages_rejected", "watchdog_trips"):
    assert isinstance(s[k], (int, float)), k
for k in ("p50", "p99", "p999", "max"):
    assert s["round_trip_us"][k] > 0, k
for k in ("p50", "p99", "max"):
    assert s["compute_ns"][k] > 0, k
assert s["round_trip_us"]["p50"] <= s["round_trip_us"]["p99"] <= s["round_trip_us"]["p999"] <= s["round_trip_us"]["max"]
assert s["states_published"] == s["commands_applied"] == s["commands_published"] == 1000, s
assert s["commands_missing"] == 0 and s["messages_rejected"] == 0 and s["watchdog_trips"] == 0, s
assert s["log_dropped"] == 0, s
print("summary.json: fields present, 1000 states answered by 1000 commands")
PY

"$test_bin/lcm_log_summary" "$work/run.lcmlog" | tee "$work/log.txt"
# The log is complete: each process recorded every message it published, so the counts are exact.
grep -Fxq "channel LOCKSTEP$$_STATE 1000" "$work/log.txt"
grep -Fxq "channel LOCKSTEP$$_COMMAND 1000" "$work/log.txt"
grep -Fxq "channel LOCKSTEP$$_STATS 2" "$work/log.txt"
[ "$(grep -c '^channel ' "$work/log.txt")" -eq 3 ]
grep -q "stats plant states_published=1000 commands_applied=1000" "$work/log.txt"
grep -q "stats controller .*commands_published=1000 messages_rejected=0" "$work/log.txt"
