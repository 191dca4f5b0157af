//! What a compiled scene uses, so that `--stats` can say what the render path runs and what it skips.

use std::fmt;

use super::{Light, Scene};
use crate::scene::desc::{Material, Pattern, PostFilter, Shade};

/// How many primitives of each kind a scene has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Counts {
    /// Plain spheres.
    pub(crate) spheres: usize,
    /// The registered kinds' primitives ([`crate::kinds`]: polygons, ellipsoids, planes, open cones, tori),
    /// in the registry's order.
    pub(crate) kinds: [usize; crate::kinds::COUNT],
}

/// The parts of the tracer a scene needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Features {
    /// Primitives by kind: a kind with none is skipped.
    pub(crate) counts: Counts,
    /// Some kind is searched through a BVH (else all brute force).
    pub(crate) bvh: bool,
    /// Lights that shade something: Lambert and Phong terms.
    pub(crate) direct: bool,
    /// Shadow rays: lights shade, and some light is away from the eye or rays bounce (camera rays' hits see
    /// a light at the eye without one, `shade::Tracer::direct`).
    pub(crate) shadow_rays: bool,
    /// Mirror materials and a depth limit above 0.
    pub(crate) reflection: bool,
    /// Transmissive materials and a depth limit above 0.
    pub(crate) refraction: bool,
    /// More than one sample per pixel or a postfilter.
    pub(crate) antialiasing: bool,
    /// Ambient occlusion shading (which replaces the lights and the bounces).
    pub(crate) ao: bool,
}

impl Features {
    /// Detects the features of a compiled scene.
    pub(crate) fn of(scene: &Scene) -> Features {
        let g = &scene.geometry;
        let m = &scene.materials;
        let ao = matches!(scene.render.shade, Shade::Ao(_));
        let deep = scene.render.max_depth > 0 && !ao;
        let direct = !ao && lights_shade(!scene.lights.is_empty(), m);
        Features {
            counts: Counts { spheres: g.spheres.len() + g.particles.len(), kinds: g.kinds.counts() },
            bvh: g.bvhs().next().is_some(),
            direct,
            shadow_rays: !ao && casts_shadows(&scene.lights, m, scene.render.max_depth),
            reflection: !ao && bounces(scene.render.max_depth, m),
            refraction: deep && m.iter().any(|m| m.transmit > 0.0),
            antialiasing: scene.render.pattern != Pattern::Grid(1)
                || scene.render.postfilter != PostFilter::None,
            ao,
        }
    }

    fn list(&self) -> Vec<(&'static str, bool)> {
        let kinds = crate::kinds::NAMES.iter().zip(self.counts.kinds).map(|(&name, n)| (name, n > 0));
        let mut list = vec![
            ("spheres", self.counts.spheres > 0),
            ("bvh", self.bvh),
            ("direct light", self.direct),
            ("shadow rays", self.shadow_rays),
            ("reflection", self.reflection),
            ("refraction", self.refraction),
            ("antialiasing", self.antialiasing),
            ("ambient occlusion rays", self.ao),
        ];
        list.splice(2..2, kinds);
        list
    }
}

/// Whether lights shade anything: there are some, and some material has a Lambert or Phong term.
pub(crate) fn lights_shade(has_lights: bool, materials: &[Material]) -> bool {
    has_lights && materials.iter().any(|m| m.diffuse > 0.0 || m.specular > 0.0)
}

/// Whether Whitted shading casts shadow rays: lights shade, and some light is away from the eye or rays
/// bounce (camera rays' hits see a light at the eye without one, [`Light::at_eye`]).
pub(crate) fn casts_shadows(lights: &[Light], materials: &[Material], max_depth: u32) -> bool {
    lights_shade(!lights.is_empty(), materials)
        && (bounces(max_depth, materials) || !lights.iter().all(Light::at_eye))
}

/// Whether rays bounce: a depth limit above 0 and some mirror or transmissive material.
pub(crate) fn bounces(max_depth: u32, materials: &[Material]) -> bool {
    max_depth > 0 && materials.iter().any(|m| m.reflect > 0.0 || m.transmit > 0.0)
}

impl fmt::Display for Features {
    /// `uses: a, b; skips: c, d`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names =
            |on: bool| self.list().iter().filter(|(_, v)| *v == on).map(|(n, _)| *n).collect::<Vec<_>>();
        write!(f, "uses: {}; skips: {}", names(true).join(", "), names(false).join(", "))
    }
}
