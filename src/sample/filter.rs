//! Reconstruction filters: each sample's radiance reaches every pixel whose centre lies within the filter's
//! radius, weighted by the filter at the offset, and a pixel is its weighted sum over its weights' sum.

use crate::scene::desc::{Filter, FilterKind};

impl Filter {
    /// The separable weight at offset `(dx, dy)` (in pixels) from a pixel centre: `f(dx)·f(dy)`, zero from
    /// the radius on.
    pub(crate) fn weight(&self, dx: f32, dy: f32) -> f32 {
        self.weight_1d(dx) * self.weight_1d(dy)
    }

    /// The one-dimensional profile.
    fn weight_1d(&self, d: f32) -> f32 {
        let (r, x) = (self.radius, d.abs());
        if x >= r {
            return 0.0;
        }
        match self.kind {
            FilterKind::Box => 1.0,
            FilterKind::Tent => 1.0 - x / r,
            // A Gaussian of standard deviation r/3, lowered to reach 0 at the radius.
            FilterKind::Gaussian => {
                let g = |v: f32| (-4.5 * (v / r) * (v / r)).exp();
                g(x) - g(r)
            }
            // Mitchell–Netravali with B = C = 1/3 over [−2, 2], stretched to the radius.
            FilterKind::Mitchell => {
                let t = 2.0 * x / r;
                let (b, c) = (1.0 / 3.0, 1.0 / 3.0);
                if t < 1.0 {
                    ((12.0 - 9.0 * b - 6.0 * c) * t * t * t
                        + (-18.0 + 12.0 * b + 6.0 * c) * t * t
                        + (6.0 - 2.0 * b))
                        / 6.0
                } else {
                    ((-b - 6.0 * c) * t * t * t
                        + (6.0 * b + 30.0 * c) * t * t
                        + (-12.0 * b - 48.0 * c) * t
                        + (8.0 * b + 24.0 * c))
                        / 6.0
                }
            }
        }
    }

    /// Pixels beyond a tile's edge whose samples can reach its pixels: the radius less the half pixel from a
    /// sample's pixel to its edge, rounded up.
    pub(crate) fn apron(&self) -> u32 {
        (self.radius - 0.5).max(0.0).ceil() as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filter(kind: FilterKind, radius: f32) -> Filter {
        Filter { kind, radius }
    }

    #[test]
    fn profiles_peak_at_the_centre_and_vanish_at_the_radius() {
        for kind in [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian, FilterKind::Mitchell] {
            let f = filter(kind, 1.5);
            assert!(f.weight(0.0, 0.0) > 0.0, "{kind:?}");
            assert_eq!(f.weight(1.5, 0.0), 0.0, "{kind:?}");
            assert_eq!(f.weight(0.3, -1.6), 0.0, "{kind:?}");
            assert!(f.weight(0.2, 0.0) >= f.weight(0.7, 0.0), "{kind:?}");
            assert_eq!(f.weight(0.4, 0.1), f.weight(-0.4, -0.1), "{kind:?}: symmetric");
        }
        // Mitchell's lobes go negative between 1 and 2 of its [−2, 2] support.
        assert!(filter(FilterKind::Mitchell, 2.0).weight(1.5, 0.0) < 0.0);
        let m = filter(FilterKind::Mitchell, 2.0);
        assert!((m.weight_1d(0.0) - 8.0 / 9.0).abs() < 1e-6, "{}", m.weight_1d(0.0));
    }

    #[test]
    fn aprons_cover_the_radius() {
        assert_eq!(filter(FilterKind::Box, 0.5).apron(), 0);
        assert_eq!(filter(FilterKind::Tent, 1.0).apron(), 1);
        assert_eq!(filter(FilterKind::Gaussian, 1.5).apron(), 1);
        assert_eq!(filter(FilterKind::Mitchell, 2.0).apron(), 2);
    }
}
