//! What the ellipsoid and plane kinds share: a generic shape (the unit sphere, the plane z = 0) placed by
//! an affine map ([`Shape`], whose kernel carries the ray into object space), its description, its store
//! and the object-space scale of the twin's rules.

use glam::{DAffine3, DVec3};

use crate::geometry::{Shape, ShapeKind};
use crate::math::{Vec3f, V3};

/// A generic shape placed in the world, in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PlacedDesc {
    /// Places the generic shape in the world (invertible).
    pub(crate) world_from_object: DAffine3,
    /// Index into `SceneDesc::materials`.
    pub(crate) material: u32,
}

impl PlacedDesc {
    /// The shape of kind `kind` in f64, moved by `−origin` (only the translation changes).
    pub(crate) fn shape(&self, kind: ShapeKind, origin: DVec3) -> Shape<f64> {
        let m = DAffine3 {
            matrix3: self.world_from_object.matrix3,
            translation: self.world_from_object.translation - origin,
        };
        Shape::placed(kind, &m, self.material)
    }
}

/// Placed shapes of one kind in rendering space, rounded to f32 once, with their boxes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Placed {
    /// The shapes, in file order.
    pub(crate) shapes: Vec<Shape<f32>>,
    /// Boxes around them (infinite for planes): low and high corners.
    pub(crate) bounds: Vec<(Vec3f, Vec3f)>,
}

impl Placed {
    /// Appends `desc` as a shape of kind `kind` moved by `−origin`, with its box `bounds`.
    pub(crate) fn push(&mut self, kind: ShapeKind, desc: &PlacedDesc, origin: DVec3, bounds: (Vec3f, Vec3f)) {
        self.shapes.push(desc.shape(kind, origin).to_f32());
        self.bounds.push(bounds);
    }
}

/// Sum of the column lengths of a shape's object-from-world map: a bound on how much it stretches any
/// vector (‖L⁻¹·x‖ ≤ this · ‖x‖), so on how far a world-space stray moves the object-space ray.
pub(crate) fn stretch(s: &Shape<f64>) -> f64 {
    s.object_from_world.cols.iter().map(|c| c.length()).sum()
}

/// The scale the object-space coordinates of point `p` are rounded at: `Σ|L⁻¹_i|·(|p_i| + |c_i|)`, the f32
/// map's columns applied to `p − c` (tests/library/stress_*.rs measures it).
pub(crate) fn spread(s: &Shape<f64>, p: V3<f64>) -> f64 {
    let (m, c) = (&s.object_from_world, s.center);
    m.cols[0].length() * (p.x.abs() + c.x.abs())
        + m.cols[1].length() * (p.y.abs() + c.y.abs())
        + m.cols[2].length() * (p.z.abs() + c.z.abs())
}

#[cfg(test)]
impl super::KindDescs {
    /// Appends the generic shape `kind` placed by `world_from_object`, material 0, to its kind's list (the
    /// unit sphere to the ellipsoids, the plane z = 0 to the planes).
    pub(crate) fn push_shape(&mut self, kind: ShapeKind, world_from_object: DAffine3) {
        let desc = PlacedDesc { world_from_object, material: 0 };
        match kind {
            ShapeKind::Sphere => self.ellipsoids.push(desc),
            ShapeKind::Plane => self.planes.push(desc),
        }
    }
}
