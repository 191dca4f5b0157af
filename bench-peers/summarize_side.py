#!/usr/bin/env python3
"""Summarize run_side_by_side.sh output: per (N, threads) the median Mrays/s of Embree and bareray over the
rounds, and the median of the per-round ratios bareray / Embree (each ratio from two runs minutes apart at
most, on the same loaded machine)."""
import json, statistics, sys
from collections import defaultdict

runs = defaultdict(dict)  # (n, threads) -> round -> tracer -> json
for line in open(sys.argv[1]):
    if line.startswith('#') or not line.strip():
        continue
    head, _, js = line.partition('{')
    fields = dict(kv.split('=') for kv in head.split()[1:])
    rec = json.loads('{' + js)
    runs[(float(fields['n']), rec['threads'])].setdefault(fields['round'], {})[head.split()[0]] = rec

print('| N | threads | Embree Mrays/s | bareray Mrays/s | bareray / Embree (median of rounds) | rounds |')
print('| ---: | ---: | ---: | ---: | ---: | ---: |')
for (n, t), rounds in sorted(runs.items()):
    pairs = [r for r in rounds.values() if 'embree' in r and 'bareray' in r]
    e = statistics.median(r['embree']['mrays_per_s'] for r in pairs)
    b = statistics.median(r['bareray']['mrays_per_s'] for r in pairs)
    ratio = statistics.median(r['bareray']['mrays_per_s'] / r['embree']['mrays_per_s'] for r in pairs)
    print(f'| {n:.0e} | {t} | {e:.1f} | {b:.1f} | {ratio:.2f}x | {len(pairs)} |')
