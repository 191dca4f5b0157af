//! Scene readers (NFF, xyzr, f32r), generators (contract field, SPD sphereflake) and the polygon primitive, through
//! the library API.

use std::path::Path;

use bareray::accel::Geometry;
use bareray::compile::Scene;
use bareray::geometry::{Departure, Ray, NO_PRIM};
use bareray::io::generate::{flake, flake_count, flake_nff, FieldParams};
use bareray::io::{f32r, nff, xyzr, SceneError, SceneFormat};
use bareray::kinds::polygon::{intersect_triangle, triangulate, PolygonDesc};
use bareray::kinds::sphere::SphereDesc;
use bareray::kinds::KindDescs;
use bareray::math::{Rgb, V3};
use bareray::scene::desc::{Aim, Field, Sweep};
use bareray::scene::SceneDesc;

use glam::DVec3;

/// SPD's `balls` output at size 2 (91 spheres on a floor polygon, its view and lights), as SPD's NFF writer
/// prints it (`%g`, six significant digits): the independent reference for the sphereflake generator.
const BALLS2: &str = include_str!("../data/balls2.nff");

fn nff_err(src: &str) -> SceneError {
    nff::parse(Path::new("t.nff"), src).expect_err("the scene must be rejected")
}

fn xyzr_err(src: &str) -> SceneError {
    xyzr::parse(Path::new("t.xyzr"), src).expect_err("the list must be rejected")
}

const VIEW: &str = "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 64\n";

// ---------------------------------------------------------------------------------------------------- NFF

#[test]
fn balls2_counts_camera_lights_and_fills() {
    let d = nff::parse(Path::new("balls2.nff"), BALLS2).unwrap();
    assert_eq!((d.spheres.len(), d.kinds.polygons.len(), d.lights.len()), (91, 1, 3));
    assert_eq!(d.camera.eye, DVec3::new(2.1, 1.3, 1.7));
    assert_eq!(d.camera.aim, Aim::LookAt(DVec3::ZERO));
    assert_eq!(d.camera.up, DVec3::Z);
    assert_eq!(d.camera.field, Field::HorizontalAngle(45.0));
    assert_eq!((d.camera.width, d.camera.height, d.camera.sweep), (512, 512, Sweep::PixelCentre));
    assert_eq!(d.render.background, Rgb::new(0.078, 0.361, 0.753));
    // Colourless lights: 1/sqrt(3) each.
    let third = 1.0 / 3f32.sqrt();
    assert!(d.lights.iter().all(|l| l.color == Rgb::all(third)));
    assert_eq!(d.lights[1].position, DVec3::new(1.0, -4.0, 4.0));
    // Floor fill then sphere fill; Ks is both the highlight and the mirror weight.
    let floor = &d.materials[d.kinds.polygons[0].material as usize];
    assert_eq!((floor.color, floor.diffuse, floor.reflect), (Rgb::new(1.0, 0.75, 0.33), 0.8, 0.0));
    let ball = &d.materials[d.spheres[0].material as usize];
    assert_eq!((ball.diffuse, ball.specular, ball.reflect, ball.shininess), (0.5, 0.5, 0.5, 3.0827));
    assert_eq!(d.kinds.polygons[0].vertices[2], DVec3::new(-12.0, -12.0, -0.5));
    assert_eq!(d.spheres[90].center, DVec3::new(0.471405, -0.471405, -0.222222));
}

#[test]
fn balls2_frames_like_spd_pov_ray_output() {
    // SPD's POV-Ray camera spans 2·tan(angle/2) edge to edge: the ray through the image's left edge
    // (pixel-space x = 0) makes exactly half the angle with the view direction.
    let d = nff::parse(Path::new("balls2.nff"), BALLS2).unwrap();
    let scene = Scene::compile(&d).unwrap();
    let cam = &scene.camera_f64;
    let edge = cam.ray(0.0, 256.0).dir;
    let angle = edge.dot(cam.forward).acos().to_degrees();
    assert!((angle - 22.5).abs() < 1e-9, "{angle}");
}

