//! The f64 twin's closest hit, shared by its brute-force loops (`twin/`) and its BVH (`bvh64.rs`).

use crate::geometry::NO_PRIM;

/// A closest hit in f64: its parameter (`inf` on a miss) and scene-file id ([`NO_PRIM`] on a miss).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit64 {
    /// Ray parameter (the direction's units).
    pub(crate) t: f64,
    /// Scene-file id.
    pub(crate) prim: u32,
}

impl Hit64 {
    /// No hit.
    pub(crate) const MISS: Hit64 = Hit64 { t: f64::INFINITY, prim: NO_PRIM };

    /// True when something was hit.
    pub(crate) fn is_hit(&self) -> bool {
        self.prim != NO_PRIM
    }

    /// Takes `(prim, t)` when it is closer by the renderer's total order: smaller t, or equal t and a lower id.
    #[inline]
    pub(crate) fn update(&mut self, prim: u32, t: f64) {
        if t < self.t || (t == self.t && prim < self.prim) {
            *self = Hit64 { t, prim };
        }
    }
}
