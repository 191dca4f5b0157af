#!/usr/bin/env python3
"""Medians per (label, scene) of run_ab.sh output, and each label's ratio to the first label."""
import statistics
import sys
from collections import defaultdict

runs = defaultdict(list)
labels, scenes, sums = [], [], {}
for line in open(sys.argv[1]):
    if line.startswith("#"):
        continue
    label, scene, _k, seconds, _s, mrays, _unit, checksum = line.split()
    runs[label, scene].append(float(mrays))
    sums.setdefault(scene, set()).add(checksum)
    labels += [label] if label not in labels else []
    scenes += [scene] if scene not in scenes else []
print("scene".ljust(12) + "".join(f"{l:>16}" for l in labels) + "   checksums")
for scene in scenes:
    base = statistics.median(runs[labels[0], scene])
    cells = []
    for label in labels:
        m = statistics.median(runs[label, scene])
        cells.append(f"{m:7.2f} ({m / base:4.2f}x)")
    same = "equal" if len(sums[scene]) == 1 else "DIFFER"
    print(scene.ljust(12) + "".join(f"{c:>16}" for c in cells) + "   " + same)
