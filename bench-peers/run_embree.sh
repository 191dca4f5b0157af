#!/usr/bin/env bash
# Build embree_bench and run the peer matrix: N in {1e3, 1e5, 1e6} x {points, user} x {rtcIntersect1,4,8,16}
# x {1, 2 threads}, on the contract's camera (1920x1080). JSON lines go to stdout and to
# results/embree-<UTC date>.jsonl; a header with the date, machine and load goes to the matching .txt.
# Extra arguments are passed to every embree_bench call (e.g. --reps 9, --pregen, --quality high).
# Override the sizes with COUNTS="1e3 1e4" ./run_embree.sh
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
make -s -C "$here/embree"
mkdir -p "$here/results"
stamp="$(date -u +%Y-%m-%dT%H%M%SZ)"
out="$here/results/embree-$stamp.jsonl"
meta="$here/results/embree-$stamp.txt"
{
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "host: $(uname -srm)"
  echo "nproc: $(nproc)"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "embree: $(dpkg-query -W -f='${Version}' libembree3-3 2>/dev/null || echo unknown)"
  echo "compiler: $(g++ --version | head -1)"
  echo "command: $0 $*"
  echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
} > "$meta"
for n in ${COUNTS:-1e3 1e5 1e6}; do
  echo "# N=$n  load $(cut -d' ' -f1-3 /proc/loadavg)" >> "$meta"
  echo "cmd: $here/embree/embree_bench --count $n $*" >> "$meta"
  "$here/embree/embree_bench" --count "$n" "$@" 2>>"$meta" | tee -a "$out"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$meta"
echo "results: $out" >&2
