#!/usr/bin/env python3
"""Fault campaign: the closed loop over LCM (Duffing scene, 1 kHz, real time, stabilization
zeta 1, omega 20) under network faults and process crashes, each case with its expectation
written down before it runs.

Network faults are injected by fault_relay between the plant's LCM URL and the controller's
(delay, jitter, loss, duplication, reordering, the link down for a while): this machine's kernel
has no netem qdisc. Crashes kill a process with SIGKILL and start a new one.

usage: fault_campaign.py BIN_DIR TEST_BIN_DIR SCENE OUT_DIR
Writes OUT_DIR/faults.md (the table) and exits 1 if any case missed its expectation.
"""
import csv
import json
import os
import signal
import subprocess
import sys
import time

DURATION = 3.0
FAULT_AT = 1.0  # s into the run

# name, relay options, crash, expectation text, checks on the run's figures
# checks: max_error (while no watchdog trip), final error, watchdog trips range, other conditions.
# Error bounds are guarantees on a loaded machine (the suite runs beside CPU hogs), start-up
# included: the first answers come a period or more late, so a run starts with a few periods of
# zero force. The table reports what was measured.
CASES = [
    ("no fault", [], None,
     "every command applied but a few (missing first answers at start-up included), error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0))),
    ("delay 1 ms", ["--delay-ms", "1"], None, "answers one period later: error < 2e-2, no watchdog trip",
     dict(max_error=2e-2, trips=(0, 0))),
    ("delay 5 ms", ["--delay-ms", "5"], None, "answers about 5 periods late: error < 5e-2, no watchdog trip",
     dict(max_error=5e-2, trips=(0, 0))),
    ("jitter 2 +- 1.5 ms", ["--delay-ms", "2", "--jitter-ms", "1.5"], None,
     "late and out-of-order answers counted, error < 3e-2, no watchdog trip", dict(max_error=3e-2, trips=(0, 0))),
    ("loss 1 %", ["--loss", "0.01"], None,
     "2 % of periods lose their command (a state or its answer lost) beyond those the loaded machine answers late, error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0), loss=0.01)),
    ("loss 10 %", ["--loss", "0.10"], None, "19 % of periods lose their command beyond the late ones, error < 2e-2",
     dict(max_error=2e-2, trips=(0, 0), loss=0.10)),
    ("loss 50 %", ["--loss", "0.50"], None,
     "75 % of periods lose their command beyond the late ones, held forces keep the error < 5e-2, no watchdog trip",
     dict(max_error=5e-2, trips=(0, 0), loss=0.50)),
    ("duplication 10 %", ["--duplicate", "0.10"], None,
     "duplicate states answered again with the same command, duplicate commands refused, error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0), rejected_min=10)),
    ("reordering 10 %", ["--reorder", "0.10"], None, "reordered answers late or refused as stale, error < 2e-2",
     dict(max_error=2e-2, trips=(0, 0))),
    ("link down 200 ms", ["--down-at-s", str(FAULT_AT), "--down-ms", "200"], None,
     "the watchdog trips once and applies zero force; tracking recovers: final error < 5e-3",
     dict(trips=(1, 1), final_error=5e-3)),
    ("controller killed, restarted 0.5 s later", [], "controller",
     "the watchdog trips once; the new controller serves the same run; final error < 5e-3",
     dict(trips=(1, 1), final_error=5e-3)),
    ("plant killed, restarted", [], "plant",
     "the new plant is a new run (new run_id); the same controller serves it from its first state: "
     "its error < 1e-2, controller counts 2 runs",
     dict(max_error=1e-2, trips=(0, 0), controller_runs=2)),
    ("both killed, restarted", [], "both",
     "a new plant and a new controller close the loop again from the start: error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0))),
]


def wait_ready(proc_log, timeout=5.0):
    end = time.time() + timeout
    while time.time() < end:
        if os.path.exists(proc_log) and "ready" in open(proc_log).read():
            return True
        time.sleep(0.02)
    return False


def run_case(idx, name, relay_args, crash, bin_dir, test_bin, scene, out):
    work = os.path.join(out, f"case{idx:02d}")
    os.makedirs(work, exist_ok=True)
    port = 7710 + 2 * idx
    # Network cases put the relay between two URLs; crash cases share one URL.
    use_relay = crash is None
    url_plant = f"udpm://239.255.76.67:{port}?ttl=0"
    url_controller = f"udpm://239.255.76.67:{port + 1}?ttl=0" if use_relay else url_plant
    sets = ["--set", "control.mode=sampled", "--set", "control.rate=1000", "--set", f"duration={DURATION}",
            "--set", "tracking.stabilization={zeta: 1.0, omega: 20.0}"]
    rt = ["--rt-priority", "80"] if os.geteuid() == 0 else []
    procs = []

    def start_controller(tag):
        log = os.path.join(work, f"controller_{tag}.log")
        p = subprocess.Popen([os.path.join(bin_dir, "gausstrack-controller"), "--config", scene, *sets, "--lcm-url",
                              url_controller, "--stats-out", os.path.join(work, f"controller_{tag}.json"), *rt],
                             stdout=open(log, "w"), stderr=subprocess.STDOUT)
        procs.append(p)
        if not wait_ready(log):
            raise RuntimeError(f"{name}: controller not ready")
        return p

    def start_plant(tag, duration=None):
        extra = ["--set", f"duration={duration}"] if duration else []
        return subprocess.Popen([os.path.join(bin_dir, "gausstrack-plant"), "--scene", scene, *sets, *extra, "--lcm-url",
                                 url_plant, "--out", os.path.join(work, f"plant_{tag}"), *rt],
                                stdout=open(os.path.join(work, f"plant_{tag}.log"), "w"), stderr=subprocess.STDOUT)

    relay = None
    if use_relay:
        rlog = os.path.join(work, "relay.log")
        chrt = ["chrt", "-f", "80"] if os.geteuid() == 0 else []  # the link is as real-time as the loop
        relay = subprocess.Popen([*chrt, os.path.join(test_bin, "lcm_fault_relay"), "--a", url_plant, "--b",
                                  url_controller, *relay_args], stdout=open(rlog, "w"), stderr=subprocess.STDOUT)
        if not wait_ready(rlog):
            raise RuntimeError(f"{name}: relay not ready")
    controller = start_controller("1")
    try:
        if crash in ("plant", "both"):
            first = start_plant("1")
            time.sleep(FAULT_AT)
            first.kill()
            first.wait()
            if crash == "both":
                controller.kill()
                controller.wait()
                controller = start_controller("2")
            plant = start_plant("2")
            plant.wait(timeout=60)
            result_dir = os.path.join(work, "plant_2")
        else:
            plant = start_plant("1")
            if crash == "controller":
                time.sleep(FAULT_AT)
                controller.kill()
                controller.wait()
                time.sleep(0.5)
                controller = start_controller("2")
            plant.wait(timeout=60)
            result_dir = os.path.join(work, "plant_1")
    finally:
        for p in procs + ([relay] if relay else []):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in procs + ([relay] if relay else []):
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
    s = json.load(open(os.path.join(result_dir, "summary.json")))
    rows = list(csv.DictReader(open(os.path.join(result_dir, "trajectory.csv"))))
    errors = [abs(float(r["tracking_error"])) for r in rows]
    ctrl = [json.load(open(os.path.join(work, f))) for f in sorted(os.listdir(work))
            if f.startswith("controller_") and f.endswith(".json")]
    # Recovery: from the end of the fault, the time until the error stays below 2e-3 (about twice
    # the no-fault level).
    recovery = None
    if crash == "controller" or "--down-ms" in relay_args:
        fault_end = FAULT_AT + (0.5 if crash == "controller" else 0.2)
        settled = None
        for r, e in zip(rows, errors):
            t = float(r["t"])
            if e >= 2e-3:
                settled = None
            elif settled is None:
                settled = t
        recovery = None if settled is None else max(0.0, settled - fault_end)
    return s, errors, ctrl, recovery


def check(expect, s, errors, ctrl):
    problems = []
    periods = s["states_published"]
    if s["commands_applied"] + s["commands_missing"] != periods:
        problems.append("periods not accounted for")
    if not s["completed"]:
        problems.append("run did not complete")
    lo, hi = expect.get("trips", (0, 99))
    if not lo <= s["watchdog_trips"] <= hi:
        problems.append(f"watchdog trips {s['watchdog_trips']} not in [{lo}, {hi}]")
    if "max_error" in expect and s["max_tracking_error"] >= expect["max_error"]:
        problems.append(f"max error {s['max_tracking_error']:.3g} >= {expect['max_error']:g}")
    if "final_error" in expect and errors[-1] >= expect["final_error"]:
        problems.append(f"final error {errors[-1]:.3g} >= {expect['final_error']:g}")
    if "loss" in expect:
        # A period misses its command when its state or the answer is lost: 1 - (1 - p)^2, on top
        # of the periods a loaded machine misses by itself. Those are counted in the same run (an
        # answer that came late, a plant that woke past its deadline), not taken from another run:
        # the load on a shared machine changes from one case to the next.
        lost = 1 - (1 - expect["loss"]) ** 2
        frac = s["commands_missing"] / periods
        own = max(s["commands_late"], s["deadline_misses"]) / periods
        lo, hi = max(0.0, lost - 0.03), min(1.0, own + lost + 0.05)
        if not lo <= frac <= hi:
            problems.append(f"missing fraction {frac:.3f} not in [{lo:.3f}, {hi:.3f}]")
    if "rejected_min" in expect:
        rejected = s["messages_rejected"] + sum(c["messages_rejected"] + c.get("commands_repeated", 0) for c in ctrl)
        if rejected < expect["rejected_min"]:
            problems.append(f"only {rejected} duplicates refused or answered again")
    if "controller_runs" in expect and ctrl and ctrl[0]["runs"] != expect["controller_runs"]:
        problems.append(f"controller saw {ctrl[0]['runs']} runs")
    return problems


def main(bin_dir, test_bin, scene, out):
    os.makedirs(out, exist_ok=True)
    lines = ["| case | expectation (stated before the run) | max / rms error | missing | late | rejected "
             "(plant / controller) | watchdog trips | deadline misses | recovery | met |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    failures = 0
    for idx, (name, relay_args, crash, text, expect) in enumerate(CASES):
        s, errors, ctrl, recovery = run_case(idx, name, relay_args, crash, bin_dir, test_bin, scene, out)
        problems = check(expect, s, errors, ctrl)
        failures += bool(problems)
        rec = "" if recovery is None else f"{recovery * 1e3:.0f} ms"
        crej = sum(c["messages_rejected"] for c in ctrl)
        lines.append(f"| {name} | {text} | {s['max_tracking_error']:.2g} / {s['rms_tracking_error']:.2g} | "
                     f"{s['commands_missing']} of {s['states_published']} | {s['commands_late']} | "
                     f"{s['messages_rejected']} / {crej} | {s['watchdog_trips']} | {s['deadline_misses']} | {rec} | "
                     f"{'yes' if not problems else 'NO: ' + '; '.join(problems)} |")
        print(lines[-1], flush=True)
    with open(os.path.join(out, "faults.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"fault campaign: {len(CASES) - failures} of {len(CASES)} cases met their expectation -> "
          f"{os.path.join(out, 'faults.md')}")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(*sys.argv[1:]))
