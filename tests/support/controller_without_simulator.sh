#!/usr/bin/env bash
# The controller box: configures the project with the simulator switched off
# (GAUSSTRACK_BUILD_PLANT_SIM=OFF: no plant_sim, no Boost.Odeint, no MuJoCo target exists), builds
# the controller programs, checks that nothing of the simulator entered their compile or link
# lines, and runs gausstrack-controller on a scene's tracking section until it says ready.
# usage: controller_without_simulator.sh SOURCE_DIR WORK_DIR SCENE
set -euo pipefail
source_dir=$1 work=$2 scene=$3
rm -rf "$work"
mkdir -p "$work"
cmake -S "$source_dir" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DGAUSSTRACK_BUILD_PLANT_SIM=OFF \
  -DGAUSSTRACK_BUILD_TESTS=OFF -DGAUSSTRACK_BUILD_BENCH=OFF -DGAUSSTRACK_BUILD_FIRMWARE=OFF \
  -DCMAKE_EXPORT_COMPILE_COMMANDS=ON > "$work/configure.log"
cmake --build "$work/build" -j2 --target gausstrack-controller gausstrack-log-merge > "$work/build.log"
bin="$work/build/bin/gausstrack-controller"
# Nothing of the simulator in the build: no such target, no include path, no library.
if cmake --build "$work/build" --target gausstrack_plant_sim > /dev/null 2>&1; then
  echo "FAIL: the simulator's library is a target of a build without it" >&2
  exit 1
fi
if grep -E "plant_sim|mujoco|boost" "$work/build/compile_commands.json"; then
  echo "FAIL: a compile line above names the simulator, Boost or MuJoCo" >&2
  exit 1
fi
if ldd "$bin" | grep -Ei "mujoco|boost"; then
  echo "FAIL: gausstrack-controller links the simulator's dependencies" >&2
  exit 1
fi
# It runs: configuration read, LCM opened (in-process memq), ready; SIGTERM ends it cleanly.
"$bin" --config "$scene" --lcm-url memq:// > "$work/controller.log" 2>&1 &
pid=$!
for _ in $(seq 100); do grep -q ready "$work/controller.log" && break; sleep 0.05; done
kill -TERM $pid
wait $pid
cat "$work/controller.log"
grep -q "gausstrack-controller: ready (coupled_duffing, 2 coordinates, 1 constraint rows, unauthenticated)" "$work/controller.log"
echo "controller built and ran without the simulator"
