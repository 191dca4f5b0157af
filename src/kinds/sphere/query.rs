//! Spheres as the items of BVH leaves ([`LeafQuery`]) and of brute force: the sphere kernel over a range of
//! spheres, generic over the lane type (lanes = rays; the K = 1 instance tests one sphere at a time, the
//! scalar walk's leaf test), and the single-ray leaf test with the spheres across the lanes. Hits are
//! combined by [`HitPacket::update`]'s (t, id) order, so the result does not depend on the order of the
//! loops.

use crate::bvh::{LeafQuery, SingleLeafQuery};
use crate::geometry::{first_root, sphere_approach, EyeLanes, HitPacket, Pyramid, Ray, SphereRay};
use crate::math::{Mask, Vec3f};
use crate::simd::{set_bits, IdLanes, Lanes};

use super::Spheres;

/// A sphere query as every kernel and traversal takes it: the spheres, the rays, each ray's exclusive end
/// `t_max`, and the sphere each ray leaves (`skip`, never reported).
#[derive(Clone, Copy)]
pub(crate) struct SphereQuery<'a, F: Lanes> {
    /// The spheres.
    pub(crate) spheres: &'a Spheres,
    /// Exclusive end of each ray's range.
    pub(crate) t_max: F,
    /// The departure sphere of each ray.
    pub(crate) skip: F::Ids,
    /// Planes enclosing the live rays, from the packet's maker ([`crate::geometry::RayPacket::pyramid`]).
    pub(crate) pyramid: Option<Pyramid>,
    /// The rays and their per-ray terms, shared by every sphere test.
    terms: SphereRay<F>,
    /// The lanes that start at the eye.
    eye: EyeLanes<F::Mask>,
}

impl<'a, F: Lanes> SphereQuery<'a, F> {
    /// A query of `ray` (the lanes of `live`) over `spheres` in `[0, t_max)`, never reporting `skip`.
    #[inline(always)]
    pub(crate) fn new(
        spheres: &'a Spheres,
        ray: Ray<F>,
        t_max: F,
        skip: F::Ids,
        pyramid: Option<Pyramid>,
        live: F::Mask,
    ) -> Self {
        let terms = SphereRay::new(ray);
        let eye = EyeLanes::of(terms.from_eye(), live);
        Self { spheres, t_max, skip, pyramid, terms, eye }
    }

    /// The roots of sphere `i` (splatted) for these rays ([`crate::geometry::sphere_roots_of`]).
    #[inline(always)]
    fn roots_of(&self, line: &crate::geometry::Approach<F>, i: usize) -> crate::geometry::Roots<F> {
        let s = self.spheres;
        crate::geometry::sphere_roots_of(
            s.eye_terms_help,
            line,
            || F::splat_v3(s.center(i)),
            F::splat_f32(s.c_eye[i]),
            &self.terms,
            self.eye,
        )
    }

    /// Sphere `i`'s hits for the lanes of `live`: the lanes it is hit in (the departure sphere excluded) and
    /// their t, or `None` when no live lane's line meets it — most spheres of a leaf, which skip the roots'
    /// division and square root.
    #[inline(always)]
    fn sphere(&self, i: usize, live: F::Mask) -> Option<(F::Mask, F)> {
        let s = self.spheres;
        let line = sphere_approach(F::splat_v3(s.center(i)), F::splat_f32(s.r[i]), &self.terms);
        if !(line.meets() & live).any() {
            return None;
        }
        let (hit, t) = first_root(&self.roots_of(&line, i), self.t_max);
        Some((live & hit & !F::ids_eq(F::Ids::splat(i as u32), self.skip), t))
    }
}

impl<'a, F: Lanes> LeafQuery<F> for SphereQuery<'a, F> {
    type One = SphereQuery<'a, f32>;

