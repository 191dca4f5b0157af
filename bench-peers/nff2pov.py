#!/usr/bin/env python3
"""Convert an NFF (Eric Haines' SPD Neutral File Format) scene to a POV-Ray 3.7 scene.

usage: nff2pov.py IN.nff [-o OUT.pov] [--width W --height H] [--angle-mode spd|centres] [--max-trace-level D]

Mapping (written for bareray's peer benchmarks; see README.md):
  v (from/at/up/angle/hither/resolution)
      camera { perspective location <from> sky <up> up y right -x*W/H angle A look_at <at> }
      'right -x' makes POV-Ray's left-handed camera render NFF's right-handed world unmirrored.
      --angle-mode spd (default): A = NFF angle as the full horizontal angle edge to edge, i.e. the image
        half-width is tan(angle/2), as SPD's own POV-Ray output and its reference images do.
      --angle-mode centres: NFF.TXT's literal definition (angle between the centres of the extreme pixel
        columns): half-width = tan(angle/2) * W/(W-1).
      hither is ignored (POV-Ray has no near clipping plane).
  b r g b          background { rgb <r,g,b> }
  l x y z [r g b]  light_source { <x,y,z> rgb C }; without a colour C = 1/sqrt(number of lights)
  f r g b Kd Ks shine T ior
      material { texture { pigment { rgb <r,g,b> transmit T }
                           finish { ambient 0 diffuse Kd phong Ks phong_size shine reflection Ks } }
                 interior { ior ior } }          (Ks is the Whitted reflection weight, as in SPD)
  s x y z r        sphere { <x,y,z>, r }
  p n + n vertices polygon { n+1, v1, ..., vn, v1 }
  pp n + n (vertex, normal) lines   smooth_triangle fan (convex patches assumed)
  c base r0 apex r1                 cone { <base>, r0, <apex>, r1 open }
Every object gets the material of the last 'f' before it. '#' lines are comments.
Anything unreadable is an error naming the line number.
"""
import argparse
import math
import sys


class NffError(Exception):
    pass


class Reader:
    """Token stream over an NFF file that remembers line numbers."""

    def __init__(self, path):
        self.path = path
        self.toks = []  # (token, line)
        with open(path) as f:
            for no, line in enumerate(f, 1):
                s = line.strip()
                if not s or s.startswith("#"):
                    continue
                for t in s.split():
                    self.toks.append((t, no))
        self.i = 0

    def eof(self):
        return self.i >= len(self.toks)

    def line(self):
        return self.toks[min(self.i, len(self.toks) - 1)][1] if self.toks else 0

    def err(self, msg, line=None):
        return NffError(f"{self.path}:{line if line is not None else self.line()}: {msg}")

    def word(self):
        if self.eof():
            raise self.err("unexpected end of file")
        t, _ = self.toks[self.i]
        self.i += 1
        return t

    def peek(self):
        return None if self.eof() else self.toks[self.i][0]

    def num(self, what):
        line = self.line()
        t = self.word()
        try:
            v = float(t)
        except ValueError:
            raise self.err(f"expected a number for {what}, got '{t}'", line)
        if not math.isfinite(v):
            raise self.err(f"{what} is not finite: '{t}'", line)
        return v

    def vec(self, what):
        return (self.num(what), self.num(what), self.num(what))

    def is_number(self, t):
        try:
            float(t)
            return True
        except (TypeError, ValueError):
            return False


def parse(path):
    r = Reader(path)
    scene = {
        "view": None,
        "background": (0.0, 0.0, 0.0),
        "lights": [],
        "fills": [],
        "objects": [],  # (kind, fill_index, data)
    }
    fill = -1
    while not r.eof():
        line = r.line()
        cmd = r.word()
        if cmd == "v":
            view = {}
            for key in ("from", "at", "up", "angle", "hither", "resolution"):
                kl = r.line()
                k = r.word()
                if k != key:
                    raise r.err(f"view: expected '{key}', got '{k}'", kl)
                if key in ("from", "at", "up"):
                    view[key] = r.vec(key)
                elif key == "resolution":
                    w, h = r.num("resolution"), r.num("resolution")
                    if w < 1 or h < 1 or w != int(w) or h != int(h):
                        raise r.err("resolution must be two positive integers", kl)
                    view[key] = (int(w), int(h))
                else:
                    view[key] = r.num(key)
            if not (0 < view["angle"] < 180):
                raise r.err(f"view angle must be in (0, 180), got {view['angle']}", line)
            scene["view"] = view
        elif cmd == "b":
            scene["background"] = r.vec("background colour")
        elif cmd == "l":
            pos = r.vec("light position")
            col = None
            # Optional colour: three more numbers on the same line.
            if r.peek() is not None and r.is_number(r.peek()) and r.toks[r.i][1] == line:
                col = r.vec("light colour")
            scene["lights"].append((pos, col))
        elif cmd == "f":
            vals = [r.num("fill") for _ in range(8)]
            scene["fills"].append(vals)
            fill = len(scene["fills"]) - 1
        elif cmd in ("s", "p", "pp", "c"):
            if fill < 0:
                raise r.err(f"'{cmd}' before any 'f' fill", line)
            if cmd == "s":
                c = r.vec("sphere centre")
                rad = r.num("sphere radius")
                if not rad > 0:
                    raise r.err(f"sphere radius must be positive, got {rad}", line)
                scene["objects"].append(("s", fill, (c, rad)))
            elif cmd == "p":
                n = r.num("polygon vertex count")
                if n < 3 or n != int(n):
                    raise r.err("polygon needs an integer count >= 3", line)
                verts = [r.vec("polygon vertex") for _ in range(int(n))]
                scene["objects"].append(("p", fill, verts))
            elif cmd == "pp":
                n = r.num("patch vertex count")
                if n < 3 or n != int(n):
                    raise r.err("polygonal patch needs an integer count >= 3", line)
                verts = []
                for _ in range(int(n)):
                    verts.append((r.vec("patch vertex"), r.vec("patch normal")))
                scene["objects"].append(("pp", fill, verts))
            else:
                b, br = r.vec("cone base"), r.num("cone base radius")
                a, ar = r.vec("cone apex"), r.num("cone apex radius")
                scene["objects"].append(("c", fill, (b, br, a, ar)))
        else:
            raise r.err(f"unknown or unsupported NFF entity '{cmd}'", line)
    if scene["view"] is None:
        raise NffError(f"{path}: no 'v' view entity")
    return scene


