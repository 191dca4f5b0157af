#!/usr/bin/env python3
"""Summarize embree_bench JSON lines: the best api per (spheres, geometry, threads), and Embree's best mode.

usage: summarize.py results/embree-*.jsonl [--by seconds|seconds_min]
'best' = lowest median render time (--by seconds, default), lowest single repetition (--by seconds_min), or
lowest median process CPU time per render (--by cpu_s; robust when other jobs share the cores; the Mrays/s
column is then per CPU-second, i.e. the wall rate an unloaded machine would give with perfect scaling).
Several files (re-runs) are pooled; each cell then shows the best run.
"""
import argparse
import json
from collections import defaultdict

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("files", nargs="+")
ap.add_argument("--by", choices=("seconds", "seconds_min", "cpu_s"), default="seconds")
a = ap.parse_args()
rows = []
for f in a.files:
    for line in open(f):
        line = line.strip()
        if line.startswith("{"):
            r = json.loads(line)
            r["_file"] = f
            rows.append(r)
cells = defaultdict(list)
for r in rows:
    cells[(r["spheres"], r["geometry"], r["threads"])].append(r)
print(f"{'spheres':>8} {'geometry':>8} {'thr':>3}  best api  {'s (median)':>10} {'s (min)':>8} {'Mrays/s':>8}  "
      f"{'build_s':>8} {'bld_cpu':>8}  all apis (Mrays/s by --by)")
best_overall = {}
for key in sorted(cells):
    rs = cells[key]
    b = min(rs, key=lambda r: r[a.by])
    per_api = defaultdict(float)
    for r in rs:
        rate = r["width"] * r["height"] / r[a.by] / 1e6
        if a.by == "cpu_s":
            rate *= r["threads"]
        per_api[r["api"]] = max(per_api[r["api"]], rate)
    apis = " ".join(f"{k}:{v:.2f}" for k, v in sorted(per_api.items(), key=lambda kv: int(kv[0])))
    W, H = b["width"], b["height"]
    mr = W * H / b[a.by] / 1e6 * (b["threads"] if a.by == "cpu_s" else 1)
    print(f"{key[0]:>8} {key[1]:>8} {key[2]:>3}  {b['api']:>8}  {b['seconds']:>10.4f} {b['seconds_min']:>8.4f} "
          f"{mr:>8.2f}  {b['build_s']:>8.4f} {b.get('build_cpu_s', float('nan')):>8.4f}  {apis}")
    k2 = (key[0], key[2])
    if k2 not in best_overall or b[a.by] < best_overall[k2][a.by]:
        best_overall[k2] = b
print("\nEmbree's best mode per (spheres, threads):")
for (n, t), b in sorted(best_overall.items()):
    mr = b["width"] * b["height"] / b[a.by] / 1e6 * (b["threads"] if a.by == "cpu_s" else 1)
    print(f"  N={n:<8} threads={t}: {b['geometry']} rtcIntersect{b['api']}  {b[a.by]:.4f} s ({a.by})  "
          f"{mr:.2f} Mrays/s  (build {b['build_s']:.4f} s, checksum {b['checksum']})")
