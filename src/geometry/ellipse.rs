//! Ellipses in the plane and the exact area and centroid of an ellipse's intersection with an axis-aligned
//! rectangle, in f64: what the coverage pattern needs for a sphere's silhouette over a pixel.
//!
//! The method: an affine map `N` takes the ellipse onto the unit disc and the rectangle onto a
//! parallelogram; the disc ∩ parallelogram is summed as a fan of signed triangles from the disc's centre
//! (Green's theorem split along the polygon's edges). Each edge's triangle meets the disc in at most three
//! pieces along the edge: circular sectors where the edge runs outside the circle and a triangle where it
//! runs inside, all in closed form (areas ½·Δφ and ½·A×B, first moments ⅓·(sin, −cos) differences and
//! (A + B)/3 times the area). Affine maps scale areas by `1/|det N|` and carry centroids along, so the
//! pixel-space answer follows from the disc-space one.

/// The points `p` with `|N·(p − centre)| ≤ 1`: the image of the unit disc under `N⁻¹`, moved to `centre`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ellipse {
    /// The centre.
    pub(crate) centre: [f64; 2],
    /// The rows of `N`, which takes the ellipse (centred at the origin) onto the unit disc; invertible.
    pub(crate) to_unit: [[f64; 2]; 2],
}

/// The part of a region inside a rectangle: its area and its centroid (the rectangle's centre when the area
/// is 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Part {
    /// Area, in the rectangle's units (0 ≤ area ≤ the rectangle's area).
    pub(crate) area: f64,
    /// Centroid of the part.
    pub(crate) centroid: [f64; 2],
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

impl Ellipse {
    /// The ellipse with semi-axes `axes[0]` along the direction at `angle` (radians from +x, toward +y) and
    /// `axes[1]` across it.
    #[cfg(test)]
    pub(crate) fn from_axes(centre: [f64; 2], axes: [f64; 2], angle: f64) -> Ellipse {
        let (s, c) = angle.sin_cos();
        Ellipse { centre, to_unit: [[c / axes[0], s / axes[0]], [-s / axes[1], c / axes[1]]] }
    }

    /// `det N`: the ellipse's area is `π/|det N|`.
    pub(crate) fn det(&self) -> f64 {
        let n = &self.to_unit;
        n[0][0] * n[1][1] - n[0][1] * n[1][0]
    }

    /// The ellipse's area.
    pub(crate) fn area(&self) -> f64 {
        std::f64::consts::PI / self.det().abs()
    }

    /// `|N·(p − centre)|²`: below 1 inside, 1 on the boundary, above 1 outside.
    pub(crate) fn level(&self, p: [f64; 2]) -> f64 {
        let q = self.map(p);
        dot(q, q)
    }

    /// Whether `p` lies inside or on the boundary.
    pub(crate) fn contains(&self, p: [f64; 2]) -> bool {
        self.level(p) <= 1.0
    }

    /// `N·(p − centre)`: `p` in the space where the ellipse is the unit disc.
    fn map(&self, p: [f64; 2]) -> [f64; 2] {
        let d = [p[0] - self.centre[0], p[1] - self.centre[1]];
        [dot(self.to_unit[0], d), dot(self.to_unit[1], d)]
    }

    /// `centre + N⁻¹·q`: a disc-space point back in the plane.
    fn unmap(&self, q: [f64; 2]) -> [f64; 2] {
        let n = &self.to_unit;
        let det = self.det();
        let x = (n[1][1] * q[0] - n[0][1] * q[1]) / det;
        let y = (n[0][0] * q[1] - n[1][0] * q[0]) / det;
        [self.centre[0] + x, self.centre[1] + y]
    }

    /// Half the width and half the height of the ellipse's bounding box: the lengths of the rows of `N⁻¹`.
    pub(crate) fn half_extent(&self) -> [f64; 2] {
        let n = &self.to_unit;
        let det = self.det().abs();
        [n[1][1].hypot(n[0][1]) / det, n[1][0].hypot(n[0][0]) / det]
    }

