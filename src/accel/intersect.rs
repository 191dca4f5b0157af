//! Closest-hit queries over the geometry (`intersect`): a packet's lanes, a tile of camera packets walked as
//! one large packet, and the K = 1 instance for one ray; spheres, particles, then the registered kinds, then
//! the departure surface's own exit.

use crate::bvh::{Bvh, LeafQuery};
use crate::geometry::{Departure, DeparturePacket, Hit, HitPacket, Pyramid, Ray, RayPacket, NO_PRIM};
use crate::kinds::{Kind, KindItems, VisitItems};
use crate::math::Mask;
use crate::simd::{IdLanes, Lanes};

use super::{count_work, Geometry, Work};

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

    /// The scene-file ids of the lanes' primitives in `lanes` (the others: [`NO_PRIM`]).
    fn keys_k<F: Lanes>(&self, prims: F::Ids, lanes: F::Mask) -> F::Ids {
        if !lanes.any() {
            return F::Ids::splat(NO_PRIM);
        }
        F::Ids::from_fn(|i| if F::mask_lane(lanes, i) { self.file_id(prims.lane(i)) } else { NO_PRIM })
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
