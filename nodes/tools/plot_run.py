#!/usr/bin/python3
"""Draws a run's figures as PNG files next to its trajectory.csv, in the manner of the paper's
panels: displacements and velocities over time, phase plots, constraint or tracking error on a
log axis, and control forces; and, for a closed-loop run with a latency.csv, its round-trip
latency over the run and as a histogram.

usage: plot_run.py DIR [DIR ...]
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no samples")
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def plot_dir(d):
    data = read(os.path.join(d, "trajectory.csv"))
    n = sum(1 for k in data if k.startswith("qd"))
    t = data["t"]
    styles = ["-", "--", ":"]
    written = []

    def save(fig, name):
        fig.tight_layout()
        path = os.path.join(d, name)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    fig, ax = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for i in range(1, n + 1):
        ax[0].plot(t, data[f"q{i}"], styles[(i - 1) % 3], label=f"q{i}")
        ax[1].plot(t, data[f"qd{i}"], styles[(i - 1) % 3], label=f"qd{i}")
    ax[0].set_ylabel("displacement")
    ax[1].set_ylabel("velocity")
    ax[1].set_xlabel("time [s]")
    for a in ax:
        a.legend()
        a.grid(True, alpha=0.3)
    save(fig, "states.png")

    fig, ax = plt.subplots(1, n, figsize=(4 * n, 4))
    for i in range(1, n + 1):
        ax[i - 1].plot(data[f"q{i}"], data[f"qd{i}"], lw=0.8)
        ax[i - 1].set_xlabel(f"q{i}")
        ax[i - 1].set_ylabel(f"qd{i}")
        ax[i - 1].set_title(f"phase plane {i}")
    save(fig, "phase.png")

    for column, name, label in (("tracking_error", "tracking_error.png", "tracking error"),
                                ("constraint_residual", "constraint_residual.png", "constraint residual")):
        values = [abs(v) for v in data[column]]
        if max(values) > 0:
            fig, ax = plt.subplots(figsize=(7, 3.5))
            ax.semilogy(t, [max(v, 1e-18) for v in values])
            ax.set_xlabel("time [s]")
            ax.set_ylabel(f"|{label}|")
            ax.grid(True, which="both", alpha=0.3)
            save(fig, name)

    if any(any(v != 0 for v in data[f"u{i}"]) for i in range(1, n + 1)):
        fig, ax = plt.subplots(figsize=(7, 3.5))
        for i in range(1, n + 1):
            ax.plot(t, data[f"u{i}"], styles[(i - 1) % 3], label=f"u{i}")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("control force [N]")
        ax.legend()
        ax.grid(True, alpha=0.3)
        save(fig, "control.png")

    latency_path = os.path.join(d, "latency.csv")
    if os.path.exists(latency_path):
        with open(latency_path, newline="") as f:
            rows = list(csv.DictReader(f))
        if rows:
            rt = sorted(float(r["round_trip_us"]) for r in rows)
            fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
            ax[0].plot([int(r["state_sequence"]) for r in rows], [float(r["round_trip_us"]) for r in rows],
                       ".", ms=1.5)
            ax[0].set_yscale("log")
            ax[0].set_xlabel("state sequence (control period)")
            ax[0].set_ylabel("round trip [us]")
            ax[1].hist(rt, bins=100, log=True)
            for q, style in ((0.5, "-"), (0.99, "--"), (0.999, ":")):
                v = rt[min(len(rt) - 1, int(q * len(rt)))]
                ax[1].axvline(v, color="k", ls=style, lw=0.8, label=f"p{q * 100:g} {v:.0f} us")
            ax[1].set_xlabel("round trip: state published to command received [us]")
            ax[1].set_ylabel("count")
            ax[1].legend()
            for a in ax:
                a.grid(True, which="both", alpha=0.3)
            save(fig, "latency.png")
    return written


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    for d in argv[1:]:
        for path in plot_dir(d):
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
