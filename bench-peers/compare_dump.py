#!/usr/bin/env python3
"""Compare two per-pixel hit dumps (t and primitive id), e.g. embree_bench --dump against bareray's AOVs.

Both inputs are BRDUMP1 files (embree_bench --dump): 8-byte magic b"BRDUMP1\\0", u32 width, u32 height
(little-endian), then width*height f32 t (inf on miss), then width*height i32 id (-1 on miss); row-major,
row 0 at the top. To compare another tracer's AOVs, load them into numpy arrays and write a BRDUMP1 with
write_dump() below (import this module), so both sides use one documented format.

Reports: pixels, id mismatches (count and per million), hit/miss disagreements, and on pixels where both
hit the same id, the max and 99.9th percentile of |t_a - t_b| / max(|t_a|, |t_b|).
Exit status 1 if --max-id-ppm or --max-rel is exceeded.
"""
import argparse
import struct
import sys

import numpy as np

MAGIC = b"BRDUMP1\0"


def read_dump(path):
    with open(path, "rb") as f:
        head = f.read(16)
        if len(head) != 16 or head[:8] != MAGIC:
            sys.exit(f"{path}: not a BRDUMP1 file")
        w, h = struct.unpack("<II", head[8:])
        t = np.fromfile(f, dtype="<f4", count=w * h)
        ids = np.fromfile(f, dtype="<i4", count=w * h)
    if t.size != w * h or ids.size != w * h:
        sys.exit(f"{path}: truncated ({w}x{h} expected)")
    return w, h, t.reshape(h, w), ids.reshape(h, w)


def write_dump(path, t, ids):
    """t: (H, W) float32 with inf on miss; ids: (H, W) int32 with -1 on miss."""
    t = np.ascontiguousarray(t, dtype="<f4")
    ids = np.ascontiguousarray(ids, dtype="<i4")
    h, w = t.shape
    with open(path, "wb") as f:
        f.write(MAGIC + struct.pack("<II", w, h))
        t.tofile(f)
        ids.tofile(f)


def checksum(ids):
    """embree_bench's checksum: FNV-1a 64 over the int32 ids' little-endian bytes, row-major."""
    h = 0xCBF29CE484222325
    for byte in np.ascontiguousarray(ids, dtype="<i4").tobytes():
        h = ((h ^ byte) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--max-id-ppm", type=float, default=None, help="fail above this many id mismatches per million")
    ap.add_argument("--max-rel", type=float, default=None, help="fail above this max relative t difference")
    ap.add_argument("--show", type=int, default=5, help="print this many mismatching pixels")
    ap.add_argument("--checksum", action="store_true", help="also print both id checksums (slow: pure Python)")
    args = ap.parse_args()

    wa, ha, ta, ia = read_dump(args.a)
    wb, hb, tb, ib = read_dump(args.b)
    if (wa, ha) != (wb, hb):
        sys.exit(f"size differs: {wa}x{ha} vs {wb}x{hb}")
    n = wa * ha
    mism = ia != ib
    nm = int(mism.sum())
    hit_a, hit_b = ia >= 0, ib >= 0
    hitmiss = int((hit_a != hit_b).sum())
    same = (ia == ib) & hit_a
    denom = np.maximum(np.abs(ta[same]), np.abs(tb[same])).astype(np.float64)
    rel = np.abs(ta[same].astype(np.float64) - tb[same].astype(np.float64)) / np.where(denom > 0, denom, 1.0)
    relmax = float(rel.max()) if rel.size else 0.0
    rel999 = float(np.quantile(rel, 0.999)) if rel.size else 0.0
    ulps = np.abs(ta[same].view(np.int32).astype(np.int64) - tb[same].view(np.int32).astype(np.int64))
    if args.checksum:
        print(f"checksum a {checksum(ia)}  b {checksum(ib)}")
    print(f"pixels {n}  hits a {int(hit_a.sum())} b {int(hit_b.sum())}")
    print(f"id mismatches {nm} ({nm / n * 1e6:.2f} per million), of which hit/miss disagreements {hitmiss}")
    print(f"t on same-id hits: max rel {relmax:.3e}, 99.9% rel {rel999:.3e}, "
          f"bit-identical {int((ulps == 0).sum())}/{int(same.sum())}, max ulps {int(ulps.max()) if ulps.size else 0}")
    if nm and args.show:
        ys, xs = np.nonzero(mism)
        for y, x in list(zip(ys, xs))[: args.show]:
            print(f"  pixel ({x},{y}): a id {ia[y, x]} t {ta[y, x]!r}   b id {ib[y, x]} t {tb[y, x]!r}")
    bad = False
    if args.max_id_ppm is not None and nm / n * 1e6 > args.max_id_ppm:
        bad = True
    if args.max_rel is not None and relmax > args.max_rel:
        bad = True
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
