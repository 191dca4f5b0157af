#!/usr/bin/env python3
"""Compare a POV-Ray render and a bareray render of one SPD scene (helper of spd_compare.sh).

usage:
  spd_compare.py compare POV.png BARERAY.png SCENE.nff [--tol T] [--side SIDE.png] [--cov POV_Q0.png AOV.exr]
      Prints one line of key=value fields:
        vis_agree   fraction of pixels where both images agree on background vs object. A pixel is background
                    when every channel is within T (default 3, of 0..255) of the NFF `b` colour x 255.
        pov_only    fraction of pixels that are object in POV-Ray's image but background in bareray's
                    (bareray misses something there), br_only the reverse
        bg_pov, bg_br  background fraction of each image (a scene with no background visible makes
                    vis_agree trivially 1)
        mad_r, mad_g, mad_b  mean absolute difference per channel, 0..255
      --cov: geometric coverage, independent of shading. POV_Q0.png is POV-Ray's +Q0 render (quick colours:
        flat pigment colours, no transmitted, reflected or refracted rays, so glass is opaque), read against
        the background colour as above; AOV.exr is bareray's `--aov id` output (id -1 or 0xFFFFFFFF: the
        primary ray missed). Adds cov_agree (fraction of pixels where both agree on hit vs miss),
        cov_pov_only, cov_br_only. Needs the OpenEXR module; without it prints cov=n/a.
      --side writes POV-Ray | bareray | mask (white: both object, black: both background, red: object only
      in POV-Ray's image, green: object only in bareray's) as one PNG; with --cov a fourth panel, the same
      mask for coverage.
  spd_compare.py table LINES.txt OUT.md
      Turns spd_compare.sh's result lines (key=value fields) into a markdown table.
"""
import sys

import numpy as np
from PIL import Image


def nff_background(path):
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "b":
                return np.array([float(x) for x in t[1:4]])
    return np.zeros(3)  # NFF's default background is black


def load(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int32)


def bareray_hits(exr):
    import OpenEXR
    ids = np.asarray(OpenEXR.File(exr).channels()["id"].pixels).astype(np.int64)
    return (ids != -1) & (ids != 0xFFFFFFFF)


def mask_image(oa, ob):
    m = np.zeros(oa.shape + (3,), np.int32)
    m[oa & ob] = 255
    m[oa & ~ob] = (255, 0, 0)
    m[ob & ~oa] = (0, 255, 0)
    return m


def compare(argv):
    tol, side, cov, pos = 3, None, None, []
    i = 0
    while i < len(argv):
        if argv[i] == "--cov":
            cov = (argv[i + 1], argv[i + 2]); i += 3
        elif argv[i] == "--tol":
            tol = float(argv[i + 1]); i += 2
        elif argv[i] == "--side":
            side = argv[i + 1]; i += 2
        else:
            pos.append(argv[i]); i += 1
    pov_png, br_png, nff = pos
    a, b = load(pov_png), load(br_png)
    if a.shape != b.shape:
        print(f"error=size_mismatch pov={a.shape[1]}x{a.shape[0]} bareray={b.shape[1]}x{b.shape[0]}")
        return 1
    bg = np.rint(nff_background(nff) * 255)
    oa = np.abs(a - bg).max(axis=2) > tol  # object (not background) in POV-Ray's image
    ob = np.abs(b - bg).max(axis=2) > tol
    mad = np.abs(a - b).mean(axis=(0, 1))
    print(f"vis_agree={(oa == ob).mean():.5f} pov_only={(oa & ~ob).mean():.5f} br_only={(ob & ~oa).mean():.5f} "
          f"bg_pov={(~oa).mean():.4f} bg_br={(~ob).mean():.4f} "
          f"mad_r={mad[0]:.2f} mad_g={mad[1]:.2f} mad_b={mad[2]:.2f}", end="")
    panels = [a, b, mask_image(oa, ob)]
    if cov:
        try:
            hb = bareray_hits(cov[1])
        except ImportError:
            print(" cov=n/a", end="")
        else:
            ha = np.abs(load(cov[0]) - bg).max(axis=2) > tol
            print(f" cov_agree={(ha == hb).mean():.5f} cov_pov_only={(ha & ~hb).mean():.5f} "
                  f"cov_br_only={(hb & ~ha).mean():.5f}", end="")
            panels.append(mask_image(ha, hb))
    print()
    if side:
        gap = np.full((a.shape[0], 4, 3), 128, np.int32)
        row = [panels[0]]
        for p in panels[1:]:
            row += [gap, p]
        Image.fromarray(np.concatenate(row, axis=1).astype(np.uint8)).save(side)
    return 0


def table(argv):
    src, out = argv
    cols = [("scene", "scene"), ("ents", "NFF primitives"), ("status", "status"), ("vis_agree", "visibility agreement"),
            ("pov_only", "object only in POV-Ray"), ("br_only", "object only in bareray"),
            ("cov_agree", "coverage agreement"), ("cov_pov_only", "hit only in POV-Ray"),
            ("cov_br_only", "hit only in bareray"), ("n2p_cov_agree", "coverage vs POV-Ray on nff2pov"),
            ("pov_degenerate", "POV-Ray degenerate triangles"),
            ("bg_pov", "background (POV-Ray)"), ("bg_br", "background (bareray)"),
            ("mad", "mean abs diff R,G,B (0..255)"), ("pov_s", "POV-Ray wall s"), ("br_s", "bareray wall s"),
            ("error", "error (first line)")]
    rows = []
    for line in open(src):
        if line.startswith("#") or not line.strip():
            continue
        f = {}
        head = line.split(" error=", 1)[0]
        for tok in head.split(" "):
            k, sep, v = tok.partition("=")
            if sep and k in ("scene", "ents", "status", "vis_agree", "pov_only", "br_only", "bg_pov", "bg_br", "mad_r",
                             "mad_g", "mad_b", "pov_s", "br_s", "cov_agree", "cov_pov_only", "cov_br_only",
                             "n2p_cov_agree", "pov_degenerate"):
                f[k] = v.strip()
        if " error=" in line:  # the error text runs to the end of the line
            f["error"] = line.split(" error=", 1)[1].strip().replace("|", "\\|")
        if "mad_r" in f:
            f["mad"] = f"{f['mad_r']}, {f['mad_g']}, {f['mad_b']}"
        for k in ("vis_agree", "cov_agree", "n2p_cov_agree"):
            if k in f:
                f[k] = f"{100 * float(f[k]):.2f}%"
        rows.append(f)
    with open(out, "w") as o:
        header = [line for line in open(src) if line.startswith("#")]
        for h in header:
            o.write(h[1:].strip() + "  \n")
        o.write("\n| " + " | ".join(c[1] for c in cols) + " |\n")
        o.write("|" + " --- |" * len(cols) + "\n")
        for f in rows:
            o.write("| " + " | ".join(f.get(c[0], "") for c in cols) + " |\n")
    return 0


if __name__ == "__main__":
    cmd, rest = sys.argv[1], sys.argv[2:]
    sys.exit({"compare": compare, "table": table}[cmd](rest))
