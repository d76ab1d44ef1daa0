#!/usr/bin/python3
"""Summarizes the benchmark outputs in DIR (written by scripts/bench) as DIR/README.md: the
control law per system and strategy beside its baselines, the targets as ratios from one run,
how cost grows with N (fitted exponent), the plant step, the firmware loop, transport, the
closed loop against its floors, and the accuracy and MuJoCo studies.

usage: report_bench.py DIR [--doc PAGE.md]
  --doc  also replace the measured part of PAGE.md (between its "scripts/bench: begin" and
         "scripts/bench: end" lines) with the same tables
"""
import argparse
import csv
import json
import math
import os
import sys
from statistics import median

BEGIN, END = "<!-- scripts/bench: begin", "<!-- scripts/bench: end"

STRATEGIES = ("cholesky", "cholesky_refactor", "cholesky_dense_refactor", "cholesky_held", "svd", "cod", "damped")
BASELINES = ("literal_fixed", "dynamic_user", "dynamic_kkt", "plain_fixed", "model_terms", "closed_form")


def load(d, name):
    path = os.path.join(d, name)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def benchmarks(doc):
    """name -> (median real time [ns], counters) from a Google Benchmark JSON with repetitions, in
    the order the benchmarks were registered (repetitions run interleaved at random)."""
    runs = {}
    order = lambda b: (b.get("family_index", 0), b.get("per_family_instance_index", 0))
    for b in sorted(doc["benchmarks"], key=order):
        name = b.get("run_name", b["name"])
        if b.get("run_type") == "aggregate":
            if b.get("aggregate_name") == "median":
                runs.setdefault(name, {})["median"] = b
            continue
        runs.setdefault(name, {}).setdefault("iterations", []).append(b)
    out = {}
    for name, r in runs.items():
        b = r.get("median") or r["iterations"][0]
        scale = {"ns": 1, "us": 1e3, "ms": 1e6, "s": 1e9}[b.get("time_unit", "ns")]
        it = r.get("iterations", [b])
        counters = {k: median(x[k] for x in it)
                    for k in ("p50_ns", "p99_ns", "p999_ns", "max_ns", "allocs_per_call") if k in it[0]}
        counters["max_ns"] = max(x.get("max_ns", 0) for x in it)
        counters["min_time_ns"] = min(x["real_time"] * scale for x in it)
        out[name] = (b["real_time"] * scale, counters)
    return out


def ns(v):
    return f"{v / 1e3:.2f} us" if v >= 1e4 else f"{v:.0f} ns"


def demote(text_or_lines):
    """Headings one level down (the lines of a text or a list of lines that may hold several)."""
    lines = text_or_lines if isinstance(text_or_lines, list) else [text_or_lines]
    lines = [l for item in lines for l in item.split("\n")]
    return [("#" + l if l.startswith("#") else l) for l in lines]


def studies(d):
    """The accuracy and MuJoCo studies' own tables (their headings one level down), if they ran."""
    out = []
    for path, title in ((os.path.join(d, "accuracy_vs_time", "README.md"), "What accuracy costs"),
                        (os.path.join(d, "mujoco_study", "mujoco_study.md"), "MuJoCo as the plant")):
        if os.path.exists(path):
            with open(path) as f:
                lines = f.read().rstrip("\n").split("\n")
            if lines and lines[0].startswith("# "):
                lines = lines[1:]
            out += [f"## {title}", ""] + demote(lines) + [""]
    return out


def update_doc(page, body):
    """Replaces the lines between the page's begin and end markers with body."""
    with open(page) as f:
        lines = f.read().split("\n")
    begin = next((i for i, l in enumerate(lines) if l.startswith(BEGIN)), None)
    end = next((i for i, l in enumerate(lines) if l.startswith(END)), None)
    if begin is None or end is None or end < begin:
        print(f"report_bench.py: {page} has no '{BEGIN} ...' and '{END} ...' lines", file=sys.stderr)
        return 1
    # Figures stay beside the run's own README (out/bench/...): the page carries the tables.
    body = [l for l in demote(body) if not l.startswith("![")]
    with open(page, "w") as f:
        f.write("\n".join(lines[:begin + 1] + body + lines[end:]))
    print(page)
    return 0