    #[inline(always)]
    fn ray(&self) -> &Ray<F> {
        &self.terms.ray
    }
    #[inline(always)]
    fn t_max(&self) -> F {
        self.t_max
    }
    #[inline(always)]
    fn pyramid(&self) -> Option<Pyramid> {
        self.pyramid
    }
    #[inline(always)]
    fn ball(&self, i: usize) -> Option<(Vec3f, f32)> {
        Some((self.spheres.center(i), self.spheres.r[i]))
    }

    /// Lane `i` as a one-ray query (its terms taken from the packet's, not recomputed: same bits).
    #[inline(always)]
    fn lane(&self, i: usize) -> SphereQuery<'a, f32> {
        let terms = self.terms.map(|v| v.lane(i));
        let eye = match self.eye {
            EyeLanes::All => EyeLanes::All,
            EyeLanes::None => EyeLanes::None,
            EyeLanes::Some(m) if F::mask_lane(m, i) => EyeLanes::All,
            EyeLanes::Some(_) => EyeLanes::None,
        };
        SphereQuery {
            spheres: self.spheres,
            t_max: self.t_max.lane(i),
            skip: self.skip.lane(i),
            pyramid: None,
            terms,
            eye,
        }
    }

    #[inline(always)]
    fn departure(&self, i: usize) -> Option<usize> {
        Some(self.skip.lane(i) as usize).filter(|&s| s < self.spheres.len())
    }

    /// The first and last entry of each array the sphere test reads.
    #[inline(always)]
    fn prefetch(&self, first: usize, count: usize) {
        let s = self.spheres;
        let last = first + count.max(1) - 1;
        for v in [&s.cx, &s.cy, &s.cz, &s.r, &s.c_eye] {
            crate::simd::prefetch(v, first);
            crate::simd::prefetch(v, last);
        }
    }

    /// Closest hits of `spheres` (indices) for the lanes of `live`, merged into `best`.
    #[inline(always)]
    fn intersect(&self, spheres: impl Iterator<Item = usize>, live: F::Mask, best: &mut HitPacket<F>) {
        for i in spheres {
            if let Some((hit, t)) = self.sphere(i, live) {
                best.update(hit, t, F::Ids::splat(i as u32), F::Ids::splat(self.spheres.key[i]));
            }
        }
    }

    /// Lanes of `live` blocked by a sphere in `range`; `blocker` is set to a sphere that blocked some lane,
    /// if any did. Stops as soon as every live lane is blocked.
    #[inline(always)]
    fn occluded(&self, range: std::ops::Range<usize>, live: F::Mask, blocker: &mut u32) -> F::Mask {
        let mut blocked = F::mask_from_bits(0);
        for i in range {
            let Some((hit, _)) = self.sphere(i, live) else { continue };
            if hit.any() {
                *blocker = i as u32;
                blocked = blocked | hit;
                if (blocked | !live).all() {
                    break;
                }
            }
        }
        blocked
    }
}

impl SingleLeafQuery for SphereQuery<'_, f32> {
    /// [`SphereQuery::intersect`] over the leaf `first..first + count`, `LeafLanes` spheres at a time:
    /// the same hits, merged by the same (t, id) order.
    #[inline(always)]
    fn intersect_leaf(&self, first: usize, count: usize, best: &mut HitPacket<f32>) {
        let end = first + count;
        for at in (first..end).step_by(LeafLanes::K) {
            let Some((bits, t)) = self.leaf_chunk::<LeafLanes>(at, end - at) else { continue };
            for j in set_bits(bits) {
                let i = at + j;
                best.update(true, t.lane(j), i as u32, self.spheres.key[i]);
            }
        }
    }

    /// [`SphereQuery::occluded`] over the leaf `first..first + count` for the one ray, `LeafLanes`
    /// spheres at a time; `blocker` is set to the lowest-index blocking sphere, as the scalar loop finds it.
    #[inline(always)]
    fn occluded_leaf(&self, first: usize, count: usize, blocker: &mut u32) -> bool {
        let end = first + count;
        for at in (first..end).step_by(LeafLanes::K) {
            match self.leaf_chunk::<LeafLanes>(at, end - at) {
                Some((bits, _)) if bits != 0 => {
                    *blocker = (at + bits.trailing_zeros() as usize) as u32;
                    return true;
                }
                _ => {}
            }
        }
        false
    }
}

