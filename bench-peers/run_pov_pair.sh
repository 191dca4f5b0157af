#!/usr/bin/env bash
# POV-Ray 3.7 and one or more bareray builds on the level-4 sphereflake (1024², 1 spp, depth 5, THREADS
# threads), alternated run by run, ROUNDS rounds: on a host whose speed drifts, each round's ratio compares
# runs made seconds apart. Prints each round's wall times (ms) and per build the median POV-Ray / bareray
# ratio; writes them to results/povpair-<UTC stamp>.txt.
#
# With DROP_CACHES=1 (root) the page cache is dropped before every run and the run's files read back in, so
# each run's program text lands on fresh physical pages: on these VMs one load of a binary can run 10-15%
# slower than another load of the same bytes, for as long as its pages stay cached (docs/perf-log/2026-11.md, session 12).
#
# The header and footer give the load average and the share of CPU time the hypervisor took (steal): the ratio
# has measured 10.4-10.6x on a quiet host and 9.4-9.9x on a loaded one (docs/perf-log/2026-11.md, sessions 13-14).
#
# usage: run_pov_pair.sh path/to/bareray [more builds...]     env: ROUNDS=8 THREADS=2 DROP_CACHES=0
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ $# -ge 1 ] || { echo "usage: $0 path/to/bareray [more builds...]" >&2; exit 2; }
threads="${THREADS:-2}"
flake="$here/out/balls4.nff"; pov="$here/out/balls4.pov"
[ -f "$flake" ] || "$1" gen flake --level 4 -o "$flake" >&2
[ -f "$pov" ] || python3 "$here/nff2pov.py" "$flake" -o "$pov" --width 1024 --height 1024 --angle-mode spd \
  --max-trace-level 5 >&2
out="$here/results/povpair-$(date -u +%Y-%m-%dT%H%M%SZ).txt"
# Fresh page-cache pages for a program, its shared libraries and the inputs, read in before the clock starts.
fresh() {
  [ "${DROP_CACHES:-0}" = 1 ] || return 0
  sync; echo 1 > /proc/sys/vm/drop_caches
  cat "$1" $(ldd "$1" | awk '{for (i = 1; i <= NF; i++) if ($i ~ /^\//) print $i}') "$flake" "$pov" > /dev/null
}
# The cpu line of /proc/stat: its 8th number is the time the hypervisor gave this VM's CPUs to others (steal).
cpu_ticks() { head -1 /proc/stat | cut -d' ' -f3-; }
steal_share() {
  python3 -c "import sys; a, b = [list(map(int, x.split())) for x in sys.argv[1:]]; d = [y - x for x, y in zip(a, b)]; print(f'{100 * d[7] / max(1, sum(d)):.1f}%')" "$1" "$2"
}
ms() { local s e; s=$(date +%s%N); "$@" >/dev/null 2>&1; e=$(date +%s%N); echo $(( (e - s) / 1000000 )); }
before="$(cpu_ticks)"
{
  echo "# date: $(date -u +%Y-%m-%dT%H:%M:%SZ)  nproc: $(nproc)  cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "# drop caches before each run: ${DROP_CACHES:-0}  load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "# povray +W1024 +H1024 -A +WT$threads -D +FN; bareray render --width 1024 --height 1024 --spp 1 --depth 5 --threads $threads -q"
  for r in $(seq "${ROUNDS:-8}"); do
    fresh "$(command -v povray)"
    line="pov $(ms povray +I"$pov" +O"$here/out/balls4.pair.pov.png" +W1024 +H1024 -A +WT"$threads" -D +FN \
      File_Gamma=1.0 Display_Gamma=1.0)"
    for b in "$@"; do
      fresh "$b"
      line="$line $(basename "$b") $(ms "$b" render "$flake" -o "$here/out/balls4.pair.png" --width 1024 \
        --height 1024 --spp 1 --depth 5 --threads "$threads" -q)"
    done
    echo "$line"
  done
  echo "# load at end: $(cut -d' ' -f1-3 /proc/loadavg)  CPU time stolen by the host: $(steal_share "$before" "$(cpu_ticks)")"
} | tee "$out" | python3 -c "
import sys, statistics as st
rows = [l.split() for l in sys.stdin if not l.startswith('#')]
for k, name in enumerate(rows[0][2::2]):
    walls = [int(r[3 + 2 * k]) for r in rows]
    ratios = [int(r[1]) / w for r, w in zip(rows, walls)]
    print(f'{name}: POV-Ray / bareray median {st.median(ratios):.2f}x (min {min(ratios):.2f}, max {max(ratios):.2f});'
          f' median wall {st.median(walls)} ms, POV-Ray {st.median(int(r[1]) for r in rows)} ms')
" | tee -a "$out"
echo "results: $out" >&2
