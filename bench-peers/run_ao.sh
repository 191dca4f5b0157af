#!/usr/bin/env bash
# Ambient occlusion, Embree against bareray: the same contract field (`bareray gen field`, generated again by
# embree_bench from the same splitmix64 stream), the same contract camera, S occlusion rays of length D per
# camera hit. Per round, bareray's `bench --shade ao:S,D` at 1, 8 and 16 lanes and embree_bench --ao S,D
# (points and user geometry, rtcIntersect/rtcOccluded at each API of EMBREE_APIS), in alternating order
# (odd rounds bareray first, even rounds Embree first). Both time camera + occlusion rays together and count
# both in Mrays/s. Output: results/ao-<UTC stamp>.txt (header: date, machine, commands; one line per
# measurement) and a summary on stdout: per configuration the median seconds and Mrays/s over rounds, the
# camera-hit check (Embree's "hits" against bareray's (rays - W*H)/S) and bareray's best row over Embree's
# best configuration, per round and the median of those ratios.
#
# The two tracers draw different directions (bareray: a shifted Fibonacci lattice per hit; Embree harness:
# splitmix64 per pixel, Malley's method) and leave the surface differently (bareray skips the departure
# sphere; the harness moves the origin out by max(1e-4 r, 2^-21 max(|c|, r))), so their open shares agree
# statistically, not ray for ray.
#
# usage: run_ao.sh
# env:   COUNT=1e5 WIDTH=960 HEIGHT=540 AO="16,0.875" THREADS=2 ROUNDS=3 EMBREE_APIS="1,16"
#        EMBREE_ARGS="" (e.g. "--isa avx2")  BAREBIN=target/release/bareray (relative to the repository root)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"
bareray="${BAREBIN:-target/release/bareray}"
case "$bareray" in /*) ;; *) bareray="$root/$bareray" ;; esac
[ -x "$bareray" ] || { echo "run_ao.sh: no bareray binary at $bareray (set BAREBIN)" >&2; exit 2; }
count="${COUNT:-1e5}"
width="${WIDTH:-960}"
height="${HEIGHT:-540}"
ao="${AO:-16,0.875}"
threads="${THREADS:-2}"
rounds="${ROUNDS:-3}"
apis="${EMBREE_APIS:-1,16}"
embree_args="${EMBREE_ARGS:-}"
make -s -C "$here/embree"
mkdir -p "$here/results"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
field="$tmp/field-$count.f32r"
"$bareray" gen field --count "$count" -o "$field" >&2
stamp="$(date -u +%Y-%m-%dT%H%M%SZ)"
out="$here/results/ao-$stamp.txt"
# The contract camera, passed to both (embree_bench's defaults are the same; bareray's .f32r camera is not
# guaranteed to be, so it is given explicitly, as run_side_by_side.sh does).
cam=(--eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width "$width" --height "$height")
bcmd=(bench "$field" --shade "ao:$ao" "${cam[@]}" --threads "$threads" --lanes 1,8,16 --reps 3 --by-kind false --json)
# shellcheck disable=SC2206
ecmd=(--count "$count" "${cam[@]}" --threads "$threads" --geometry points,user --api "$apis" --ao "$ao" --reps 3
      $embree_args)
{
  echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ)  host: $(uname -srm)  nproc: $(nproc)"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "# embree: $(dpkg-query -W -f='${Version}' libembree3-3 2>/dev/null || echo unknown)  bareray: $("$bareray" --version | tr "\n" " ")"
  echo "# field: $bareray gen field --count $count -o field.f32r"
  echo "# bareray: $bareray ${bcmd[*]}"
  echo "# embree: embree_bench ${ecmd[*]}"
  echo "# load before: $(cut -d' ' -f1-3 /proc/loadavg)"
} > "$out"
run_bareray() {
  local load; load="$(cut -d' ' -f1 /proc/loadavg)"
  "$bareray" "${bcmd[@]}" | sed "s/^/bareray round=$1 load=$load /" | tee -a "$out"
}
run_embree() {
  local load; load="$(cut -d' ' -f1 /proc/loadavg)"
  "$here/embree/embree_bench" "${ecmd[@]}" 2>/dev/null | sed "s/^/embree round=$1 load=$load /" | tee -a "$out"
}
for round in $(seq 1 "$rounds"); do
  if [ $((round % 2)) -eq 1 ]; then run_bareray "$round"; run_embree "$round"
  else run_embree "$round"; run_bareray "$round"; fi
done
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out"
echo "results: $out" >&2
echo
python3 - "$out" "$ao" "$width" "$height" <<'EOF'
import json, statistics, sys
from collections import defaultdict

path, ao, W, H = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
S = int(ao.split(',')[0])
rows = defaultdict(dict)  # config -> round -> record
order = {}  # config -> sort key (tracer, geometry, lanes or api as a number)
for line in open(path):
    if line.startswith('#') or not line.strip():
        continue
    head, _, js = line.partition('{')
    tracer, *kv = head.split()
    fields = dict(x.split('=', 1) for x in kv)
    rec = json.loads('{' + js)
    if tracer == 'bareray':
        cfg = f"bareray lanes={rec['lanes']}"
        rec['camera_hits'] = (rec['rays'] - W * H) / S
        rec['camera_hits'] = int(rec['camera_hits']) if rec['camera_hits'].is_integer() else rec['camera_hits']
        rec['ao_open_share'] = None  # bench does not print it
    else:
        cfg = f"embree {rec['geometry']} api={rec['api']}"
        rec['camera_hits'] = rec['hits']
    rows[cfg][int(fields['round'])] = rec
    order[cfg] = (tracer, rec.get('geometry', ''), int(rec.get('lanes', rec.get('api', 0))))

print(f"AO {ao} (S = {S}), {W}x{H}, medians over rounds; Mrays/s = (camera + AO rays) / median seconds")
print()
print('| tracer / configuration | threads | rounds | median s | Mrays/s | AO Mrays/s | rays | camera hits | open share |')
print('| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |')
for cfg, by_round in sorted(rows.items(), key=lambda kv: order[kv[0]]):
    recs = list(by_round.values())
    sec = statistics.median(r['seconds'] for r in recs)
    rays = recs[0]['rays']
    ao_rays = rays - W * H
    hits = sorted({r['camera_hits'] for r in recs})
    share = recs[0]['ao_open_share']
    print(f"| {cfg} | {recs[0]['threads']} | {len(recs)} | {sec:.4f} | {rays / sec / 1e6:.2f} | "
          f"{ao_rays / sec / 1e6:.2f} | {rays} | {', '.join(f'{h:g}' for h in hits)} | "
          f"{'-' if share is None else f'{share:.4f}'} |")

bhits = {r['camera_hits'] for c, rr in rows.items() if c.startswith('bareray') for r in rr.values()}
ehits = {r['camera_hits'] for c, rr in rows.items() if c.startswith('embree') for r in rr.values()}
print()
print(f"camera hits: bareray (rays - W*H)/S = {sorted(bhits)}, Embree hits = {sorted(ehits)}"
      + ('' if bhits == ehits else '  <-- MISMATCH: check the field and camera'))

print()
print("bareray's best row against Embree's best configuration, per round (Mrays/s, camera + AO rays):")
print()
print('| round | bareray best | Mrays/s | Embree best | Mrays/s | ratio |')
print('| ---: | --- | ---: | --- | ---: | ---: |')
ratios = []
for rnd in sorted({r for rr in rows.values() for r in rr}):
    b = [(rr[rnd]['mrays_per_s'], c) for c, rr in rows.items() if c.startswith('bareray') and rnd in rr]
    e = [(rr[rnd]['mrays_per_s'], c) for c, rr in rows.items() if c.startswith('embree') and rnd in rr]
    if not b or not e:
        continue
    (bm, bc), (em, ec) = max(b), max(e)
    ratios.append(bm / em)
    print(f'| {rnd} | {bc} | {bm:.2f} | {ec} | {em:.2f} | {bm / em:.2f}x |')
if ratios:
    print()
    print(f'median of per-round ratios (bareray best / Embree best): {statistics.median(ratios):.2f}x over {len(ratios)} rounds')
EOF
