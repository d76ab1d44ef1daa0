#!/usr/bin/python3
"""report_bench's targets on a made-up Google Benchmark output with repetitions: each ratio from
the rows' medians (what the verdict judges) and from their fastest repetitions, beside it."""
import importlib.util
import os
import sys

spec = importlib.util.spec_from_file_location("report_bench", os.path.join(os.path.dirname(__file__), "report_bench.py"))
report = importlib.util.module_from_spec(spec)
spec.loader.exec_module(report)


def rows(name, times_ns):
    """A benchmark's repetitions (in microseconds, as a row may report them) and its median aggregate."""
    reps = [{"name": name, "run_name": name, "run_type": "iteration", "real_time": t / 1e3, "time_unit": "us"}
            for t in times_ns]
    ordered = sorted(times_ns)
    median = {"name": name + "_median", "run_name": name, "run_type": "aggregate", "aggregate_name": "median",
              "real_time": ordered[len(ordered) // 2] / 1e3, "time_unit": "us"}
    return reps + [median]


# duffing_2x1 declares a diagonal A (its general case is cholesky_dense_refactor); dense_2x1
# declares a dense one (its general case is cholesky_refactor).
doc = {"benchmarks": rows("law/duffing_2x1/cholesky", [30, 60, 45]) +                # median 45, fastest 30
                     rows("baseline/duffing_2x1/closed_form", [25, 20, 30]) +        # median 25, fastest 20
                     rows("law/duffing_2x1/cholesky_refactor", [45, 50, 40]) +       # median 45, fastest 40
                     rows("law/duffing_2x1/cholesky_dense_refactor", [55, 50, 60]) +  # median 55, fastest 50
                     rows("law/duffing_2x1/cholesky_held", [90, 80, 100]) +          # median 90, fastest 80
                     rows("baseline/duffing_2x1/dynamic_kkt", [100, 80, 120]) +      # median 100, fastest 80
                     rows("law/dense_2x1/cholesky", [40, 40, 40]) +
                     rows("law/dense_2x1/cholesky_refactor", [45, 50, 40]) +
                     rows("baseline/dense_2x1/dynamic_kkt", [100, 80, 120])}
b = report.benchmarks(doc)
lines = report.targets(b, ["duffing_2x1", "dense_2x1"])

failures = []


def expect_row(label, system, measured, fastest, met):
    row = next((l for l in lines if l.startswith(f"| {label} | {system} |")), None)
    want = f"| {label} | {system} | {measured} | {fastest} | {met} |"
    if row != want:
        failures.append(f"expected {want!r}, got {row!r}")


general = "general (dense A, factored every call) >= 2x faster than dynamic KKT LU"
expect_row("Duffing law <= 1.5x its closed form", "duffing_2x1", "1.80x", "1.50x", "**no**")
expect_row(general, "duffing_2x1", "1.82x", "1.60x", "**no**")
expect_row("declared diagonal A (factored every call) >= 4x faster than dynamic KKT LU", "duffing_2x1", "2.22x",
           "2.00x", "**no**")
expect_row("sampled-data hold (two evaluations: about twice) <= 2.5x default", "duffing_2x1", "2.00x", "2.67x", "yes")
expect_row(general, "dense_2x1", "2.22x", "2.00x", "yes")
if any(l.startswith("| declared diagonal") and "| dense_2x1 |" in l for l in lines):
    failures.append("a declared-diagonal target for a model declared dense")
median, fastest = b["law/duffing_2x1/cholesky"][0], b["law/duffing_2x1/cholesky"][1]["min_time_ns"]
if abs(median - 45) > 1e-9 or abs(fastest - 30) > 1e-9:
    failures.append(f"benchmarks(): {b['law/duffing_2x1/cholesky']}")
for f in failures:
    print(f, file=sys.stderr)
sys.exit(1 if failures else 0)
