//! What the registry generates over its list of kinds (`registry!`): every kind's descriptions
//! ([`KindDescs`]), compiled items ([`KindStores`]) and f64 forms ([`KindTwins`]), with the loops over them.

use glam::DVec3;

use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

use super::{registry, Ids, Kind, KindItems, Stray, VisitItems};

/// Evaluates `$body` with the kind that holds primitive `$id` (numbered over every kind's primitives in id
/// order), its part and the primitive's index within the kind; `$none` when no kind holds it.
macro_rules! dispatch {
    ($self:ident, $id:expr, $none:expr, |$items:ident, $K:ident, $k:ident| $body:expr; $($field:ident: $kind:ty),*) => {{
        #[allow(unused_mut, unused_assignments)]
        let mut $k: usize = $id;
        $(
            #[allow(unused_assignments)]
            {
                type $K = $kind;
                let $items = &$self.$field;
                if $k < Ids::ids($items) {
                    return $body;
                }
                $k -= Ids::ids($items);
            }
        )*
        $none
    }};
}

macro_rules! per_kind {
    ($($field:ident: $kind:ty),* $(,)?) => {
        /// The registered kinds' TOML names, in id order.
        pub(crate) const NAMES: &[&str] = &[$(<$kind as Kind>::PLURAL),*];
        /// The number of registered kinds.
        pub(crate) const COUNT: usize = NAMES.len();

        /// Every registered kind's descriptions, in file order (ids in the registry's order).
        #[derive(Clone, Debug, Default, PartialEq)]
        pub struct KindDescs {
            $(
                #[doc = concat!("The `", stringify!($field), "` of the scene.")]
                pub(crate) $field: Vec<<$kind as Kind>::Desc>,
            )*
        }

        /// Every registered kind's compiled items and trees.
        #[derive(Clone, Debug, Default)]
        pub(crate) struct KindStores {
            $(
                #[doc = concat!("The compiled `", stringify!($field), "`.")]
                pub(crate) $field: KindItems<$kind>,
            )*
            /// Bit i: kind i (in the registry's order) has items. The queries visit those alone: most
            /// scenes have one kind or none beside the spheres.
            present: u32,
            /// Kind i's first primitive, numbered over every kind's primitives.
            first: [u32; COUNT],
        }

        /// Every registered kind's items in f64, for the accuracy twin.
        #[derive(Clone, Debug, Default)]
        pub(crate) struct KindTwins {
            $(
                #[doc = concat!("The `", stringify!($field), "` in f64.")]
                pub(crate) $field: Vec<<$kind as Kind>::Twin>,
            )*
        }

        // With no kind registered, the per-kind parts expand to nothing and leave arguments unused.
        #[allow(unused_variables, unused_mut)]
        impl KindDescs {
            /// The number of items of every kind.
            pub fn len(&self) -> usize {
                0 $(+ self.$field.len())*
            }
            /// True when there are none.
            pub fn is_empty(&self) -> bool {
                self.len() == 0
            }
            /// The items compiled: each description moved by `−origin` and rounded ([`Kind::push`]).
            pub(crate) fn compile(&self, origin: DVec3) -> KindStores {
                #[allow(unused_mut)]
                let mut stores = KindStores::default();
                let (mut kind, mut first) = (0, 0);
                $(
                    for d in &self.$field {
                        <$kind as Kind>::push(&mut stores.$field.store, d, origin);
                    }
                    stores.first[kind] = first as u32;
                    first += stores.$field.ids();
                    stores.present |= u32::from(stores.$field.len() > 0) << kind;
                    kind += 1;
                )*
                let _ = (origin, kind, first);
                stores
            }
            /// The items in f64, moved by `−origin`.
            pub(crate) fn twins(&self, origin: DVec3) -> KindTwins {
                let _ = origin;
                KindTwins {
                    $($field: self.$field.iter().map(|d| <$kind as Kind>::twin(d, origin)).collect(),)*
                }
            }
            /// Every bounded item's world box.
            pub(crate) fn world_boxes(&self) -> Vec<[DVec3; 2]> {
                #[allow(unused_mut)]
                let mut boxes = Vec::new();
                $(boxes.extend(self.$field.iter().filter_map(<$kind as Kind>::world_box));)*
                boxes
            }
            /// Whether some item is unbounded (a plane).
            pub(crate) fn has_unbounded(&self) -> bool {
                false $(|| self.$field.iter().any(|d| <$kind as Kind>::world_box(d).is_none()))*
            }
        }

        // With no kind registered, the per-kind parts expand to nothing and leave arguments unused.
        #[allow(unused_variables, unused_mut)]
        impl KindStores {
            /// Every primitive as stored, widened exactly to f64 ([`Kind::widen`]), in id order.
            #[cfg(test)]
            pub(crate) fn widened(&self) -> KindTwins {
                KindTwins {
                    $($field: (0..<$kind as Kind>::ids(&self.$field.store))
                        .map(|k| <$kind as Kind>::widen(&self.$field.store, k))
                        .collect(),)*
                }
            }
            /// Calls `v` with each kind's items in id order, for the kinds that have some.
            #[inline(always)]
            pub(crate) fn visit(&self, v: &mut impl VisitItems) {
                let mut kind = 0;
                $(
                    if self.present & (1 << kind) != 0 {
                        v.visit::<$kind>(&self.$field, self.first[kind]);
                    }
                    kind += 1;
                )*
                let _ = (v, kind);
            }
            /// The number of primitives of every kind.
            pub(crate) fn len(&self) -> usize {
                0 $(+ self.$field.ids())*
            }
            /// Whether some kind has items for the queries to test.
            #[inline(always)]
            pub(crate) fn has_items(&self) -> bool {
                self.present != 0
            }
            /// Each kind's number of primitives, in id order.
            pub(crate) fn counts(&self) -> [usize; COUNT] {
                [$(self.$field.ids()),*]
            }
            /// The number of primitives of each kind that has some, in words ("1 torus", "2 tori"), in id
            /// order.
            pub(crate) fn counted(&self) -> Vec<String> {
                let word = |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
                let all: [(usize, &str, &str); COUNT] =
                    [$((self.$field.ids(), <$kind as Kind>::SINGULAR, <$kind as Kind>::PLURAL)),*];
                all.iter().filter(|(n, _, _)| *n > 0).map(|&(n, one, many)| word(n, one, many)).collect()
            }
            /// Whether each kind has a tree, in id order.
            pub(crate) fn trees(&self) -> [bool; COUNT] {
                [$(self.$field.bvh.is_some()),*]
            }
            /// The kinds' trees.
            pub(crate) fn bvhs(&self) -> impl Iterator<Item = &Bvh> {
                [$(self.$field.bvh.as_ref()),*].into_iter().flatten()
            }
            /// The kinds' trees, to change their walk settings.
            pub(crate) fn bvhs_mut(&mut self) -> impl Iterator<Item = &mut Bvh> {
                [$(self.$field.bvh.as_mut()),*].into_iter().flatten()
            }
            /// Builds a tree for each kind that `wants` one (given its number of items), where every
            /// item's box is finite: `build(n, box of item k)` returns the tree and its leaf order.
            pub(crate) fn build_trees(
                &mut self,
                wants: impl Fn(usize) -> bool,
                mut build: impl FnMut(usize, &(dyn Fn(usize) -> (Vec3f, Vec3f) + Sync)) -> (Bvh, Vec<u32>),
            ) {
                $(
                    let items = &mut self.$field;
                    let n = items.len();
                    let store = &items.store;
                    let bounds = |k: usize| <$kind as Kind>::bounds(store, k);
                    let finite = (0..n).all(|k| {
                        let (lo, hi) = bounds(k);
                        [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z].iter().all(|v| v.is_finite())
                    });
                    if finite && wants(n) {
                        let (tree, order) = build(n, &bounds);
                        (items.bvh, items.order) = (Some(tree), order);
                    }
                )*
                let _ = (wants, &mut build);
            }
            /// Whether some kind that a departing ray can meet again ([`Kind::MEETS_AGAIN`]) has items: else
            /// no departing ray needs asking.
            pub(crate) fn any_meets_again(&self) -> bool {
                false $(|| (<$kind as Kind>::MEETS_AGAIN && self.$field.len() > 0))*
            }
            /// Whether a ray leaving primitive `id` (numbered over every kind's primitives in id order) can
            /// meet it again ([`Kind::MEETS_AGAIN`]).
            pub(crate) fn meets_again(&self, id: usize) -> bool {
                dispatch!(self, id, false, |_items, K, _k| K::MEETS_AGAIN; $($field: $kind),*)
            }
            /// [`Kind::rehit`] of item `id`: where a ray leaving it meets it again (a solid's exit, for a
            /// ray heading in).
            pub(crate) fn rehit(&self, id: usize, ray: &Ray<f32>, t_max: f32) -> Option<f32> {
                dispatch!(self, id, None, |items, K, k| K::rehit(&items.store, k, ray, t_max); $($field: $kind),*)
            }
            /// Item `id`'s outward unit normal at hit `t` (at `point`) of `ray`, the point in its frame,
            /// and its material.
            pub(crate) fn surface(
                &self,
                id: usize,
                ray: &Ray<f32>,
                t: f32,
                point: Vec3f,
            ) -> Option<(Vec3f, Vec3f, u32)> {
                dispatch!(self, id, None, |items, K, k| {
                    let (normal, object) = K::surface(&items.store, k, ray, t, point);
                    Some((normal, object, K::item_material(&items.store, k)))
                }; $($field: $kind),*)
            }
            /// The material of item `id`, when [`Kind::surface_k`] gives it a lane form.
            pub(crate) fn material_in_lanes(&self, id: usize) -> Option<u32> {
                dispatch!(self, id, None, |items, K, k| {
                    K::has_surface_k(&items.store, k).then(|| K::item_material(&items.store, k))
                }; $($field: $kind),*)
            }
            /// [`Kind::surface_k`] of item `id`, with its material (inlined: its result is returned in
            /// registers, not through memory).
            #[inline(always)]
            pub(crate) fn surface_k<F: Lanes>(
                &self,
                id: usize,
                ray: &Ray<F>,
                t: F,
            ) -> Option<(V3<F>, V3<F>, u32)> {
                dispatch!(self, id, None, |items, K, k| {
                    let material = K::item_material(&items.store, k);
                    K::surface_k(&items.store, k, ray, t).map(|(n, o)| (n, o, material))
                }; $($field: $kind),*)
            }
            /// [`Kind::eye_term`] of item `id`.
            pub(crate) fn eye_term(&self, id: usize) -> Option<f32> {
                dispatch!(self, id, None, |items, K, k| K::eye_term(&items.store, k); $($field: $kind),*)
            }
        }

        // With no kind registered, the per-kind parts expand to nothing and leave arguments unused.
        #[allow(unused_variables, unused_mut)]
        impl KindTwins {
            /// The number of items of every kind.
            pub(crate) fn len(&self) -> usize {
                0 $(+ self.$field.len())*
            }
            /// The closest hit in `[0, t_max)` over every item but `skip` (ids from `base`), as `(id, t)`
            /// merged into `best` where nearer (ties to the lower id).
            pub(crate) fn intersect(&self, base: u32, skip: u32, ray: &Ray<f64>, t_max: f64, best: &mut (u32, f64)) {
                #[allow(unused_mut)]
                let mut id = base;
                $(
                    for item in &self.$field {
                        if id != skip {
                            if let Some(t) = <$kind as Kind>::intersect64(item, ray, t_max) {
                                if t < best.1 || (t == best.1 && id < best.0) {
                                    *best = (id, t);
                                }
                            }
                        }
                        id += 1;
                    }
                )*
                let _ = (skip, ray, t_max, best, id);
            }
            /// Whether a ray leaving item `id` can meet it again.
            pub(crate) fn meets_again(&self, id: usize) -> bool {
                dispatch!(self, id, false, |_items, K, _k| K::MEETS_AGAIN; $($field: $kind),*)
            }
            /// [`Kind::rehit64`] of item `id`.
            pub(crate) fn rehit(&self, id: usize, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
                dispatch!(self, id, None, |items, K, k| K::rehit64(&items[k], ray, t_max); $($field: $kind),*)
            }
            /// [`Kind::eye_term64`] of item `id`.
            pub(crate) fn eye_term(&self, id: usize) -> Option<f64> {
                dispatch!(self, id, None, |items, K, k| K::eye_term64(&items[k]); $($field: $kind),*)
            }
            /// Item `id`'s hit along `ray` in `[0, inf)`.
            pub(crate) fn hit_of(&self, id: usize, ray: &Ray<f64>) -> Option<f64> {
                dispatch!(self, id, None, |items, K, k| K::intersect64(&items[k], ray, f64::INFINITY); $($field: $kind),*)
            }
            /// Item `id`'s outward unit normal at hit `t` (at `point`) of `ray`.
            pub(crate) fn normal(&self, id: usize, ray: &Ray<f64>, t: f64, point: V3<f64>) -> Option<V3<f64>> {
                dispatch!(self, id, None, |items, K, k| Some(K::normal64(&items[k], ray, t, point)); $($field: $kind),*)
            }
            /// [`Kind::geometric_normal64`] of item `id`.
            pub(crate) fn geometric_normal(&self, id: usize, ray: &Ray<f64>, t: f64, point: V3<f64>) -> Option<V3<f64>> {
                dispatch!(self, id, None, |items, K, k| Some(K::geometric_normal64(&items[k], ray, t, point)); $($field: $kind),*)
            }
            /// [`Kind::grazing64`] of item `id`.
            pub(crate) fn grazing(&self, id: usize, ray: &Ray<f64>, tol: f64, stray: Stray) -> Option<bool> {
                dispatch!(self, id, None, |items, K, k| Some(K::grazing64(&items[k], ray, tol, stray)); $($field: $kind),*)
            }
            /// [`Kind::near64`] of item `id` and point `p`.
            pub(crate) fn near(&self, id: usize, p: V3<f64>, tol: f64, slack: f64) -> Option<bool> {
                dispatch!(self, id, None, |items, K, k| Some(K::near64(&items[k], p, tol, slack)); $($field: $kind),*)
            }
        }
    };
}
registry!(per_kind);
