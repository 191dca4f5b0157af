//! The packets that trace a level's new lattice points: K points a ray packet, each with its pyramid, and
//! up to [`crate::bvh::MAX_PACKETS`] ray packets walking the tree as one large packet.

use crate::accel::{traced, RayKind};
use crate::compile::Scene;
use crate::geometry::RayPacket;
use crate::render::{lane_rgb, Tile};
use crate::shade::Tracer;
use crate::simd::{IdLanes, Lanes};

use super::lattice::Lattice;
use super::Point;

/// Reusable buffers for one large packet of lattice points.
pub(super) struct Packets<F: Lanes> {
    rays: Vec<RayPacket<F>>,
    hits: Vec<crate::geometry::HitPacket<F>>,
}

impl<F: Lanes> Default for Packets<F> {
    fn default() -> Self {
        Self { rays: Vec::new(), hits: Vec::new() }
    }
}

impl<F: Lanes> Packets<F> {
    /// Traces `points` (lattice points of `tile`, `unit` steps a pixel) in the order given, K at a time, each
    /// packet with the pyramid of its points and [`crate::bvh::MAX_PACKETS`] packets as one large packet, and
    /// stores their colours and ids in `lattice`. A point's position is `x0 + p·2^-depth`, the same bits from
    /// whichever tile shares it.
    /// `FAR` says whether the camera's rays start away from the eye
    /// ([`Camera::rays_in`](crate::camera::Camera::rays_in)).
    pub(super) fn trace<const FAR: bool>(
        &mut self,
        scene: &Scene,
        tracer: &mut Tracer<F>,
        tile: Tile,
        unit: u32,
        points: &[(u32, u32)],
        lattice: &mut Lattice,
    ) {
        let camera = &scene.camera_f64;
        let pyramids = scene.geometry.culls_by_pyramid() && F::K > 1;
        let step = 1.0 / unit as f32;
        // A coordinate's range over a chunk's points, from its extreme points: `x0 + p·step` rounds
        // monotonically in p, so these are the extremes of the lanes' values.
        let range = |chunk: &[(u32, u32)], coordinate: fn(&(u32, u32)) -> u32, x0: u32| {
            let (lo, hi) =
                chunk.iter().map(coordinate).fold((u32::MAX, 0), |(lo, hi), c| (lo.min(c), hi.max(c)));
            [x0 as f32 + lo as f32 * step, x0 as f32 + hi as f32 * step]
        };
        for group in points.chunks(F::K * crate::bvh::MAX_PACKETS) {
            self.rays.clear();
            let (mut xs, mut ys) = ([f32::INFINITY, f32::NEG_INFINITY], [f32::INFINITY, f32::NEG_INFINITY]);
            for chunk in group.chunks(F::K) {
                // Lanes past the chunk's end repeat its last point (inactive, and inside its pyramid).
                let at = |i: usize| chunk[i.min(chunk.len() - 1)];
                let sx = F::from_fn(|i| tile.x0 as f32 + at(i).0 as f32 * step);
                let sy = F::from_fn(|i| tile.y0 as f32 + at(i).1 as f32 * step);
                let ray = camera.rays_in::<F, FAR>(sx, sy);
                let (rx, ry) = (range(chunk, |p| p.0, tile.x0), range(chunk, |p| p.1, tile.y0));
                (xs, ys) = ([xs[0].min(rx[0]), xs[1].max(rx[1])], [ys[0].min(ry[0]), ys[1].max(ry[1])]);
                let pyramid = pyramids.then(|| camera.pyramid(rx, ry)).flatten();
                let active = F::lanes_below(chunk.len());
                self.rays.push(RayPacket {
                    pyramid,
                    ..RayPacket::new(ray.origin, ray.dir, F::splat_f32(f32::INFINITY), active)
                });
            }
            let pyramid = pyramids.then(|| camera.pyramid(xs, ys)).flatten();
            self.hits.resize(self.rays.len(), crate::geometry::HitPacket::miss());
            let (rays, hits) = (&self.rays, &mut self.hits);
            traced(RayKind::Camera, || scene.geometry.intersect_tile(rays, pyramid.as_ref(), hits));
            for ((rays, hit), chunk) in self.rays.iter().zip(&self.hits).zip(group.chunks(F::K)) {
                let c = tracer.primary_from(rays, *hit);
                let (keys, ts) = (IdLanes::to_array(hit.key), hit.t.to_array());
                for (i, &p) in chunk.iter().enumerate() {
                    let (key, t) = (keys.as_ref()[i], ts.as_ref()[i]);
                    lattice.set(p, Point { colour: lane_rgb(&c, i), key, t });
                }
            }
        }
    }
}
