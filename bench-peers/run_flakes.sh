#!/usr/bin/env bash
# SPD sphereflakes (bareray gen flake) at levels LEVELS, 1024², 1 sample per pixel, depth 5, THREADS threads:
# POV-Ray 3.7 (via nff2pov.py) and Tachyon through run_pov_tachyon.sh, then bareray render, REPS runs each,
# interleaved per level. Wall and CPU times go to results/flakes-<UTC stamp>/times.txt (one line per run),
# with a header of date, machine, load and commands; images to out/. bareray's lines also hold its own split
# (parse, build, and tracing with the streamed PNG, from its summary line) and its peak RSS in MB.
#
# usage: run_flakes.sh [path/to/bareray]       env: LEVELS="4 5 6" REPS=3 THREADS=2 SIZE=1024 LANES=16
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bareray="${1:-$here/../target/native/release/bareray}"
stamp="$(date -u +%Y-%m-%dT%H%M%SZ)"
res="$here/results/flakes-$stamp"
mkdir -p "$res" "$here/out"
size="${SIZE:-1024}"; threads="${THREADS:-2}"; reps="${REPS:-3}"; lanes="${LANES:-16}"
{
  echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ)  host: $(uname -srm)  nproc: $(nproc)"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "# povray: $(povray --version 2>&1 | head -1)  tachyon: $(dpkg-query -W -f='${Version}' tachyon-bin-nox 2>/dev/null)"
  echo "# bareray: $("$bareray" --version | tr "\n" " "); render FLAKE -o out/FLAKE.bareray.png --width $size --height $size --spp 1 --depth 5 --threads $threads --lanes $lanes (its summary line kept)"
  echo "# peers: SIZE=$size THREADS=$threads DEPTH=5 REPS=$reps run_pov_tachyon.sh FLAKE out"
} > "$res/times.txt"
for level in ${LEVELS:-4 5 6}; do
  flake="$here/out/balls$level.nff"
  [ -f "$flake" ] || "$bareray" gen flake --level "$level" -o "$flake" >&2
  echo "# level $level: load $(cut -d' ' -f1-3 /proc/loadavg)" >> "$res/times.txt"
  SIZE="$size" THREADS="$threads" DEPTH=5 REPS="$reps" "$here/run_pov_tachyon.sh" "$flake" "$here/out" \
    | tee -a "$res/times.txt"
  for k in $(seq 1 "$reps"); do
    t0=$(date +%s.%N)
    /usr/bin/time -f "%U %S %M" -o "$res/.cpu" "$bareray" render "$flake" -o "$here/out/balls$level.bareray.png" \
      --width "$size" --height "$size" --spp 1 --depth 5 --threads "$threads" --lanes "$lanes" > "$res/.line"
    t1=$(date +%s.%N)
    # The summary line: "FILE: WxH in R s (parse P s, build B s); ..." (R: tracing and the streamed PNG).
    split=$(sed -n 's/.* in \([0-9.]*\) s (parse \([0-9.]*\) s, build \([0-9.]*\) s).*/render_s=\1 parse_s=\2 build_s=\3/p' "$res/.line")
    line="tracer=bareray scene=balls$level size=$size threads=$threads rep=$k wall_s=$(echo "$t1 - $t0" | bc) cpu_s=$(awk '{printf "%.2f", $1 + $2}' "$res/.cpu") $split peak_mb=$(awk '{printf "%.0f", $3 / 1024}' "$res/.cpu")"
    echo "$line" | tee -a "$res/times.txt"
  done
done
rm -f "$res/.cpu" "$res/.line"
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$res/times.txt"
echo "results: $res/times.txt" >&2
