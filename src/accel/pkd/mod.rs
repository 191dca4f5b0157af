//! The particle tree: a balanced k-d tree whose nodes are the spheres themselves (the P-k-d tree of Wald,
//! Knoll, Johnson, Usher, Pascucci and Papka, "CPU Ray Tracing Large Particle Data with Balanced P-k-d
//! Trees", 2015), for sphere fields too large for a BVH. It costs 4 bytes per sphere beside the spheres'
//! own records: a `u32` holding the scene-file index (30 bits, so at most `MAX_PARTICLES` spheres) and,
//! for a node, its split axis (the top 2 bits).
//!
//! **Layout.** Implicit and in order: the spheres of a range `lo..hi` longer than [`LEAF`] are split at
//! `mid = lo + (hi − lo)/2`; sphere `mid` is the node, split on the widest axis of its range's box, and every centre in `lo..mid`
//! is at or below its centre on that axis, every centre in `mid + 1..hi` at or above (ties ordered by file
//! index). Ranges of at most [`LEAF`] spheres are leaves. No node holds a box: a walk carries its node's box
//! down, cutting it at the split plane widened by the largest radius (`Particles::r_max`; one bound for the
//! whole field, as the paper's, so a field of very mixed radii culls less well but never wrongly).
//!
//! **Records.** The spheres' world-space values, `x, y, z, r`, as the file holds them (in a private mapping
//! of an `.f32r` file, `crate::io::f32r::map`) or in memory, in f32 or in f64 (a scene description's
//! spheres). The walk moves each visited centre into rendering space (`centre − eye` in f64, rounded once)
//! and computes its exact eye term as compile does for the BVH's spheres ([`crate::geometry::eye_term`]),
//! so the sphere kernel sees the same bits, and with `crate::geometry::HitPacket::update`'s (t, file
//! index) order the closest hits are the BVH's and brute force's, bit for bit, at every packet width.

mod build;
mod large;
mod walk;

use glam::DVec3;
use rayon::prelude::*;

use crate::geometry::eye_term;
use crate::math::{Rgb8, Vec3f, V3};

pub(crate) use build::LEAF;

/// Bits of a key holding the scene-file index; the two above hold a node's split axis.
pub(crate) const INDEX_BITS: u32 = 30;
/// The index part of a key.
pub(crate) const INDEX_MASK: u32 = (1 << INDEX_BITS) - 1;
/// The most spheres a particle tree holds (2³⁰, 1.07e9).
pub(crate) const MAX_PARTICLES: usize = 1 << INDEX_BITS;

/// A sphere's world-space record `x, y, z, r`, in f32 (files) or f64 (scene descriptions).
pub(crate) trait Record: Copy + Send + Sync {
    /// Coordinate `a` (0..3) of the centre, or the radius (3), in f64 (exactly).
    fn value(&self, a: usize) -> f64;
}

impl Record for [f32; 4] {
    #[inline(always)]
    fn value(&self, a: usize) -> f64 {
        f64::from(self[a])
    }
}

impl Record for [f64; 4] {
    #[inline(always)]
    fn value(&self, a: usize) -> f64 {
        self[a]
    }
}

/// f32 records that live elsewhere than in a `Vec`: a private mapping of an `.f32r` file
/// (`crate::io::f32r::MappedRecords`), which the tree reorders in place.
pub(crate) trait RecordStore: Send + Sync {
    /// The records `x, y, z, r`.
    fn records(&self) -> &[[f32; 4]];
    /// The records, to reorder them.
    fn records_mut(&mut self) -> &mut [[f32; 4]];
}

/// The spheres' records, wherever they are.
pub(crate) enum Records {
    /// f32 records in a store of their own (a mapped file).
    Mapped(Box<dyn RecordStore>),
    /// f32 records in memory.
    F32(Vec<[f32; 4]>),
    /// f64 records in memory (a scene description's spheres, whose values need not be f32s).
    F64(Vec<[f64; 4]>),
}

impl Records {
    /// Number of records.
    pub(crate) fn len(&self) -> usize {
        match self {
            Records::Mapped(m) => m.records().len(),
            Records::F32(v) => v.len(),
            Records::F64(v) => v.len(),
        }
    }
}

impl Default for Records {
    fn default() -> Self {
        Records::F32(Vec::new())
    }
}

/// A mapping cannot be cloned: its clone holds the records in memory.
impl Clone for Records {
    fn clone(&self) -> Self {
        match self {
            Records::Mapped(m) => Records::F32(m.records().to_vec()),
            Records::F32(v) => Records::F32(v.clone()),
            Records::F64(v) => Records::F64(v.clone()),
        }
    }
}

impl std::fmt::Debug for Records {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self {
            Records::Mapped(_) => "mapped f32",
            Records::F32(_) => "f32",
            Records::F64(_) => "f64",
        };
        write!(f, "Records({} {kind})", self.len())
    }
}

