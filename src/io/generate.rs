//! Scene generators: the benchmark contract's random sphere field (DESIGN.md, "Peer benchmark contract") and
//! SPD's sphereflake (`balls`), written as `.xyzr` (or binary `.f32r`) and `.nff` text.

use std::io::{self, Write};

use glam::{DMat3, DVec3};
use thiserror::Error;

use crate::math::SplitMix64;

/// Generator arguments that make no sense.
#[derive(Debug, Error, PartialEq)]
#[error("{0}")]
pub struct GenError(pub String);

/// The contract's sphere field.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldParams {
    /// Number of spheres (≥ 1).
    pub count: u64,
    /// splitmix64 seed (contract default 1).
    pub seed: u64,
    /// Box corner (x0, y0, z0).
    pub lo: [f64; 3],
    /// Opposite corner (x1, y1, z1), each coordinate above `lo`'s.
    pub hi: [f64; 3],
    /// Smallest radius; default `0.1·s` with `s = (x1 − x0)/cbrt(N)`.
    pub rmin: Option<f64>,
    /// Largest radius; default `0.25·s`.
    pub rmax: Option<f64>,
}

impl Default for FieldParams {
    fn default() -> Self {
        Self { count: 1000, seed: 1, lo: [-1.0; 3], hi: [1.0; 3], rmin: None, rmax: None }
    }
}

impl FieldParams {
    /// The radius range after defaults, checked: `0 < rmin ≤ rmax`, all finite, box non-empty, count ≥ 1.
    pub fn radii(&self) -> Result<(f64, f64), GenError> {
        if self.count == 0 {
            return Err(GenError("--count must be at least 1".into()));
        }
        let ok_box =
            (0..3).all(|k| self.lo[k].is_finite() && self.hi[k].is_finite() && self.lo[k] < self.hi[k]);
        if !ok_box {
            return Err(GenError(format!(
                "--box must have x0 < x1, y0 < y1, z0 < z1 (finite), got {:?} .. {:?}",
                self.lo, self.hi
            )));
        }
        let s = (self.hi[0] - self.lo[0]) / (self.count as f64).cbrt();
        let (rmin, rmax) = (self.rmin.unwrap_or(0.1 * s), self.rmax.unwrap_or(0.25 * s));
        for (name, r) in [("--rmin", rmin), ("--rmax", rmax)] {
            if !(r > 0.0 && r.is_finite()) {
                return Err(GenError(format!("{name} must be a positive finite number, got {r}")));
            }
        }
        if rmin > rmax {
            return Err(GenError(format!("--rmin ({rmin}) must not exceed --rmax ({rmax})")));
        }
        Ok((rmin, rmax))
    }

    /// The spheres `[x, y, z, r]` in order, computed in f64 and rounded to f32 once, as the contract says.
    pub fn spheres(&self) -> Result<impl Iterator<Item = [f32; 4]>, GenError> {
        let (rmin, rmax) = self.radii()?;
        let (lo, hi) = (self.lo, self.hi);
        let mut rng = SplitMix64::new(self.seed);
        Ok((0..self.count).map(move |_| {
            let u = [rng.unit(), rng.unit(), rng.unit(), rng.unit()];
            let c = |k: usize| (lo[k] + u[k] * (hi[k] - lo[k])) as f32;
            [c(0), c(1), c(2), (rmin + u[3] * (rmax - rmin)) as f32]
        }))
    }

