//! Spheres in structure-of-arrays layout, the form every sphere kernel and traversal reads, and the exact eye
//! term each sphere carries.

use crate::geometry::eye_term;
use crate::math::{Rgb8, Vec3f, V3};

/// Spheres in structure-of-arrays layout: one array per coordinate, so lanes load contiguous values.
#[derive(Clone, Debug, Default)]
pub struct Spheres {
    /// Centre x.
    pub cx: Vec<f32>,
    /// Centre y.
    pub cy: Vec<f32>,
    /// Centre z.
    pub cz: Vec<f32>,
    /// Radius.
    pub r: Vec<f32>,
    /// The exact eye term `|centre − eye|² − r²` (the eye is the rendering space's origin), computed in f64
    /// from the scene's own values and rounded once: camera rays use it instead of computing it in f32
    /// ([`crate::geometry::Approach::roots_from_eye`]).
    pub c_eye: Vec<f32>,
    /// Material index.
    pub(crate) material: Vec<u32>,
    /// Per-sphere colours, replacing the material's colour: empty (no sphere has its own), or one per
    /// sphere, in the same order as the other arrays (permuted with them). Three bytes a sphere
    /// ([`Rgb8`]), allocated only for scenes that give colours.
    pub color: Vec<Rgb8>,
    /// Scene-file index (the identity until `Spheres::permuted`): breaks ties in t and names the sphere
    /// in reports.
    pub key: Vec<u32>,
    /// Some sphere has the eye within about its radius of its surface (`|c_eye| < 4·r²`): only then can `c`
    /// from the eye term be the more accurate one for rays that do not start at the eye (a large ground
    /// sphere near the eye), so only then do those rays pay for computing both
    /// ([`crate::geometry::Approach::roots_with_eye_term`]); elsewhere they take `|oc|² − r²` directly.
    pub(crate) eye_terms_help: bool,
}

impl Spheres {
    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.r.len()
    }
    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.r.is_empty()
    }
    /// Bytes of the arrays' contents.
    pub(crate) fn bytes(&self) -> usize {
        let floats = [&self.cx, &self.cy, &self.cz, &self.r, &self.c_eye].map(Vec::len).iter().sum::<usize>();
        floats * size_of::<f32>()
            + (self.material.len() + self.key.len()) * size_of::<u32>()
            + self.color.len() * size_of::<Rgb8>()
    }
    /// The colour of sphere `i` when the spheres have colours of their own.
    #[inline]
    pub(crate) fn color_of(&self, i: usize) -> Option<Rgb8> {
        self.color.get(i).copied()
    }
    /// Centre of sphere `i`.
    #[inline(always)]
    pub(crate) fn center(&self, i: usize) -> Vec3f {
        V3::new(self.cx[i], self.cy[i], self.cz[i])
    }
    /// The spheres in a new order: `order[j]` is the old index of new sphere `j`.
    pub(crate) fn permuted(&self, order: &[u32]) -> Spheres {
        Spheres {
            cx: gathered(&self.cx, order),
            cy: gathered(&self.cy, order),
            cz: gathered(&self.cz, order),
            r: gathered(&self.r, order),
            c_eye: gathered(&self.c_eye, order),
            material: gathered(&self.material, order),
            color: if self.color.is_empty() { Vec::new() } else { gathered(&self.color, order) },
            key: gathered(&self.key, order),
            eye_terms_help: self.eye_terms_help,
        }
    }

    /// Appends a sphere whose f32 centre and radius are exact (hand-built geometry, tests); its file index is
    /// its position. Its eye term is computed from these values.
    pub fn push(&mut self, center: Vec3f, radius: f32, material: u32) {
        self.push_exact(center.to_f64(), f64::from(radius), material);
    }

    /// `n` spheres given in f64 (rendering space) by `sphere(i)` = (centre, radius, material), each stored as
    /// [`Spheres::push_exact`] appends it, filled in slices on the current rayon pool.
    pub(crate) fn from_exact(n: usize, sphere: impl Fn(usize) -> (V3<f64>, f64, u32) + Sync) -> Spheres {
        use rayon::prelude::*;
        const SLICE: usize = 1 << 14;
        let zeros = || vec![0.0; n];
        let (mut cx, mut cy, mut cz, mut r, mut c_eye) = (zeros(), zeros(), zeros(), zeros(), zeros());
        let (mut material, mut key) = (vec![0; n], vec![0; n]);
        let floats = (cx.par_chunks_mut(SLICE).zip(cy.par_chunks_mut(SLICE)).zip(cz.par_chunks_mut(SLICE)))
            .zip(r.par_chunks_mut(SLICE).zip(c_eye.par_chunks_mut(SLICE)));
        let ints = material.par_chunks_mut(SLICE).zip(key.par_chunks_mut(SLICE));
        let slices = floats.zip(ints).enumerate();
        let eye_terms_help = (slices.map(|(k, ((((cx, cy), cz), (r, c_eye)), (material, key)))| {
            let mut help = false;
            for j in 0..cx.len() {
                let i = k * SLICE + j;
                let (center, radius, m) = sphere(i);
                let c = center.to_f32();
                (cx[j], cy[j], cz[j], r[j]) = (c.x, c.y, c.z, radius as f32);
                let term = eye_term(center, radius);
                help |= term.abs() < 4.0 * radius * radius;
                (c_eye[j], material[j], key[j]) = (term as f32, m, i as u32);
            }
            help
        }))
        .reduce(|| false, |a, b| a || b);
        Spheres { cx, cy, cz, r, c_eye, material, color: Vec::new(), key, eye_terms_help }
    }

    /// Appends a sphere given in f64 (rendering space), rounding its centre and radius to f32 once and
    /// computing its eye term from the f64 values.
    pub(crate) fn push_exact(&mut self, center: V3<f64>, radius: f64, material: u32) {
        let c = center.to_f32();
        self.cx.push(c.x);
        self.cy.push(c.y);
        self.cz.push(c.z);
        self.key.push(self.r.len() as u32);
        self.r.push(radius as f32);
        let c_eye = eye_term(center, radius);
        self.eye_terms_help |= c_eye.abs() < 4.0 * radius * radius;
        self.c_eye.push(c_eye as f32);
        self.material.push(material);
    }
}

