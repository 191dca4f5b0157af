//! bareray: a data-oriented SIMD packet ray tracer.
//!
//! It renders scenes of spheres, transformed quadrics, polygons and cones by Whitted ray tracing (shadows,
//! mirrors, glass) in packets of 4, 8 or 16 rays through a 4-wide BVH, and every packet width gives the
//! same bits as single rays (K = 1) and as the scalar path (binary BVHs, one box and one primitive at a
//! time, [`compile::CompileOptions::scalar`]). The same compiled scene also answers ray queries: closest
//! hit and occlusion, one ray or K at a time.
//!
//! # Data flow
//!
//! 1. [`io::load`] reads a scene file (TOML, NFF or xyzr) into a [`scene::SceneDesc`]: plain data in f64,
//!    which can also be built or changed in code.
//! 2. [`compile::Scene::compile`] turns the description into the immutable [`compile::Scene`] every render
//!    thread shares: camera frame, spheres in SoA arrays, BVHs ([`accel::Geometry`]).
//! 3. [`render::render_lanes`] traces it tile by tile on a thread pool, in packets of K camera rays shaded by
//!    `shade`, reporting finished tiles to a [`render::Progress`], into a [`film::Image`] of linear RGB.
//! 4. [`output::write_image`] writes the image as PNG, PPM, EXR or HDR, chosen by the file's extension.
//!    For images of any size, [`still::render`] does 3 and 4 band by band, streaming each finished band
//!    into the file (memory: the scene and a few bands), for the whole image or a region of it;
//!    [`still::check`] first refuses what cannot work (sizes, memory, disk, paths).
//!
//! Rays can be traced without rendering: [`accel::Geometry::intersect`] for one ray,
//! [`accel::Geometry::intersect_k`] for a [`geometry::RayPacket`] of K.
//!
//! Everything on the ray path is generic over the lane type ([`simd::Lanes`]: `f32` and `wide`'s `f32x4`,
//! `f32x8`, `f32x16`). Modules are layered (ARCHITECTURE.md, "Layers"; checked by `tests/layers.rs`): each
//! imports only layers below its own.
//!
//! # Example
//!
//! Read a scene, compile it, render it with a progress callback, write it:
//!
//! ```
//! use std::path::Path;
//!
//! use bareray::{compile::Scene, io, output, render};
//!
//! // Read a scene (.toml, .nff or .xyzr) into plain data, and change it as you like.
//! let mut desc = io::load(Path::new("scenes/whitted.toml"))?;
//! (desc.camera.width, desc.camera.height) = (160, 120);
//!
//! // One thread pool for the run (`None`: all cores); compiling builds the BVH on it.
//! let pool = render::thread_pool(None)?;
//! let scene = pool.install(|| Scene::compile(&desc))?;
//!
//! // Packets of 8 rays (1, 4, 8 or 16: every width gives the same bits); `&()` reports nothing.
//! let done = render::render_lanes(&scene, 8, &pool, &|done: u64, total: u64| {
//!     eprint!("\r{done}/{total} tiles");
//! });
//! println!("{} rays in {:.3} s", done.counts.total(), done.seconds);
//!
//! let path = std::env::temp_dir().join("bareray-crate-doc.png");
//! output::write_image(&done.image, &path, scene.render.transfer)?;
//! # std::fs::remove_file(&path)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! `examples/` holds complete programs: rendering a file, building a sphere field in code, tracing rays of
//! your own.

#![deny(missing_docs)]

pub mod accel;
pub mod accuracy;
pub mod aov;
pub mod api;
pub mod bench;
pub(crate) mod bvh;
pub mod camera;
pub mod compile;
pub mod converge;
pub mod film;
pub mod geometry;
pub mod imagediff;
pub mod io;
pub mod kinds;
pub mod math;
pub mod output;
pub mod render;
pub(crate) mod sample;
pub mod scene;
pub mod settings;
pub(crate) mod shade;
pub mod simd;
pub mod still;

// The tests of the library's items (tests/library/) name it `bareray::`, as a user would, and reach its
// crate-private items.
#[cfg(test)]
extern crate self as bareray;
#[cfg(test)]
#[path = "../tests/library/mod.rs"]
mod library_tests;