    /// Writes the field as `.xyzr`: a `#` header naming the parameters, then `x y z r` per line. f32
    /// `Display` is the shortest text that parses back to the same f32, so the file reproduces the floats
    /// exactly. Invalid parameters are an `InvalidInput` error before anything is written.
    pub fn write_xyzr(&self, w: &mut impl Write) -> io::Result<()> {
        let (rmin, rmax) = self.radii().map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
        writeln!(
            w,
            "# bareray gen field: {} spheres, splitmix64 seed {}, box {:?}..{:?}, radii {rmin}..{rmax}",
            self.count, self.seed, self.lo, self.hi
        )?;
        writeln!(w, "# x y z r")?;
        for [x, y, z, r] in self.spheres().map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))? {
            writeln!(w, "{x} {y} {z} {r}")?;
        }
        Ok(())
    }

    /// Writes the field as `.f32r` ([`super::f32r`]): the f32 values [`Self::write_xyzr`] writes as text.
    /// Invalid parameters (or more spheres than the format's u32 count holds) are an `InvalidInput` error
    /// before anything is written.
    pub fn write_f32r(&self, w: &mut impl Write) -> io::Result<()> {
        let spheres = self.spheres().map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
        super::f32r::write(w, self.count, spheres)
    }
}

/// The largest sphereflake level `flake` accepts (level 7 is 5.4 million spheres).
pub const MAX_FLAKE_LEVEL: u32 = 7;

/// Number of spheres of a sphereflake of level `level`: 1 + 9 + … + 9^level.
pub fn flake_count(level: u32) -> u64 {
    (9u64.pow(level + 1) - 1) / 8
}

/// The spheres `[x, y, z, r]` of SPD `balls` at size factor `level`, in SPD's output order (depth first,
/// parent before children), in f64.
///
/// Geometry as SPD's balls.c builds it: nine child directions (three around each of three tilted triples), a
/// child of radius r/3 at distance 4r/3 from its parent's centre, each child's set turned so that the set's
/// +z maps onto the direction from parent to child.
pub fn flake(level: u32) -> Result<Vec<[f64; 4]>, GenError> {
    let mut out = Vec::with_capacity(flake_count(level.min(MAX_FLAKE_LEVEL)) as usize);
    for_each_flake_sphere(level, &mut |s| out.push(s))?;
    Ok(out)
}

/// Calls `visit` with each sphere of [`flake`] in order, without storing them.
fn for_each_flake_sphere(level: u32, visit: &mut dyn FnMut([f64; 4])) -> Result<(), GenError> {
    if level > MAX_FLAKE_LEVEL {
        return Err(GenError(format!("--level must be at most {MAX_FLAKE_LEVEL}, got {level}")));
    }
    grow(&child_directions(), level, DVec3::ZERO, 0.5, DVec3::Z, visit);
    Ok(())
}

/// The nine unit directions of one set of children, for a parent whose axis is +z.
fn child_directions() -> [DVec3; 9] {
    let d = std::f64::consts::FRAC_1_SQRT_2;
    // A triple of directions 90° apart, lifted about (1, −1, 0) so that the first one leans toward +z ...
    let lift = DMat3::from_axis_angle(DVec3::new(1.0, -1.0, 0.0).normalize(), (2.0 / 6f64.sqrt()).asin());
    let trio = [DVec3::new(d, d, 0.0), DVec3::new(d, 0.0, -d), DVec3::new(0.0, d, -d)].map(|v| lift * v);
    // ... then repeated at 0°, 120° and 240° about z.
    let mut set = [DVec3::ZERO; 9];
    for (k, chunk) in set.chunks_mut(3).enumerate() {
        let turn = DMat3::from_rotation_z(k as f64 * 2.0 * std::f64::consts::PI / 3.0);
        for (slot, v) in chunk.iter_mut().zip(trio) {
            *slot = turn * v;
        }
    }
    set
}

/// Emits the sphere at `center` and, while `depth` lasts, its nine children around `axis`.
fn grow(
    set: &[DVec3; 9],
    depth: u32,
    center: DVec3,
    radius: f64,
    axis: DVec3,
    out: &mut dyn FnMut([f64; 4]),
) {
    out([center.x, center.y, center.z, radius]);
    if depth == 0 {
        return;
    }
    let turn = rotation_from_z(axis);
    let reach = radius * (1.0 + 1.0 / 3.0);
    for v in set {
        let child = center + turn * *v * reach;
        grow(set, depth - 1, child, radius / 3.0, (child - center) / reach, out);
    }
}

