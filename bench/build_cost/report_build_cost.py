#!/usr/bin/env python3
"""Table of scripts/build-cost's log: one line per compiler run (CPU seconds, peak KB, object),
heaviest first, with the totals and the compile-budget targets met or not."""
import argparse
import sys

TARGETS = {  # (CPU seconds, peak MB)
    "user model": (5.0, 400.0),
    "heaviest": (60.0, 1536.0),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("log")
    ap.add_argument("--wall", type=int, default=0, help="wall seconds of the whole build")
    ap.add_argument("--markdown", help="also write the table to this file")
    args = ap.parse_args()
    rows = []
    with open(args.log) as f:
        for line in f:
            parts = line.split(maxsplit=2)
            if len(parts) == 3:
                rows.append((float(parts[0]), int(parts[1]) / 1024.0, parts[2].strip()))
    if not rows:
        sys.exit("no compiler runs recorded")
    probes = [r for r in rows if r[2].startswith("bench/build_cost/")]
    build = [r for r in rows if not r[2].startswith("bench/build_cost/")]
    build.sort(key=lambda r: -r[0])
    lines = []
    lines.append("| CPU s | peak MB | translation unit |")
    lines.append("|---:|---:|---|")
    for cpu, mb, obj in build:
        lines.append(f"| {cpu:.1f} | {mb:.0f} | `{obj}` |")
    total = sum(r[0] for r in build)
    heavy = build[0]
    summary = [
        f"- {len(build)} compiler runs, {total / 60:.1f} CPU minutes in all"
        + (f", {args.wall / 60:.1f} minutes of wall time at -j2" if args.wall else ""),
        f"- heaviest: `{heavy[2]}` {heavy[0]:.1f} s, {max(r[1] for r in build):.0f} MB peak (largest of any unit)",
    ]
    ok_all = True
    cpu_t, mb_t = TARGETS["heaviest"]
    ok = heavy[0] <= cpu_t and max(r[1] for r in build) <= mb_t
    ok_all &= ok
    summary.append(f"- target heaviest unit <= {cpu_t:.0f} s and <= {mb_t / 1024:.1f} GB: {'met' if ok else 'NOT met'}")
    cpu_t, mb_t = TARGETS["user model"]
    for cpu, mb, obj in probes:
        ok = cpu <= cpu_t and mb <= mb_t
        ok_all &= ok
        name = obj.split("/")[-1].removesuffix(".cpp")
        summary.append(f"- user model `{name}`: {cpu:.1f} s, {mb:.0f} MB (target <= {cpu_t:.0f} s, <= {mb_t:.0f} MB: "
                       f"{'met' if ok else 'NOT met'})")
    text = "\n".join(summary) + "\n\n" + "\n".join(lines) + "\n"
    print(text)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(text)
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
