#!/usr/bin/python3
"""The closed loop against the machine's own floors, measured in one run: for each control rate,
scheduler (default; --realtime with the two processes on two CPUs, and on one) and load (quiet, one CPU hog), first `transport_bench --rate R`
(a bare clock_nanosleep loop in the manner of cyclictest, then bare LCM and raw UDP round trips
paced at the same rate and scheduling), then `gausstrack-run` on the Duffing scene at that rate.
Writes OUT/loop_vs_floor.json, the programs' outputs, and OUT/README.md with the table and the
targets (the loop's round trip within 1.2x of bare LCM at the same pace; its deadline misses within
2x of the floor's and its wake-up lateness within 1.2x; --realtime never worse than the default
scheduler).

usage: loop_vs_floor.py BIN_DIR SCENE OUT [--seconds S] [--rates 1000,10000] [--no-hog]
                        [--schedulers default,realtime,realtime_1cpu] [--set KEY=VALUE ...] [--spin-us S]
  --set      passed to gausstrack-run (e.g. integrator={method: rk4, step: 1.0e-4}: a fixed-step plant)
  --spin-us  the plant's --spin-us, and the same for the paced round trips (the floor always sleeps)
"""
import argparse
import json
import os
import subprocess
import sys
import threading
import time


def run(cmd, log):
    with open(log, "w") as f:
        return subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, timeout=600).returncode


def quantiles(doc, key):
    q = doc.get(key) or {}
    return {k: q.get(k, float("nan")) for k in ("p50", "p99", "p999", "max")}


def softirq_snapshot():
    """CPU time of the ksoftirqd threads (ms) and NET_RX softirqs run, all CPUs: packet delivery
    that the kernel could not run at interrupt exit is deferred to ksoftirqd, an ordinary thread
    that competes with everything else (e.g. a CPU hog)."""
    ticks, hz = 0, os.sysconf("SC_CLK_TCK")
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/comm") as f:
                if not f.read().startswith("ksoftirqd/"):
                    continue
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            ticks += int(fields[11]) + int(fields[12])  # utime, stime
        except (OSError, IndexError, ValueError):
            continue
    net_rx = 0
    try:
        with open("/proc/softirqs") as f:
            for line in f:
                if line.strip().startswith("NET_RX:"):
                    net_rx = sum(int(x) for x in line.split()[1:])
    except OSError:
        pass
    return 1000.0 * ticks / hz, net_rx


def process_threads(prefix, known):
    """Scheduling counters of each thread of the plant and controller processes started with the
    channel prefix: CPU time and time spent runnable but waiting for a CPU (ms, from
    /proc/PID/task/TID/schedstat), voluntary and involuntary context switches. The main thread is
    the real-time loop; the others (LCM's receive thread; the message log's writer when there is one) are summed as `other`."""
    # `known` (pid -> role) spares a scan of every process once both are found.
    if len(known) < 2:
        for pid in os.listdir("/proc"):
            if not pid.isdigit() or pid in known:
                continue
            try:
                with open(f"/proc/{pid}/cmdline", "rb") as f:
                    argv = f.read().split(b"\0")
            except OSError:
                continue
            name = os.path.basename(argv[0].decode(errors="replace"))
            role = {"gausstrack-plant": "plant", "gausstrack-controller": "controller"}.get(name)
            if role is not None and f"{prefix}_STATE".encode() in argv:
                known[pid] = role
    found = {}
    for pid, role in known.items():
        try:
            for tid in os.listdir(f"/proc/{pid}/task"):
                with open(f"/proc/{pid}/task/{tid}/schedstat") as f:
                    run_ns, wait_ns, _ = (int(x) for x in f.read().split())
                vol = invol = 0
                with open(f"/proc/{pid}/task/{tid}/status") as f:
                    for line in f:
                        if line.startswith("voluntary_ctxt_switches:"):
                            vol = int(line.split()[1])
                        elif line.startswith("nonvoluntary_ctxt_switches:"):
                            invol = int(line.split()[1])
                found[(role, pid, tid)] = (run_ns / 1e6, wait_ns / 1e6, vol, invol, tid == pid)
        except (OSError, ValueError):
            continue
    return found


