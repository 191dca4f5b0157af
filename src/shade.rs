//! Whitted shading for packets of K rays: ambient + Lambert + Phong from coloured point lights, hard shadows
//! by packet occlusion queries, mirror reflection and refraction (Snell, total internal reflection, optional
//! Fresnel) as masked packets, to a depth limit; or ambient occlusion (`ao.rs`). Generic over the lane type;
//! K = 1 is single-ray SIMD (one ray; the BVH walk is SIMD over a node's children).
//!
//! Work that differs per lane and has no exact SIMD form (surface lookup by primitive id, material fetch,
//! checker `floor`, Phong's `powf`) is done lane by lane with the scalar code, so every width computes the
//! same bits; everything else is lane arithmetic in the one-ray f32 code's operation order.

mod ao;
mod ao_stream;
mod walks;

use std::marker::PhantomData;
use std::ops::AddAssign;

use crate::accel::{traced, PrimRef, RayKind};
use crate::compile::Scene;
use crate::geometry::{at_eye, DeparturePacket, HitPacket, RayPacket};
use crate::math::{Mask, Real, Rgb, Vec3f, V3};
use crate::scene::desc::{Falloff, Material, Shade};
use crate::simd::{set_bits, IdLanes, Lanes};

/// Secondary rays whose contribution to the pixel would be below this weight are not traced.
const MIN_WEIGHT: f32 = 1.0 / 1024.0;

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

/// The outward `normal` turned toward rays along `dir`, and the lanes where it was flipped (hit from
/// inside: the lecture's case 4): in the lanes of `known`, inside where `eye_inside` says so (a camera ray's
/// sphere hit, [`crate::accel::Geometry::eye_inside`]); elsewhere where `n·d > 0`. Zero normals (lanes that
/// found nothing) stay unflipped.
fn facing<F: Lanes>(normal: V3<F>, dir: V3<F>, known: F::Mask, eye_inside: F::Mask) -> (V3<F>, F::Mask) {
    let inside = (known & eye_inside) | (!known & normal.dot(dir).gt(F::splat_f32(0.0)));
    (V3::select(inside, -normal, normal), inside)
}

/// A colour in every lane.
fn splat_rgb<F: Lanes>(c: Rgb) -> V3<F> {
    F::splat_v3(c)
}

/// What shading needs at the hit of each lane, gathered from the lanes' primitives and materials.
struct Surface<F: Lanes> {
    point: V3<F>,
    /// Unit normal turned toward the incoming ray.
    normal: V3<F>,
    /// Lanes hit from inside (normal flipped: the lecture's case 4).
    inside: F::Mask,
    base: V3<F>,
    ambient: F,
    diffuse: F,
    specular: F,
    shininess: F,
    reflect: F,
    transmit: F,
    ior: F,
    fresnel: F::Mask,
}

impl<F: Lanes> Surface<F> {
    /// `a` in the lanes of `m`, `b` in the others.
    fn select(m: F::Mask, a: Self, b: Self) -> Self {
        let pick = |x: F, y: F| F::select(m, x, y);
        Self {
            point: V3::select(m, a.point, b.point),
            normal: V3::select(m, a.normal, b.normal),
            inside: (m & a.inside) | (!m & b.inside),
            base: V3::select(m, a.base, b.base),
            ambient: pick(a.ambient, b.ambient),
            diffuse: pick(a.diffuse, b.diffuse),
            specular: pick(a.specular, b.specular),
            shininess: pick(a.shininess, b.shininess),
            reflect: pick(a.reflect, b.reflect),
            transmit: pick(a.transmit, b.transmit),
            ior: pick(a.ior, b.ior),
            fresnel: (m & a.fresnel) | (!m & b.fresnel),
        }
    }

    /// The surface of a packet whose found lanes (`found`, as bits) all have material `m`: the normal turned
    /// toward the rays and the lanes hit from inside ([`facing`]), and the material's constants in every lane.
    fn of_material(
        point: V3<F>,
        (normal, inside): (V3<F>, F::Mask),
        base: V3<F>,
        m: &Material,
        found: u32,
    ) -> Self {
        let splat = F::splat_f32;
        Self {
            point,
            normal,
            inside,
            base,
            ambient: splat(m.ambient),
            diffuse: splat(m.diffuse),
            specular: splat(m.specular),
            shininess: splat(m.shininess),
            reflect: splat(m.reflect),
            transmit: splat(m.transmit),
            ior: splat(m.ior),
            fresnel: F::mask_from_bits(if m.fresnel { found } else { 0 }),
        }
    }
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

