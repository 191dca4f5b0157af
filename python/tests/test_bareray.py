"""Tests of the bareray Python module: shapes and dtypes, bad input, the command line's image for the same
spheres, the GIL released while tracing, scene files through load().

The command-line comparison runs the `bareray` binary: $BARERAY_BIN, else target/debug/bareray or
target/release/bareray of this repository (.ci/run sets $BARERAY_BIN).
"""

import errno
import os
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import bareray

REPO = pathlib.Path(__file__).resolve().parents[2]


def field(n, seed=1):
    """n random spheres in a cube, with colours on the 8-bit grid (stored exactly)."""
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-4.0, 4.0, size=(n, 3))
    radii = rng.uniform(0.08, 0.33, size=n)
    colors = np.floor(rng.uniform(0.0, 256.0, size=(n, 3))).clip(0, 255) / 255.0
    return centers, radii, colors


def binary():
    path = os.environ.get("BARERAY_BIN")
    if path:
        return pathlib.Path(path)
    for profile in ("debug", "release"):
        candidate = REPO / "target" / profile / "bareray"
        if candidate.exists():
            return candidate
    pytest.skip("no bareray binary: set BARERAY_BIN or build it (cargo build)")


def test_image_shape_dtype_and_background():
    centers, radii, colors = field(200)
    image = bareray.render(centers, radii, colors, width=64, height=40, threads=2)
    assert image.shape == (40, 64, 3)
    assert image.dtype == np.float32
    # Framed like a particle file: the bounding sphere fits with a margin, so the corners are the white
    # background, and the spheres are shaded below white somewhere.
    assert (image[0, 0] == 1.0).all() and (image[-1, -1] == 1.0).all()
    assert image.min() < 0.9


def test_float32_and_float64_arrays_give_the_same_image():
    centers, radii, colors = field(150)
    c32, r32, k32 = (a.astype(np.float32) for a in (centers, radii, colors))
    a = bareray.render(c32, r32, k32, width=48, height=32, threads=2)
    b = bareray.render(c32.astype(np.float64), r32.astype(np.float64), k32.astype(np.float64), width=48,
                       height=32, threads=2)
    # Strided views and lists are converted, and give the same spheres.
    wide = np.zeros((len(c32), 6), dtype=np.float32)
    wide[:, ::2] = c32
    c = bareray.render(wide[:, ::2], r32.tolist(), k32, width=48, height=32, threads=2)
    assert np.array_equal(a, b) and np.array_equal(a, c)


def test_colours_replace_the_grey_and_one_radius_serves_all():
    centers, _, _ = field(100)
    red = np.tile([1.0, 0.0, 0.0], (100, 1))
    image = bareray.render(centers, 0.3, red, width=48, height=32, threads=2)
    grey = bareray.render(centers, 0.3, width=48, height=32, threads=2)
    hit = (image != 1.0).any(axis=2)
    assert hit.any()
    assert (image[hit][:, 1] <= image[hit][:, 0]).all(), "red spheres have no more green than red"
    assert not np.array_equal(image, grey)


def test_every_packet_width_the_scalar_path_and_thread_count_agree():
    centers, radii, colors = field(300, seed=4)
    reference = bareray.render(centers, radii, colors, width=64, height=48, threads=2)
    for lanes in (1, 4, 8, 16, "scalar"):
        for threads in (1, 2):
            image = bareray.render(centers, radii, colors, width=64, height=48, threads=threads, lanes=lanes)
            assert np.array_equal(image, reference), (lanes, threads)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda c, r, k: (c[:, :2], r, k), "centers must have shape (n, 3)"),
        (lambda c, r, k: (c, r[:-1], k), "radii must have shape (20,)"),
        (lambda c, r, k: (c, r, k[:, :2]), "colors must have shape (n, 3)"),
        (lambda c, r, k: (np.where(np.arange(20)[:, None] == 3, np.nan, c), r, k), "centers[3]"),
        (lambda c, r, k: (np.where(np.arange(20)[:, None] == 6, np.inf, c), r, k), "centers[6]"),
        (lambda c, r, k: (c, np.where(np.arange(20) == 5, -1.0, r), k), "radii[5]"),
        (lambda c, r, k: (c, np.where(np.arange(20) == 0, 0.0, r), k), "radii[0]"),
        (lambda c, r, k: (c, r, np.where(np.arange(20)[:, None] == 2, 1.5, k)), "colors[2]"),
        (lambda c, r, k: (c, r, np.where(np.arange(20)[:, None] == 9, -0.1, k)), "colors[9]"),
        (lambda c, r, k: ([["a", "b", "c"]] * 20, r, k), "centers"),
    ],
)
def test_bad_arrays_raise_value_error_naming_the_first_bad_index(change, message):
    centers, radii, colors = field(20)
    with pytest.raises(ValueError) as error:
        bareray.render(*change(centers, radii, colors), width=8, height=8)
    assert message in str(error.value)


