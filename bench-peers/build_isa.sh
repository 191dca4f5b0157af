#!/usr/bin/env bash
# Builds the same source for x86-64-v2, v3 and v4 (or the levels given), one release build per level in a
# target directory of its own, so that no build recompiles another: target/isa/<level>/release/bareray,
# which `bareray bench --isa v2,v3,v4 SCENE` runs side by side. Each level is the cargo alias
# `cargo build-<level>` of .cargo/config.toml; this script runs them one after another from the repository
# root. `RUSTFLAGS` would replace every alias's `-C target-cpu` and make the builds identical, so it is
# cleared (extra cargo flags such as --locked can go in CARGO_FLAGS).
#
# usage: bench-peers/build_isa.sh [v2] [v3] [v4]     (default: all three)
set -euo pipefail
cd "$(dirname "$0")/.."
levels=("$@")
[ ${#levels[@]} -gt 0 ] || levels=(v2 v3 v4)
for level in "${levels[@]}"; do
  case "$level" in
    v2|v3|v4) ;;
    *) echo "error: unknown level '$level' (expected v2, v3 or v4)" >&2; exit 2 ;;
  esac
done
if [ -n "${RUSTFLAGS:-}" ]; then
  echo "note: RUSTFLAGS ('$RUSTFLAGS') is ignored here: it would replace each level's -C target-cpu" >&2
fi
# The features each level needs, as `bench --isa` checks them (src/cpu.rs, X86_64_V2/V3/V4, each level
# including the ones below it), in /proc/cpuinfo's names (pni is sse3, cx16 cmpxchg16b, abm lzcnt). A level
# this CPU lacks is skipped: its build scripts are compiled for the level too, so they would stop at an
# illegal instruction, and `bench --isa` skips that level on this CPU anyway.
v2_needs="pni ssse3 sse4_1 sse4_2 popcnt cx16"
v3_needs="$v2_needs avx avx2 fma bmi1 bmi2 abm movbe f16c"
v4_needs="$v3_needs avx512f avx512bw avx512cd avx512dq avx512vl"
needs() {
  case "$1" in
    v2) echo "$v2_needs" ;;
    v3) echo "$v3_needs" ;;
    v4) echo "$v4_needs" ;;
  esac
}
for level in "${levels[@]}"; do
  if [ -r /proc/cpuinfo ]; then
    flags=" $(grep -m1 '^flags' /proc/cpuinfo | cut -d: -f2) "
    lacks=$(for f in $(needs "$level"); do [[ "$flags" == *" $f "* ]] || printf ' %s' "$f"; done)
    if [ -n "$lacks" ]; then
      echo "note: x86-64-$level skipped: this CPU lacks$lacks, so the level's build scripts would not run here" >&2
      continue
    fi
  fi
  echo "== cargo build-$level -> target/isa/$level/release/bareray" >&2
  # shellcheck disable=SC2086
  env -u RUSTFLAGS cargo "build-$level" ${CARGO_FLAGS:-}
done
