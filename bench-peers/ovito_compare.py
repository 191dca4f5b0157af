#!/usr/bin/env python3
"""bareray against OVITO (PyPI `ovito`, its Tachyon and OSPRay renderers) on the same spheres and camera.

For each data set (1e5 random particles; a real molecule, a PDB file such as MDAnalysisTests' adk_oplsaa.pdb,
read in place) the script writes the spheres as an .xyzr list (x y z r: the radii passed explicitly to every
renderer), chooses one perspective camera (bareray's particle framing from +z: the bounding sphere fills 95% of
the vertical half-angle at 1920x1080, horizontal angle 45 degrees) and renders it

  - with OVITO's TachyonRenderer: direct light with shadows, no ambient occlusion, no antialiasing;
  - with TachyonRenderer and ambient occlusion of N samples (Tachyon keeps shadows with AO);
  - with OVITO's OSPRayRenderer: 1 sample, 1 refinement (as issue 39 timed it), and N samples per pixel
    (its path tracer's ambient light then takes N samples a pixel, the nearest it has to N AO rays);
  - with `bareray render` at Whitted (a point light at the eye, 1 sample at the pixel centre; its visible hits
    see that light without a shadow ray, since the camera ray found the way back clear) and `--shade ao:N,L`
    (N occlusion rays a hit, no light), with L the diagonal of the spheres' box, so that an occlusion ray
    reaches every sphere as Tachyon's do (its shader sets their `maxdist` to FHUGE, unbounded), and with
    bareray's default L (a quarter of that diagonal).

Tachyon's AO render still does more per hit than bareray's: its direct light and shadow ray (one more ray a
hit) besides the N occlusion rays, which it samples uniformly over the hemisphere where bareray's are
cosine-weighted.

OVITO's time is that of `Viewport.render_image` (its scene preparation, Tachyon's or OSPRay's build and the
trace); bareray's is the wall time of the whole `bareray render` process (reading the list, the BVH build,
the trace and writing the PNG), with the parse, build and render (tracing with the PNG) seconds of its
summary line beside it. Where the bareray Python module imports (`pip install ./python` in the same
environment), the same renders are also timed in this process through `bareray.render(centers, radii, ...)`
(rows `bareray-py-*`): the arrays in memory, as OVITO's pipeline holds them, and no file or PNG on either
side. Each time is the median of --reps runs, the renders taken in turn in each round. The object mask of
each image written to a PNG (bareray: a pixel not the black background; OVITO: alpha > 0, the image rendered
with a transparent background) is compared with OVITO Tachyon's without AO, as intersection over union; not
bareray's AO image, which is black where a hit is fully occluded. The module's Whitted image (mid-grey
particles on white) is compared with the command's instead: its JSON field `iou_vs_command` is the lowest
IoU over the rounds.

The camera: OVITO's `Viewport.fov` is the vertical angle of a perspective view (its documentation; for an image
wider than tall), bareray's `--hfov` the horizontal angle across the outer pixel edges, so the script passes
fov = 2 atan(tan(hfov/2) * height/width). `--fov-check` renders one small off-centre sphere with both and prints
where each puts it, which is how that mapping was checked. OVITO's Tachyon image is also displaced by half a
pixel left and down against bareray's, which traces through pixel centres: as if its rays went through the
pixels' corners. On 2000 random spheres of 3-7 pixels the masks' IoU is 0.770 as they are and 0.998 with
bareray's camera turned by half a pixel right and up (a whole pixel gives 0.768), so the script turns bareray's
look point by --pixel-shift pixels (default 0.5; 0 for the cameras as they are).

Usage (a virtual environment with `pip install ovito pillow numpy`; headless, OVITO needs
`apt-get install libvulkan1 mesa-vulkan-drivers`):

    python bench-peers/ovito_compare.py --bareray target/release/bareray \\
        --molecule /path/to/MDAnalysisTests/data/adk_oplsaa.pdb --out /tmp/ovito-cmp --reps 3 --ao 12

It prints one line per render and a summary table, and writes a JSON of every number to OUT/results.json.
"""

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import time

