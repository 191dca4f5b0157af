//! Changes to a scene's settings, as the command line's flags and the Python module's keywords give them
//! ([`Overrides`], applied in one place), and the names reports give the settings ([`PatternName`],
//! [`shade_name`], [`filter_name`]).

use crate::io::toml::grid_side;
use crate::scene::desc::{CameraOverrides, Filter, FilterKind, Pattern, PostFilter, Shade, Transfer};
use crate::scene::SceneDesc;

/// Changes to a scene description's camera and render settings; `None` (and the default) keeps the
/// scene's own.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Changes to the camera (eye, look, up, field of view, resolution).
    pub camera: CameraOverrides,
    /// Ambient coefficients: one for every material, or one per material in the description's order.
    pub ambient: Option<Vec<f32>>,
    /// Samples per pixel on a regular grid (a square: 1, 4, 9, …), replacing the scene's pattern.
    pub spp: Option<u32>,
    /// The sampling pattern, replacing the scene's (after `spp`, which callers give one of).
    pub pattern: Option<Pattern>,
    /// The reconstruction filter.
    pub filter: Option<Filter>,
    /// The shading mode.
    pub shade: Option<Shade>,
    /// The postfilter over the finished image.
    pub postfilter: Option<PostFilter>,
    /// The reflection and refraction depth limit.
    pub max_depth: Option<u32>,
    /// How values become 8-bit pixels.
    pub transfer: Option<Transfer>,
    /// Camera rays to their closest hit only: the lights are removed and the depth limit set to 0, so the
    /// build skips what only secondary rays use.
    pub primary_only: bool,
}

/// An override the scene cannot take.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// `spp` is not a square number.
    #[error("{0}")]
    Spp(String),
    /// The ambient list has neither one value nor one per material.
    #[error(
        "ambient gave {given} values; the scene defines {materials} material{} (one value sets them all)",
        if *materials == 1 { "" } else { "s" }
    )]
    Ambient {
        /// Values given.
        given: usize,
        /// Materials the scene defines.
        materials: usize,
    },
}

impl Overrides {
    /// Applies the changes to `desc`; on an error `desc` may be changed in part. A light at the eye is a
    /// headlight (particle files and arrays are lit so): a new eye takes it along.
    pub fn apply(&self, desc: &mut SceneDesc) -> Result<(), SettingsError> {
        let eye = desc.camera.eye;
        self.camera.apply(&mut desc.camera);
        for light in desc.lights.iter_mut().filter(|l| l.position == eye) {
            light.position = desc.camera.eye;
        }
        if let Some(ambient) = &self.ambient {
            set_ambient(desc, ambient)?;
        }
        let render = &mut desc.render;
        if let Some(spp) = self.spp {
            render.pattern = Pattern::Grid(grid_side(spp).map_err(SettingsError::Spp)?);
        }
        if let Some(pattern) = self.pattern {
            render.pattern = pattern;
        }
        if let Some(filter) = self.filter {
            render.filter = Some(filter);
        }
        if let Some(shade) = self.shade {
            render.shade = shade;
        }
        if let Some(postfilter) = self.postfilter {
            render.postfilter = postfilter;
        }
        if let Some(depth) = self.max_depth {
            render.max_depth = depth;
        }
        if let Some(transfer) = self.transfer {
            render.transfer = transfer;
        }
        if self.primary_only {
            desc.lights.clear();
            desc.render.max_depth = 0;
        }
        Ok(())
    }
}

/// One value for every material, or one per material in order.
fn set_ambient(desc: &mut SceneDesc, ambient: &[f32]) -> Result<(), SettingsError> {
    let materials = &mut desc.materials;
    match ambient {
        [a] => materials.iter_mut().for_each(|m| m.ambient = *a),
        list if list.len() == materials.len() => {
            materials.iter_mut().zip(list).for_each(|(m, a)| m.ambient = *a);
        }
        list => return Err(SettingsError::Ambient { given: list.len(), materials: materials.len() }),
    }
    Ok(())
}

/// The names of a sampling pattern in reports.
#[derive(Clone, Debug, PartialEq)]
pub struct PatternName {
    /// Samples per pixel, where the pattern has a fixed count.
    pub samples: Option<u32>,
    /// A short label for tables and JSON (`grid 4x4`, `sobol 16`).
    pub short: String,
    /// A sentence for summaries and image metadata (`16 samples per pixel (4×4 grid)`).
    pub long: String,
}