/// The rotation taking +z to `axis` about `z × axis` (SPD's choice; near ±z, identity or a half turn).
fn rotation_from_z(axis: DVec3) -> DMat3 {
    if axis.z >= 0.9999 {
        DMat3::IDENTITY
    } else if axis.z <= -0.9999 {
        DMat3::from_rotation_y(std::f64::consts::PI)
    } else {
        let angle = axis.z.clamp(-1.0, 1.0).acos();
        DMat3::from_axis_angle(DVec3::Z.cross(axis).normalize(), angle)
    }
}

/// Writes the sphereflake as NFF: SPD balls' background, view, three colourless lights, beige floor polygon
/// and pale-yellow mirror fill (as SPD prints them), then the spheres at full f64 precision. No comment line:
/// Tachyon's NFF reader silently reads nothing from a file that starts with one, and peers must read it.
pub fn write_flake_nff(level: u32, w: &mut impl Write) -> io::Result<()> {
    let invalid = |e: GenError| io::Error::new(io::ErrorKind::InvalidInput, e);
    w.write_all(FLAKE_HEADER.as_bytes())?;
    let mut result = Ok(());
    for_each_flake_sphere(level, &mut |s| {
        if result.is_ok() {
            result = write_sphere(w, s);
        }
    })
    .map_err(invalid)?;
    result
}

/// The sphereflake NFF text in memory (for tests and small levels).
pub fn flake_nff(level: u32) -> Result<String, GenError> {
    let mut out = Vec::new();
    write_flake_nff(level, &mut out).map_err(|e| GenError(e.to_string()))?;
    Ok(String::from_utf8(out).expect("generated text is ASCII"))
}

fn write_sphere(w: &mut impl Write, s: [f64; 4]) -> io::Result<()> {
    w.write_all(b"s")?;
    for v in s {
        w.write_all(b" ")?;
        write_number(w, v)?;
    }
    w.write_all(b"\n")
}

/// Everything of SPD `balls` before the spheres, in SPD's own NFF text.
const FLAKE_HEADER: &str = "b 0.078 0.361 0.753
v
from 2.1 1.3 1.7
at 0 0 0
up 0 0 1
angle 45
hither 0.01
resolution 512 512
l 4 3 2
l 1 -4 4
l -3 1 5
f 1 0.75 0.33 0.8 0 100000 0 1
p 4
12 12 -0.5
-12 12 -0.5
-12 -12 -0.5
12 -12 -0.5
f 1 0.9 0.7 0.5 0.5 3.0827 0 1
";

/// Shortest round-trip text of `v`, in scientific notation when plain digits would be long (tiny or huge).
fn write_number(w: &mut impl Write, v: f64) -> io::Result<()> {
    let a = v.abs();
    if a == 0.0 || (1e-5..1e15).contains(&a) {
        write!(w, "{v}")
    } else {
        write!(w, "{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flake_nff_starts_with_an_entity_not_a_comment() {
        // Tachyon reads nothing from an NFF whose first line is a comment.
        let mut out = Vec::new();
        write_flake_nff(1, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("b "), "{}", &text[..20]);
        assert!(!text.lines().any(|l| l.starts_with('#')));
    }

    #[test]
    fn child_directions_are_unit_and_the_first_leans_up() {
        let set = child_directions();
        assert!(set.iter().all(|v| (v.length() - 1.0).abs() < 1e-15));
        let s = 1.0 / 6f64.sqrt();
        assert!((set[0] - DVec3::new(s, s, 2.0 * s)).length() < 1e-15, "{:?}", set[0]);
    }

    #[test]
    fn numbers_print_compactly_and_round_trip() {
        let text = |v: f64| {
            let mut out = Vec::new();
            write_number(&mut out, v).unwrap();
            String::from_utf8(out).unwrap()
        };
        for v in [0.5, 1.1102230246251565e-16, -0.0555556, 0.0, 3e20] {
            assert_eq!(text(v).parse::<f64>().unwrap(), v, "{}", text(v));
        }
        assert_eq!(text(1e-20), "1e-20");
        assert_eq!(text(0.25), "0.25");
    }
}
