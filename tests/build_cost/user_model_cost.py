#!/usr/bin/env python3
"""A user's model translation unit stays within its compile-memory budget (docs/build_cost.md).

Compiles the two user-model probes of bench/build_cost (a 2 x 1 model and the 3-link arm, one
compute() each) alone, and fails when the compiler's peak memory exceeds the user-model budget
(bench/build_cost/report_build_cost.py's TARGETS). Peak memory is a property of the code and the
compiler, the same from run to run within a few MB, so it is checked; CPU time depends on the
machine and is only printed. scripts/build-cost compiles the probes with this script too
(--log appends each compile to its log; --record-only never fails).

    user_model_cost.py CXX SOURCE_DIR EIGEN_INCLUDE_DIR WORK_DIR [--budget-mb MB] [--log FILE]
                       [--record-only]
"""
import argparse
import os
import resource
import subprocess
import sys
import time

PROBES = ("model_2x1", "model_arm")


def compile_probe(cxx, source_dir, eigen, work, probe):
    """Compiles one probe in a child process; returns (peak MB, CPU s, exit status, stderr)."""
    out = os.path.join(work, probe + ".o")
    command = [cxx, "-std=c++20", "-O2", "-DNDEBUG",
               "-I" + os.path.join(source_dir, "controller", "include"),
               "-I" + os.path.join(source_dir, "examples", "my_first_model"),
               "-isystem", eigen, "-c", os.path.join(source_dir, "bench", "build_cost", probe + ".cpp"),
               "-o", out]
    # A fresh child per probe that measures its own descendants (the driver, cc1plus, as): the
    # rusage of reaped children is the maximum over every child this process has waited for, so
    # each probe runs under its own measuring process.
    measure = (
        "import resource, subprocess, sys\n"
        "r = subprocess.run(sys.argv[1:], stderr=subprocess.PIPE, text=True)\n"
        "u = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
        "print(u.ru_maxrss, u.ru_utime + u.ru_stime, r.returncode)\n"
        "sys.stderr.write(r.stderr)\n")
    done = subprocess.run([sys.executable, "-c", measure] + command, capture_output=True, text=True)
    if done.returncode != 0 or not done.stdout.strip():
        return None, None, done.returncode or 1, done.stderr
    kb, cpu, status = done.stdout.split()
    return int(kb) / 1024.0, float(cpu), int(status), done.stderr


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("cxx")
    parser.add_argument("source_dir")
    parser.add_argument("eigen_include")
    parser.add_argument("work_dir")
    parser.add_argument("--budget-mb", type=float, help="default: the user-model target of report_build_cost.py")
    parser.add_argument("--log", help="append 'CPU_S PEAK_KB SOURCE' per probe (scripts/build-cost's log)")
    parser.add_argument("--record-only", action="store_true", help="report, but do not fail on the budget")
    args = parser.parse_args()
    if args.budget_mb is None:
        sys.path.insert(0, os.path.join(args.source_dir, "bench", "build_cost"))
        from report_build_cost import TARGETS
        args.budget_mb = TARGETS["user model"][1]
    os.makedirs(args.work_dir, exist_ok=True)
    failures, over = [], []
    for probe in PROBES:
        start = time.monotonic()
        mb, cpu, status, stderr = compile_probe(args.cxx, args.source_dir, args.eigen_include, args.work_dir, probe)
        if status != 0:
            failures.append(f"{probe}: the compiler failed (status {status}):\n{stderr}")
            continue
        if args.log:
            with open(args.log, "a") as log:
                log.write(f"{cpu:.2f} {round(mb * 1024)} bench/build_cost/{probe}.cpp\n")
        verdict = "within" if mb <= args.budget_mb else "ABOVE"
        print(f"{probe}: peak {mb:.0f} MB ({verdict} the {args.budget_mb:.0f} MB budget), "
              f"{cpu:.1f} s of CPU, {time.monotonic() - start:.1f} s of wall time")
        if mb > args.budget_mb:
            over.append(f"{probe}: peak compile memory {mb:.0f} MB is above the user-model budget of "
                        f"{args.budget_mb:.0f} MB (docs/build_cost.md)")
    for failure in failures + over:
        print("FAIL " + failure, file=sys.stderr)
    return 1 if failures or (over and not args.record_only) else 0


if __name__ == "__main__":
    sys.exit(main())
