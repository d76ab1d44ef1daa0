#!/usr/bin/env bash
# Checks the model, runs the example offline, then as two LCM processes in lock-step, and checks
# that both track.
# usage: run.sh BUILD_DIR OUT_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$1 out=$2
scene="$here/tethered_puck.yaml"
mkdir -p "$out/offline" "$out/lcm"
"$build/my_model_check"
"$build/my_model_sim" "$scene" "$out/offline"
url="udpm://239.255.76.67:7667?ttl=0"
sets=(--set control.mode=sampled --set control.rate=500)
"$build/my_model_controller" --config "$scene" --lcm-url "$url" --state-channel "PUCK_STATE_$$" \
  --command-channel "PUCK_COMMAND_$$" > "$out/lcm/controller.log" &
controller=$!
trap 'kill $controller 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q ready "$out/lcm/controller.log" && break; sleep 0.05; done
"$build/my_model_plant" --scene "$scene" "${sets[@]}" --lockstep --lcm-url "$url" --state-channel "PUCK_STATE_$$" \
  --command-channel "PUCK_COMMAND_$$" --out "$out/lcm"
kill -TERM $controller && wait $controller
cat "$out/lcm/controller.log"
/usr/bin/python3 - "$out/offline/summary.json" "$out/lcm/summary.json" <<'PY'
import json, sys
offline, lcm = (json.load(open(p)) for p in sys.argv[1:3])
print(f"offline max tracking error {offline['max_tracking_error']:.3g}, over LCM {lcm['max_tracking_error']:.3g}")
assert offline["completed"] and lcm["completed"]
assert offline["max_tracking_error"] < 2e-2 and lcm["max_tracking_error"] < 2e-2
assert lcm["commands_applied"] == lcm["states_published"] == 5000 and lcm["commands_missing"] == 0
PY