def control_law(d):
    """The law per system and strategy beside its baselines, the targets, the solve taken apart, growth."""
    doc = load(d, "controller_bench.json")
    if not doc:
        return []
    ctx = doc["context"]
    out = [f"Machine: {ctx.get('num_cpus')} CPUs at {ctx.get('mhz_per_cpu')} MHz; built for the host CPU: "
           f"{ctx.get('build_for_host_cpu', 'no')}. The timer's own cost per timed call (two clock reads) is the "
           "`timer_overhead` row.", "",
           "Law rows: `cholesky` is the default (the mass matrix as the model declares it; the factorization "
           "kept while A and D are unchanged bit for bit, as they are for the Duffing systems); "
           "`cholesky_refactor` factors on every call, as a configuration-dependent A and D need; "
           "`cholesky_dense_refactor` also reads a declared-diagonal A as dense (the general case). "
           "`plain_fixed` is the same mathematics on the law's own kernels with no checks and no diagnostics.", ""]
    b = benchmarks(doc)
    models = []
    for name in b:
        parts = name.split("/")
        if len(parts) == 3 and parts[1] not in models:
            models.append(parts[1])
    return (out + law_table(b, models) + targets(b, models) + solve_split(b, models) + phases(b, models)
            + growth(b, models) + natural_form(b) + actuation(b))


def timed(b):
    return lambda key: b[key][0] if key in b else math.nan


def fastest(b):
    """Like timed, the fastest repetition instead of the median."""
    return lambda key: b[key][1]["min_time_ns"] if key in b else math.nan


def law_table(b, models):
    out = ["## Control law: one full evaluation (model terms + eq. 32)", "",
           "Time is Google Benchmark's median over repetitions; p50/p99/p99.9/max come from calls timed one by "
           "one (they include the timer's own cost); allocations are per call.", ""]
    rows = []
    for m in models:
        for kind, names in (("law", STRATEGIES), ("baseline", BASELINES)):
            for s in names:
                key = f"{kind}/{m}/{s}"
                if key in b:
                    t, c = b[key]
                    rows.append([m, f"{kind}: {s}", ns(t), ns(c.get("p50_ns", 0)), ns(c.get("p99_ns", 0)),
                                 ns(c.get("p999_ns", 0)), ns(c.get("max_ns", 0)), f"{c.get('allocs_per_call', 0):.0f}"])
    if "baseline/timer_overhead" in b:
        t, c = b["baseline/timer_overhead"]
        rows.append(["-", "timer overhead", ns(t), ns(c["p50_ns"]), ns(c["p99_ns"]), ns(c["p999_ns"]),
                     ns(c["max_ns"]), "0"])
    out += ["| system | code | time | p50 | p99 | p99.9 | max | allocs |", "|---|---|---|---|---|---|---|---|"]
    return out + ["| " + " | ".join(r) + " |" for r in rows]


def targets(b, models):
    """Each target's ratio from the rows' medians (what `met` judges) and from their fastest
    repetitions: on a shared machine whose speed moves between repetitions, the two ratios
    differing says a verdict rests on the noise."""
    t, fast = timed(b), fastest(b)
    out = ["", "### Targets (ratios from this run)", "",
           "`measured` is the ratio of the rows' medians, which `met` judges; `fastest` is the same ratio of "
           "their fastest repetitions.", "",
           "| target | system | measured | fastest | met |", "|---|---|---|---|---|"]

    def target(label, m, ratio, ok):
        """ratio(times) for times = t or fast; ok(value) says whether the target is met."""
        value = ratio(t)
        out.append(f"| {label} | {m} | {value:.2f}x | {ratio(fast):.2f}x | {'yes' if ok(value) else '**no**'} |")

    at_most = lambda limit: (lambda v: v <= limit)
    at_least = lambda limit: (lambda v: v >= limit)
    target("Duffing law <= 1.5x its closed form", "duffing_2x1",
           lambda x: x("law/duffing_2x1/cholesky") / x("baseline/duffing_2x1/closed_form"), at_most(1.5))
    for m in models:
        if math.isnan(t(f"law/{m}/cholesky")):
            continue  # a system with no law rows in this run (e.g. timed by the natural-form benchmarks only)
        declared = not math.isnan(t(f"law/{m}/cholesky_dense_refactor"))
        over = lambda num, den: (lambda x: x(num) / x(den))
        general = lambda x: general_time(x, m)
        kkt = f"baseline/{m}/dynamic_kkt"
        target("general (dense A, factored every call) >= 2x faster than dynamic KKT LU", m,
               lambda x: x(kkt) / general(x), at_least(2))
        if declared:
            target("declared diagonal A (factored every call) >= 4x faster than dynamic KKT LU", m,
                   over(kkt, f"law/{m}/cholesky_refactor"), at_least(4))
            target("constant A and D, factorization kept (default) >= 4x faster than dynamic KKT LU", m,
                   over(kkt, f"law/{m}/cholesky"), at_least(4))
        target("checks and diagnostics <= 1.2x the same solve without them", m,
               lambda x: general(x) / x(f"baseline/{m}/plain_fixed"), at_most(1.2))
        target("default >= 8x faster than literal fixed-size SVD", m,
               over(f"baseline/{m}/literal_fixed", f"law/{m}/cholesky"), at_least(8))
        target("default >= 15x faster than dynamic-size user code", m,
               over(f"baseline/{m}/dynamic_user", f"law/{m}/cholesky"), at_least(15))
        for s_ in ("svd", "cod"):
            target(f"rank-revealing ({s_.upper()}) <= 3x default", m, over(f"law/{m}/{s_}", f"law/{m}/cholesky"),
                   at_most(3))
        if not math.isnan(t(f"law/{m}/cholesky_held")):
            target("sampled-data hold (two evaluations: about twice) <= 2.5x default", m,
                   over(f"law/{m}/cholesky_held", f"law/{m}/cholesky"), at_most(2.5))
    return out