impl SphereQuery<'_, f32> {
    /// Whether one of the spheres `ids` whose bound in `near` (non-decreasing, one per id) is at most `reach`
    /// blocks the one ray, `LeafLanes` spheres at a time, gathered: each lane computes
    /// [`SphereQuery::sphere`]'s bits. Each chunk's bounds are compared in lanes, so finding where the
    /// prefix ends adds no chain of dependent loads. `blocker` is set to the first blocking sphere in `ids`'
    /// order.
    #[inline(always)]
    pub(crate) fn occluded_listed(&self, ids: &[u32], near: &[f32], reach: f32, blocker: &mut u32) -> bool {
        debug_assert_eq!(ids.len(), near.len());
        let reach = LeafLanes::splat_f32(reach);
        for (k, chunk) in ids.chunks(LeafLanes::K).enumerate() {
            let bounds = LeafLanes::load_partial(near, k * LeafLanes::K, f32::INFINITY);
            let within = (LeafLanes::move_mask(crate::math::Real::le(bounds, reach)).trailing_ones()
                as usize)
                .min(chunk.len());
            if within == 0 {
                return false;
            }
            if let Some((bits, _)) = self.gathered_chunk::<LeafLanes>(&chunk[..within]) {
                if bits != 0 {
                    *blocker = chunk[bits.trailing_zeros() as usize];
                    return true;
                }
            }
            if within < chunk.len() {
                return false;
            }
        }
        false
    }

    /// [`SphereQuery::leaf_chunk`] over the spheres `ids` (at most `L::K` of them) instead of a range.
    #[inline(always)]
    fn gathered_chunk<L: Lanes>(&self, ids: &[u32]) -> Option<(u32, L)> {
        // Lanes past `ids` read a zero sphere at the origin; `valid` drops them.
        let load = |v: &[f32]| L::from_fn(|j| ids.get(j).map_or(0.0, |&i| v[i as usize]));
        let lane_ids = L::Ids::from_fn(|j| ids.get(j).copied().unwrap_or(crate::geometry::NO_PRIM));
        self.chunk(load, lane_ids, L::lanes_below(ids.len()))
    }
}

/// The lane type of a single ray's leaf test, one sphere per lane: leaves hold at most 8 spheres (the SAH
/// builder's `MAX_LEAF`, obvhs's `max_prims_per_leaf` in every preset bareray uses), so one pass covers a
/// leaf.
pub(crate) type LeafLanes = wide::f32x8;

