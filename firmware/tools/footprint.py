#!/usr/bin/python3
"""The footprint table of the firmware images: reads DIR/*.json (written by run_image.sh) and
prints a Markdown table per target, each law beside the closed-form Duffing force of the same
build. Exits 1 if an image's figures are missing."""
import glob
import json
import os
import sys

TARGETS = {"m4": "Cortex-M4F (float, mps2-an386)", "m7": "Cortex-M7 (double, mps2-an500)"}
LAWS = ("duffing", "duffing_held", "arm", "arm_held", "cart_pole", "arm_passive_wrist", "differential_drive", "closed_form")


def main():
    d = sys.argv[1]
    runs = {}
    for path in glob.glob(os.path.join(d, "*.json")):
        r = json.load(open(path))
        runs[(r["target"], r["law"])] = r
    missing = [f"{t}_{l}" for t in TARGETS for l in LAWS if (t, l) not in runs]
    if missing:
        sys.exit("missing: " + ", ".join(missing))
    print("| target | law | flash | RAM | law's state | stack (measured / bound) | instructions per call (mean / max) | x closed form | tracking error | float vs double, max dq |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for t, title in TARGETS.items():
        floor = runs[(t, "closed_form")]["instructions_per_call"]["mean"]
        for l in LAWS:
            r = runs[(t, l)]
            ipc = r["instructions_per_call"]
            print(f"| {title} | {l} | {r['flash_bytes']} B | {r['ram_bytes']} B | {r['law_state_bytes']} B | "
                  f"{r['stack_measured_bytes']} / {r['stack_bound_bytes']} B | {ipc['mean']} / {ipc['max']} | "
                  f"{ipc['mean'] / floor:.1f}x | {r['max_tracking_error_m']:.2e} m | {r['q_max_difference']:.2e} |")


if __name__ == "__main__":
    main()
