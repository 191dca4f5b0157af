//! The primitive kinds of the registry: each kind lives in one folder that holds everything about it (its
//! description and TOML form, its f32 store, its kernel generic over lanes, bounds, surface, departure rule
//! and its f64 form for the accuracy twin), behind the `Kind` trait. One list, `registry!`, names the
//! kinds; the scene description ([`KindDescs`]), the TOML reader, compile, the queries over the geometry
//! (`KindStores`) and the twin (`KindTwins`) are written once over it.
//!
//! Adding a kind: a folder here with a type implementing `Kind`, and its name in `registry!`. Its
//! primitive ids follow the spheres' (and the particle tree's) in the list's order.
//!
//! ```
//! use bareray::kinds::{KindDescs, COUNT, NAMES};
//! // Every registered kind has a list of descriptions, empty by default, and a name.
//! let descs = KindDescs::default();
//! assert_eq!(descs.len(), 0);
//! assert_eq!(NAMES.len(), COUNT);
//! ```

use std::fmt::Debug;
use std::ops::Range;

use glam::DVec3;
use serde::de::DeserializeOwned;

use crate::bvh::item_query::ItemTest;
use crate::bvh::Bvh;
use crate::geometry::Ray;
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

pub(crate) mod cone;
pub(crate) mod ellipsoid;
pub(crate) mod placed;
pub(crate) mod placement;
pub(crate) mod plane;
pub(crate) mod polygon;
pub(crate) mod torus;

/// The registry: every kind, as `field: type`, the field naming its TOML array of tables and its list in
/// the description. Called with the name of a macro, it calls that macro with the list; the structures
/// below and the TOML reader are generated that way, so this line is the only place a kind is registered.
macro_rules! registry {
    ($then:ident) => {
        $then! {
            polygons: $crate::kinds::polygon::Polygon,
            ellipsoids: $crate::kinds::ellipsoid::Ellipsoid,
            planes: $crate::kinds::plane::Plane,
            cones: $crate::kinds::cone::OpenCone,
            tori: $crate::kinds::torus::Torus,
        }
    };
}
pub(crate) use registry;

/// A TOML or description error of one kind's entry: the byte range of the offending value in the file and
/// the message (the reader adds the file, line and column).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct KindError {
    /// Byte range of the value in the file.
    pub(crate) span: Range<usize>,
    /// What is wrong and what was expected.
    pub(crate) message: String,
}

/// Where a primitive is measured from in the accuracy twin: the scale its f32 rounding is proportional to,
/// and how far the f32 ray may stray from the f64 one (see `accuracy::twin::Slack`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Stray {
    /// Distance between the two rays' origins.
    pub(crate) origin: f64,
    /// Distance between the two unit directions.
    pub(crate) dir: f64,
}

impl Stray {
    /// How far apart the two rays can be at distance `s` along them.
    pub(crate) fn at(&self, s: f64) -> f64 {
        self.origin + self.dir * s.abs()
    }
}

