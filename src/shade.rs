//! Whitted shading for packets of K rays: ambient + Lambert + Phong from coloured point lights, hard shadows
//! by packet occlusion queries, mirror reflection and refraction (Snell, total internal reflection, optional
//! Fresnel) as masked packets, to a depth limit; or ambient occlusion (`ao.rs`). Generic over the lane type;
//! K = 1 is single-ray SIMD (one ray; the BVH walk is SIMD over a node's children).
//!
//! Work that differs per lane and has no exact SIMD form (surface lookup by primitive id, material fetch,
//! checker `floor`, Phong's `powf`) is done lane by lane with the scalar code, so every width computes the
//! same bits; everything else is lane arithmetic in the one-ray f32 code's operation order.
//!
//! Files: `surface.rs` (each lane's hit point, normal and material), `direct.rs` (lights and shadow rays),
//! `secondary.rs` (mirror and refracted rays), `ao.rs` and `ao_stream.rs` (ambient occlusion), `walks.rs`
//! (the walk of scattered secondary packets).

mod ao;
mod ao_stream;
mod direct;
mod secondary;
mod surface;
mod walks;

use std::marker::PhantomData;
use std::ops::AddAssign;

use crate::accel::{traced, RayKind};
use crate::compile::Scene;
use crate::geometry::{at_eye, DeparturePacket, HitPacket, RayPacket};
use crate::math::{Mask, Rgb, V3};
use crate::scene::desc::Shade;
use crate::simd::{set_bits, Lanes};
use surface::Surface;

/// How many rays of each kind were traced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Occlusion rays toward lights.
    pub shadow: u64,
    /// Mirror rays.
    pub reflection: u64,
    /// Transmitted rays.
    pub refraction: u64,
    /// Ambient occlusion rays.
    pub ao: u64,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflection + self.refraction + self.ao
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
        self.ao += o.ao;
    }
}

/// The number of set lanes.
fn lanes_set<F: Lanes>(m: F::Mask) -> u64 {
    u64::from(F::move_mask(m).count_ones())
}

/// Whether a secondary packet has so few live lanes (at most 3/4 of K) that tracing them one by one beats
/// tracing the packet: below that, the packet walk visits nodes for lanes that are not there. The share was
/// measured on sphereflakes at K = 8 and 16: anything from 1/2 to 7/8 of K gave about the same, all of K lost
/// on the coherent first reflections, and never going one ray at a time was slower (PERF.md, Register:
/// "Sparse secondary packets"; docs/perf-log/2026-11.md).
fn is_sparse<F: Lanes>(active: F::Mask) -> bool {
    4 * lanes_set::<F>(active) <= 3 * F::K as u64
}

/// The live lanes of a secondary packet traced one at a time by the K = 1 tracer. A lane's K = 1 trace
/// computes the same bits as the packet trace, so only the time changes.
fn trace_lane_by_lane<F: Lanes>(
    scalar: &mut Tracer<'_, f32>,
    kind: RayKind,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    depth: u32,
    weight: F,
) -> V3<F> {
    let mut rgb = [F::splat_f32(0.0).to_array(); 3];
    for i in set_bits(F::move_mask(rays.active)) {
        let (ray, t_max, _) = rays.lane(i);
        let one = RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true);
        let d = from.lane(i);
        let c = scalar.trace(
            kind,
            &one,
            &DeparturePacket { prim: d.prim, inward: d.inward },
            depth,
            weight.lane(i),
        );
        (rgb[0].as_mut()[i], rgb[1].as_mut()[i], rgb[2].as_mut()[i]) = (c.x, c.y, c.z);
    }
    let channel = |k: usize| F::from_lanes(rgb[k].as_ref());
    V3::new(channel(0), channel(1), channel(2))
}

/// A colour in every lane.
fn splat_rgb<F: Lanes>(c: Rgb) -> V3<F> {
    F::splat_v3(c)
}

/// Traces packets through one scene, counting rays. One per thread.
pub(crate) struct Tracer<'a, F: Lanes> {
    scene: &'a Scene,
    /// Rays traced so far.
    pub(crate) counts: RayCounts,
    /// Per light, a sphere that blocked the last shadow packet toward it: tested first for the next one
    /// (the shadow cache of Haines & Greenberg; it changes what is tested first, never the answer).
    shadow_hints: Vec<u32>,
    /// A sphere that blocked the last ambient occlusion packet, tested first for the next one.
    ao_hint: u32,
    /// A packet's ambient occlusion rays regrouped by direction, reused from packet to packet.
    ao_stream: ao_stream::AoStream,
    /// The tangent-frame directions of one hit's ambient occlusion rays, reused from hit to hit.
    ao_directions: Vec<V3<f32>>,
    /// The K = 1 tracer that secondary packets with few live lanes are handed to, lane by lane (`None`
    /// for K = 1).
    sparse: Option<Box<Tracer<'a, f32>>>,
    lanes: PhantomData<F>,
}

