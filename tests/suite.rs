//! The integration tests, compiled as one binary: each file of `tests/` is a module here, so the library's
//! generic kernels are instantiated and optimised once for all of them, not once per file, and one link
//! serves every file. Run one file's tests with `cargo test --test suite NAME::`, e.g.
//! `cargo test --test suite layers::`. The MPI tests (`tests/mpi.rs`, feature `mpi`) stay a binary of their own.

mod common;

#[path = "accuracy.rs"]
mod accuracy;
#[path = "ao.rs"]
mod ao;
#[path = "bench_kinds.rs"]
mod bench_kinds;
#[path = "bvh.rs"]
mod bvh;
#[path = "camera.rs"]
mod camera;
#[path = "cli.rs"]
mod cli;
#[path = "cones.rs"]
mod cones;
#[path = "coverage.rs"]
mod coverage;
#[path = "far_scenes.rs"]
mod far_scenes;
#[path = "fuzz_merge.rs"]
mod fuzz_merge;
#[path = "fuzz_particles.rs"]
mod fuzz_particles;
#[path = "fuzz_readers.rs"]
mod fuzz_readers;
#[path = "layers.rs"]
mod layers;
#[path = "packet_kernels.rs"]
mod packet_kernels;
#[path = "particle_files.rs"]
mod particle_files;
#[path = "particles.rs"]
mod particles;
#[path = "random_scenes.rs"]
mod random_scenes;
#[path = "readers.rs"]
mod readers;
#[path = "render.rs"]
mod render;
#[path = "scene_toml.rs"]
mod scene_toml;
#[path = "sphere_colors.rs"]
mod sphere_colors;
#[path = "stills.rs"]
mod stills;
#[path = "stress_acne.rs"]
mod stress_acne;
#[path = "stress_departure.rs"]
mod stress_departure;
#[path = "stress_discriminant.rs"]
mod stress_discriminant;
#[path = "stress_f64_oracle.rs"]
mod stress_f64_oracle;
#[path = "tori.rs"]
mod tori;
