#!/usr/bin/python3
"""Closes the loop over LCM: launches gausstrack-controller and gausstrack-plant on one scene,
waits for the run, stops the processes, then prints and writes the run's summary and draws its
plots. With --log each process records every message it publishes (states, commands, their
loop statistics) in its own LCM log, and the two are merged into FILE: the record is complete
whatever the pace, unlike a listener on the network, which can miss a burst.

usage: gausstrack-run SCENE [--duration T] [--rate HZ] [--lockstep] [--log FILE] [--out DIR]
                      [--set key=value ...] [--lcm-url URL] [--channel-prefix P]
                      [--realtime [--cpus PLANT,CONTROLLER]] [--spin-us S] [--watchdog-ms W]
                      [--safe-action zero|hold] [--no-plots]

The scene runs with sampled control at --rate (default 1000 Hz). DIR (default out/run/<scene>)
receives trajectory.csv (the columns of gausstrack-sim), latency.csv, summary.json (the plant's
run and loop statistics merged with the controller's), controller.json, the processes' logs and
the plots. --realtime asks both processes for SCHED_FIFO, CPU pinning and mlockall (a warning
when not permitted); --cpus chooses the two CPUs (default: the last two, one each; the same CPU
twice puts both processes on it). --spin-us S has the plant wake S us before each period's
deadline and spin until it: fewer late periods at high rates, for up to S us of CPU per period.
Exit status: 0 when the run completed and both processes stopped cleanly.
"""
import argparse
import json
import os
import signal
import subprocess
import sys
import threading

HERE = os.path.dirname(os.path.realpath(__file__))


def tool(name):
    path = os.path.join(HERE, name)
    if not os.path.exists(path):
        sys.exit(f"gausstrack-run: {path} not found (run the copy in the build tree)")
    return path


class Once(argparse.Action):
    """Stores an option's value and refuses the option a second time, as the C++ programs do (argparse
    would keep the last value silently). With nargs=0, a flag that stores True."""

    def __init__(self, option_strings, dest, nargs=None, **kwargs):
        if nargs == 0:
            kwargs.setdefault("const", True)
            kwargs.setdefault("default", False)
        super().__init__(option_strings, dest, nargs=nargs, **kwargs)
        self.given = False

    def __call__(self, parser, namespace, values, option_string=None):
        if self.given:
            parser.error(f"{self.option_strings[0]} given more than once")
        self.given = True
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)


def parse(argv):
    p = argparse.ArgumentParser(prog="gausstrack-run", description=__doc__.split("\n\n")[0])
    p.register("action", "once", Once)
    p.add_argument("scene")
    p.add_argument("--duration", action="once", type=float, help="run length [s] (default: the scene's)")
    p.add_argument("--rate", action="once", type=float, default=1000.0, help="control rate [Hz] (default 1000)")
    p.add_argument("--lockstep", action="once", nargs=0, help="the plant waits for each command")
    p.add_argument("--log", action="once", metavar="FILE", help="record every message of the run (LCM log)")
    p.add_argument("--out", action="once", metavar="DIR")
    p.add_argument("--set", action="append", default=[], metavar="key=value", help="scene override")
    p.add_argument("--lcm-url", action="once", default="", help="default: LCM_DEFAULT_URL, else LCM's own")
    p.add_argument("--channel-prefix", action="once", default="GAUSSTRACK")
    p.add_argument("--realtime", action="once", nargs=0, help="SCHED_FIFO, pinning and mlockall")
    p.add_argument("--cpus", action="once", metavar="PLANT,CONTROLLER", help="with --realtime: the CPUs to pin to")
    p.add_argument("--spin-us", action="once", type=int, default=0,
                   help="the plant wakes this long before each deadline and spins until it (less than the period)")
    p.add_argument("--watchdog-ms", action="once", type=int, default=50)
    p.add_argument("--safe-action", action="once", choices=("zero", "hold"), default="zero")
    p.add_argument("--timeout-ms", action="once", type=int, default=2000, help="lock-step: longest wait for a command")
    p.add_argument("--no-plots", action="once", nargs=0)
    args = p.parse_args(argv)
    if args.rate <= 0 or (args.duration is not None and args.duration <= 0):
        p.error("--rate and --duration must be positive")
    if args.spin_us and args.lockstep:
        p.error("--spin-us applies in real time, not with --lockstep")
    if not 0 <= args.spin_us < 1e6 / args.rate:
        p.error(f"--spin-us must be at least 0 and less than the period ({1e6 / args.rate:g} us at {args.rate:g} Hz)")
    if args.cpus is not None:
        try:
            args.cpus = [int(c) for c in args.cpus.split(",")]
        except ValueError:
            args.cpus = []
        if len(args.cpus) != 2 or min(args.cpus) < 0:
            p.error("--cpus takes two CPU numbers, PLANT,CONTROLLER (e.g. 1,1)")
        if not args.realtime:
            p.error("--cpus applies with --realtime")
    return args


