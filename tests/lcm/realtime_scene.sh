#!/usr/bin/env bash
# Any scene over LCM in real time at 1 kHz for 2 s, run as a user runs it on a busy machine
# (--realtime where permitted). Asserts what the product guarantees whatever the load: every
# period is accounted for (a fresh command applied or a missing one counted), nothing is
# rejected, and the tracking error stays below BOUND while commands keep coming (no watchdog
# trip) and is back below it at the end in any case.
# A run that misses the bound while the machine held the loop back 10 ms or more (the plant woke
# that late, or the controller found that many periods' states queued at once: machine_stall.py)
# runs once more and says so, as the fault campaign does; a product fault shows in both runs.
# usage: realtime_scene.sh BIN_DIR SCENE WORK_DIR BOUND [--set key=value ...]
set -euo pipefail
bin=$1 scene=$2 work=$3 bound=$4
shift 4

run_once() {
  rm -rf "$work" && mkdir -p "$work"
  "$bin/gausstrack-run" "$scene" --rate 1000 --duration 2 --out "$work/run" --channel-prefix "RT$$" --realtime \
    --no-plots "$@" > "$work/run.log"
  /usr/bin/python3 - "$work/run/summary.json" "$work/run/trajectory.csv" "$bound" "$(dirname "$0")" <<'PY'
import csv, json, sys
sys.path.insert(0, sys.argv[4])
from machine_stall import machine_stall
s = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
bound = float(sys.argv[3])
stall = machine_stall(s)
print({k: s[k] for k in ("max_tracking_error", "rms_tracking_error", "states_published", "commands_applied",
                         "commands_missing", "commands_failed", "deadline_misses", "watchdog_trips",
                         "largest_backlog")},
      f"latest wake {((s.get('wake_late_us') or {}).get('max', 0.0)) / 1e3:.1f} ms")
assert s["mode"] == "realtime" and s["completed"], s
assert s["states_published"] == 2000, s["states_published"]
assert s["commands_applied"] + s["commands_missing"] == s["states_published"]
assert s["messages_rejected"] == 0 and s["commands_failed"] == 0
final = abs(float(rows[-1]["tracking_error"]))
bound_met = (s["watchdog_trips"] > 0 or s["max_tracking_error"] < bound) and final < bound
if not bound_met:
    print(f"tracking error {s['max_tracking_error']:.3g} (final {final:.3g}) above {bound}")
    if stall:
        print(stall)
    sys.exit(3 if stall else 1)  # 3: the machine held the loop back
PY
}

status=0
run_once "$@" || status=$?
if [ "$status" -eq 3 ]; then
  echo "run again: the machine held the loop back 10 ms or more in the first run"
  status=0
  run_once "$@" || status=$?
fi
[ "$status" -eq 0 ] || { echo "FAIL"; exit 1; }