    /// The part of the ellipse inside the rectangle `[lo[0], hi[0]] × [lo[1], hi[1]]`, exactly up to f64
    /// rounding (relative error about 1e-15 of the terms summed: areas of 1e-12 of the rectangle and more
    /// come out right to several digits even for ellipses 1e6 times the rectangle's size).
    pub(crate) fn clip(&self, lo: [f64; 2], hi: [f64; 2]) -> Part {
        let rect_area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let rect_centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let nothing = Part { area: 0.0, centroid: rect_centre };
        let e = self.half_extent();
        let (c, det) = (self.centre, self.det());
        if !(det.is_finite() && det != 0.0) {
            return nothing;
        }
        if c[0] + e[0] <= lo[0] || c[0] - e[0] >= hi[0] || c[1] + e[1] <= lo[1] || c[1] - e[1] >= hi[1] {
            return nothing;
        }
        if c[0] - e[0] >= lo[0] && c[0] + e[0] <= hi[0] && c[1] - e[1] >= lo[1] && c[1] + e[1] <= hi[1] {
            return Part { area: self.area().min(rect_area), centroid: c };
        }
        let corners = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
        // An ellipse is convex: holding the corners, it holds the rectangle.
        if corners.iter().all(|&p| self.contains(p)) {
            return Part { area: rect_area, centroid: rect_centre };
        }
        let (area, moment, crossed) = disc_polygon(&corners.map(|p| self.map(p)));
        // No edge of the rectangle enters the ellipse, and it is not inside (the bounding boxes said so):
        // they are apart, whatever the sectors' rounding left.
        if !crossed {
            return nothing;
        }
        // The corners go counter-clockwise; N reverses that when det N < 0, which flips both signs.
        let (area, moment) = if det < 0.0 { (-area, moment.map(|m| -m)) } else { (area, moment) };
        if area <= 0.0 {
            return nothing;
        }
        let centroid = self.unmap([moment[0] / area, moment[1] / area]);
        let clamp = |v: f64, a: f64, b: f64| v.max(a).min(b);
        Part {
            area: (area / det.abs()).min(rect_area),
            centroid: [clamp(centroid[0], lo[0], hi[0]), clamp(centroid[1], lo[1], hi[1])],
        }
    }
}

/// Signed area and first moment of the unit disc ∩ the polygon `poly` (counter-clockwise for a positive
/// area), as the sum over the edges of the disc ∩ the triangle (origin, edge), and whether some edge runs
/// inside the disc.
fn disc_polygon(poly: &[[f64; 2]]) -> (f64, [f64; 2], bool) {
    let mut acc = (0.0, [0.0, 0.0]);
    let mut crossed = false;
    for (k, &p) in poly.iter().enumerate() {
        crossed |= edge(p, poly[(k + 1) % poly.len()], &mut acc);
    }
    (acc.0, acc.1, crossed)
}

/// Adds the disc ∩ triangle (origin, p, q) to `acc` (signed: positive when q is counter-clockwise of p);
/// true when part of the edge lies inside the disc.
/// Points of the edge `p + s·d`, s in [0, 1], lie inside the circle for s between the roots of
/// `|p + s·d|² = 1`; the triangle's part there is a triangle, elsewhere a sector. Cross and dot products of
/// the pieces' ends are formed from `p × d`, so a short edge far from the origin keeps its relative
/// precision.
fn edge(p: [f64; 2], q: [f64; 2], acc: &mut (f64, [f64; 2])) -> bool {
    let d = [q[0] - p[0], q[1] - p[1]];
    let a = dot(d, d);
    if a == 0.0 {
        return false;
    }
    let (b, c) = (dot(p, d), dot(p, p) - 1.0);
    let pxd = cross(p, d);
    let at = |s: f64| [p[0] + s * d[0], p[1] + s * d[1]];
    let disc = b * b - a * c;
    if disc <= 0.0 {
        sector(p, q, pxd, dot(p, q), acc);
        return false;
    }
    let root = disc.sqrt();
    // The roots of a·s² + 2b·s + c, each without cancellation.
    let (s1, s2) = if b >= 0.0 {
        let m = -(b + root);
        (m / a, c / m)
    } else {
        let m = root - b;
        (c / m, m / a)
    };
    let (t1, t2) = (s1.clamp(0.0, 1.0), s2.clamp(0.0, 1.0));
    if t1 >= t2 {
        sector(p, q, pxd, dot(p, q), acc);
        return false;
    }
    let (ea, eb) = (at(t1), at(t2));
    if t1 > 0.0 {
        sector(p, ea, t1 * pxd, dot(p, ea), acc);
    }
    let area = 0.5 * (t2 - t1) * pxd;
    acc.0 += area;
    acc.1[0] += (ea[0] + eb[0]) / 3.0 * area;
    acc.1[1] += (ea[1] + eb[1]) / 3.0 * area;
    if t2 < 1.0 {
        sector(eb, q, (1.0 - t2) * pxd, dot(eb, q), acc);
    }
    true
}