class Process:
    """A child process whose stdout is kept in a log and collected line by line (and echoed)."""

    def __init__(self, name, cmd, log_path):
        self.name = name
        self.lines = []
        self.ready = threading.Event()
        self.log = open(log_path, "w")
        # stderr stays the caller's: warnings and the plant's progress display go straight there
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, bufsize=1)
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.proc.stdout:
            self.log.write(line)
            self.log.flush()
            self.lines.append(line.rstrip("\n"))
            if line.startswith(f"{self.name}: ready"):
                self.ready.set()
            elif line.strip():
                sys.stdout.write(line)
                sys.stdout.flush()

    def stop(self, timeout=5.0):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.reader.join(timeout)
        self.log.close()
        return self.proc.returncode


def fresh_output_dir(args, scene_name):
    """The run's directory, without the files of an earlier run."""
    out = args.out or os.path.join("out", "run", scene_name)
    os.makedirs(out, exist_ok=True)
    for stale in ("summary.json", "trajectory.csv", "latency.csv", "controller.json"):
        if os.path.exists(os.path.join(out, stale)):
            os.remove(os.path.join(out, stale))
    return out


def command_lines(args, out):
    """The arguments both processes share, each one's real-time options and log, and the logs to merge."""
    sets = list(args.set) + ["control.mode=sampled", f"control.rate={args.rate:g}"]
    if args.duration is not None:
        sets.append(f"duration={args.duration:g}")
    common = ["--scene", args.scene]
    for s in sets:
        common += ["--set", s]
    prefix = args.channel_prefix
    common += ["--state-channel", f"{prefix}_STATE", "--command-channel", f"{prefix}_COMMAND",
               "--stats-channel", f"{prefix}_STATS"]
    if args.lcm_url:
        common += ["--lcm-url", args.lcm_url]
    own = {"controller": [], "plant": []}
    if args.realtime:
        cpus = os.cpu_count() or 1
        plant_cpu, controller_cpu = args.cpus or (cpus - 1, max(0, cpus - 2))
        for name, cpu in (("plant", plant_cpu), ("controller", controller_cpu)):
            # The plant above the controller: on a shared CPU the plant's clock (the physical world's) is
            # not held up by the controller's work; the plant's loop then runs one above its receiver.
            own[name] += ["--rt-priority", "82" if name == "plant" else "80", "--lock-memory", "--cpu", str(cpu)]
    part_logs = []
    if args.log:
        if os.path.exists(args.log):
            os.remove(args.log)
        for name in own:
            path = os.path.join(out, f"{name}.lcmlog")
            part_logs.append(path)
            own[name] += ["--log", path] + (["--log-wait"] if args.lockstep else [])
    own["controller"] += ["--stats-out", os.path.join(out, "controller.json")]
    own["plant"] += ["--out", out, "--watchdog-ms", str(args.watchdog_ms), "--safe-action", args.safe_action,
                     "--timeout-ms", str(args.timeout_ms)]
    own["plant"] += ["--lockstep"] if args.lockstep else ["--spin-us", str(args.spin_us)]
    return common, own, part_logs


def merge_logs(args, part_logs):
    """Joins the processes' logs into --log; returns the merge's status."""
    merge = subprocess.run([tool("gausstrack-log-merge"), args.log] + part_logs, capture_output=True, text=True)
    if merge.returncode != 0:
        print(f"gausstrack-run: merging the logs failed:\n{merge.stderr}", file=sys.stderr)
    else:
        for path in part_logs:
            os.remove(path)
    return merge.returncode