impl PatternName {
    /// The names of `pattern`.
    pub fn of(pattern: Pattern) -> Self {
        let per_pixel =
            |n: u32, how: &str| format!("{n} sample{} per pixel ({how})", if n == 1 { "" } else { "s" });
        let (samples, short, long) = match pattern {
            Pattern::Grid(n) => (Some(n * n), format!("grid {n}x{n}"), per_pixel(n * n, &format!("{n}×{n} grid"))),
            Pattern::Stratified(n) => {
                (Some(n * n), format!("stratified {n}x{n}"), per_pixel(n * n, &format!("{n}×{n} jittered grid")))
            }
            Pattern::R2(n) => (Some(n), format!("r2 {n}"), per_pixel(n, "R2 sequence, rotated per pixel")),
            Pattern::Sobol(n) => {
                (Some(n), format!("sobol {n}"), per_pixel(n, "Sobol' sequence, Owen-scrambled per pixel"))
            }
            Pattern::HalfPixel => (
                None,
                "half-pixel".to_owned(),
                "half-pixel pattern (9 samples per pixel shared with the neighbours)".to_owned(),
            ),
            Pattern::Adaptive { threshold, depth } => (
                None,
                format!("adaptive {threshold} to depth {depth}"),
                format!("adaptive: corners shared, squares split where they differ by > {threshold}, to depth {depth}"),
            ),
            Pattern::Coverage => (
                None,
                "coverage".to_owned(),
                "coverage: spheres' covered areas per pixel, one ray per part".to_owned(),
            ),
        };
        PatternName { samples, short, long }
    }
}

/// The name of a shading mode as the command line spells it, with its settings (`ao:16,0.5`; a default
/// distance, not yet resolved by compiling, is left out).
pub fn shade_name(shade: Shade) -> String {
    match shade {
        Shade::Whitted => "whitted".to_owned(),
        Shade::Ao(ao) => match ao.distance {
            Some(d) => format!("ao:{},{d}", ao.samples),
            None => format!("ao:{}", ao.samples),
        },
    }
}

/// The name of a reconstruction filter as the command line spells it: `none`, or the kind and its radius
/// in pixels (`gaussian:1.5`).
pub fn filter_name(filter: Option<Filter>) -> String {
    let Some(f) = filter else { return "none".to_owned() };
    let kind = match f.kind {
        FilterKind::Box => "box",
        FilterKind::Tent => "tent",
        FilterKind::Gaussian => "gaussian",
        FilterKind::Mitchell => "mitchell",
    };
    format!("{kind}:{}", f.radius)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::Ao;

    #[test]
    fn patterns_have_a_short_and_a_long_name() {
        let grid = PatternName::of(Pattern::Grid(4));
        assert_eq!((grid.samples, grid.short.as_str()), (Some(16), "grid 4x4"));
        assert_eq!(grid.long, "16 samples per pixel (4×4 grid)");
        assert_eq!(PatternName::of(Pattern::Grid(1)).long, "1 sample per pixel (1×1 grid)");
        assert_eq!(
            PatternName::of(Pattern::Sobol(1)).long,
            "1 sample per pixel (Sobol' sequence, Owen-scrambled per pixel)"
        );
        assert_eq!(PatternName::of(Pattern::HalfPixel).samples, None);
    }

    #[test]
    fn shades_and_filters_are_named_as_the_command_line_takes_them() {
        assert_eq!(shade_name(Shade::Ao(Ao { samples: 8, distance: Some(1.5) })), "ao:8,1.5");
        assert_eq!(shade_name(Shade::Ao(Ao { samples: 8, distance: None })), "ao:8");
        assert_eq!(filter_name(None), "none");
        assert_eq!(filter_name(Some(Filter { kind: FilterKind::Box, radius: 0.5 })), "box:0.5");
    }

    #[test]
    fn overrides_replace_settings_and_check_spp_and_ambient() {
        let mut desc = SceneDesc::default();
        let overrides =
            Overrides { spp: Some(9), max_depth: Some(3), primary_only: false, ..Overrides::default() };
        overrides.apply(&mut desc).unwrap();
        assert_eq!((desc.render.pattern, desc.render.max_depth), (Pattern::Grid(3), 3));
        let bad = Overrides { spp: Some(5), ..Overrides::default() };
        assert!(matches!(bad.apply(&mut desc), Err(SettingsError::Spp(_))));
        let ambient =
            Overrides { ambient: Some(vec![0.1; desc.materials.len() + 2]), ..Overrides::default() };
        let e = ambient.apply(&mut desc).unwrap_err();
        assert!(e.to_string().starts_with("ambient gave"), "{e}");
    }

    #[test]
    fn a_new_eye_takes_the_headlight_along() {
        use crate::scene::desc::LightDesc;
        use glam::DVec3;
        let mut desc = SceneDesc::default();
        let light =
            |position| LightDesc { position, color: crate::math::Rgb::all(1.0), falloff: Default::default() };
        let (eye, away) = (desc.camera.eye, DVec3::new(3.0, 4.0, 5.0));
        desc.lights = vec![light(eye), light(away)];
        let look = Overrides {
            camera: CameraOverrides { look: Some(DVec3::X), ..CameraOverrides::default() },
            ..Overrides::default()
        };
        look.apply(&mut desc).unwrap();
        assert_eq!((desc.lights[0].position, desc.lights[1].position), (eye, away), "the eye stayed");
        let to = DVec3::new(1.0, 2.0, -9.0);
        let moved = Overrides {
            camera: CameraOverrides { eye: Some(to), ..CameraOverrides::default() },
            ..Overrides::default()
        };
        moved.apply(&mut desc).unwrap();
        assert_eq!((desc.camera.eye, desc.lights[0].position, desc.lights[1].position), (to, to, away));
    }
}
