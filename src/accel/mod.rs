//! The scene's geometry laid out for intersection, and the queries over it: `intersect` (closest hit,
//! `intersect.rs`) and `occluded` (any hit, `occluded.rs`), for packets of K rays (`_k`) and for single rays
//! (the K = 1 instance); what an id refers to and its surface here.
//!
//! Each bounded kind has its own BVH (`crate::bvh`, one tree type monomorphised over the kind's
//! `crate::bvh::LeafQuery`): spheres (`SphereQuery`) and each registered kind ([`crate::kinds`]: polygons'
//! triangles, ellipsoids, open cones, tori); a kind with few items is tested brute
//! force by the same query, and so is an unbounded kind (planes). One kind per tree keeps each leaf loop
//! free of a per-item dispatch and leaves the sphere walk exactly as it is without other kinds.

mod colors;
mod departure;
mod intersect;
mod light_buffer;
mod near_first;
mod occluded;
pub(crate) mod pkd;
pub(crate) use crate::bvh::item_query::{ItemQuery, ItemTest};
pub(crate) use crate::bvh::work::{add_work, count_work, counting, traced};
pub(crate) use crate::bvh::work::{
    probe_overhead, take_kind_work, take_work, ticks, KindWork, KIND_SLOTS, UNTAGGED,
};
pub use crate::bvh::work::{Probe, RayKind, Work};
pub(crate) use crate::kinds::sphere::SphereQuery;
pub(crate) use light_buffer::LightBuffer;
pub(crate) use near_first::NearFirst;
pub(crate) use pkd::Particles;

use crate::bvh::Bvh;
use crate::kinds::KindStores;

use crate::geometry::{DeparturePacket, Ray, RayPacket, NO_PRIM};
use crate::kinds::sphere::Spheres;
use crate::math::Vec3f;
use crate::simd::Lanes;

/// All primitives: spheres have ids `0..spheres.len()`, then the spheres of the particle tree (a scene has
/// one or the other), then the registered kinds' primitives ([`crate::kinds`]: polygons, ellipsoids,
/// planes, cones, tori) kind by kind.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Plain spheres, in BVH leaf order when there is a BVH.
    pub spheres: Spheres,
    /// The BVH over the spheres, or `None` for brute force.
    pub(crate) sphere_bvh: Option<Bvh>,
    /// Spheres in a particle tree (`--accel pkd`, for fields too large for a BVH) instead of `spheres`.
    pub(crate) particles: Particles,
    /// The registered kinds' items and trees ([`crate::kinds`]), ids after the spheres.
    pub(crate) kinds: KindStores,
    /// Per point light (in the scene's order), the spheres each direction from it may meet, for its
    /// shadow rays ([`LightBuffer`]); empty where shading casts no shadow rays or the spheres have no tree,
    /// `None` for a light its buffer would not serve well.
    pub(crate) light_buffers: Vec<Option<LightBuffer>>,
}

/// What a primitive id refers to.
#[derive(Clone, Copy, Debug)]
pub(crate) enum PrimRef {
    /// Index into [`Geometry::spheres`].
    Sphere(usize),
    /// Position in [`Geometry::particles`].
    Particle(usize),
    /// Index over the registered kinds' primitives in id order ([`Geometry::kinds`]).
    Kind(usize),
}

/// What shading needs to know about a hit point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfacePoint {
    /// World-space hit point.
    pub(crate) point: Vec3f,
    /// Unit geometric normal, pointing out of the primitive (not yet turned toward the ray).
    pub(crate) normal: Vec3f,
    /// The hit point in the primitive's own frame (centre-relative for spheres, z = 0 for planes), for
    /// solid textures.
    pub(crate) object_point: Vec3f,
    /// Material index.
    pub(crate) material: u32,
}