def general_time(t, m):
    general = t(f"law/{m}/cholesky_dense_refactor")
    return t(f"law/{m}/cholesky_refactor") if math.isnan(general) else general


def solve_split(b, models):
    t = timed(b)
    out = ["", "### Where the time goes: the model's terms and the solve", "",
           "Every row evaluates the model's terms once; `model_terms` times that alone. The solve is a row's "
           "time minus it (same run; a difference of two medians, so small ones are noisy); the baselines' "
           "solve includes copying the terms into their own matrices. The last two columns are the KKT "
           "baseline's solve over the law's.", "",
           "| system | model terms | solve: default | solve: general | solve: plain_fixed | solve: dynamic KKT "
           "| KKT / default (solve) | KKT / general (solve) |", "|---|---|---|---|---|---|---|---|"]

    def over(a, b_):  # a difference of two medians can be at or below zero: then no ratio
        return f"{a / b_:.2f}x" if a > 0 and b_ > 0 else "n/a"

    for m in models:
        terms = t(f"baseline/{m}/model_terms")
        if math.isnan(terms):
            continue
        solve = [t(f"law/{m}/cholesky") - terms, general_time(t, m) - terms, t(f"baseline/{m}/plain_fixed") - terms,
                 t(f"baseline/{m}/dynamic_kkt") - terms]
        out.append(f"| {m} | {ns(terms)} | " + " | ".join(ns(v) for v in solve)
                   + f" | {over(solve[3], solve[0])} | {over(solve[3], solve[1])} |")
    return out


def phases(b, models):
    t = timed(b)
    kernels = ("mass_cholesky", "constraint_solve", "gram", "gram_cholesky", "gram_inverse")
    phased = [m for m in models if f"phase/{m}/kkt_lu" in b]
    if not phased:
        return []
    out = ["", "### The general case's solve taken apart", "",
           "Each kernel of the refactoring path alone (`phase/*`, the law's own kernels on the benchmark "
           "states' terms, each input copied in first): Cholesky of A (N^3/3 flops), B^T = L^-1 D^T "
           "with u = L^-1 (Q - f) beside it, one substitution (N^2 (P + 1)), the Gram matrix B B^T (N P (P + 1), its lower triangle), its Cholesky (P^3/3) and the "
           "inverse factor the condition bound needs (P^3/3); with P = 1 the law takes a scalar path "
           "instead of the last two (shown as -). `rest` is the general row's solve (row less "
           "`model_terms`) less the kernels it runs: the right-hand sides and their triangular solves, the "
           "products, the checks and the residual. Beside it the KKT baseline's LU alone as a user writes "
           "it (`kkt_lu`: a `PartialPivLU<MatrixXd>` constructed on the assembled matrix, so its 3 "
           "allocations, the matrix's copy and Eigen's norm pass included; 2 (N+P)^3/3 flops) and the KKT "
           "row's solve (row less `model_terms`). The flop counts are those of dense D; above 8 "
           "coordinates the law's solve of B^T and its Gram matrix run only where D's rows can be nonzero "
           "(a chain's row touches two coordinates), so there the rates below are dense-equivalent.", "",
           "| system | " + " | ".join(kernels) + " | rest | general solve | kkt_lu | KKT solve |",
           "|---|" + "---|" * (len(kernels) + 4)]
    for m in phased:
        general, terms = general_time(t, m), t(f"baseline/{m}/model_terms")
        times = phase_times(t, m, kernels)
        out.append(f"| {m} | " + " | ".join("-" if math.isnan(times[k]) else ns(times[k]) for k in kernels)
                   + f" | {ns(times['rest'])} | {ns(general - terms)} | "
                   f"{ns(times['kkt_lu'])} | {ns(t(f'baseline/{m}/dynamic_kkt') - terms)} |")
    return out + flop_rates(t, phased, kernels)


