#!/usr/bin/env python3
"""Two builds of the Python module on one render, each timed in a process of its own, alternated round by
round: `bareray.render` of the spheres in an .xyzr list (default: the OVITO harness's 1e5 random particles)
at 1920x1080, Whitted, mid grey, with a camera given as flags. OLD_DIR holds the old build's `bareray`
package (a copy of the installed one's folder, put first on `sys.path`); the installed module is the new one.
Per round, the median of 7 calls after one warm-up; the per-round ratio new/old, and whether the images'
sums agree.

usage: python python_ab.py ROUNDS OLD_DIR XYZR EYE LOOK UP HFOV     (EYE, LOOK, UP as x,y,z)
"""
import statistics as st
import subprocess
import sys

CHILD = r"""
import sys, time, numpy as np
old, xyzr, eye, look, up, hfov = sys.argv[1:7]
if old:
    sys.path.insert(0, old)
import bareray
x = np.loadtxt(xyzr, ndmin=2); c = np.ascontiguousarray(x[:, :3]); r = np.ascontiguousarray(x[:, 3])
grey = np.full((len(r), 3), 0.5)
vec = lambda s: [float(v) for v in s.split(",")]
kw = dict(width=1920, height=1080, eye=vec(eye), look=vec(look), up=vec(up), hfov=float(hfov))
image = bareray.render(c, r, grey, **kw)
times = []
for _ in range(7):
    start = time.perf_counter(); image = bareray.render(c, r, grey, **kw); times.append(time.perf_counter() - start)
print(sorted(times)[3], float(image.sum()))
"""


def main():
    if len(sys.argv) != 8:
        sys.exit(__doc__)
    rounds, old, scene = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
    res = {"old": [], "new": []}
    for k in range(rounds):
        for which in ("old", "new") if k % 2 == 0 else ("new", "old"):
            args = [sys.executable, "-c", CHILD, old if which == "old" else "", *scene]
            done = subprocess.run(args, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(done.stderr)
            seconds, total = done.stdout.split()
            res[which].append((float(seconds), total))
    ratios = [n[0] / o[0] for o, n in zip(res["old"], res["new"])]
    print("old", [round(t[0], 4) for t in res["old"]])
    print("new", [round(t[0], 4) for t in res["new"]])
    print("image sums equal:", all(o[1] == n[1] for o, n in zip(res["old"], res["new"])))
    print(f"new/old median {st.median(ratios):.3f} (min {min(ratios):.3f}, max {max(ratios):.3f}); old median "
          f"{st.median(t[0] for t in res['old']):.4f} s, new {st.median(t[0] for t in res['new']):.4f} s")


if __name__ == "__main__":
    main()
