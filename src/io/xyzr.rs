//! `.xyzr` sphere lists (the MSMS/Chimera atom-list convention): one sphere `x y z r` per line, separated by
//! any whitespace; blank lines and lines starting with `#` are skipped. Every error names `file:line`.
//!
//! The file holds geometry only, so the rest of the scene is chosen here: bareray's default material, and
//! the benchmark contract's camera orientation (from −z looking +z, up +y, horizontal angle 45°, 1920×1080,
//! pixel centres), centred on the field's bounding box and backed off until the box's front face fills the
//! image in its tighter direction (`frame_box`); for the contract's [−1, 1]³ field that puts the eye near
//! z = −5.6 (the contract's fixed z = −4 crops the field, on purpose). One white light sits above and to the
//! left of the eye so that shading shows the spheres' shape. The CLI overrides the camera. Values go to 8-bit
//! images with [`Transfer::Linear`], as NFF's do (the benchmark's peers read sphere lists as NFF spheres).

use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use crate::kinds::sphere::{sphere_bounds, SphereDesc};
use crate::math::Rgb;

use super::error::SceneError;
use crate::scene::desc::*;

/// Reads an `.xyzr` file.
pub(crate) fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let source = super::error::read_text(path, "sphere list")?;
    parse(path, &source)
}

/// Parses `.xyzr` text; `path` names it in errors. Chunks of whole lines are parsed in parallel (a 1e7-sphere
/// list is 460 MB of text) and joined in file order, so ids, and the first error reported, are those of a
/// sequential read.
pub(crate) fn parse(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
    parse_in_chunks(path, source, CHUNK_BYTES)
}

/// [`parse`] with chunks of about `chunk_bytes` (a whole line at least). Each chunk's sphere lines are
/// counted first, so that its spheres are parsed straight into their place in the one list: no per-chunk
/// lists to grow and then copy (at 1e7 spheres, 400 MB of fresh memory and a copy of it).
fn parse_in_chunks(path: &Path, source: &str, chunk_bytes: usize) -> Result<SceneDesc, SceneError> {
    let chunks = crate::io::pieces::line_pieces(source, chunk_bytes);
    let counts: Vec<usize> =
        chunks.par_iter().map(|text| text.lines().filter(|line| is_sphere(line.trim())).count()).collect();
    // Lines that are not blank or comments are spheres or errors, so with none there is no error to report.
    let total = counts.iter().sum();
    if total == 0 {
        return Err(SceneError::whole_file(path, "no spheres: expected lines of `x y z r`"));
    }
    let unset = SphereDesc { center: DVec3::ZERO, radius: 0.0, material: 0 };
    let mut spheres: Vec<SphereDesc> = (0..total).into_par_iter().map(|_| unset).collect();
    let slots = crate::io::pieces::slices_of(&mut spheres, &counts);
    let parsed: Vec<_> = chunks.par_iter().zip(slots).map(|(text, out)| parse_lines(text, out)).collect();
    if let Some((k, (line, message))) = parsed.into_iter().enumerate().find_map(|(k, r)| Some((k, r.err()?)))
    {
        // Line numbers are counted only for a report: the chunks before the bad one, then its own line.
        let before: usize = chunks[..k].iter().map(|text| text.bytes().filter(|&b| b == b'\n').count()).sum();
        return Err(SceneError::at_line(path, before + line, message));
    }
    Ok(scene_around(spheres))
}

/// Bytes of text per parallel chunk.
const CHUNK_BYTES: usize = 1 << 20;

/// Whether a trimmed line holds a sphere (or an error): it is neither blank nor a `#` comment.
pub(super) fn is_sphere(trimmed: &str) -> bool {
    !trimmed.is_empty() && !trimmed.starts_with('#')
}

/// Parses the sphere lines of `text` into `out` (one slot for each, [`is_sphere`]), or returns the first bad
/// line's number within `text` (from 1) and what is wrong with it.
fn parse_lines(text: &str, out: &mut [SphereDesc]) -> Result<(), (usize, String)> {
    let mut slots = out.iter_mut();
    for (i, line) in text.lines().map(str::trim).enumerate().filter(|(_, line)| is_sphere(line)) {
        *slots.next().expect("a slot for each sphere line") = sphere(line).map_err(|m| (i + 1, m))?;
    }
    Ok(())
}

