#!/usr/bin/env bash
# The particle tree (--accel pkd) against the BVH from 1e6 to 5e8 spheres (PERF.md, "Scale"): camera rays in
# alternated rounds, checksums and images at every width and thread count, the time split and peak memory of
# Whitted renders, the 5e8 field left to `auto`, and AO. Fields are generated into DIR when missing (5e8 is an
# 8 GB file; its render needs about 10 GB of memory).
#
# usage: run_scale.sh [DIR]      env: BAREray=path/to/bareray (default target/release/bareray), ROUNDS=5
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
B="$(realpath "${BAREray:-$here/../target/release/bareray}")"
dir="${1:-$here/out/scale}"
mkdir -p "$dir" && cd "$dir"
echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ) nproc: $(nproc) cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
for n in 1e6 1e7 1e8 5e8; do
  [ -f "f$n.f32r" ] || "$B" gen field --count "$n" -o "f$n.f32r" >/dev/null
done
echo "== camera rays, lanes 16, 2 threads, ${ROUNDS:-5} alternated rounds (bench --primary-only --reps 3 each)"
for n in 1e6 1e7; do
  for round in $(seq "${ROUNDS:-5}"); do
    for a in bvh pkd; do
      echo "$n $a round $round $("$B" bench "f$n.f32r" --accel $a --lanes 16 --threads 2 --primary-only --reps 3 2>&1 | tail -1)"
    done
  done
done
echo "== bench checksums at every width and thread count"
for n in 1e6 1e7; do for a in bvh pkd; do
  echo "$n $a"; "$B" bench "f$n.f32r" --accel $a --lanes 1,4,8,16 --threads 1,2 --primary-only --reps 1 2>&1 | tail -8
done; done
echo "== mapped path: Whitted images at every width and thread count (one md5 per field: the same image)"
for n in 1e6 1e7; do
  for l in 1 4 8 16; do for t in 1 2; do for a in bvh pkd; do
    "$B" render "f$n.f32r" --accel $a --lanes $l --threads $t -o "img_${n}_${a}_${l}_${t}.png" --quiet
  done; done; done
  md5sum img_"${n}"_*.png | awk '{print $1}' | sort | uniq -c
done
echo "== peak memory and time split, Whitted 1920x1080, 2 threads"
for n in 1e6 1e7 1e8; do for a in bvh pkd; do
  echo "$n $a"
  /usr/bin/time -f "wall %e s, peak %M KB" "$B" render "f$n.f32r" --accel $a --threads 2 -o "mem_${n}_$a.png" --stats 2>&1 |
    grep -E "accel:|time:|wall|rays:"
done; done
ls -l f*.f32r
echo "== 5e8, auto, Whitted 1920x1080, 2 threads"
/usr/bin/time -f "wall %e s, peak %M KB" "$B" render f5e8.f32r --width 1920 --height 1080 -o f5e8.png --stats --threads 2 2>&1 |
  grep -E "accel:|time:|wall|rays:"
echo "== AO:16 at 1e7"
for a in bvh pkd; do
  /usr/bin/time -f "wall %e s, peak %M KB" "$B" render f1e7.f32r --accel $a --shade ao:16 --threads 2 -o "ao_$a.png" --stats 2>&1 |
    grep -E "time:|wall|throughput"
done
md5sum ao_*.png
