#!/usr/bin/env bash
# A/B of two bareray builds (or two settings of one) on the contract fields and a sphereflake, alternated per
# round so both see the same machine load. Prints one line per measurement: label, scene, K, median seconds,
# Mrays/s, checksum (equal checksums: same results).
#
# usage: run_ab.sh "LABEL=/path/to/bareray [bench flags]" "LABEL=/path/to/bareray [bench flags]" ...
# env:   ROUNDS=3 REPS=5 THREADS=1 LANES=16 FIELDS="1e3 1e5 1e6" FLAKES="4" (fields and flakes from out/)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cam=(--eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width 1920 --height 1080)
echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ) nproc: $(nproc) cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
echo "# load: $(cut -d' ' -f1-3 /proc/loadavg) rounds: ${ROUNDS:-3} reps: ${REPS:-5} threads: ${THREADS:-1} lanes: ${LANES:-16}"
run() { # label bin flags... -- scene args...
  local label="$1" scene="$2"; shift 2
  "$@" --lanes "${LANES:-16}" --threads "${THREADS:-1}" --reps "${REPS:-5}" --json |
    python3 -c "import sys, json
for l in sys.stdin:
    d = json.loads(l)
    print(f\"$label $scene K={d['lanes']} {d['seconds']:.4f} s {d['mrays_per_s']:.2f} Mrays/s {d['checksum']}\")"
}
for round in $(seq 1 "${ROUNDS:-3}"); do
  for spec in "$@"; do
    label="${spec%%=*}"; read -r -a cmd <<< "${spec#*=}"
    bin="${cmd[0]}"; flags=("${cmd[@]:1}")
    for n in ${FIELDS:-1e3 1e5 1e6}; do
      run "$label" "field-$n" "$bin" bench "$here/out/field-$n.xyzr" --primary-only "${cam[@]}" "${flags[@]}"
    done
    for level in ${FLAKES:-4}; do
      run "$label" "balls$level" "$bin" bench "$here/out/balls$level.nff" --width 1024 --height 1024 "${flags[@]}"
    done
  done
done
