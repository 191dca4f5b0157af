//! Accuracy and cost of three f32 ray/sphere formulas on camera rays (PERF.md, "Accuracy").
//!
//! Formulas, each in scalar f32 over the compiled spheres (rendering space: the eye at the origin):
//!
//! - **textbook**: `b = oc·d`, `disc = b² − (d·d)(oc·oc − r²)`, `t = (b ∓ √disc)/(d·d)` (far root when the
//!   near one is behind);
//! - **perpendicular**: `proj = (oc·d)/(d·d)`, `l² = |oc − proj·d|²`, roots `proj ∓ √((r² − l²)/(d·d))`
//!   (Haines et al.; Embree's and pbrt's form);
//! - **eye term**: the renderer's kernel for camera rays, [`SphereRay`] once per ray, then
//!   [`sphere_approach`], [`Approach::roots_from_eye`] with the sphere's exact eye term `c_eye` and the
//!   discriminant chosen by bound (as in a scene with a sphere near the eye), and [`first_root`].
//!
//! The reference is the generic kernel at f64 ([`intersect_sphere::<f64>`]) over the scene file's spheres
//! moved into the scene's rendering space in f64, along the f64 camera rays that the f32 rays are rounded
//! from (a far scene's start short of it, where the eye-term row does not apply: no ray starts at the eye). Every pass is a brute
//! force over the spheres only (shapes and polygons are ignored by all formulas and the reference), closest
//! hit with ties to the lower id (scene-file order: compiled with [`Accel::Brute`]). Reported per scene and
//! formula: pixels whose hit/miss differs from the reference, pixels that hit a different sphere, the relative
//! error of `t` over the pixels hitting the same sphere (nearest-rank percentiles), and nanoseconds per
//! ray-sphere test: the best of 3 timed brute-force passes over all traced pixels × spheres (repeated to at
//! least 1e7 tests), single thread, without any early-out beyond what each formula computes. Scenes with more
//! than 1e8 pixel × sphere tests trace every k-th pixel in both directions (noted in the table).
//!
//! The last row, **f64 on f32 rays**, runs the f64 reference kernel along the f32-rounded camera rays: the
//! disagreements that come from rounding the rays, which no f32 sphere formula can remove.
//!
//! Run: `cargo run --release --example formulas -- scenes/stress/*.toml scenes/stress/*.nff scenes/field1k.xyzr`

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use bareray::accuracy::Percentiles;
use bareray::compile::{Accel, CompileOptions, Scene};
use bareray::geometry::{first_root, intersect_sphere, sphere_approach, Approach, Ray, SphereRay, NO_PRIM};
use bareray::io;
use bareray::kinds::sphere::Spheres;
use bareray::math::V3;

/// Cap on pixel × sphere tests per pass before pixels are subsampled.
const MAX_TESTS: f64 = 1e8;
/// Minimum tests per timed run.
const MIN_TIMED: f64 = 1e7;

/// One f32 ray/sphere formula: per-ray terms, then one test returning (hit in `[0, t_max)`, t).
trait Formula {
    const NAME: &'static str;
    type Pre: Copy;
    fn pre(ray: &Ray<f32>) -> Self::Pre;
    fn test(pre: &Self::Pre, c: V3<f32>, r: f32, c_eye: f32, t_max: f32) -> (bool, f32);
}

struct Textbook;
impl Formula for Textbook {
    const NAME: &'static str = "textbook";
    type Pre = Ray<f32>;
    fn pre(ray: &Ray<f32>) -> Ray<f32> {
        *ray
    }
    #[inline(always)]
    fn test(ray: &Ray<f32>, c: V3<f32>, r: f32, _: f32, t_max: f32) -> (bool, f32) {
        let (d, oc) = (ray.dir, c - ray.origin);
        let (b, dd) = (oc.dot(d), d.dot(d));
        let disc = b * b - dd * (oc.dot(oc) - r * r);
        let sq = disc.sqrt();
        let (near, far) = ((b - sq) / dd, (b + sq) / dd);
        let t = if near >= 0.0 { near } else { far };
        (disc >= 0.0 && t >= 0.0 && t < t_max, t)
    }
}