def test_bad_settings_raise_value_error():
    centers, radii, _ = field(10)
    for kwargs in ({"spp": 2}, {"shade": "phong"}, {"lanes": 3}, {"view": "up"}, {"hfov": 180.0},
                   {"eye": (0, 0)}, {"width": 0}, {"threads": 0}):
        settings = {"width": 8, "height": 8, **kwargs}
        with pytest.raises(ValueError):
            bareray.render(centers, radii, **settings)


def test_render_equals_the_command_lines_image(tmp_path):
    centers, radii, colors = field(400, seed=9)
    lines = [f"{len(radii)}", "Properties=species:S:1:pos:R:3:radius:R:1:color:R:3"]
    for c, r, k in zip(centers, radii, colors):
        lines.append("C " + " ".join(repr(float(v)) for v in (*c, r, *k)))
    scene = tmp_path / "field.extxyz"
    scene.write_text("\n".join(lines) + "\n")
    out = tmp_path / "field.ppm"
    for args, kwargs in (
        ([], {}),
        (["--view", "-x", "--shade", "ao:8"], {"view": "-x", "shade": "ao:8"}),
        (["--eye", "0,1,-20", "--look", "0,0,0", "--hfov", "30"], {"eye": (0, 1, -20), "look": (0, 0, 0), "hfov": 30}),
    ):
        subprocess.run([str(binary()), "render", str(scene), "-o", str(out), "--width", "120", "--height", "80",
                        "--quiet", *args], check=True)
        data = out.read_bytes()
        header = b"P6\n120 80\n255\n"
        assert data.startswith(header)
        cli = np.frombuffer(data[len(header):], dtype=np.uint8).reshape(80, 120, 3)
        image = bareray.render(centers, radii, colors, width=120, height=80, **kwargs)
        assert np.array_equal(bareray.to_uint8(image, "linear"), cli), args


def test_a_second_thread_runs_while_a_render_is_in_progress():
    centers, radii, colors = field(20000, seed=2)
    # Larger images until a render lasts long enough to tell: a fast machine finishes the first at once.
    for scale in (1, 2, 4, 8):
        done = {}

        def render(width=640 * scale, height=480 * scale):
            start = time.perf_counter()
            done["image"] = bareray.render(centers, radii, colors, width=width, height=height, shade="ao:16", threads=1)
            done["seconds"] = time.perf_counter() - start

        worker = threading.Thread(target=render)
        worker.start()
        ticks = 0
        while worker.is_alive():
            ticks += 1
            time.sleep(0.001)
        worker.join()
        assert done["image"].shape == (480 * scale, 640 * scale, 3)
        if done["seconds"] > 0.1:
            break
    # With the GIL held for the whole render this loop could not run until it ended (a tick or two).
    assert done["seconds"] > 0.1, "the render was too quick to tell"
    assert ticks > 20, f"{ticks} ticks in {done['seconds']:.2f} s"


WATER = """3
water
O 0.000 0.000 0.000
H 0.757 0.586 0.000
H -0.757 0.586 0.000
"""


def test_load_reads_a_particle_file_and_renders_it(tmp_path):
    path = tmp_path / "water.xyz"
    path.write_text(WATER)
    scene = bareray.load(str(path))
    assert scene.spheres == 3
    assert scene.size == (1920, 1080)
    assert scene.transfer == "linear"
    assert scene.warnings == []
    image = scene.render(width=96, height=54, threads=2)
    assert image.shape == (54, 96, 3) and image.dtype == np.float32
    assert (image[0, 0] == 1.0).all(), "particle files render on white"
    # The same spheres as arrays give the same image.
    centers = [[0, 0, 0], [0.757, 0.586, 0], [-0.757, 0.586, 0]]
    oxygen, hydrogen = np.array([255, 13, 13]) / 255, np.array([255, 255, 255]) / 255
    arrays = bareray.render(centers, [1.5, 1.2, 1.2], [oxygen, hydrogen, hydrogen], width=96, height=54)
    assert np.array_equal(image, arrays)
    report = scene.accuracy(width=48, height=27, threads=2)
    assert report["rays"] == 48 * 27 and report["unexplained_disagree"] == 0
    timing = scene.bench(reps=1, width=48, height=27, threads=2)
    assert timing["rays"] >= 48 * 27 and timing["median"] > 0


