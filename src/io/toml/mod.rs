//! bareray's own scene format, in TOML. Every key is optional but the shapes; unknown keys are errors; every
//! error names the file, the line and what was expected. The format is documented in docs/scene-format.md.
//!
//! This file: `load` and `parse`, the file's tables with the spheres and the registered kinds, the `Reader`
//! with its checks, and `grid_side`; the camera and render tables are read in `camera_render.rs`, the
//! materials and lights in `materials_lights.rs`.

mod camera_render;
mod materials_lights;
#[cfg(test)]
mod tests;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

use ::toml::Spanned;
use glam::{DAffine3, DVec3};
use serde::Deserialize;

use self::camera_render::{CameraToml, RenderToml};
use self::materials_lights::{LightToml, MaterialToml};
use crate::kinds::placement::{self, TransformOp};
#[allow(unused_imports)] // used per registered kind
use crate::kinds::{Kind, KindDescs, KindError};
use crate::math::Rgb;

use super::error::SceneError;
use crate::kinds::sphere::SphereDesc;
use crate::scene::desc::SceneDesc;

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
