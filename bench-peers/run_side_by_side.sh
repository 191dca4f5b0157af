#!/usr/bin/env bash
# Embree and bareray on the same contract fields, rays and thread counts, interleaved in one session:
# for each round, N and thread count, Embree with user-geometry exact spheres at each packet API of EMBREE_APIS
# (its best mode is the fastest of them in that round: rtcIntersect16 on AVX-512 machines, rtcIntersect8 on
# AVX2 ones; add more with EMBREE_ARGS) and then bareray's primary-only bench at K = 16. Fields come from `bareray gen
# field`, so both read the same file. Output: results/side-<UTC stamp>.txt (header: date, machine, load,
# commands) with one line per measurement; summarize with `python3 summarize_side.py FILE`.
#
# bareray runs once per BVH preset in PRESETS (default: morton, its default, and sah, the SAH alone).
#
# usage: run_side_by_side.sh [path/to/bareray]
# env:   COUNTS="1e3 1e5 1e6" THREADS="1 2" ROUNDS=3 REPS=7 PRESETS="morton sah" EMBREE_APIS="8 16"
#        EMBREE_ARGS=""
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bareray="${1:-$here/../target/native/release/bareray}"
make -s -C "$here/embree"
mkdir -p "$here/results" "$here/out"
stamp="$(date -u +%Y-%m-%dT%H%M%SZ)"
out="$here/results/side-$stamp.txt"
cam=(--eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width 1920 --height 1080)
reps="${REPS:-7}"
{
  echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ)  host: $(uname -srm)  nproc: $(nproc)"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "# embree: $(dpkg-query -W -f='${Version}' libembree3-3 2>/dev/null || echo unknown)  bareray: $("$bareray" --version | tr "\n" " ")"
  echo "# embree: embree_bench --xyzr F --geometry user --api A --threads T --reps $reps ${EMBREE_ARGS:-} (A in ${EMBREE_APIS:-8 16})"
  echo "# bareray: bareray bench F --primary-only ${cam[*]} --lanes 16 --threads T --reps $reps --json --bvh-preset P (P in ${PRESETS:-morton sah})"
} > "$out"
for n in ${COUNTS:-1e3 1e5 1e6}; do
  [ -f "$here/out/field-$n.xyzr" ] || "$bareray" gen field --count "$n" -o "$here/out/field-$n.xyzr" >&2
done
for round in $(seq 1 "${ROUNDS:-3}"); do
  for n in ${COUNTS:-1e3 1e5 1e6}; do
    f="$here/out/field-$n.xyzr"
    for t in ${THREADS:-1 2}; do
      load="$(cut -d' ' -f1 /proc/loadavg)"
      for api in ${EMBREE_APIS:-8 16}; do
        "$here/embree/embree_bench" --xyzr "$f" --geometry user --api "$api" --threads "$t" --reps "$reps" \
          ${EMBREE_ARGS:-} 2>/dev/null | sed "s/^/embree round=$round n=$n load=$load /" | tee -a "$out"
      done
      for preset in ${PRESETS:-morton sah}; do
        "$bareray" bench "$f" --primary-only "${cam[@]}" --lanes 16 --threads "$t" --reps "$reps" --json \
          --bvh-preset "$preset" | sed "s/^/bareray round=$round n=$n load=$load /" | tee -a "$out"
      done
    done
  done
done
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out"
echo "results: $out" >&2
