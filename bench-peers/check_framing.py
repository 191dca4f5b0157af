#!/usr/bin/env python3
"""Measure how POV-Ray (via nff2pov.py) and Tachyon frame the same NFF view.

usage: check_framing.py [OUTDIR]     (default out/framing; needs povray, tachyon, numpy, pillow)

Renders scenes/axes.nff (balls view; spheres at the origin, +x red, +y green, +z blue) at 512x512 with the
view angle set to 30, 45 and 60 degrees, finds the red and green spheres' pixel centroids, and prints
  * which side +x and +y land on (a right-handed world seen from (2.1, 1.3, 1.7), up +z: +x left, +y right),
  * the red-green distance against the pinhole projection with image half-width tan(angle/2), and the
    half-width that distance implies.
"""
import math
import os
import subprocess
import sys

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
S = 512


def centroid(path, ch):
    im = np.asarray(Image.open(path).convert("RGB")).astype(int)
    o = [i for i in range(3) if i != ch]
    m = (im[:, :, ch] > 120) & (im[:, :, o[0]] < 60) & (im[:, :, o[1]] < 60)
    ys, xs = np.nonzero(m)
    return (xs.mean(), ys.mean()) if xs.size else None


def project(p, half):
    e = np.array([2.1, 1.3, 1.7])
    f = -e / np.linalg.norm(e)
    r = np.cross(f, [0, 0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    v = np.array(p) - e
    x, y = (v @ r) / (v @ f), (v @ u) / (v @ f)
    return ((x / half + 1) * S / 2, (1 - y / half) * S / 2)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "out", "framing")
    os.makedirs(out, exist_ok=True)
    src = open(os.path.join(HERE, "scenes", "axes.nff")).read()
    for angle in (30, 45, 60):
        nff = os.path.join(out, f"axes{angle}.nff")
        open(nff, "w").write(src.replace("angle 45", f"angle {angle}"))
        pov = nff[:-4] + ".pov"
        subprocess.run([sys.executable, os.path.join(HERE, "nff2pov.py"), nff, "-o", pov,
                        "--width", str(S), "--height", str(S)], check=True, capture_output=True)
        subprocess.run(["povray", f"+I{pov}", f"+O{nff[:-4]}.pov.png", f"+W{S}", f"+H{S}", "-A", "-D", "+FN"],
                       check=True, capture_output=True)
        subprocess.run(["tachyon", nff, "-res", str(S), str(S), "-aasamples", "0", "-format", "PNG",
                        "-o", f"{nff[:-4]}.tachyon.png"], check=True, capture_output=True)
        half = math.tan(math.radians(angle) / 2)
        expect = math.dist(project([1, 0, 0], half), project([0, 1, 0], half))
        for name in ("pov", "tachyon"):
            png = f"{nff[:-4]}.{name}.png"
            red, green = centroid(png, 0), centroid(png, 1)
            if red is None or green is None:
                print(f"angle {angle:>2} {name:>7}: a marker is outside the image")
                continue
            d = math.dist(red, green)
            side = "+x left, +y right" if red[0] < green[0] else "+x right, +y left (mirrored)"
            print(f"angle {angle:>2} {name:>7}: {side}; red-green {d:6.1f} px, pinhole tan(angle/2) predicts "
                  f"{expect:6.1f} px -> implied half-width {half * expect / d:.4f} (tan(angle/2) = {half:.4f})")


if __name__ == "__main__":
    main()