/// Runs `$body` with `$recs` bound to the records' slice, whichever form they are in: each walk is
/// monomorphised over the record type, with no per-sphere dispatch.
macro_rules! with_records {
    ($records:expr, |$recs:ident| $body:expr) => {
        match $records {
            Records::Mapped(m) => {
                let $recs = m.records();
                $body
            }
            Records::F32(v) => {
                let $recs = v.as_slice();
                $body
            }
            Records::F64(v) => {
                let $recs = v.as_slice();
                $body
            }
        }
    };
}
pub(crate) use with_records;

/// Spheres in a particle tree (see the module documentation), with what the walk and shading need.
#[derive(Clone, Debug, Default)]
pub(crate) struct Particles {
    /// The spheres in tree order.
    records: Records,
    /// Scene-file index of the sphere at each position (breaks ties in t and names it), and a node's split
    /// axis in the top bits.
    key: Vec<u32>,
    /// Material of the sphere at each position; empty when every sphere has `material0`.
    material: Vec<u32>,
    /// The material of every sphere when `material` is empty.
    material0: u32,
    /// Colour of the sphere at each position, replacing its material's; empty when the spheres have none
    /// of their own ([`crate::kinds::sphere::Spheres::color`]).
    color: Vec<Rgb8>,
    /// The rendering space's origin (the eye) in world space.
    origin: DVec3,
    /// The largest radius, as the kernel sees it (rounded to f32).
    r_max: f32,
    /// The root's box in rendering space: every centre's box widened by `r_max + 2·pad`.
    bounds: [[f32; 3]; 2],
    /// The culling padding (the BVH's, [`crate::bvh::padding`]).
    pad: f32,
    /// Some sphere has the eye within about its radius of its surface (the flag of
    /// [`crate::kinds::sphere::Spheres`]).
    eye_terms_help: bool,
    /// Camera packets cull by their pyramids and tiles walk as large packets
    /// ([`crate::bvh::Bvh::frustum_culling`]'s setting for the tree).
    pub(crate) frustum_culling: bool,
}

impl Particles {
    /// Spheres given in f64 (world space: `x, y, z, r`), their materials and their colours (empty, or one
    /// per sphere) in a particle tree, in rendering space about `origin` (the eye), culling with padding
    /// `pad`.
    pub(crate) fn from_f64(
        records: Vec<[f64; 4]>,
        material: Vec<u32>,
        color: Vec<Rgb8>,
        origin: DVec3,
        pad: f32,
    ) -> Particles {
        let material0 = material.first().copied().unwrap_or(0);
        let varied = material.iter().any(|&m| m != material0);
        let material = if varied { material } else { Vec::new() };
        Self::build(Records::F64(records), material, color, material0, origin, pad)
    }

    /// The records of a store (a mapped `.f32r` file) in a particle tree, built in the store's own memory,
    /// every sphere with material 0.
    pub(crate) fn from_store(records: Box<dyn RecordStore>, origin: DVec3, pad: f32) -> Particles {
        Self::build(Records::Mapped(records), Vec::new(), Vec::new(), 0, origin, pad)
    }

    /// Builds the tree over `records` (reordering them, their keys, `material` and `color` alike), then
    /// finds the bounds and flags the walk needs.
    fn build(
        mut records: Records,
        mut material: Vec<u32>,
        mut color: Vec<Rgb8>,
        material0: u32,
        origin: DVec3,
        pad: f32,
    ) -> Self {
        let n = records.len();
        assert!(n <= MAX_PARTICLES, "{n} spheres: a particle tree holds at most {MAX_PARTICLES}");
        assert!(color.is_empty() || color.len() == n, "{} colours for {n} spheres", color.len());
        let mut key: Vec<u32> = (0..n as u32).into_par_iter().with_min_len(1 << 16).collect();
        match &mut records {
            Records::Mapped(m) => build::build(m.records_mut(), &mut key, &mut material, &mut color),
            Records::F32(v) => build::build(v, &mut key, &mut material, &mut color),
            Records::F64(v) => build::build(v, &mut key, &mut material, &mut color),
        }
        let mut p = Particles {
            records,
            key,
            material,
            material0,
            color,
            origin,
            r_max: 0.0,
            bounds: [[0.0; 3]; 2],
            pad,
            eye_terms_help: false,
            frustum_culling: true,
        };
        p.measure();
        p
    }