    /// Each found lane's surface point and material: by lane arithmetic when every found lane hit a sphere
    /// of one plain material (most packets), or one item of a kind with a lane form, or a mix of the two
    /// ([`Tracer::split_surface`]); else lane by lane with the scalar code. `camera`: the rays are
    /// camera rays (departing from nothing); those that start at the eye take their sphere or ellipsoid
    /// hit's side from the eye term.
    fn surface(&self, rays: &RayPacket<F>, hit: &HitPacket<F>, found: F::Mask, camera: bool) -> Surface<F> {
        self.sphere_surface(rays, hit, found, camera)
            .or_else(|| self.kind_surface(rays, hit, found, camera))
            .or_else(|| self.split_surface(rays, hit, found, camera))
            .unwrap_or_else(|| self.surface_by_lane(rays, hit, found, camera))
    }

    /// [`Tracer::surface`] for packets whose found lanes hit spheres of one plain material and one item of a
    /// registered kind with a lane form and a plain material (a flake's spheres and the floor under them):
    /// each part by its own lane form, merged by selects, so every lane has the bits the lane-by-lane path
    /// would give it. `None` for any other packet, and for a checkered item, whose colours are lane by lane
    /// in either form (the split was slower there: PERF.md, Register).
    #[inline(never)]
    fn split_surface(
        &self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        found: F::Mask,
        camera: bool,
    ) -> Option<Surface<F>> {
        if F::K == 1 || !self.scene.split_surfaces {
            return None;
        }
        let geometry = &self.scene.geometry;
        let on_spheres = found & F::ids_lt(hit.prim, F::Ids::splat(geometry.spheres.len() as u32));
        let rest = found & !on_spheres;
        if !on_spheres.any() {
            return None;
        }
        // The cheap tests first: the other lanes on one item of a kind, its material plain.
        let k = self.kind_item(hit, rest)?;
        let material = geometry.kinds.material_in_lanes(k)?;
        if self.scene.materials[material as usize].checker.is_some() {
            return None;
        }
        let sphere = self.sphere_surface(rays, hit, on_spheres, camera)?;
        let item = self.kind_surface(rays, hit, rest, camera)?;
        Some(Surface::select(on_spheres, sphere, item))
    }

    /// The item (numbered among the registered kinds' primitives) that every lane of `lanes` hit, if they
    /// all hit one item of a registered kind (not a sphere or a particle); `None` for no lanes.
    #[inline(always)]
    fn kind_item(&self, hit: &HitPacket<F>, lanes: F::Mask) -> Option<usize> {
        let bits = F::move_mask(lanes);
        let prim = hit.prim.lane(set_bits(bits).next()?);
        let PrimRef::Kind(k) = self.scene.geometry.prim(prim) else { return None };
        set_bits(bits).all(|i| hit.prim.lane(i) == prim).then_some(k)
    }

    /// [`Tracer::surface`] for packets whose found lanes all hit one item of a registered kind that has a
    /// lane form of its surface ([`crate::kinds::Kind::surface_k`]: a ground plane, most often, or an
    /// ellipsoid): object point and normal in lanes, the checker's colour lane by lane. `None` for any
    /// other packet.
    #[inline(always)]
    fn kind_surface(
        &self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        found: F::Mask,
        camera: bool,
    ) -> Option<Surface<F>> {
        let geometry = &self.scene.geometry;
        let bits = F::move_mask(found);
        let k = self.kind_item(hit, found)?;
        let prim = hit.prim.lane(set_bits(bits).next()?);
        let ray = rays.ray();
        let (normal, object_point, material) = geometry.kinds.surface_k(k, ray, hit.t)?;
        let m = &self.scene.materials[material as usize];
        let zero = V3::all(F::splat_f32(0.0));
        let point = V3::select(found, ray.at(hit.t), zero);
        let normal = V3::select(found, normal, zero);
        // The eye's side, for camera rays from the eye, where the eye term tells it (`Geometry::eye_inside`).
        let (known, eye_inside) = match geometry.eye_inside(prim) {
            Some(side) if camera => {
                (found & at_eye(ray.origin), F::mask_from_bits(if side { bits } else { 0 }))
            }
            _ => (F::mask_from_bits(0), F::mask_from_bits(0)),
        };
        let turned = facing(normal, ray.dir, known, eye_inside);
        let base = match m.checker {
            None => splat_rgb::<F>(m.color),
            Some(_) => {
                let colour = |i: usize| {
                    let p = V3::new(object_point.x.lane(i), object_point.y.lane(i), object_point.z.lane(i));
                    if bits >> i & 1 == 1 {
                        surface_color(m, m.color, p)
                    } else {
                        Rgb::new(0.0, 0.0, 0.0)
                    }
                };
                let c: [Rgb; 16] = std::array::from_fn(|i| if i < F::K { colour(i) } else { Rgb::default() });
                V3::new(F::from_fn(|i| c[i].x), F::from_fn(|i| c[i].y), F::from_fn(|i| c[i].z))
            }
        };
        Some(Surface::of_material(point, turned, base, m, bits))
    }

