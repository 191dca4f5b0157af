#!/usr/bin/env bash
# BVH build time of Embree (user-geometry spheres, its default build quality) and one or more bareray builds
# on the same field, alternated run by run for ROUNDS rounds at THREADS threads, one build per process: on a
# host whose speed drifts, each round compares builds made seconds apart. Prints per tracer the min, median
# and max build seconds and the median of the per-round ratios Embree / bareray; writes the raw lines to
# results/buildpair-<UTC stamp>.txt. bareray's load + build (bench's parse + compile seconds: reading the
# file, the scene and its BVH) is reported beside its build and compared with Embree's build alone
# (Embree's reading of the text file is not timed); FORMAT=f32r gives bareray the binary file of the same
# field (Embree reads the .xyzr).
#
# With DROP_CACHES=1 (root) the page cache is dropped before every run and the program and field read back
# in (see run_pov_pair.sh for why).
#
# usage: run_build_pair.sh path/to/bareray [more builds...]
#   env: N=1e6 ROUNDS=10 THREADS=2 DROP_CACHES=0 FORMAT=xyzr|f32r
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ $# -ge 1 ] || { echo "usage: $0 path/to/bareray [more builds...]" >&2; exit 2; }
make -s -C "$here/embree"
n="${N:-1e6}"; threads="${THREADS:-2}"
field="$here/out/field-$n.xyzr"
ours="$here/out/field-$n.${FORMAT:-xyzr}"
mkdir -p "$here/out"
for f in "$field" "$ours"; do [ -f "$f" ] || "$1" gen field --count "$n" -o "$f" >&2; done
mkdir -p "$here/results"
out="$here/results/buildpair-$(date -u +%Y-%m-%dT%H%M%SZ).txt"
fresh() {
  [ "${DROP_CACHES:-0}" = 1 ] || return 0
  sync; echo 1 > /proc/sys/vm/drop_caches
  cat "$1" "$field" "$ours" > /dev/null
}
{
  echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ)  nproc: $(nproc)  cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "# field $field (bareray: $ours), $threads threads, drop caches: ${DROP_CACHES:-0}"
  echo "# embree: embree_bench --xyzr F --geometry user --api 8 --threads T --reps 1 (build_s)"
  echo "# bareray: bareray bench F --primary-only --lanes 16 --threads T --reps 1 ('BVH build' seconds, then parse + compile)"
  for r in $(seq "${ROUNDS:-10}"); do
    fresh "$here/embree/embree_bench"
    line="embree $("$here/embree/embree_bench" --xyzr "$field" --geometry user --api 8 --threads "$threads" --reps 1 2>/dev/null \
      | grep -o '"build_s":[0-9.]*' | cut -d: -f2)"
    for b in "$@"; do
      fresh "$b"
      line="$line $(basename "$b") $("$b" bench "$ours" --primary-only --lanes 16 --threads "$threads" --reps 1 \
        2>&1 | grep -oE 'parse [0-9.]+ s, compile [0-9.]+ s \(BVH build [0-9.]+' | tr -d '(,' \
        | awk '{printf "%s %.4f", $9, $2 + $5}')"
    done
    echo "$line"
  done
} | tee "$out" | python3 -c "
import sys, statistics as st
rows = [l.split() for l in sys.stdin if not l.startswith('#')]
embree = [float(r[1]) for r in rows]
print(f'embree: build min {min(embree):.3f} median {st.median(embree):.3f} max {max(embree):.3f} s')
for k, name in enumerate(rows[0][2::3]):
    ours = [float(r[3 + 3 * k]) for r in rows]
    total = [float(r[4 + 3 * k]) for r in rows]
    ratio = st.median(e / o for e, o in zip(embree, ours))
    whole = st.median(e / o for e, o in zip(embree, total))
    print(f'{name}: build min {min(ours):.3f} median {st.median(ours):.3f} max {max(ours):.3f} s;'
          f' Embree / bareray median {ratio:.2f}x; load + build min {min(total):.3f}'
          f' median {st.median(total):.3f} max {max(total):.3f} s, Embree build / bareray load + build'
          f' median {whole:.2f}x')
" | tee -a "$out"
echo "results: $out" >&2