#[test]
fn balls2_floor_is_one_primitive_after_the_spheres() {
    let d = nff::parse(Path::new("balls2.nff"), BALLS2).unwrap();
    let scene = Scene::compile(&d).unwrap();
    let g = &scene.geometry;
    assert_eq!((g.len(), g.kinds.polygons.ids(), g.kinds.polygons.len()), (92, 1, 2));
    // Straight down onto the floor, away from the flake: polygon id 91, at z = −0.5, normal ±z.
    let ray = Ray::new(scene.to_rendering(DVec3::new(5.0, 5.0, 3.0)), V3::new(0.0, 0.0, -1.0));
    let hit = g.intersect(&ray, Departure::CAMERA, f32::INFINITY);
    assert_eq!((hit.prim, hit.t), (91, 3.5));
    let sp = g.surface(&ray, hit.t, hit.prim);
    assert_eq!(sp.normal, V3::new(0.0, 0.0, 1.0));
}

#[test]
fn nff_errors_name_the_line() {
    let cases: &[(&str, usize, &str)] = &[
        (
            "# c\n\nv\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nresolution 8 8\nq 1\n",
            9,
            "unknown entity `q`",
        ),
        (&format!("{VIEW}s 0 0 0 1\nc\n0 0 0 1\n0 1 0 -1\n"), 9, "cone radii must not be negative"),
        (&format!("{VIEW}# x\ns 0 0 abc 1\n"), 9, "expected sphere centre"),
        (&format!("{VIEW}s 0 0 0\n-1\n"), 8, "radius must be positive"),
        (&format!("{VIEW}f 1 1 1 0.5 0.5 3 0 1\np 4\n0 0 0\n1 0 0\n1 1 0.5\n0 1 0\n"), 9, "not planar"),
        (&format!("{VIEW}p 3\n0 0 0\n1 0 0\n"), 10, "unexpected end of file"),
        (&format!("{VIEW}p 2\n0 0 0\n1 0 0\n"), 8, "whole number from 3"),
        (&format!("{VIEW}pp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0\n"), 11, "unexpected end of file"),
        (&format!("{VIEW}l 1 2 3 0.5\n"), 8, "unexpected end of file"),
        (&format!("{VIEW}l 1 2 3 0.5 1 -1\n"), 8, "must not be negative"),
        (&format!("{VIEW}f 1 1 1 0.5 0.5 3 0.5 0\n"), 8, "index of refraction"),
        ("b 0 0 0\nv\nfrom 0 0 0\nat 0 0 0\nup 0 1 0\nangle 45\nresolution 8 8\n", 2, "view: "),
        ("v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nresolution 8 8\n", 1, "lacks its `angle`"),
        ("v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nresolution 8 0\n", 6, "whole number from 1"),
        (&format!("{VIEW}{VIEW}"), 8, "second view"),
    ];
    for (src, line, needle) in cases {
        let e = nff_err(src);
        assert_eq!(e.line, *line, "{e} for:\n{src}");
        assert!(e.message.contains(needle), "`{e}` lacks `{needle}`");
        assert!(e.to_string().starts_with(&format!("t.nff:{line}: ")), "{e}");
    }
    let e = nff_err("s 0 0 0 1\n");
    assert_eq!((e.line, e.message.contains("no view")), (0, true), "{e}");
}

