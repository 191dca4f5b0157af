#!/usr/bin/env bash
# The 1e7 contract field: bareray's primary-only bench and Embree's user-geometry rtcIntersect8 (AVX2 machines;
# API=16 on AVX-512 ones) one after the other, PAIRS times, each under /usr/bin/time for peak resident memory.
# Output: results/1e7-<UTC stamp>.txt (header: date, machine, load, bareray version; every command and its
# output). The field (about 330 MB) is generated once into out/.
#
# usage: run_1e7.sh [path/to/bareray]       env: PAIRS=2 THREADS=2 API=8 REPS=3
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bareray="${1:-$here/../target/native/release/bareray}"
make -s -C "$here/embree"
mkdir -p "$here/results" "$here/out"
f="$here/out/field-1e7.xyzr"
[ -f "$f" ] || "$bareray" gen field --count 1e7 -o "$f" >&2
out="$here/results/1e7-$(date -u +%Y-%m-%dT%H%M%SZ).txt"
threads="${THREADS:-2}"
reps="${REPS:-3}"
cam=(--eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width 1920 --height 1080)
{
  echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ) nproc: $(nproc) cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)" \
    "load: $(cut -d' ' -f1-3 /proc/loadavg) bareray: $("$bareray" --version | tr "\n" " ")"
  for pair in $(seq 1 "${PAIRS:-2}"); do
    echo "## pair $pair"
    echo "\$ bareray bench field-1e7.xyzr --primary-only ${cam[*]} --reps $reps --lanes 16 --threads $threads"
    /usr/bin/time -f "peak RSS %M KB, wall %e s" "$bareray" bench "$f" --primary-only "${cam[@]}" \
      --reps "$reps" --lanes 16 --threads "$threads" 2>&1
    echo "\$ embree_bench --xyzr field-1e7.xyzr --geometry user --api ${API:-8} --threads $threads --reps $reps --build-reps 1"
    /usr/bin/time -f "peak RSS %M KB, wall %e s" "$here/embree/embree_bench" --xyzr "$f" --geometry user \
      --api "${API:-8}" --threads "$threads" --reps "$reps" --build-reps 1 2>&1
  done
  echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$out"
echo "results: $out" >&2
