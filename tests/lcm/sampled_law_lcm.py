#!/usr/bin/env python3
"""The sampled-data law over LCM: the Duffing loop (alpha = 4, stabilization zeta 1, omega 20) at
1 kHz for 3 s, the controller holding the law for the middle of the interval its answer acts on
(tracking.hold: midpoint, the default), with two checks:

1. Real time against lock-step. The largest tracking error in real time, where no answer was
   missing, is at most 3x lock-step's. "Where no answer was missing": the samples before which
   every period of the last WINDOW_S held the answer due (periods.csv: period - applied state ==
   hold lag); on a shared machine the host's stalls hold periods back, and those periods are the
   machine's, not the law's (the run prints its largest error over every sample beside it). At
   least MIN_CLEAN of the samples must qualify.
2. A delay of 1 ms each way (tests/lcm fault_relay). The plant measures the round trips and
   applies each answer a fixed lag after its state (HoldLag), and reports that lag in each state;
   the held midpoint law predicts over it. Its median error is at least 10x smaller than the law at
   the measured state held over the same link (tracking.hold: sample). The median: the largest
   error is set by the machine's stalls, the same for both.

A check that misses while the machine held one of its runs back (the plant woke more than 10 ms
late, the fault campaign's rule, or more than 1 % of the periods went without their answer: a quiet
machine loses a few in 3000) runs once more, and says so. When the machine cannot hold real
time at all (fewer than MIN_CLEAN of the samples qualify, twice) the first check is not judged
and the test reports itself skipped (exit 77) with the reason, unless the other check failed.

usage: sampled_law_lcm.py BIN_DIR TEST_BIN_DIR SCENE OUT_DIR
"""
import csv
import json
import os
import signal
import subprocess
import sys

from fault_campaign import wait_ready  # same directory
from machine_stall import STALL_MS, machine_stall

RATE = 1000
# Ten time constants of the stabilization (1 / omega = 50 ms; critically damped, a disturbance
# decays as (1 + omega t) e^(-omega t)): to 5e-4 of itself, so that even a stall's 2e-3 m excursion
# ends below the lock-step error (1.5e-6 m). Six (to 2 %) left such an excursion at 3e-5 m, 20x it.
WINDOW_S = 0.5
MIN_CLEAN = 0.10  # 30 of 300 samples, 0.3 s of the trajectory at least
MISSING_SHARE = 0.01