#[test]
fn nff_patches_interpolate_normals_and_concave_polygons_are_triangulated() {
    // A triangle whose vertex normals lean outward; at the centroid the shading normal is their mean.
    let src = format!(
        "{VIEW}f 1 1 1 1 0 1 0 1\npp 3\n0 0 0  -1 -1 4\n1 0 0  2 -1 4\n0 1 0  -1 2 4\n\
         p 6\n0 0 5\n2 0 5\n2 1 5\n1 1 5\n1 2 5\n0 2 5\n"
    );
    let d = nff::parse(Path::new("t.nff"), &src).unwrap();
    let n = d.kinds.polygons[0].normals.as_ref().unwrap();
    assert_eq!(n[1], DVec3::new(2.0, -1.0, 4.0));
    let g = Scene::compile(&d).unwrap().geometry;
    assert_eq!((g.kinds.polygons.ids(), g.kinds.polygons.len()), (2, 5));
    let ray = Ray::new(V3::new(1.0f32 / 3.0, 1.0 / 3.0, -1.0), V3::new(0.0, 0.0, 1.0));
    let hit = g.intersect(&ray, Departure::CAMERA, f32::INFINITY);
    assert_eq!(hit.prim, 0);
    let sp = g.surface(&ray, hit.t, hit.prim);
    let unit = |v: [f32; 3]| V3::new(v[0], v[1], v[2]).normalize();
    let mean = (unit([-1.0, -1.0, 4.0]) + unit([2.0, -1.0, 4.0]) + unit([-1.0, 2.0, 4.0])).normalize();
    assert!((sp.normal - mean).length() < 1e-6, "{:?} vs {mean:?}", sp.normal);
    // The L-shaped hexagon: hit in its arm, miss in its notch.
    let at = |x: f32, y: f32| Ray::new(V3::new(x, y, 0.0), V3::new(0.0, 0.0, 1.0));
    assert_eq!(g.intersect(&at(0.5, 1.5), Departure::CAMERA, f32::INFINITY).prim, 1);
    assert_eq!(g.intersect(&at(1.5, 1.5), Departure::CAMERA, f32::INFINITY).prim, NO_PRIM);
}

/// A tiny deterministic generator for the garbling test (no dependency on the system's randomness).
fn lcg(state: &mut u64) -> u64 {
    *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *state >> 33
}