def summarize_threads(seen):
    """Per role, the main thread and the others summed, from each thread's last counters seen."""
    out = {}
    for (role, _, _), (cpu, wait, vol, invol, main) in seen.items():
        t = out.setdefault(role, {k: {"cpu_ms": 0.0, "runqueue_wait_ms": 0.0, "voluntary_switches": 0,
                                      "involuntary_switches": 0, "threads": 0} for k in ("main", "other")})
        c = t["main" if main else "other"]
        c["cpu_ms"] += cpu
        c["runqueue_wait_ms"] += wait
        c["voluntary_switches"] += vol
        c["involuntary_switches"] += invol
        c["threads"] += 1
    return out


def run_watching_threads(cmd, log, prefix):
    """run(), keeping the last process_threads(prefix) seen while cmd ran (the counters are
    cumulative, so the last sample before the processes exit is the whole run, less at most the
    polling interval)."""
    seen, known = {}, {}
    done = threading.Event()

    def poll():
        while not done.is_set():
            # Counters only grow: each thread's latest reading is its whole run so far, and a thread
            # that has ended (LCM's, joined at exit) keeps its last one.
            seen.update(process_threads(prefix, known))
            done.wait(0.1)

    poller = threading.Thread(target=poll, daemon=True)
    poller.start()
    try:
        code = run(cmd, log)
    finally:
        done.set()
        poller.join()
    return code, summarize_threads(seen)


# Schedulers: the default one; --realtime with the two processes pinned to the last two CPUs (one
# each); --realtime with both on the last CPU (wake-ups without an inter-processor interrupt).
SCHEDULERS = ("default", "realtime", "realtime_1cpu")


def scheduler_args(sched):
    last = (os.cpu_count() or 1) - 1
    return {"default": [], "realtime": ["--realtime"],
            "realtime_1cpu": ["--realtime", "--cpus", f"{last},{last}"]}[sched]


def measure(bin_dir, scene, out, rate, sched, hog, seconds, sets=(), spin_us=0):
    tag = f"{rate:g}hz_{sched}_{'hog' if hog else 'quiet'}"
    hogs = [subprocess.Popen(["yes"], stdout=subprocess.DEVNULL)] if hog else []
    try:
        rt = scheduler_args(sched)
        spin = ["--spin-us", str(spin_us)] if spin_us else []
        tj = os.path.join(out, f"transport_{tag}.json")
        if run([os.path.join(bin_dir, "bench", "transport_bench"), "--rate", f"{rate:g}", "--seconds", f"{seconds:g}",
                "--out", tj] + rt + spin, os.path.join(out, f"transport_{tag}.txt")) != 0:
            return {"tag": tag, "error": "transport_bench failed"}
        loop_dir = os.path.join(out, f"loop_{tag}")
        softirq_before = softirq_snapshot()
        prefix = f"FLOOR{os.getpid()}"
        code, threads = run_watching_threads(
            [os.path.join(bin_dir, "bin", "gausstrack-run"), scene, "--rate", f"{rate:g}", "--duration",
             f"{seconds:g}", "--set", "tracking.stabilization={zeta: 1.0, omega: 20.0}", "--out", loop_dir,
             "--no-plots", "--channel-prefix", prefix] + [x for kv in sets for x in ("--set", kv)] + rt + spin,
            os.path.join(out, f"loop_{tag}.txt"), prefix)
        softirq_after = softirq_snapshot()
        if code != 0:
            return {"tag": tag, "error": f"gausstrack-run exited {code}"}
        if set(threads) != {"plant", "controller"}:
            return {"tag": tag, "error": f"the loop's processes were not seen in /proc (saw {sorted(threads)})"}
    finally:
        for h in hogs:
            h.kill()
            h.wait()
    with open(tj) as f:
        t = json.load(f)
    with open(os.path.join(loop_dir, "summary.json")) as f:
        s = json.load(f)
    periods = t["round_trips"]
    loop_periods = s.get("states_published", 0) or 1
    return {
        "tag": tag, "rate_hz": rate, "scheduler": sched, "hog": hog, "spin_us": spin_us, "periods": periods,
        "floor_wake_us": quantiles(t, "sleep_wake_late_us"), "floor_misses": t.get("sleep_deadline_misses"),
        "udp_us": quantiles(t, "udp_us"), "lcm_us": quantiles(t, "lcm_us"),
        "lcm_wake_us": quantiles(t, "lcm_wake_late_us"), "lcm_misses": t.get("lcm_deadline_misses"),
        "loop_us": quantiles(s, "round_trip_us"), "loop_wake_us": quantiles(s, "wake_late_us"),
        "loop_misses": s.get("deadline_misses"), "loop_periods": loop_periods,
        "loop_missing": s.get("commands_missing"), "loop_max_error": s.get("max_tracking_error"),
        "loop_answered": s.get("commands_published"), "loop_superseded": s.get("states_superseded"),
        "loop_ksoftirqd_ms": softirq_after[0] - softirq_before[0], "loop_net_rx": softirq_after[1] - softirq_before[1],
        "loop_threads": threads,
    }


