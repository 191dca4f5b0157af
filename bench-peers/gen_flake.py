#!/usr/bin/env python3
"""Tiny SPD-style sphereflake ("balls") generator, for testing the peer scripts.

usage: gen_flake.py LEVEL [-o OUT.nff]

Writes the view, background, lights, fills and ground polygon of SPD balls (as in
SPD's balls2.nff) and (9^(LEVEL+1) - 1)/8 spheres: a root of radius 0.5 at the origin; each
sphere of radius r at centre c, reached from its parent along unit direction d, has 9 children of radius r/3
at c + (r + r/3) * R(d) b_k, where R(d) is the smallest rotation taking +z to d (+z itself for the root) and
b_k are, for k = 0, 1, 2: one direction at elevation asin(sqrt(2/3)) and azimuth 45 + 120k degrees, then two
at elevation 0 and azimuths 15 + 120k and 75 + 120k. Spheres are written in pre-order (a sphere, then each
child's subtree). Written from an inspection of balls2.nff: levels 1 and 2 reproduce that file to its
6 printed digits; deeper levels follow the same rule but are not checked against SPD's own output.
"""
import argparse
import math
import os
import sys

HEADER = """b 0.078 0.361 0.753
v
from 2.1 1.3 1.7
at 0 0 0
up 0 0 1
angle 45
hither 0.01
resolution 512 512
l 4 3 2
l 1 -4 4
l -3 1 5
f 1 0.75 0.33 0.8 0 100000 0 1
p 4
12 12 -0.5
-12 12 -0.5
-12 -12 -0.5
12 -12 -0.5
f 1 0.9 0.7 0.5 0.5 3.0827 0 1
"""


def base_dirs():
    e = math.asin(math.sqrt(2.0 / 3.0))
    out = []
    for k in range(3):
        for az, el in ((45 + 120 * k, e), (15 + 120 * k, 0.0), (75 + 120 * k, 0.0)):
            a = math.radians(az)
            out.append((math.cos(el) * math.cos(a), math.cos(el) * math.sin(a), math.sin(el)))
    return out


def rotate_z_to(d, v):
    """Apply the smallest rotation taking +z to unit d, to vector v (Rodrigues)."""
    ax, ay = -d[1], d[0]  # z x d
    s2 = ax * ax + ay * ay
    c = d[2]
    if s2 < 1e-30:
        return v if c > 0 else (v[0], -v[1], -v[2])
    k = (1.0 - c) / s2
    # R = I + [a]x + k [a]x^2 with a = (ax, ay, 0)
    x, y, z = v
    cx = ay * z            # a x v
    cy = -ax * z
    cz = ax * y - ay * x
    ccx = ay * cz          # a x (a x v)
    ccy = -ax * cz
    ccz = ax * cy - ay * cx
    return (x + cx + k * ccx, y + cy + k * ccy, z + cz + k * ccz)


def flake(level, out):
    base = base_dirs()
    count = 0

    def emit(c, r, d, depth):
        nonlocal count
        out.write(f"s {c[0]:.6g} {c[1]:.6g} {c[2]:.6g} {r:.6g}\n")
        count += 1
        if depth == 0:
            return
        rc = r / 3.0
        for b in base:
            dd = rotate_z_to(d, b)
            cc = (c[0] + (r + rc) * dd[0], c[1] + (r + rc) * dd[1], c[2] + (r + rc) * dd[2])
            emit(cc, rc, dd, depth - 1)

    out.write(HEADER)
    emit((0.0, 0.0, 0.0), 0.5, (0.0, 0.0, 1.0), level)
    return count


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("level", type=int)
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    if not 0 <= a.level <= 7:
        sys.exit("gen_flake: level must be in 0..7")
    sys.setrecursionlimit(100)
    if a.output:
        os.makedirs(os.path.dirname(a.output) or ".", exist_ok=True)
        with open(a.output, "w") as f:
            n = flake(a.level, f)
    else:
        n = flake(a.level, sys.stdout)
    print(f"gen_flake: level {a.level}: {n} spheres", file=sys.stderr)


if __name__ == "__main__":
    main()