/// One `x y z r` line.
pub(super) fn sphere(text: &str) -> Result<SphereDesc, String> {
    let mut v = [0.0f64; 4];
    let mut words = text.split_ascii_whitespace();
    for (k, name) in ["x", "y", "z", "r"].iter().enumerate() {
        let w = words.next().ok_or_else(|| format!("expected 4 numbers `x y z r`, got {k}"))?;
        v[k] = match w.parse::<f64>() {
            Ok(x) if x.is_finite() && (x as f32).is_finite() => x,
            _ => return Err(format!("expected {name} (a finite number within f32 range), got `{w}`")),
        };
    }
    if let Some(extra) = words.next() {
        return Err(format!("expected 4 numbers `x y z r`, got more (`{extra}`)"));
    }
    if v[3] <= 0.0 {
        return Err(format!("radius must be positive, got {}", v[3]));
    }
    Ok(SphereDesc { center: DVec3::new(v[0], v[1], v[2]), radius: v[3], material: 0 })
}

/// Writes `spheres` as `.xyzr` after the `#` line `comment`: `x y z r` per line, each value in the
/// shortest text that reads back to it (as an f32 where the value is one, so f32 fields stay short).
pub fn write(w: &mut impl Write, comment: &str, spheres: &[SphereDesc]) -> io::Result<()> {
    writeln!(w, "# {comment}\n# x y z r")?;
    for s in spheres {
        let [x, y, z, r] = [s.center.x, s.center.y, s.center.z, s.radius].map(Shortest);
        writeln!(w, "{x} {y} {z} {r}")?;
    }
    Ok(())
}

/// An f64 shown as its f32 when it is one exactly.
struct Shortest(f64);

impl std::fmt::Display for Shortest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let single = self.0 as f32;
        match f64::from(single) == self.0 {
            true => write!(f, "{single}"),
            false => write!(f, "{}", self.0),
        }
    }
}

/// A scene showing `spheres`: default material, a camera framing their bounds, one light.
pub(crate) fn scene_around(spheres: Vec<SphereDesc>) -> SceneDesc {
    let (lo, hi) = sphere_bounds(&spheres);
    SceneDesc { spheres, ..scene_framing(lo, hi, None) }
}

/// The scene [`scene_around`] makes for spheres within `[lo, hi]`, without the spheres (a mapped field's
/// are compiled apart, [`crate::compile::Scene::compile_mapped`]). Without a `view`, the contract camera
/// ([`frame_box`]) and a light above and left of it; with one, the box's bounding sphere seen from the
/// side `view` points to ([`frame_sphere`]) and a headlight, a light at the eye.
pub(crate) fn scene_framing(lo: DVec3, hi: DVec3, view: Option<DVec3>) -> SceneDesc {
    let (camera, light) = match view {
        None => {
            let camera = frame_box(lo, hi);
            let reach = (camera.eye - (lo + hi) * 0.5).length();
            (camera, camera.eye + DVec3::new(0.5, 0.5, 0.0) * reach)
        }
        Some(view) => {
            let camera = frame_sphere(lo, hi, view);
            (camera, camera.eye)
        }
    };
    SceneDesc {
        camera,
        materials: vec![Material::default()],
        lights: vec![LightDesc { position: light, color: Rgb::all(1.0), falloff: Falloff::None }],
        // Colours as in NFF: written as they are (see the NFF reader's module documentation).
        render: RenderDesc { transfer: Transfer::Linear, ..RenderDesc::default() },
        ..SceneDesc::default()
    }
}

/// The share of the view's half-angle that the bounding sphere fills in [`frame_sphere`].
pub(crate) const SPHERE_FILL: f64 = 0.95;

/// A camera on the `view` side of the box `[lo, hi]`, looking at its centre along −`view`, backed off
/// until the box's bounding sphere fits the image (1920×1080, horizontal angle 45°) in its tighter
/// direction, with a margin ([`SPHERE_FILL`]). Up is +y, or −z looking down from +y and +z looking up
/// from −y (a view within about 8° of the y axis).
pub(crate) fn frame_sphere(lo: DVec3, hi: DVec3, view: DVec3) -> CameraDesc {
    let (width, height) = (1920u32, 1080u32);
    let hfov = 45.0f64;
    let tan_w = (hfov.to_radians() / 2.0).tan();
    let tan_h = tan_w * f64::from(height) / f64::from(width);
    let half_angle = tan_w.min(tan_h).atan() * SPHERE_FILL;
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo) * 0.5).length().max(1e-9);
    let dir = view.try_normalize().unwrap_or(DVec3::Z);
    let up = match dir.y {
        y if y > 0.99 => DVec3::NEG_Z,
        y if y < -0.99 => DVec3::Z,
        _ => DVec3::Y,
    };
    CameraDesc::looking_at(centre + dir * (radius / half_angle.sin()), centre, up, hfov, width, height)
}

