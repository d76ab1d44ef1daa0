#!/usr/bin/env python3
"""Fault campaign: the closed loop over LCM (Duffing scene, 1 kHz, real time, stabilization
zeta 1, omega 20) under network faults and process crashes, each case with its expectation
written down before it runs.

Network faults are injected by fault_relay between the plant's LCM URL and the controller's
(delay, jitter, loss, duplication, reordering, the link down for a while): this machine's kernel
has no netem qdisc. Crashes kill a process with SIGKILL and start a new one.

Attacks on a pair that shares a key (--key): a third process answering every state first, a
recorded log played back during a live run, floods asking for 100,000 messages per second (the
table says what the flooder could send beside the pair on this machine), a controller
holding another key. They run only inside a network namespace made for them, with LCM's ttl=0,
and each attacker is bounded in time and count; without root (no namespace) they are skipped and
the table says so.

usage: fault_campaign.py BIN_DIR TEST_BIN_DIR SCENE OUT_DIR
Writes OUT_DIR/faults.md (the table) and exits 1 if any case missed its expectation.
"""
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

from machine_stall import machine_stall

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
     "duplicate states answered once or again with the same command, duplicate commands refused, error < 1e-2",
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


# Attacks on an authenticated pair: name, attacker, expectation text, checks. The attacker's
# arguments go to lcm_rogue_peer (answer, flood), or "replay" plays back a log recorded from an
# earlier keyed run, or "wrong key" gives the controller another key.
# checks: as above, plus refused = {reason: minimum} counted by the plant (unauthenticated,
# bad_tag, replayed), controller_refused likewise (from its statistics), max_deadline_work_us =
# the bound on the median of the plant's work from a period's wake to its state's publication
# (where a flood would hold the period back: the socket is drained at the deadline). Its tail and
# the deadline misses (waking late) are reported, not bounded: they are the machine's, and this
# virtual machine's host takes up to a fifth of its CPU time at random (the no-attack case misses
# 2 to 30 % of its deadlines, and its work after the wake reads 40 us at the median, over 1 ms at
# p99, from one run to the next).
FLOOD = ["--rate", "100000", "--seconds", "2"]  # 200,000 messages, half on each channel
ATTACKS = [
    ("no attack (the keyed pair alone)", None, "every state answered and verified, error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0))),
    ("rogue answering every state first, no key", ["answer"],
     "none of its commands applied (each refused as unauthenticated), tracking as without it: error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0), refused=dict(unauthenticated=1000))),
    ("rogue answering every state first, forged trailer", ["answer", "--forge"],
     "each of its commands refused as a bad tag, none applied: error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0), refused=dict(bad_tag=1000))),
    ("replay of a recorded keyed run (1 s) during a live run", "replay",
     "every replayed state and command refused as replayed (their counters are older), error < 1e-2",
     dict(max_error=1e-2, trips=(0, 0), refused=dict(replayed=500), controller_refused=dict(replayed=500))),
    ("flood of garbage, 100,000 messages/s asked for 2 s", ["flood", "--kind", "garbage", *FLOOD],
     "refused unread (no trailer) at bounded cost: the period's work after its wake < 100 us at the median "
     "(a tenth of the period), a quarter of the commands applied or more, error < 2e-2",
     dict(max_error=2e-2, trips=(0, 0), max_deadline_work_us=100, applied_min=0.25,
          refused=dict(unauthenticated=10000))),
    ("flood of well-formed unauthenticated commands, 100,000/s asked for 2 s", ["flood", "--kind", "command", *FLOOD],
     "none applied; the period's work after its wake < 100 us at the median, a quarter of the commands "
     "applied or more, error < 2e-2",
     dict(max_error=2e-2, trips=(0, 0), max_deadline_work_us=100, applied_min=0.25,
          refused=dict(unauthenticated=10000))),
    ("controller holding another key", "wrong key",
     "the plant applies nothing and ends the run at its timeout saying why (exit 1); the controller counts "
     "the plant's first state, sent every 100 ms until then, as bad tags",
     dict(refuses_to_run=True, controller_refused=dict(bad_tag=10))),
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
    if expect.get("refuses_to_run"):
        return problems  # checked by check_attack
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
        rejected = s["messages_rejected"] + sum(c["messages_rejected"] + c.get("commands_repeated", 0) + c.get("states_duplicated", 0)
                                                for c in ctrl)
        if rejected < expect["rejected_min"]:
            problems.append(f"only {rejected} duplicates refused or answered again")
    if "controller_runs" in expect and ctrl and ctrl[0]["runs"] != expect["controller_runs"]:
        problems.append(f"controller saw {ctrl[0]['runs']} runs")
    return problems


def netns_available(ns):
    if os.geteuid() != 0:
        return "network namespaces need root"
    r = subprocess.run(["ip", "netns", "add", ns], capture_output=True, text=True)
    if r.returncode != 0:
        return "cannot create a network namespace: " + r.stderr.strip()
    for cmd in (["link", "set", "lo", "up"], ["link", "set", "lo", "multicast", "on"],
                ["route", "add", "224.0.0.0/4", "dev", "lo"]):
        subprocess.run(["ip", "-n", ns, *cmd], check=True)
    return None


def run_attack(idx, name, attacker, bin_dir, test_bin, scene, out, ns, keys):
    work = os.path.join(out, f"attack{idx:02d}")
    os.makedirs(work, exist_ok=True)
    inside = ["ip", "netns", "exec", ns]
    url = f"udpm://239.255.76.67:{7760 + idx}?ttl=0"
    sets = ["--set", "control.mode=sampled", "--set", "control.rate=1000", "--set", f"duration={DURATION}",
            "--set", "tracking.stabilization={zeta: 1.0, omega: 20.0}"]
    rt = ["--rt-priority", "80"]
    procs = []

    def start(tag, argv, ready=True):
        log = os.path.join(work, f"{tag}.log")
        p = subprocess.Popen([*inside, *argv], stdout=open(log, "w"), stderr=subprocess.STDOUT)
        procs.append(p)
        if ready and not wait_ready(log):
            raise RuntimeError(f"{name}: {tag} not ready")
        return p

    def controller(tag, key):
        return start(tag, [os.path.join(bin_dir, "gausstrack-controller"), "--config", scene, *sets, "--lcm-url", url,
                           "--key", key, "--stats-out", os.path.join(work, f"{tag}.json"), *rt])

    def plant(tag, extra=()):
        return subprocess.Popen([*inside, os.path.join(bin_dir, "gausstrack-plant"), "--scene", scene, *sets, *extra,
                                 "--lcm-url", url, "--key", keys[0], "--out", os.path.join(work, tag), *rt],
                                stdout=open(os.path.join(work, f"{tag}.log"), "w"), stderr=subprocess.STDOUT)

    def stop_all():
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
        procs.clear()

    try:
        recording = os.path.join(work, "recorded.lcmlog")
        if attacker == "replay":
            # An earlier keyed run of 1 s, recorded by a listener on the group.
            start("logger", ["lcm-logger", "-q", "-f", f"--lcm-url={url}", recording], ready=False)
            controller("recorded_controller", keys[0])
            plant("recorded_plant", ["--set", "duration=1"]).wait(timeout=60)
            stop_all()
        ctrl = controller("controller", keys[1] if attacker == "wrong key" else keys[0])
        if isinstance(attacker, list) and attacker[0] == "answer":
            start("rogue", [os.path.join(test_bin, "lcm_rogue_peer"), *attacker, "--lcm-url", url])
        p = plant("plant")
        if attacker == "replay" or (isinstance(attacker, list) and attacker[0] == "flood"):
            time.sleep(FAULT_AT)
            argv = (["lcm-logplayer", f"--lcm-url={url}", recording] if attacker == "replay"
                    else [os.path.join(test_bin, "lcm_rogue_peer"), *attacker, "--lcm-url", url])
            start("attacker", argv, ready=False)
        p.wait(timeout=60)
        stop_all()
    finally:
        stop_all()
    summary = os.path.join(work, "plant", "summary.json")
    s = json.load(open(summary)) if os.path.exists(summary) else None
    errors = [abs(float(r["tracking_error"])) for r in csv.DictReader(open(os.path.join(work, "plant", "trajectory.csv")))] \
        if s else []
    c = json.load(open(os.path.join(work, "controller.json")))
    sent = ""
    attacker_log = os.path.join(work, "attacker.log")
    if os.path.exists(attacker_log):
        m = re.search(r"(\d+) messages sent in ([\d.]+) s", open(attacker_log).read())
        if m:
            sent = f" (sent {int(m.group(1)) / float(m.group(2)) / 1e3:.0f} thousand/s)"
    return s, errors, c, p.returncode, open(os.path.join(work, "plant.log")).read(), sent


def check_attack(expect, s, errors, c, rc, plant_log):
    if expect.get("refuses_to_run"):
        problems = []
        if rc != 1 or "no command verified" not in plant_log:
            problems.append(f"the plant did not refuse to run with the reason (exit {rc})")
        if s and s["commands_applied"] != 0:
            problems.append(f"{s['commands_applied']} commands applied")
    elif s is None:
        return [f"the plant wrote no summary (exit {rc})"]
    else:
        problems = check(expect, s, errors, [c])
        work = s["deadline_work_us"]["p50"]
        if "max_deadline_work_us" in expect and work >= expect["max_deadline_work_us"]:
            problems.append(f"work after the wake {work:.0f} us at the median")
        if "applied_min" in expect and s["commands_applied"] < expect["applied_min"] * s["states_published"]:
            problems.append(f"{s['commands_applied']} commands applied")
    for reason, least in expect.get("refused", {}).items():
        got = s["rejected"][reason] if s else 0
        if got < least:
            problems.append(f"the plant refused {got} as {reason} (expected at least {least})")
    for reason, least in expect.get("controller_refused", {}).items():
        if c[f"rejected_{reason}"] < least:
            problems.append(f"the controller refused {c[f'rejected_{reason}']} as {reason} (expected at least {least})")
    return problems


def attacks(bin_dir, test_bin, scene, out):
    """The attack cases' table lines, how many ran and how many missed their expectation."""
    lines = ["", "Attacks on an authenticated pair (inside a network namespace, LCM ttl=0):", "",
             "| case | expectation (stated before the run) | max error | applied / missing | refused by the plant "
             "(no key / bad tag / replayed) | refused by the controller | deadline misses | work after the wake "
             "p50 / p99 / max | met |",
             "|---|---|---|---|---|---|---|---|---|"]
    ns = f"gt_attack_{os.getpid()}"
    why = netns_available(ns)
    if why:
        lines.append(f"| all | skipped: {why} | | | | | | | |")
        print(lines[-1], flush=True)
        return lines, 0, 0
    failures = 0
    try:
        keys = [os.path.join(out, "keys", k) for k in ("pair.key", "other.key")]
        os.makedirs(os.path.dirname(keys[0]), exist_ok=True)
        for k in keys:
            if os.path.exists(k):
                os.remove(k)
            subprocess.run([os.path.join(bin_dir, "gausstrack-keygen"), k], check=True, stdout=subprocess.DEVNULL)
        for idx, (name, attacker, text, expect) in enumerate(ATTACKS):
            s, errors, c, rc, plant_log, sent = run_attack(idx, name, attacker, bin_dir, test_bin, scene, out, ns, keys)
            problems = check_attack(expect, s, errors, c, rc, plant_log)
            stall = machine_stall(s, [c]) if s else None
            if problems and stall is not None:  # as for the faults above
                shutil.rmtree(os.path.join(out, f"attack{idx:02d}"), ignore_errors=True)
                s, errors, c, rc, plant_log, sent = run_attack(idx, name, attacker, bin_dir, test_bin, scene, out, ns,
                                                               keys)
                problems = check_attack(expect, s, errors, c, rc, plant_log)
                name += f" (run again: in the first run {stall})"
            failures += bool(problems)
            if s:
                r = s["rejected"]
                figures = (f"{s['max_tracking_error']:.2g} | {s['commands_applied']} / {s['commands_missing']} | "
                           f"{r['unauthenticated']} / {r['bad_tag']} / {r['replayed']}")
            else:
                figures = f"ended: exit {rc} | | "
            w = s["deadline_work_us"] if s and s.get("deadline_work_us") else None
            work = f"{w['p50']:.0f} / {w['p99']:.0f} / {w['max']:.0f} us" if w else ""
            lines.append(f"| {name}{sent} | {text} | {figures} | {c['rejected_unauthenticated']} / {c['rejected_bad_tag']} / "
                         f"{c['rejected_replayed']} | {s['deadline_misses'] if s else ''} | {work} | "
                         f"{'yes' if not problems else 'NO: ' + '; '.join(problems)} |")
            print(lines[-1], flush=True)
    finally:
        subprocess.run(["ip", "netns", "del", ns], check=False)
    return lines, len(ATTACKS), failures


def main(bin_dir, test_bin, scene, out):
    os.makedirs(out, exist_ok=True)
    lines = ["| case | expectation (stated before the run) | max / rms error | missing | late | rejected "
             "(plant / controller) | watchdog trips | deadline misses | recovery | met |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    failures = 0
    for idx, (name, relay_args, crash, text, expect) in enumerate(CASES):
        s, errors, ctrl, recovery = run_case(idx, name, relay_args, crash, bin_dir, test_bin, scene, out)
        problems = check(expect, s, errors, ctrl)
        stall = machine_stall(s, ctrl)
        if problems and stall is not None:
            # The machine, not the fault, held the loop back: judged again on a second run.
            shutil.rmtree(os.path.join(out, f"case{idx:02d}"), ignore_errors=True)
            s, errors, ctrl, recovery = run_case(idx, name, relay_args, crash, bin_dir, test_bin, scene, out)
            problems = check(expect, s, errors, ctrl)
            name += f" (run again: in the first run {stall})"
        failures += bool(problems)
        rec = "" if recovery is None else f"{recovery * 1e3:.0f} ms"
        crej = sum(c["messages_rejected"] for c in ctrl)
        lines.append(f"| {name} | {text} | {s['max_tracking_error']:.2g} / {s['rms_tracking_error']:.2g} | "
                     f"{s['commands_missing']} of {s['states_published']} | {s['commands_late']} | "
                     f"{s['messages_rejected']} / {crej} | {s['watchdog_trips']} | {s['deadline_misses']} | {rec} | "
                     f"{'yes' if not problems else 'NO: ' + '; '.join(problems)} |")
        print(lines[-1], flush=True)
    attack_lines, attacks_run, attack_failures = attacks(bin_dir, test_bin, scene, out)
    lines += attack_lines
    failures += attack_failures
    with open(os.path.join(out, "faults.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    total = len(CASES) + attacks_run
    print(f"fault campaign: {total - failures} of {total} cases met their expectation -> "
          f"{os.path.join(out, 'faults.md')}")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(*sys.argv[1:]))
