#!/usr/bin/python3
"""Worst-case stack of one control call, from GCC's -fcallgraph-info=su files: the largest sum of
frame sizes along any call path from the function whose name contains ROOT. Functions outside
the compiled sources (newlib's sinf, expf, ...) have no frame size in the graph; they are listed,
and each path through one adds EXTERNAL bytes (the caller passes an allowance it states).
usage: stack_bound.py ROOT EXTERNAL FILE.ci... ; prints "static_bound BYTES" and the path.
Exits 1 on recursion or a dynamic frame (no static bound)."""
import re
import sys


def main():
    root_pattern, external = sys.argv[1], int(sys.argv[2])
    frames, labels, edges = {}, {}, {}
    for path in sys.argv[3:]:
        text = open(path).read()
        for m in re.finditer(r'node: \{ title: "([^"]+)" label: "((?:[^"\\]|\\.)*)"', text):
            title, label = m.group(1), m.group(2)
            labels[title] = label.split("\\n")[0]
            size = re.search(r"\\n(\d+) bytes \(([a-z,]+)\)", label)
            if size:
                if size.group(2) != "static":
                    sys.exit(f"no static bound: {labels[title]} has a {size.group(2)} frame")
                frames[title] = int(size.group(1))
        for m in re.finditer(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"', text):
            edges.setdefault(m.group(1), []).append(m.group(2))
    # Calls across files resolve by symbol name (the part after the last ':').
    by_symbol = {}
    for title in list(frames) + list(labels):
        by_symbol.setdefault(title.rsplit(":", 1)[-1], title)
    roots = [t for t, l in labels.items() if root_pattern in l and t in frames]
    if not roots:
        sys.exit(f"no function matching {root_pattern!r}")
    externals = set()
    memo, active = {}, set()

    def worst(node):
        node = by_symbol.get(node.rsplit(":", 1)[-1], node)
        if node in memo:
            return memo[node]
        if node in active:
            sys.exit(f"recursion through {labels.get(node, node)}: no static bound")
        if node not in frames:
            externals.add(labels.get(node, node.rsplit(":", 1)[-1]))
            return external, [node.rsplit(":", 1)[-1] + " (external)"]
        active.add(node)
        best, best_path = 0, []
        for callee in edges.get(node, []):
            depth, path = worst(callee)
            if depth > best:
                best, best_path = depth, path
        active.discard(node)
        memo[node] = (frames[node] + best, [labels[node][:100] + f" [{frames[node]} B]"] + best_path)
        return memo[node]

    depth, path = max(worst(r) for r in roots)
    print(f"static_bound {depth}")
    for p in path:
        print(f"  {p}")
    if externals:
        print("  external functions (each counted as %d B): %s" % (external, ", ".join(sorted(externals))))


if __name__ == "__main__":
    main()
