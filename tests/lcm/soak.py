#!/usr/bin/python3
"""Soak: the closed loop over LCM at 1 kHz in real time for 10 minutes, with both processes'
resident memory sampled every second.

usage: soak.py BIN_DIR SCENE OUT_DIR [--duration S] [--rate HZ] [--set key=value ...]

Passes (exit 0) when
- every period is accounted for: the plant published one state per period, and each period
  applied a command or counted one missing (applied + missing = states published);
- resident memory is flat: from the first minute to the end of the loop neither process grows by
  more than 1 MiB (the trajectory is kept once a second here, so the data the plant keeps is about
  100 KiB; its latency records are allocated, and locked in memory, before the run starts); what
  the plant allocates afterwards to write its outputs is reported, not judged;
- both processes stopped cleanly.
Writes OUT_DIR/soak.md (the table) and OUT_DIR/rss.csv (time, plant and controller RSS in KiB).
"""
import argparse
import json
import os
import subprocess
import sys
import time

LIMIT_KIB = 1024


def rss_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def find_pid(name, marker):
    """The pid of the process named `name` whose command line holds `marker`."""
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                argv = f.read().split(b"\0")
        except OSError:
            continue
        if argv and os.path.basename(argv[0].decode(errors="replace")) == name and \
                any(marker.encode() in a for a in argv):
            return int(entry)
    return None


def main():
    p = argparse.ArgumentParser()
    p.add_argument("bin_dir")
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--duration", type=float, default=600.0)
    p.add_argument("--rate", type=float, default=1000.0)
    p.add_argument("--set", action="append", default=[], metavar="key=value", help="scene override")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    prefix = f"SOAK{os.getpid()}"
    cmd = [os.path.join(a.bin_dir, "gausstrack-run"), a.scene, "--duration", f"{a.duration:g}",
           "--rate", f"{a.rate:g}", "--set", "output_period=1.0", "--out", os.path.join(a.out, "run"),
           "--channel-prefix", prefix, "--no-plots"]
    for override in a.set:
        cmd += ["--set", override]
    realtime = os.geteuid() == 0
    if realtime:
        cmd.append("--realtime")
    print(" ".join(cmd), flush=True)
    run = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    start = time.monotonic()
    samples = []  # (t, plant KiB, controller KiB)
    pids = {}
    while run.poll() is None:
        for name in ("gausstrack-plant", "gausstrack-controller"):
            if name not in pids:
                pid = find_pid(name, prefix)
                if pid:
                    pids[name] = pid
        t = time.monotonic() - start
        plant = rss_kib(pids["gausstrack-plant"]) if "gausstrack-plant" in pids else None
        ctrl = rss_kib(pids["gausstrack-controller"]) if "gausstrack-controller" in pids else None
        if plant and ctrl:
            samples.append((t, plant, ctrl))
            if len(samples) % 60 == 0:
                print(f"soak: t = {t:5.0f} s  plant {plant} KiB  controller {ctrl} KiB", flush=True)
        time.sleep(1.0)
    output = run.stdout.read()
    print(output)

    with open(os.path.join(a.out, "rss.csv"), "w") as f:
        f.write("t_s,plant_kib,controller_kib\n")
        for t, pk, ck in samples:
            f.write(f"{t:.1f},{pk},{ck}\n")
    summary_path = os.path.join(a.out, "run", "summary.json")
    if run.returncode != 0 or not os.path.exists(summary_path):
        print(f"soak: FAILED: gausstrack-run exited {run.returncode}", file=sys.stderr)
        return 1
    with open(summary_path) as f:
        s = json.load(f)

    periods = round(a.duration * a.rate)
    failures = []
    if s["states_published"] < periods:
        failures.append(f"{s['states_published']} states published for {periods} periods")
    if s["commands_applied"] + s["commands_missing"] != s["states_published"]:
        failures.append(f"applied {s['commands_applied']} + missing {s['commands_missing']} != "
                        f"states {s['states_published']}")
    if s["plant_status"] != 0 or s["controller_status"] != 0:
        failures.append(f"exit statuses plant {s['plant_status']}, controller {s['controller_status']}")

    # The loop runs from start-up to the end of its duration; afterwards the plant writes its
    # outputs (latency.csv has a row per period), which is not the loop's memory.
    def growth(column):
        settled = [row for row in samples if 60.0 <= row[0] <= a.duration - 2.0] or samples
        values = [row[column] for row in settled]
        return values[0], max(values), values[-1]

    rows = []
    for column, name in ((1, "plant"), (2, "controller")):
        if not samples:
            failures.append("no memory samples")
            break
        first, peak, last = growth(column)
        grown = peak - first
        rows.append((name, first, peak, last, grown, max(row[column] for row in samples)))
        if grown > LIMIT_KIB:
            failures.append(f"{name} resident memory grew {grown} KiB after the first minute")

    rt = s["round_trip_us"]
    wl = s.get("wake_late_us") or {}
    lines = [
        f"Soak: {os.path.basename(a.scene)} over LCM, {a.rate:g} Hz, {a.duration:g} s, "
        f"{'--realtime' if realtime else 'default scheduler (not root)'}",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| periods | {periods} |",
        f"| states published | {s['states_published']} |",
        f"| commands applied + missing | {s['commands_applied']} + {s['commands_missing']} |",
        f"| commands late | {s['commands_late']} |",
        f"| deadline misses | {s['deadline_misses']} |",
        f"| watchdog trips | {s['watchdog_trips']} |",
        f"| messages rejected | {s['messages_rejected']} |",
        f"| max tracking error | {s['max_tracking_error']:.3g} |",
        f"| round trip p50 / p99 / max [us] | {rt['p50']:.0f} / {rt['p99']:.0f} / {rt['max']:.0f} |",
        f"| wake-up lateness p99 / max [us] | {wl.get('p99', float('nan')):.0f} / {wl.get('max', float('nan')):.0f} |",
    ]
    for name, first, peak, last, grown, overall in rows:
        lines.append(f"| {name} RSS over the loop, 60 s to the end: first / peak / last [KiB] | "
                     f"{first} / {peak} / {last} (grew {grown}); peak {overall} with the outputs written after it |")
    lines += ["", "PASS" if not failures else "FAIL: " + "; ".join(failures)]
    report = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "soak.md"), "w") as f:
        f.write(report)
    print(report)
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main())
