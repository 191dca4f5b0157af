//! The scene's geometry laid out for intersection, and the queries over it: `intersect` (closest hit) and
//! `occluded` (any hit), for packets of K rays (`_k`) and for single rays (the K = 1 instance).
//!
//! Each bounded kind has its own BVH (`crate::bvh`, one tree type monomorphised over the kind's
//! `crate::bvh::LeafQuery`): spheres (`SphereQuery`) and each registered kind ([`crate::kinds`]: polygons'
//! triangles, ellipsoids, open cones, tori); a kind with few items is tested brute
//! force by the same query, and so is an unbounded kind (planes). One kind per tree keeps each leaf loop
//! free of a per-item dispatch and leaves the sphere walk exactly as it is without other kinds.

mod colors;
mod departure;
mod light_buffer;
mod near_first;
pub(crate) mod pkd;
mod sphere_query;
pub(crate) use crate::bvh::item_query::{ItemQuery, ItemTest};
pub(crate) use crate::bvh::work::{add_work, count_work, counting, traced};
pub(crate) use crate::bvh::work::{
    probe_overhead, take_kind_work, take_work, ticks, KindWork, KIND_SLOTS, UNTAGGED,
};
pub use crate::bvh::work::{Probe, RayKind, Work};
pub(crate) use light_buffer::LightBuffer;
pub(crate) use near_first::NearFirst;
pub(crate) use pkd::Particles;
pub(crate) use sphere_query::SphereQuery;

use crate::bvh::{Bvh, LeafQuery};
use crate::kinds::{Kind, KindItems, KindStores, VisitItems};

use crate::geometry::{
    Departure, DeparturePacket, Hit, HitPacket, Pyramid, Ray, RayPacket, Spheres, NO_PRIM,
};
use crate::math::{Mask, Vec3f};
use crate::simd::{IdLanes, Lanes};

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

/// Closest hits of the `n` items of one kind for the lanes of `live`, merged into `best`: through the kind's
/// BVH when it has one, else brute force over all of them.
#[inline(always)]
fn intersect_items<F: Lanes, Q: LeafQuery<F>>(
    bvh: Option<&Bvh>,
    q: &Q,
    n: usize,
    live: F::Mask,
    best: &mut HitPacket<F>,
) {
    match bvh {
        Some(bvh) => bvh.intersect_k(q, live, best),
        None => {
            count_work(|| Work::lanes(n, n * F::move_mask(live).count_ones() as usize, 0, 0));
            q.intersect(0..n, live, best);
        }
    }
}

