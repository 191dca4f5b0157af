//! `bareray accuracy`: the f32 renderer against an f64 twin of the same scene, ray by ray.
//!
//! Every primary ray (one per pixel centre) is traced by the renderer's own primary-hit pass
//! (`crate::render::trace_primary_lanes`, packets of K) and by the `Twin`, an independent f64 tracer
//! over the exact [`SceneDesc`] in camera-relative space with unrounded f64 camera rays. Only
//! frame-independent quantities are compared: hit or miss, scene-file primitive id, t (rays have unit
//! directions in both), and occlusion. With secondary rays, each precision builds its own Whitted rays from
//! its own hit wherever the two primary hits agree on the primitive: one shadow ray per light that faces
//! the surface, compared as occluded booleans, the mirror ray (every hit, whatever its material), compared
//! like a primary ray, and on transmitting materials the refraction ray (where both precisions refract;
//! total internal reflection in one precision only is a disagreement of its own, `tir_disagree`), compared
//! like a primary ray.
//!
//! A disagreement is *explained* when rounding can account for it; the tolerances are multiples of
//! ε32 = 2⁻²⁴ (`EPS32`) of the magnitudes involved, with the constants below:
//!
//! - **graze** (`K_GRAZE`): the ray passes within tolerance of tangency with either primitive
//!   (`Twin::grazing`: spheres, ellipsoids in object space, planes within k·ε32 of parallel, polygon
//!   outlines, cones near tangency or with a hit near an end rim);
//! - **tie** (`K_TIE`): both primitives are hit in f64 within `K_TIE·ε32·(|o| + t)` of each other, times
//!   how fast a moved ray's hits move apart (1 head on, the inverse cosines at a slant: `Twin::tie`);
//! - **start** (`K_START`, secondary rays): the ray starts within tolerance of either primitive's surface
//!   (`Twin::near_surface`: contact points of touching spheres, a ray leaving one cone where another's
//!   wall or rim is);
//! - **light** (`K_START`, shadow rays): the light lies within tolerance of the blocker's surface;
//! - **facing** (`K_GRAZE`, shadow rays): the light is in front of the surface in one precision only and
//!   within `K_GRAZE·ε32` of its tangent plane (|cos| in f64);
//! - **diverge** (secondary rays): none of the above at their own tolerances, but each holds once the
//!   tolerances grow by how far the f32 ray actually strays from the f64 one (origins and directions differ
//!   because each starts from its own hit point along its own normal, `Slack`): the primary hit's error
//!   carried forward, not a fault of the secondary query.
//!
//! Anything else is *unexplained*. A *self-hit* is a secondary ray whose hit (or shadow blocker) in f32 is
//! its departure primitive itself, or lies within `K_SELF·ε32·|o|` of its origin, while in f64 it is not
//! (both hitting the same other primitive is agreement; the twin's own near hit is a surface the exact ray
//! meets there, and the f32 contact rule's entry into a sphere is no re-hit: `is_self_hit`); a ray leaving a
//! solid inward (refraction into glass, any ray from an inside hit) meets the solid's far side, so for it
//! only a hit within `K_SELF·ε32·|o|` counts. Relative t errors `|t32 − t64| / t64` are taken over rays whose two
//! hits agree on the primitive; percentiles are nearest-rank: the p-th of n sorted values is the
//! ⌈p·n⌉-th.

pub(crate) mod bvh64;
mod hit64;
mod report;
mod secondary;
pub(crate) mod twin;

use report::Reason;
pub use report::{Example, Percentiles, Report};
pub(crate) use report::{Explained, HitStats, ShadowStats};

use std::time::Instant;

use anyhow::Result;
use rayon::prelude::*;

use crate::compile::{CompileOptions, Scene};
use crate::geometry::{at_eye, Departure, Ray, NO_PRIM};
use crate::math::V3;
use crate::render::{thread_pool, trace_primary_lanes, PrimaryHits};
use crate::scene::SceneDesc;

pub(crate) use twin::{Hit64, Slack, Twin, EPS32};

/// Tolerance of the "graze" and "facing" explanations, in ε32 of the magnitudes involved (tests/library/stress_f64_oracle.rs's).
pub(crate) const K_GRAZE: f64 = 16.0;
/// Tolerance of the "tie" explanation, in ε32 of `|o| + t` (tests/library/stress_f64_oracle.rs's).
pub(crate) const K_TIE: f64 = 64.0;
/// Tolerance of the "start" and "light" explanations, in ε32 of the magnitudes involved.
pub(crate) const K_START: f64 = 16.0;
/// Distance from the origin within which a secondary ray's hit counts as a self-hit, in ε32 of `|o|` (the
/// origin's distance from the eye): the f32 origin's own rounding (at most half an ulp per coordinate,
/// about `1.7·ε32·|o|`) with room. A hit farther away is a hit on something else, compared as such.
pub(crate) const K_SELF: f64 = 4.0;

