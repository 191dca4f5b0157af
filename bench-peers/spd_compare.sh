#!/usr/bin/env bash
# bareray against POV-Ray 3.7 on Eric Haines' SPD scenes: framing/visibility agreement, mean absolute
# difference and wall times. POV-Ray renders SPD's own POV-Ray output of each scene (not our nff2pov.py), so
# it is an independent reference for framing and visibility; bareray renders SPD's NFF output of the same scene.
#
# 1. Build SPD's generators and write the scenes (once):
#      SPD_DIR=$HOME/spd bench-peers/spd_compare.sh setup SPD_SRC
#    SPD_SRC is a checkout of https://github.com/erich666/StandardProceduralDatabases (the directory holding
#    src/makefile) or a bare git directory of it (exported with `git archive HEAD`). The sources go to
#    $SPD_DIR/src and are built with SPD's own makefile. They call MSVC's sscanf_s/sprintf_s/fopen_s, so the
#    build force-includes $SPD_DIR/spd_compat.h, which maps them onto sscanf/snprintf/fopen:
#      make CC="cc -O -w -include $SPD_DIR/spd_compat.h" balls gears ...
#    Each scene goes to $SPD_DIR/scenes/NAME/: `GEN -s $SPD_S -r 1 > NAME.nff` (NFF) and `GEN -s $SPD_S -r 4 >
#    NAME.pov` (SPD's "POV-Ray 3.1" output; sombrero's writes its height field to hf000.tga beside it).
#    $SPD_DIR/scenes/entities.txt lists the NFF entities of each scene.
# 2. Compare:
#      SPD_DIR=$HOME/spd bench-peers/spd_compare.sh path/to/bareray [SIZE]
#    For each scene, at SIZE x SIZE (default 256), one sample per pixel, THREADS threads (default 2):
#      * POV-Ray: SPD's .pov with `#version 3.7; global_settings { assumed_gamma 1.0 }` put in front (SPD
#        writes neither; without them POV-Ray 3.7 warns and falls back to 3.62 compatibility with gamma
#        correction off, which gives the same pixels on balls), rendered with
#        `povray +W +H -A +WT -D +FN File_Gamma=1.0 Display_Gamma=1.0 +L<scene dir>` (no antialiasing, the PNG
#        holds the scene's values unencoded, as NFF renders do; max_trace_level stays POV-Ray's default 5).
#      * bareray: `BIN render NAME.nff -o OUT --width S --height S --spp 1 --depth 5 --threads T -q`
#        (NFF's default linear transfer).
#      * spd_compare.py: visibility agreement against the NFF `b` colour (tolerance TOL, default 3 of 255),
#        per-channel mean absolute difference, and a side-by-side PNG (POV-Ray | bareray | mask | coverage
#        mask; white both, red POV-Ray only, green bareray only).
#      * a coverage pass, untimed: POV-Ray again at +Q0 (flat quick colours, no transmitted/reflected rays,
#        so a glass object is opaque) against bareray's `--aov id` (primary hit or miss): the geometric
#        visibility, which the colour test cannot see where a clear object shows the background through it.
#      * with NFF2POV=1 (default), coverage also against POV-Ray +Q0 on nff2pov.py's conversion of the NFF
#        (n2p_cov_agree), and pov_degenerate, the number of triangles POV-Ray reported as degenerate and
#        never intersects: zero-area ones, and smooth_triangles whose three vertex normals are not all on one
#        side of the face (POV-Ray's Compute_Smooth_Triangle). SPD's teapot has 16 such at -s 2.
#    Known reference problem: SPD's sombrero writes different geometry to its two outputs. The NFF
#    polygons have y = -4 + h (h in [-1, 1], libply.c lib_output_polygon_height ignores y1), the POV-Ray
#    height_field maps h onto y in [-3, 3] (libpr3.c). Its POV-Ray image is not a reference for the NFF.
#    A scene that fails in either tracer gets status pov_failed / bareray_failed / both_failed and the first
#    line of the error.
#    NFF carries no ambient coefficient; SPD's generators pass one to their POV-Ray output. With SPD_AMBIENT=1
#    bareray gets the generator's values through `--ambient` (spd_ambient below, read from each generator's
#    lib_output_color calls, in the order of the NFF's `f` lines); without it, NFF's default 0.1. lattice
#    mixes 0 and 0.1 over 81 fills and keeps the default.
# env: SPD_DIR (required), SPD_S=2 (generator size factor, setup), SCENES="balls gears ..." (subset),
#      THREADS=2, TOL=3, OUT=$SPD_DIR/out, NFF2POV=1, SPD_AMBIENT=0
# Output: one line per scene on stdout and in $OUT/results.txt, the markdown table $OUT/results.md,
#         images $OUT/NAME.pov.png, NAME.bareray.png, NAME.side.png, logs NAME.povray.log, NAME.bareray.log.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
all_scenes="balls gears mount rings teapot tetra tree shells jacks lattice sombrero"
scenes="${SCENES:-$all_scenes}"
: "${SPD_DIR:?set SPD_DIR to the directory for the SPD build and scenes (see the header of $0)}"
[ $# -ge 1 ] || { echo "usage: SPD_DIR=DIR $0 setup SPD_SRC | SPD_DIR=DIR $0 BARERAY [SIZE]" >&2; exit 2; }

if [ "$1" = setup ]; then
  src="${2:?usage: SPD_DIR=DIR $0 setup SPD_SRC (checkout or bare git dir)}"
  mkdir -p "$SPD_DIR/src" "$SPD_DIR/scenes"
  if [ -f "$src/src/makefile" ]; then
    cp -r "$src/src/." "$SPD_DIR/src/"
  else
    git --git-dir="$src" archive HEAD src | tar -x -C "$SPD_DIR"
  fi
  cat > "$SPD_DIR/spd_compat.h" <<'EOF'
/* MSVC's bounds-checked calls used by SPD, mapped onto C99 (force-included by spd_compare.sh setup) */
#include <stdio.h>
#define sscanf_s sscanf
#define sprintf_s snprintf
#define fopen_s(pf, name, mode) ((*(pf) = fopen((name), (mode))) == NULL)
EOF
  make -C "$SPD_DIR/src" CC="cc -O -w -include $SPD_DIR/spd_compat.h" $all_scenes >/dev/null
  : > "$SPD_DIR/scenes/entities.txt"
  for s in $scenes; do
    d="$SPD_DIR/scenes/$s"; mkdir -p "$d"
    (cd "$d" && "$SPD_DIR/src/$s" -s "${SPD_S:-2}" -r 1 > "$s.nff" && "$SPD_DIR/src/$s" -s "${SPD_S:-2}" -r 4 > "$s.pov")
    # NFF entity counts: the keyword lines (vertex lines start with a number)
    ents=$(awk '$1 ~ /^(b|l|f|s|p|pp|c|v)$/ { n[$1]++ } END { for (k in n) printf "%s:%d,", k, n[k] }' "$d/$s.nff")
    echo "$s -s ${SPD_S:-2}: ${ents%,}" | tee -a "$SPD_DIR/scenes/entities.txt"
  done
  exit 0
fi

# The ambient coefficients SPD's generators give their materials (0.1: jacks and sombrero; 0.2: balls' floor).
spd_ambient() {
  case "$1" in
    balls) echo 0.2,0 ;;
    jacks|sombrero) echo 0.1 ;;
    lattice) ;;
    *) echo 0 ;;
  esac
}