    /// [`Tracer::surface`] for packets whose found lanes all hit spheres of one material without a checker:
    /// point and normal from the SoA sphere arrays in lanes, by [`crate::accel::Geometry::surface`]'s
    /// operations in its order (so each lane gets the scalar bits), and the material splatted. `None` for
    /// any other packet.
    #[inline(always)]
    fn sphere_surface(
        &self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        found: F::Mask,
        camera: bool,
    ) -> Option<Surface<F>> {
        let spheres = &self.scene.geometry.spheres;
        let bits = F::move_mask(found);
        let lanes = || set_bits(bits);
        let first = lanes().next()?;
        let sphere = |i: usize| hit.prim.lane(i) as usize;
        let material = *spheres.material.get(sphere(first))?;
        if !lanes().all(|i| spheres.material.get(sphere(i)) == Some(&material)) {
            return None;
        }
        let m = &self.scene.materials[material as usize];
        if m.checker.is_some() {
            return None;
        }
        // Lanes that found nothing take the first found lane's sphere and are zeroed below.
        let index = |i: usize| if bits >> i & 1 == 1 { sphere(i) } else { sphere(first) };
        let gather = |v: &[f32]| F::from_fn(|i| v[index(i)]);
        let center = V3::new(gather(&spheres.cx), gather(&spheres.cy), gather(&spheres.cz));
        let zero = V3::all(F::splat_f32(0.0));
        let point = V3::select(found, rays.ray().at(hit.t), zero);
        // `Geometry::eye_inside` in lanes, for camera rays from the eye: known where the eye term is not zero
        // (the eye not on the surface).
        let c_eye = gather(&spheres.c_eye);
        let zero_f = F::splat_f32(0.0);
        let camera_lanes = if camera { found & at_eye(rays.ray.origin) } else { F::mask_from_bits(0) };
        let from_eye = camera_lanes & (c_eye.lt(zero_f) | c_eye.gt(zero_f));
        let eye_inside = c_eye.lt(zero_f);
        let outward = V3::select(found, (point - center).normalize(), zero);
        let turned = facing(outward, rays.ray.dir, from_eye, eye_inside);
        // The spheres' own colours, when they have them, replace the material's.
        let base = match spheres.color.is_empty() {
            true => splat_rgb::<F>(m.color),
            false => {
                let rgb = |i: usize| spheres.color[index(i)].to_rgb();
                V3::new(F::from_fn(|i| rgb(i).x), F::from_fn(|i| rgb(i).y), F::from_fn(|i| rgb(i).z))
            }
        };
        Some(Surface::of_material(point, turned, base, m, bits))
    }

    /// [`Tracer::surface`] lane by lane with the scalar code: any primitives and materials.
    fn surface_by_lane(
        &self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        found: F::Mask,
        camera: bool,
    ) -> Surface<F> {
        // K lanes per row, not 16: the scalar tracer gathers once per ray, and zeroing 1 KB each time showed.
        let mut v = [F::splat_f32(0.0).to_array(); 16];
        let (mut fresnel, mut known, mut eye_inside) = (0u32, 0u32, 0u32);
        for i in set_bits(F::move_mask(found)) {
            let (ray, _, _) = rays.lane(i);
            let geometry = &self.scene.geometry;
            let sp = geometry.surface(&ray, hit.t.lane(i), hit.prim.lane(i));
            if let (true, Some(side)) = (camera && at_eye(ray.origin), geometry.eye_inside(hit.prim.lane(i)))
            {
                known |= 1 << i;
                eye_inside |= u32::from(side) << i;
            }
            let m = &self.scene.materials[sp.material as usize];
            let own = geometry.sphere_color(hit.prim.lane(i)).map(|c| c.to_rgb());
            let base = surface_color(m, own.unwrap_or(m.color), sp.object_point);
            let row = [
                sp.point.x,
                sp.point.y,
                sp.point.z,
                sp.normal.x,
                sp.normal.y,
                sp.normal.z,
                base.x,
                base.y,
                base.z,
                m.ambient,
                m.diffuse,
                m.specular,
                m.shininess,
                m.reflect,
                m.transmit,
                m.ior,
            ];
            for (k, x) in row.into_iter().enumerate() {
                v[k].as_mut()[i] = x;
            }
            fresnel |= u32::from(m.fresnel) << i;
        }
        let lane = |k: usize| F::from_lanes(v[k].as_ref());
        let v3 = |k: usize| V3::new(lane(k), lane(k + 1), lane(k + 2));
        let (normal, inside) =
            facing(v3(3), rays.ray.dir, F::mask_from_bits(known), F::mask_from_bits(eye_inside));
        Surface {
            point: v3(0),
            normal,
            inside,
            base: v3(6),
            ambient: lane(9),
            diffuse: lane(10),
            specular: lane(11),
            shininess: lane(12),
            reflect: lane(13),
            transmit: lane(14),
            ior: lane(15),
            fresnel: F::mask_from_bits(fresnel),
        }
    }

