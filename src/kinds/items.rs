//! One kind's compiled items and tree ([`KindItems`]), its items as a leaf query's ([`Items`]), and the
//! traits the registry's generated code walks the kinds by.

use crate::bvh::item_query::ItemTest;
use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::simd::Lanes;

use super::Kind;

/// One kind's compiled items, the tree over them (`None`: brute force) and, with a tree, its leaf order.
#[derive(Clone, Debug, Default)]
pub(crate) struct KindItems<K: Kind> {
    /// The items in description order (their ids).
    pub(crate) store: K::Store,
    /// The BVH over the items, if any.
    pub(crate) bvh: Option<Bvh>,
    /// With a BVH: the items' indices in its leaf order.
    pub(crate) order: Vec<u32>,
}

impl<K: Kind> KindItems<K> {
    /// The number of items.
    pub(crate) fn len(&self) -> usize {
        K::len(&self.store)
    }
    /// The number of primitives (ids).
    pub(crate) fn ids(&self) -> usize {
        K::ids(&self.store)
    }
    /// The leaf test over these items for a query: the tree's items in leaf order, or all in order.
    pub(crate) fn items(&self, base: u32) -> Items<'_, K> {
        let order = self.bvh.as_ref().map(|_| self.order.as_slice());
        Items { store: &self.store, order, base }
    }
}

/// The items of one kind as a leaf query's items ([`ItemTest`]): item `j` is `order[j]` (without a list,
/// `j`), of primitive `base + item_id(order[j])`.
pub(crate) struct Items<'a, K: Kind> {
    /// The kind's store.
    pub(crate) store: &'a K::Store,
    /// The tree's leaf order, or `None` for every item in order (brute force).
    pub(crate) order: Option<&'a [u32]>,
    /// The id of the kind's first primitive.
    pub(crate) base: u32,
}

impl<K: Kind> Items<'_, K> {
    /// The store's index of leaf item `j`.
    #[inline(always)]
    fn item(&self, j: usize) -> usize {
        self.order.map_or(j, |order| order[j] as usize)
    }
}

impl<K: Kind> Clone for Items<'_, K> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<K: Kind> Copy for Items<'_, K> {}

impl<K: Kind> ItemTest for Items<'_, K> {
    #[inline(always)]
    fn id(&self, j: usize) -> u32 {
        self.base + K::item_id(self.store, self.item(j))
    }

    #[inline(always)]
    fn test<F: Lanes>(&self, j: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        K::test(self.store, self.item(j), ray, t_max)
    }

    /// The kind's own cull, in brute force only (a tree's boxes have culled already).
    #[inline(always)]
    fn culled<F: Lanes>(&self, j: usize, ray: &Ray<F>, reach: F) -> F::Mask {
        match self.order {
            None => K::culled(self.store, j, ray, reach),
            Some(_) => F::mask_from_bits(0),
        }
    }
}

/// The number of primitives in one kind's part of the registry's structures: the ids its items carry, or
/// its f64 forms (one a primitive).
pub(crate) trait Ids {
    /// The number of primitives.
    fn ids(&self) -> usize;
}

impl<K: Kind> Ids for KindItems<K> {
    fn ids(&self) -> usize {
        KindItems::ids(self)
    }
}

impl<T> Ids for Vec<T> {
    fn ids(&self) -> usize {
        self.len()
    }
}

/// Something done to each kind's compiled items, in the registry's order (the order of their ids).
pub(crate) trait VisitItems {
    /// Kind `K`'s items (some), its first primitive numbered `first` over every kind's primitives.
    fn visit<K: Kind>(&mut self, items: &KindItems<K>, first: u32);
}
