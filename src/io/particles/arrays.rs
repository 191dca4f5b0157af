//! Spheres given as arrays in memory (centres, radii, colours), checked and made the scene a particle file
//! of the same spheres makes (`super::scene::particle_scene`): what the Python module renders.
//!
//! The arrays are read where they are, as f32 or f64 ([`Floats`]); the description holds each sphere in
//! f64 (40 bytes) and its colour in 3 bytes.

use glam::DVec3;
use rayon::prelude::*;

use super::scene::{particle_scene, DEFAULT_VIEW};
use crate::kinds::sphere::SphereDesc;
use crate::math::{Rgb, Rgb8};
use crate::scene::desc::SceneDesc;

/// A flat array of numbers, borrowed as it is: f32 or f64.
#[derive(Clone, Copy, Debug)]
pub enum Floats<'a> {
    /// Single precision.
    F32(&'a [f32]),
    /// Double precision.
    F64(&'a [f64]),
}

impl Floats<'_> {
    /// Number of values.
    pub(crate) fn len(&self) -> usize {
        match self {
            Floats::F32(v) => v.len(),
            Floats::F64(v) => v.len(),
        }
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` in f64 (exactly).
    #[inline]
    pub(crate) fn get(&self, i: usize) -> f64 {
        match self {
            Floats::F32(v) => f64::from(v[i]),
            Floats::F64(v) => v[i],
        }
    }
}

/// Spheres as arrays: `centers` holds `x, y, z` of each sphere in turn (3·n values), `radii` one value per
/// sphere, `colors` (if any) `r, g, b` per sphere with channels in [0, 1].
#[derive(Clone, Copy, Debug)]
pub struct SphereArrays<'a> {
    /// Centres, `x, y, z` per sphere.
    pub centers: Floats<'a>,
    /// Radii, one per sphere (positive).
    pub radii: Floats<'a>,
    /// Colours, `r, g, b` per sphere, or `None`: every sphere gets the one material's grey (0.8).
    pub colors: Option<Floats<'a>>,
}

/// What is wrong with an array: its name, and the index of the first bad sphere if the fault is in one.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}: {message}", match .index { Some(i) => format!("{array}[{i}]"), None => array.to_string() })]
pub struct ArrayError {
    /// `centers`, `radii` or `colors`.
    pub(crate) array: &'static str,
    /// The first bad sphere, or `None` for a fault of the whole array (its length).
    pub index: Option<usize>,
    /// What is wrong.
    pub(crate) message: String,
}

impl ArrayError {
    fn at(array: &'static str, index: usize, message: String) -> Self {
        ArrayError { array, index: Some(index), message }
    }
}

impl SphereArrays<'_> {
    /// Number of spheres.
    pub(crate) fn len(&self) -> usize {
        self.radii.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    /// Checks the arrays: lengths that agree and at least one sphere, finite centres (within f32's range,
    /// as every reader demands), positive finite radii, colour channels in [0, 1]. The error names the first
    /// bad sphere (the spheres are checked in parallel).
    pub fn check(&self) -> Result<(), ArrayError> {
        let n = self.len();
        let whole = |array, message: String| Err(ArrayError { array, index: None, message });
        if n == 0 {
            return whole("radii", "no spheres".to_owned());
        }
        if self.centers.len() != 3 * n {
            return whole("centers", format!("{} values for {n} spheres: expected n×3", self.centers.len()));
        }
        if let Some(c) = self.colors.filter(|c| c.len() != 3 * n) {
            return whole("colors", format!("{} values for {n} spheres: expected n×3", c.len()));
        }
        // The first bad sphere, found in parallel: its centre, then its radius, then its colour.
        let in_f32 = |v: f64| v.is_finite() && (v as f32).is_finite();
        let fault = |i: usize| {
            let c = [0, 1, 2].map(|k| self.centers.get(3 * i + k));
            if !c.iter().all(|&v| in_f32(v)) {
                let message = format!("({}, {}, {}) is not finite (or beyond f32's range)", c[0], c[1], c[2]);
                return Some(ArrayError::at("centers", i, message));
            }
            let r = self.radii.get(i);
            if !(in_f32(r) && r > 0.0 && r as f32 > 0.0) {
                return Some(ArrayError::at("radii", i, format!("{r} is not a positive finite radius")));
            }
            let rgb = self.colors.map(|colors| [0, 1, 2].map(|k| colors.get(3 * i + k)))?;
            let message = || format!("({}, {}, {}) has a channel outside [0, 1]", rgb[0], rgb[1], rgb[2]);
            (!rgb.iter().all(|v| (0.0..=1.0).contains(v))).then(|| ArrayError::at("colors", i, message()))
        };
        (0..n).into_par_iter().find_map_first(fault).map_or(Ok(()), Err)
    }

    /// The scene of these spheres, as a particle file of them gives it (`particle_scene`): seen from `view`
    /// (+z when `None`), framed at 1920×1080, a headlight, a white background; each sphere's colour in the
    /// per-sphere colour store. Checks the arrays first ([`SphereArrays::check`]).
    ///
    /// ```
    /// use bareray::io::particles::arrays::{Floats, SphereArrays};
    ///
    /// let centers = [0.0f32, 0.0, 0.0, 2.0, 0.0, 0.0];
    /// let radii = [1.0f32, 0.5];
    /// let colors = [1.0f32, 0.0, 0.0, 0.0, 0.0, 1.0];
    /// let arrays = SphereArrays {
    ///     centers: Floats::F32(&centers),
    ///     radii: Floats::F32(&radii),
    ///     colors: Some(Floats::F32(&colors)),
    /// };
    /// let desc = arrays.scene(None)?;
    /// assert_eq!(desc.spheres.len(), 2);
    /// assert_eq!(desc.sphere_colors[1].0, [0, 0, 255]);
    ///
    /// let bad = SphereArrays { radii: Floats::F32(&[1.0, -1.0]), ..arrays };
    /// assert_eq!(bad.scene(None).unwrap_err().to_string(), "radii[1]: -1 is not a positive finite radius");
    /// # Ok::<(), bareray::io::particles::arrays::ArrayError>(())
    /// ```
    pub fn scene(&self, view: Option<DVec3>) -> Result<SceneDesc, ArrayError> {
        self.check()?;
        let n = self.len();
        let spheres = (0..n)
            .into_par_iter()
            .map(|i| SphereDesc {
                center: DVec3::new(
                    self.centers.get(3 * i),
                    self.centers.get(3 * i + 1),
                    self.centers.get(3 * i + 2),
                ),
                radius: self.radii.get(i),
                material: 0,
            })
            .collect();
        let colors = match self.colors {
            Some(c) => (0..n)
                .into_par_iter()
                .map(|i| {
                    let [r, g, b] = [0, 1, 2].map(|k| c.get(3 * i + k) as f32);
                    Rgb8::quantize(Rgb::new(r, g, b))
                })
                .collect(),
            None => Vec::new(),
        };
        Ok(particle_scene(spheres, colors, view.unwrap_or(DEFAULT_VIEW)))
    }
}
