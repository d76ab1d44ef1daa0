#!/usr/bin/python3
"""Closes the loop over LCM: launches gausstrack-controller and gausstrack-plant (and lcm-logger
with --log) on one scene, waits for the run, stops the processes, then prints and writes the
run's summary and draws its plots.

usage: gausstrack-run SCENE [--duration T] [--rate HZ] [--lockstep] [--log FILE] [--out DIR]
                      [--set key=value ...] [--lcm-url URL] [--channel-prefix P]
                      [--realtime] [--watchdog-ms W] [--safe-action zero|hold] [--no-plots]

The scene runs with sampled control at --rate (default 1000 Hz). DIR (default out/run/<scene>)
receives trajectory.csv (the columns of gausstrack-sim), latency.csv, summary.json (the plant's
run and loop statistics merged with the controller's), controller.json, the processes' logs and
the plots. --realtime asks both processes for SCHED_FIFO, CPU pinning and mlockall (a warning
when not permitted). Exit status: 0 when the run completed and both processes stopped cleanly.
"""
import argparse
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import urllib.parse

HERE = os.path.dirname(os.path.realpath(__file__))


def tool(name):
    path = os.path.join(HERE, name)
    if not os.path.exists(path):
        sys.exit(f"gausstrack-run: {path} not found (run the copy in the build tree)")
    return path