/// The contract-oriented camera (see the module documentation) for the box `[lo, hi]`.
pub(crate) fn frame_box(lo: DVec3, hi: DVec3) -> CameraDesc {
    let (width, height) = (1920u32, 1080u32);
    let hfov = 45.0f64;
    let tan_w = (hfov.to_radians() / 2.0).tan();
    let tan_h = tan_w * f64::from(height) / f64::from(width);
    let centre = (lo + hi) * 0.5;
    let half = ((hi - lo) * 0.5).max(DVec3::splat(1e-9));
    let back = half.z + (half.x / tan_w).max(half.y / tan_h);
    CameraDesc::looking_at(centre - DVec3::new(0.0, 0.0, back), centre, DVec3::Y, hfov, width, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text of `n` lines: spheres in varied spellings, comments, blank lines, CRLF endings, no final newline.
    fn list(n: usize) -> String {
        let mut s = String::new();
        for i in 0..n {
            let v = (i as f64 * 0.37).sin();
            s += &match i % 7 {
                0 => "# comment 1 2 3\n".to_owned(),
                1 => "\n".to_owned(),
                2 => format!("{v} {} {:e} 0.{i}1\r\n", v * 3.0, -v),
                _ => format!("  {v}\t{i}e-3 {} {}\n", 1.0 / (i as f64 + 1.0), i % 5 + 1),
            };
        }
        s + "1 2 3 4"
    }

    /// Chunks of any size, down to a line each, read what one chunk (a sequential read) reads, bit for bit,
    /// and report the same first error at the same line.
    #[test]
    fn chunked_reads_equal_the_sequential_read() {
        let path = Path::new("t.xyzr");
        let text = list(3000);
        let whole = parse_in_chunks(path, &text, usize::MAX).unwrap();
        // 429 comments and 429 blank lines among the 3000; the last line has no newline.
        assert_eq!(whole.spheres.len(), 3000 - 2 * 429 + 1);
        let bits = |d: &SceneDesc| -> Vec<[u64; 4]> {
            d.spheres
                .iter()
                .map(|s| [s.center.x, s.center.y, s.center.z, s.radius].map(f64::to_bits))
                .collect()
        };
        let mut bad = text.clone();
        for (line, junk) in [(2900, "1 2 3 -4"), (1700, "1 2 x 4"), (2500, "1 2 3")] {
            let at: usize = bad.split_inclusive('\n').take(line - 1).map(str::len).sum();
            bad.insert_str(at, &format!("{junk}\n"));
        }
        let first = parse_in_chunks(path, &bad, usize::MAX).unwrap_err();
        assert_eq!(
            (first.line, first.message.as_str()),
            (1700, "expected z (a finite number within f32 range), got `x`")
        );
        for size in [1, 2, 40, 100, 4096, 65_536] {
            let chunked = parse_in_chunks(path, &text, size).unwrap();
            assert_eq!(bits(&chunked), bits(&whole), "chunks of {size} bytes");
            assert_eq!(chunked, whole, "chunks of {size} bytes");
            assert_eq!(parse_in_chunks(path, &bad, size).unwrap_err(), first, "chunks of {size} bytes");
        }
    }

    #[test]
    fn a_view_frames_the_bounding_sphere_from_its_side() {
        let (lo, hi) = (DVec3::new(-1.0, -2.0, -2.0), DVec3::new(3.0, 2.0, 2.0));
        let cam = frame_sphere(lo, hi, DVec3::new(-2.0, 0.0, 0.0));
        let centre = DVec3::new(1.0, 0.0, 0.0);
        assert_eq!(cam.aim, Aim::LookAt(centre));
        assert!(cam.eye.x < -1.0 && cam.eye.y == 0.0 && cam.eye.z == 0.0, "{cam:?}");
        // The bounding sphere (radius the half-diagonal) subtends the tighter half-angle, shrunk.
        let r = ((hi - lo) * 0.5).length();
        let tan_h = (22.5f64.to_radians()).tan() * 1080.0 / 1920.0;
        let seen = (r / (cam.eye - centre).length()).asin();
        assert!((seen - tan_h.atan() * SPHERE_FILL).abs() < 1e-12);
        assert_eq!(frame_sphere(lo, hi, DVec3::Y).up, DVec3::NEG_Z);
        let scene = scene_framing(lo, hi, Some(DVec3::Z));
        assert_eq!(scene.lights[0].position, scene.camera.eye);
    }

    #[test]
    fn camera_sees_the_whole_front_face() {
        let cam = frame_box(DVec3::splat(-1.0), DVec3::splat(1.0));
        // The face z = −1 is (eye distance − 1) away; its half-height 1 must fit tan_h times that.
        let d = -1.0 - cam.eye.z;
        let tan_h = (22.5f64.to_radians()).tan() * 1080.0 / 1920.0;
        assert!((d * tan_h - 1.0).abs() < 1e-12, "{cam:?}");
    }
}