    /// Lambert and Phong from every light each lane sees, by one occlusion packet per light.
    ///
    /// A light at the eye needs no shadow ray from the lanes of `clear`, camera rays' closest hits: the way
    /// back to the eye is the camera ray's own segment, on which it found nothing nearer. (The shadow ray
    /// from the rounded hit point would retrace it only up to rounding, so where it reported a blocker, a
    /// surface grazed or left, the light was in fact seen.) Particle files and arrays light their spheres so
    /// by default, and those shadow rays cost as much as the camera rays, all of them unblocked.
    fn direct(
        &mut self,
        s: &Surface<F>,
        view: V3<F>,
        lanes: F::Mask,
        from: &DeparturePacket<F>,
        clear: F::Mask,
    ) -> V3<F> {
        let zero = F::splat_f32(0.0);
        let mut sum = V3::all(zero);
        for (k, light) in self.scene.lights.iter().enumerate() {
            let to_light = F::splat_v3(light.position) - s.point;
            let dist2 = to_light.dot(to_light);
            let dist = dist2.sqrt();
            let l = to_light * (F::splat_f32(1.0) / dist);
            let cos = s.normal.dot(l);
            // Lights behind the surface (or a NaN normal) contribute nothing.
            let lit = lanes & cos.gt(zero);
            if !lit.any() {
                continue;
            }
            let seen = match light.at_eye() {
                true => lit & clear,
                false => F::mask_from_bits(0),
            };
            let asked = lit & !seen;
            let mut visible = seen;
            if asked.any() {
                self.counts.shadow += lanes_set::<F>(asked);
                let shadow = RayPacket::new(s.point, l, dist, asked);
                let hint = &mut self.shadow_hints[k];
                let geometry = &self.scene.geometry;
                let blocked = traced(RayKind::Shadow, || geometry.shadowed_k(&shadow, from, hint, k));
                visible = visible | (asked & !blocked);
            }
            let intensity = match light.falloff {
                Falloff::None => splat_rgb::<F>(light.color),
                Falloff::InverseSquare => splat_rgb::<F>(light.color) * (F::splat_f32(1.0) / dist2),
            };
            let mut reflected = s.base * (s.diffuse * cos);
            let phong = visible & s.specular.gt(zero);
            if phong.any() {
                let mirror = s.normal * (F::splat_f32(2.0) * cos) - l;
                let along = mirror.dot(view);
                // powf only where it matters: lanes outside `phong` are discarded by the select below, and
                // 0^n is +0 for n > 0 without the call.
                let mut highlight = F::splat_f32(0.0).to_array();
                for i in set_bits(F::move_mask(phong)) {
                    let (base, n) = (along.lane(i).max(0.0), s.shininess.lane(i));
                    if base != 0.0 || n <= 0.0 {
                        highlight.as_mut()[i] = base.powf(n);
                    }
                }
                let highlight = F::from_lanes(highlight.as_ref());
                reflected = V3::select(phong, reflected + V3::all(s.specular * highlight), reflected);
            }
            sum = V3::select(visible, sum + reflected.mul_elem(intensity), sum);
        }
        sum
    }

    /// Mirror and transmitted contributions, as masked packets.
    fn secondary(
        &mut self,
        s: &Surface<F>,
        rays: &RayPacket<F>,
        found: F::Mask,
        prim: F::Ids,
        depth: u32,
        weight: F,
    ) -> V3<F> {
        let zero = F::splat_f32(0.0);
        let one = F::splat_f32(1.0);
        let mut kr = s.reflect;
        let mut kt = s.transmit;
        let transmitting = found & kt.gt(zero);
        let mut refracted = None;
        if transmitting.any() {
            let eta = F::select(s.inside, s.ior, one / s.ior);
            let (through, dir, fresnel) = refract(rays.ray.dir, s.normal, eta);
            let through = transmitting & through;
            let split = through & s.fresnel;
            kr = F::select(split, kr + kt * fresnel, kr);
            kt = F::select(split, kt * (one - fresnel), kt);
            // Total internal reflection: all transmitted energy is reflected.
            let tir = transmitting & !through;
            kr = F::select(tir, kr + kt, kr);
            kt = F::select(tir, zero, kt);
            refracted = Some((through, dir));
        }
        let min_weight = F::splat_f32(MIN_WEIGHT);
        let mut color = V3::all(zero);
        let mirror = found & (kr * weight).gt(min_weight);
        if mirror.any() {
            self.counts.reflection += lanes_set::<F>(mirror);
            let d = rays.ray.dir;
            let dir = (d - s.normal * (F::splat_f32(2.0) * d.dot(s.normal))).normalize();
            let next = RayPacket::new(s.point, dir, F::splat_f32(f32::INFINITY), mirror);
            let from = DeparturePacket { prim, inward: s.inside };
            let c = self.trace(RayKind::Reflection, &next, &from, depth + 1, weight * kr);
            color = V3::select(mirror, color + c * kr, color);
        }
        if let Some((through, dir)) = refracted {
            let glass = through & (kt * weight).gt(min_weight);
            if glass.any() {
                self.counts.refraction += lanes_set::<F>(glass);
                let next = RayPacket::new(s.point, dir, F::splat_f32(f32::INFINITY), glass);
                let from = DeparturePacket { prim, inward: !s.inside };
                let c = self.trace(RayKind::Refraction, &next, &from, depth + 1, weight * kt);
                color = V3::select(glass, color + c * kt, color);
            }
        }
        color
    }
}