impl SphereQuery<'_, f32> {
    /// Spheres `at..at + min(count, L::K)` against the one ray (lanes = spheres, the transpose of
    /// [`SphereQuery::sphere`]; each lane computes that kernel's bits): bit j set where sphere `at + j` is
    /// hit within `t_max` (the departure sphere excluded), with each lane's t. `None` when the ray's line
    /// meets none of them, which skips the roots' division and square root for the whole chunk.
    #[inline(always)]
    fn leaf_chunk<L: Lanes>(&self, at: usize, count: usize) -> Option<(u32, L)> {
        // Lanes past the array's end read a zero sphere at the origin; `valid` drops them.
        let load = |v: &[f32]| L::load_partial(v, at, 0.0);
        self.chunk(load, L::Ids::splat(at as u32) + L::lane_ids(), L::lanes_below(count))
    }

    /// The chunk kernel of [`SphereQuery::leaf_chunk`] and [`SphereQuery::gathered_chunk`]: the spheres
    /// `load` reads from each array (one a lane), their ids `ids`, the lanes of `valid` taken.
    #[inline(always)]
    fn chunk<L: Lanes>(&self, load: impl Fn(&[f32]) -> L, ids: L::Ids, valid: L::Mask) -> Option<(u32, L)> {
        let s = self.spheres;
        let ray = self.terms.map(L::splat_f32);
        let centre = crate::math::V3::new(load(&s.cx), load(&s.cy), load(&s.cz));
        let line = sphere_approach(centre, load(&s.r), &ray);
        if !(line.meets() & valid).any() {
            return None;
        }
        let eye = match self.eye {
            EyeLanes::None => EyeLanes::None,
            _ => EyeLanes::All,
        };
        // The eye term is read only where the roots use it.
        let c_eye = match s.eye_terms_help || !matches!(eye, EyeLanes::None) {
            true => load(&s.c_eye),
            false => L::splat_f32(0.0),
        };
        let roots = crate::geometry::sphere_roots_of(s.eye_terms_help, &line, || centre, c_eye, &ray, eye);
        let (hit, t) = first_root(&roots, L::splat_f32(self.t_max));
        let hit = hit & valid & !L::ids_eq(ids, L::Ids::splat(self.skip));
        Some((L::move_mask(hit), t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;
    use crate::math::V3;

    /// The leaf kernel (lanes = spheres) gives the scalar loop's closest hit and blocker, bit for bit: over
    /// leaves of every size from 1 to past one chunk, at the array's end (partial loads), with rays from
    /// outside, from sphere surfaces that skip their own sphere, and with short `t_max`.
    #[test]
    fn leaf_lanes_give_the_scalar_loop() {
        let mut rng = SplitMix64::new(5);
        let mut unit = move || rng.unit() as f32 * 2.0 - 1.0;
        let mut spheres = Spheres::default();
        for _ in 0..40 {
            spheres.push(V3::new(unit(), unit(), unit()) * 0.6, 0.05 + 0.3 * unit().abs(), 0);
        }
        let n = spheres.len();
        let (mut hits, mut blocked) = (0, 0);
        for k in 0..4000 {
            let count = 1 + k % 12;
            let first = if k % 5 == 0 { n - count } else { k * 7 % (n - count + 1) };
            let skip = if k % 3 == 0 { (first + k % count) as u32 } else { crate::geometry::NO_PRIM };
            let origin = match skip as usize {
                s if s < n => spheres.center(s) + V3::new(unit(), unit(), unit()).normalize() * spheres.r[s],
                _ => V3::new(unit(), unit(), -2.0),
            };
            // Aimed near a sphere of the leaf, so most rays meet some of them.
            let aim = spheres.center(first + k / 3 % count) + V3::new(unit(), unit(), unit()) * 0.2;
            let dir = aim - origin;
            let t_max = if k % 4 == 0 { 0.5 + unit().abs() } else { f32::INFINITY };
            let q = SphereQuery::new(&spheres, Ray::new(origin, dir), t_max, skip, None, true);
            let (mut lanes, mut scalar) = (HitPacket::<f32>::miss(), HitPacket::<f32>::miss());
            q.intersect_leaf(first, count, &mut lanes);
            q.intersect(first..first + count, true, &mut scalar);
            assert_eq!(
                (lanes.t.to_bits(), lanes.prim, lanes.key),
                (scalar.t.to_bits(), scalar.prim, scalar.key)
            );
            let (mut b_lanes, mut b_scalar) = (u32::MAX, u32::MAX);
            let got = q.occluded_leaf(first, count, &mut b_lanes);
            assert_eq!(got, q.occluded(first..first + count, true, &mut b_scalar), "leaf {k}");
            assert_eq!(b_lanes, b_scalar, "leaf {k}");
            hits += usize::from(scalar.prim != crate::geometry::NO_PRIM);
            blocked += usize::from(got);
        }
        assert!(hits > 2000 && blocked > 2000, "only {hits} hits, {blocked} blocked");
    }
}