/// Lanes of `live` blocked by one of the `n` items of one kind, like [`intersect_items`]; `blocker` is set to
/// an item that blocked a lane.
#[inline(always)]
fn occluded_items<F: Lanes, Q: LeafQuery<F>>(
    bvh: Option<&Bvh>,
    q: &Q,
    n: usize,
    live: F::Mask,
    blocker: &mut u32,
) -> F::Mask {
    if !live.any() {
        return live;
    }
    match bvh {
        Some(bvh) => bvh.occluded_k(q, live, blocker),
        None => {
            // Counted as every item, as a visited BVH leaf counts all of its items (the test may stop early).
            count_work(|| Work::lanes(n, n * F::move_mask(live).count_ones() as usize, 0, 0));
            q.occluded(0..n, live, blocker)
        }
    }
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
    /// Closest hits of a packet in each lane's `[0, t_max)`, never on the near side of its departure surface.
    /// Misses and inactive lanes report `t = inf` and [`NO_PRIM`].
    ///
    /// Lane `i` of the result is what [`Geometry::intersect`] finds for lane `i`'s ray, bit for bit:
    ///
    /// ```
    /// use std::path::Path;
    ///
    /// use bareray::geometry::{Departure, DeparturePacket, RayPacket};
    /// use wide::f32x8;
    ///
    /// let desc = bareray::io::load(Path::new("scenes/field.toml"))?;
    /// let scene = bareray::compile::Scene::compile(&desc)?;
    /// // Camera rays through eight pixel centres along the middle row (rendering space: eye at the origin).
    /// let row = scene.camera.height as f32 / 2.0;
    /// let rays: Vec<_> = (0..8).map(|i| scene.camera_f64.ray_f32(40.0 * i as f32 + 0.5, row)).collect();
    ///
    /// let packet = RayPacket::<f32x8>::from_rays(&rays, f32::INFINITY);
    /// let hits = scene.geometry.intersect_k(&packet, &DeparturePacket::camera());
    /// for (i, ray) in rays.iter().enumerate() {
    ///     let one = scene.geometry.intersect(ray, Departure::CAMERA, f32::INFINITY);
    ///     assert_eq!(hits.lane(i), one);
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn intersect_k<F: Lanes>(&self, rays: &RayPacket<F>, from: &DeparturePacket<F>) -> HitPacket<F> {
        self.intersect_walked(rays, from, false)
    }

    /// [`Geometry::intersect_k`], the sphere tree walked by each live lane alone when `by_lanes` (the same
    /// bits).
    pub(crate) fn intersect_walked<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        by_lanes: bool,
    ) -> HitPacket<F> {
        let mut best = HitPacket::miss();
        if !rays.active.any() {
            return best;
        }
        if !self.spheres.is_empty() {
            let q = self.sphere_query(rays, from);
            match (by_lanes, self.sphere_bvh.as_ref()) {
                (true, Some(bvh)) => bvh.intersect_lanes(&q, rays.active, &mut best),
                (_, bvh) => intersect_items(bvh, &q, self.spheres.len(), rays.active, &mut best),
            }
        }
        self.intersect_other_kinds(rays, from, true, &mut best);
        let (exits, t) = self.departure_exits_k(rays, from);
        best.update(exits, t, from.prim, self.keys_k::<F>(from.prim, exits));
        best
    }

    /// [`Geometry::intersect_k`] for each packet of a tile of camera rays (origin at the eye, departing from
    /// no surface) into `hits`, bit for bit: with a sphere BVH that culls by frusta
    /// ([`Bvh::frustum_culling`]) and `pyramid` (enclosing every active ray of the tile), the packets walk
    /// the sphere tree together as one large packet; at most [`crate::bvh::MAX_PACKETS`] packets then. The large
    /// walk culls by frusta alone, so with frustum culling off every packet walks on its own.
    pub(crate) fn intersect_tile<F: Lanes>(
        &self,
        packets: &[RayPacket<F>],
        pyramid: Option<&Pyramid>,
        hits: &mut [HitPacket<F>],
    ) {
        let camera = DeparturePacket::camera();
        let bvh = self.sphere_bvh.as_ref().filter(|bvh| bvh.frustum_culling);
        let tree = (!self.particles.is_empty() && self.particles.frustum_culling).then_some(&self.particles);
        let (Some(pyramid), true, true) = (pyramid, F::K > 1, bvh.is_some() || tree.is_some()) else {
            for (rays, hit) in packets.iter().zip(hits) {
                *hit = self.intersect_k(rays, &camera);
            }
            return;
        };
        hits.fill(HitPacket::miss());
        match bvh {
            Some(bvh) => {
                bvh.intersect_large(packets, |p| self.sphere_query(&packets[p], &camera), pyramid, hits)
            }
            None if !self.spheres.is_empty() => {
                for (rays, hit) in packets.iter().zip(hits.iter_mut()) {
                    let q = self.sphere_query(rays, &camera);
                    intersect_items(self.sphere_bvh.as_ref(), &q, self.spheres.len(), rays.active, hit);
                }
            }
            None => {}
        }
        if let Some(tree) = tree {
            tree.intersect_large(packets, pyramid, self.spheres.len() as u32, hits);
        }
        let particles_left = tree.is_none() && !self.particles.is_empty();
        if self.has_other_kinds() || particles_left {
            for (rays, hit) in packets.iter().zip(hits).filter(|(rays, _)| rays.active.any()) {
                self.intersect_other_kinds(rays, &camera, particles_left, hit);
            }
        }
    }

    /// Whether the scene has primitives other than spheres and particles.
    fn has_other_kinds(&self) -> bool {
        self.kinds.has_items()
    }

    /// The closest hits of every kind but spheres (and particles unless `particles`), merged into `best`.
    fn intersect_other_kinds<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        particles: bool,
        best: &mut HitPacket<F>,
    ) {
        if particles {
            self.particles.intersect_k(rays, from, self.spheres.len() as u32, best);
        }
        if self.kinds.has_items() {
            let base = self.kinds_base() as u32;
            self.kinds.visit(&mut IntersectKinds { rays, from, best, base });
        }
    }

    /// Lanes of the packet whose ray meets anything in its `[0, t_max)` (the departure surface's near side
    /// excluded); inactive lanes are false. The renderer asks through [`Geometry::occluded_hinted_k`] and
    /// [`Geometry::shadowed_k`]; the tests ask here.
    #[cfg(test)]
    pub(crate) fn occluded_k<F: Lanes>(&self, rays: &RayPacket<F>, from: &DeparturePacket<F>) -> F::Mask {
        let mut hint = NO_PRIM;
        self.occluded_hinted_k(rays, from, &mut hint)
    }

    /// Lanes of the packet whose ray meets anything in its `[0, t_max)` (the departure surface's near side
    /// excluded; inactive lanes are false). The sphere `hint` is tested first (a blocker of an earlier, nearby
    /// packet: neighbouring shadow rays tend to be blocked by the same sphere), and `hint` is left holding a
    /// sphere that blocked some lane this time. The answer is the same whatever the hint: it only decides
    /// what is tested first.
    pub(crate) fn occluded_hinted_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        hint: &mut u32,
    ) -> F::Mask {
        self.occluded_through(rays, from, hint, None)
    }

    /// [`Geometry::occluded_hinted_k`] for shadow rays toward point light `light` (rays from their hit
    /// points, `t_max` the distance to the light): the spheres are found through the light's buffer when it
    /// has one ([`LightBuffer`]), with the same answer.
    pub(crate) fn shadowed_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        hint: &mut u32,
        light: usize,
    ) -> F::Mask {
        self.occluded_through(rays, from, hint, self.light_buffers.get(light).and_then(Option::as_ref))
    }

    /// [`Geometry::occluded_hinted_k`], the spheres through `buffer` when given.
    #[inline(always)]
    fn occluded_through<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        hint: &mut u32,
        buffer: Option<&LightBuffer>,
    ) -> F::Mask {
        let live = rays.active;
        if !live.any() {
            return live;
        }
        let mut blocked = F::mask_from_bits(0);
        if !self.spheres.is_empty() {
            let q = self.sphere_query(rays, from);
            if (*hint as usize) < self.spheres.len() {
                let h = *hint as usize;
                count_work(|| Work::lanes(1, F::move_mask(live).count_ones() as usize, 0, 0));
                blocked = q.occluded(h..h + 1, live, hint);
                if (blocked | !live).all() {
                    return blocked;
                }
            }
            let open = live & !blocked;
            blocked = blocked
                | match (buffer, self.sphere_bvh.as_ref()) {
                    (Some(buffer), Some(bvh)) => buffer.occluded(&q, open, bvh.walks_scalar(), hint),
                    (_, bvh) => occluded_items(bvh, &q, self.spheres.len(), open, hint),
                };
            if (blocked | !live).all() {
                return blocked;
            }
        }
        if !self.particles.is_empty() {
            let base = self.spheres.len() as u32;
            blocked = blocked | self.particles.occluded_k(rays, from, base, live & !blocked);
            if (blocked | !live).all() {
                return blocked;
            }
        }
        if self.kinds.has_items() && !(blocked | !live).all() {
            let base = self.kinds_base() as u32;
            let mut visit = OccludedKinds { rays, from, live, blocked, base };
            self.kinds.visit(&mut visit);
            blocked = visit.blocked;
        }
        blocked | self.departure_exits_k(rays, from).0
    }

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

    /// Closest hit of one ray in `[0, t_max)`: the K = 1 instance of [`Geometry::intersect_k`].
    ///
    /// The geometry lives in the compiled scene's rendering space, whose origin is the camera's eye
    /// ([`crate::compile::Scene::to_rendering`] maps world points into it); `from` is
    /// [`Departure::CAMERA`] for a ray that starts on no surface.
    ///
    /// ```
    /// use std::path::Path;
    ///
    /// use bareray::geometry::{Departure, Ray};
    /// use bareray::math::V3;
    ///
    /// let desc = bareray::io::load(Path::new("scenes/whitted.toml"))?;
    /// let scene = bareray::compile::Scene::compile(&desc)?;
    /// // From the eye (the origin of rendering space) through the image centre.
    /// let (width, height) = (scene.camera.width as f32, scene.camera.height as f32);
    /// let ahead = scene.camera_f64.ray_f32(width / 2.0, height / 2.0);
    /// let hit = scene.geometry.intersect(&ahead, Departure::CAMERA, f32::INFINITY);
    /// if hit.is_hit() {
    ///     let id = scene.geometry.file_id(hit.prim);
    ///     println!("primitive {id} (scene-file numbering) at t = {}", hit.t);
    /// }
    /// // Straight up from far below the scene: nothing there.
    /// let up = Ray::new(scene.to_rendering(glam::DVec3::new(0.0, -1e6, 0.0)), V3::new(0.0, -1.0, 0.0));
    /// assert!(!scene.geometry.intersect(&up, Departure::CAMERA, f32::INFINITY).is_hit());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn intersect(&self, ray: &Ray<f32>, from: Departure, t_max: f32) -> Hit {
        let rays = RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true);
        let hit = self.intersect_k(&rays, &DeparturePacket { prim: from.prim, inward: from.inward });
        Hit { t: hit.t, prim: hit.prim }
    }

    /// Whether one ray meets anything in `[0, t_max)`: the K = 1 instance of [`Geometry::occluded_k`].
    #[cfg(test)]
    pub(crate) fn occluded(&self, ray: &Ray<f32>, from: Departure, t_max: f32) -> bool {
        let rays = RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true);
        self.occluded_k(&rays, &DeparturePacket { prim: from.prim, inward: from.inward })
    }

    /// Whether one shadow ray toward point light `light` (from its hit point, `t_max` the distance to the
    /// light) is blocked: the K = 1 instance of [`Geometry::shadowed_k`], through the light's buffer.
    pub(crate) fn shadowed(&self, ray: &Ray<f32>, from: Departure, t_max: f32, light: usize) -> bool {
        let rays = RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true);
        let (from, mut hint) = (DeparturePacket { prim: from.prim, inward: from.inward }, NO_PRIM);
        self.shadowed_k(&rays, &from, &mut hint, light)
    }

    /// The scene-file ids of the lanes' primitives in `lanes` (the others: [`NO_PRIM`]).
    fn keys_k<F: Lanes>(&self, prims: F::Ids, lanes: F::Mask) -> F::Ids {
        if !lanes.any() {
            return F::Ids::splat(NO_PRIM);
        }
        F::Ids::from_fn(|i| if F::mask_lane(lanes, i) { self.file_id(prims.lane(i)) } else { NO_PRIM })
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

/// The registered kinds' closest hits for a packet, merged into `best`, kind by kind.
struct IntersectKinds<'a, F: Lanes> {
    rays: &'a RayPacket<F>,
    from: &'a DeparturePacket<F>,
    best: &'a mut HitPacket<F>,
    /// The id of the kinds' first primitive.
    base: u32,
}

