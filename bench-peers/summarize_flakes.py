#!/usr/bin/env python3
"""Summarize run_flakes.sh output (times.txt): per scene and tracer the wall and CPU seconds of every run,
their medians, and POV-Ray's and Tachyon's median wall time over bareray's; then bareray's own split (parse,
build, tracing with the streamed PNG) and peak RSS, medians, where its lines hold them."""
import statistics, sys
from collections import defaultdict

runs = defaultdict(lambda: defaultdict(list))  # scene -> tracer -> [(wall, cpu)]
split = defaultdict(list)  # scene -> [fields of bareray's lines]
for line in open(sys.argv[1]):
    if line.startswith('#') or 'tracer=' not in line:
        continue
    f = dict(kv.split('=', 1) for kv in line.split() if '=' in kv)
    runs[f['scene']][f['tracer']].append((float(f['wall_s']), float(f['cpu_s'])))
    if f['tracer'] == 'bareray' and 'render_s' in f:
        split[f['scene']].append(f)

print('| scene | tracer | wall s (runs) | median wall s | median CPU s | wall / bareray |')
print('| --- | --- | --- | ---: | ---: | ---: |')
for scene, tracers in runs.items():
    base = statistics.median(w for w, _ in tracers['bareray'])
    for tracer in ['povray', 'tachyon', 'bareray']:
        if tracer not in tracers:
            continue
        walls = [w for w, _ in tracers[tracer]]
        wall, cpu = statistics.median(walls), statistics.median(c for _, c in tracers[tracer])
        print(f'| {scene} | {tracer} | {", ".join(f"{w:.2f}" for w in walls)} | {wall:.2f} | {cpu:.2f} | '
              f'{wall / base:.1f}x |')

if split:
    print()
    print('| scene | bareray parse s | build s | tracing + PNG s | peak RSS MB |')
    print('| --- | ---: | ---: | ---: | ---: |')
    for scene, lines in split.items():
        med = lambda k: statistics.median(float(f[k]) for f in lines)
        print(f"| {scene} | {med('parse_s'):.3f} | {med('build_s'):.3f} | {med('render_s'):.3f} | "
              f"{med('peak_mb'):.0f} |")
