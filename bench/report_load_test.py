#!/usr/bin/python3
"""report_bench.integration_load on made-up loop runs: per-period CPU time from the plant's loop
thread, the pairing of each scene's adaptive and fixed-step runs case by case (a case without
its pair, or at another rate, is left out), the misses and errors beside them, the median
difference per scene and the integrators' offline errors from integrators.csv."""
import importlib.util
import json
import os
import sys
import tempfile

spec = importlib.util.spec_from_file_location("report_bench", os.path.join(os.path.dirname(__file__), "report_bench.py"))
report = importlib.util.module_from_spec(spec)
spec.loader.exec_module(report)


def row(sched, hog, cpu_ms, misses, error, rate=10000.0, periods=50000):
    return {"tag": f"{rate:g}_{sched}", "rate_hz": rate, "scheduler": sched, "hog": hog, "loop_periods": periods,
            "loop_misses": misses, "loop_max_error": error,
            "loop_threads": {"plant": {"main": {"cpu_ms": cpu_ms, "threads": 1}}}}


def write(d, name, rows):
    os.makedirs(os.path.join(d, name))
    with open(os.path.join(d, name, "loop_vs_floor.json"), "w") as f:
        json.dump(rows, f)


failures = []


def check(condition, what):
    if not condition:
        failures.append(what)


with tempfile.TemporaryDirectory() as d:
    # Duffing: two cases paired, one only in the adaptive run, one at 1 kHz.
    write(d, "loop_vs_floor", [row("realtime", False, 1500.0, 200, 1.3e-5), row("default", True, 1750.0, 3000, 1e-4),
                               row("realtime_1cpu", False, 1400.0, 100, 1e-5),
                               row("realtime", False, 500.0, 4, 1e-5, rate=1000.0, periods=5000)])
    write(d, "loop_vs_floor_rk4", [row("realtime", False, 1600.0, 210, 5e-6), row("default", True, 1500.0, 2600, 6e-5),
                                   row("realtime", False, 450.0, 3, 1e-5, rate=1000.0, periods=5000)])
    # The chain: three cases, 1 CPU saturated with dopri5.
    write(d, "loop_vs_floor_chain8", [row("realtime_1cpu", False, 2000.0, 7383, 1.9e-2),
                                      row("realtime", False, 1750.0, 350, 1.3e-6),
                                      row("realtime", True, 1900.0, 400, 2e-6)])
    write(d, "loop_vs_floor_chain8_rk4", [row("realtime_1cpu", False, 1500.0, 95, 1.4e-6),
                                          row("realtime", False, 1800.0, 440, 2.3e-6),
                                          row("realtime", True, 1600.0, 300, 2e-6)])
    os.makedirs(os.path.join(d, "accuracy_vs_time"))
    with open(os.path.join(d, "accuracy_vs_time", "integrators.csv"), "w") as f:
        f.write("scene,method,setting,rhs_evaluations,wall_s,max_error,final_error\n"
                "duffing_chain8,rk4,0.001,1,1,4.2e-11,1\nduffing_chain8,rk4,0.0001,1,1,2.8e-13,1\n"
                "duffing_chain8,dopri5,1e-09,1,1,1.8e-09,1\nduffing_chain8,dopri5,1e-10,1,1,1.8e-10,1\n"
                "duffing_alpha4,rk4,0.0001,1,1,1.2e-12,1\n")
    text = "\n".join(report.integration_load(d))

lines = text.split("\n")
table = [l for l in lines if l.startswith("| duffing")]
check(len(table) == 5, f"5 paired 10 kHz cases expected, got {len(table)}:\n{text}")
# 1500 ms over 50000 periods is 30.0 us a period; 1600 ms 32.0 us.
check("| duffing_alpha4 | realtime | quiet | 30.0 | 32.0 | -2.0 | 200 / 210 | 1.3e-05 / 5.0e-06 |" in table,
      "the Duffing realtime row")
check("| duffing_alpha4 | default | 1 hog | 35.0 | 30.0 | +5.0 | 3000 / 2600 | 1.0e-04 / 6.0e-05 |" in table,
      "the Duffing default row with a hog")
check(not any("realtime_1cpu" in l and "alpha4" in l for l in table), "a case without its pair is left out")
check("| duffing_chain8 | realtime_1cpu | quiet | 40.0 | 30.0 | +10.0 | 7383 / 95 | 1.9e-02 / 1.4e-06 |" in table,
      "the chain's one-CPU row")
# Chain differences: +10.0, -1.0, +6.0 -> median +6.0; Duffing: -2.0, +5.0 -> median +1.5.
chain = [l for l in lines if l.startswith("- duffing_chain8")]
check(len(chain) == 1 and "+6.0 us" in chain[0], f"the chain's median difference: {chain}")
check(len(chain) == 1 and "1.80e-10" in chain[0] and "2.80e-13" in chain[0], f"the chain's offline errors: {chain}")
duffing = [l for l in lines if l.startswith("- duffing_alpha4")]
check(len(duffing) == 1 and "+1.5 us" in duffing[0], f"the Duffing median difference: {duffing}")
check(len(duffing) == 1 and "offline" not in duffing[0], "no offline errors without both integrators' rows")

with tempfile.TemporaryDirectory() as d:
    check(report.integration_load(d) == [], "no runs, no table")

if failures:
    print("report_load_test: FAILED\n" + "\n".join(failures))
    sys.exit(1)
print("report_load_test: ok")
