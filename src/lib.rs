//! bareray: a data-oriented SIMD packet ray tracer.
//!
//! Data flow (see ARCHITECTURE.md): a scene file (TOML, NFF or xyzr) is read by [`io`] into a plain
//! [`scene::SceneDesc`], compiled by [`compile`] into an immutable [`compile::Scene`] (SoA spheres, BVH),
//! rendered tile by tile ([`render`]) in packets of K rays by Whitted shading ([`shade`]) over the packet
//! queries of [`accel`], whose kernels live in [`geometry`], into a [`film::Image`] that [`output`] writes.
//! Everything on the ray path is generic over the lane type ([`simd::Lanes`]); K = 1 is the scalar reference
//! path, and every width gives the same bits. Modules are layered (ARCHITECTURE.md, "Layers"; checked by
//! `tests/layers.rs`): each imports only layers below its own.

pub mod accel;
pub mod accuracy;
pub mod aov;
pub mod camera;
pub mod cli;
pub mod compile;
pub mod converge;
pub mod cpu;
pub mod film;
pub mod geometry;
pub mod huge_pages;
pub mod imagediff;
pub mod io;
pub mod math;
pub mod output;
pub mod render;
pub mod sample;
pub mod scene;
pub mod shade;
pub mod simd;