def phase_times(t, m, kernels):
    """The time of each kernel of the general case's solve for system m (NaN where the law does not
    run it: with P = 1 a scalar path replaces the Gram Cholesky and its inverse factor), `rest` (the
    general row's solve less those kernels) and the KKT LU's."""
    scalar = m.endswith("x1")
    times = {k: (math.nan if scalar and k in ("gram_cholesky", "gram_inverse") else t(f"phase/{m}/{k}"))
             for k in kernels}
    solve = general_time(t, m) - t(f"baseline/{m}/model_terms")
    times["rest"] = solve - sum(v for v in times.values() if not math.isnan(v))
    times["kkt_lu"] = t(f"phase/{m}/kkt_lu")
    return times


def size_of(m):
    """(N, P) from a system's name, e.g. chain_16x8 -> (16, 8)."""
    n, p = m.rsplit("_", 1)[1].split("x")
    return int(n), int(p)


def kernel_flops(k, n, p):
    """Flops of one kernel of the general case's solve, as the table above counts them; `rest`: the
    right-hand sides and products (D a = B u, G^-1 on two right sides, D^T w for both parts, B^T w,
    L^-T on two columns for a and q'', the residual D q''): about 2 N^2 + 10 N P + 4 P^2."""
    return {"mass_cholesky": n ** 3 / 3, "constraint_solve": n * n * (p + 1), "gram": n * p * (p + 1),
            "gram_cholesky": p ** 3 / 3, "gram_inverse": p ** 3 / 3, "rest": 2 * n * n + 10 * n * p + 4 * p * p,
            "kkt_lu": 2 * (n + p) ** 3 / 3}[k]


def flop_rates(t, phased, kernels):
    """Each kernel's flop rate beside the KKT LU's, and where the general target is missed, the kernel
    that holds the most time (the one at fault) with its rate."""
    out = ["", "Flop rates of the same kernels (GFlop/s: the kernel's flop count over its time; `rest` from "
           "its count 2 N^2 + 10 N P + 4 P^2 over its time), beside the KKT LU's. The general case needs about "
           "half the KKT's flops (N^3/3 + N^2 P + N P^2 + 2 P^3/3 against 2 (N + P)^3/3), so it is 2x faster "
           "only where its kernels run at the LU's rate and the model's terms are small beside both.", "",
           "| system | " + " | ".join(kernels) + " | rest | kkt_lu | general / KKT (row) | kernel at fault |",
           "|---|" + "---|" * (len(kernels) + 4)]
    for m in phased:
        n, p = size_of(m)
        general, terms = general_time(t, m), t(f"baseline/{m}/model_terms")
        times = phase_times(t, m, kernels)

        def rate(k):
            v = times[k]
            return "-" if math.isnan(v) or v <= 0 else f"{kernel_flops(k, n, p) / v:.2f}"

        speedup = t(f"baseline/{m}/dynamic_kkt") / general
        fault = ""
        if speedup < 2:
            worst = max((k for k in times if k != "kkt_lu" and not math.isnan(times[k])), key=lambda k: times[k])
            fault = (f"`{worst}`: {ns(times[worst])}, {100 * times[worst] / (general - terms):.0f} % of the solve, "
                     f"{rate(worst)} GFlop/s")
        out.append(f"| {m} | " + " | ".join(rate(k) for k in kernels) + f" | {rate('rest')} | {rate('kkt_lu')} "
                   f"| {speedup:.2f}x | {fault} |")
    return out


def growth(b, models):
    t = timed(b)
    chains = sorted(((int(m.split("_")[1].split("x")[0]), m) for m in models if m.startswith("chain_")))
    if len(chains) < 3:
        return [""]
    out = ["", "### Growth with N (Duffing chains, P = N/2)", "",
           "Least-squares slope of log(time) against log(N), N = " + ", ".join(str(n) for n, _ in chains) + ":", ""]
    for code in [f"law/{{}}/{s}" for s in STRATEGIES] + [f"baseline/{{}}/{s}" for s in BASELINES[:3]]:
        xs = [math.log(n) for n, m in chains if code.format(m) in b]
        ys = [math.log(t(code.format(m))) for n, m in chains if code.format(m) in b]
        if len(xs) >= 3:
            mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
            slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
            out.append(f"- `{code.format('chain')}`: time ~ N^{slope:.2f}")
    return out + [""]


