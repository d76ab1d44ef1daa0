"""The rule the LCM tests share for a run the machine, not the product, held back.

A process of the loop held back 10 ms or more was stalled by the machine (a virtual machine's
host taking its CPU, another process), not by a fault under test: no network fault or crash of
the other process delays the plant's own wake-ups, and the test relay bunches states up by its
jitter only (a few periods), so a controller that found 10 periods' states queued at once was
held back, or its link was. A check that misses its expectation in such a run is run once more
and says so; a product fault shows in both runs.
"""

STALL_MS = 10.0


def machine_stall(summary, controllers=(), period_ms=1.0):
    """How the machine held the loop back in this run (a sentence), or None.

    summary: the plant's summary.json (gausstrack-run's carries the controller's largest_backlog
    too); controllers: the controllers' statistics files, read; period_ms: the control period.
    """
    late_ms = (summary.get("wake_late_us") or {}).get("max", 0.0) / 1e3
    if late_ms > STALL_MS:
        return f"the machine stalled the plant {late_ms:.0f} ms"
    backlog = max([summary.get("largest_backlog", 0)] + [c.get("largest_backlog", 0) for c in controllers])
    if backlog * period_ms >= STALL_MS:
        return (f"the machine held the controller or its link back {backlog * period_ms:.0f} ms or more "
                f"({backlog} states found queued at once)")
    return None