/// `v` in a new order, `order[j]` being the old index of new item `j`: how the store follows its BVH's leaf
/// order. Large stores are gathered on the thread pool.
fn gathered<T: Copy + Send + Sync>(v: &[T], order: &[u32]) -> Vec<T> {
    use rayon::prelude::*;
    order.par_iter().with_min_len(1 << 14).map(|&i| v[i as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Built in slices on a pool of three threads, the arrays hold what appending each sphere gives: centres
    /// and radii rounded once, eye terms from the f64 values, file order as keys; the flag for eye terms set
    /// by the one sphere near the eye (or by none).
    #[test]
    fn spheres_built_in_slices_are_the_appended_ones() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        for near in [None, Some(40_000)] {
            let sphere = |i: usize| {
                let f = i as f64;
                let center = V3::new(f.sin() * 1e3 + 0.1, (f * 0.37).cos() * 7e2, 5.0 + f * 1e-3);
                match Some(i) == near {
                    true => (V3::new(0.0, 0.0, 1.0 + 1e-9), 1.0, 2),
                    false => (center, 0.1 + (i % 7) as f64 * 0.013, (i % 5) as u32),
                }
            };
            let n = 3 * (1 << 14) + 12_345;
            let built = pool.install(|| Spheres::from_exact(n, sphere));
            let mut appended = Spheres::default();
            (0..n).map(sphere).for_each(|(c, r, m)| appended.push_exact(c, r, m));
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            for (a, b) in [(&built.cx, &appended.cx), (&built.cy, &appended.cy), (&built.cz, &appended.cz)]
                .into_iter()
                .chain([(&built.r, &appended.r), (&built.c_eye, &appended.c_eye)])
            {
                assert_eq!(bits(a), bits(b));
            }
            assert_eq!((&built.material, &built.key), (&appended.material, &appended.key));
            assert_eq!(built.eye_terms_help, near.is_some());
            assert_eq!(appended.eye_terms_help, near.is_some());
        }
    }
}