impl<F: Lanes> VisitItems for IntersectKinds<'_, F> {
    #[inline(always)]
    fn visit<K: Kind>(&mut self, items: &KindItems<K>, first: u32) {
        let base = self.base + first;
        match K::INLINE_QUERIES {
            true => intersect_kind_here(items, base, self.rays, self.from, self.best),
            false => intersect_kind(items, base, self.rays, self.from, self.best),
        }
    }
}

/// One kind's closest hits for a packet, merged into `best`: a function of each kind's own, and its tree
/// walk one more. Inlined into the loop over kinds, every kind's kernel and walk would share one stack frame
/// of several pages (the walk's stack, a torus's solver), set up and probed on every query of any kind:
/// 2.5% of whitted.toml's instructions (a plane and two spheres), per cachegrind.
#[inline(never)]
fn intersect_kind<F: Lanes, K: Kind>(
    items: &KindItems<K>,
    base: u32,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    best: &mut HitPacket<F>,
) {
    // The query is built in each arm: the brute-force arm does not copy the pyramid, which only walks read.
    let q = || Geometry::item_query(items.items(base), rays, from);
    match &items.bvh {
        Some(bvh) => intersect_tree(bvh, &q(), rays.active, best),
        None => intersect_items(None, &q(), items.len(), rays.active, best),
    }
}