/// What to measure.
#[derive(Clone, Debug)]
pub struct Options {
    /// Packet width of the f32 primary pass: 1, 4, 8 or 16.
    pub lanes: usize,
    /// Compile the f32 scene for the scalar path ([`crate::compile::CompileOptions::scalar`]): with `lanes`
    /// 1, every f32 ray walks binary BVHs one box and one primitive at a time.
    pub scalar: bool,
    /// Also compare shadow, mirror and refraction rays.
    pub secondary: bool,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Unexplained disagreements and self-hits to keep as examples, per kind.
    pub max_examples: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self { lanes: 16, scalar: false, secondary: false, threads: None, max_examples: 8 }
    }
}

/// Compiles `desc` for the f32 renderer and builds its f64 `Twin`, then compares them (`compare`).
/// `name` labels the report. Fails only on a camera that cannot form an image (or a thread pool that cannot
/// start).
pub fn run(name: &str, desc: &SceneDesc, opts: &Options) -> Result<Report> {
    let start = Instant::now();
    let pool = thread_pool(opts.threads)?;
    let options = CompileOptions { scalar: opts.scalar, ..CompileOptions::default() };
    let compile = || Scene::compile_with_options(desc, options);
    let (scene, twin) = pool.install(|| rayon::join(compile, || Twin::new(desc)));
    let mut report = compare(name, &scene?, &twin?, opts, &pool);
    report.seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

/// Compares the compiled f32 `scene` with its `twin` (both from one [`SceneDesc`]) on `pool`: every pixel
/// centre's primary ray, and with `opts.secondary` the shadow, mirror and refraction rays of every pixel
/// whose two primary hits agree on the primitive.
pub(crate) fn compare(
    name: &str,
    scene: &Scene,
    twin: &Twin,
    opts: &Options,
    pool: &rayon::ThreadPool,
) -> Report {
    let start = Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let mut hits = PrimaryHits::new(width, height);
    trace_primary_lanes(scene, opts.lanes, pool, &mut hits);
    let cmp = Comparer { scene, twin, hits: &hits, opts };
    let acc = pool.install(|| {
        (0..height)
            .into_par_iter()
            .map(|y| {
                let mut acc = Acc::default();
                for x in 0..width {
                    cmp.pixel(x, y, &mut acc);
                }
                acc
            })
            .reduce(Acc::default, |a, b| a.merge(b, opts.max_examples))
    });
    let mut examples = acc.examples;
    examples.sort_by(|a, b| (&a.kind, a.y, a.x).cmp(&(&b.kind, b.y, b.x)));
    Report {
        scene: name.to_owned(),
        width,
        height,
        lanes: opts.lanes,
        scalar: opts.scalar && opts.lanes == 1,
        primitives: twin.len(),
        twin_bvh: twin.has_bvh(),
        primary: acc.primary.finish(),
        shadow: opts.secondary.then_some(acc.shadow),
        reflection: opts.secondary.then(|| acc.reflection.finish()),
        refraction: opts.secondary.then(|| acc.refraction.finish()),
        examples,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// [`HitStats`] being gathered: the t errors as a list.
#[derive(Default)]
struct HitAcc {
    rays: u64,
    hits_agree: u64,
    misses_agree: u64,
    hit_miss_disagree: u64,
    id_disagree: u64,
    tir_disagree: u64,
    explained: Explained,
    unexplained: u64,
    self_hits: u64,
    t_rel_err: Vec<f64>,
}

impl HitAcc {
    fn merge(&mut self, mut o: HitAcc) {
        self.rays += o.rays;
        self.hits_agree += o.hits_agree;
        self.misses_agree += o.misses_agree;
        self.hit_miss_disagree += o.hit_miss_disagree;
        self.id_disagree += o.id_disagree;
        self.tir_disagree += o.tir_disagree;
        self.explained.add(&o.explained);
        self.unexplained += o.unexplained;
        self.self_hits += o.self_hits;
        self.t_rel_err.append(&mut o.t_rel_err);
    }
    fn finish(self) -> HitStats {
        HitStats {
            rays: self.rays,
            hits_agree: self.hits_agree,
            misses_agree: self.misses_agree,
            hit_miss_disagree: self.hit_miss_disagree,
            id_disagree: self.id_disagree,
            tir_disagree: self.tir_disagree,
            explained: self.explained,
            unexplained: self.unexplained,
            self_hits: self.self_hits,
            t_rel_err: Percentiles::of(self.t_rel_err),
        }
    }
}

/// Everything gathered over some rows.
#[derive(Default)]
struct Acc {
    primary: HitAcc,
    shadow: ShadowStats,
    reflection: HitAcc,
    refraction: HitAcc,
    examples: Vec<Example>,
}

impl Acc {
    fn merge(mut self, o: Acc, max_examples: usize) -> Acc {
        self.primary.merge(o.primary);
        self.shadow.add(&o.shadow);
        self.reflection.merge(o.reflection);
        self.refraction.merge(o.refraction);
        self.examples.extend(o.examples);
        // Keep the first examples of each kind in image order.
        self.examples.sort_by(|a, b| (&a.kind, a.y, a.x).cmp(&(&b.kind, b.y, b.x)));
        let mut seen: Vec<(String, usize)> = Vec::new();
        self.examples.retain(|e| {
            let n = match seen.iter_mut().find(|(k, _)| *k == e.kind) {
                Some((_, n)) => n,
                None => {
                    seen.push((e.kind.clone(), 0));
                    &mut seen.last_mut().expect("pushed").1
                }
            };
            *n += 1;
            *n <= max_examples
        });
        self
    }

    fn example(&mut self, kind: &str, pixel: (u32, u32), light: Option<usize>, a: Hit64, b: Hit64) {
        push_example(&mut self.examples, kind, pixel, light, a, b);
    }
}

fn push_example(
    examples: &mut Vec<Example>,
    kind: &str,
    (x, y): (u32, u32),
    light: Option<usize>,
    a: Hit64,
    b: Hit64,
) {
    let id = |h: Hit64| if h.is_hit() { i64::from(h.prim) } else { -1 };
    examples.push(Example {
        kind: kind.to_owned(),
        x,
        y,
        light,
        f32_hit: (id(a), a.t),
        f64_hit: (id(b), b.t),
    });
}

fn len(v: V3<f64>) -> f64 {
    v.dot(v).sqrt()
}

/// `normal` turned toward rays along `dir`, and whether it was flipped (hit from inside): shade/surface.rs's
/// `facing`, which is private, replicated with the same operations: the side `eye_inside` gives where it is
/// known (a camera ray's sphere hit), else `n·d > 0` flips.
fn facing<F: crate::math::Real>(normal: V3<F>, dir: V3<F>, eye_inside: Option<bool>) -> (V3<F>, bool)
where
    F::Mask: Into<bool>,
{
    let inside: bool = eye_inside.unwrap_or_else(|| normal.dot(dir).gt(F::splat(0.0)).into());
    (if inside { -normal } else { normal }, inside)
}

/// Whether a secondary ray leaving primitive `departed` self-hits in f32: its hit (`a` in f32, `b` in f64)
/// is the departure primitive itself, or lies within `tol` of the origin, in f32 and not in f64. Both hitting
/// the same other primitive is agreement, however close to the origin (a neighbour closer than the f32
/// rounding of the origin's position). When the departure primitive can be met again away from the origin
/// (`meets_again`: an open cone's far wall), only hits within `tol` count: a far-wall hit in one precision
/// and not the other is a disagreement like any other, to be explained or not. A near hit of the twin's
/// alone is no self-hit: the twin skips the start by its departure rules, so its hit is a surface the exact
/// ray meets there (a torus left at a grazing slant that curves back into its path), and the f32 ray
/// meeting it farther or not at all is compared as any hit is. `contact`: `a` is the f32 contact rule's
/// entry into another sphere ([`Twin::contact_entry`]), the origin taken as on that sphere, no re-hit.
fn is_self_hit(a: Hit64, b: Hit64, departed: u32, tol: f64, meets_again: bool, contact: bool) -> bool {
    if a.is_hit() && a.prim != departed && (a.prim == b.prim || contact) {
        return false;
    }
    let selfish = |h: Hit64| h.is_hit() && ((h.prim == departed && !meets_again) || h.t <= tol);
    selfish(a) && !selfish(b)
}

/// The per-pixel comparison.
struct Comparer<'a> {
    scene: &'a Scene,
    twin: &'a Twin,
    hits: &'a PrimaryHits,
    opts: &'a Options,
}

impl Comparer<'_> {
    /// The f32 primitive's scene-file id ([`NO_PRIM`] stays).
    fn file_id(&self, storage: u32) -> u32 {
        if storage == NO_PRIM {
            NO_PRIM
        } else {
            self.scene.geometry.file_id(storage)
        }
    }

    fn pixel(&self, x: u32, y: u32, acc: &mut Acc) {
        let at = y as usize * self.hits.width as usize + x as usize;
        let (storage, t32) = (self.hits.prim[at], self.hits.t[at]);
        let h32 = Hit64 { t: f64::from(t32), prim: self.file_id(storage) };
        let ray64 = self.twin.camera_ray(f64::from(x) + 0.5, f64::from(y) + 0.5);
        let h64 = self.twin.intersect(&ray64, Departure::CAMERA, f64::INFINITY);
        self.compare_hits(
            &mut acc.primary,
            &mut acc.examples,
            "primary",
            (x, y),
            &ray64,
            Departure::CAMERA,
            h32,
            h64,
            Slack::default(),
        );
        if !self.opts.secondary || !h64.is_hit() || h32.prim != h64.prim {
            return;
        }
        // Each precision's own hit point and facing normal: the f32 ray is the one the primary pass traced
        // (the same f64 direction rounded once, as `render::for_each_packet` makes it).
        let g = &self.scene.geometry;
        let ray32 = self.scene.camera_f64.ray_f32(x as f32 + 0.5, y as f32 + 0.5);
        let sp = g.surface(&ray32, t32, storage);
        // The side from the exact eye term only for rays that start at the eye, as shade/surface.rs rules.
        let from_eye32 = at_eye(ray32.origin);
        let (n32, inside32) = facing(sp.normal, ray32.dir, g.eye_inside(storage).filter(|_| from_eye32));
        let (p64, outward64) = self.twin.surface(&ray64, h64.t, h64.prim);
        let from_eye64 = at_eye(ray64.origin);
        let (n64, inside64) =
            facing(outward64, ray64.dir, self.twin.eye_inside(h64.prim).filter(|_| from_eye64));
        // The twin works in the f32 scene's rendering space, so the two points compare as they are.
        let o32 = sp.point.to_f64();
        let start = secondary::Start {
            pixel: (x, y),
            prim: h64.prim,
            point32: sp.point,
            dir32: ray32.dir,
            normal32: n32,
            inside32,
            from32: Departure { prim: storage, inward: inside32 },
            from_eye32,
            point64: p64,
            dir64: ray64.dir,
            normal64: n64,
            inside64,
            from64: Departure { prim: h64.prim, inward: inside64 },
            origin_slack: len(o32 - p64),
            // A hit this close to the origin is a re-hit of the surface the ray starts on: the f32 origin is
            // off by a few ε32 of its distance from the eye.
            self_tol: K_SELF * EPS32 * len(p64),
            material: self.scene.materials.get(sp.material as usize).copied().unwrap_or_default(),
        };
        self.shadows(&start, acc);
        self.reflection(&start, acc);
        self.refraction(&start, acc);
    }

    /// Compares a closest-hit ray's two answers: `a` from f32, `b` from the twin along `ray` (leaving
    /// `from`), counting it into `st` and explaining a disagreement.
    #[allow(clippy::too_many_arguments)]
    fn compare_hits(
        &self,
        st: &mut HitAcc,
        examples: &mut Vec<Example>,
        kind: &str,
        pixel: (u32, u32),
        ray: &Ray<f64>,
        from: Departure,
        a: Hit64,
        b: Hit64,
        slack: Slack,
    ) {
        st.rays += 1;
        if a.prim == b.prim {
            if b.is_hit() {
                st.hits_agree += 1;
                st.t_rel_err.push(if a.t == b.t { 0.0 } else { (a.t - b.t).abs() / b.t });
            } else {
                st.misses_agree += 1;
            }
            return;
        }
        if a.is_hit() && b.is_hit() {
            st.id_disagree += 1;
        } else {
            st.hit_miss_disagree += 1;
        }
        let twin = self.twin;
        let secondary = from.prim != NO_PRIM;
        let why = |s: Slack| {
            let prims = [a.prim, b.prim];
            if prims.iter().any(|&p| twin.grazing(p, ray, K_GRAZE, s)) {
                return Some(Reason::Graze);
            }
            if twin.tie(a.prim, b.prim, ray, from, K_TIE, s) {
                return Some(Reason::Tie);
            }
            if secondary && prims.iter().any(|&p| twin.near_surface(p, ray.origin, K_START, s.origin)) {
                return Some(Reason::Start);
            }
            None
        };
        let diverged = || (slack != Slack::default()).then(|| why(slack)).flatten().map(|_| Reason::Diverge);
        match why(Slack::default()).or_else(diverged) {
            Some(r) => st.explained.count(r),
            None => {
                st.unexplained += 1;
                push_example(examples, kind, pixel, None, a, b);
            }
        }
    }
}