def natural_form(b):
    """Rows derived from phi (or psi) against the same rows written by hand, and the jet against
    Eigen's AutoDiffScalar."""
    t = timed(b)
    systems = sorted({k.split("/")[1] for k in b if k.startswith("natural/")})
    if not systems:
        return []
    out = ["## Constraints in their natural form", "",
           "A controller call whose rows are derived from phi against the same rows written by hand (target: "
           "within 1.5x), and the one-pass jet (D, e, e', g) against Eigen's `AutoDiffScalar` (fixed-size "
           "derivatives, nested for the second directional derivative).", "",
           "| system | derived | hand-written | derived / hand-written | met | jet | Eigen AutoDiff |",
           "|---|---|---|---|---|---|---|"]
    for m in systems:
        derived, hand = t(f"natural/{m}/derived"), t(f"natural/{m}/hand_written")
        jet, autodiff = t(f"jet/{m}/ours"), t(f"jet/{m}/eigen_autodiff")
        ratio = derived / hand
        out.append(f"| {m} | {ns(derived)} | {ns(hand)} | {ratio:.2f}x | {'yes' if ratio <= 1.5 else '**no**'} | "
                   + " | ".join("-" if math.isnan(v) else ns(v) for v in (jet, autodiff)) + " |")
    return out + [""]


def actuation(b):
    """The actuated law (K actuators, Gauss's weight) beside the plain law on the same model and a
    Lagrange-multiplier (KKT) solve of the same problem, all factoring A on every call. Target: a
    model without B (B = I) costs at most 1.05x the plain law."""
    t = timed(b)
    cases = sorted({k.split("/")[1] for k in b if k.startswith("actuation/") and k.endswith("/actuated")})
    if not cases:
        return []
    out = ["## The actuated law", "",
           "`ActuatedController` (the commands of K actuators, least u^T W u with Gauss's weight: an orthonormal "
           "basis of the actuated directions, then the task's normal equations when it is of full row rank and "
           "well conditioned, its SVD otherwise) beside `TrackingController` on the same model with every "
           "coordinate actuated, and beside the same problem solved as one dynamic-size KKT system "
           "(`dynamic_kkt_control`: least u^T W u over q'', u and the physical reactions), all factoring A on "
           "every call. `<model>_no_b`: a model that declares no B, controlled through B = I: the actuated law's "
           "plain case, eq. (32) by the plain law's own solver, with u beside B u and the rows judged one by one "
           "(target: at most 1.05x the plain law). `drive_2_of_3_no_slip`: the differential drive, its no-slip row held by the "
           "ground.", "",
           "| case | actuated | plain law, every coordinate | actuated / plain | KKT (dynamic LU) | KKT / actuated | target |",
           "|---|---|---|---|---|---|---|"]
    for c in cases:
        family = c.split("_")[0]
        laws = [k for k in b if k.startswith(f"actuation/{family}_") and k.endswith("/law")]
        actuated, law = t(f"actuation/{c}/actuated"), (t(laws[0]) if laws else math.nan)
        kkt = t(f"actuation/{c}/kkt")
        target = "-"
        if c.endswith("_no_b") and not math.isnan(law):
            target = "met (<= 1.05x)" if actuated / law <= 1.05 else "**not met** (<= 1.05x)"
        out.append(f"| {c} | {ns(actuated)} | {'-' if math.isnan(law) else ns(law)} | "
                   f"{'-' if math.isnan(law) else f'{actuated / law:.2f}x'} | "
                   f"{'-' if math.isnan(kkt) else ns(kkt)} | {'-' if math.isnan(kkt) else f'{kkt / actuated:.2f}x'} | "
                   f"{target} |")
    return out + [""]