def merged_summary(args, out, plant_status, controller_status):
    """The plant's summary.json with the controller's counts added, rewritten in place; None without one."""
    summary_path = os.path.join(out, "summary.json")
    if not os.path.exists(summary_path):
        print(f"gausstrack-run: the plant wrote no summary (status {plant_status})", file=sys.stderr)
        return None
    with open(summary_path) as f:
        summary = json.load(f)
    ctrl = {}
    if os.path.exists(os.path.join(out, "controller.json")):
        with open(os.path.join(out, "controller.json")) as f:
            ctrl = json.load(f)
    plant_rejected = summary.get("messages_rejected", 0)
    controller_rejected = ctrl.get("messages_rejected", 0)
    summary.update({
        "messages_rejected": plant_rejected + controller_rejected,
        "messages_rejected_by_plant": plant_rejected,
        "messages_rejected_by_controller": controller_rejected,
        "log_dropped": summary.get("log_dropped", 0) + ctrl.get("log_dropped", 0),
        "commands_published": ctrl.get("commands_published", 0),
        "states_superseded": ctrl.get("states_superseded", 0),
        "largest_backlog": ctrl.get("largest_backlog", 0),
        "compute_ns_at_plant": summary.get("compute_ns"),
        "compute_ns": ctrl.get("compute_ns", summary.get("compute_ns")),
        "lcm_url": args.lcm_url or os.environ.get("LCM_DEFAULT_URL", "(LCM default)"),
        "log": args.log,
        "plant_status": plant_status,
        "controller_status": controller_status,
    })
    with open(summary_path, "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    return summary


# More periods than this share starting late (deadline misses) makes the summary say what starts
# them on time.
LATE_START_SHARE = 0.01


def deadline_note(summary, realtime):
    """What the summary says after the deadline misses of a real-time run: the spin the plant took
    before each deadline, and, when more than LATE_START_SHARE of the periods started late
    without a spin, what would start them on time; empty otherwise."""
    if summary.get("mode") != "realtime":
        return ""
    spin = summary.get("spin_us") or 0
    if spin:
        return f" (spinning up to {spin} us before each deadline: {summary.get('spun_ms', 0):.0f} ms in all)"
    share = summary["deadline_misses"] / max(summary["states_published"], 1)
    if share <= LATE_START_SHARE:
        return ""
    cures = "--spin-us S (e.g. 30 at 10 kHz)" + ("" if realtime else " or --realtime")
    return f" ({100 * share:.1f} % of the periods started late: {cures} can start more of them on time, docs/lcm.md)"


def print_summary(args, scene_name, mode, summary, summary_path):
    rt, cp = summary["round_trip_us"], summary["compute_ns"]
    wl = summary.get("wake_late_us") or {}
    print(f"""
{scene_name}: {mode} at {args.rate:g} Hz over LCM
  tracking error      max {summary['max_tracking_error']:.3g}, rms {summary['rms_tracking_error']:.3g}
  round trip [us]     p50 {rt['p50']:.1f}  p99 {rt['p99']:.1f}  p99.9 {rt['p999']:.1f}  max {rt['max']:.1f}
  compute [ns]        p50 {cp['p50']:.0f}  p99 {cp['p99']:.0f}  max {cp['max']:.0f}
  wake-up late [us]   p99 {wl.get('p99', 0):.1f}  max {wl.get('max', 0):.1f}
  states published    {summary['states_published']} ({summary['states_superseded']} superseded at the controller \
by a newer one before it answered)
  commands applied    {summary['commands_applied']} (missing {summary['commands_missing']}, \
late {summary['commands_late']})
  deadline misses     {summary['deadline_misses']}{deadline_note(summary, args.realtime)}
  messages rejected   {summary['messages_rejected']} (plant {summary['messages_rejected_by_plant']}, \
controller {summary['messages_rejected_by_controller']})
  watchdog trips      {summary['watchdog_trips']}
  written             {summary_path}""")
    if args.log:
        print(f"  log                 {args.log} ({summary['log_dropped']} messages dropped)")


def draw_plots(out):
    plots = subprocess.run(["/usr/bin/python3", tool("plot_run.py"), out], capture_output=True, text=True)
    if plots.returncode != 0:
        print(f"gausstrack-run: plotting failed:\n{plots.stderr}", file=sys.stderr)
    for line in plots.stdout.split():
        print(f"  figure              {line}")


def main(argv):
    args = parse(argv)
    scene_name = os.path.splitext(os.path.basename(args.scene))[0]
    out = fresh_output_dir(args, scene_name)
    common, own, part_logs = command_lines(args, out)

    controller = Process("gausstrack-controller", [tool("gausstrack-controller")] + common + own["controller"],
                         os.path.join(out, "controller.log"))
    while not controller.ready.wait(0.05):
        if controller.proc.poll() is not None:
            controller.stop()
            print("\n".join(controller.lines), file=sys.stderr)
            return 1

    mode = "lock-step" if args.lockstep else "real time"
    print(f"gausstrack-run: {scene_name} at {args.rate:g} Hz, {mode}, output in {out}", flush=True)
    plant = Process("gausstrack-plant", [tool("gausstrack-plant")] + common + own["plant"],
                    os.path.join(out, "plant.log"))
    try:
        plant.proc.wait()
    except KeyboardInterrupt:  # the plant got the SIGINT too: it writes what it has and stops
        plant.proc.wait()
    plant_status = plant.stop()
    controller_status = controller.stop()
    log_status = merge_logs(args, part_logs) if args.log else 0

    summary = merged_summary(args, out, plant_status, controller_status)
    if summary is None:
        return 1
    print_summary(args, scene_name, mode, summary, os.path.join(out, "summary.json"))
    if not args.no_plots:
        draw_plots(out)
    return 0 if plant_status == 0 and controller_status == 0 and log_status == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
