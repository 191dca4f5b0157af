//! Where the rendering space's origin is, and where camera rays start.
//!
//! f32 resolves a coordinate to about ε32 = 2⁻²⁴ of its magnitude, so the geometry is as fine as its distance
//! from the rendering space's origin allows. With the origin at the eye (the usual frame) that is the
//! distance from the eye: right for what the camera sees near it, too coarse for a scene far away — a
//! cluster of spheres 10⁶ from the eye is stored in steps of 0.06, wider than gaps of a few hundredths
//! between them, and every reflection off it starts from a point that coarse.
//!
//! When every primitive is bounded and the eye lies more than [`FAR_RATIO`] times the geometry's bounding
//! radius R from its centre C, the frame moves: the origin goes to C, so every stored coordinate is at most R
//! in magnitude, and camera rays start at the distance [`RenderingFrame::start`] = |eye − C| − R·(1 + 2⁻¹⁰)
//! along their exact f64 direction, just short of the bounding sphere, rounded once to f32 there. A ray
//! that can reach the geometry then starts within about 1.5R of C and crosses it within about 2R, so its
//! error there (the origin's rounding and the direction's over that length) is of order ε32·R instead of
//! ε32·|eye − C|: a scene far from the eye is resolved about as finely as it would be near it. Such rays
//! share no apex, so camera packets are not culled by a frustum there.
//!
//! Otherwise (something unbounded such as a plane, or the eye within [`FAR_RATIO`]·R) the origin stays at
//! the eye and camera rays start at exactly zero, which lets spheres carry exact eye terms.

use glam::DVec3;

use crate::geometry::box_union;
use crate::kinds::sphere::sphere_bounds;
use crate::scene::desc::SceneDesc;

/// The eye must be this many bounding radii from the geometry's centre for the frame to move there: the
/// gain in resolution is about this over 3 (the origin's and the direction's roundings above), so the frame
/// moves only where it gains more than an order of magnitude.
pub(crate) const FAR_RATIO: f64 = 64.0;

/// Camera rays start this fraction of R short of the bounding sphere: more than the start point's f64
/// rounding (about 2⁻⁵³·|eye − C|) wherever |eye − C| < 2⁴³·R.
const START_MARGIN: f64 = 1.0 / 1024.0;

/// The rendering space of a compiled scene (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RenderingFrame {
    /// The rendering space's origin in world space: the eye, or the centre of a far scene's bounds.
    pub(crate) origin: DVec3,
    /// How far from the eye camera rays start: 0, or |eye − C| − R·(1 + 2⁻¹⁰) for a far scene.
    pub(crate) start: f64,
}

impl RenderingFrame {
    /// The frame for `desc`, with `extra` the world box of spheres compiled apart (a mapped field's).
    pub(crate) fn of(desc: &SceneDesc, extra: Option<[DVec3; 2]>) -> Self {
        let eye = desc.camera.eye;
        let at_eye = Self { origin: eye, start: 0.0 };
        let unbounded = desc.kinds.has_unbounded();
        let Some((lo, hi)) = bounded_box(desc, extra).filter(|_| !unbounded) else {
            return at_eye;
        };
        let centre = (lo + hi) * 0.5;
        let radius = (hi - lo).length() * 0.5;
        let distance = (eye - centre).length();
        if distance <= FAR_RATIO * radius || !distance.is_finite() || radius.is_nan() {
            return at_eye;
        }
        Self { origin: centre, start: distance - radius * (1.0 + START_MARGIN) }
    }

    /// Whether camera rays start away from the eye.
    #[cfg(test)]
    pub(crate) fn is_far(&self) -> bool {
        self.start != 0.0
    }
}

/// The box around every bounded primitive and the box `extra`, in f64 world space (`None` without any):
/// spheres, polygons and the registered kinds' bounded items (ellipsoids, cones, tori; not planes).
pub(crate) fn bounded_box(desc: &SceneDesc, extra: Option<[DVec3; 2]>) -> Option<(DVec3, DVec3)> {
    let spheres = sphere_bounds(&desc.spheres);
    let kinds = desc.kinds.world_boxes().into_iter().flatten();
    let (lo, hi) = kinds.chain(extra.into_iter().flatten()).map(|p| (p, p)).fold(spheres, box_union);
    lo.cmple(hi).all().then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ShapeKind;
    use crate::kinds::sphere::SphereDesc;

    /// Two touching unit spheres at `centre ± (1, 0, 0)` seen from `eye`.
    fn pair(eye: DVec3, centre: DVec3) -> SceneDesc {
        let mut desc = SceneDesc::default();
        desc.camera.eye = eye;
        for dx in [-1.0, 1.0] {
            desc.spheres.push(SphereDesc { center: centre + DVec3::X * dx, radius: 1.0, material: 0 });
        }
        desc
    }

    #[test]
    fn a_scene_near_the_eye_keeps_the_eye_as_origin() {
        let eye = DVec3::new(1e6, -2e6, 3e6);
        // The bounding radius is √(4 + 4 + 4)/2 ≈ 1.73; 64 of them is about 111.
        let frame = RenderingFrame::of(&pair(eye, eye + DVec3::new(0.0, 0.0, 100.0)), None);
        assert_eq!(frame, RenderingFrame { origin: eye, start: 0.0 });
        assert!(!frame.is_far());
    }

    #[test]
    fn a_far_scene_is_centred_and_rays_start_short_of_it() {
        let eye = DVec3::new(3.25, 1.75, -2.5);
        let centre = eye + DVec3::new(0.48, 0.6, 0.64) * 1e6;
        let desc = pair(eye, centre);
        let frame = RenderingFrame::of(&desc, None);
        assert_eq!(frame.origin, centre);
        assert!(frame.is_far());
        // No sphere is nearer the eye than where rays start, and they start within 2R of the nearest.
        let nearest =
            desc.spheres.iter().map(|s| (s.center - eye).length() - s.radius).fold(f64::MAX, f64::min);
        let radius = 3f64.sqrt();
        assert!(frame.start < nearest && frame.start > nearest - 2.0 * radius, "{frame:?} {nearest}");
    }

    #[test]
    fn an_unbounded_primitive_keeps_the_eye_as_origin() {
        let eye = DVec3::ZERO;
        let mut desc = pair(eye, DVec3::new(0.0, 0.0, 1e6));
        assert!(RenderingFrame::of(&desc, None).is_far());
        let plane = glam::DAffine3::from_translation(DVec3::new(0.0, 0.0, 1e6));
        desc.kinds.push_shape(ShapeKind::Plane, plane);
        assert_eq!(RenderingFrame::of(&desc, None), RenderingFrame { origin: eye, start: 0.0 });
    }

    #[test]
    fn a_mapped_fields_box_counts() {
        let eye = DVec3::ZERO;
        let desc = pair(eye, DVec3::new(0.0, 0.0, 1e6));
        // A field around the eye: the scene is no longer far.
        let field = [DVec3::splat(-10.0), DVec3::splat(10.0)];
        assert!(!RenderingFrame::of(&desc, Some(field)).is_far());
    }
}