def test_load_takes_the_first_frame_of_any_file(tmp_path):
    # Frame 0, the default, is every file's first: a sphere list loads with it; a later one is for particle files.
    path = tmp_path / "pair.xyzr"
    path.write_text("0 0 0 1\n3 0 0 1\n")
    assert bareray.load(str(path)).spheres == 2
    assert bareray.load(str(path), frame=0).spheres == 2
    with pytest.raises(ValueError, match="for particle files"):
        bareray.load(str(path), frame=1)


def test_bench_splits_the_render_by_ray_kind_on_every_path(tmp_path):
    # A 6×6×6 lattice of spheres: enough for a BVH, so every path has box tests to count. As an `.xyzr` list
    # it is lit from beside the camera, so its hits send shadow rays.
    spheres = [f"{1.6 * x} {1.6 * y} {1.6 * z} 0.9" for x in range(6) for y in range(6) for z in range(6)]
    path = tmp_path / "lattice.xyzr"
    path.write_text("\n".join(spheres) + "\n")
    scene = bareray.load(str(path))
    plain = scene.bench(reps=1, width=48, height=27, threads=1, lanes=8)
    assert "by_kind" not in plain and plain["lanes"] == 8
    for lanes in ["scalar", 1, 16]:
        timing = scene.bench(reps=1, width=48, height=27, threads=1, lanes=lanes, by_kind=True)
        assert timing["lanes"] == lanes
        split = timing["by_kind"]
        kinds = {k["kind"]: k for k in split["kinds"]}
        # Whitted with one light and no mirrors: camera and shadow rays, every ray counted once.
        assert set(kinds) == {"camera", "shadow"}, kinds
        assert sum(k["rays"] for k in kinds.values()) == timing["rays"]
        assert kinds["camera"]["rays"] == 48 * 27
        assert all(k["mrays_per_s"] > 0 and 0 < k["share"] <= 1 for k in kinds.values())
        # One ray per test on the single-ray paths; a packet's tests serve more where its lanes are live.
        per_box = kinds["camera"]["rays_per_box_test"]
        assert per_box == 1.0 if lanes in ["scalar", 1] else per_box > 1.0, (lanes, per_box)
    # The same lattice as a particle file has a headlight, which camera rays' hits see without shadow rays.
    atoms = [f"C {1.6 * x} {1.6 * y} {1.6 * z}" for x in range(6) for y in range(6) for z in range(6)]
    xyz = tmp_path / "lattice.xyz"
    xyz.write_text(f"{len(atoms)}\nlattice\n" + "\n".join(atoms) + "\n")
    headlit = bareray.load(str(xyz)).bench(reps=1, width=48, height=27, threads=1, lanes=8, by_kind=True)
    assert [k["kind"] for k in headlit["by_kind"]["kinds"]] == ["camera"], headlit["by_kind"]
    assert headlit["rays"] == 48 * 27
    # Ambient occlusion: camera rays and `ao` rays, 4 per hit.
    ao = scene.bench(reps=1, width=48, height=27, threads=1, lanes=8, shade="ao:4,2", by_kind=True)
    kinds = {k["kind"]: k["rays"] for k in ao["by_kind"]["kinds"]}
    assert set(kinds) == {"camera", "ao"} and kinds["ao"] % 4 == 0 and kinds["ao"] > 0, kinds
    assert sum(kinds.values()) == ao["rays"]


def test_load_errors_name_the_file_and_line(tmp_path):
    path = tmp_path / "bad.xyz"
    path.write_text("3\nwater\nO 0 0 0\nH 0.7 zero 0\nH -0.7 0.5 0\n")
    with pytest.raises(ValueError) as error:
        bareray.load(str(path))
    assert "bad.xyz:4" in str(error.value)
    with pytest.raises(ValueError) as error:
        bareray.load(str(path), frame=1)
    assert "bad.xyz" in str(error.value)
    # A missing file is told apart from a bad one, as open() tells it.
    missing = tmp_path / "missing.pdb"
    with pytest.raises(FileNotFoundError) as error:
        bareray.load(str(missing))
    assert error.value.errno == errno.ENOENT and error.value.filename == str(missing)
    assert not isinstance(error.value, ValueError)
    with pytest.raises(FileNotFoundError):
        bareray.load(tmp_path / "missing" / "water.xyz")  # a path object, in a missing directory
    # A missing sidecar named nowhere is no error; a bad one beside the file is, with its line.
    (tmp_path / "bad.xyz.types.toml").write_text("[O]\nradius = 0\n")
    path.write_text(WATER)
    with pytest.raises(ValueError) as error:
        bareray.load(str(path))
    assert "bad.xyz.types.toml:2" in str(error.value)
