//! The tests of the library's items, kernels and invariants, compiled into the library's own test build
//! (`src/lib.rs` includes this folder under `cfg(test)`), so that they reach crate-private items. They name
//! the library `bareray::` as a user would (`lib.rs` declares `extern crate self as bareray` for tests).
//! Run one file's tests with `cargo test --lib NAME::`, e.g. `cargo test --lib stress_acne::`.

mod common;

mod accuracy;
mod ao;
mod bench_kinds;
mod bvh;
mod camera;
mod cones;
mod coverage;
mod far_scenes;
mod fuzz_particles;
mod fuzz_readers;
mod headlight;
mod light_buffers;
mod packet_kernels;
mod particle_files;
mod particles;
mod random_scenes;
mod readers;
mod render;
mod scene_toml;
mod stills;
mod stress_acne;
mod stress_departure;
mod stress_discriminant;
mod stress_f64_oracle;
mod tori;
