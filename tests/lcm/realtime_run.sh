#!/usr/bin/env bash
# gausstrack-run in real time at 1 kHz for 2 s with stabilization (zeta 1, omega 20): the loop
# closes and the statistics add up.
# The plant holds each command for one period and applies the command answering state k only
# from period k + 1, so the force lags the law by 1 to 2 ms; with stabilization that lag keeps
# the tracking error near 1e-3 (measured: max 1.1e-3, rms 4.6e-4). The bound checked, 1e-2,
# leaves room for a loaded machine's late commands; without the loop closed the error is O(1).
# usage: realtime_run.sh BIN_DIR SCENE WORK_DIR
set -euo pipefail
bin=$1 scene=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
"$bin/gausstrack-run" "$scene" --rate 1000 --duration 2 --set "tracking.stabilization={zeta: 1.0, omega: 20.0}" \
  --out "$work/run" --channel-prefix "REALTIME$$" --realtime --no-plots
/usr/bin/python3 - "$work/run/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print({k: s[k] for k in ("max_tracking_error", "rms_tracking_error", "states_published", "commands_applied",
                         "commands_missing", "commands_published", "deadline_misses", "watchdog_trips")})
assert s["mode"] == "realtime"
assert s["states_published"] == 2000, s["states_published"]
# Every period applied a fresh command or counted one missing; the controller answered every state.
assert s["commands_applied"] + s["commands_missing"] == s["states_published"]
assert s["states_published"] - 5 <= s["commands_published"] <= s["states_published"]
assert s["commands_applied"] >= 1900          # a few periods may miss on a loaded machine
assert s["messages_rejected"] == 0
assert s["max_tracking_error"] < 1e-2 and s["rms_tracking_error"] < 5e-3
assert s["round_trip_us"]["count"] >= s["commands_applied"]   # one round trip per accepted command
assert 0 < s["round_trip_us"]["p50"] <= s["round_trip_us"]["p99"] <= s["round_trip_us"]["max"]
PY
