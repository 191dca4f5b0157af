//! The leaf query of every kind whose items are tested one at a time against all lanes, with nothing
//! shared between items: triangles and the registered kinds' items (ellipsoids, planes, cones, tori). Each
//! kind says only how to test item `j` ([`ItemTest`]); the loops, the departure rule and the one-ray form
//! are written once, here.

use std::borrow::Borrow;

use crate::geometry::{HitPacket, Pyramid, Ray};
use crate::math::{Mask, Vec3f, V3};
use crate::simd::{IdLanes, Lanes};

use super::{LeafQuery, SingleLeafQuery};

/// How one kind tests its items.
pub(crate) trait ItemTest: Copy {
    /// Item `j`'s primitive id.
    fn id(&self, j: usize) -> u32;
    /// Item `j` against the rays in `[0, t_max)`: the lanes it is hit in and their t.
    fn test<F: Lanes>(&self, j: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F);
    /// Lanes whose ray cannot meet item `j` before `reach` (its best hit so far, or its `t_max`): a
    /// conservative test cheaper than [`ItemTest::test`], which is skipped when it rules out every live lane.
    /// None by default.
    #[inline(always)]
    fn culled<F: Lanes>(&self, _j: usize, _ray: &Ray<F>, _reach: F) -> F::Mask {
        F::mask_from_bits(0)
    }
}

/// A query of rays against the items of one kind: the rays (`R`: borrowed from the packet, which a packet
/// query does rather than copy them, or owned, as one lane's query is), each ray's exclusive end `t_max`, and
/// the primitive each ray leaves (`skip`, never reported).
#[derive(Clone, Copy)]
pub(crate) struct ItemQuery<F: Lanes, T: ItemTest, R: Borrow<Ray<F>> + Copy = Ray<F>> {
    /// The kind's items.
    pub(crate) items: T,
    /// The rays.
    pub(crate) ray: R,
    /// Exclusive end of each ray's range.
    pub(crate) t_max: F,
    /// The departure primitive of each ray.
    pub(crate) skip: F::Ids,
    /// Planes enclosing the live rays, from the packet's maker.
    pub(crate) pyramid: Option<Pyramid>,
}

impl<F: Lanes, T: ItemTest, R: Borrow<Ray<F>> + Copy> ItemQuery<F, T, R> {
    /// Item `j`'s hits for the lanes of `live` (the departure primitive's excluded), its t and id. The
    /// departure is checked first: an item no live ray may hit (the one every lane leaves) is not tested.
    #[inline(always)]
    fn item(&self, j: usize, live: F::Mask) -> (F::Mask, F, F::Ids) {
        let id = F::Ids::splat(self.items.id(j));
        let lanes = live & !F::ids_eq(id, self.skip);
        if !lanes.any() {
            return (lanes, self.t_max, id);
        }
        let (hit, t) = self.items.test(j, self.ray.borrow(), self.t_max);
        (lanes & hit, t, id)
    }
}

impl<F: Lanes, T: ItemTest, R: Borrow<Ray<F>> + Copy> LeafQuery<F> for ItemQuery<F, T, R> {
    type One = ItemQuery<f32, T>;

    #[inline(always)]
    fn ray(&self) -> &Ray<F> {
        self.ray.borrow()
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
    fn lane(&self, i: usize) -> ItemQuery<f32, T> {
        let lane = |v: &V3<F>| V3::new(v.x.lane(i), v.y.lane(i), v.z.lane(i));
        let ray = self.ray();
        ItemQuery {
            items: self.items,
            ray: Ray { origin: lane(&ray.origin), dir: lane(&ray.dir) },
            t_max: self.t_max.lane(i),
            skip: self.skip.lane(i),
            pyramid: None,
        }
    }

    #[inline(always)]
    fn intersect(&self, items: impl Iterator<Item = usize>, live: F::Mask, best: &mut HitPacket<F>) {
        for j in items {
            let lanes = live & !self.items.culled(j, self.ray(), best.t.min_of(self.t_max));
            if !lanes.any() {
                continue;
            }
            let (hit, t, id) = self.item(j, lanes);
            best.update(hit, t, id, id);
        }
    }

    #[inline(always)]
    fn occluded(&self, items: std::ops::Range<usize>, live: F::Mask, blocker: &mut u32) -> F::Mask {
        let mut blocked = F::mask_from_bits(0);
        for j in items {
            let lanes = live & !self.items.culled(j, self.ray(), self.t_max);
            if !lanes.any() {
                continue;
            }
            let (hit, _, _) = self.item(j, lanes);
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

impl<T: ItemTest> SingleLeafQuery for ItemQuery<f32, T> {
    #[inline(always)]
    fn intersect_leaf(&self, first: usize, count: usize, best: &mut HitPacket<f32>) {
        self.intersect(first..first + count, true, best);
    }
    #[inline(always)]
    fn occluded_leaf(&self, first: usize, count: usize, blocker: &mut u32) -> bool {
        self.occluded(first..first + count, true, blocker)
    }
}