    /// Sets `r_max`, `bounds` and `eye_terms_help` from the records.
    fn measure(&mut self) {
        type Acc = ([f32; 3], [f32; 3], f32, bool);
        let empty = || -> Acc { ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3], 0.0, false) };
        let merge = |a: Acc, b: Acc| -> Acc {
            let m = |f: fn(f32, f32) -> f32, x: [f32; 3], y: [f32; 3]| [0, 1, 2].map(|k| f(x[k], y[k]));
            (m(f32::min, a.0, b.0), m(f32::max, a.1, b.1), a.2.max(b.2), a.3 | b.3)
        };
        let origin = self.origin;
        let (lo, hi, r_max, help) = with_records!(&self.records, |recs| recs
            .par_iter()
            .with_min_len(1 << 16)
            .fold(empty, |acc, rec| {
                let (c, r) = place(rec, origin);
                let c_eye = eye_term_of(rec, origin);
                let r64 = rec.value(3);
                merge(acc, ([c.x, c.y, c.z], [c.x, c.y, c.z], r, c_eye.abs() < 4.0 * r64 * r64))
            })
            .reduce(empty, merge));
        let widen = r_max + 2.0 * self.pad;
        self.r_max = r_max;
        self.bounds = [lo.map(|v| v - widen), hi.map(|v| v + widen)];
        self.eye_terms_help = help;
    }

    /// Number of spheres.
    pub(crate) fn len(&self) -> usize {
        self.key.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.key.is_empty()
    }

    /// Whether the records are a mapped file's.
    pub(crate) fn is_mapped(&self) -> bool {
        matches!(self.records, Records::Mapped(_))
    }

    /// Bytes beside the records: keys, materials and colours (the tree's whole cost, and the colours').
    pub(crate) fn overhead_bytes(&self) -> usize {
        (self.key.len() + self.material.len()) * size_of::<u32>() + self.color.len() * size_of::<Rgb8>()
    }

    /// Bytes of the records.
    pub(crate) fn record_bytes(&self) -> usize {
        match &self.records {
            Records::F64(v) => v.len() * size_of::<[f64; 4]>(),
            r => r.len() * size_of::<[f32; 4]>(),
        }
    }

    /// Centre (rendering space) and radius of the sphere at position `i`, as the kernel sees them.
    pub(crate) fn sphere(&self, i: usize) -> (Vec3f, f32) {
        with_records!(&self.records, |recs| place(&recs[i], self.origin))
    }

    /// The exact eye term of the sphere at position `i`, rounded to f32 ([`crate::geometry::eye_term`]).
    pub(crate) fn c_eye(&self, i: usize) -> f32 {
        with_records!(&self.records, |recs| eye_term_of(&recs[i], self.origin)) as f32
    }

    /// Material of the sphere at position `i`.
    pub(crate) fn material(&self, i: usize) -> u32 {
        self.material.get(i).copied().unwrap_or(self.material0)
    }

    /// The colour of the sphere at position `i`, when the spheres have colours of their own.
    #[inline]
    pub(crate) fn color(&self, i: usize) -> Option<Rgb8> {
        self.color.get(i).copied()
    }

    /// How many spheres have a colour of their own (0 or all).
    pub(crate) fn colors(&self) -> usize {
        self.color.len()
    }

    /// Scene-file index of the sphere at position `i`.
    #[inline(always)]
    pub(crate) fn key(&self, i: usize) -> u32 {
        self.key[i] & INDEX_MASK
    }

    /// The largest coordinate magnitude of the root's box: bounds the frustum tests' rounding (the BVH's
    /// [`crate::bvh::Bvh::extent`]).
    pub(crate) fn extent(&self) -> f32 {
        self.bounds[0].iter().chain(&self.bounds[1]).fold(0.0f32, |m, v| m.max(v.abs()))
    }

    /// How far a range's box reaches past its parent's split plane: the largest radius and twice the padding.
    pub(crate) fn split_reach(&self) -> f32 {
        self.r_max + 2.0 * self.pad
    }

    /// Split axis of the node at position `i`.
    #[inline(always)]
    pub(crate) fn axis(&self, i: usize) -> usize {
        (self.key[i] >> INDEX_BITS) as usize
    }
}

/// A record's centre in rendering space (`centre − origin` in f64, rounded once) and its radius in f32:
/// the values compile gives a BVH's sphere ([`crate::kinds::sphere::Spheres::push_exact`]).
#[inline(always)]
pub(crate) fn place<R: Record>(rec: &R, origin: DVec3) -> (Vec3f, f32) {
    let c = V3::new(rec.value(0) - origin.x, rec.value(1) - origin.y, rec.value(2) - origin.z);
    (c.to_f32(), rec.value(3) as f32)
}

/// A record's exact eye term in f64, as compile computes it.
#[inline(always)]
pub(crate) fn eye_term_of<R: Record>(rec: &R, origin: DVec3) -> f64 {
    let c = V3::new(rec.value(0) - origin.x, rec.value(1) - origin.y, rec.value(2) - origin.z);
    eye_term(c, rec.value(3))
}