/// The surface's colour at an object-space point: `color` (the material's, or the sphere's own), or a solid
/// checkerboard of it and the checker's colour.
fn surface_color(mat: &Material, color: Rgb, object_point: Vec3f) -> Rgb {
    match mat.checker {
        None => color,
        Some(ch) => {
            let cell = |v: f32| (v / ch.size).floor() as i64;
            let parity = cell(object_point.x) + cell(object_point.y) + cell(object_point.z);
            if parity.rem_euclid(2) == 0 {
                color
            } else {
                ch.color
            }
        }
    }
}

/// Snell refraction of unit direction `d` through unit normal `n` (facing against `d`) with
/// `eta = n_incident / n_transmitted`. Returns the lanes that refract (not totally internally reflected),
/// the unit transmitted direction and the unpolarised dielectric Fresnel reflectance.
fn refract<F: Real>(d: V3<F>, n: V3<F>, eta: F) -> (F::Mask, V3<F>, F) {
    let one = F::splat(1.0);
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (one - cos_i * cos_i);
    let through = sin2_t.le(one);
    let cos_t = (one - sin2_t).sqrt();
    let dir = (d * eta + n * (eta * cos_i - cos_t)).normalize();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (through, dir, F::splat(0.5) * (rs * rs + rp * rp))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane-arithmetic sphere surface is the scalar one, bit for bit, in every found lane: point,
    /// normal, side and material, for rays from outside and from inside the spheres and from the eye.
    #[test]
    fn sphere_lanes_give_the_scalar_surface() {
        use crate::geometry::Ray;
        use crate::math::SplitMix64;
        use crate::scene::desc::{SceneDesc, SphereDesc};
        use wide::f32x8;
        let mut rng = SplitMix64::new(11);
        let mut unit = move || rng.unit() * 2.0 - 1.0;
        let mut desc = SceneDesc::default();
        for _ in 0..300 {
            let center = glam::DVec3::new(unit(), unit(), unit());
            desc.spheres.push(SphereDesc { center, radius: 0.05 + 0.1 * unit().abs(), material: 0 });
        }
        let scene = Scene::compile(&desc).expect("scene");
        let tracer = Tracer::<f32x8>::new(&scene);
        let mut checked = 0;
        for p in 0..400 {
            let rays = RayPacket::<f32x8>::from_fn(|i| {
                let inside = desc.spheres[(p * 8 + i) % 300].center;
                let origin = if p % 2 == 0 { glam::DVec3::new(unit(), unit(), -3.0) } else { inside };
                // Rays are made in the file's space; the compiled scene is in rendering space, whose origin
                // is the eye.
                let origin = if p % 3 == 2 { V3::all(0.0) } else { V3::from(origin - scene.origin) };
                let dir = V3::new(unit() * 0.3, unit() * 0.3, 1.0);
                (Ray::new(origin.to_f32(), dir.to_f32()), f32::INFINITY, (p + i) % 7 != 0)
            });
            let hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
            let found = hit.found() & rays.active;
            let camera = p % 3 == 2;
            let Some(lanes) = tracer.sphere_surface(&rays, &hit, found, camera) else { continue };
            let scalar = tracer.surface_by_lane(&rays, &hit, found, camera);
            let bits = |v: V3<f32x8>, i: usize| [v.x, v.y, v.z].map(|c| c.lane(i).to_bits());
            for i in (0..8).filter(|&i| f32x8::mask_lane(found, i)) {
                assert_eq!(bits(lanes.point, i), bits(scalar.point, i), "packet {p} lane {i}");
                assert_eq!(bits(lanes.normal, i), bits(scalar.normal, i), "packet {p} lane {i}");
                assert_eq!(bits(lanes.base, i), bits(scalar.base, i), "packet {p} lane {i}");
                assert_eq!(f32x8::mask_lane(lanes.inside, i), f32x8::mask_lane(scalar.inside, i));
                let fields = |s: &Surface<f32x8>| {
                    [s.ambient, s.diffuse, s.specular, s.shininess, s.reflect, s.transmit, s.ior]
                        .map(|f| f.lane(i).to_bits())
                };
                assert_eq!(fields(&lanes), fields(&scalar), "packet {p} lane {i}");
                checked += 1;
            }
        }
        assert!(checked > 1000, "only {checked} lanes checked");
    }

    /// Packets mixing spheres of one plain material and a flat polygon floor, or an ellipsoid, get the
    /// lane-by-lane surface's bits from the split form, at K = 4, 8 and 16, for camera rays and for rays
    /// leaving the hits, with the materials apart in every field and with spheres' own colours; a floor with a
    /// checker, or with vertex normals, is never split.
    #[test]
    fn split_surfaces_give_the_lane_by_lane_bits() {
        use crate::kinds::polygon::PolygonDesc;
        use crate::math::Rgb8;
        use crate::scene::desc::{Checker, SceneDesc, SphereDesc};
        use glam::{DAffine3, DVec3};
        let floor = |normals: Option<Vec<DVec3>>| PolygonDesc {
            vertices: [(-4.0, -4.0), (4.0, -4.0), (4.0, 4.0), (-4.0, 4.0)]
                .map(|(x, z)| DVec3::new(x, -1.0, z))
                .to_vec(),
            normals,
            material: 1,
        };
        let mut desc = SceneDesc::default();
        let glass = Material {
            color: Rgb::new(0.3, 0.6, 0.9),
            ambient: 0.15,
            diffuse: 0.7,
            specular: 0.3,
            shininess: 20.0,
            reflect: 0.25,
            transmit: 0.5,
            ior: 1.33,
            fresnel: true,
            checker: None,
        };
        let matte = Material {
            color: Rgb::new(0.9, 0.7, 0.5),
            ambient: 0.05,
            shininess: 64.0,
            ..Material::default()
        };
        desc.materials.extend([glass, matte]);
        let mut rng = crate::math::SplitMix64::new(21);
        for _ in 0..60 {
            let center = DVec3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 0.8 - 0.6, rng.unit() * 4.0 + 1.0);
            desc.spheres.push(SphereDesc { center, radius: 0.05 + 0.2 * rng.unit(), material: 0 });
        }
        desc.kinds.polygons.push(floor(None));
        let mut colored = desc.clone();
        colored.sphere_colors = (0..60u8).map(|i| Rgb8([i * 4, 255 - i * 4, 128])).collect();
        let mut ellipsoid = desc.clone();
        ellipsoid.kinds.polygons.clear();
        let stretch = DAffine3::from_scale_rotation_translation(
            DVec3::new(3.0, 0.6, 2.0),
            glam::DQuat::from_rotation_y(0.4),
            DVec3::new(0.0, -1.2, 3.5),
        );
        ellipsoid.kinds.push_shape(crate::geometry::ShapeKind::Sphere, stretch);
        ellipsoid.kinds.ellipsoids[0].material = 1;
        for (name, d) in [("floor", &desc), ("own colours", &colored), ("ellipsoid", &ellipsoid)] {
            let scene = Scene::compile(d).expect("scene");
            assert!(scene.split_surfaces, "{name}");
            let compared = check_split::<wide::f32x4>(&scene)
                + check_split::<wide::f32x8>(&scene)
                + check_split::<wide::f32x16>(&scene);
            assert!(compared > 500, "{name}: only {compared} lanes compared");
        }
        let mut checked = desc.clone();
        checked.materials[1].checker = Some(Checker { color: Rgb::new(0.1, 0.2, 0.3), size: 0.5 });
        assert!(!Scene::compile(&checked).expect("scene").split_surfaces);
        let mut smooth = desc.clone();
        smooth.kinds.polygons[0] = floor(Some(vec![DVec3::Y; 4]));
        let smooth = Scene::compile(&smooth).expect("scene");
        assert!(!smooth.split_surfaces);
        assert_eq!(check_split::<wide::f32x8>(&smooth), 0, "a floor with vertex normals was split");
    }

    /// Lanes of split surfaces compared with [`Tracer::surface_by_lane`] over packets aimed at the scene's
    /// spheres and floor, from the eye and from the spheres' hits.
    fn check_split<F: Lanes>(scene: &Scene) -> usize {
        use crate::geometry::Ray;
        let tracer = Tracer::<F>::new(scene);
        let mut rng = crate::math::SplitMix64::new(22);
        let mut compared = 0;
        for p in 0..1500 {
            let camera = p % 2 == 0;
            let rays = RayPacket::<F>::from_fn(|_| {
                let dir = V3::new(rng.unit() * 1.6 - 0.8, rng.unit() * 0.9 - 0.7, 1.0).to_f32();
                (Ray::new(V3::all(0.0), dir), f32::INFINITY, rng.unit() < 0.9)
            });
            let mut hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
            let mut rays = rays;
            if !camera {
                // Mirror rays from the camera rays' hits: they leave spheres and the floor.
                let found = hit.found() & rays.active;
                let s = tracer.surface_by_lane(&rays, &hit, found, true);
                let d = rays.ray.dir - s.normal * (F::splat_f32(2.0) * s.normal.dot(rays.ray.dir));
                rays = RayPacket::new(s.point, d, F::splat_f32(f32::INFINITY), found);
                let from = DeparturePacket { prim: hit.prim, inward: s.inside };
                hit = scene.geometry.intersect_k(&rays, &from);
            }
            let found = hit.found() & rays.active;
            let Some(lanes) = tracer.split_surface(&rays, &hit, found, camera) else { continue };
            let scalar = tracer.surface_by_lane(&rays, &hit, found, camera);
            let bits = |v: V3<F>, i: usize| [v.x, v.y, v.z].map(|c| c.lane(i).to_bits());
            for i in (0..F::K).filter(|&i| F::mask_lane(found, i)) {
                assert_eq!(bits(lanes.point, i), bits(scalar.point, i), "packet {p} lane {i}");
                assert_eq!(bits(lanes.normal, i), bits(scalar.normal, i), "packet {p} lane {i}");
                assert_eq!(bits(lanes.base, i), bits(scalar.base, i), "packet {p} lane {i}");
                assert_eq!(F::mask_lane(lanes.inside, i), F::mask_lane(scalar.inside, i));
                assert_eq!(F::mask_lane(lanes.fresnel, i), F::mask_lane(scalar.fresnel, i));
                let fields = |s: &Surface<F>| {
                    [s.ambient, s.diffuse, s.specular, s.shininess, s.reflect, s.transmit, s.ior]
                        .map(|f| f.lane(i).to_bits())
                };
                assert_eq!(fields(&lanes), fields(&scalar), "packet {p} lane {i}");
                compared += 1;
            }
        }
        compared
    }

    /// Camera rays grazing a unit sphere, and an ellipsoid, 1e6 away: the rounded hit point often puts the
    /// outward normal on the ray's side (`n·d > 0`), yet the eye is outside, so no hit is taken as from
    /// inside.
    #[test]
    fn grazing_camera_hits_on_a_distant_sphere_are_outside() {
        use crate::geometry::ShapeKind;
        use crate::math::SplitMix64;
        use crate::scene::desc::{SceneDesc, SphereDesc};
        use wide::f32x8;
        let centre = glam::DVec3::new(0.0, 0.0, 1e6);
        // Semi-axes: 1 and 1 for the sphere, 1 and 1.5 across the view for the ellipsoid.
        for stretch in [1.0, 1.5] {
            let mut desc = SceneDesc::default();
            if stretch == 1.0 {
                desc.spheres.push(SphereDesc { center: centre, radius: 1.0, material: 0 });
            } else {
                let world_from_object = glam::DAffine3::from_scale_rotation_translation(
                    glam::DVec3::new(1.0, stretch, 1.0),
                    glam::DQuat::IDENTITY,
                    centre,
                );
                desc.kinds.push_shape(ShapeKind::Sphere, world_from_object);
            }
            // A plane behind the eye keeps the eye's frame (alone, the far shape would be compiled around its
            // own centre, `crate::compile::RenderingFrame`): camera rays from the eye are what this checks.
            let behind = glam::DAffine3::from_translation(glam::DVec3::new(0.0, 0.0, -10.0));
            desc.kinds.push_shape(ShapeKind::Plane, behind);
            let scene = Scene::compile(&desc).expect("scene");
            assert_eq!(scene.camera_f64.start, 0.0, "the eye's frame");
            let tracer = Tracer::<f32x8>::new(&scene);
            let mut rng = SplitMix64::new(5);
            let (mut found_lanes, mut normal_wrong_side) = (0, 0);
            for _ in 0..500 {
                let rays = RayPacket::<f32x8>::from_fn(|_| {
                    // Aimed within a relative 1e-3 of the rim, all around it.
                    let a = rng.unit() * std::f64::consts::TAU;
                    let rim = 1.0 - 1e-3 * rng.unit();
                    let dir = V3::new(rim * a.cos(), stretch * rim * a.sin(), 1e6 - scene.origin.z).to_f32();
                    (crate::geometry::Ray::new(V3::all(0.0), dir), f32::INFINITY, true)
                });
                let hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
                let found = hit.found() & rays.active;
                let outward_dot = |s: &Surface<f32x8>, i: usize| {
                    let d = |v: wide::f32x8| v.lane(i);
                    // The flipped normal points back out where `inside` is set.
                    let sign = if f32x8::mask_lane(s.inside, i) { -1.0 } else { 1.0 };
                    sign * (d(s.normal.x) * d(rays.ray.dir.x)
                        + d(s.normal.y) * d(rays.ray.dir.y)
                        + d(s.normal.z) * d(rays.ray.dir.z))
                };
                let lanes = tracer.sphere_surface(&rays, &hit, found, true);
                assert_eq!(lanes.is_some(), stretch == 1.0 && found.any());
                for s in lanes.into_iter().chain([tracer.surface_by_lane(&rays, &hit, found, true)]) {
                    for i in (0..8).filter(|&i| f32x8::mask_lane(found, i)) {
                        assert!(!f32x8::mask_lane(s.inside, i), "a camera hit taken as from inside");
                        found_lanes += 1;
                        normal_wrong_side += usize::from(outward_dot(&s, i) > 0.0);
                    }
                }
            }
            assert!(found_lanes > 2000, "stretch {stretch}: {found_lanes} hits");
            assert!(normal_wrong_side > 0, "stretch {stretch}: no hit had its normal on the ray's side");
        }
    }

    /// The eye exactly on a sphere's surface (eye term 0): camera rays heading into the sphere hit it from
    /// outside at t = 0, rays heading away hit it from inside (its exit, also at t = 0); the side comes from
    /// the normal there, not from the eye term's sign.
    #[test]
    fn eye_on_a_sphere_takes_the_side_from_the_normal() {
        use crate::scene::desc::{SceneDesc, SphereDesc};
        use wide::f32x8;
        let mut desc = SceneDesc::default();
        // The default eye is (0, 0, −5): on this sphere, exactly.
        desc.spheres.push(SphereDesc { center: glam::DVec3::ZERO, radius: 5.0, material: 0 });
        let scene = Scene::compile(&desc).expect("scene");
        assert_eq!(scene.geometry.spheres.c_eye[0], 0.0);
        let tracer = Tracer::<f32x8>::new(&scene);
        let rays = RayPacket::<f32x8>::from_fn(|i| {
            let z = if i % 2 == 0 { 1.0 } else { -1.0 };
            let dir = V3::new(0.1 * i as f32 - 0.35, 0.05, z);
            (crate::geometry::Ray::new(V3::all(0.0), dir), f32::INFINITY, true)
        });
        let hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
        let found = hit.found() & rays.active;
        assert!(found.all());
        for s in [
            tracer.sphere_surface(&rays, &hit, found, true).expect("one material"),
            tracer.surface_by_lane(&rays, &hit, found, true),
        ] {
            for i in 0..8 {
                assert_eq!(f32x8::mask_lane(s.inside, i), i % 2 == 1, "lane {i}");
            }
        }
    }

    #[test]
    fn refraction_obeys_snell_and_fresnel_at_normal_incidence() {
        let n = V3::new(0.0, 1.0, 0.0);
        let d = V3::new(0.6f32, -0.8, 0.0);
        let (ok, t, f) = refract(d, n, 1.0 / 1.5);
        assert!(ok);
        // sin θ_t = sin θ_i / 1.5
        assert!((t.x - 0.6 / 1.5).abs() < 1e-6);
        assert!(f > 0.0 && f < 1.0);
        let (_, _, f0) = refract(V3::new(0.0, -1.0, 0.0), n, 1.0 / 1.5);
        assert!((f0 - 0.04).abs() < 1e-6, "normal-incidence reflectance of glass is 4%: {f0}");
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let n = V3::new(0.0, 1.0, 0.0);
        // Leaving glass (eta = 1.5) at 60° from the normal: sin θ_t = 1.3 > 1.
        assert!(!refract(V3::new(0.866_025_4f32, -0.5, 0.0), n, 1.5).0);
        assert!(refract(V3::new(0.5f32, -0.866_025_4, 0.0), n, 1.5).0);
    }

    #[test]
    fn checker_alternates_across_cells_and_zero() {
        let m = Material {
            checker: Some(crate::scene::desc::Checker { color: Rgb::all(0.0), size: 1.0 }),
            ..Material::default()
        };
        assert_eq!(surface_color(&m, m.color, V3::new(0.5, 0.5, 0.0)), m.color);
        assert_eq!(surface_color(&m, m.color, V3::new(1.5, 0.5, 0.0)), Rgb::all(0.0));
        assert_eq!(surface_color(&m, m.color, V3::new(-0.5, 0.5, 0.0)), Rgb::all(0.0));
    }
}
