//! bareray's own scene format, in TOML. Every key is optional but the shapes; unknown keys are errors; every
//! error names the file, the line and what was expected. The format is documented in README.md.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

use ::toml::Spanned;
use glam::{DAffine3, DVec3};
use serde::Deserialize;

use crate::camera::Camera;
use crate::kinds::placement::{self, TransformOp};
#[allow(unused_imports)] // used per registered kind
use crate::kinds::{Kind, KindDescs, KindError};
use crate::math::Rgb;

use super::error::SceneError;
use crate::scene::desc::*;

type Vec3 = [f64; 3];

/// The file's tables, with an array of tables per registered kind ([`crate::kinds::registry!`]), and
/// the reading of those arrays into the description.
macro_rules! file_with_kinds {
    ($($field:ident: $kind:ty),* $(,)?) => {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct File {
            camera: Option<Spanned<CameraToml>>,
            render: Option<RenderToml>,
            #[serde(default)]
            materials: BTreeMap<String, MaterialToml>,
            #[serde(default)]
            lights: Vec<LightToml>,
            #[serde(default)]
            spheres: Vec<SphereToml>,
            $(
                #[serde(default)]
                $field: Vec<<$kind as Kind>::Toml>,
            )*
        }

        // With no kind registered, the loop expands to nothing.
        #[allow(unused_variables, unused_mut)]
        impl Reader<'_> {
            /// The registered kinds' tables, each with its material index from `material`.
            fn kinds(
                &self,
                file: &File,
                material: impl Fn(Option<&Spanned<String>>) -> Result<u32, SceneError>,
            ) -> Result<KindDescs, SceneError> {
                let mut kinds = KindDescs::default();
                $(
                    for t in &file.$field {
                        let m = material(<$kind as Kind>::toml_material(t))?;
                        kinds.$field.push(<$kind as Kind>::from_toml(t, m).map_err(|e| self.kind_err(e))?);
                    }
                )*
                Ok(kinds)
            }
        }
    };
}
crate::kinds::registry!(file_with_kinds);

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    eye: Option<Vec3>,
    look_at: Option<Vec3>,
    direction: Option<Vec3>,
    up: Option<Vec3>,
    distance: Option<f64>,
    hfov: Option<f64>,
    pixel_size: Option<f64>,
    width: Option<u32>,
    height: Option<u32>,
    sweep: Option<SweepToml>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum SweepToml {
    PixelCentre,
    WindowEdges,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderToml {
    samples: Option<Spanned<u32>>,
    pattern: Option<PatternToml>,
    postfilter: Option<PostFilterToml>,
    filter: Option<FilterToml>,
    filter_radius: Option<Spanned<f64>>,
    max_depth: Option<u32>,
    shade: Option<Spanned<String>>,
    background: Option<Spanned<Vec3>>,
    ambient: Option<Spanned<Vec3>>,
    transfer: Option<TransferToml>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum TransferToml {
    Srgb,
    Linear,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "kebab-case")]
enum PatternToml {
    Grid,
    HalfPixel,
    Stratified,
    R2,
    Sobol,
    Coverage,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum FilterToml {
    Box,
    Tent,
    Gaussian,
    Mitchell,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum PostFilterToml {
    None,
    #[serde(rename = "lecture-3x3")]
    Lecture3x3,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialToml {
    color: Option<Spanned<Vec3>>,
    checker: Option<CheckerToml>,
    ambient: Option<Spanned<f64>>,
    diffuse: Option<Spanned<f64>>,
    specular: Option<Spanned<f64>>,
    shininess: Option<Spanned<f64>>,
    reflect: Option<Spanned<f64>>,
    transmit: Option<Spanned<f64>>,
    ior: Option<Spanned<f64>>,
    fresnel: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CheckerToml {
    color: Spanned<Vec3>,
    size: Spanned<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightToml {
    position: Vec3,
    color: Option<Spanned<Vec3>>,
    intensity: Option<Spanned<f64>>,
    falloff: Option<FalloffToml>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum FalloffToml {
    None,
    InverseSquare,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereToml {
    center: Vec3,
    radius: Spanned<f64>,
    material: Option<Spanned<String>>,
    transform: Option<Vec<Spanned<TransformOp>>>,
}

/// Reads a TOML scene from a file.
pub fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let source = super::error::read_text(path, "scene")?;
    parse(path, &source)
}

/// Parses TOML scene text; `path` names it in errors.
pub fn parse(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
    let file: File = ::toml::from_str(source).map_err(|e| match e.span() {
        Some(span) => SceneError::at_offset(path, source, span.start, e.message().trim()),
        None => spanless(path, source, e.message().trim()),
    })?;
    Reader { path, source }.build(file)
}

/// An error the toml crate gives without a place. The one known is its limit on the parts of a dotted key
/// or table name (80), which it reports as "recursion limit": that is put at the line whose key has the most
/// dots, or at the start of the file if no key has any.
fn spanless(path: &Path, source: &str, message: &str) -> SceneError {
    let dots = |line: &str| {
        let line = line.trim_start();
        let key = if line.starts_with('[') { line.split(']').next() } else { line.split('=').next() };
        key.map_or(0, |k| k.matches('.').count())
    };
    let (mut best, mut offset, mut at) = (0, 0, 0);
    for line in source.split_inclusive('\n') {
        let n = dots(line);
        if n > best {
            (best, offset) = (n, at + (line.len() - line.trim_start().len()));
        }
        at += line.len();
    }
    let message = if message == "recursion limit" && best > 0 {
        format!("{message}: a dotted key or table name of {} parts (the limit is 80)", best + 1)
    } else {
        message.to_owned()
    };
    SceneError::at_offset(path, source, offset, message)
}

struct Reader<'a> {
    path: &'a Path,
    source: &'a str,
}

impl Reader<'_> {
    fn err(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::at_offset(self.path, self.source, span.start, message)
    }

    /// A value that must lie in a range, with the key's name for the message.
    fn ranged(
        &self,
        v: &Spanned<f64>,
        key: &str,
        ok: impl Fn(f64) -> bool,
        want: &str,
    ) -> Result<f32, SceneError> {
        let x = *v.get_ref();
        if ok(x) && x.is_finite() {
            Ok(x as f32)
        } else {
            Err(self.err(v.span(), format!("{key} must be {want}, got {x}")))
        }
    }

    fn color(&self, v: &Spanned<Vec3>, key: &str) -> Result<Rgb, SceneError> {
        let c = v.get_ref();
        if c.iter().all(|x| x.is_finite() && *x >= 0.0) {
            Ok(Rgb::new(c[0] as f32, c[1] as f32, c[2] as f32))
        } else {
            Err(self.err(v.span(), format!("{key} must be three finite non-negative numbers, got {c:?}")))
        }
    }

    fn build(&self, file: File) -> Result<SceneDesc, SceneError> {
        let (names, materials) = self.materials(&file.materials)?;
        let material = |m: Option<&Spanned<String>>| -> Result<u32, SceneError> {
            match m {
                None => Ok(0),
                Some(name) => names.get(name.get_ref().as_str()).copied().ok_or_else(|| {
                    let known: Vec<&str> = names.keys().copied().collect();
                    self.err(
                        name.span(),
                        format!(
                            "unknown material `{}`, expected one of {}",
                            name.get_ref(),
                            known.join(", ")
                        ),
                    )
                }),
            }
        };
        let mut kinds = self.kinds(&file, material)?;
        let mut desc = SceneDesc {
            camera: self.camera(file.camera)?,
            render: self.render(file.render)?,
            materials,
            ..SceneDesc::default()
        };
        for l in &file.lights {
            desc.lights.push(self.light(l)?);
        }
        for s in &file.spheres {
            let radius =
                self.ranged(&s.radius, "radius", |r| r > 0.0 && (r as f32).is_finite(), "positive")?;
            if !s.center.iter().all(|c| (*c as f32).is_finite()) {
                return Err(self.err(
                    s.radius.span(),
                    format!("center must be finite (within f32 range), got {:?}", s.center),
                ));
            }
            let center = DVec3::from(s.center);
            let mat = material(s.material.as_ref())?;
            match &s.transform {
                None => desc.spheres.push(SphereDesc { center, radius: *s.radius.get_ref(), material: mat }),
                Some(ops) => {
                    let user = self.transform(ops)?;
                    let radii = DVec3::splat(f64::from(radius));
                    kinds.ellipsoids.push(crate::kinds::ellipsoid::placed(center, user, radii, mat));
                }
            }
        }
        desc.kinds = kinds;
        Ok(desc)
    }

    fn camera(&self, cam: Option<Spanned<CameraToml>>) -> Result<CameraDesc, SceneError> {
        let Some(cam) = cam else {
            return Ok(CameraDesc::default());
        };
        let span = cam.span();
        let c = cam.into_inner();
        let d = CameraDesc::default();
        let aim = match (c.look_at, c.direction) {
            (Some(_), Some(_)) => return Err(self.err(span, "camera: give look_at or direction, not both")),
            (Some(p), None) => Aim::LookAt(p.into()),
            (None, Some(v)) => Aim::Direction(v.into()),
            (None, None) => d.aim,
        };
        let field = match (c.hfov, c.pixel_size) {
            (Some(_), Some(_)) => return Err(self.err(span, "camera: give hfov or pixel_size, not both")),
            (Some(a), None) => Field::HorizontalAngle(a),
            (None, Some(s)) => Field::PixelSize(s),
            (None, None) => d.field,
        };
        let desc = CameraDesc {
            eye: c.eye.map_or(d.eye, DVec3::from),
            aim,
            up: c.up.map_or(d.up, DVec3::from),
            distance: c.distance.unwrap_or(d.distance),
            field,
            width: c.width.unwrap_or(d.width),
            height: c.height.unwrap_or(d.height),
            sweep: match c.sweep {
                None => d.sweep,
                Some(SweepToml::PixelCentre) => Sweep::PixelCentre,
                Some(SweepToml::WindowEdges) => Sweep::WindowEdges,
            },
        };
        // Catch unusable cameras here, where the error can point at the table.
        Camera::new(&desc).map_err(|e| self.err(span, format!("camera: {e}")))?;
        Ok(desc)
    }

    fn render(&self, r: Option<RenderToml>) -> Result<RenderDesc, SceneError> {
        let d = RenderDesc::default();
        let Some(r) = r else { return Ok(d) };
        let pattern = match (r.pattern.unwrap_or(PatternToml::Grid), &r.samples) {
            (PatternToml::HalfPixel, Some(s)) if *s.get_ref() != 9 => {
                return Err(self.err(s.span(), "the half-pixel pattern takes 9 samples per pixel"));
            }
            (PatternToml::HalfPixel, _) => Pattern::HalfPixel,
            (PatternToml::Grid, None) => d.pattern,
            (PatternToml::Grid, Some(s)) => {
                Pattern::Grid(grid_side(*s.get_ref()).map_err(|m| self.err(s.span(), m))?)
            }
            (PatternToml::Stratified, None) => Pattern::Stratified(1),
            (PatternToml::Stratified, Some(s)) => {
                Pattern::Stratified(grid_side(*s.get_ref()).map_err(|m| self.err(s.span(), m))?)
            }
            (PatternToml::R2, None) => Pattern::R2(1),
            (PatternToml::R2, Some(s)) if *s.get_ref() == 0 => {
                return Err(self.err(s.span(), "the R2 pattern takes at least 1 sample per pixel"));
            }
            (PatternToml::R2, Some(s)) => Pattern::R2(*s.get_ref()),
            (PatternToml::Sobol, None) => Pattern::Sobol(1),
            (PatternToml::Sobol, Some(s)) if *s.get_ref() == 0 => {
                return Err(self.err(s.span(), "the Sobol pattern takes at least 1 sample per pixel"));
            }
            (PatternToml::Sobol, Some(s)) => Pattern::Sobol(*s.get_ref()),
            (PatternToml::Coverage, Some(s)) => {
                return Err(self.err(s.span(), "the coverage pattern computes areas and takes no samples"));
            }
            (PatternToml::Coverage, None) => Pattern::Coverage,
        };
        let filter = match (r.filter, &r.filter_radius) {
            (None, None) => None,
            (None, Some(radius)) => return Err(self.err(radius.span(), "filter_radius needs a filter")),
            (Some(kind), radius) => {
                let kind = match kind {
                    FilterToml::Box => FilterKind::Box,
                    FilterToml::Tent => FilterKind::Tent,
                    FilterToml::Gaussian => FilterKind::Gaussian,
                    FilterToml::Mitchell => FilterKind::Mitchell,
                };
                let radius = match radius {
                    None => Filter::default_radius(kind),
                    Some(r) => match *r.get_ref() {
                        v if v > 0.0 && v <= f64::from(Filter::MAX_RADIUS) => v as f32,
                        _ => {
                            let max = Filter::MAX_RADIUS;
                            return Err(
                                self.err(r.span(), format!("filter_radius runs above 0 up to {max} pixels"))
                            );
                        }
                    },
                };
                Some(Filter { kind, radius })
            }
        };
        Ok(RenderDesc {
            pattern,
            filter,
            postfilter: match r.postfilter {
                None => d.postfilter,
                Some(PostFilterToml::None) => PostFilter::None,
                Some(PostFilterToml::Lecture3x3) => PostFilter::Lecture3x3,
            },
            max_depth: r.max_depth.unwrap_or(d.max_depth),
            shade: match &r.shade {
                None => d.shade,
                Some(m) => {
                    Shade::parse(m.get_ref()).map_err(|e| self.err(m.span(), format!("shade: {e}")))?
                }
            },
            background: r.background.as_ref().map_or(Ok(d.background), |c| self.color(c, "background"))?,
            ambient: r.ambient.as_ref().map_or(Ok(d.ambient), |c| self.color(c, "ambient"))?,
            transfer: match r.transfer {
                None => d.transfer,
                Some(TransferToml::Srgb) => Transfer::Srgb,
                Some(TransferToml::Linear) => Transfer::Linear,
            },
        })
    }

    fn materials<'t>(
        &self,
        table: &'t BTreeMap<String, MaterialToml>,
    ) -> Result<(BTreeMap<&'t str, u32>, Vec<Material>), SceneError> {
        // Index 0 is the material of shapes that name none: `default`, given or built in.
        let mut names = BTreeMap::from([("default", 0u32)]);
        let mut list = vec![Material::default()];
        for (name, m) in table {
            let mat = self.material(m)?;
            if name == "default" {
                list[0] = mat;
            } else {
                names.insert(name.as_str(), list.len() as u32);
                list.push(mat);
            }
        }
        Ok((names, list))
    }

    fn material(&self, m: &MaterialToml) -> Result<Material, SceneError> {
        let d = Material::default();
        let unit = |v: &Option<Spanned<f64>>, key: &str, dflt: f32| {
            v.as_ref().map_or(Ok(dflt), |v| self.ranged(v, key, |x| x >= 0.0, "a non-negative number"))
        };
        Ok(Material {
            color: m.color.as_ref().map_or(Ok(d.color), |c| self.color(c, "color"))?,
            checker: match &m.checker {
                None => None,
                Some(c) => Some(Checker {
                    color: self.color(&c.color, "checker color")?,
                    size: self.ranged(&c.size, "checker size", |s| s > 0.0, "positive")?,
                }),
            },
            ambient: unit(&m.ambient, "ambient", d.ambient)?,
            diffuse: unit(&m.diffuse, "diffuse", d.diffuse)?,
            specular: unit(&m.specular, "specular", d.specular)?,
            shininess: unit(&m.shininess, "shininess", d.shininess)?,
            reflect: unit(&m.reflect, "reflect", d.reflect)?,
            transmit: unit(&m.transmit, "transmit", d.transmit)?,
            ior: m.ior.as_ref().map_or(Ok(d.ior), |v| self.ranged(v, "ior", |x| x > 0.0, "positive"))?,
            fresnel: m.fresnel.unwrap_or(d.fresnel),
        })
    }

    fn light(&self, l: &LightToml) -> Result<LightDesc, SceneError> {
        let color = l.color.as_ref().map_or(Ok(Rgb::all(1.0)), |c| self.color(c, "color"))?;
        let intensity = l
            .intensity
            .as_ref()
            .map_or(Ok(1.0), |v| self.ranged(v, "intensity", |x| x >= 0.0, "a non-negative number"))?;
        Ok(LightDesc {
            position: l.position.into(),
            color: color * intensity,
            falloff: match l.falloff {
                None | Some(FalloffToml::None) => Falloff::None,
                Some(FalloffToml::InverseSquare) => Falloff::InverseSquare,
            },
        })
    }

    /// The ops composed in list order: the first applies first.
    fn transform(&self, ops: &[Spanned<TransformOp>]) -> Result<DAffine3, SceneError> {
        placement::transform(ops).map_err(|e| self.kind_err(e))
    }

    fn kind_err(&self, e: KindError) -> SceneError {
        self.err(e.span, e.message)
    }
}

/// The side n of an n×n grid for `samples` per pixel.
pub fn grid_side(samples: u32) -> Result<u32, String> {
    let n = (f64::from(samples).sqrt().round()) as u32;
    if samples >= 1 && n * n == samples {
        Ok(n)
    } else {
        Err(format!("samples must be a square number (1, 4, 9, 16, ...) for the regular grid, got {samples}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(s: &str) -> Result<SceneDesc, SceneError> {
        parse(Path::new("t.toml"), s)
    }

    #[test]
    fn overlong_dotted_keys_name_their_line() {
        let key = vec!["a"; 100].join(".");
        for line in [format!("{key} = 1"), format!("[{key}]"), format!("[[{key}]]")] {
            let e = parse_str(&format!("[camera]\nwidth = 64\n\n  {line}\n")).unwrap_err();
            assert_eq!((e.line, e.column), (4, 3), "{e}");
            assert!(e.message.contains("100 parts"), "{e}");
        }
    }

    #[test]
    fn cones_are_read_with_their_material() {
        let d = parse_str(
            "[materials.red]\ncolor = [1, 0, 0]\n\n[[cones]]\nbase = [0, 0, 0]\nbase_radius = 1\n\
             apex = [0, 2, 0]\napex_radius = 0\nmaterial = \"red\"\n\n[[cones]]\nbase = [1, 1, 1]\n\
             base_radius = 0.5\napex = [1, 1, 3]\napex_radius = 0.5\n",
        )
        .unwrap();
        assert_eq!(d.kinds.cones.len(), 2);
        let c = d.kinds.cones[0];
        assert_eq!((c.base, c.base_radius, c.apex, c.apex_radius), (DVec3::ZERO, 1.0, DVec3::Y * 2.0, 0.0));
        assert_eq!(d.materials[c.material as usize].color, Rgb::new(1.0, 0.0, 0.0));
        assert_eq!(d.kinds.cones[1].material, 0);
    }

    #[test]
    fn the_coverage_pattern_takes_no_samples() {
        let d = parse_str("[render]\npattern = \"coverage\"\n").unwrap();
        assert_eq!(d.render.pattern, Pattern::Coverage);
        let e = parse_str("[render]\npattern = \"coverage\"\nsamples = 4\n").unwrap_err();
        assert_eq!((e.line, e.column), (3, 11), "{e}");
        assert!(e.message.contains("takes no samples"), "{e}");
    }

    #[test]
    fn shade_reads_whitted_and_ambient_occlusion() {
        assert_eq!(parse_str("[render]\n").unwrap().render.shade, Shade::Whitted);
        let d = parse_str("[render]\nshade = \"ao:8,2.5\"\n").unwrap();
        assert_eq!(d.render.shade, Shade::Ao(Ao { samples: 8, distance: Some(2.5) }));
        let d = parse_str("[render]\nshade = \"ao\"\n").unwrap();
        assert_eq!(d.render.shade, Shade::Ao(Ao { samples: Ao::DEFAULT_SAMPLES, distance: None }));
        for (text, says) in [("ao:0", "SAMPLES"), ("ao:4,-1", "DISTANCE"), ("phong", "unknown shading")] {
            let e = parse_str(&format!("[render]\nmax_depth = 2\nshade = \"{text}\"\n")).unwrap_err();
            assert_eq!((e.line, e.column), (3, 9), "{e}");
            assert!(e.message.contains(says) && e.message.contains("ao:SAMPLES,DISTANCE"), "{e}");
        }
    }

    #[test]
    fn bad_cones_name_line_and_column() {
        let cone = |body: &str| format!("[[cones]]\n{body}");
        for (body, line, column, says) in [
            ("base = [0,0,0]\nbase_radius = -1\napex = [0,0,1]\napex_radius = 1\n", 3, 15, "non-negative"),
            ("base = [0,0,0]\nbase_radius = 1\napex = [0,0,0]\napex_radius = 1\n", 4, 8, "differ"),
            ("base = [0,0,0]\nbase_radius = 0\napex = [0,0,1]\napex_radius = 0\n", 3, 15, "positive radius"),
            ("base = [0,0,0]\nbase_radius = 1\napex = [0,0,1]\n", 1, 1, "missing field `apex_radius`"),
            ("base = [0,0,0]\nradius = 1\n", 3, 1, "unknown field `radius`, expected one of `base`"),
            ("base = [0,0,1e39]\nbase_radius = 1\napex = [0,0,1]\napex_radius = 1\n", 2, 8, "within f32"),
        ] {
            let e = parse_str(&cone(body)).unwrap_err();
            assert_eq!((e.line, e.column), (line, column), "{body:?}: {e}");
            assert!(e.message.contains(says), "{body:?}: {e}");
        }
    }
}