def peer(d):
    """The law beside Simbody 3.7 (simbody_bench.json) on the same constrained motion."""
    doc = load(d, "simbody_bench.json")
    if not doc:
        return ["## A multibody peer: Simbody", "", "Not measured in this run (Simbody is not installed: "
                "`scripts/setup peer`).", ""]
    b = benchmarks(doc)
    t = timed(b)
    law, simbody, kkt = t("peer/arm/law"), t("peer/arm/simbody"), t("peer/arm/kkt")
    return ["## A multibody peer: Simbody", "",
            "The planar arm's hand on its circle built in Simbody 3.7 (three Pin mobilizers, the hand held by a "
            "holonomic `Constraint::Custom`, `bench/peer/simbody_arm.hpp`) and solved by `realize(Acceleration)` "
            "from a state whose q, u and t changed; the law (`TrackingController`, stabilization off) on the same "
            "states. Before timing, the two agree on q'' to 1e-9 at every state (`simbody_bench` exits "
            "otherwise; `tests/peer/simbody_test.cpp` holds q'' and the constraint force at up to 1,000 states, the near-singular arms left out).", "",
            "| evaluation | time | Simbody / this |", "|---|---|---|",
            f"| Simbody 3.7, realize(Acceleration) | {ns(simbody)} | 1.00x |",
            f"| the law (model terms, eq. 32, checks, q'') | {ns(law)} | {simbody / law:.1f}x |",
            f"| model terms and dynamic-size KKT LU | {ns(kkt)} | {simbody / kkt:.1f}x |", ""]


def plant_step(d):
    step = load(d, "step_cost_bench.json")
    if not step:
        return []
    b = benchmarks(step)
    out = ["## Plant step as effects are added", "",
           "1000 RK4 steps (4 right-hand-side evaluations each) of the Duffing plant with the first k effects "
           "of eq. (35) and more (`BM_PlantStep/k`); no controller.", "", "| benchmark | time |", "|---|---|"]
    return out + [f"| {k} | {ns(v[0])} |" for k, v in b.items()] + [""]


def firmware_loop(d):
    fw = load(d, "firmware_loop.json")
    if not fw:
        return []
    out = ["## Firmware-style loop", "",
           f"{fw['iterations']} iterations at a {fw['period_us']} us period: sensor read, law, actuator "
           "write (histogram in firmware_loop.txt).", "",
           "| law | p50 | p99 | p99.9 | max | wake jitter p99 | allocations | max tracking error |",
           "|---|---|---|---|---|---|---|---|"]
    for k in ("closed_form", "gausstrack"):
        r = fw[k]
        lat, jit = r["latency_ns"], r["jitter_ns"]
        out.append(f"| {k} | {ns(lat['p50'])} | {ns(lat['p99'])} | {ns(lat['p999'])} | {ns(lat['max'])} | "
                   f"{ns(jit['p99'])} | {r['allocations']} | {r['max_tracking_error']:.2e} |")
    return out + [""]


def transport(d):
    tr = load(d, "transport.json")
    loop = load(d, os.path.join("closed_loop", "summary.json"))
    out = []
    if tr:
        out += ["## Transport: round trip between two processes", "",
                f"State {tr['state_bytes']} bytes out, command {tr['command_bytes']} bytes back, "
                f"{tr['round_trips']} round trips each.", "",
                "| path | p50 | p99 | p99.9 | max |", "|---|---|---|---|---|"]
        for k, label in (("udp_us", "raw UDP loopback (floor)"), ("lcm_us", "bare LCM, real message types")):
            r = tr[k]
            out.append(f"| {label} | {r['p50']:.1f} us | {r['p99']:.1f} us | {r['p999']:.1f} us | {r['max']:.1f} us |")
        if loop:
            r = loop["round_trip_us"]
            out.append(f"| gausstrack-run closed loop, 1 kHz real time (state to command, with the law) | "
                       f"{r['p50']:.1f} us | {r['p99']:.1f} us | {r['p999']:.1f} us | {r['max']:.1f} us |")
        out.append("")
    floor = os.path.join(d, "loop_vs_floor", "README.md")
    if os.path.exists(floor):
        with open(floor) as f:
            body = f.read().split("\n", 1)[1]
        out += ["## The closed loop against the machine's floors (same run)"] + demote(body)
    def spin(name):
        """The spin of a loop_vs_floor run (its rows' spin_us), and what it means."""
        us = max((r.get("spin_us") or 0 for r in load(os.path.join(d, name), "loop_vs_floor.json") or []), default=0)
        return us, (f"the plant waking {us} us before each deadline and spinning until it (`--spin-us {us}`), so "
                    "that its period starts without waiting for the scheduler to wake it; the price is up to "
                    f"{us} us of a CPU per period (the plant's `spun_ms`). Under `--realtime` the spin also holds "
                    "off the plant's own LCM receive thread (one priority below its loop, on its CPU), and under "
                    "`realtime_1cpu` the controller: a command arriving during the spin is taken when the period "
                    "starts. The floor sleeps; the section before is the same loop without the spin. Each case is "
                    "one 5 s run: compare a case with the same case there, each beside its own floor (the floor "
                    "itself moves between runs).")
    duffing_spin, duffing_text = spin("loop_vs_floor_rk4_spin")
    chain_spin, chain_text = spin("loop_vs_floor_chain8_rk4_spin")
    sections = (("loop_vs_floor_rk4", "## The same at 10 kHz with a fixed-step plant (one RK4 step per period)",
                 "What a user running a plant in real time would choose: the Duffing scene with "
                 f"`integrator={FIXED_STEP}` instead of dopri5 at 1e-10."),
                ("loop_vs_floor_rk4_spin", f"## The same fixed-step plant spinning the last {duffing_spin} us of "
                 "each period", f"The Duffing scene with `integrator={FIXED_STEP}`, {duffing_text}"),
                ("loop_vs_floor_chain8", "## The 8-mass chain at 10 kHz", "Eight coordinates and four tracked rows, "
                 "the plant integrated by its scene's dopri5 at 1e-10 each period."),
                ("loop_vs_floor_chain8_rk4", "## The 8-mass chain at 10 kHz with a fixed-step plant (one RK4 step "
                 "per period)", f"The same scene with `integrator={FIXED_STEP}`."),
                ("loop_vs_floor_chain8_rk4_spin", f"## The 8-mass chain's fixed-step plant spinning the last "
                 f"{chain_spin} us of each period", f"The 8-mass chain with `integrator={FIXED_STEP}`, {chain_text}"))
    for name, title, intro in sections:
        path = os.path.join(d, name, "README.md")
        if os.path.exists(path):
            with open(path) as f:
                body = f.read().split("\n", 1)[1]
            out += [title, "", intro] + demote(demote(body))
    return out + demote(integration_load(d))


