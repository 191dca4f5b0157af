//! bareray: a data-oriented SIMD packet ray tracer.
//!
//! Data flow (see ARCHITECTURE.md): a scene file is read into a plain [`scene::SceneDesc`], compiled into an
//! immutable [`scene::Scene`], rendered tile by tile ([`render`]) by Whitted shading ([`shade`]) over the
//! intersection queries of [`accel`], whose kernels live in [`geometry`], into a [`film::Image`] that
//! [`output`] writes.

pub mod accel;
pub mod aov;
pub mod camera;
pub mod cli;
pub mod film;
pub mod geometry;
pub mod math;
pub mod output;
pub mod render;
pub mod sample;
pub mod scene;
pub mod shade;
pub mod simd;