def fmt(x):
    return repr(float(x)) if abs(x) >= 1e-4 or x == 0 else f"{x:.9g}"


def v3(v):
    return f"<{fmt(v[0])},{fmt(v[1])},{fmt(v[2])}>"


def write_pov(scene, out, width, height, angle_mode, max_trace):
    view = scene["view"]
    w = width or view["resolution"][0]
    h = height or view["resolution"][1]
    half = math.tan(math.radians(view["angle"]) / 2)
    if angle_mode == "centres" and w > 1:
        half *= w / (w - 1)
    angle = math.degrees(2 * math.atan(half))
    p = out.write
    p("// Generated by bareray bench-peers/nff2pov.py\n")
    p(f"// camera framing: --angle-mode {angle_mode}, horizontal angle {angle:.9g} deg, aspect {w}x{h}\n")
    p(f"#version 3.7;\nglobal_settings {{ assumed_gamma 1.0 max_trace_level {max_trace} }}\n")
    p(f"background {{ rgb {v3(scene['background'])} }}\n")
    p("camera {\n  perspective\n")
    p(f"  location {v3(view['from'])}\n  sky {v3(view['up'])}\n")
    p(f"  up <0,1,0>\n  right <{fmt(-w / h)},0,0>\n  angle {angle!r}\n")
    p(f"  look_at {v3(view['at'])}\n}}\n")
    nl = len(scene["lights"])
    for pos, col in scene["lights"]:
        if col is None:
            c = 1.0 / math.sqrt(nl)
            col = (c, c, c)
        p(f"light_source {{ {v3(pos)} rgb {v3(col)} }}\n")
    for k, (r_, g, b, kd, ks, shine, t, ior) in enumerate(scene["fills"]):
        p(f"#declare F{k} = material {{\n  texture {{\n")
        p(f"    pigment {{ rgb <{fmt(r_)},{fmt(g)},{fmt(b)}> transmit {fmt(t)} }}\n")
        p(f"    finish {{ ambient 0 diffuse {fmt(kd)} phong {fmt(ks)} phong_size {fmt(max(shine, 1e-6))} "
          f"reflection {fmt(ks)} }}\n  }}\n")
        p(f"  interior {{ ior {fmt(ior if ior > 0 else 1.0)} }}\n}}\n")
    for kind, fill, d in scene["objects"]:
        m = f"material {{ F{fill} }}"
        if kind == "s":
            p(f"sphere {{ {v3(d[0])}, {fmt(d[1])} {m} }}\n")
        elif kind == "p":
            pts = ", ".join(v3(v) for v in d + [d[0]])
            p(f"polygon {{ {len(d) + 1}, {pts} {m} }}\n")
        elif kind == "pp":
            for i in range(1, len(d) - 1):
                a, b, c = d[0], d[i], d[i + 1]
                p(f"smooth_triangle {{ {v3(a[0])}, {v3(a[1])}, {v3(b[0])}, {v3(b[1])}, "
                  f"{v3(c[0])}, {v3(c[1])} {m} }}\n")
        else:
            b, br, a, ar = d
            p(f"cone {{ {v3(b)}, {fmt(br)}, {v3(a)}, {fmt(ar)} open {m} }}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input")
    ap.add_argument("-o", "--output", help="output .pov (default: stdout)")
    ap.add_argument("--width", type=int, help="image width the camera aspect is set for (default: NFF resolution)")
    ap.add_argument("--height", type=int, help="image height (default: NFF resolution)")
    ap.add_argument("--angle-mode", choices=("spd", "centres"), default="spd")
    ap.add_argument("--max-trace-level", type=int, default=5)
    args = ap.parse_args()
    try:
        scene = parse(args.input)
    except (NffError, OSError) as e:
        sys.exit(f"nff2pov: {e}")
    if args.output:
        with open(args.output, "w") as f:
            write_pov(scene, f, args.width, args.height, args.angle_mode, args.max_trace_level)
    else:
        write_pov(scene, sys.stdout, args.width, args.height, args.angle_mode, args.max_trace_level)
    n = {k: sum(1 for o in scene["objects"] if o[0] == k) for k in ("s", "p", "pp", "c")}
    print(f"nff2pov: {args.input}: {len(scene['lights'])} lights, {len(scene['fills'])} fills, "
          f"{n['s']} spheres, {n['p']} polygons, {n['pp']} patches, {n['c']} cones", file=sys.stderr)


if __name__ == "__main__":
    main()