impl<'a, F: Lanes> Tracer<'a, F> {
    /// A tracer over `scene` with zero counts.
    pub(crate) fn new(scene: &'a Scene) -> Self {
        let shadow_hints = vec![crate::geometry::NO_PRIM; scene.lights.len()];
        let sparse = (F::K > 1).then(|| Box::new(Tracer::<f32>::new(scene)));
        let ao_hint = crate::geometry::NO_PRIM;
        Self {
            scene,
            counts: RayCounts::default(),
            shadow_hints,
            ao_hint,
            ao_directions: Vec::new(),
            ao_stream: ao_stream::AoStream::default(),
            sparse,
            lanes: PhantomData,
        }
    }

    /// Radiance along each active camera ray (zero in inactive lanes), by the scene's shading mode.
    pub(crate) fn primary(&mut self, rays: &RayPacket<F>) -> V3<F> {
        let hit =
            traced(RayKind::Camera, || self.scene.geometry.intersect_k(rays, &DeparturePacket::camera()));
        self.primary_from(rays, hit)
    }

    /// [`Tracer::primary`] for camera rays whose closest hits `hit` are known: from
    /// [`crate::accel::Geometry::intersect_tile`], which finds a tile's camera hits as one large packet.
    pub(crate) fn primary_from(&mut self, rays: &RayPacket<F>, hit: HitPacket<F>) -> V3<F> {
        self.counts.primary += lanes_set::<F>(rays.active);
        match self.scene.render.shade {
            Shade::Whitted => self.shade(rays, &hit, 0, F::splat_f32(1.0)),
            Shade::Ao(ao) => self.ambient_occlusion(rays, &hit, ao),
        }
    }

    /// Radiance along secondary rays of `kind` (reflection or refraction) leaving `from`.
    fn trace(
        &mut self,
        kind: RayKind,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        depth: u32,
        weight: F,
    ) -> V3<F> {
        if depth > 0 && is_sparse::<F>(rays.active) {
            if let Some(scalar) = self.sparse.as_deref_mut() {
                let color = trace_lane_by_lane(scalar, kind, rays, from, depth, weight);
                self.counts += std::mem::take(&mut scalar.counts);
                return color;
            }
        }
        let geometry = &self.scene.geometry;
        let hit = match F::K > 1 && walks::scattered::<F>(from.prim, rays.active) {
            true => {
                let (scene, live) = (self.scene as *const Scene as usize, lanes_set::<F>(rays.active) as u32);
                walks::walk_scattered(scene, live, |by_lanes| {
                    traced(kind, || geometry.intersect_walked(rays, from, by_lanes))
                })
            }
            false => traced(kind, || geometry.intersect_k(rays, from)),
        };
        self.shade(rays, &hit, depth, weight)
    }

    /// Radiance along `rays` whose closest hits are `hit`: the background where they
    /// found nothing, else the surface's shading and, below the depth limit, its reflection and refraction.
    fn shade(&mut self, rays: &RayPacket<F>, hit: &HitPacket<F>, depth: u32, weight: F) -> V3<F> {
        let (found, background) = self.found_or_background(rays, hit);
        if !found.any() {
            return background;
        }
        let s = self.surface(rays, hit, found, depth == 0);
        let view = -rays.ray.dir;
        let mut color = s.base.mul_elem(splat_rgb::<F>(self.scene.render.ambient)) * s.ambient;
        let zero_f = F::splat_f32(0.0);
        let lambert_or_phong = found & (s.diffuse.gt(zero_f) | s.specular.gt(zero_f));
        if lambert_or_phong.any() {
            let same_side = DeparturePacket { prim: hit.prim, inward: s.inside };
            // Camera rays' hits see a light at the eye (`Tracer::direct`).
            let clear = match depth {
                0 => at_eye(rays.ray.origin),
                _ => F::mask_from_bits(0),
            };
            let direct = self.direct(&s, view, lambert_or_phong, &same_side, clear);
            color = V3::select(lambert_or_phong, color + direct, color);
        }
        if depth < self.scene.render.max_depth {
            color = color + self.secondary(&s, rays, found, hit.prim, depth, weight);
        }
        V3::select(found, color, background)
    }

    /// The active lanes of `rays` that found a hit in `hit`, and the background colour in the active lanes
    /// that did not (zero in the rest).
    fn found_or_background(&self, rays: &RayPacket<F>, hit: &HitPacket<F>) -> (F::Mask, V3<F>) {
        let found = hit.found() & rays.active;
        let zero = V3::all(F::splat_f32(0.0));
        let background = V3::select(rays.active & !found, splat_rgb::<F>(self.scene.render.background), zero);
        (found, background)
    }
}
