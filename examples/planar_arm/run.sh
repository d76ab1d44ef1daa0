#!/usr/bin/env bash
# The arm offline, through its stretched configuration, then as the shipped controller and plant
# processes over LCM in lock-step (the installed gausstrack-controller and gausstrack-plant).
# usage: run.sh BUILD_DIR INSTALL_PREFIX OUT_DIR
set -euo pipefail
build=$1 prefix=$2 out=$3
bin=$prefix/bin arm=$prefix/share/gausstrack/scenes/planar_arm.yaml
mkdir -p "$out/stretched" "$out/lcm"
"$build/planar_arm_track" "$arm"
"$build/planar_arm_stretched" "$out/stretched" | tee "$out/stretched/table.md"
url="udpm://239.255.76.67:7667?ttl=0"
"$bin/gausstrack-controller" --config "$arm" --lcm-url "$url" --state-channel "ARM_STATE_$$" \
  --command-channel "ARM_COMMAND_$$" > "$out/lcm/controller.log" &
controller=$!
trap 'kill $controller 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q ready "$out/lcm/controller.log" && break; sleep 0.05; done
"$bin/gausstrack-plant" --scene "$arm" --set control.mode=sampled --set control.rate=1000 --lockstep \
  --lcm-url "$url" --state-channel "ARM_STATE_$$" --command-channel "ARM_COMMAND_$$" --out "$out/lcm"
kill -TERM $controller && wait $controller
cat "$out/lcm/controller.log"
/usr/bin/python3 - "$out/lcm/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["completed"] and s["commands_missing"] == 0 and s["max_tracking_error"] < 1e-3, s
print(f"over LCM at 1 kHz: max tracking error {s['max_tracking_error']:.3g} m")
PY