def parse(argv):
    p = argparse.ArgumentParser(prog="gausstrack-run", description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--duration", type=float, help="run length [s] (default: the scene's)")
    p.add_argument("--rate", type=float, default=1000.0, help="control rate [Hz] (default 1000)")
    p.add_argument("--lockstep", action="store_true", help="the plant waits for each command")
    p.add_argument("--log", metavar="FILE", help="record the run's messages with lcm-logger")
    p.add_argument("--out", metavar="DIR")
    p.add_argument("--set", action="append", default=[], metavar="key=value", help="scene override")
    p.add_argument("--lcm-url", default="", help="default: LCM_DEFAULT_URL, else LCM's own")
    p.add_argument("--channel-prefix", default="GAUSSTRACK")
    p.add_argument("--realtime", action="store_true", help="SCHED_FIFO, pinning and mlockall")
    p.add_argument("--watchdog-ms", type=int, default=50)
    p.add_argument("--safe-action", choices=("zero", "hold"), default="zero")
    p.add_argument("--timeout-ms", type=int, default=2000, help="lock-step: longest wait for a command")
    p.add_argument("--no-plots", action="store_true")
    args = p.parse_args(argv)
    if args.rate <= 0 or (args.duration is not None and args.duration <= 0):
        p.error("--rate and --duration must be positive")
    return args


def wait_for_logger(url, channel, log_path, timeout=5.0):
    """lcm-logger says nothing when it has subscribed: publish a probe message (LCM's UDP
    multicast wire format: magic "LC02", sequence number, NUL-terminated channel, payload) until
    the log file shows it. Other transports are given a moment instead."""
    url = url or os.environ.get("LCM_DEFAULT_URL") or "udpm://239.255.76.67:7667?ttl=0"
    parsed = urllib.parse.urlparse(url)
    if parsed.scheme != "udpm":
        time.sleep(0.5)
        return True
    ttl = int(urllib.parse.parse_qs(parsed.query).get("ttl", ["0"])[0])
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, ttl)
    sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
    deadline = time.monotonic() + timeout
    seq = 0
    try:
        while time.monotonic() < deadline:
            packet = struct.pack(">II", 0x4C433032, seq) + channel.encode() + b"\0" + b"probe"
            sock.sendto(packet, (parsed.hostname, parsed.port or 7667))
            seq += 1
            time.sleep(0.05)
            if os.path.exists(log_path) and os.path.getsize(log_path) > 0:
                return True
        return False
    finally:
        sock.close()


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


def main(argv):
    args = parse(argv)
    scene_name = os.path.splitext(os.path.basename(args.scene))[0]
    out = args.out or os.path.join("out", "run", scene_name)
    os.makedirs(out, exist_ok=True)
    for stale in ("summary.json", "trajectory.csv", "latency.csv", "controller.json"):
        if os.path.exists(os.path.join(out, stale)):
            os.remove(os.path.join(out, stale))

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
    cpus = os.cpu_count() or 1
    rt_plant, rt_controller = [], []
    if args.realtime:
        rt_plant = ["--rt-priority", "80", "--lock-memory", "--cpu", str(cpus - 1)]
        rt_controller = ["--rt-priority", "80", "--lock-memory", "--cpu", str(max(0, cpus - 2))]

    logger = None
    if args.log:
        if os.path.exists(args.log):
            os.remove(args.log)
        cmd = ["lcm-logger", "-f", "-q", "--flush-interval=10", "-c", f"{prefix}_.*", args.log]
        # A lock-step run publishes as fast as the loop turns: give the logger's socket a large
        # receive buffer (the kernel caps it at net.core.rmem_max) so that a busy machine does
        # not make it drop messages.
        url = args.lcm_url or os.environ.get("LCM_DEFAULT_URL") or "udpm://239.255.76.67:7667?ttl=0"
        if url.startswith("udpm://") and "recv_buf_size" not in url:
            url += ("&" if "?" in url else "?") + "recv_buf_size=16777216"
        cmd.insert(1, f"--lcm-url={url}")
        logger = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
        ready = wait_for_logger(args.lcm_url, f"{prefix}_LOG_PROBE", args.log)
        if logger.poll() is not None or not ready:
            logger.kill()
            sys.exit(f"gausstrack-run: lcm-logger did not start recording {args.log}")

    controller = Process("gausstrack-controller",
                         [tool("gausstrack-controller")] + common + rt_controller +
                         ["--stats-out", os.path.join(out, "controller.json")],
                         os.path.join(out, "controller.log"))
    while not controller.ready.wait(0.05):
        if controller.proc.poll() is not None:
            controller.stop()
            print("\n".join(controller.lines), file=sys.stderr)
            if logger:
                logger.send_signal(signal.SIGINT)
                logger.wait()
            return 1

    plant_cmd = [tool("gausstrack-plant")] + common + rt_plant + [
        "--out", out, "--watchdog-ms", str(args.watchdog_ms), "--safe-action", args.safe_action,
        "--timeout-ms", str(args.timeout_ms)]
    if args.lockstep:
        plant_cmd.append("--lockstep")
    mode = "lock-step" if args.lockstep else "real time"
    print(f"gausstrack-run: {scene_name} at {args.rate:g} Hz, {mode}, output in {out}", flush=True)
    plant = Process("gausstrack-plant", plant_cmd, os.path.join(out, "plant.log"))
    try:
        plant.proc.wait()
    except KeyboardInterrupt:  # the plant got the SIGINT too: it writes what it has and stops
        plant.proc.wait()
    plant_status = plant.stop()
    controller_status = controller.stop()
    if logger:
        time.sleep(0.2)  # the processes' final loop_stats_t
        logger.send_signal(signal.SIGINT)
        logger.wait()

    summary_path = os.path.join(out, "summary.json")
    if not os.path.exists(summary_path):
        print(f"gausstrack-run: the plant wrote no summary (status {plant_status})", file=sys.stderr)
        return 1
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
        "commands_published": ctrl.get("commands_published", 0),
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

    rt, cp = summary["round_trip_us"], summary["compute_ns"]
    wl = summary.get("wake_late_us") or {}
    print(f"""
{scene_name}: {mode} at {args.rate:g} Hz over LCM
  tracking error      max {summary['max_tracking_error']:.3g}, rms {summary['rms_tracking_error']:.3g}
  round trip [us]     p50 {rt['p50']:.1f}  p99 {rt['p99']:.1f}  p99.9 {rt['p999']:.1f}  max {rt['max']:.1f}
  compute [ns]        p50 {cp['p50']:.0f}  p99 {cp['p99']:.0f}  max {cp['max']:.0f}
  wake-up late [us]   p99 {wl.get('p99', 0):.1f}  max {wl.get('max', 0):.1f}
  states published    {summary['states_published']}
  commands applied    {summary['commands_applied']} (missing {summary['commands_missing']}, \
late {summary['commands_late']})
  deadline misses     {summary['deadline_misses']}
  messages rejected   {summary['messages_rejected']} (plant {plant_rejected}, controller {controller_rejected})
  watchdog trips      {summary['watchdog_trips']}
  written             {summary_path}""")
    if args.log:
        print(f"  log                 {args.log}")

    if not args.no_plots:
        plots = subprocess.run(["/usr/bin/python3", tool("plot_run.py"), out], capture_output=True, text=True)
        if plots.returncode != 0:
            print(f"gausstrack-run: plotting failed:\n{plots.stderr}", file=sys.stderr)
        for line in plots.stdout.split():
            print(f"  figure              {line}")
    return 0 if plant_status == 0 and controller_status == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
