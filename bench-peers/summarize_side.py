#!/usr/bin/env python3
"""Summarize run_side_by_side.sh output: per (N, threads) the median Mrays/s of Embree and of bareray (per BVH
preset) over the rounds, and the median of the per-round ratios bareray / Embree (each ratio from runs a few
seconds apart on the same machine). Where Embree ran several packet APIs, its best in each round is used, and
a last table gives each API's median. Taking the best of several noisy runs per round favours Embree, so a
second ratio is printed too: bareray's median over Embree's best mode, the API with the highest median."""
import json, statistics, sys
from collections import defaultdict

runs = defaultdict(dict)  # (n, threads) -> round -> tracer -> json
apis = defaultdict(list)  # (n, threads, api) -> Embree Mrays/s
for line in open(sys.argv[1]):
    if line.startswith('#') or not line.strip():
        continue
    head, _, js = line.partition('{')
    fields = dict(kv.split('=') for kv in head.split()[1:])
    rec = json.loads('{' + js)
    tracer = head.split()[0]
    if tracer == 'bareray':
        tracer += ' ' + rec.get('bvh_preset', 'Fast')
    cell = runs[(float(fields['n']), rec['threads'])].setdefault(fields['round'], {})
    if tracer == 'embree':
        apis[(float(fields['n']), rec['threads'], int(rec.get('api', 16)))].append(rec['mrays_per_s'])
        if tracer in cell and cell[tracer]['mrays_per_s'] >= rec['mrays_per_s']:
            continue
    cell[tracer] = rec

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
print('Build seconds (median over rounds; Embree medium quality, bareray tree build + collapse + reorder):')
print()
print('| N | threads | Embree | ' + ' | '.join(tracers) + ' |')
print('| ---: | ---: | ---: | ' + ' | '.join('---:' for _ in tracers) + ' |')
for (n, threads), rounds in sorted(runs.items()):
    med = lambda t: statistics.median(r[t]['build_s'] for r in rounds.values() if t in r)
    print(f'| {n:.0e} | {threads} | {med("embree"):.4f} | ' + ' | '.join(f'{med(t):.4f}' for t in tracers) + ' |')

print()
print('Embree per packet API (median Mrays/s over rounds):')
print()
print('| N | threads | ' + ' | '.join(f'rtcIntersect{a}' for a in sorted({k[2] for k in apis})) + ' |')
print('| ---: | ---: | ' + ' | '.join('---:' for _ in sorted({k[2] for k in apis})) + ' |')
for (n, threads) in sorted(runs):
    row = [apis.get((n, threads, a)) for a in sorted({k[2] for k in apis})]
    print(f'| {n:.0e} | {threads} | ' + ' | '.join(f'{statistics.median(v):.1f}' if v else '-' for v in row) + ' |')

print()
print("Against Embree's best mode by median (the API with the highest median; ratio of medians):")
print()
print('| N | threads | best API | Embree Mrays/s | ' + ' | '.join(f'{t} / Embree' for t in tracers) + ' |')
print('| ---: | ---: | ---: | ---: | ' + ' | '.join('---:' for _ in tracers) + ' |')
for (n, threads), rounds in sorted(runs.items()):
    medians = {a: statistics.median(v) for (m, th, a), v in apis.items() if (m, th) == (n, threads)}
    api, best = max(medians.items(), key=lambda kv: kv[1])
    cells = [statistics.median(r[t]['mrays_per_s'] for r in rounds.values() if t in r) / best for t in tracers]
    print(f'| {n:.0e} | {threads} | {api} | {best:.1f} | ' + ' | '.join(f'{c:.2f}x' for c in cells) + ' |')