/// What a primitive kind provides. A kind's store holds items, which its tree and its leaf tests take one
/// at a time, and each item belongs to one of its primitives, which get the ids ([`Kind::item_id`]; one
/// item per primitive by default, a polygon's triangles share its id). [`Kind::len`], [`Kind::bounds`] and
/// [`Kind::test`] are per item `k`; the rest (`rehit`, `surface`, `eye_term`, the material and the f64
/// forms) per primitive `k`. Ids, trees, the loops over items and the twin's bookkeeping are the
/// registry's.
pub(crate) trait Kind: Clone + Debug + Default + Send + Sync + 'static {
    /// One item, in messages and statistics ("torus").
    const SINGULAR: &'static str;
    /// Several items ("tori"): also the TOML array's name.
    const PLURAL: &'static str;
    /// Whether a ray leaving an item can meet it again (open or non-convex surfaces): then the queries ask
    /// [`Kind::rehit`] for every ray departing from it, whichever side it heads to.
    const MEETS_AGAIN: bool;
    /// Whether the queries over the kind's items are inlined into the loop over kinds: worth it for a small
    /// kernel (a triangle's), where the call costs as much as a test. Not by default: a large kernel (a
    /// torus's solver) inlined there puts its stack frame on every query of any kind.
    const INLINE_QUERIES: bool = false;

    /// The item as described, in world space and f64, validated by its reader.
    type Desc: Clone + Debug + PartialEq + Send + Sync;
    /// The TOML table of one item.
    type Toml: DeserializeOwned;
    /// The compiled items in rendering space, rounded to f32 once (structure of arrays where it pays).
    type Store: Clone + Debug + Default + Send + Sync;
    /// One item in f64, camera-relative, for the accuracy twin.
    type Twin: Clone + Debug + Send + Sync;

    /// The description of a TOML table, given its material index.
    fn from_toml(toml: &Self::Toml, material: u32) -> Result<Self::Desc, KindError>;
    /// The material a TOML table names.
    fn toml_material(toml: &Self::Toml) -> Option<&::toml::Spanned<String>>;
    /// A world box around the item, `[lo, hi]` (framing, AO's default reach and the BVH's padding scale);
    /// `None` for an unbounded item (a plane).
    fn world_box(desc: &Self::Desc) -> Option<[DVec3; 2]>;

    /// Appends the item, moved to rendering space by `−origin` in f64 and rounded once. A description the
    /// reader would have rejected still gets an item (one no ray can see), so that ids never shift.
    fn push(store: &mut Self::Store, desc: &Self::Desc, origin: DVec3);
    /// The number of items.
    fn len(store: &Self::Store) -> usize;
    /// The number of primitives.
    fn ids(store: &Self::Store) -> usize {
        Self::len(store)
    }
    /// The primitive item `k` belongs to (below [`Kind::ids`]).
    #[inline(always)]
    fn item_id(store: &Self::Store, k: usize) -> u32 {
        let _ = store;
        k as u32
    }
    /// A box `(lo, hi)` around item `k` covering every hit the f32 kernel can report; infinite corners for
    /// an unbounded item (the kind is then tested brute force).
    fn bounds(store: &Self::Store, k: usize) -> (Vec3f, Vec3f);
    /// Item `k` against the rays in `[0, t_max)`: the lanes it is hit in and their t (`t_max` elsewhere).
    /// Lane `i` of the result must be the bits of the one-lane call with lane `i`'s ray.
    fn test<F: Lanes>(store: &Self::Store, k: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F);
    /// Lanes whose ray cannot meet item `k` before `reach`: a conservative test cheaper than
    /// [`Kind::test`], asked only where no tree culls (brute force). None by default.
    #[inline(always)]
    fn culled<F: Lanes>(store: &Self::Store, k: usize, ray: &Ray<F>, reach: F) -> F::Mask {
        let _ = (store, k, ray, reach);
        F::mask_from_bits(0)
    }
    /// For a ray that starts on item `k` (the departure primitive, which [`Kind::test`] is not asked
    /// about): where it meets the item again in `[0, t_max)`. Asked for every departing ray when
    /// [`Kind::MEETS_AGAIN`], else for rays heading into the item (a solid's exit). None by default.
    fn rehit(store: &Self::Store, k: usize, ray: &Ray<f32>, t_max: f32) -> Option<f32> {
        let _ = (store, k, ray, t_max);
        None
    }
    /// The outward unit normal at hit `t` (at `point`) of `ray` on item `k` (rendering space), and the
    /// point in the item's own frame (for solid textures).
    fn surface(store: &Self::Store, k: usize, ray: &Ray<f32>, t: f32, point: Vec3f) -> (Vec3f, Vec3f);
    /// [`Kind::surface`] for the lanes of a packet that all hit item `k`, in lane arithmetic with the
    /// same operations in the same order (every lane the bits of the scalar call); `None` where item `k`
    /// has no such form ([`Kind::has_surface_k`] false; the default), and shading then asks lane by lane.
    fn surface_k<F: Lanes>(store: &Self::Store, k: usize, ray: &Ray<F>, t: F) -> Option<(V3<F>, V3<F>)> {
        let _ = (store, k, ray, t);
        None
    }
    /// Whether [`Kind::surface_k`] gives item `k` a lane form (false by default).
    fn has_surface_k(store: &Self::Store, k: usize) -> bool {
        let _ = (store, k);
        false
    }
    /// The exact eye term of a solid item whose side a camera ray's hit takes from it (negative when the
    /// eye is inside, [`crate::geometry::eye_side`]); `None` (the default) for the rest.
    fn eye_term(store: &Self::Store, k: usize) -> Option<f32> {
        let _ = (store, k);
        None
    }
    /// Item `k`'s material index.
    fn item_material(store: &Self::Store, k: usize) -> u32;

    /// The item in f64, moved by `−origin` (the twin's camera-relative space).
    fn twin(desc: &Self::Desc, origin: DVec3) -> Self::Twin;
    /// Item `k` as stored (f32, rendering space) widened exactly to f64: an oracle over the compiled scene
    /// measures the kernel's f32 arithmetic alone, not the rounding of the description.
    #[cfg(test)]
    fn widen(store: &Self::Store, k: usize) -> Self::Twin;
    /// The closest hit in `[0, t_max)`, by a method independent of [`Kind::test`]'s where one exists (so
    /// that a miss of the f32 method shows).
    fn intersect64(item: &Self::Twin, ray: &Ray<f64>, t_max: f64) -> Option<f64>;
    /// [`Kind::rehit`] in f64.
    fn rehit64(item: &Self::Twin, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let _ = (item, ray, t_max);
        None
    }
    /// The outward unit normal at hit `t` (at `point`) of `ray` on the item.
    fn normal64(item: &Self::Twin, ray: &Ray<f64>, t: f64, point: V3<f64>) -> V3<f64>;
    /// The unit normal of the surface the hit's `t` is measured on: [`Kind::normal64`] but where shading
    /// bends it (a polygon's interpolated vertex normals).
    fn geometric_normal64(item: &Self::Twin, ray: &Ray<f64>, t: f64, point: V3<f64>) -> V3<f64> {
        Self::normal64(item, ray, t, point)
    }
    /// [`Kind::eye_term`] in f64.
    fn eye_term64(item: &Self::Twin) -> Option<f64> {
        let _ = item;
        None
    }
    /// Whether moving `ray`'s line by `tol` (a multiple of ε32) of the item's rounding scale plus `stray`
    /// can change whether (or where, across a boundary) it hits the item: where an f32 and an f64 kernel
    /// may disagree on hit or miss.
    fn grazing64(item: &Self::Twin, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool;
    /// Whether point `p` lies within `tol` (a multiple of ε32) of the item's rounding scale, plus `slack`,
    /// of its surface: where a ray starting or ending at `p` can find or miss the item by rounding.
    fn near64(item: &Self::Twin, p: V3<f64>, tol: f64, slack: f64) -> bool;
}

/// `tol` of the rounding scale for a ray from (or a point at) `origin` near an item whose f32 values, and
/// a ray's coordinates relative to it, are rounded at `scale`: `tol·(|origin| + scale)`, the nudge the
/// cone's and the torus's twin rules take.
pub(crate) fn nudge(origin: V3<f64>, scale: f64, tol: f64) -> f64 {
    tol * (origin.length() + scale)
}

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
        pub const NAMES: &[&str] = &[$(<$kind as Kind>::PLURAL),*];
        /// The number of registered kinds.
        pub const COUNT: usize = NAMES.len();

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
