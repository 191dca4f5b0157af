//! The `[materials.NAME]` tables and the `[[lights]]` array: Whitted materials (with their checkers) by name,
//! and point lights, read into their descriptions.

use std::collections::BTreeMap;

use ::toml::Spanned;
use serde::Deserialize;

use super::{Reader, Vec3};
use crate::io::error::SceneError;
use crate::math::Rgb;
use crate::scene::desc::{Checker, Falloff, LightDesc, Material};

/// One `[materials.NAME]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialToml {
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

/// One `[[lights]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightToml {
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

impl Reader<'_> {
    /// The materials in a list, and the index of each name in it.
    pub(super) fn materials<'t>(
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

    /// A point light; its colour is the given colour times the intensity.
    pub(super) fn light(&self, l: &LightToml) -> Result<LightDesc, SceneError> {
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
}
