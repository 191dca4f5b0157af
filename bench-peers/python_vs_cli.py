#!/usr/bin/env python3
"""The Python module against the command line on the same spheres (issue 39's figure): `bareray.render` of 1e6
random spheres (uniform in [-1, 1]^3, radii uniform in [0.005, 0.015]) at 1920x1080, its default framing and
shading, timed in this process, against `BIN render` of the same spheres written as extended XYZ, whose summary
line's build and render seconds are summed (its parse is left out: the module reads no file). Rounds
alternate which goes first; medians and their ratio are printed.

usage: python python_vs_cli.py BIN ROUNDS     (a virtual environment with numpy and the module installed)
"""
import re
import statistics as st
import subprocess
import sys
import time

import numpy as np

import bareray


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    binary, rounds = sys.argv[1], int(sys.argv[2])
    rng = np.random.default_rng(1)
    n = 1_000_000
    centers = rng.uniform(-1, 1, (n, 3))
    radii = rng.uniform(0.005, 0.015, n)
    path = "/tmp/python-vs-cli-1e6.xyz"
    with open(path, "w") as f:
        f.write(f"{n}\nProperties=species:S:1:pos:R:3:radius:R:1\n")
        np.savetxt(f, np.column_stack([centers, radii]), fmt="C %.9g %.9g %.9g %.9g")
    py, cli = [], []
    for r in range(rounds):
        for which in ("py", "cli") if r % 2 == 0 else ("cli", "py"):
            if which == "py":
                start = time.perf_counter()
                image = bareray.render(centers, radii, width=1920, height=1080)
                py.append(time.perf_counter() - start)
            else:
                done = subprocess.run([binary, "render", path, "-o", "/tmp/python-vs-cli.png"],
                                      capture_output=True, text=True)
                text = done.stdout + done.stderr
                m = re.search(r" in ([0-9.]+) s \(parse ([0-9.]+) s, build ([0-9.]+) s\)", text)
                if not m:
                    sys.exit(text)
                cli.append(float(m.group(1)) + float(m.group(3)))
    print(f"python bareray.render: median {st.median(py):.3f} s ({min(py):.3f}-{max(py):.3f})")
    print(f"CLI build + render:    median {st.median(cli):.3f} s ({min(cli):.3f}-{max(cli):.3f})")
    print(f"ratio python / CLI: {st.median(py) / st.median(cli):.3f}", image.shape, image.dtype)


if __name__ == "__main__":
    main()