def ratio(a, b):
    return a / b if b else float("inf") if a else 1.0


def report(rows, out, seconds, scene="", sets=(), spin_us=0):
    spin = (f"; the plant wakes {spin_us} us before each deadline and spins until it (`--spin-us {spin_us}`), and so "
            "does the pacing of the bare UDP and LCM round trips; the floor sleeps") if spin_us else ""
    lines = ["# The closed loop against the machine's floors", "",
             f"Scene `{os.path.basename(scene)}`" + (", " + ", ".join(f"`--set {x}`" for x in sets) if sets else "")
             + spin + ".", "",
             f"Written by `bench/transport/loop_vs_floor.py`; every row is one run of {seconds:g} s per path, all "
             "rows in one invocation. `floor`: a bare `clock_nanosleep` loop at the rate (cyclictest's method); "
             "`UDP`, `LCM`: bare round trips paced at the same rate and scheduling; `loop`: `gausstrack-run` (the "
             "scene's plant and controller processes). Schedulers: `default`; `realtime` (SCHED_FIFO, the "
             "plant's loop at 83 above its LCM receive thread at 82, the controller's loop and receive thread "
             "at 80; mlockall; the two processes pinned to the last two CPUs, one each); `realtime_1cpu` (the "
             "same, both on the last CPU). Round trips and wake-up lateness in us (p50 / p99); "
             "misses: wake-ups more than half a period late; ksoftirqd: CPU time of the kernel's deferred-softirq "
             "threads during the loop's run (packet delivery the kernel put off to a thread), in ms, beside the "
             "NET_RX softirqs run.", "",
             "| rate | scheduler | load | floor wake | floor misses | UDP | LCM | loop | loop / LCM (p50) "
             "| loop wake | loop misses | ksoftirqd ms / NET_RX |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['tag']} | | | **{r['error']}** | | | | | | | | |")
            continue
        f, u, l, p, w = r["floor_wake_us"], r["udp_us"], r["lcm_us"], r["loop_us"], r["loop_wake_us"]
        lines.append(
            f"| {r['rate_hz']:g} Hz | {r['scheduler']} | {'1 hog' if r['hog'] else 'quiet'} "
            f"| {f['p50']:.0f} / {f['p99']:.0f} | {r['floor_misses']} / {r['periods']} | {u['p50']:.0f} / {u['p99']:.0f} "
            f"| {l['p50']:.0f} / {l['p99']:.0f} | {p['p50']:.0f} / {p['p99']:.0f} | {ratio(p['p50'], l['p50']):.2f}x "
            f"| {w['p50']:.0f} / {w['p99']:.0f} | {r['loop_misses']} / {r['loop_periods']} "
            f"| {r.get('loop_ksoftirqd_ms', float('nan')):.0f} / {r.get('loop_net_rx', 0)} |")
    lines += ["", "## Where the loop's time goes: its threads", "",
              "Per process, its real-time thread (`main`: the loop) and the rest (`other`: here LCM's receive thread, which takes every incoming message off the socket for the loop; also the message log's "
              "writer when a run keeps a log), over the loop's run: CPU time, time runnable but waiting for a CPU (run-queue wait, from "
              "schedstat) and involuntary context switches (preemptions), as ms / ms / count. A tail that the "
              "run-queue wait does not explain is time the thread spent blocked (waiting for a message or a "
              "lock), not time it was kept off a CPU. States answered / superseded: the controller answers "
              "the newest of the states queued when it gets to them; a controller short of CPU time "
              "supersedes many.", "",
              "| rate | scheduler | load | loop p99 | plant main | plant other | controller main | controller other "
              "| states answered / superseded |",
              "|---|---|---|---|---|---|---|---|---|"]

    def cell(r, role, kind):
        t = (r.get("loop_threads") or {}).get(role, {}).get(kind)
        if not t or not t["threads"]:
            return ""
        return f"{t['cpu_ms']:.0f} / {t['runqueue_wait_ms']:.1f} / {t['involuntary_switches']}"

    for r in rows:
        if "error" in r:
            continue
        lines.append(f"| {r['rate_hz']:g} Hz | {r['scheduler']} | {'1 hog' if r['hog'] else 'quiet'} "
                     f"| {r['loop_us']['p99']:.0f} us | {cell(r, 'plant', 'main')} | {cell(r, 'plant', 'other')} "
                     f"| {cell(r, 'controller', 'main')} | {cell(r, 'controller', 'other')} "
                     f"| {r.get('loop_answered', '')} / {r.get('loop_superseded', '')} |")
    lines += ["", "## Targets", "", "| target | case | measured | met |", "|---|---|---|---|"]

    def target(label, case, text, ok):
        lines.append(f"| {label} | {case} | {text} | {'yes' if ok else '**no**'} |")

    ok_rows = [r for r in rows if "error" not in r]
    for r in ok_rows:
        case = r["tag"]
        x = ratio(r["loop_us"]["p50"], r["lcm_us"]["p50"])
        target("loop round trip <= 1.2x bare LCM at the same pace (p50)", case, f"{x:.2f}x", x <= 1.2)
        fm = max(r["floor_misses"] or 0, 0) / r["periods"]
        lm = (r["loop_misses"] or 0) / r["loop_periods"]
        target("loop deadline misses <= 2x the floor's (per period)", case, f"{lm:.2e} vs {fm:.2e}",
               lm <= 2 * fm or lm == 0)
        x = ratio(r["loop_wake_us"]["p99"], r["floor_wake_us"]["p99"])
        target("loop wake-up lateness <= 1.2x the floor's (p99)", case, f"{x:.2f}x", x <= 1.2)
    for r in ok_rows:
        if r["scheduler"] != "default":
            continue
        for q in ok_rows:
            if q["scheduler"] == "default" or q["rate_hz"] != r["rate_hz"] or q["hog"] != r["hog"]:
                continue
            case = f"{r['rate_hz']:g} Hz, {'1 hog' if r['hog'] else 'quiet'}, {q['scheduler']}"
            worse_p50 = q["loop_us"]["p50"] > r["loop_us"]["p50"] * 1.05
            worse_miss = (q["loop_misses"] or 0) > (r["loop_misses"] or 0)
            target("--realtime never worse than the default scheduler (loop p50 within 5%, misses)", case,
                   f"p50 {q['loop_us']['p50']:.0f} vs {r['loop_us']['p50']:.0f} us, misses {q['loop_misses']} vs "
                   f"{r['loop_misses']}", not worse_p50 and not worse_miss)
    with open(os.path.join(out, "README.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("bin_dir")
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--seconds", type=float, default=5)
    p.add_argument("--rates", default="1000,10000")
    p.add_argument("--no-hog", action="store_true")
    p.add_argument("--schedulers", default=",".join(SCHEDULERS), help="of " + ", ".join(SCHEDULERS))
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="passed to gausstrack-run")
    p.add_argument("--spin-us", type=int, default=0,
                   help="the plant's --spin-us, also the paced round trips' (the floor always sleeps)")
    p.add_argument("--report-only", action="store_true",
                   help="measure nothing: rewrite OUT/README.md from OUT's rows and the loop runs' summaries")
    a = p.parse_args(argv)
    if a.report_only:
        with open(os.path.join(a.out, "loop_vs_floor.json")) as f:
            rows = json.load(f)
        for r in rows:
            path = os.path.join(a.out, f"loop_{r['tag']}", "summary.json")
            if "error" not in r and os.path.exists(path):
                with open(path) as f:
                    s = json.load(f)
                r.setdefault("loop_answered", s.get("commands_published"))
                r.setdefault("loop_superseded", s.get("states_superseded"))
        report(rows, a.out, a.seconds, a.scene, a.set, max((r.get("spin_us", 0) for r in rows), default=0))
        return 0
    schedulers = a.schedulers.split(",")
    if any(x not in SCHEDULERS for x in schedulers):
        p.error("--schedulers takes a list of " + ", ".join(SCHEDULERS))
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for rate in [float(x) for x in a.rates.split(",")]:
        for sched in schedulers:
            for hog in (False,) if a.no_hog else (False, True):
                rows.append(measure(a.bin_dir, a.scene, a.out, rate, sched, hog, a.seconds, a.set, a.spin_us))
                print(json.dumps(rows[-1]), flush=True)
    with open(os.path.join(a.out, "loop_vs_floor.json"), "w") as f:
        json.dump(rows, f, indent=1)
    report(rows, a.out, a.seconds, a.scene, a.set, a.spin_us)
    return 0 if all("error" not in r for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
