//! Whole-pipeline benchmarks at K = 1 (single-ray SIMD), 4, 8 and 16, in rays per second:
//!
//! - `bvh_primary/K`: camera-ray packets through the BVH of a 10 000-sphere contract field (slab tests of
//!   two-child nodes plus leaf sphere tests: the packet/box path).
//! - `shading/K`: a full Whitted render of scenes/whitted.toml at 96×72, one thread (shadow packets,
//!   masked reflection and refraction packets, per-lane material gathers).

mod common;

use std::path::Path;

use bareray::compile::Scene;
use bareray::geometry::DeparturePacket;
use bareray::io::toml;
use bareray::render::{for_each_packet, render, thread_pool, tiles};
use bareray::scene::desc::{Aim, CameraDesc};
use bareray::simd::Lanes;
use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, Throughput};
use glam::DVec3;
use wide::{f32x16, f32x4, f32x8};

fn field_scene() -> Scene {
    let mut desc = common::field_desc(10_000);
    desc.camera = CameraDesc {
        eye: DVec3::new(0.0, 0.0, -4.0),
        aim: Aim::LookAt(DVec3::ZERO),
        width: 192,
        height: 108,
        ..CameraDesc::default()
    };
    Scene::compile(&desc).expect("scene compiles")
}

fn bvh_primary<F: Lanes>(group: &mut BenchmarkGroup<WallTime>, scene: &Scene) {
    let camera = &scene.camera_f64;
    let all = tiles(scene.camera.width, scene.camera.height);
    group.bench_function(BenchmarkId::from_parameter(F::K), |b| {
        b.iter(|| {
            let mut found = 0u32;
            for &tile in &all {
                for_each_packet::<F>(
                    camera,
                    tile,
                    (0.5, 0.5),
                    scene.geometry.culls_by_pyramid(),
                    |rays, _| {
                        let hit = scene.geometry.intersect_k(rays, &DeparturePacket::camera());
                        found += F::move_mask(hit.found()).count_ones();
                    },
                );
            }
            found
        })
    });
}

fn shading<F: Lanes>(group: &mut BenchmarkGroup<WallTime>, scene: &Scene) {
    group.bench_function(BenchmarkId::from_parameter(F::K), |b| {
        let pool = thread_pool(Some(1)).expect("thread pool");
        b.iter(|| render::<F>(scene, &pool, &()).counts.total())
    });
}

fn benches(c: &mut Criterion) {
    let field = field_scene();
    let mut group = c.benchmark_group("bvh_primary");
    group.throughput(Throughput::Elements(u64::from(field.camera.width * field.camera.height)));
    bvh_primary::<f32>(&mut group, &field);
    bvh_primary::<f32x4>(&mut group, &field);
    bvh_primary::<f32x8>(&mut group, &field);
    bvh_primary::<f32x16>(&mut group, &field);
    group.finish();

    let mut desc =
        toml::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml")).expect("demo scene");
    desc.camera.width = 96;
    desc.camera.height = 72;
    let whitted = Scene::compile(&desc).expect("scene compiles");
    let pool = thread_pool(Some(1)).expect("thread pool");
    let rays = render::<f32>(&whitted, &pool, &()).counts.total();
    let mut group = c.benchmark_group("shading");
    group.throughput(Throughput::Elements(rays));
    shading::<f32>(&mut group, &whitted);
    shading::<f32x4>(&mut group, &whitted);
    shading::<f32x8>(&mut group, &whitted);
    shading::<f32x16>(&mut group, &whitted);
    group.finish();
}

criterion_group!(render_benches, benches);
criterion_main!(render_benches);
