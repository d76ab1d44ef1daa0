#!/usr/bin/python3
"""What gausstrack-run's summary says after the deadline misses, on made-up summaries: the spin
and its total when the plant spun; when more than 1 % of a real-time run's periods started late
without a spin, what can start more of them on time (--realtime only where it was not used);
nothing in lock-step or at 1 % or less."""
import importlib.machinery
import importlib.util
import os
import sys

path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "nodes", "tools", "gausstrack_run.py")
loader = importlib.machinery.SourceFileLoader("gausstrack_run", path)
spec = importlib.util.spec_from_loader("gausstrack_run", loader)
run = importlib.util.module_from_spec(spec)
loader.exec_module(run)

failures = []


def expect(what, got, says=(), not_says=()):
    for s in says:
        if s not in got:
            failures.append(f"{what}: {got!r} does not say {s!r}")
    for s in not_says:
        if s in got:
            failures.append(f"{what}: {got!r} says {s!r}")


def summary(misses, states=10000, mode="realtime", **extra):
    return {"mode": mode, "deadline_misses": misses, "states_published": states} | extra


expect("a spinning plant", run.deadline_note(summary(3, spin_us=30, spun_ms=412.4), False),
       says=("spinning up to 30 us before each deadline", "412 ms in all"), not_says=("started late",))
expect("a spinning plant, many misses", run.deadline_note(summary(500, spin_us=30, spun_ms=1.0), False),
       says=("up to 30 us",), not_says=("started late",))
expect("2 % late, default scheduler", run.deadline_note(summary(200), False),
       says=("2.0 % of the periods started late", "--spin-us S (e.g. 30 at 10 kHz) or --realtime"))
expect("2 % late, --realtime", run.deadline_note(summary(200), True),
       says=("--spin-us S (e.g. 30 at 10 kHz) can start",), not_says=("--realtime",))
# The share is of the states published (the run's periods), not of a fixed count.
expect("1.5 % of 2000", run.deadline_note(summary(30, states=2000), False), says=("1.5 %",))
expect("exactly 1 %", run.deadline_note(summary(100), False), not_says=("late", "spinning"))
expect("under 1 %", run.deadline_note(summary(99), False), not_says=("late",))
expect("no periods", run.deadline_note(summary(0, states=0), False), not_says=("late",))
expect("lock-step", run.deadline_note(summary(9000, mode="lockstep", spin_us=30), False), not_says=("late", "spinning"))
if run.deadline_note(summary(99), False) != "" or run.deadline_note(summary(0, mode="lockstep"), False) != "":
    failures.append("nothing to say must add nothing to the line")

if failures:
    print("run_summary_test: FAILED\n" + "\n".join(failures))
    sys.exit(1)
print("run_summary_test: ok")
