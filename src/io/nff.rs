//! Eric Haines' Neutral File Format (NFF), the language of the Standard Procedural Databases (SPD).
//!
//! The file is read as a stream of whitespace-separated tokens, each with its line number: entities may be
//! split over lines and use any whitespace, numbers may use scientific notation, and `#` starts a comment that
//! runs to the end of its line. Every error names `file:line` and what was expected there. Supported:
//! `v` (with `from`, `at`, `up`, `angle`, `hither`, `resolution` in any order), `b`, `l` (with or without
//! colour), `f`, `s`, `p`, `pp`, and `c` (`base.x base.y base.z base_radius apex.x apex.y apex.z apex_radius`:
//! an open cone or cylinder without caps; a radius may be 0 but not negative, not both are 0, and the two
//! end points differ).
//!
//! # Framing
//!
//! NFF defines `angle` between the centres of the extreme pixel rows and columns, with aspect ratio 1. SPD's
//! reference images were rendered by POV-Ray 3.1 from SPD's own POV-Ray output, whose camera spans
//! `2·tan(angle/2)` from the left edge of the image to the right edge, pixels sampled at their centres. To
//! frame like those images, the angle becomes bareray's [`Field::HorizontalAngle`] with [`Sweep::PixelCentre`]
//! (the window's edges are the image's edges). The literal NFF reading ([`Sweep::WindowEdges`]) differs by
//! one pixel across the image; Tachyon's reader frames visibly wider than both. NFF assumes square images;
//! for a non-square `resolution` the angle is taken as the horizontal one.
//!
//! NFF objects are one-sided unless transmitting; that only matters to renderers that cull back faces.
//! bareray's primitives are two-sided, which shades the same for SPD's closed or floor-like geometry.
//!
//! # Shading
//!
//! `f r g b Kd Ks shine T ior` becomes a [`Material`] with `diffuse = Kd`, `specular = Ks` (Phong exponent
//! `shine`), `reflect = Ks` (NFF's Ks is also the mirror weight in Whitted use), `transmit = T`, `ior`. NFF has
//! no ambient term; NFF materials get `NFF_AMBIENT`, the value SPD's own NFF reader gives them, which keeps
//! fully shadowed floor from going black. SPD's generators pass their own per-material values to their other
//! outputs only (balls: floor 0.2, spheres 0); `render --ambient` sets them. Lights without colour
//! each get intensity `1/sqrt(number of lights)`, as SPD's converters do for every renderer but NFF's own.
//!
//! # Colours
//!
//! NFF colours are display values: SPD's own renderer, POV-Ray (SPD's POV-Ray output, rendered as SPD's
//! reference images were) and Tachyon write the shaded values out as they come, clamped and times 255, with
//! no transfer curve. NFF scenes therefore get [`Transfer::Linear`]; encoding them with the sRGB curve, as
//! TOML scenes are, washes them out: against POV-Ray's render of SPD's own POV-Ray output the curve is most
//! of the difference, and the ambient term the rest, which SPD's values (`--ambient 0.2,0`) take away
//! (measured: docs/scene-format.md, "NFF (SPD)"). `render --transfer srgb` still chooses the curve.

use std::path::Path;

use glam::DVec3;

use crate::camera::Camera;
use crate::math::Rgb;

use super::error::SceneError;
use crate::kinds::cone::ConeDesc;
use crate::kinds::polygon::{triangulate, PolygonDesc};
use crate::kinds::sphere::SphereDesc;
use crate::scene::desc::*;

mod chunks;
mod tokens;

use tokens::{Tok, Tokens};

/// Ambient coefficient of NFF materials (see the module documentation).
pub(crate) const NFF_AMBIENT: f32 = 0.1;

/// Reads an NFF scene from a file.
pub(crate) fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let source = super::error::read_text(path, "scene")?;
    parse(path, &source)
}

/// Parses NFF text; `path` names it in errors. Large files are cut into pieces at entity boundaries and the
/// pieces read in parallel (the `chunks` module); the scene, and any error, are those of one reading from
/// the start.
pub fn parse(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
    chunks::parse(path, source, chunks::CHUNK_BYTES)
}

/// Reads `source` from start to end on the calling thread.
fn parse_sequential(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
    let mut reader = Reader::new(path, source, false);
    reader.read_all()?;
    reader.finish()
}

struct Reader<'a> {
    path: &'a Path,
    tokens: Tokens<'a>,
    desc: SceneDesc,
    /// The material of the last `f`, if any.
    material: Option<u32>,
    /// Reading a piece of a file: objects before the piece's first `f` get [`chunks::INHERITED`] (the fill
    /// in force where the piece starts), not a material of their own.
    piece: bool,
    /// Indices of lights given without colour, scaled once the number of lights is known.
    colourless: Vec<usize>,
    view_seen: bool,
    background_seen: bool,
}