FIXED_STEP = "{method: rk4, step: 1.0e-4}"
# Scene, its loop runs with the scene's adaptive integrator, with one fixed RK4 step per period, and
# with that step and a spin before each deadline.
LOAD_RUNS = (("duffing_alpha4", "loop_vs_floor", "loop_vs_floor_rk4", "loop_vs_floor_rk4_spin"),
             ("duffing_chain8", "loop_vs_floor_chain8", "loop_vs_floor_chain8_rk4", "loop_vs_floor_chain8_rk4_spin"))


def integration_load(d):
    """Whether the plant's integration is the load at 10 kHz, scene by scene and integrator by
    integrator: the right-hand-side evaluations the plant's integrator made per period (the loop
    runs' summaries), times the cost of one evaluation (accuracy_vs_time's finest RK4 run of the
    scene, whose right-hand side also evaluates the law: an upper bound for the plant's alone),
    beside the plant's loop thread's CPU time per period; medians over the run's 10 kHz cases."""
    cost = rhs_cost_us(d)
    out = []
    for scene, adaptive, fixed, spinning in LOAD_RUNS:
        for name, label in ((adaptive, "dopri5 1e-10"), (fixed, "RK4, step 1e-4"), (spinning, "RK4, step 1e-4")):
            evals, loop, spun_us, spins = [], [], [], set()
            for r in load(os.path.join(d, name), "loop_vs_floor.json") or []:
                main = (r.get("loop_threads") or {}).get("plant", {}).get("main")
                summary = load(os.path.join(d, name, f"loop_{r.get('tag')}"), "summary.json")
                if "error" in r or r.get("rate_hz") != 10000 or not (main and main.get("threads")) or not summary:
                    continue
                if summary.get("states_published"):
                    evals.append(summary["rhs_evaluations"] / summary["states_published"])
                    loop.append(per_period_us(r, summary))
                    spun_us.append(1e3 * summary.get("spun_ms", 0.0) / max(r["loop_periods"], 1))
                    spins.add(summary.get("spin_us", 0))
            if evals:
                spun = ", ".join(f"{x} us spun" for x in sorted(spins) if x)
                out.append((scene, label + (f", {spun}" if spun else ""), median(evals), cost.get(scene),
                            median(loop), median(spun_us) if spun else None))
    if not out:
        return []
    lines = ["# Is the plant's integration the load?", "",
             "Per period at 10 kHz (the median over the cases above): the right-hand-side evaluations the "
             "plant's integrator made (the runs' summaries), the integration's time as those evaluations "
             "times the cost of one (the scene's RK4 at its finest step in What accuracy costs, whose "
             "right-hand side also evaluates the law: an upper bound for the plant's alone), and the "
             "plant's loop thread's CPU time (wake-up, the socket's messages, the state's publication, "
             "the integration, the sleep), less the time it spun before the deadlines where it spins, which "
             "is shown beside it (wall time from waking to the deadline: its CPU time is at most that).", "",
             "| scene | integrator | evaluations per period | integration, at most [us] | plant's loop thread, "
             "less the spin [us] | spun [us] | integration's share, at most |", "|---|---|---|---|---|---|---|"]
    verdicts = {}
    for scene, label, evals, c, loop, spun in out:
        spun_cell = "-" if spun is None else f"{spun:.1f}"
        if c is None:
            lines.append(f"| {scene} | {label} | {evals:.1f} | - | {loop:.1f} | {spun_cell} | - |")
            continue
        share = evals * c / loop if loop > 0 else math.nan
        verdicts.setdefault(scene, []).append((label, share))
        lines.append(f"| {scene} | {label} | {evals:.1f} | {evals * c:.2f} | {loop:.1f} | {spun_cell} "
                     f"| {100 * share:.0f} % |")
    lines.append("")
    for scene, shares in verdicts.items():
        worst = max(share for _, share in shares)
        verdict = ("is the load" if worst >= 0.5 else "is a large part of the load" if worst >= 0.25
                   else "is not the load: the loop's time is its messages and its timer")
        lines.append(f"- {scene}: the integration {verdict} (at most {100 * worst:.0f} % of the plant's loop "
                     "thread with any of its integrators).")
    return lines + [""]