#[test]
fn truncated_and_garbled_files_never_panic() {
    let extra = format!(
        "{VIEW}pp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\nl 1 1 1 0.2 0.3 0.4\nc 0 0 0 1 0 1 0 1\n"
    );
    let field = "# a field\n0 0 0 1\n\n1e0 2 3 0.5\n-1 -2 -3 2.5e-1\n";
    let junk = [" ", "\n", "#", "-", "e", "1e999", "nan", "inf", "p 0", "pp", "x", "0", "é", "\t", "v", "f"];
    let mut state = 7u64;
    for src in [BALLS2, extra.as_str(), field] {
        for cut in (0..=src.len()).filter(|&i| src.is_char_boundary(i)) {
            let _ = nff::parse(Path::new("t.nff"), &src[..cut]);
            let _ = xyzr::parse(Path::new("t.xyzr"), &src[..cut]);
        }
        for _ in 0..3000 {
            let mut s = src.to_owned();
            for _ in 0..1 + lcg(&mut state) % 4 {
                let mut at = lcg(&mut state) as usize % (s.len() + 1);
                while !s.is_char_boundary(at) {
                    at -= 1;
                }
                s.insert_str(at, junk[lcg(&mut state) as usize % junk.len()]);
            }
            if let Ok(d) = nff::parse(Path::new("t.nff"), &s) {
                // Whatever parses must also compile without panicking.
                let _ = Scene::compile(&d);
            }
            if let Ok(d) = xyzr::parse(Path::new("t.xyzr"), &s) {
                assert!(Scene::compile(&d).is_ok(), "an accepted xyzr list always gets a usable camera");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------- xyzr

#[test]
fn xyzr_reads_spheres_and_frames_them() {
    let d = xyzr::parse(Path::new("t.xyzr"), "# atoms\n\n 1 2 3 0.5\n\t-1e0 0 0 2\n").unwrap();
    assert_eq!(d.spheres.len(), 2);
    assert_eq!(d.spheres[1], SphereDesc { center: DVec3::new(-1.0, 0.0, 0.0), radius: 2.0, material: 0 });
    assert_eq!(d.lights.len(), 1);
    // Looks +z at the centre of the bounds [-3, 1.5] × [-2, 2.5] × [-2, 3.5], from in front of them.
    assert_eq!(d.camera.aim, Aim::LookAt(DVec3::new(-0.75, 0.25, 0.75)));
    assert!(d.camera.eye.z < -2.0 && d.camera.eye.x == -0.75 && d.camera.eye.y == 0.25);
    assert!(Scene::compile(&d).is_ok());
}

#[test]
fn xyzr_errors_name_the_line() {
    let cases: &[(&str, usize, &str)] = &[
        ("0 0 0 1\n# c\n\n1 2 3\n", 4, "expected 4 numbers"),
        ("0 0 0 1\n1 2 x 4\n", 2, "expected z"),
        ("\n\n\n1 2 3 -4\n", 4, "radius must be positive"),
        ("1 2 3 0\n", 1, "radius must be positive"),
        ("1 2 3 4 5\n", 1, "got more"),
        ("# only\n1 2 3 nan\n", 2, "expected r"),
    ];
    for (src, line, needle) in cases {
        let e = xyzr_err(src);
        assert_eq!(e.line, *line, "{e} for {src:?}");
        assert!(e.message.contains(needle), "`{e}` lacks `{needle}`");
        assert!(e.to_string().starts_with(&format!("t.xyzr:{line}: ")), "{e}");
    }
    assert_eq!(xyzr_err("# nothing\n\n").line, 0);
}

/// Lists of several megabytes are read in parallel chunks: spheres stay in file order, and errors name the
/// file's line, also deep in a later chunk, and the first bad line when several chunks have one.
#[test]
fn long_xyzr_lists_keep_order_and_line_numbers() {
    // About 5 MB, with comment and blank lines (and CRLF endings) so that lines and spheres are counted apart.
    let mut src = String::new();
    for i in 0..200_000 {
        match i % 10 {
            3 => src.push_str("# comment\r\n"),
            7 => src.push('\n'),
            _ => src.push_str(&format!("{i} -{i}.5 0.25 {}\n", 1 + i % 5)),
        }
    }
    let d = xyzr::parse(Path::new("t.xyzr"), &src).unwrap();
    assert_eq!(d.spheres.len(), 160_000);
    for (k, s) in d.spheres.iter().enumerate() {
        // Sphere k is on line i + 1, where i skips the comment and blank lines.
        let i = (k / 8) * 10 + [0, 1, 2, 4, 5, 6, 8, 9][k % 8];
        assert_eq!((s.center.x, s.center.y, s.radius), (i as f64, -(i as f64) - 0.5, (1 + i % 5) as f64));
    }
    let lines: Vec<&str> = src.split_inclusive('\n').collect();
    let with_errors = |bad: &[usize]| {
        let mut text = lines.clone();
        bad.iter().for_each(|&l| text[l - 1] = "1 2 3 oops\n");
        xyzr_err(&text.concat())
    };
    assert_eq!(with_errors(&[123_457]).line, 123_457);
    assert_eq!(with_errors(&[180_001, 2, 99_999]).line, 2);
    assert_eq!(with_errors(&[180_001, 99_999]).line, 99_999);
}

// ---------------------------------------------------------------------------------------------------- f32r

/// The generator's f32 values of a field, as the f32r reader gives them back.
fn f32r_values(bytes: &[u8]) -> Vec<[f32; 4]> {
    let d = f32r::parse(Path::new("t.f32r"), bytes).unwrap();
    d.spheres.iter().map(|s| [s.center.x, s.center.y, s.center.z, s.radius].map(|v| v as f32)).collect()
}

/// An `.f32r` field holds the generator's f32 values bit for bit, and frames them as an `.xyzr` list does.
#[test]
fn f32r_fields_hold_the_generators_values_and_frame_like_xyzr() {
    let p = FieldParams { count: 5000, ..Default::default() };
    let mut bytes = Vec::new();
    p.write_f32r(&mut bytes).unwrap();
    assert_eq!(bytes.len(), 16 + 16 * 5000);
    let want: Vec<[f32; 4]> = p.spheres().unwrap().collect();
    let got = f32r_values(&bytes);
    assert_eq!(
        got.iter().map(|v| v.map(f32::to_bits)).collect::<Vec<_>>(),
        want.iter().map(|v| v.map(f32::to_bits)).collect::<Vec<_>>()
    );
    // The same spheres written as text and read back (f64 values) round to the same f32s; the scene
    // around them differs only by the text's decimals, far below what frames the camera.
    let from_text = xyzr::parse(Path::new("t.xyzr"), &xyzr_text(&p)).unwrap();
    let from_binary = f32r::parse(Path::new("t.f32r"), &bytes).unwrap();
    assert_eq!((from_binary.materials.len(), from_binary.lights.len()), (1, 1));
    assert!((from_binary.camera.eye - from_text.camera.eye).length() < 1e-6, "{:?}", from_binary.camera);
    assert!(Scene::compile(&from_binary).is_ok());
    // Read from memory as standard input is.
    let again =
        bareray::io::parse_with(SceneFormat::F32r, Path::new("<stdin>"), bytes.clone(), &Default::default());
    let again = again.unwrap().desc;
    assert_eq!(again, from_binary);
}

/// Each way a file can be wrong is an error naming the file and, for records, the record and its byte.
#[test]
fn f32r_errors_name_the_file_record_and_byte() {
    let p = FieldParams { count: 100, ..Default::default() };
    let mut good = Vec::new();
    p.write_f32r(&mut good).unwrap();
    let err = |b: &[u8]| f32r::parse(Path::new("t.f32r"), b).unwrap_err().to_string();
    let mut flipped = good.clone();
    flipped[0] ^= 0x80; // a 7-bit transfer
    let mut crlf = good.clone();
    crlf.remove(5); // a text-mode transfer turning CR LF into LF
    let mut count = good.clone();
    count[12] = 99;
    let mut nan = good.clone();
    nan[16 + 16 * 42 + 4..16 + 16 * 42 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut zero = good.clone();
    zero[16 + 16 * 7 + 12..16 + 16 * 8].copy_from_slice(&0f32.to_le_bytes());
    for (bytes, expected) in [
        (&flipped[..], "t.f32r: not an .f32r sphere list: the first 8 bytes are not 89 46 33 32 52 0d 0a 1a"),
        (&crlf[..], "t.f32r: not an .f32r sphere list"),
        (&xyzr_text(&p).into_bytes()[..], "t.f32r: not an .f32r sphere list"),
        (&good[..11], "t.f32r: the file ends inside the 16-byte header, after 11 bytes"),
        (&good[..16 + 16 * 60 + 15], "t.f32r: the file ends inside record 60 (byte 976): the header's count is 100, which needs 1616 bytes, the file has 991"),
        (&count[..], "t.f32r: 16 bytes follow the last of the header's 99 records"),
        (&nan[..], "t.f32r: record 42 (byte 688): y is not finite (NaN)"),
        (&zero[..], "t.f32r: record 7 (byte 128): radius must be positive, got 0"),
    ] {
        assert!(err(bytes).starts_with(expected), "{} does not start with {expected}", err(bytes));
    }
    let mut longer = good.clone();
    longer.extend_from_slice(&[0; 16 * 3]);
    assert!(err(&longer).starts_with("t.f32r: 48 bytes follow the last of the header's 100 records"));
}
// ---------------------------------------------------------------------------------------------------- field

// Expected spheres were computed independently in Python 3.11 from the contract's text (bench-peers/README.md,
// "Embree harness"): a direct transcription of splitmix64 on Python integers masked to 64 bits,
// u = (next >> 40) * 2.0**-24 in f64, s = 2 / math.cbrt(N), rmin = 0.1*s, rmax = 0.25*s, each value rounded
// with numpy.float32 and printed with str() (shortest round-trip, the same digits as Rust's f32 Display).

#[test]
fn field_1e3_matches_the_contract() {
    let p = FieldParams { count: 1000, ..Default::default() };
    let all: Vec<[f32; 4]> = p.spheres().unwrap().collect();
    assert_eq!(all.len(), 1000);
    assert_eq!(all[0], [0.13312304, 0.49156344, 0.9420054, 0.033330776]);
    assert_eq!(all[1], [-0.1114707, 0.52578866, 0.7546973, 0.035692014]);
    assert_eq!(all[999], [-0.9755169, 0.56174314, -0.67024505, 0.042300448]);
    // The text form round-trips every f32 exactly through the xyzr reader (which reads f64; compile rounds to
    // f32, and the shortest round-trip text rounds back to the same f32).
    let back = xyzr::parse(Path::new("f.xyzr"), &xyzr_text(&p)).unwrap();
    assert_eq!(back.spheres.len(), 1000);
    for (s, e) in back.spheres.iter().zip(&all) {
        let got = [s.center.x as f32, s.center.y as f32, s.center.z as f32, s.radius as f32];
        assert_eq!(got.map(f32::to_bits), e.map(f32::to_bits));
    }
}

#[test]
fn field_1e6_matches_the_contract() {
    let p = FieldParams { count: 1_000_000, ..Default::default() };
    assert_eq!(p.radii().unwrap(), (0.002, 0.005));
    let mut it = p.spheres().unwrap();
    assert_eq!(it.next().unwrap(), [0.13312304, 0.49156344, 0.9420054, 0.0033330775]);
    let rest: Vec<[f32; 4]> = it.collect();
    assert_eq!(rest.len(), 999_999);
    assert_eq!(rest[rest.len() - 1], [0.22951663, 0.6491512, 0.7597028, 0.002159116]);
}

#[test]
fn field_box_seed_and_radii_are_honoured_and_checked() {
    let p = FieldParams {
        count: 8,
        seed: 7,
        lo: [0.0; 3],
        hi: [10.0, 20.0, 30.0],
        rmin: Some(0.5),
        rmax: Some(1.0),
    };
    assert_eq!(p.spheres().unwrap().next().unwrap(), [3.8982968, 0.33576488, 27.02282, 0.79146516]);
    let bad = |q: FieldParams| q.radii().unwrap_err().to_string();
    assert!(bad(FieldParams { count: 0, ..Default::default() }).contains("--count"));
    assert!(
        bad(FieldParams { lo: [0.0, 1.0, 0.0], hi: [1.0, 1.0, 1.0], ..Default::default() }).contains("--box")
    );
    assert!(bad(FieldParams { rmin: Some(0.3), rmax: Some(0.2), ..Default::default() })
        .contains("must not exceed"));
    assert!(bad(FieldParams { rmin: Some(-1.0), ..Default::default() }).contains("--rmin must be a positive"));
    assert!(
        bad(FieldParams { rmax: Some(f64::NAN), ..Default::default() }).contains("--rmax must be a positive")
    );
}

// ---------------------------------------------------------------------------------------------------- flake

#[test]
fn flake_counts_follow_nine_children_per_sphere() {
    for (level, n) in [(2, 91), (3, 820), (4, 7381)] {
        assert_eq!(flake_count(level), n);
        let spheres = flake(level).unwrap();
        assert_eq!(spheres.len() as u64, n);
        // Each level's radius is a third of its parent's: count the smallest ones.
        let smallest = 0.5 / 3f64.powi(level as i32);
        let leaves = spheres.iter().filter(|s| (s[3] - smallest).abs() < 1e-15).count();
        assert_eq!(leaves as u64, 9u64.pow(level));
    }
    assert!(flake(8).is_err());
}

#[test]
fn flake_level_2_reproduces_spd_balls2_to_its_printed_precision() {
    let reference = nff::parse(Path::new("balls2.nff"), BALLS2).unwrap();
    let mine = flake(2).unwrap();
    assert_eq!(mine.len(), reference.spheres.len());
    for (i, (m, r)) in mine.iter().zip(&reference.spheres).enumerate() {
        let want = [r.center.x, r.center.y, r.center.z, r.radius];
        for k in 0..4 {
            // %g prints 6 significant digits: half a unit of the 6th digit is at most 5e-6 of the value.
            let tol = 5e-6 * want[k].abs() + 1e-12;
            assert!((m[k] - want[k]).abs() <= tol, "sphere {i} component {k}: {} vs {}", m[k], want[k]);
        }
    }
}

#[test]
fn flake_nff_parses_back_with_balls_view_lights_and_floor() {
    let d = nff::parse(Path::new("b4.nff"), &flake_nff(4).unwrap()).unwrap();
    let balls = nff::parse(Path::new("balls2.nff"), BALLS2).unwrap();
    assert_eq!((d.spheres.len(), d.kinds.polygons.len(), d.lights.len()), (7381, 1, 3));
    assert_eq!((d.camera, d.render, &d.materials), (balls.camera, balls.render, &balls.materials));
    assert_eq!(d.kinds.polygons, balls.kinds.polygons);
    // Level 4 starts like level 2 (depth first: the first child of the first child comes third) ...
    assert!((d.spheres[2].radius - 0.5 / 9.0).abs() < 1e-16);
    assert!((d.spheres[2].center - balls.spheres[2].center).length() < 1e-6);
    // ... and every sphere's text is its f64 exactly.
    let exact = flake(4).unwrap();
    assert!(d.spheres.iter().zip(&exact).all(|(s, e)| [s.center.x, s.center.y, s.center.z, s.radius] == *e));
}

// ---------------------------------------------------------------------------------------------------- polygon kernel

fn tri_f64() -> (V3<f64>, V3<f64>, V3<f64>) {
    (V3::new(1.0, 1.0, 2.0), V3::new(2.0, 0.0, 0.0), V3::new(0.0, 3.0, 0.0))
}

#[test]
fn triangle_kernel_inside_outside_edge_vertex_parallel() {
    let (v0, e1, e2) = tri_f64();
    let down = |x: f64, y: f64| Ray::new(V3::new(x, y, 5.0), V3::new(0.0, 0.0, -2.0));
    let inf = f64::INFINITY;
    assert_eq!(intersect_triangle(v0, e1, e2, &down(1.5, 1.5), inf), (true, 1.5));
    assert!(!intersect_triangle(v0, e1, e2, &down(2.9, 3.9), inf).0, "beyond the hypotenuse");
    assert!(!intersect_triangle(v0, e1, e2, &down(0.5, 1.5), inf).0, "left of the triangle");
    assert!(intersect_triangle(v0, e1, e2, &down(2.0, 1.0), inf).0, "on an edge: inclusive");
    assert!(intersect_triangle(v0, e1, e2, &down(1.0, 1.0), inf).0, "on a vertex: inclusive");
    let up = Ray::new(V3::new(1.5, 1.5, 0.0), V3::new(0.0, 0.0, 1.0));
    assert_eq!(intersect_triangle(v0, e1, e2, &up, inf), (true, 2.0), "both sides are hit");
    let behind = Ray::new(V3::new(1.5, 1.5, 0.0), V3::new(0.0, 0.0, -1.0));
    assert!(!intersect_triangle(v0, e1, e2, &behind, inf).0);
    for origin_z in [2.0, 3.0] {
        let parallel = Ray::new(V3::new(0.0, 1.5, origin_z), V3::new(1.0, 0.0, 0.0));
        assert!(!intersect_triangle(v0, e1, e2, &parallel, inf).0, "parallel at z = {origin_z}");
    }
    let nan = Ray::new(V3::new(1.5, 1.5, 5.0), V3::new(f64::NAN, 0.0, -1.0));
    assert!(!intersect_triangle(v0, e1, e2, &nan, inf).0);
    // Lanes that miss give t_max, whichever step of the test they fail at.
    for miss in [behind, Ray::new(V3::new(-1.0, 1.5, 5.0), V3::new(0.0, 0.0, -1.0))] {
        assert_eq!(intersect_triangle(v0, e1, e2, &miss, 7.0), (false, 7.0));
    }
}

#[test]
fn triangle_kernel_f32_agrees_with_the_f64_oracle() {
    let (v0, e1, e2) = tri_f64();
    let f32v = |v: V3<f64>| v.to_f32();
    let mut state = 3u64;
    let mut unit = || (lcg(&mut state) as f64) / (1u64 << 31) as f64;
    let (mut hits, mut checked) = (0, 0);
    for _ in 0..20_000 {
        let o = V3::new(unit() * 6.0 - 2.0, unit() * 6.0 - 2.0, 4.0 + unit() * 4.0);
        let target = V3::new(unit() * 4.0, unit() * 5.0, 2.0);
        let ray = Ray::new(o, target - o);
        let (h64, t64) = intersect_triangle(v0, e1, e2, &ray, f64::INFINITY);
        let ray32 = Ray::new(f32v(ray.origin), f32v(ray.dir));
        let (h32, t32) = intersect_triangle(f32v(v0), f32v(e1), f32v(e2), &ray32, f32::INFINITY);
        // Away from the edges both instances must agree on the hit, and on t to f32 accuracy. The point
        // on the triangle's plane (z = 2) says how far from an edge the line passes, hit or miss.
        let p = ray.at((2.0 - ray.origin.z) / ray.dir.z);
        let margin = [(p.x - 1.0), (p.y - 1.0), 1.0 - (p.x - 1.0) / 2.0 - (p.y - 1.0) / 3.0];
        if margin.iter().all(|m| m.abs() > 1e-4) {
            checked += 1;
            assert_eq!(h32, h64, "ray {ray:?}");
            if h64 {
                hits += 1;
                assert!((f64::from(t32) - t64).abs() <= 1e-6 * t64, "t32 {t32} vs t64 {t64}");
            }
        }
    }
    assert!(hits > 1000 && checked > 19_000, "the sample exercises both outcomes: {hits}/{checked}");
}

#[test]
fn a_ray_leaving_a_polygon_never_hits_it_again() {
    // Two parallel squares; a ray starting on the first, heading through it at a grazing angle or away,
    // must never report the first (id 1, after one sphere), yet must see the second (id 2).
    let square = |z: f64| PolygonDesc {
        vertices: [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
            .map(|[x, y]| DVec3::new(x, y, z))
            .to_vec(),
        normals: None,
        material: 0,
    };
    let desc = SceneDesc {
        spheres: vec![SphereDesc { center: DVec3::new(50.0, 0.0, 0.0), radius: 1.0, material: 0 }],
        kinds: KindDescs { polygons: vec![square(0.0), square(-1.0)], ..KindDescs::default() },
        ..SceneDesc::default()
    };
    let scene = Scene::compile(&desc).unwrap();
    let g: &Geometry = &scene.geometry;
    let start = scene.to_rendering(DVec3::new(0.1, 0.2, 0.0));
    let from = Departure { prim: 1, inward: false };
    for dir in [V3::new(0.3f32, 0.1, -1e-3), V3::new(0.0, 0.0, -1.0), V3::new(0.2, 0.3, 1.0)] {
        let ray = Ray::new(start, dir);
        let hit = g.intersect(&ray, from, f32::INFINITY);
        assert_ne!(hit.prim, 1, "{dir:?}");
        let inward = g.intersect(&ray, Departure { prim: 1, inward: true }, f32::INFINITY);
        assert_ne!(inward.prim, 1, "planar primitives have no inside: {dir:?}");
        assert!(!g.occluded(&ray, from, 0.5), "{dir:?}");
    }
    let down = Ray::new(start, V3::new(0.0, 0.0, -1.0));
    assert_eq!(g.intersect(&down, from, f32::INFINITY).prim, 2);
    assert!(g.occluded(&down, from, 2.0) && !g.occluded(&down, from, 0.5));
    assert_eq!(triangulate(&square(0.0).vertices).unwrap().len(), 2);
}

// ---------------------------------------------------------------------------------------------------- CLI

/// The `.xyzr` text `gen field` writes for `p`.
fn xyzr_text(p: &FieldParams) -> String {
    let mut out = Vec::new();
    p.write_xyzr(&mut out).expect("valid field parameters");
    String::from_utf8(out).expect("generated text is ASCII")
}
