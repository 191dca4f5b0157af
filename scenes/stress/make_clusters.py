#!/usr/bin/env python3
"""Writes cluster-10.toml, cluster-1e4.toml, cluster-1e5.toml and cluster-1e6.toml: one cluster of 24
near-touching mirror spheres (radii 0.25-1, gaps 0.01-0.05 between touching neighbours, at least 0.01
between any two) placed D = 10, 1e4, 1e5, 1e6 from the eye along (0.48, 0.6, 0.64), the same cluster in
each, filling the view. Every coordinate is an exact decimal: local offsets have 6 decimals, D * direction
is exact, so the f64 twin reads each centre to within an f64 ulp of the same relative layout."""
import math
import random
from decimal import Decimal as Dec

EYE = (Dec("3.25"), Dec("1.75"), Dec("-2.5"))
DIR = (Dec("0.48"), Dec("0.6"), Dec("0.64"))
COUNT = 24


def layout(seed=20261127):
    rng = random.Random(seed)
    spheres = [((Dec(0), Dec(0), Dec(0)), Dec("1.0"))]
    while len(spheres) < COUNT:
        r = Dec(rng.uniform(0.25, 1.0)).quantize(Dec("0.001"))
        (cj, rj) = rng.choice(spheres)
        gap = rng.uniform(0.012, 0.048)
        while True:
            v = [rng.gauss(0, 1) for _ in range(3)]
            n = math.sqrt(sum(x * x for x in v))
            if n > 1e-3:
                break
        dist = float(rj + r) + gap
        c = tuple((cj[i] + Dec(v[i] / n * dist)).quantize(Dec("0.000001")) for i in range(3))
        gaps = [math.dist([float(x) for x in c], [float(x) for x in ci]) - float(r + ri) for ci, ri in spheres]
        if min(gaps) < 0.01:
            continue
        touching = sorted(gaps)[0]
        if not 0.01 <= touching <= 0.05:
            continue
        spheres.append((c, r))
    return spheres


def write(name, distance, spheres):
    centre = tuple(EYE[i] + Dec(distance) * DIR[i] for i in range(3))
    extent = max(math.dist([float(x) for x in c], [0, 0, 0]) + float(r) for c, r in spheres)
    hfov = math.degrees(2 * math.atan(0.8 * extent / float(distance)))
    light = tuple(centre[i] + off for i, off in enumerate((Dec("-2.5"), Dec("4.0"), Dec("-3.5"))))
    out = [
        f"# {COUNT} near-touching mirror spheres {distance} from the eye along (0.48, 0.6, 0.64),",
        "# written by make_clusters.py: the same cluster as the other cluster-*.toml, filling the view.",
        "",
        "[camera]",
        f"eye = [{EYE[0]}, {EYE[1]}, {EYE[2]}]",
        f"look_at = [{centre[0]}, {centre[1]}, {centre[2]}]",
        "up = [0.0, 1.0, 0.0]",
        f"hfov = {hfov!r}",
        "width = 128",
        "height = 96",
        "",
        "[render]",
        "max_depth = 3",
        "background = [0.3, 0.38, 0.5]",
        "ambient = [1.0, 1.0, 1.0]",
        "",
        "[materials.mirror]",
        "color = [0.8, 0.8, 0.85]",
        "ambient = 0.05",
        "diffuse = 0.3",
        "specular = 0.5",
        "shininess = 80.0",
        "reflect = 0.7",
        "",
        "[materials.gold]",
        "color = [0.85, 0.7, 0.4]",
        "ambient = 0.1",
        "diffuse = 0.5",
        "specular = 0.4",
        "shininess = 40.0",
        "reflect = 0.5",
        "",
        "[[lights]]",
        f"position = [{light[0]}, {light[1]}, {light[2]}]",
        "intensity = 1.0",
    ]
    for k, (c, r) in enumerate(spheres):
        p = [centre[i] + c[i] for i in range(3)]
        out += ["", "[[spheres]]", f"center = [{p[0]}, {p[1]}, {p[2]}]", f"radius = {r}",
                f'material = "{"gold" if k % 3 == 0 else "mirror"}"']
    with open(name, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    import os
    here = os.path.dirname(os.path.abspath(__file__))
    s = layout()
    for label, d in (("10", "10"), ("1e4", "10000"), ("1e5", "100000"), ("1e6", "1000000")):
        write(os.path.join(here, f"cluster-{label}.toml"), d, s)