import numpy as np

WIDTH, HEIGHT, HFOV = 1920, 1080, 45.0

# Van der Waals radii (Å) of Alvarez 2013, as bareray's table has them, for the elements of proteins in water.
RADII = {"H": 1.20, "C": 1.77, "N": 1.66, "O": 1.50, "S": 1.89, "P": 1.90, "NA": 2.50, "CL": 1.82, "K": 2.73}
FALLBACK = 1.5


def pdb_spheres(path):
    """Centres and radii of the ATOM/HETATM records of a PDB file (first model), the element from columns
    77-78 or else the atom name's first letter."""
    centers, radii = [], []
    with open(path) as f:
        for line in f:
            record = line[:6].strip()
            if record == "ENDMDL":
                break
            if record not in ("ATOM", "HETATM"):
                continue
            centers.append((float(line[30:38]), float(line[38:46]), float(line[46:54])))
            element = line[76:78].strip().upper() or line[12:16].strip()[:1].upper()
            radii.append(RADII.get(element, FALLBACK))
    return np.array(centers, dtype=np.float64), np.array(radii, dtype=np.float64)


def random_spheres(n, seed=1):
    """n spheres uniform in the cube [-1, 1]^3, radii uniform in [0.005, 0.015]."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.0, 1.0, (n, 3)), rng.uniform(0.005, 0.015, n)


def bounds(centers, radii):
    """The corners of the box around the spheres."""
    return (centers - radii[:, None]).min(axis=0), (centers + radii[:, None]).max(axis=0)


def camera(centers, radii, shift=0.0):
    """bareray's particle framing from +z: eye, look, up, hfov (degrees) and OVITO's vertical fov (radians);
    and bareray's look point turned by `shift` pixels right and up (see the module's documentation)."""
    lo, hi = bounds(centers, radii)
    centre = (lo + hi) / 2
    radius = np.linalg.norm((hi - lo) / 2)
    tan_w = math.tan(math.radians(HFOV) / 2)
    tan_h = tan_w * HEIGHT / WIDTH
    half = math.atan(min(tan_w, tan_h)) * 0.95
    distance = radius / math.sin(half)
    eye = centre + np.array([0.0, 0.0, distance])
    # Looking down -z with +y up, right is +x; one pixel at the look point is 2 tan(hfov/2) d / width.
    pixel = 2 * tan_w * distance / WIDTH
    shifted = centre + np.array([shift * pixel, shift * pixel, 0.0])
    return eye, centre, np.array([0.0, 1.0, 0.0]), HFOV, 2 * math.atan(tan_h), shifted


def write_xyzr(path, centers, radii):
    np.savetxt(path, np.column_stack([centers, radii]), fmt="%.9g")


def vec(v):
    return ",".join(f"{x:.17g}" for x in v)


def run_bareray(binary, xyzr, out, cam, shade):
    eye, _, up, hfov, _, look = cam
    # `--view +z` gives the list a headlight at the eye, which the camera flags then move to the same camera's
    # eye, so that every visible hit is lit head-on, as under Tachyon's direct light (without it the list's
    # light would sit beside the camera). Hits see a light at the eye without shadow rays.
    cmd = [binary, "render", xyzr, "-o", out, "--view", "+z", "--width", str(WIDTH), "--height", str(HEIGHT),
           "--eye", vec(eye), "--look", vec(look), "--up", vec(up), "--hfov", repr(hfov), "--shade", shade]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"bareray failed: {' '.join(cmd)}\n{done.stderr}")
    text = done.stdout + done.stderr
    # The summary line (not `--stats`, whose work counters would be timed too): "FILE: WxH in 0.244 s (parse
    # 0.036 s, build 0.064 s); ..."; its first time is the tracing with the streamed PNG.
    patterns = {"render": r" in ([0-9.]+) s \(", "parse": r"parse ([0-9.]+) s", "build": r"build ([0-9.]+) s"}
    stats = {k: float(m.group(1)) for k, p in patterns.items() for m in [re.search(p, text)] if m}
    return wall, stats, " ".join(cmd), text


def python_module():
    """The bareray Python module, or None where it is not installed in this environment."""
    try:
        import bareray
    except ImportError:
        return None
    return bareray if hasattr(bareray, "render") else None


def run_python(module, centers, radii, cam, shade):
    """`bareray.render` of the arrays with the command's camera and shading, timed in this process, and its
    8-bit codes (`to_uint8`: linear, as the command encodes an .xyzr render)."""
    eye, _, up, hfov, _, look = cam
    # Mid grey, so that no lit pixel saturates to the white background.
    grey = np.full((len(radii), 3), 0.5)
    start = time.perf_counter()
    image = module.render(centers, radii, grey, width=WIDTH, height=HEIGHT, eye=eye, look=look, up=up,
                          hfov=hfov, shade=shade)
    seconds = time.perf_counter() - start
    return seconds, module.to_uint8(image)


def ovito_scene(centers, radii):
    from ovito.data import DataCollection
    from ovito.pipeline import Pipeline, StaticSource

    data = DataCollection()
    particles = data.create_particles(count=len(radii))
    particles.create_property("Position", data=centers)
    particles.create_property("Radius", data=radii)
    particles.create_property("Color", data=np.full((len(radii), 3), 0.8))
    pipeline = Pipeline(source=StaticSource(data=data))
    pipeline.add_to_scene()
    return pipeline


def run_ovito(renderer, cam, out):
    from ovito.vis import Viewport

    eye, look, up, _, fov, _ = cam
    vp = Viewport(type=Viewport.Type.Perspective, camera_pos=tuple(eye), camera_dir=tuple(look - eye),
                  camera_up=tuple(up), fov=fov)
    start = time.perf_counter()
    image = vp.render_image(size=(WIDTH, HEIGHT), renderer=renderer, alpha=True, background=(0, 0, 0))
    seconds = time.perf_counter() - start
    image.save(out)
    return seconds


def mask(path, alpha):
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGBA"))
    return img[..., 3] > 0 if alpha else img[..., :3].max(axis=2) > 0


def iou(a, b):
    return float((a & b).sum()) / float((a | b).sum())


def renderers(ao):
    from ovito.vis import OSPRayRenderer, TachyonRenderer

    return {
        "tachyon": lambda: TachyonRenderer(shadows=True, direct_light=True, ambient_occlusion=False,
                                           antialiasing=False),
        f"tachyon-ao{ao}": lambda: TachyonRenderer(shadows=True, direct_light=True, ambient_occlusion=True,
                                                   ambient_occlusion_samples=ao, antialiasing=False),
        "ospray-1": lambda: OSPRayRenderer(samples_per_pixel=1, refinement_iterations=1,
                                           denoising_enabled=False),
        f"ospray-{ao}": lambda: OSPRayRenderer(samples_per_pixel=ao, refinement_iterations=1,
                                               denoising_enabled=False),
    }


def fov_check(binary, out):
    """One sphere off centre: where each renderer puts it (its mask's centroid), to check the fov mapping."""
    centers = np.array([[0.0, 0.0, 0.0], [3.0, 1.5, 0.0]])
    radii = np.array([0.5, 0.25])
    eye, look, up = np.array([0.0, 0.0, 10.0]), np.zeros(3), np.array([0.0, 1.0, 0.0])
    tan_h = math.tan(math.radians(HFOV) / 2) * HEIGHT / WIDTH
    cam = (eye, look, up, HFOV, 2 * math.atan(tan_h), look)
    xyzr = os.path.join(out, "fov.xyzr")
    write_xyzr(xyzr, centers, radii)
    run_bareray(binary, xyzr, os.path.join(out, "fov-bareray.png"), cam, "whitted")
    from ovito.vis import TachyonRenderer

    pipeline = ovito_scene(centers, radii)
    run_ovito(TachyonRenderer(antialiasing=False), cam, os.path.join(out, "fov-ovito.png"))
    pipeline.remove_from_scene()
    a = mask(os.path.join(out, "fov-bareray.png"), False)
    b = mask(os.path.join(out, "fov-ovito.png"), True)
    for name, m in (("bareray", a), ("ovito", b)):
        ys, xs = np.nonzero(m[:, WIDTH // 2 + 100:])
        print(f"{name}: small sphere centred at x {xs.mean() + WIDTH // 2 + 100:.1f}, y {ys.mean():.1f}; "
              f"{m.sum()} pixels in all")
    print(f"IoU {iou(a, b):.4f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bareray", default="target/release/bareray")
    ap.add_argument("--molecule", help="a PDB file (first model)")
    ap.add_argument("--random", type=int, default=100_000, help="random particles (0: none)")
    ap.add_argument("--out", default="/tmp/ovito-compare")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--ao", type=int, default=12, help="AO samples (Tachyon's default is 12)")
    ap.add_argument("--skip", default="", help="comma-separated renders to leave out, e.g. ospray-12")
    ap.add_argument("--fov-check", action="store_true")
    ap.add_argument("--pixel-shift", type=float, default=0.5,
                    help="pixels to turn bareray's camera right and up, onto Tachyon's pixel grid")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    binary = os.path.abspath(args.bareray)
    if args.fov_check:
        fov_check(binary, args.out)
        return
    import ovito

    module = python_module()
    print(f"bareray Python module: {module.__file__ if module else 'not installed, its rows skipped'}")
    sets = []
    if args.random:
        sets.append((f"random-{args.random}", *random_spheres(args.random)))
    if args.molecule:
        sets.append((os.path.basename(args.molecule), *pdb_spheres(args.molecule)))
    skip = set(filter(None, args.skip.split(",")))
    results = {"ovito": ovito.version_string, "cpu": cpu(), "sets": {}}
    for name, centers, radii in sets:
        cam = camera(centers, radii, args.pixel_shift)
        xyzr = os.path.join(args.out, f"{name}.xyzr")
        write_xyzr(xyzr, centers, radii)
        res = results["sets"][name] = {"spheres": len(radii), "eye": list(cam[0]), "look": list(cam[1]),
                                       "hfov": cam[3], "ovito_fov_rad": cam[4], "pixel_shift": args.pixel_shift,
                                       "bareray_look": list(cam[5]), "renders": {}}
        print(f"== {name}: {len(radii)} spheres, eye {vec(cam[0])}, look {vec(cam[1])}", flush=True)
        pipeline = ovito_scene(centers, radii)
        jobs = {}
        ious = {}
        lo, hi = bounds(centers, radii)
        reach = float(np.linalg.norm(hi - lo))
        res["ao_reach"] = reach
        for shade in ("whitted", f"ao:{args.ao}", f"ao:{args.ao},{reach:.9g}"):
            key = f"bareray-{shade}" if "," not in shade else f"bareray-ao:{args.ao},diagonal"
            png = os.path.join(args.out, f"{name}-{key}.png".replace(":", "").replace(",", "-"))
            jobs[key] = (png, lambda png=png, shade=shade: run_bareray(binary, xyzr, png, cam, shade))
            if module is not None:
                py_key = key.replace("bareray-", "bareray-py-")
                jobs[py_key] = (None, lambda png=png, shade=shade, py_key=py_key: python_job(
                    module, centers, radii, cam, shade, png, ious.setdefault(py_key, [])))
        for key, make in renderers(args.ao).items():
            if key not in skip:
                png = os.path.join(args.out, f"{name}-{key}.png")
                jobs[key] = (png, lambda png=png, make=make: (run_ovito(make(), cam, png), {}, "", ""))
        # Rounds of every render in turn, so that a change in the shared host's load falls on all of them.
        runs = {key: [] for key in jobs}
        for round_ in range(args.reps):
            for key, (png, job) in jobs.items():
                runs[key].append(job())
                print(f"round {round_ + 1} {key}: {runs[key][-1][0]:.3f} s {runs[key][-1][1] or ''} "
                      f"(load {os.getloadavg()[0]:.2f})", flush=True)
        for key, (png, _) in jobs.items():
            times = [r[0] for r in runs[key]]
            entry = {"seconds": statistics.median(times), "runs": times, "png": png}
            if key.startswith("bareray-py-"):
                if ious.get(key):
                    entry["iou_vs_command"] = min(ious[key])
            elif key.startswith("bareray"):
                entry.update(stats=runs[key][-1][1], command=runs[key][-1][2])
            res["renders"][key] = entry
        pipeline.remove_from_scene()
        ref = mask(res["renders"]["tachyon"]["png"], True) if "tachyon" in res["renders"] else None
        for key, entry in res["renders"].items():
            # bareray's AO image is black where a hit is fully occluded, so its mask is not the objects'.
            if ref is not None and entry["png"] and not key.startswith("bareray-ao"):
                entry["iou_vs_tachyon"] = iou(mask(entry["png"], key.startswith(("tachyon", "ospray"))), ref)
        if ref is not None and args.pixel_shift:
            # The same camera without the half-pixel turn, for the record.
            png = os.path.join(args.out, f"{name}-bareray-whitted-unshifted.png")
            run_bareray(binary, xyzr, png, cam[:5] + (cam[1],), "whitted")
            res["iou_unshifted_vs_tachyon"] = iou(mask(png, False), ref)
            print(f"bareray whitted without the pixel shift: IoU {res['iou_unshifted_vs_tachyon']:.4f}")
        summary(name, res, args.ao, module)
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)


def python_job(module, centers, radii, cam, shade, png, ious):
    """One in-process render, timed. For Whitted, appends to `ious` its object mask's IoU against the
    command's PNG `png` (written earlier in the round): the module renders particles mid grey on white, the
    command an .xyzr list in its default material on black, so the masks are compared, not the pixels."""
    seconds, image = run_python(module, centers, radii, cam, shade)
    if shade == "whitted":
        ours = (np.asarray(image) != 255).any(axis=2)
        ious.append(iou(ours, mask(png, False)))
    return seconds, {}, "", ""


def fmt(xs):
    return ", ".join(f"{x:.3f}" for x in xs)


def summary(name, res, ao, module):
    """Each render's median and its ratio to bareray's at the same shading: Whitted for Tachyon and OSPRay at
    1 sample; for the AO renders both bareray AO lengths, the diagonal (Tachyon's reach) first. The ratios to
    the command's wall time come first, then, where the Python module ran, to its in-process time."""
    r = res["renders"]
    bases = "(command; in process)" if module is not None else "(command)"
    print(f"-- {name}: seconds, ratio to bareray at the same shading {bases}, mask IoU against OVITO Tachyon")
    for key, entry in r.items():
        if "ao" not in key and key != f"ospray-{ao}":
            keys = ["bareray-whitted"]
        else:
            keys = [f"bareray-ao:{ao},diagonal", f"bareray-ao:{ao}"]
        cells = []
        for prefix in ("bareray-", "bareray-py-"):
            bases = [r[k.replace("bareray-", prefix)] for k in keys if k.replace("bareray-", prefix) in r]
            if bases:
                cells.append(" / ".join(f"{entry['seconds'] / b['seconds']:.1f}x" for b in bases))
        extra = ""
        if "iou_vs_command" in entry:
            extra = f"  IoU {entry['iou_vs_command']:.4f} against the command's"
        print(f"   {key:27s} {entry['seconds']:8.3f} s  {'; '.join(cells):>29s}  "
              f"IoU {entry.get('iou_vs_tachyon', float('nan')):.4f}{extra}")


def cpu():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip() + f", {os.cpu_count()} threads"
    except OSError:
        pass
    return f"{os.cpu_count()} threads"


if __name__ == "__main__":
    main()