impl<'a> Reader<'a> {
    fn new(path: &'a Path, source: &'a str, piece: bool) -> Self {
        Reader {
            path,
            tokens: Tokens::new(source),
            desc: SceneDesc {
                render: RenderDesc { transfer: Transfer::Linear, ..RenderDesc::default() },
                ..SceneDesc::default()
            },
            material: None,
            piece,
            colourless: Vec::new(),
            view_seen: false,
            background_seen: false,
        }
    }

    fn read_all(&mut self) -> Result<(), SceneError> {
        while let Some(tok) = self.tokens.next() {
            self.entity(tok)?;
        }
        Ok(())
    }

    fn err(&self, line: usize, message: impl Into<String>) -> SceneError {
        SceneError::at_line(self.path, line, message)
    }

    /// The next token, or an error saying what was expected instead of the end of the file.
    fn expect(&mut self, what: &str) -> Result<Tok<'a>, SceneError> {
        let last = self.tokens.line();
        self.tokens.next().ok_or_else(|| self.err(last, format!("unexpected end of file, expected {what}")))
    }

    fn number(&mut self, what: &str) -> Result<f64, SceneError> {
        let tok = self.expect(what)?;
        let (text, line) = (tok.text, tok.line);
        match text.parse::<f64>() {
            // Geometry is rendered in f32: a value beyond its range would become infinite there.
            Ok(v) if v.is_finite() && (v as f32).is_finite() => Ok(v),
            _ => {
                Err(self
                    .err(line, format!("expected {what} (a finite number within f32 range), got `{text}`")))
            }
        }
    }

    fn vec3(&mut self, what: &str) -> Result<DVec3, SceneError> {
        Ok(DVec3::new(self.number(what)?, self.number(what)?, self.number(what)?))
    }

    fn color(&mut self, what: &str) -> Result<Rgb, SceneError> {
        let line = self.tokens.peek().map_or(self.tokens.line(), |t| t.line);
        let c = self.vec3(what)?;
        if c.min_element() < 0.0 {
            return Err(self.err(line, format!("{what} must not be negative, got {c}")));
        }
        Ok(Rgb::new(c.x as f32, c.y as f32, c.z as f32))
    }

    /// A count or resolution: a whole number in `lo..=hi`.
    fn integer(&mut self, what: &str, lo: u32, hi: u32) -> Result<u32, SceneError> {
        let tok = self.expect(what)?;
        let (text, line) = (tok.text, tok.line);
        match text.parse::<u32>() {
            Ok(v) if (lo..=hi).contains(&v) => Ok(v),
            _ => {
                Err(self
                    .err(line, format!("expected {what} (a whole number from {lo} to {hi}), got `{text}`")))
            }
        }
    }

    fn entity(&mut self, tok: Tok<'_>) -> Result<(), SceneError> {
        let line = tok.line;
        match tok.text {
            "v" => self.view(line),
            "b" => {
                self.desc.render.background = self.color("background colour r g b")?;
                self.background_seen = true;
                Ok(())
            }
            "l" => self.light(),
            "f" => self.fill(line),
            "s" => self.sphere(line),
            "p" => self.polygon(line, false),
            "pp" => self.polygon(line, true),
            "c" => self.cone(line),
            other => Err(self.err(
                line,
                format!("unknown entity `{other}`, expected one of v, b, l, f, s, p, pp, c (or a # comment)"),
            )),
        }
    }

    /// `v` and its keyword lines, in any order; all but `hither` are required.
    fn view(&mut self, line: usize) -> Result<(), SceneError> {
        if self.view_seen {
            return Err(self.err(line, "a second view (`v`): NFF files have one"));
        }
        self.view_seen = true;
        let (mut from, mut at, mut up, mut angle, mut res) = (None, None, None, None, None);
        while let Some(key) = self.tokens.peek().map(|t| t.text) {
            match key {
                "from" | "at" | "up" | "angle" | "hither" | "resolution" => self.tokens.next(),
                _ => break,
            };
            match key {
                "from" => from = Some(self.vec3("`from` x y z")?),
                "at" => at = Some(self.vec3("`at` x y z")?),
                "up" => up = Some(self.vec3("`up` x y z")?),
                "angle" => angle = Some(self.number("`angle` in degrees")?),
                // bareray needs no near plane: rays start at the eye. Read and checked, then ignored.
                "hither" => {
                    self.number("`hither` distance")?;
                }
                _ => res = Some((self.integer("width", 1, 65536)?, self.integer("height", 1, 65536)?)),
            }
        }
        let missing = |name: &str| self.err(line, format!("view (`v`) lacks its `{name}` line"));
        let camera = CameraDesc {
            eye: from.ok_or_else(|| missing("from"))?,
            aim: Aim::LookAt(at.ok_or_else(|| missing("at"))?),
            up: up.ok_or_else(|| missing("up"))?,
            distance: 1.0,
            field: Field::HorizontalAngle(angle.ok_or_else(|| missing("angle"))?),
            width: res.ok_or_else(|| missing("resolution"))?.0,
            height: res.ok_or_else(|| missing("resolution"))?.1,
            sweep: Sweep::PixelCentre,
        };
        Camera::new(&camera).map_err(|e| self.err(line, format!("view: {e}")))?;
        self.desc.camera = camera;
        Ok(())
    }

    /// `l x y z [r g b]`: the colour is there when a number follows the position.
    fn light(&mut self) -> Result<(), SceneError> {
        let position = self.vec3("light position x y z")?;
        let has_color = self.tokens.peek().is_some_and(|t| t.text.parse::<f64>().is_ok());
        let color = if has_color {
            self.color("light colour r g b")?
        } else {
            self.colourless.push(self.desc.lights.len());
            Rgb::all(1.0)
        };
        self.desc.lights.push(LightDesc { position, color, falloff: Falloff::None });
        Ok(())
    }

    /// `f r g b Kd Ks shine T ior`.
    fn fill(&mut self, line: usize) -> Result<(), SceneError> {
        let color = self.color("fill colour r g b")?;
        let mut coef = [0.0f64; 5];
        for (v, what) in coef.iter_mut().zip(["Kd", "Ks", "shine", "T", "ior"]) {
            *v = self.number(what)?;
        }
        let [kd, ks, shine, t, ior] = coef;
        if kd < 0.0 || ks < 0.0 || shine < 0.0 || t < 0.0 {
            return Err(self.err(line, "fill: Kd, Ks, shine and T must not be negative"));
        }
        if t > 0.0 && ior <= 0.0 {
            return Err(self.err(line, format!("fill: index of refraction must be positive, got {ior}")));
        }
        self.desc.materials.push(Material {
            color,
            checker: None,
            ambient: NFF_AMBIENT,
            diffuse: kd as f32,
            specular: ks as f32,
            shininess: shine as f32,
            reflect: ks as f32,
            transmit: t as f32,
            // Only transmitting fills use the index; others may carry anything, e.g. 0.
            ior: if ior > 0.0 { ior as f32 } else { 1.0 },
            fresnel: false,
        });
        self.material = Some(self.desc.materials.len() as u32 - 1);
        Ok(())
    }

    /// The current fill; objects before any `f` get bareray's default material (in a piece of a file,
    /// [`chunks::INHERITED`] until the piece's first `f`).
    fn current_material(&mut self) -> u32 {
        if self.piece && self.material.is_none() {
            return chunks::INHERITED;
        }
        *self.material.get_or_insert_with(|| {
            self.desc.materials.push(Material { ambient: NFF_AMBIENT, ..Material::default() });
            self.desc.materials.len() as u32 - 1
        })
    }

    fn sphere(&mut self, line: usize) -> Result<(), SceneError> {
        let center = self.vec3("sphere centre x y z")?;
        let radius = self.number("sphere radius")?;
        if radius <= 0.0 {
            return Err(self.err(line, format!("sphere radius must be positive, got {radius}")));
        }
        let material = self.current_material();
        self.desc.spheres.push(SphereDesc { center, radius, material });
        Ok(())
    }

    /// `c`: base point and radius, then apex point and radius, on one line or several. Errors name the
    /// line of the `c`.
    fn cone(&mut self, line: usize) -> Result<(), SceneError> {
        let base = self.vec3("cone base x y z")?;
        let base_radius = self.number("cone base radius")?;
        let apex = self.vec3("cone apex x y z")?;
        let apex_radius = self.number("cone apex radius")?;
        if base_radius < 0.0 || apex_radius < 0.0 {
            return Err(self
                .err(line, format!("cone radii must not be negative, got {base_radius} and {apex_radius}")));
        }
        if base_radius == 0.0 && apex_radius == 0.0 {
            return Err(self.err(line, "cone has radius 0 at both ends (it would be a line)"));
        }
        if base == apex {
            return Err(self.err(line, format!("cone base and apex are the same point {base}")));
        }
        let material = self.current_material();
        self.desc.kinds.cones.push(ConeDesc { base, base_radius, apex, apex_radius, material });
        Ok(())
    }

    /// `p n` then n vertices; `pp n` then n vertices each followed by its normal.
    fn polygon(&mut self, line: usize, patch: bool) -> Result<(), SceneError> {
        let n = self.integer("number of vertices", 3, 1 << 20)?;
        let mut vertices = Vec::with_capacity(n as usize);
        let mut normals = Vec::with_capacity(if patch { n as usize } else { 0 });
        for _ in 0..n {
            vertices.push(self.vec3("polygon vertex x y z")?);
            if patch {
                normals.push(self.vec3("patch vertex normal nx ny nz")?);
            }
        }
        triangulate(&vertices).map_err(|e| self.err(line, e.to_string()))?;
        let material = self.current_material();
        let normals = patch.then_some(normals);
        self.desc.kinds.polygons.push(PolygonDesc { vertices, normals, material });
        Ok(())
    }

    fn finish(mut self) -> Result<SceneDesc, SceneError> {
        if !self.view_seen {
            return Err(SceneError::whole_file(
                self.path,
                "no view (`v`): an NFF file must define its camera",
            ));
        }
        let scale = 1.0 / (self.desc.lights.len() as f32).sqrt();
        for &i in &self.colourless {
            self.desc.lights[i].color = Rgb::all(scale);
        }
        Ok(self.desc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VIEW: &str = "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 48\n";

    fn parse_str(s: &str) -> Result<SceneDesc, SceneError> {
        parse(Path::new("t.nff"), s)
    }

    #[test]
    fn tokens_may_span_lines_and_use_any_whitespace() {
        let d = parse_str(&format!("{VIEW}s\t1e0  2\r\n 3\n\n   0.5 # trailing\n# whole line\n")).unwrap();
        assert_eq!(d.spheres[0].center, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(d.spheres[0].radius, 0.5);
        assert_eq!((d.camera.width, d.camera.height), (64, 48));
    }

    #[test]
    fn cones_on_one_line_or_split_across_lines() {
        let d = parse_str(&format!(
            "{VIEW}f 1 0 0 1 0 0 0 0\nc 0 0 0 1 0 0 2 0.5\nc\n1 2 3\n 0 # base\n4 5 6 2\n"
        ))
        .unwrap();
        assert_eq!(d.kinds.cones.len(), 2);
        let c = d.kinds.cones[0];
        assert_eq!(
            (c.base, c.base_radius, c.apex, c.apex_radius),
            (DVec3::ZERO, 1.0, DVec3::new(0.0, 0.0, 2.0), 0.5)
        );
        let c = d.kinds.cones[1];
        assert_eq!(
            (c.base, c.base_radius, c.apex, c.apex_radius),
            (DVec3::new(1.0, 2.0, 3.0), 0.0, DVec3::new(4.0, 5.0, 6.0), 2.0)
        );
        assert_eq!(c.material, 0, "the current fill");
    }

    #[test]
    fn bad_cones_name_file_and_line() {
        let view_lines = VIEW.lines().count();
        for (body, line, says) in [
            ("c 0 0 0 -1 0 0 1 1\n", 1, "must not be negative"),
            ("\nc 0 0 0 1\n 0 0 1 -0.5\n", 2, "must not be negative"),
            ("c 1 2 3 1 1 2 3 2\n", 1, "same point"),
            ("c 0 0 0 0 0 0 1 0\n", 1, "both ends"),
            ("c 0 0 0 1 0 0 x 1\n", 1, "cone apex x y z"),
            ("c 0 0 0 1\n0 0 1\n", 2, "unexpected end of file, expected cone apex radius"),
        ] {
            let e = parse_str(&format!("{VIEW}{body}")).unwrap_err();
            assert_eq!(e.line, view_lines + line, "{body:?}: {e}");
            assert!(e.to_string().starts_with(&format!("t.nff:{}: ", view_lines + line)), "{e}");
            assert!(e.message.contains(says), "{body:?}: {e}");
        }
    }

    #[test]
    fn colourless_lights_share_unit_power_and_coloured_ones_keep_theirs() {
        let d = parse_str(&format!("{VIEW}l 1 2 3\nl 4 5 6 0.5 0.25 1\nl 7 8 9\nl 0 0 0\n")).unwrap();
        assert_eq!(d.lights[0].color, Rgb::all(0.5));
        assert_eq!(d.lights[1].color, Rgb::new(0.5, 0.25, 1.0));
        assert_eq!(d.lights[3].position, DVec3::ZERO);
    }
}