impl Geometry {
    /// The sphere part of a packet query.
    fn sphere_query<'a, F: Lanes>(
        &'a self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
    ) -> SphereQuery<'a, F> {
        SphereQuery::new(&self.spheres, *rays.ray(), rays.t_max, from.prim, rays.pyramid, rays.active)
    }

    /// A query of one kind's `items` for the packet.
    #[inline(always)]
    fn item_query<'r, F: Lanes, T: ItemTest>(
        items: T,
        rays: &'r RayPacket<F>,
        from: &DeparturePacket<F>,
    ) -> ItemQuery<F, T, &'r Ray<F>> {
        ItemQuery { items, ray: rays.ray(), t_max: rays.t_max, skip: from.prim, pyramid: rays.pyramid }
    }

    /// The BVHs the scene has.
    pub(crate) fn bvhs(&self) -> impl Iterator<Item = &Bvh> {
        self.sphere_bvh.iter().chain(self.kinds.bvhs())
    }

    /// The BVHs the scene has, to change their walk settings.
    pub(crate) fn bvhs_mut(&mut self) -> impl Iterator<Item = &mut Bvh> {
        self.sphere_bvh.iter_mut().chain(self.kinds.bvhs_mut())
    }

    /// Sets whether single rays (K = 1: [`Geometry::intersect`], the any-hit queries and the `_k` queries
    /// at `f32`) walk each BVH's binary tree one box and one primitive at a time (the scalar path), or the
    /// wide nodes with SIMD over a node's children and a leaf's spheres (single-ray SIMD). Both give the same
    /// bits. Turning it on needs the trees, kept by compiling with
    /// [`crate::compile::CompileOptions::scalar`] (which also turns it on); returns whether every BVH walks
    /// as asked.
    pub(crate) fn set_scalar_walk(&mut self, on: bool) -> bool {
        let mut all = true;
        for bvh in self.bvhs_mut() {
            bvh.scalar_walk = on;
            all &= !on || bvh.scalar.is_some();
        }
        all
    }

    /// Whether packet queries cull by a `crate::geometry::Pyramid`: only then is it worth a packet maker's
    /// while to compute one.
    pub fn culls_by_pyramid(&self) -> bool {
        self.bvhs().any(|bvh| bvh.frustum_culling)
            || (!self.particles.is_empty() && self.particles.frustum_culling)
    }

    /// The scene-file id of primitive `prim` (spheres are stored in BVH or particle-tree order; other ids
    /// are unchanged).
    pub fn file_id(&self, prim: u32) -> u32 {
        let (i, spheres) = (prim as usize, self.spheres.len());
        match self.spheres.key.get(i) {
            Some(&id) => id,
            None if (spheres..self.kinds_base()).contains(&i) => {
                (spheres + self.particles.key(i - spheres) as usize) as u32
            }
            None => prim,
        }
    }

    /// Total number of primitives.
    pub fn len(&self) -> usize {
        self.kinds_base() + self.kinds.len()
    }
    /// True when the scene has no primitives.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The id of the registered kinds' first primitive (their primitives are numbered on from it in the
    /// registry's order).
    pub(crate) fn kinds_base(&self) -> usize {
        self.spheres.len() + self.particles.len()
    }

    /// What primitive id `prim` (< `len()`) refers to.
    pub(crate) fn prim(&self, prim: u32) -> PrimRef {
        let i = prim as usize;
        if i < self.spheres.len() {
            PrimRef::Sphere(i)
        } else if i < self.kinds_base() {
            PrimRef::Particle(i - self.spheres.len())
        } else {
            PrimRef::Kind(i - self.kinds_base())
        }
    }

    /// Whether a camera ray (from the eye, the rendering space's origin) meets primitive `prim` from inside,
    /// where that is known exactly: for a sphere or a kind with an eye term (an ellipsoid), the sign of its
    /// exact eye term (`|C|² − r²`, or `|o_eye|² − 1` in object space: negative when the eye is in it,
    /// [`crate::kinds::Kind::eye_term`]). `None` where the eye term is zero
    /// (the eye on the surface: rays leave it or enter it there, and the normal tells which) and for the
    /// other kinds, whose side is read from the normal. Why:
    /// at a grazing hit the rounded hit point can put the normal's side wrong (a unit sphere 1e6 away, `t`
    /// one ulp long, turns `n·d` from −0.013 to +0.013), and the hit would be shaded and left as if from
    /// inside.
    pub(crate) fn eye_inside(&self, prim: u32) -> Option<bool> {
        let c_eye = match self.prim(prim) {
            PrimRef::Sphere(i) => self.spheres.c_eye[i],
            PrimRef::Particle(i) => self.particles.c_eye(i),
            PrimRef::Kind(k) => self.kinds.eye_term(k)?,
        };
        crate::geometry::eye_side(f64::from(c_eye))
    }

    /// Position, normal and material of hit `t` on primitive `prim` along `ray`.
    pub(crate) fn surface(&self, ray: &Ray<f32>, t: f32, prim: u32) -> SurfacePoint {
        debug_assert_ne!(prim, NO_PRIM);
        let point = ray.at(t);
        match self.prim(prim) {
            PrimRef::Sphere(i) => {
                let object_point = point - self.spheres.center(i);
                let normal = object_point.normalize();
                SurfacePoint { point, normal, object_point, material: self.spheres.material[i] }
            }
            PrimRef::Particle(i) => {
                let (centre, _) = self.particles.sphere(i);
                let object_point = point - centre;
                let normal = object_point.normalize();
                SurfacePoint { point, normal, object_point, material: self.particles.material(i) }
            }
            PrimRef::Kind(k) => {
                let (normal, object_point, material) =
                    self.kinds.surface(k, ray, t, point).expect("an id below len() is an item");
                SurfacePoint { point, normal, object_point, material }
            }
        }
    }
}