def rhs_cost_us(d):
    """Per scene, the cost of one right-hand-side evaluation [us]: its RK4 run with the most
    evaluations in accuracy_vs_time's integrators.csv (wall time over evaluations)."""
    path = os.path.join(d, "accuracy_vs_time", "integrators.csv")
    if not os.path.exists(path):
        return {}
    best = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            if row["method"] == "rk4" and int(row["rhs_evaluations"]) > best.get(row["scene"], (0, 0))[0]:
                best[row["scene"]] = (int(row["rhs_evaluations"]), float(row["wall_s"]))
    return {scene: 1e6 * wall / evals for scene, (evals, wall) in best.items()}


def per_period_us(r, summary):
    """The plant's loop thread's CPU time per period [us] of one loop_vs_floor row, less the time it
    spun before its deadlines (--spin-us; the run's summary). spun_ms is wall time, at least the
    spin's CPU time, so the figure is at most the loop's CPU time outside the spin (never below 0)."""
    cpu_ms = max(r["loop_threads"]["plant"]["main"]["cpu_ms"] - summary.get("spun_ms", 0.0), 0.0)
    return 1e3 * cpu_ms / max(r["loop_periods"], 1)


def authentication(d):
    doc = load(d, "auth_bench.json")
    if not doc:
        return []
    b = benchmarks(doc)
    t = {k: v[0] for k, v in b.items()}
    out = ["## Message authentication per message", "",
           "What a receiver does with one message (`auth_bench`): the decode alone (the work before "
           "authentication), and with the keyed BLAKE2b verification in front; what refusing costs; the "
           "sender's seal.", "", "| step | time | beside the decode alone |", "|---|---|---|"]
    for kind in ("command", "state"):
        dec, ver = t.get(f"BM_Decode/{kind}"), t.get(f"BM_VerifyAndDecode/{kind}")
        if dec and ver:
            out.append(f"| {kind}: decode alone | {ns(dec)} | 1 |")
            out.append(f"| {kind}: verify and decode | {ns(ver)} | {ver / dec:.1f}x |")
    for name, label in (("BM_RefuseGarbage", "refuse bytes without a trailer"),
                        ("BM_RefuseForged", "refuse a forged trailer (whole hash)"), ("BM_Seal", "seal a command")):
        if name in t:
            out.append(f"| {label} | {ns(t[name])} | |")
    forged = t.get("BM_RefuseForged")
    if forged:
        out += ["", f"At {ns(forged)} per forged message one core refuses about {1e9 / forged / 1e3:.0f} thousand "
                "per second; garbage costs less."]
    return out + [""]


def main(d, page=None):
    out = ["# Benchmarks", "", "Written by `scripts/bench`; every figure in a table comes from one run on the machine "
           "that ran it, baselines included.", ""]
    out += control_law(d) + peer(d) + plant_step(d) + firmware_loop(d) + transport(d) + authentication(d) + studies(d)
    with open(os.path.join(d, "README.md"), "w") as f:
        f.write("\n".join(out) + "\n")
    print(os.path.join(d, "README.md"))
    return update_doc(page, out[2:]) if page else 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dir")
    parser.add_argument("--doc", metavar="PAGE.md")
    args = parser.parse_args()
    sys.exit(main(args.dir, args.doc))
