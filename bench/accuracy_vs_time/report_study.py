#!/usr/bin/python3
"""Turns the accuracy_vs_time CSVs in DIR into work-precision tables (DIR/README.md), plots
(DIR/*.png) and the Pareto front: for each accuracy budget, the cheapest method that meets it.

usage: report_study.py DIR
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

BUDGETS = (1e-3, 1e-6, 1e-9, 1e-12)


def rows(d, name):
    with open(os.path.join(d, name), newline="") as f:
        return list(csv.DictReader(f))


def num(v):
    return float(v) if v not in ("", "nan") else math.nan


def fmt(v):
    v = num(v) if isinstance(v, str) else v
    if math.isnan(v):
        return "-"
    return f"{v:.2e}" if v != 0 and (abs(v) < 1e-2 or abs(v) >= 1e5) else f"{v:.3g}"


def table(header, body):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in body]
    return "\n".join(lines)


def pareto(points):
    """Points (cost, error, label) not beaten in both cost and error by another."""
    front, best = [], math.inf
    for cost, err, label in sorted(points, key=lambda p: (p[0], p[1])):
        if err < best:
            front.append((cost, err, label))
            best = err
    return front


def cheapest(points, budget):
    ok = [p for p in points if p[1] <= budget]
    return min(ok, key=lambda p: p[0]) if ok else None


def loglog_plot(path, title, series, xlabel, ylabel="error"):
    """One log-log line per (label, xs, ys) series; non-positive and missing values are left out."""
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for label, xs, ys in series:
        pts = sorted((x, y) for x, y in zip(xs, ys) if x > 0 and y > 0 and not math.isnan(y))
        if pts:
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", ms=3, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def integrators(d):
    """The integrators on every scene: tables, Pareto fronts, cheapest per error budget, plots."""
    out = []
    integ = rows(d, "integrators.csv")
    scenes = sorted({r["scene"] for r in integ})
    out += ["## Integrators on the paper's scenes", ""]
    for scene in scenes:
        rs = [r for r in integ if r["scene"] == scene and r["method"] != "reference_uncertainty"]
        unc = [r for r in integ if r["scene"] == scene and r["method"] == "reference_uncertainty"]
        has_indep = any(not math.isnan(num(r["independent_difference"])) for r in rs)
        header = ["method", "step / tol", "RHS evals", "wall [s]", "max error", "final error"]
        if has_indep:
            header.append("vs independent model")
        header += ["max tracking err", "max constraint res"]
        body = []
        for r in rs:
            row = [r["method"], r["setting"], r["rhs_evaluations"], fmt(r["wall_s"]), fmt(r["max_error"]),
                   fmt(r["final_error"])]
            if has_indep:
                row.append(fmt(r["independent_difference"]))
            row += [fmt(r["max_tracking_error"]), fmt(r["max_constraint_residual"])]
            body.append(row)
        points = [(num(r["wall_s"]), num(r["max_error"]), f"{r['method']} {r['setting']}") for r in rs]
        front = pareto(points)
        picks = []
        for b in BUDGETS:
            c = cheapest(points, b)
            picks.append([f"{b:g}", c[2] if c else "none reached it", fmt(c[0]) if c else "-"])
        methods = sorted({r["method"] for r in rs})
        png = f"integrators_{scene}.png"
        loglog_plot(os.path.join(d, png), f"{scene}: work-precision",
                            [(m, [num(r["rhs_evaluations"]) for r in rs if r["method"] == m],
                              [num(r["max_error"]) for r in rs if r["method"] == m]) for m in methods],
                            "right-hand-side evaluations")
        out += [f"### {scene}", ""]
        if unc:
            out += [f"Reference: Fehlberg 7(8) and Bulirsch-Stoer at 1e-14 agree to {fmt(unc[0]['max_error'])}.", ""]
        out += [table(header, body), "",
                "Pareto front (wall time against max error): " + ", ".join(p[2] for p in front) + ".", "",
                table(["error budget", "cheapest method", "wall [s]"], picks), "", f"![{scene}]({png})", ""]
    return out


def peer(d):
    """SUNDIALS ARKODE against odeint on the Duffing task."""
    out = []
    peer = rows(d, "peer.csv")
    out += ["## Peer integrator: SUNDIALS ARKODE against odeint", "",
            "The Duffing tracking task (alpha = 0.4, 10 s) as one ODE whose right-hand side evaluates the "
            "control law; the same tableaux in both libraries; final-state error against odeint's Fehlberg "
            "7(8) at 1e-14.", ""]
    out.append(table(["integrator", "tolerance", "RHS evals", "wall [s]", "final error"],
                     [[r["integrator"], r["tolerance"], r["rhs_evaluations"], fmt(r["wall_s"]),
                       fmt(r["final_error"])] for r in peer]))
    points = [(num(r["wall_s"]), num(r["final_error"]), f"{r['integrator']} {r['tolerance']}") for r in peer]
    picks = []
    for b in BUDGETS:
        c = cheapest(points, b)
        picks.append([f"{b:g}", c[2] if c else "none reached it", fmt(c[0]) if c else "-"])
    out += ["", "At equal error, the cheapest:", "", table(["error budget", "cheapest", "wall [s]"], picks), ""]
    names = sorted({r["integrator"] for r in peer})
    loglog_plot(os.path.join(d, "peer.png"), "Duffing task: odeint vs ARKODE",
                        [(n, [num(r["rhs_evaluations"]) for r in peer if r["integrator"] == n],
                          [num(r["final_error"]) for r in peer if r["integrator"] == n]) for n in names],
                        "right-hand-side evaluations")
    out += ["![peer](peer.png)", ""]
    return out


def strategies(d):
    """The generalized-inverse strategies and damping on manufactured solutions."""
    out = []
    st = rows(d, "strategies.csv")
    out += ["## Generalized-inverse strategies and damping", "",
            "6 x 3 constraint sets; force error relative to a manufactured exact solution (q'' and the multipliers "
            "chosen first, then g and Q - f built from them); "
            "residual ||D q'' - g||; warnings are `gausstrack::warning` flags (1 rank deficient, 2 constraints "
            "not met, 4 ill-conditioned, 8 fell back to SVD).", ""]
    out.append(table(["case", "strategy", "damping", "force error", "residual", "||Q'||", "ns per call",
                      "warnings"],
                     [[r["case"], r["strategy"], r["damping"], fmt(r["force_error"]), fmt(r["constraint_residual"]),
                       fmt(r["force_norm"]), r["ns_per_call"], r["warnings"]] for r in st]))
    out.append("")
    return out


def control_rate(d):
    """The control rate (sampled and held)."""
    out = []
    cr = rows(d, "control_rate.csv")
    out += ["## Control rate (sampled and held), Duffing alpha = 4", "",
            "`midpoint`: the held law (docs/sampled_law.md), second order in the period; `sample`: the law at "
            "the measured state, held, first order. The order is read off each pair of neighbouring rates "
            "(log of the error ratio over log of the rate ratio; the median of the pairs).", ""]
    out.append(table(["rate [Hz]", "stabilization omega", "hold", "max tracking error", "rms",
                      "control evaluations", "wall [s]"],
                     [[r["rate_hz"], r["stabilization_omega"], r.get("hold", ""), fmt(r["max_tracking_error"]),
                       fmt(r["rms_tracking_error"]), r["control_evaluations"], fmt(r["wall_s"])] for r in cr]))
    series = sorted({(r["stabilization_omega"], r.get("hold", "")) for r in cr}, key=lambda k: (float(k[0]), k[1]))
    orders = []
    for om, hold in series:
        pts = sorted((num(r["rate_hz"]), num(r["max_tracking_error"])) for r in cr
                     if r["stabilization_omega"] == om and r.get("hold", "") == hold)
        slopes = sorted(math.log(e0 / e1) / math.log(r1 / r0) for (r0, e0), (r1, e1) in zip(pts, pts[1:])
                        if e0 > 0 and e1 > 0 and r1 > r0)
        if slopes:
            orders.append(f"{hold or 'held'} at omega {om}: order {slopes[len(slopes) // 2]:.2f}")
    if orders:
        out += ["", "Order of accuracy read off: " + "; ".join(orders) + "."]
    loglog_plot(os.path.join(d, "control_rate.png"), "Duffing task: control rate",
                [(f"{hold or 'held'}, omega {om}",
                  [num(r["rate_hz"]) for r in cr if r["stabilization_omega"] == om and r.get("hold", "") == hold],
                  [num(r["max_tracking_error"]) for r in cr
                   if r["stabilization_omega"] == om and r.get("hold", "") == hold]) for om, hold in series],
                "control rate [Hz]", "max tracking error")
    out += ["", "![control rate](control_rate.png)", ""]
    return out


def stabilization(d):
    """The stabilization gains at 1 kHz."""
    out = []
    sb = rows(d, "stabilization.csv")
    out += ["## Stabilization gains at 1 kHz (zeta = 1)", ""]
    out.append(table(["plant", "omega", "max tracking error", "rms", "final"],
                     [[r["plant"], r["stabilization_omega"], fmt(r["max_tracking_error"]),
                       fmt(r["rms_tracking_error"]), fmt(r["final_tracking_error"])] for r in sb]))
    plants = sorted({r["plant"] for r in sb})
    loglog_plot(os.path.join(d, "stabilization.png"), "Duffing task at 1 kHz: stabilization gain",
                [(p, [num(r["stabilization_omega"]) for r in sb if r["plant"] == p],
                  [num(r["rms_tracking_error"]) for r in sb if r["plant"] == p]) for p in plants],
                "stabilization omega [rad/s]", "rms tracking error")
    out += ["", "![stabilization](stabilization.png)", ""]
    return out


def projection(d):
    """Projection onto the constraint manifolds."""
    out = []
    pj = rows(d, "projection.csv")
    out += ["## Constraint drift: projection after each step (Fig. 2, Fig. 3's a; dopri5)", "",
            "Error against Fehlberg 7(8) at tolerance 1e-13 with projection (another method), largest "
            "|q - q_ref| over the samples.", ""]
    out.append(table(["a", "tolerance", "projection", "rhs evaluations", "wall [s]", "max residual [m^2]",
                      "max error [m]", "final error [m]"],
                     [[r["a"], r["tolerance"], "yes" if r["projection"] == "1" else "no", r["rhs_evaluations"],
                       fmt(r["wall_s"]), fmt(r["max_constraint_residual"]), fmt(r["max_error"]),
                       fmt(r["final_error"])] for r in pj]))
    out.append("")
    return out


def main(d):
    out = ["# What accuracy costs in time", "",
           "Generated by `scripts/bench` (`accuracy_vs_time` then `report_study.py`). Error is the largest "
           "|q - q_ref| over 11 sparse sample times (every tenth of the run: no step is cut by the output "
           "grid) against a reference from two methods at tolerance 1e-14, Fehlberg 7(8) and Bulirsch-Stoer "
           "(their mean; their difference is given per scene as the reference's uncertainty: errors below "
           "it are not resolved); cost is right-hand-side evaluations and wall time on the machine that ran "
           "it. Bulirsch-Stoer allocates as it steps: an offline choice.", ""]

    for section in (integrators, peer, strategies, control_rate, stabilization, projection):
        if os.path.exists(os.path.join(d, section.__name__ + ".csv")):  # a part run alone (--only) leaves the rest out
            out += section(d)

    with open(os.path.join(d, "README.md"), "w") as f:
        f.write("\n".join(out) + "\n")
    print(os.path.join(d, "README.md"))
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1]))