struct OldPerp;
impl Formula for OldPerp {
    const NAME: &'static str = "perpendicular";
    type Pre = Ray<f32>;
    fn pre(ray: &Ray<f32>) -> Ray<f32> {
        *ray
    }
    /// The perpendicular form with `proj ∓ td`, at f32.
    #[inline(always)]
    fn test(ray: &Ray<f32>, centre: V3<f32>, radius: f32, _: f32, t_max: f32) -> (bool, f32) {
        let d = ray.dir;
        let c = centre - ray.origin;
        let dd = d.dot(d);
        let proj = c.dot(d) / dd;
        let perp = c - d * proj;
        let (l2, r2) = (perp.dot(perp), radius * radius);
        let td = ((r2 - l2) / dd).sqrt();
        let (near, far) = (proj - td, proj + td);
        let t = if near >= 0.0 { near } else { far };
        (l2 <= r2 && t >= 0.0 && t < t_max, t)
    }
}

struct Current;
impl Formula for Current {
    const NAME: &'static str = "eye term";
    type Pre = SphereRay<f32>;
    fn pre(ray: &Ray<f32>) -> SphereRay<f32> {
        SphereRay::new(*ray)
    }
    #[inline(always)]
    fn test(pre: &SphereRay<f32>, c: V3<f32>, r: f32, c_eye: f32, t_max: f32) -> (bool, f32) {
        let line: Approach<f32> = sphere_approach(c, r, pre);
        first_root(&line.roots_from_eye(c_eye, true), t_max)
    }
}

/// Closest hit of `ray` over every sphere: (id or [`NO_PRIM`], t); the strict `<` keeps the lower id on ties.
#[inline(never)]
fn closest<F: Formula>(s: &Spheres, ray: &Ray<f32>) -> (u32, f32) {
    let pre = F::pre(ray);
    let (mut id, mut best) = (NO_PRIM, f32::INFINITY);
    for i in 0..s.len() {
        let (hit, t) = F::test(&pre, V3::new(s.cx[i], s.cy[i], s.cz[i]), s.r[i], s.c_eye[i], best);
        if hit {
            (id, best) = (i as u32, t);
        }
    }
    (id, best)
}

/// Pixels whose hit/miss differs, pixels hitting another sphere, and relative t errors where both agree.
type Stats = (usize, usize, Percentiles);

fn compare(hits: impl Iterator<Item = (u32, f64)>, reference: &[(u32, f64)]) -> Stats {
    let (mut hit_miss, mut id, mut errs) = (0, 0, Vec::new());
    for ((fid, ft), &(rid, rt)) in hits.zip(reference) {
        if (fid == NO_PRIM) != (rid == NO_PRIM) {
            hit_miss += 1;
        } else if fid != rid {
            id += 1;
        } else if fid != NO_PRIM {
            errs.push((ft - rt).abs() / rt);
        }
    }
    (hit_miss, id, Percentiles::of(errs))
}

/// The formula's [`Stats`] against `reference` and its time per ray-sphere test in ns.
fn measure<F: Formula>(
    s: &Spheres,
    rays: &[Ray<f32>],
    reference: &[(u32, f64)],
) -> (&'static str, Stats, f64) {
    let stats =
        compare(rays.iter().map(|ray| closest::<F>(s, ray)).map(|(id, t)| (id, f64::from(t))), reference);
    let tests = (rays.len() * s.len()).max(1) as f64;
    let reps = (MIN_TIMED / tests).ceil().max(1.0) as usize;
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut sum = 0u32;
        for _ in 0..reps {
            let (s, rays) = (black_box(s), black_box(rays));
            for ray in rays {
                sum = sum.wrapping_add(closest::<F>(s, black_box(ray)).0);
            }
        }
        black_box(sum);
        best = best.min(start.elapsed().as_secs_f64());
    }
    (F::NAME, stats, best * 1e9 / (tests * reps as f64))
}