/// [`intersect_kind`] inlined where it is asked, for a kind whose queries are small
/// ([`Kind::INLINE_QUERIES`]).
#[inline(always)]
fn intersect_kind_here<F: Lanes, K: Kind>(
    items: &KindItems<K>,
    base: u32,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    best: &mut HitPacket<F>,
) {
    let q = Geometry::item_query(items.items(base), rays, from);
    intersect_items(items.bvh.as_ref(), &q, items.len(), rays.active, best);
}

/// [`intersect_kind`]'s tree walk.
#[inline(never)]
fn intersect_tree<F: Lanes, Q: LeafQuery<F>>(bvh: &Bvh, q: &Q, live: F::Mask, best: &mut HitPacket<F>) {
    bvh.intersect_k(q, live, best)
}

/// The lanes of a packet the registered kinds block, added to `blocked`, kind by kind until all are.
struct OccludedKinds<'a, F: Lanes> {
    rays: &'a RayPacket<F>,
    from: &'a DeparturePacket<F>,
    live: F::Mask,
    blocked: F::Mask,
    /// The id of the kinds' first primitive.
    base: u32,
}

impl<F: Lanes> VisitItems for OccludedKinds<'_, F> {
    #[inline(always)]
    fn visit<K: Kind>(&mut self, items: &KindItems<K>, first: u32) {
        let (open, base) = (self.live & !self.blocked, self.base + first);
        if open.any() {
            let blocked = match K::INLINE_QUERIES {
                true => occluded_kind_here(items, base, self.rays, self.from, open),
                false => occluded_kind(items, base, self.rays, self.from, open),
            };
            self.blocked = self.blocked | blocked;
        }
    }
}

