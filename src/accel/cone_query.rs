//! Open cones and cylinders as the items of BVH leaves and of brute force ([`ItemQuery`]): the cones stay in
//! file order (their ids are their positions); a tree's items are an index list into them. A ray never
//! meets the cone it leaves here: [`rehit_cone`](crate::geometry::rehit_cone) finds where it meets it again.

use crate::geometry::{intersect_cone, Cones, Ray};
use crate::simd::Lanes;

use crate::bvh::item_query::{ItemQuery, ItemTest};

/// The cones `order` lists (item j is cone `order[j]`, primitive `base + order[j]`; without a list, cone j).
#[derive(Clone, Copy)]
pub struct ConeItems<'a> {
    /// Every cone of the scene.
    pub(crate) cones: &'a Cones,
    /// The cones the items are, in the tree's leaf order; `None`: all of them, in order.
    pub(crate) order: Option<&'a [u32]>,
    /// The id of cone 0.
    pub(crate) base: u32,
}

impl ItemTest for ConeItems<'_> {
    #[inline(always)]
    fn test<F: Lanes>(&self, j: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F, u32) {
        let k = self.order.map_or(j as u32, |order| order[j]);
        let cone = self.cones.cone(k as usize).map(F::splat_f32);
        let (hit, t) = intersect_cone(&cone, ray, t_max);
        (hit, t, self.base + k)
    }
}

/// A query of rays against cones.
pub type ConeQuery<'a, F> = ItemQuery<F, ConeItems<'a>>;
