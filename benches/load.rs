//! Loading and building, on the global thread pool (all cores), in spheres per second:
//!
//! - `load/nff_balls5`: SPD balls at size 5 (66 430 spheres, about 5 MB of NFF text) parsed from memory, in
//!   pieces on the pool.
//! - `build/field_1e5`: a 100 000-sphere contract field compiled: the rendering-space sphere arrays and the
//!   SAH tree over them.

mod common;

use std::path::Path;

use bareray::compile::Scene;
use bareray::io::generate::flake_nff;
use bareray::io::nff;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn benches(c: &mut Criterion) {
    let text = flake_nff(5).expect("balls 5");
    let spheres = nff::parse(Path::new("balls5.nff"), &text).expect("balls 5 parses").spheres.len();
    let mut group = c.benchmark_group("load");
    group.throughput(Throughput::Elements(spheres as u64));
    group.bench_function("nff_balls5", |b| {
        b.iter(|| nff::parse(Path::new("balls5.nff"), &text).expect("parses").spheres.len())
    });
    group.finish();

    let desc = common::field_desc(100_000);
    let mut group = c.benchmark_group("build");
    group.throughput(Throughput::Elements(desc.spheres.len() as u64));
    group.sample_size(20);
    group.bench_function("field_1e5", |b| {
        b.iter(|| Scene::compile(&desc).expect("compiles").bytes_per_sphere())
    });
    group.finish();
}

criterion_group!(load_benches, benches);
criterion_main!(load_benches);
