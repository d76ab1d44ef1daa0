#!/usr/bin/env bash
# gausstrack-run in real time at 1 kHz for 2 s with stabilization (zeta 1, omega 20), run the way
# a user runs it on a busy machine: --realtime (SCHED_FIFO, pinning, mlockall where permitted; CI
# runs as root), the plant spinning the last 200 us of each period (--spin-us). What is asserted
# is what the product guarantees whatever the load, not how well an unprivileged loop keeps time
# (that is measured by scripts/bench):
# - every period is accounted for: a fresh command applied or a missing one counted;
# - the log holds every state and command the processes published, exactly;
# - while commands keep coming (no watchdog trip) the tracking error stays below 1e-2: the hold
#   lags the law by 1 to 2 periods, which with stabilization keeps it near 1e-3 (measured: max
#   1.1e-3, rms 4.6e-4), and a late command only extends one hold; without the loop closed the
#   error is O(1). After a watchdog trip the error must be back below 1e-2 at the end.
# usage: realtime_run.sh BIN_DIR SCENE WORK_DIR TEST_BIN_DIR
set -euo pipefail
bin=$1 scene=$2 work=$3 test_bin=$4
rm -rf "$work" && mkdir -p "$work"
# A malformed CPU placement is refused before anything starts, with what it expects.
for bad in "--realtime --cpus 1" "--realtime --cpus 1,x" "--realtime --cpus -1,0" "--cpus 0,0"; do
  # shellcheck disable=SC2086
  if "$bin/gausstrack-run" "$scene" $bad --no-plots > "$work/bad.txt" 2>&1; then
    echo "gausstrack-run accepted $bad" >&2; exit 1
  fi
  grep -q -- "--cpus" "$work/bad.txt" || { cat "$work/bad.txt" >&2; exit 1; }
done
# So is a spin that is negative, not shorter than the period (1000 us at 1 kHz), asked for in
# lock-step (which has no deadlines), or given twice (also as an abbreviation, which argparse takes).
for bad in "--spin-us -1" "--spin-us 1000" "--lockstep --spin-us 10" "--spin-us 10 --spin-us=20" "--spin-us 10 --spin=20"; do
  # shellcheck disable=SC2086
  if "$bin/gausstrack-run" "$scene" --rate 1000 $bad --no-plots > "$work/bad.txt" 2>&1; then
    echo "gausstrack-run accepted $bad" >&2; exit 1
  fi
  grep -q -- "--spin-us" "$work/bad.txt" || { cat "$work/bad.txt" >&2; exit 1; }
done
# The plant itself, run without gausstrack-run, refuses it too, as a malformed command line (status 2).
status=0
"$bin/gausstrack-plant" --scene "$scene" --set control.mode=sampled --set control.rate=1000 --spin-us 1000 \
  --out "$work/bad_plant" > "$work/bad.txt" 2>&1 || status=$?
[ "$status" -eq 2 ] && grep -q -- "--spin-us 1000" "$work/bad.txt" || { echo "status $status"; cat "$work/bad.txt"; exit 1; } >&2
status=0
"$bin/gausstrack-plant" --scene "$scene" --set control.mode=sampled --lockstep --spin-us 10 \
  --out "$work/bad_plant" > "$work/bad.txt" 2>&1 || status=$?
[ "$status" -eq 2 ] && grep -q -- "--spin-us" "$work/bad.txt" || { echo "status $status"; cat "$work/bad.txt"; exit 1; } >&2
prefix="REALTIME$$"
"$bin/gausstrack-run" "$scene" --rate 1000 --duration 2 --set "tracking.stabilization={zeta: 1.0, omega: 20.0}" \
  --out "$work/run" --channel-prefix "$prefix" --realtime --spin-us 200 --no-plots --log "$work/run.lcmlog" \
  > "$work/run.txt" &
