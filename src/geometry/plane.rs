//! The generic plane z = 0.
//!
//! `o_z + t·d_z = 0` gives `t = −o_z / d_z`. A ray parallel to the plane gives ±inf or NaN, which the range
//! test `0 ≤ t < t_max` rejects without a branch.

use crate::math::Real;

use super::Ray;

/// Hit of a ray with the plane z = 0 in `[0, t_max)`.
#[inline(always)]
pub(crate) fn intersect_plane<F: Real>(ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    let t = -ray.origin.z / ray.dir.z;
    (t.ge(F::splat(0.0)) & t.lt(t_max), t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::V3;

    #[test]
    fn lecture_example_hits_at_t_1() {
        // The lecture's worked example: (4,1,3) + (−3,−5,−3)t meets z = 0 at t = 1, at the point (1,−4,0).
        let ray = Ray::new(V3::new(4.0f64, 1.0, 3.0), V3::new(-3.0, -5.0, -3.0));
        let (hit, t) = intersect_plane(&ray, f64::INFINITY);
        assert!(hit);
        assert_eq!(t, 1.0);
        assert_eq!(ray.at(t), V3::new(1.0, -4.0, 0.0));
    }

    #[test]
    fn parallel_and_receding_rays_miss() {
        let parallel = Ray::new(V3::new(0.0f32, 0.0, 1.0), V3::new(1.0, 0.0, 0.0));
        assert!(!intersect_plane(&parallel, f32::INFINITY).0);
        let in_plane = Ray::new(V3::new(0.0f32, 0.0, 0.0), V3::new(1.0, 0.0, 0.0));
        assert!(!intersect_plane(&in_plane, f32::INFINITY).0);
        let receding = Ray::new(V3::new(0.0f32, 0.0, 1.0), V3::new(0.0, 0.0, 1.0));
        assert!(!intersect_plane(&receding, f32::INFINITY).0);
    }
}
