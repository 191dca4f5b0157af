//! Brute-force sphere kernels at K = 1 (one ray, plain f32), 4, 8 and 16, in rays per second:
//!
//! - `packet_vs_spheres/K`: packets of K camera rays against every sphere (lanes = rays).
//! - `ray_vs_spheres/K`: one camera ray against K spheres at a time (lanes = spheres).
//!
//! The scene is the peer benchmark's sphere field (splitmix64, DESIGN.md) with 64 spheres in [-1, 1]³, seen
//! by its camera at 64×64 pixels: most rays hit something.

use std::hint::black_box;

use bareray::camera::Camera;
use bareray::geometry::{Ray, RayPacket};
use bareray::io::generate::FieldParams;
use bareray::kinds::sphere::{intersect_spheres_1, intersect_spheres_k, Spheres};
use bareray::math::V3;
use bareray::scene::desc::{Aim, CameraDesc};
use bareray::simd::{IdLanes, Lanes};
use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, Throughput};
use glam::DVec3;
use wide::{f32x16, f32x4, f32x8};

const SPHERES: usize = 64;
const SIDE: u32 = 64;

/// The contract field of `n` spheres, from bareray's own generator.
fn sphere_field(n: usize) -> Spheres {
    let params = FieldParams { count: n as u64, ..FieldParams::default() };
    let mut spheres = Spheres::default();
    for [x, y, z, r] in params.spheres().expect("valid field") {
        spheres.push(V3::new(x, y, z), r, 0);
    }
    spheres
}

fn camera_rays() -> Vec<Ray<f32>> {
    let desc = CameraDesc {
        eye: DVec3::new(0.0, 0.0, -4.0),
        aim: Aim::LookAt(DVec3::ZERO),
        width: SIDE,
        height: SIDE,
        ..CameraDesc::default()
    };
    let camera = Camera::new(&desc).expect("valid camera").to_f32();
    (0..SIDE * SIDE).map(|p| camera.ray((p % SIDE) as f32 + 0.5, (p / SIDE) as f32 + 0.5)).collect()
}

/// Lanes = rays: the rays regrouped into packets once, outside the timed loop.
fn packet_vs_spheres<F: Lanes>(group: &mut BenchmarkGroup<WallTime>, spheres: &Spheres, rays: &[Ray<f32>]) {
    let packets: Vec<RayPacket<F>> =
        rays.chunks(F::K).map(|c| RayPacket::from_rays(c, f32::INFINITY)).collect();
    group.bench_function(BenchmarkId::new("packet_vs_spheres", F::K), |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for packet in &packets {
                let h = intersect_spheres_k(black_box(spheres), black_box(packet));
                hits = hits.wrapping_add(h.prim.lane(0));
            }
            hits
        })
    });
}

/// Lanes = spheres.
fn ray_vs_spheres<F: Lanes>(group: &mut BenchmarkGroup<WallTime>, spheres: &Spheres, rays: &[Ray<f32>]) {
    group.bench_function(BenchmarkId::new("ray_vs_spheres", F::K), |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for ray in rays {
                let h = intersect_spheres_1::<F>(black_box(spheres), black_box(ray), f32::INFINITY);
                hits = hits.wrapping_add(h.prim);
            }
            hits
        })
    });
}

fn kernels(c: &mut Criterion) {
    let spheres = sphere_field(SPHERES);
    let rays = camera_rays();
    let mut group = c.benchmark_group(format!("{SPHERES}_spheres"));
    group.throughput(Throughput::Elements(rays.len() as u64));
    packet_vs_spheres::<f32>(&mut group, &spheres, &rays);
    packet_vs_spheres::<f32x4>(&mut group, &spheres, &rays);
    packet_vs_spheres::<f32x8>(&mut group, &spheres, &rays);
    packet_vs_spheres::<f32x16>(&mut group, &spheres, &rays);
    ray_vs_spheres::<f32>(&mut group, &spheres, &rays);
    ray_vs_spheres::<f32x4>(&mut group, &spheres, &rays);
    ray_vs_spheres::<f32x8>(&mut group, &spheres, &rays);
    ray_vs_spheres::<f32x16>(&mut group, &spheres, &rays);
    group.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
