#!/usr/bin/env bash
# Render an NFF scene with POV-Ray 3.7 (through nff2pov.py) and Tachyon at SIZE x SIZE (default 1024),
# one sample per pixel (no antialiasing), THREADS threads (default 2), and print wall times.
#
# usage: run_pov_tachyon.sh SCENE.nff [OUTDIR]
# env:   SIZE=1024 THREADS=2 DEPTH=5 (max trace depth for both) REPS=1 (renders per tracer; all times printed)
#        ANGLE_MODE=spd|centres (nff2pov camera framing)
# Output lines (also appended to OUTDIR/times.txt):
#   tracer=<povray|tachyon> scene=<name> size=<S> threads=<T> rep=<k> wall_s=<seconds> cpu_s=<user+sys>
#   [parse_s=.. render_s=..]   (cpu_s from /usr/bin/time: robust against other load on a shared machine)
# Images: OUTDIR/<name>.pov.png, OUTDIR/<name>.tachyon.png; tools' own logs: OUTDIR/<name>.<tracer>.log
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
scene="${1:?usage: run_pov_tachyon.sh SCENE.nff [OUTDIR]}"
outdir="${2:-$here/out}"
size="${SIZE:-1024}"; threads="${THREADS:-2}"; depth="${DEPTH:-5}"; reps="${REPS:-1}"
mkdir -p "$outdir"
name="$(basename "$scene" .nff)"
pov="$outdir/$name.pov"

now() { date +%s.%N; }
cpu() { awk '{ printf "%.2f", $1 + $2 }' "$outdir/.cpu"; }
python3 "$here/nff2pov.py" "$scene" -o "$pov" --width "$size" --height "$size" \
  --angle-mode "${ANGLE_MODE:-spd}" --max-trace-level "$depth"

for k in $(seq 1 "$reps"); do
  # POV-Ray: +W/+H size, -A no antialiasing (one ray per pixel), +WT threads, -D no display, +FN PNG,
  # File_Gamma=1.0: write the linear values (as Tachyon and SPD do; POV-Ray would gamma-encode the PNG).
  t0=$(now)
  /usr/bin/time -f "%U %S" -o "$outdir/.cpu" povray +I"$pov" +O"$outdir/$name.pov.png" +W"$size" +H"$size" -A +WT"$threads" -D +FN File_Gamma=1.0 Display_Gamma=1.0 \
    >"$outdir/$name.povray.log" 2>&1
  t1=$(now)
  parse=$(grep -m1 'Parse Time:' "$outdir/$name.povray.log" | sed -E 's/.*\(\s*([0-9.]+) seconds\).*/\1/' || true)
  render=$(grep -m1 'Trace Time:' "$outdir/$name.povray.log" | sed -E 's/.*\(\s*([0-9.]+) seconds\).*/\1/' || true)
  line="tracer=povray scene=$name size=$size threads=$threads rep=$k wall_s=$(echo "$t1 - $t0" | bc) cpu_s=$(cpu) parse_s=${parse:-?} render_s=${render:-?}"
  echo "$line"; echo "$(date -u +%FT%TZ) $line" >> "$outdir/times.txt"

  # Tachyon reads NFF directly: -res size, -aasamples 0 (no supersampling), -numthreads, -raydepth,
  # -fullshade (default: shadows, reflections, refraction), PNG out.
  t0=$(now)
  /usr/bin/time -f "%U %S" -o "$outdir/.cpu" tachyon "$scene" -res "$size" "$size" -aasamples 0 -numthreads "$threads" -raydepth "$depth" -fullshade \
    -format PNG -o "$outdir/$name.tachyon.png" +V >"$outdir/$name.tachyon.log" 2>&1
  t1=$(now)
  rt=$(grep -m1 -i 'ray tracing time' "$outdir/$name.tachyon.log" | grep -oE '[0-9]+\.[0-9]+' | head -1 || true)
  line="tracer=tachyon scene=$name size=$size threads=$threads rep=$k wall_s=$(echo "$t1 - $t0" | bc) cpu_s=$(cpu) render_s=${rt:-?}"
  echo "$line"; echo "$(date -u +%FT%TZ) $line" >> "$outdir/times.txt"
done
