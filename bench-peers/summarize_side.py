#!/usr/bin/env python3
"""Summarize run_side_by_side.sh output: per (N, threads) the median Mrays/s of Embree and of bareray (per BVH
preset) over the rounds, and the median of the per-round ratios bareray / Embree (each ratio from runs a few
seconds apart on the same machine)."""
import json, statistics, sys
from collections import defaultdict

runs = defaultdict(dict)  # (n, threads) -> round -> tracer -> json
for line in open(sys.argv[1]):
    if line.startswith('#') or not line.strip():
        continue
    head, _, js = line.partition('{')
    fields = dict(kv.split('=') for kv in head.split()[1:])
    rec = json.loads('{' + js)
    tracer = head.split()[0]
    if tracer == 'bareray':
        tracer += ' ' + rec.get('bvh_preset', 'Fast')
    runs[(float(fields['n']), rec['threads'])].setdefault(fields['round'], {})[tracer] = rec

tracers = sorted({t for rounds in runs.values() for r in rounds.values() for t in r if t != 'embree'})
print('| N | threads | Embree Mrays/s | ' + ' | '.join(f'{t} Mrays/s | {t} / Embree' for t in tracers) + ' | rounds |')
print('| ---: | ---: | ---: | ' + ' | '.join('---: | ---:' for _ in tracers) + ' | ---: |')
for (n, threads), rounds in sorted(runs.items()):
    cells, used = [], 0
    embree = [r['embree']['mrays_per_s'] for r in rounds.values() if 'embree' in r]
    for t in tracers:
        pairs = [r for r in rounds.values() if 'embree' in r and t in r]
        used = max(used, len(pairs))
        b = statistics.median(r[t]['mrays_per_s'] for r in pairs)
        ratio = statistics.median(r[t]['mrays_per_s'] / r['embree']['mrays_per_s'] for r in pairs)
        cells.append(f'{b:.1f} | {ratio:.2f}x')
    print(f'| {n:.0e} | {threads} | {statistics.median(embree):.1f} | ' + ' | '.join(cells) + f' | {used} |')

print()
print('Build seconds (median over rounds; Embree medium quality, bareray obvhs preset + collapse + reorder):')
print()
print('| N | threads | Embree | ' + ' | '.join(tracers) + ' |')
print('| ---: | ---: | ---: | ' + ' | '.join('---:' for _ in tracers) + ' |')
for (n, threads), rounds in sorted(runs.items()):
    med = lambda t: statistics.median(r[t]['build_s'] for r in rounds.values() if t in r)
    print(f'| {n:.0e} | {threads} | {med("embree"):.4f} | ' + ' | '.join(f'{med(t):.4f}' for t in tracers) + ' |')
