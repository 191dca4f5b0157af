//! What a primitive kind provides ([`Kind`]), its errors and the f64 twin's rounding terms.

use std::fmt::Debug;
use std::ops::Range;

use glam::DVec3;
use serde::de::DeserializeOwned;

use crate::geometry::Ray;
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

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