run=$!
trap 'kill "$run" 2> /dev/null || true' EXIT
# While it runs: each process's threads with their scheduling policy (field 41 of the thread's
# stat; 1 is SCHED_FIFO), kept from the last moment both processes had all three (the loop, LCM's
# receive thread, the log's writer) or more.
: > "$work/threads.txt"
while kill -0 "$run" 2> /dev/null; do
  snapshot=""
  for pid in $(pgrep -f -- "${prefix}_STATE" || true); do
    for task in /proc/"$pid"/task/*; do
      policy=$(sed 's/.*) //' "$task/stat" 2> /dev/null | awk '{ print $39 }') || true
      [ -n "$policy" ] && snapshot+="$pid ${task##*/} $policy"$'\n'
    done
  done
  counts=$(printf '%s' "$snapshot" | awk 'NF { n[$1]++ } END { k = 0; for (p in n) if (n[p] >= 3) k++; print k }')
  [ "$counts" -eq 2 ] && printf '%s' "$snapshot" > "$work/threads.txt"
  sleep 0.05
done
wait "$run"
cat "$work/run.txt"
grep -q "deadline misses .* (spinning up to 200 us before each deadline" "$work/run.txt"   # the summary says so
/usr/bin/python3 - "$work/threads.txt" <<'PY'
import collections, sys
threads = collections.defaultdict(dict)
for line in open(sys.argv[1]):
    pid, tid, policy = line.split()
    threads[pid][tid] = int(policy)
assert len(threads) == 2, f"both processes' threads were not seen: {dict(threads)}"
for pid, tasks in threads.items():
    if tasks[pid] != 1:
        print(f"process {pid}: SCHED_FIFO not permitted here, thread policies not checked")
        continue
    # The loop and LCM's receive thread (which hands it every message) real-time; the log's
    # writer an ordinary thread (a late writer drops and counts, it never holds the loop).
    policies = sorted(tasks.values())
    assert policies.count(0) == 1 and policies.count(1) >= 2, f"process {pid}: thread policies {tasks}"
print("thread policies:", {pid: sorted(t.values()) for pid, t in threads.items()})
PY
"$test_bin/lcm_log_summary" "$work/run.lcmlog" > "$work/log.txt"
/usr/bin/python3 - "$work/run/summary.json" "$work/log.txt" "$prefix" "$work/run/trajectory.csv" <<'PY'
import csv, json, sys
s = json.load(open(sys.argv[1]))
counts = {}
for line in open(sys.argv[2]):
    if line.startswith("channel "):
        _, name, n = line.split()
        counts[name] = int(n)
prefix = sys.argv[3]
rows = list(csv.DictReader(open(sys.argv[4])))
print({k: s[k] for k in ("max_tracking_error", "rms_tracking_error", "states_published", "commands_applied",
                         "commands_missing", "commands_published", "deadline_misses", "watchdog_trips")}, counts)
assert s["mode"] == "realtime"
assert s["spin_us"] == 200, s["spin_us"]   # --spin-us reached the plant
assert 0 < s["spun_ms"] <= 2000 * 0.2, s["spun_ms"]   # at most 200 us in each of 2000 periods
assert s["states_published"] == 2000, s["states_published"]
assert s["commands_applied"] + s["commands_missing"] == s["states_published"]
assert 0 < s["commands_published"] <= s["states_published"]
assert s["messages_rejected"] == 0
assert s["log_dropped"] == 0
assert counts[prefix + "_STATE"] == s["states_published"], counts
assert counts[prefix + "_COMMAND"] == s["commands_published"], counts
assert counts[prefix + "_STATS"] == 2, counts
assert s["round_trip_us"]["count"] >= s["commands_applied"]   # one round trip per accepted command
final = abs(float(rows[-1]["tracking_error"]))
if s["watchdog_trips"] == 0:
    assert s["max_tracking_error"] < 1e-2, s["max_tracking_error"]
assert final < 1e-2, final
PY