fn main() -> anyhow::Result<()> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(!paths.is_empty(), "usage: formulas SCENE...");
    println!("| scene | spheres | pixels traced | ref hits | formula | hit/miss ≠ | id ≠ | rel t err p50 | p99 | max | ns/test |");
    println!("| --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    let sci = |x: f64| match x {
        _ if x.is_nan() => "–".to_string(),
        0.0 => "0".to_string(),
        _ => format!("{x:.1e}"),
    };
    for path in &paths {
        let desc = io::load(Path::new(path))?;
        let scene = Scene::compile_with_options(
            &desc,
            CompileOptions { accel: Accel::Brute, ..CompileOptions::default() },
        )?;
        let s = &scene.geometry.spheres;
        assert!(s.key.iter().enumerate().all(|(i, &k)| k as usize == i), "storage order is not file order");
        let mut name = Path::new(path).file_name().unwrap().to_string_lossy().into_owned();
        let ignored = desc.kinds.len();
        if ignored > 0 {
            name += &format!(" ({ignored} non-sphere primitive(s) ignored)");
        }
        let cam = &scene.camera_f64;
        let (w, h) = (cam.width, cam.height);
        let full = f64::from(w) * f64::from(h) * s.len() as f64;
        let stride = (full / MAX_TESTS).sqrt().ceil().max(1.0) as usize;
        // In the scene's rendering space (the eye, or a far scene's centre, at the origin), as its rays.
        let origin = scene.origin;
        let spheres64: Vec<(V3<f64>, f64)> =
            desc.spheres.iter().map(|sp| (V3::from(sp.center - origin), sp.radius)).collect();
        let closest64 = |ray: &Ray<f64>| {
            let (mut id, mut best) = (NO_PRIM, f64::INFINITY);
            for (k, &(c, r)) in spheres64.iter().enumerate() {
                let (hit, t) = intersect_sphere::<f64>(c, r, ray, best);
                if hit {
                    (id, best) = (k as u32, t);
                }
            }
            (id, best)
        };
        let (mut rays, mut reference, mut floor) = (Vec::new(), Vec::new(), Vec::new());
        for j in (0..h).step_by(stride) {
            for i in (0..w).step_by(stride) {
                let (sx, sy) = (i as f32 + 0.5, j as f32 + 0.5);
                let ray = cam.ray_f32(sx, sy);
                reference.push(closest64(&cam.ray(f64::from(sx), f64::from(sy))));
                floor.push(closest64(&Ray::new(ray.origin.to_f64(), ray.dir.to_f64())));
                rays.push(ray);
            }
        }
        let ref_hits = reference.iter().filter(|r| r.0 != NO_PRIM).count();
        let every = if stride > 1 { format!("every {stride}th of ") } else { String::new() };
        let rows = [
            measure::<Textbook>(s, &rays, &reference),
            measure::<OldPerp>(s, &rays, &reference),
            measure::<Current>(s, &rays, &reference),
            ("f64 on f32 rays", compare(floor.into_iter(), &reference), f64::NAN),
        ];
        for (k, (formula, (hit_miss, id, err), ns)) in rows.iter().enumerate() {
            let head = match k {
                0 => format!("{name} | {} | {} ({every}{w}×{h}) | {ref_hits}", s.len(), rays.len()),
                _ => " | | |".into(),
            };
            let ns = if ns.is_nan() { "–".into() } else { format!("{ns:.2}") };
            let (p50, p99, max) = (sci(err.p50), sci(err.p99), sci(err.max));
            println!("| {head} | {formula} | {hit_miss} | {id} | {p50} | {p99} | {max} | {ns} |");
        }
    }
    Ok(())
}
