#!/usr/bin/env python3
"""Two bareray builds on one `bench` setting, alternated round by round: A then B in even rounds, B then A in
odd ones, so that a drift in the host's speed falls on both. Each run is `BIN bench ARGS --by-kind false`; for
every (lanes, threads) row the per-round ratio is B's median time over A's (below 1: B faster), and the script
stops if a row's checksums differ. It prints each round's ratios and, per row, the median ratio with its
quartiles and both builds' median times.

A run's time is its median of `--reps` by default. With `--min` it is the run's fastest rep instead: on a
host whose speed jumps between two levels from one moment to the next (a shared VM), the fastest of a dozen
reps lands on the fast level every time, where a median lands on either; the ratio of two minima then
resolves a few per cent that medians cannot.

usage: ab_rounds.py [--min] ROUNDS BIN_A BIN_B -- SCENE [bench options]
"""
import re
import statistics
import subprocess
import sys

ROW = re.compile(r"^\s*(scalar|\d+)\s+(\d+)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+.*\s([0-9a-f]{16})$")


def run(binary, args, column):
    """The rows of one `bench` run: (lanes, threads) to (seconds, checksum), the seconds from `column` (4: the
    fastest rep, 5: the median)."""
    out = subprocess.run([binary, "bench", *args, "--by-kind", "false"], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{binary} bench failed:\n{out.stderr}")
    rows = {}
    for line in out.stdout.splitlines():
        m = ROW.match(line)
        if m:
            rows[(m.group(1), m.group(2))] = (float(m.group(column)), m.group(7))
    return rows


def main():
    argv = sys.argv[1:]
    column = 4 if argv[:1] == ["--min"] else 5
    argv = argv[1:] if column == 4 else argv
    if len(argv) < 5 or argv[3] != "--":
        sys.exit(__doc__)
    rounds, a, b, args = int(argv[0]), argv[1], argv[2], argv[4:]
    ratios, times_a, times_b = {}, {}, {}
    for r in range(rounds):
        order = [(a, "A"), (b, "B")] if r % 2 == 0 else [(b, "B"), (a, "A")]
        res = {tag: run(binary, args, column) for binary, tag in order}
        for k, (seconds_a, sum_a) in res["A"].items():
            if k not in res["B"]:
                continue
            seconds_b, sum_b = res["B"][k]
            if sum_a != sum_b:
                sys.exit(f"lanes {k[0]} threads {k[1]}: checksums differ, {sum_a} against {sum_b}")
            ratios.setdefault(k, []).append(seconds_b / seconds_a)
            times_a.setdefault(k, []).append(seconds_a)
            times_b.setdefault(k, []).append(seconds_b)
        print(f"round {r}", " ".join(f"{k[0]}x{k[1]}:{v[-1]:.3f}" for k, v in ratios.items()), flush=True)
    for k, v in ratios.items():
        v = sorted(v)
        q = statistics.quantiles(v, n=4) if len(v) >= 4 else (v[0], 0, v[-1])
        print(f"lanes {k[0]} threads {k[1]}: B/A time median {statistics.median(v):.3f} (q1 {q[0]:.3f}, q3 "
              f"{q[2]:.3f}, min {v[0]:.3f}, max {v[-1]:.3f}); A median {statistics.median(times_a[k]):.4f} s, "
              f"B median {statistics.median(times_b[k]):.4f} s, checksum same")


if __name__ == "__main__":
    main()
