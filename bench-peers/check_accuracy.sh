#!/usr/bin/env bash
# bareray's primary hits against Embree's exact-sphere reference in f64 on the contract fields: ids and t per
# pixel (compare_dump.py). Fields from `bareray gen field`, contract camera, one ray per pixel centre.
# Output: results/accuracy-<UTC stamp>.txt with every command and its report.
#
# usage: check_accuracy.sh [path/to/bareray]       env: COUNTS="1e3 1e5 1e6"
set -euo pipefail
# The dump converter and the comparison read EXR images and dumps with numpy and OpenEXR: say so before any run.
python3 -c 'import numpy, OpenEXR' 2>/dev/null || {
  echo "check_accuracy.sh: python3 needs numpy and OpenEXR (a virtual environment with them first on PATH)" >&2
  exit 1
}
here="$(cd "$(dirname "$0")" && pwd)"
bareray="${1:-$here/../target/native/release/bareray}"
make -s -C "$here/embree"
mkdir -p "$here/results" "$here/out"
out="$here/results/accuracy-$(date -u +%Y-%m-%dT%H%M%SZ).txt"
cam=(--eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width 1920 --height 1080)
run() { echo "\$ $*" | sed "s#$here/##g" >> "$out"; "$@" >> "$out" 2>&1; }
echo "# $(date -u +%Y-%m-%dT%H:%M:%SZ), $("$bareray" --version | tr "\n" " "), contract camera 1920x1080" > "$out"
for n in ${COUNTS:-1e3 1e5 1e6}; do
  f="$here/out/field-$n.xyzr"
  [ -f "$f" ] || "$bareray" gen field --count "$n" -o "$f" >&2
  run "$here/embree/embree_bench" --xyzr "$f" --geometry user --user-precision f64 --api 16 --threads 2 \
    --reps 1 --build-reps 1 --dump "$here/out/ref-$n.bin"
  run "$bareray" render "$f" "${cam[@]}" --spp 1 --depth 0 --aov depth,id -q -o "$here/out/acc-$n.exr"
  run python3 "$here/aov_to_dump.py" "$here/out/acc-$n.aov.exr" "$here/out/bareray-$n.bin"
  run python3 "$here/compare_dump.py" "$here/out/ref-$n.bin" "$here/out/bareray-$n.bin"
done
echo "results: $out" >&2
