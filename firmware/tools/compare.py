#!/usr/bin/python3
"""Compares the target's trajectory with the host's double-precision run of the same loop.
usage: compare.py TARGET.bin TARGET_BYTES_PER_VALUE(4|8) HOST.bin N
Each row is t, q (N), q' (N), u (N). The bound is stated before the run, from rounding alone:
each of the 10^4 RK4 steps rounds the state by at most a few eps |x| (eps of the target's
scalar), and the stabilized tracking direction forgets its errors (time constant 1/omega = 50
ms) while the free direction of these lightly damped systems does not; if every step's rounding
added up, the state would differ by steps * eps * max|x|. Allowed: twice that, in q and in q'.
The control force is reported beside it (it follows the state). Prints the figures and exits 1
when a bound is not met or the files disagree in length."""
import array
import sys


def read(path, width):
    a = array.array("f" if width == 4 else "d")
    with open(path, "rb") as f:
        a.frombytes(f.read())
    return a


def main():
    target, width, host, n = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    eps = 2.0 ** -23 if width == 4 else 2.0 ** -52
    a, b = read(target, width), read(host, 8)
    cols = 1 + 3 * n
    if len(a) != len(b) or len(a) % cols:
        sys.exit(f"length mismatch: target {len(a)} values, host {len(b)}")
    rows = len(a) // cols
    worst = {"q": 0.0, "qd": 0.0, "u": 0.0}
    scale = {"q": 0.0, "qd": 0.0, "u": 0.0}
    for r in range(rows):
        for name, first in (("q", 1), ("qd", 1 + n), ("u", 1 + 2 * n)):
            for i in range(first, first + n):
                x, y = a[r * cols + i], b[r * cols + i]
                d = abs(x - y)
                worst[name] = max(worst[name], d if d == d else float("inf"))  # NaN: the worst
                scale[name] = max(scale[name], abs(y))
    ok = True
    for name in ("q", "qd"):
        bound = 2 * rows * eps * scale[name]
        met = worst[name] <= bound
        ok &= met
        print(f"{name}_max_difference {worst[name]:.3g} bound {bound:.3g} ({'met' if met else 'NOT MET'})")
    print(f"u_max_difference {worst['u']:.3g} (force scale {scale['u']:.3g})")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