def run(name, port, out, bin_dir, test_bin, scene, lockstep=False, hold="midpoint", delay_ms=None):
    work = os.path.join(out, name)
    os.makedirs(work, exist_ok=True)
    group = "udpm://239.255.76.67"
    url_plant = f"{group}:{port}?ttl=0"
    url_controller = f"{group}:{port + 1}?ttl=0" if delay_ms is not None else url_plant
    sets = ["--set", "control.mode=sampled", "--set", f"control.rate={RATE}", "--set", "duration=3",
            "--set", "tracking.stabilization={zeta: 1.0, omega: 20.0}", "--set", f"tracking.hold={hold}"]
    rt = ["--rt-priority", "80"] if os.geteuid() == 0 else []
    procs = []
    try:
        if delay_ms is not None:
            relay_log = os.path.join(work, "relay.log")
            procs.append(subprocess.Popen([os.path.join(test_bin, "lcm_fault_relay"), "--a", url_plant, "--b",
                                           url_controller, "--delay-ms", str(delay_ms)],
                                          stdout=open(relay_log, "w"), stderr=subprocess.STDOUT))
            if not wait_ready(relay_log):
                sys.exit(f"{name}: the relay is not ready")
        controller_log = os.path.join(work, "controller.log")
        procs.append(subprocess.Popen([os.path.join(bin_dir, "gausstrack-controller"), "--config", scene, *sets,
                                       "--lcm-url", url_controller, *rt],
                                      stdout=open(controller_log, "w"), stderr=subprocess.STDOUT))
        if not wait_ready(controller_log):
            sys.exit(f"{name}: the controller is not ready")
        plant = subprocess.run([os.path.join(bin_dir, "gausstrack-plant"), "--scene", scene, *sets, "--lcm-url",
                                url_plant, "--out", os.path.join(work, "plant"), *rt,
                                *(["--lockstep"] if lockstep else [])],
                               stdout=open(os.path.join(work, "plant.log"), "w"), stderr=subprocess.STDOUT, timeout=60)
        if plant.returncode != 0:
            sys.exit(f"{name}: the plant failed (see {work}/plant.log)")
    finally:
        for p in procs:
            p.send_signal(signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
    summary = json.load(open(os.path.join(work, "plant", "summary.json")))
    rows = list(csv.DictReader(open(os.path.join(work, "plant", "trajectory.csv"))))
    samples = [(float(r["t"]), abs(float(r["tracking_error"]))) for r in rows]
    errors = sorted(e for _, e in samples)
    r = {"name": name, "summary": summary, "samples": samples, "median": errors[len(errors) // 2],
         "max": errors[-1], "stall_ms": 0.0 if lockstep else summary["wake_late_us"]["max"] / 1e3}
    r["held_back"] = (machine_stall(summary, period_ms=1e3 / RATE) is not None or
                      summary["commands_missing"] > MISSING_SHARE * summary["states_published"])
    if not lockstep:
        periods = list(csv.DictReader(open(os.path.join(work, "plant", "periods.csv"))))
        r["on_time"] = [int(p["period"]) - int(p["applied_state"]) <= int(p["hold_lag"]) for p in periods]
        r["lag"] = summary["hold_lag_periods"]
    print(f"{name}: median error {r['median']:.3g}, max {r['max']:.3g}, round trip p50 "
          f"{summary['round_trip_us']['p50']:.0f} us, {summary['commands_missing']} of "
          f"{summary['states_published']} periods without a new answer, {summary['commands_late']} late, "
          f"deadline misses {summary['deadline_misses']}, latest wake {r['stall_ms']:.1f} ms late"
          + (f", hold lag p50 {r['lag']['p50']:.0f} max {r['lag']['max']:.0f} periods" if not lockstep else ""),
          flush=True)
    return r


def where_no_answer_was_missing(r):
    """The errors of the samples before which every period of the last WINDOW_S held its answer."""
    window = int(round(WINDOW_S * RATE))
    on_time = r["on_time"]
    missing_before = [0]  # prefix sums of periods without their answer
    for ok in on_time:
        missing_before.append(missing_before[-1] + (0 if ok else 1))
    clean = []
    for t, e in r["samples"]:
        p = int(round(t * RATE))
        if window <= p <= len(on_time) and missing_before[p] - missing_before[p - window] == 0:
            clean.append(e)
    return clean


def realtime_against_lockstep(out, *args):
    lock = run("lockstep", 7780, out, *args, lockstep=True)
    real = run("realtime", 7782, out, *args)
    clean = where_no_answer_was_missing(real)
    share = len(clean) / len(real["samples"])
    if share < MIN_CLEAN:
        print(f"realtime: only {share:.0%} of the samples follow {WINDOW_S} s in which every period held its answer "
              f"(at least {MIN_CLEAN:.0%} needed to judge): the machine did not hold real time")
        return "unjudged", True
    worst = max(clean)
    print(f"realtime: largest error where no answer was missing {worst:.3g} over {share:.0%} of the samples "
          f"(lock-step {lock['max']:.3g}: {worst / lock['max']:.2f}x, expected <= 3x); over every sample "
          f"{real['max']:.3g}")
    return ("pass" if worst <= 3 * lock["max"] else "fail"), real["held_back"]


def delay(out, *args):
    sample = run("delay_sample", 7784, out, *args, hold="sample", delay_ms=1)
    midpoint = run("delay_midpoint", 7786, out, *args, delay_ms=1)
    ratio = sample["median"] / midpoint["median"] if midpoint["median"] > 0 else float("inf")
    print(f"delay: the midpoint law's median error is {ratio:.0f}x smaller than the law at the measured state "
          f"(expected >= 10x)")
    return ("pass" if ratio >= 10 else "fail"), sample["held_back"] or midpoint["held_back"]


def main(bin_dir, test_bin, scene, out):
    """0: both checks passed; 1: one failed; 77 (skipped): none failed, but the machine did not
    hold real time for one of them in two tries (it is not judged, and says so)."""
    verdicts = {}
    for check in (realtime_against_lockstep, delay):
        for attempt in (1, 2):
            verdict, held_back = check(out, bin_dir, test_bin, scene)
            if verdict == "pass" or attempt == 2 or not held_back:
                break
            print(f"{check.__name__}: the machine held a run back (a wake over {STALL_MS:g} ms late, or over "
                  f"{MISSING_SHARE:.0%} of the periods without their answer); running it again", flush=True)
        verdicts[check.__name__] = verdict
    print("sampled_law_lcm: " + ", ".join(f"{name} {v}" for name, v in verdicts.items()))
    if "fail" in verdicts.values():
        return 1
    return 77 if "unjudged" in verdicts.values() else 0


if __name__ == "__main__":
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(*sys.argv[1:]))
