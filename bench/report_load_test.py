#!/usr/bin/python3
"""report_bench.integration_load on made-up loop runs: the evaluations per period from each run's
summary, the cost of one evaluation from the scene's RK4 run with the most evaluations, the
plant's loop thread's CPU time per period less the time it spun (the summary's spun_ms), medians
over the 10 kHz cases (a 1 kHz case and a case that failed left out), and the verdict per scene."""
import importlib.util
import json
import os
import sys
import tempfile

spec = importlib.util.spec_from_file_location("report_bench", os.path.join(os.path.dirname(__file__), "report_bench.py"))
report = importlib.util.module_from_spec(spec)
spec.loader.exec_module(report)


def write(d, name, cases, spin=None):
    """cases: (tag, rate, cpu_ms of the plant's loop thread, periods, rhs_evaluations, states_published);
    spin: the summaries' (spin_us, spun_ms), if the plant spun."""
    rows = []
    for tag, rate, cpu_ms, periods, evals, states in cases:
        rows.append({"tag": tag, "rate_hz": rate, "scheduler": "realtime", "hog": False, "loop_periods": periods,
                     "loop_threads": {"plant": {"main": {"cpu_ms": cpu_ms, "threads": 1}}}})
        os.makedirs(os.path.join(d, name, f"loop_{tag}"))
        with open(os.path.join(d, name, f"loop_{tag}", "summary.json"), "w") as f:
            json.dump({"rhs_evaluations": evals, "states_published": states}
                      | ({"spin_us": spin[0], "spun_ms": spin[1]} if spin else {}), f)
    rows.append({"tag": "failed", "rate_hz": 10000.0, "error": "gausstrack-run exited 1"})
    os.makedirs(os.path.join(d, name), exist_ok=True)
    with open(os.path.join(d, name, "loop_vs_floor.json"), "w") as f:
        json.dump(rows, f)


failures = []


def check(condition, what):
    if not condition:
        failures.append(what)


with tempfile.TemporaryDirectory() as d:
    # Duffing, dopri5: three 10 kHz cases (loop thread 30, 40, 35 us a period: median 35.0; 7, 7, 8
    # evaluations a period: median 7.0) and a 1 kHz case that must not count.
    write(d, "loop_vs_floor", [("a", 10000.0, 1500.0, 50000, 350000, 50000), ("b", 10000.0, 2000.0, 50000, 350000, 50000),
                               ("c", 10000.0, 1750.0, 50000, 400000, 50000), ("k", 1000.0, 900.0, 5000, 1, 5000)])
    # RK4: 800 ms over 50,000 periods is 16 us a period; 200,000 evaluations over the 40,000 states
    # published (the summary's count, not the periods') are 5 a period.
    write(d, "loop_vs_floor_rk4", [("a", 10000.0, 800.0, 50000, 200000, 40000)])
    # The same with a 30 us spin: 800 ms, 500 ms of them spun, is 6 us a period (and 10 us spun).
    write(d, "loop_vs_floor_rk4_spin", [("a", 10000.0, 800.0, 50000, 200000, 40000)], spin=(30, 500.0))
    # The chain, dopri5 only: 400 evaluations a period at 0.2 us each (80 us) against a 100 us thread.
    write(d, "loop_vs_floor_chain8", [("a", 10000.0, 5000.0, 50000, 20000000, 50000)])
    os.makedirs(os.path.join(d, "accuracy_vs_time"))
    with open(os.path.join(d, "accuracy_vs_time", "integrators.csv"), "w") as f:
        f.write("scene,method,setting,rhs_evaluations,wall_s,max_error,final_error\n"
                "duffing_alpha4,rk4,0.001,40000,0.5,1,1\n"          # 12.5 us each: not the finest
                "duffing_alpha4,rk4,1e-05,4000000,0.4,1,1\n"        # 0.1 us each
                "duffing_alpha4,dopri5,1e-10,100000000,1.0,1,1\n"   # not RK4
                "duffing_chain8,rk4,1e-05,2000000,0.4,1,1\n")       # 0.2 us each
    lines = report.integration_load(d)

table = [l for l in lines if l.startswith("| duffing")]
check(len(table) == 4, f"four scene-integrator rows expected:\n" + "\n".join(lines))
check("| duffing_alpha4 | dopri5 1e-10 | 7.0 | 0.70 | 35.0 | - | 2 % |" in table, "Duffing, dopri5: " + str(table))
check("| duffing_alpha4 | RK4, step 1e-4 | 5.0 | 0.50 | 16.0 | - | 3 % |" in table, "Duffing, RK4: " + str(table))
check("| duffing_alpha4 | RK4, step 1e-4, 30 us spun | 5.0 | 0.50 | 6.0 | 10.0 | 8 % |" in table,
      "Duffing, RK4 spinning: " + str(table))
check("| duffing_chain8 | dopri5 1e-10 | 400.0 | 80.00 | 100.0 | - | 80 % |" in table, "chain, dopri5: " + str(table))
verdict = {l.split(":")[0]: l for l in lines if l.startswith("- ")}
check("is not the load" in verdict.get("- duffing_alpha4", ""), f"Duffing's verdict: {verdict}")
check("is the load" in verdict.get("- duffing_chain8", "") and "not" not in verdict.get("- duffing_chain8", ""),
      f"the chain's verdict: {verdict}")

with tempfile.TemporaryDirectory() as d:
    check(report.integration_load(d) == [], "no runs, no table")

if failures:
    print("report_load_test: FAILED\n" + "\n".join(failures))
    sys.exit(1)
print("report_load_test: ok")