/// The lanes of `open` one kind blocks: a function of each kind's own, its tree walk another, as for
/// [`intersect_kind`].
#[inline(never)]
fn occluded_kind<F: Lanes, K: Kind>(
    items: &KindItems<K>,
    base: u32,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    open: F::Mask,
) -> F::Mask {
    let q = || Geometry::item_query(items.items(base), rays, from);
    let mut item = 0;
    match &items.bvh {
        Some(bvh) => occluded_tree(bvh, &q(), open),
        None => occluded_items(None, &q(), items.len(), open, &mut item),
    }
}

/// [`occluded_kind`] inlined where it is asked, for a kind whose queries are small
/// ([`Kind::INLINE_QUERIES`]).
#[inline(always)]
fn occluded_kind_here<F: Lanes, K: Kind>(
    items: &KindItems<K>,
    base: u32,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    open: F::Mask,
) -> F::Mask {
    let (q, mut item) = (Geometry::item_query(items.items(base), rays, from), 0);
    occluded_items(items.bvh.as_ref(), &q, items.len(), open, &mut item)
}

/// [`occluded_kind`]'s tree walk.
#[inline(never)]
fn occluded_tree<F: Lanes, Q: LeafQuery<F>>(bvh: &Bvh, q: &Q, open: F::Mask) -> F::Mask {
    let mut item = 0;
    bvh.occluded_k(q, open, &mut item)
}