/// Adds the unit disc's sector between the directions of `a` and `b` (both outside or on the circle),
/// swept the short way, given `a × b` and `a · b`.
fn sector(a: [f64; 2], b: [f64; 2], axb: f64, adb: f64, acc: &mut (f64, [f64; 2])) {
    let angle = axb.atan2(adb);
    if angle == 0.0 {
        return;
    }
    let unit = |v: [f64; 2]| {
        let l = v[0].hypot(v[1]);
        [v[0] / l, v[1] / l]
    };
    let (ua, ub) = (unit(a), unit(b));
    acc.0 += 0.5 * angle;
    acc.1[0] += (ub[1] - ua[1]) / 3.0;
    acc.1[1] += (ua[0] - ub[0]) / 3.0;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;
    use std::f64::consts::PI;

    const UNIT: ([f64; 2], [f64; 2]) = ([0.0, 0.0], [1.0, 1.0]);

    /// Area and first moments of the ellipse inside the rectangle by counting the centres of an n×n grid of
    /// cells: exact for every cell wholly inside or outside. The ellipse's boundary is convex, so it crosses
    /// each of the 2(n + 1) grid lines at most twice and passes through at most 4(n + 1) + 1 cells; the
    /// rectangle's edges lie on cell edges. So the count is within (4n + 5) cells of the area, and each
    /// moment within that many cells times the largest coordinate.
    fn grid_count(e: &Ellipse, lo: [f64; 2], hi: [f64; 2], n: usize) -> (f64, [f64; 2], f64) {
        let (w, h) = ((hi[0] - lo[0]) / n as f64, (hi[1] - lo[1]) / n as f64);
        let (mut count, mut mx, mut my) = (0.0, 0.0, 0.0);
        for j in 0..n {
            let y = lo[1] + (j as f64 + 0.5) * h;
            for i in 0..n {
                let x = lo[0] + (i as f64 + 0.5) * w;
                if e.contains([x, y]) {
                    count += 1.0;
                    mx += x;
                    my += y;
                }
            }
        }
        let cell = w * h;
        (count * cell, [mx * cell, my * cell], (4 * n + 5) as f64 * cell)
    }

    /// Area and first moments by columns: in each of n columns the ellipse's exact chord at the column's
    /// middle, cut to the rectangle (midpoint rule in x). The chord is smooth except at the ellipse's
    /// leftmost and rightmost points, where it grows like a square root.
    fn columns(e: &Ellipse, lo: [f64; 2], hi: [f64; 2], n: usize) -> (f64, [f64; 2]) {
        let n_ = e.to_unit;
        let qa = n_[0][1] * n_[0][1] + n_[1][1] * n_[1][1];
        let h = (hi[0] - lo[0]) / n as f64;
        let (mut area, mut mx, mut my) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let x = lo[0] + (i as f64 + 0.5) * h;
            let dx = x - e.centre[0];
            let qb = (n_[0][0] * n_[0][1] + n_[1][0] * n_[1][1]) * dx;
            let qc = (n_[0][0] * n_[0][0] + n_[1][0] * n_[1][0]) * dx * dx - 1.0;
            let disc = qb * qb - qa * qc;
            if disc <= 0.0 {
                continue;
            }
            let (y0, y1) = ((-qb - disc.sqrt()) / qa + e.centre[1], (-qb + disc.sqrt()) / qa + e.centre[1]);
            let (y0, y1) = (y0.max(lo[1]), y1.min(hi[1]));
            if y1 > y0 {
                let len = (y1 - y0) * h;
                area += len;
                mx += x * len;
                my += 0.5 * (y0 + y1) * len;
            }
        }
        (area, [mx, my])
    }

    /// Checks `clip` against both estimates; returns the part.
    fn check(e: Ellipse, lo: [f64; 2], hi: [f64; 2]) -> Part {
        let part = e.clip(lo, hi);
        let (area, moment, bound) = grid_count(&e, lo, hi, 1000);
        let reach = lo.iter().chain(&hi).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!((part.area - area).abs() <= bound, "{e:?}: {part:?} against the grid's {area} ± {bound}");
        for (k, want) in moment.iter().enumerate() {
            let m = part.area * part.centroid[k];
            assert!((m - want).abs() <= bound * reach, "{e:?}: moment {k} {m} against {want}");
        }
        // The midpoint rule's error falls like h^1.5 at the chord's square-root ends (h = 5e-6 of the width:
        // about 1e-8 of the rectangle per end) and like h where the chord jumps (an edge nearly parallel to
        // the columns), where the change from n to 2n columns shows it: the tolerance is 1e-7 of the
        // rectangle plus four times that change.
        let (coarse, coarse_moment) = columns(&e, lo, hi, 100_000);
        let (area, moment) = columns(&e, lo, hi, 200_000);
        let rect = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let tol = 4.0 * (area - coarse).abs() + 1e-7 * rect;
        assert!((part.area - area).abs() <= tol, "{e:?}: {part:?} against the columns' {area} ± {tol}");
        for (k, (want, coarse)) in moment.iter().zip(coarse_moment).enumerate() {
            let m = part.area * part.centroid[k];
            let tol = 4.0 * (want - coarse).abs() + 1e-7 * rect * reach.max(1.0);
            assert!((m - moment[k]).abs() <= tol, "{e:?}: moment {k} {m} against {} ± {tol}", moment[k]);
        }
        part
    }

    #[test]
    fn a_circle_inside_outside_and_around_the_square() {
        let (lo, hi) = UNIT;
        let inside = check(Ellipse::from_axes([0.5, 0.4], [0.3, 0.3], 0.0), lo, hi);
        assert!((inside.area - PI * 0.09).abs() < 1e-15);
        assert_eq!(inside.centroid, [0.5, 0.4]);
        let outside = check(Ellipse::from_axes([3.0, 3.0], [0.5, 0.5], 0.0), lo, hi);
        assert_eq!(outside.area, 0.0);
        // The corners lie 0.71 from the centre: the square is covered.
        let around = check(Ellipse::from_axes([0.5, 0.5], [1.0, 1.0], 0.0), lo, hi);
        assert_eq!(around, Part { area: 1.0, centroid: [0.5, 0.5] });
        // Outside the bounding box's corner, though the boxes overlap.
        let near = check(Ellipse::from_axes([1.3, 1.3], [0.4, 0.4], 0.0), lo, hi);
        assert_eq!(near.area, 0.0);
    }

    #[test]
    fn ellipses_cutting_edges_and_corners() {
        let (lo, hi) = UNIT;
        // One edge: a cap below y = 0.3 of a circle of radius 0.5 centred at y = −0.2.
        let cap = check(Ellipse::from_axes([0.5, -0.2], [0.5, 0.5], 0.0), lo, hi);
        let h: f64 = 0.3;
        let cap_area = 0.25 * (1.0 - h / 0.5).acos() - (0.5 - h) * (h * (1.0 - h)).sqrt();
        assert!((cap.area - cap_area).abs() < 1e-15, "{} vs {cap_area}", cap.area);
        // The half-disc whose centre lies on the square's edge (the edge's line passes through the centre).
        let half = check(Ellipse::from_axes([0.5, 0.0], [0.3, 0.3], 0.0), lo, hi);
        assert!((half.area - PI * 0.09 / 2.0).abs() < 1e-15);
        assert!((half.centroid[1] - 4.0 * 0.3 / (3.0 * PI)).abs() < 1e-15);
        // A quarter disc at a corner.
        let quarter = check(Ellipse::from_axes([0.0, 0.0], [0.6, 0.6], 0.0), lo, hi);
        assert!((quarter.area - PI * 0.36 / 4.0).abs() < 1e-15);
        // Two opposite edges: a band across the square, and a rotated ellipse over two adjacent edges.
        let band = check(Ellipse::from_axes([0.5, 0.5], [2.0, 0.2], 0.0), lo, hi);
        assert!(band.area > 0.39 && band.area < 0.4);
        check(Ellipse::from_axes([0.9, 0.8], [0.5, 0.2], 0.7), lo, hi);
        check(Ellipse::from_axes([-0.1, 1.1], [0.6, 0.35], -0.4), lo, hi);
        // Three corners in, one out.
        check(Ellipse::from_axes([0.45, 0.45], [0.75, 0.7], 0.2), lo, hi);
    }

    #[test]
    fn thin_and_huge_ellipses() {
        let (lo, hi) = UNIT;
        // Thin: 3 by 0.01, tilted, through the square and past two edges; and one whose tip just enters.
        check(Ellipse::from_axes([0.4, 0.6], [3.0, 0.01], 0.3), lo, hi);
        check(Ellipse::from_axes([1.2, 1.1], [0.3, 0.002], 0.8), lo, hi);
        // A circle of radius 1000 whose edge crosses the square near y = 0.3.
        let big = check(Ellipse::from_axes([0.5, -999.7], [1000.0, 1000.0], 0.0), lo, hi);
        assert!((big.area - 0.3).abs() < 1e-3, "{big:?}");
        // A pixel far from the origin (image coordinates) and an ellipse 1e6 pixels wide, nearly straight.
        let (lo, hi) = ([1024.0, 2047.0], [1025.0, 2048.0]);
        let huge = check(Ellipse::from_axes([1024.25 - 1e6, 2047.5], [1e6, 3e6], 0.0), lo, hi);
        assert!((huge.area - 0.25).abs() < 1e-6, "{huge:?}");
    }

    #[test]
    fn random_ellipses_match_the_brute_force_estimates() {
        let mut rng = SplitMix64::new(22);
        let mut partial = 0;
        for _ in 0..60 {
            let centre = [rng.unit() * 2.0 - 0.5, rng.unit() * 2.0 - 0.5];
            let axes = [0.02 + rng.unit() * 1.2, 0.02 + rng.unit() * 1.2];
            let part = check(Ellipse::from_axes(centre, axes, rng.unit() * 7.0), UNIT.0, UNIT.1);
            partial += usize::from(part.area > 0.0 && part.area < 1.0);
        }
        assert!(partial > 30, "{partial} partly covered squares");
    }
}