bin="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
size="${2:-256}"; threads="${THREADS:-2}"; tol="${TOL:-3}"
out="${OUT:-$SPD_DIR/out}"; mkdir -p "$out"
res="$out/results.txt"
now() { date +%s.%N; }
secs() { printf "%.3f" "$(echo "$2 - $1" | bc)"; }
{
  echo "# $(date -u +%Y-%m-%dT%H:%M:%SZ)  nproc $(nproc)  $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "# bareray: $bin  size ${size}x$size  threads $threads  tolerance $tol  SPD_DIR $SPD_DIR"
  echo "# povray +W$size +H$size -A +WT$threads -D +FN File_Gamma=1.0 Display_Gamma=1.0 on SPD's -r 4 output with #version 3.7 and assumed_gamma 1.0 in front; bareray render --spp 1 --depth 5, SPD_AMBIENT=${SPD_AMBIENT:-0}"
} > "$res"
cat "$res"
for s in $scenes; do
  d="$SPD_DIR/scenes/$s"
  if [ ! -f "$d/$s.nff" ] || [ ! -f "$d/$s.pov" ]; then
    echo "scene=$s status=missing error=no $d/$s.nff or .pov: run '$0 setup SPD_SRC' first" | tee -a "$res"; continue
  fi
  ents=$(awk '$1 ~ /^(s|p|pp|c)$/ { n[$1]++ } END { for (k in n) printf "%s:%d,", k, n[k] }' "$d/$s.nff")
  { printf '#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n'; cat "$d/$s.pov"; } > "$out/$s.pov"
  pov_err=""; br_err=""
  amb=(); a="$(spd_ambient "$s")"
  [ "${SPD_AMBIENT:-0}" = 1 ] && [ -n "$a" ] && amb=(--ambient "$a")
  t0=$(now)
  if ! povray +I"$out/$s.pov" +O"$out/$s.pov.png" +W"$size" +H"$size" -A +WT"$threads" -D +FN \
      File_Gamma=1.0 Display_Gamma=1.0 +L"$d" >"$out/$s.povray.log" 2>&1; then
    pov_err=$(grep -m1 -E 'Error' "$out/$s.povray.log" || tail -n1 "$out/$s.povray.log")
  fi
  t1=$(now)
  if ! "$bin" render "$d/$s.nff" -o "$out/$s.bareray.png" --width "$size" --height "$size" --spp 1 --depth 5 \
      --threads "$threads" "${amb[@]}" -q >"$out/$s.bareray.log" 2>&1; then
    br_err=$(grep -m1 -v '^\s*$' "$out/$s.bareray.log" || echo "exit status non-zero, no message")
  fi
  t2=$(now)
  line="scene=$s ents=${ents%,} pov_s=$(secs "$t0" "$t1") br_s=$(secs "$t1" "$t2")"
  if [ -n "$pov_err" ] && [ -n "$br_err" ]; then
    line="$line status=both_failed error=povray: $pov_err / bareray: $br_err"
  elif [ -n "$pov_err" ]; then
    line="$line status=pov_failed error=$pov_err"
  elif [ -n "$br_err" ]; then
    line="$line status=bareray_failed error=$br_err"
  else
    # Coverage pass (untimed): POV-Ray at +Q0 (flat quick colours, no transmitted rays: glass is opaque) and
    # bareray's primary-hit ids, so that visibility is also compared where shading makes an object look like
    # the background (a clear sphere showing the background through it).
    cov=()
    if povray +I"$out/$s.pov" +O"$out/$s.cov.pov.png" +W"$size" +H"$size" -A +Q0 +WT"$threads" -D +FN \
         File_Gamma=1.0 Display_Gamma=1.0 +L"$d" >"$out/$s.cov.povray.log" 2>&1 &&
       "$bin" render "$d/$s.nff" -o "$out/$s.cov.png" --width "$size" --height "$size" --spp 1 --depth 5 \
         --threads "$threads" --aov id -q >"$out/$s.cov.bareray.log" 2>&1; then
      cov=(--cov "$out/$s.cov.pov.png" "$out/$s.cov.aov.exr")
    fi
    cmp=$(python3 "$here/spd_compare.py" compare "$out/$s.pov.png" "$out/$s.bareray.png" "$d/$s.nff" \
      --tol "$tol" --side "$out/$s.side.png" "${cov[@]}") || true
    # Second opinion on coverage (NFF2POV=1, the default): POV-Ray +Q0 on nff2pov.py's conversion of the same
    # NFF, for scenes whose SPD POV-Ray output describes other geometry than its NFF (sombrero).
    if [ "${NFF2POV:-1}" = 1 ] && [ ${#cov[@]} -gt 0 ] &&
       python3 "$here/nff2pov.py" "$d/$s.nff" -o "$out/$s.nff2pov.pov" --width "$size" --height "$size" \
         --angle-mode spd --max-trace-level 5 >/dev/null 2>&1 &&
       povray +I"$out/$s.nff2pov.pov" +O"$out/$s.nff2pov.cov.png" +W"$size" +H"$size" -A +Q0 +WT"$threads" -D \
         +FN File_Gamma=1.0 Display_Gamma=1.0 >"$out/$s.nff2pov.povray.log" 2>&1; then
      n2p=$(python3 "$here/spd_compare.py" compare "$out/$s.nff2pov.cov.png" "$out/$s.bareray.png" "$d/$s.nff" \
        --tol "$tol" --cov "$out/$s.nff2pov.cov.png" "$out/$s.cov.aov.exr" | grep -oE 'cov_agree=[0-9.]+') || true
      [ -n "$n2p" ] && cmp="$cmp n2p_$n2p"
    fi
    # POV-Ray never intersects a triangle it calls degenerate: zero area, or a smooth_triangle whose vertex
    # normals do not all lie on one side of its face (core/shape/triangle.cpp, Compute_Smooth_Triangle).
    cmp="$cmp pov_degenerate=$(grep -c 'Degenerate triangle' "$out/$s.povray.log" || true)"
    case "$cmp" in
      vis_agree=*) line="$line status=ok $cmp" ;;
      *) line="$line status=compare_failed error=${cmp:-spd_compare.py failed}" ;;
    esac
  fi
  echo "$line" | tr -d '\r' | tee -a "$res"
done
python3 "$here/spd_compare.py" table "$res" "$out/results.md"
echo "table: $out/results.md" >&2
