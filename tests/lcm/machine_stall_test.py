#!/usr/bin/python3
"""The rule that lets an LCM test run a check once more (machine_stall.py), on made-up summaries:
a run is held back by the machine exactly when the plant woke more than STALL_MS late, or a
controller found STALL_MS or more of periods' states queued at once; otherwise the check's
verdict stands on one run."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from machine_stall import STALL_MS, machine_stall  # noqa: E402

failures = []


def expect(what, got, stalled, mentions=None):
    if (got is not None) != stalled:
        failures.append(f"{what}: {'no stall' if got is None else repr(got)}, expected "
                        f"{'a stall' if stalled else 'none'}")
    elif mentions is not None and mentions not in got:
        failures.append(f"{what}: {got!r} does not say {mentions!r}")


def plant(late_max_us=0.0, backlog=None):
    s = {"wake_late_us": {"p50": 20.0, "p99": 60.0, "max": late_max_us}}
    if backlog is not None:
        s["largest_backlog"] = backlog
    return s


assert STALL_MS == 10.0, "the cases below are written for a 10 ms rule"

# The plant's own wake-ups: strictly more than 10 ms late.
expect("a quiet run", machine_stall(plant(800.0)), False)
expect("woken 10 ms late", machine_stall(plant(10000.0)), False)
expect("woken 10.6 ms late", machine_stall(plant(10600.0)), True, "stalled the plant 11 ms")
expect("woken 250 ms late", machine_stall(plant(250000.0)), True, "250 ms")

# The controller's backlog at 1 kHz: 10 states queued at once is 10 ms held back.
expect("9 states queued (plant's count)", machine_stall(plant(500.0, 9)), False)
expect("10 states queued (plant's count)", machine_stall(plant(500.0, 10)), True, "10 states found queued")
expect("the controllers' own counts", machine_stall(plant(500.0, 2), [{"largest_backlog": 3}, {"largest_backlog": 14}]),
       True, "14 states")
expect("the plant's count beside smaller controller counts", machine_stall(plant(500.0, 12), [{"largest_backlog": 1}]),
       True, "12 states")
expect("controllers under the rule", machine_stall(plant(500.0, 2), [{"largest_backlog": 9}, {}]), False)

# The same count at another rate is another duration: at 10 kHz, 99 states are 9.9 ms, 101 are 10.1 ms;
# at 100 Hz, one state queued behind another is already 20 ms.
expect("99 states at 10 kHz", machine_stall(plant(500.0, 99), period_ms=0.1), False)
expect("101 states at 10 kHz", machine_stall(plant(500.0, 101), period_ms=0.1), True, "101 states")
expect("2 states at 100 Hz", machine_stall(plant(500.0, 2), period_ms=10.0), True, "20 ms")

# The plant's lateness is reported first when both happened.
expect("both", machine_stall(plant(30000.0, 50)), True, "stalled the plant 30 ms")

# A summary without the figures (a run that ended before its first period) is no stall.
expect("an empty summary", machine_stall({}), False)
expect("no wake-up figures", machine_stall({"wake_late_us": None}), False)

for f in failures:
    print("FAIL:", f)
print(f"machine_stall: {'all cases as expected' if not failures else f'{len(failures)} failed'}")
sys.exit(1 if failures else 0)
