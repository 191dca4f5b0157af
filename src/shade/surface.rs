//! Each lane's surface at its hit: point, normal turned toward the ray, and material, by lane arithmetic
//! where the packet's found lanes allow it (spheres of one plain material, one item of a kind with a lane
//! form, or a mix of the two), else lane by lane with the scalar code; every form gives each lane the
//! scalar code's bits.

use crate::accel::PrimRef;
use crate::geometry::{at_eye, HitPacket, RayPacket};
use crate::math::{Mask, Rgb, Vec3f, V3};
use crate::scene::desc::Material;
use crate::simd::{set_bits, IdLanes, Lanes};

use super::{splat_rgb, Tracer};

/// The outward `normal` turned toward rays along `dir`, and the lanes where it was flipped (hit from
/// inside: the lecture's case 4): in the lanes of `known`, inside where `eye_inside` says so (a camera ray's
/// sphere hit, [`crate::accel::Geometry::eye_inside`]); elsewhere where `n·d > 0`. Zero normals (lanes that
/// found nothing) stay unflipped.
fn facing<F: Lanes>(normal: V3<F>, dir: V3<F>, known: F::Mask, eye_inside: F::Mask) -> (V3<F>, F::Mask) {
    let inside = (known & eye_inside) | (!known & normal.dot(dir).gt(F::splat_f32(0.0)));
    (V3::select(inside, -normal, normal), inside)
}

/// What shading needs at the hit of each lane, gathered from the lanes' primitives and materials.
pub(super) struct Surface<F: Lanes> {
    pub(super) point: V3<F>,
    /// Unit normal turned toward the incoming ray.
    pub(super) normal: V3<F>,
    /// Lanes hit from inside (normal flipped: the lecture's case 4).
    pub(super) inside: F::Mask,
    pub(super) base: V3<F>,
    pub(super) ambient: F,
    pub(super) diffuse: F,
    pub(super) specular: F,
    pub(super) shininess: F,
    pub(super) reflect: F,
    pub(super) transmit: F,
    pub(super) ior: F,
    pub(super) fresnel: F::Mask,
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

impl<F: Lanes> Tracer<'_, F> {
    /// Each found lane's surface point and material: by lane arithmetic when every found lane hit a sphere
    /// of one plain material (most packets), or one item of a kind with a lane form, or a mix of the two
    /// ([`Tracer::split_surface`]); else lane by lane with the scalar code. `camera`: the rays are
    /// camera rays (departing from nothing); those that start at the eye take their sphere or ellipsoid
    /// hit's side from the eye term.
    pub(super) fn surface(
        &self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        found: F::Mask,
        camera: bool,
    ) -> Surface<F> {
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
        let (k, _) = self.kind_item(hit, rest)?;
        let material = geometry.kinds.material_in_lanes(k)?;
        if self.scene.materials[material as usize].checker.is_some() {
            return None;
        }
        let sphere = self.sphere_surface(rays, hit, on_spheres, camera)?;
        let item = self.kind_surface(rays, hit, rest, camera)?;
        Some(Surface::select(on_spheres, sphere, item))
    }

    /// The item that every lane of `lanes` hit, if they all hit one item of a registered kind (not a sphere
    /// or a particle): its index among the registered kinds' primitives and its primitive id; `None` for no
    /// lanes.
    #[inline(always)]
    fn kind_item(&self, hit: &HitPacket<F>, lanes: F::Mask) -> Option<(usize, u32)> {
        let bits = F::move_mask(lanes);
        let prim = hit.prim.lane(set_bits(bits).next()?);
        let PrimRef::Kind(k) = self.scene.geometry.prim(prim) else { return None };
        set_bits(bits).all(|i| hit.prim.lane(i) == prim).then_some((k, prim))
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
        let (k, prim) = self.kind_item(hit, found)?;
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

#[cfg(test)]
mod tests;
