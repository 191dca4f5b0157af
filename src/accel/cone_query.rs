//! Open cones and cylinders as the items of BVH leaves ([`LeafQuery`]) and of brute force: the cones stay in
//! file order (their ids are their positions); a tree's items are an index list into them.

use crate::geometry::{intersect_cone, Cones, HitPacket, Pyramid, Ray};
use crate::math::{Mask, Vec3f, V3};
use crate::simd::{IdLanes, Lanes};

use super::bvh::{LeafQuery, SingleLeafQuery};

/// A query of rays against the cones `order` lists (item j is cone `order[j]`, primitive `base + order[j]`;
/// without a list, cone j): the rays, each ray's exclusive end `t_max`, and the primitive each ray leaves
/// (skipped here: [`rehit_cone`](crate::geometry::rehit_cone) finds where a ray meets its own cone again).
#[derive(Clone, Copy)]
pub struct ConeQuery<'a, F: Lanes> {
    /// Every cone of the scene.
    pub cones: &'a Cones,
    /// The cones the items are, in the tree's leaf order; `None`: all of them, in order.
    pub order: Option<&'a [u32]>,
    /// The id of cone 0.
    pub base: u32,
    /// The rays.
    pub ray: Ray<F>,
    /// Exclusive end of each ray's range.
    pub t_max: F,
    /// The departure primitive of each ray.
    pub skip: F::Ids,
    /// Planes enclosing the live rays, from the packet's maker.
    pub pyramid: Option<Pyramid>,
}

impl<F: Lanes> ConeQuery<'_, F> {
    /// Leaf item `j`'s hits for the lanes of `live` (its departure lanes excluded), t and id.
    #[inline(always)]
    fn cone(&self, j: usize, live: F::Mask) -> (F::Mask, F, F::Ids) {
        let k = self.order.map_or(j as u32, |order| order[j]);
        let id = F::Ids::splat(self.base + k);
        let cone = self.cones.cone(k as usize).map(F::splat_f32);
        let (hit, t) = intersect_cone(&cone, &self.ray, self.t_max);
        (live & hit & !F::ids_eq(id, self.skip), t, id)
    }
}

impl<'a, F: Lanes> LeafQuery<F> for ConeQuery<'a, F> {
    type One = ConeQuery<'a, f32>;

    #[inline(always)]
    fn ray(&self) -> &Ray<F> {
        &self.ray
    }
    #[inline(always)]
    fn t_max(&self) -> F {
        self.t_max
    }
    #[inline(always)]
    fn pyramid(&self) -> Option<Pyramid> {
        self.pyramid
    }
    #[inline(always)]
    fn ball(&self, _: usize) -> Option<(Vec3f, f32)> {
        None
    }

    #[inline(always)]
    fn lane(&self, i: usize) -> ConeQuery<'a, f32> {
        let lane = |v: &V3<F>| V3::new(v.x.lane(i), v.y.lane(i), v.z.lane(i));
        ConeQuery {
            cones: self.cones,
            order: self.order,
            base: self.base,
            ray: Ray { origin: lane(&self.ray.origin), dir: lane(&self.ray.dir) },
            t_max: self.t_max.lane(i),
            skip: self.skip.lane(i),
            pyramid: None,
        }
    }

    #[inline(always)]
    fn intersect(&self, items: impl Iterator<Item = usize>, live: F::Mask, best: &mut HitPacket<F>) {
        for j in items {
            let (hit, t, id) = self.cone(j, live);
            best.update(hit, t, id, id);
        }
    }

    #[inline(always)]
    fn occluded(&self, items: std::ops::Range<usize>, live: F::Mask, blocker: &mut u32) -> F::Mask {
        let mut blocked = F::mask_from_bits(0);
        for j in items {
            let (hit, _, _) = self.cone(j, live);
            if hit.any() {
                *blocker = j as u32;
                blocked = blocked | hit;
                if (blocked | !live).all() {
                    break;
                }
            }
        }
        blocked
    }
}

impl SingleLeafQuery for ConeQuery<'_, f32> {
    #[inline(always)]
    fn intersect_leaf(&self, first: usize, count: usize, best: &mut HitPacket<f32>) {
        self.intersect(first..first + count, true, best);
    }
    #[inline(always)]
    fn occluded_leaf(&self, first: usize, count: usize, blocker: &mut u32) -> bool {
        self.occluded(first..first + count, true, blocker)
    }
}
