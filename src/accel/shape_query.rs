//! Transformed shapes as the items of BVH leaves and of brute force ([`ItemQuery`]): the shapes stay in file
//! order (their ids are their positions); a tree's items are an index list into them.

use crate::geometry::{Ray, Shape};
use crate::simd::Lanes;

use crate::bvh::item_query::{ItemQuery, ItemTest};

/// The shapes `order` lists (item j is shape `order[j]`, primitive `base + order[j]`; without a list, shape
/// j).
#[derive(Clone, Copy)]
pub(crate) struct Shapes<'a> {
    /// Every transformed shape of the scene.
    pub(crate) shapes: &'a [Shape<f32>],
    /// The shapes the items are, in the tree's leaf order; `None`: all of them, in order.
    pub(crate) order: Option<&'a [u32]>,
    /// The id of shape 0.
    pub(crate) base: u32,
}

impl ItemTest for Shapes<'_> {
    #[inline(always)]
    fn test<F: Lanes>(&self, j: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F, u32) {
        let k = self.order.map_or(j as u32, |order| order[j]);
        let (hit, t) = self.shapes[k as usize].to_lanes::<F>().intersect(ray, t_max);
        (hit, t, self.base + k)
    }
}

/// A query of rays against transformed shapes.
pub(crate) type ShapeQuery<'a, F> = ItemQuery<F, Shapes<'a>, &'a Ray<F>>;
