//! Run time against error: each sampling method at increasing sample counts, timed and compared with a
//! high-sample reference (`metrics`), and the log-log picture of the result ([`plot`]). `bareray converge`
//! is the command line over [`study`].

pub(crate) mod metrics;
pub mod plot;
pub mod precision;

use crate::compile::Scene;
use crate::film::Image;
use crate::render::{primary_hits_lanes, render_lanes, Progress};
use crate::scene::desc::Pattern;

use metrics::{edge_mask, errors, Errors};

/// The sampling methods a study can compare, by their `--aa` names.
pub const METHODS: [&str; 7] = ["grid", "stratified", "r2", "sobol", "adaptive", "lecture", "coverage"];

/// The patterns a method runs at, by increasing sample count up to `max_spp` samples per pixel: squares
/// (1, 4, 16, 64, …) for the grids, powers of two for R2 and Sobol' (the counts where Sobol' points form
/// nets), the one half-pixel pattern for `lecture`, for `adaptive` falling thresholds (0.2 to 0.00625) at
/// depth 3 (up to 81 points a pixel where every level splits, whatever `max_spp` says), and the one setting
/// of `coverage` (it has no sample count: one ray per covered part of a pixel).
pub fn ladder(method: &str, max_spp: u32) -> Result<Vec<Pattern>, String> {
    let powers = || (0..).map(|e| 1u32 << e).take_while(move |&s| s <= max_spp.max(1));
    let squares = || {
        (1..).map(|n: u32| n * n).take_while(move |&s| s <= max_spp.max(1)).filter(|s| s.is_power_of_two())
    };
    match method {
        "grid" => Ok(squares().map(|s| Pattern::Grid(s.isqrt())).collect()),
        "stratified" => Ok(squares().map(|s| Pattern::Stratified(s.isqrt())).collect()),
        "r2" => Ok(powers().map(Pattern::R2).collect()),
        "sobol" => Ok(powers().map(Pattern::Sobol).collect()),
        "lecture" => Ok(vec![Pattern::HalfPixel]),
        "coverage" => Ok(vec![Pattern::Coverage]),
        "adaptive" => Ok([0.2, 0.1, 0.05, 0.025, 0.0125, 0.00625]
            .map(|threshold| Pattern::Adaptive { threshold, depth: 3 })
            .to_vec()),
        _ => Err(format!("unknown method `{method}`: {}", METHODS.join(", "))),
    }
}

/// One measured render.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The method's name.
    pub(crate) method: String,
    /// The reconstruction filter's name when the study compares filters (`none`, `gaussian:1.5`, …); `None`
    /// when every run keeps the scene's own filter.
    pub filter: Option<String>,
    /// Camera rays traced per pixel (counted: adaptive sampling decides its own).
    pub spp: f64,
    /// Wall-clock seconds of the render (tracing and filtering).
    pub seconds: f64,
    /// Rays traced, of every kind.
    pub rays: u64,
    /// The error against the reference.
    pub errors: Errors,
}

/// The reference of a study: the scene rendered with `pattern` (e.g. 32×32 stratified), and the edge pixels
/// of the image (where the primitive seen at the pixel centre changes between neighbours).
pub struct Reference {
    /// The reference image.
    pub image: Image,
    /// Edge pixels, row-major.
    pub(crate) edges: Vec<bool>,
}

impl Reference {
    /// Renders the reference of `scene` with `pattern` (the scene's own pattern is not used), at `lanes`.
    pub fn render(scene: &mut Scene, pattern: Pattern, lanes: usize, pool: &rayon::ThreadPool) -> Reference {
        let image = with_pattern(scene, pattern, |s| render_lanes(s, lanes, pool, &()).image);
        Reference::from_image(scene, image, lanes, pool)
    }

    /// A reference from an image rendered before (a cached file), with the edges found again.
    pub fn from_image(scene: &Scene, image: Image, lanes: usize, pool: &rayon::ThreadPool) -> Reference {
        let hits = primary_hits_lanes(scene, lanes, pool);
        let edges = edge_mask(&hits.prim, hits.width);
        Reference { image, edges }
    }
}

/// `f` of `scene` with `pattern` in place of its own, which is put back after.
fn with_pattern<T>(scene: &mut Scene, pattern: Pattern, f: impl FnOnce(&Scene) -> T) -> T {
    let own = std::mem::replace(&mut scene.render.pattern, pattern);
    let result = f(scene);
    scene.render.pattern = own;
    result
}

/// Renders `scene` with every pattern of every method in `methods` (each `(name, patterns)`, in order),
/// and measures each against `reference`; `progress` counts the renders.
pub fn study(
    scene: &mut Scene,
    methods: &[(String, Vec<Pattern>)],
    reference: &Reference,
    lanes: usize,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) -> Vec<Run> {
    let total = methods.iter().map(|(_, p)| p.len() as u64).sum();
    progress.start(total);
    let mut runs = Vec::new();
    for (name, patterns) in methods {
        for &pattern in patterns {
            let rendered = with_pattern(scene, pattern, |s| render_lanes(s, lanes, pool, &()));
            let pixels = f64::from(scene.camera.width) * f64::from(scene.camera.height);
            runs.push(Run {
                method: name.clone(),
                filter: None,
                spp: rendered.counts.primary as f64 / pixels.max(1.0),
                seconds: rendered.seconds,
                rays: rendered.counts.total(),
                errors: errors(&rendered.image, &reference.image, &reference.edges),
            });
            progress.tile_done(runs.len() as u64, total);
        }
    }
    runs
}

/// The runs as CSV: a header `method,spp,seconds,rays,rmse,rmse_edges,psnr`, one line per run; when the
/// runs compare filters, a `filter` column follows `method`.
pub fn csv(runs: &[Run]) -> String {
    let filters = runs.iter().any(|r| r.filter.is_some());
    let mut out = String::from(match filters {
        true => "method,filter,spp,seconds,rays,rmse,rmse_edges,psnr\n",
        false => "method,spp,seconds,rays,rmse,rmse_edges,psnr\n",
    });
    for r in runs {
        let e = &r.errors;
        let name = match (filters, &r.filter) {
            (true, f) => format!("{},{}", r.method, f.as_deref().unwrap_or("")),
            (false, _) => r.method.clone(),
        };
        out += &format!(
            "{name},{:.4},{:.6},{},{:.6e},{:.6e},{:.3}\n",
            r.spp, r.seconds, r.rays, e.rmse, e.rmse_edges, e.psnr
        );
    }
    out
}

impl Run {
    /// The run's series: the method, and the filter after a comma when the study compares filters
    /// (`sobol, gaussian:1.5`).
    pub fn series(&self) -> String {
        match &self.filter {
            Some(f) => format!("{}, {f}", self.method),
            None => self.method.clone(),
        }
    }
}

/// The runs as curves of RMSE against seconds, one per series ([`Run::series`]), for [`plot::svg`]: a
/// colour per method and, when filters are compared, a dash pattern per filter.
pub fn curves(runs: &[Run]) -> Vec<plot::Curve> {
    let (mut methods, mut filters): (Vec<&str>, Vec<Option<&str>>) = (Vec::new(), Vec::new());
    let mut curves: Vec<plot::Curve> = Vec::new();
    for r in runs {
        let point = (r.seconds, r.errors.rmse);
        let name = r.series();
        match curves.iter_mut().find(|c| c.name == name) {
            Some(c) => c.points.push(point),
            None => {
                let colour = index_of(&mut methods, r.method.as_str());
                let dash = index_of(&mut filters, r.filter.as_deref());
                curves.push(plot::Curve { name, points: vec![point], colour, dash });
            }
        }
    }
    curves
}

/// Where `item` is in `list`, pushed at the end when it is not there yet.
fn index_of<T: PartialEq>(list: &mut Vec<T>, item: T) -> usize {
    match list.iter().position(|m| *m == item) {
        Some(i) => i,
        None => {
            list.push(item);
            list.len() - 1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladders_climb_to_the_largest_count() {
        assert_eq!(
            ladder("grid", 64),
            Ok(vec![Pattern::Grid(1), Pattern::Grid(2), Pattern::Grid(4), Pattern::Grid(8)])
        );
        assert_eq!(ladder("stratified", 20).unwrap().len(), 3);
        assert_eq!(ladder("r2", 8), Ok(vec![Pattern::R2(1), Pattern::R2(2), Pattern::R2(4), Pattern::R2(8)]));
        assert_eq!(ladder("lecture", 64), Ok(vec![Pattern::HalfPixel]));
        assert_eq!(ladder("coverage", 1), Ok(vec![Pattern::Coverage]));
        assert_eq!(ladder("sobol", 6), Ok(vec![Pattern::Sobol(1), Pattern::Sobol(2), Pattern::Sobol(4)]));
        assert!(ladder("halton", 64).is_err());
    }

    fn run(method: &str, filter: Option<&str>, spp: f64, rmse: f64) -> Run {
        let errors = Errors { rmse, rmse_edges: 2.0 * rmse, psnr: 20.0 };
        Run { method: method.into(), filter: filter.map(String::from), spp, seconds: spp, rays: 1, errors }
    }

    /// Without a filter axis the CSV has no filter column and a curve per method; with one, each (method,
    /// filter) pair is a series of its own, named by both, coloured by the method and dashed by the filter.
    #[test]
    fn filters_make_series_of_their_own() {
        let plain = [run("sobol", None, 1.0, 0.1), run("sobol", None, 4.0, 0.05)];
        assert_eq!(csv(&plain).lines().next(), Some("method,spp,seconds,rays,rmse,rmse_edges,psnr"));
        assert!(csv(&plain).lines().nth(1).unwrap().starts_with("sobol,1.0000,"));
        assert_eq!(curves(&plain).len(), 1);
        let pairs = [
            run("sobol", Some("none"), 1.0, 0.1),
            run("sobol", Some("none"), 4.0, 0.05),
            run("sobol", Some("gaussian:1.5"), 1.0, 0.08),
            run("stratified", Some("gaussian:1.5"), 1.0, 0.09),
        ];
        let text = csv(&pairs);
        assert_eq!(text.lines().next(), Some("method,filter,spp,seconds,rays,rmse,rmse_edges,psnr"));
        assert!(text.lines().nth(3).unwrap().starts_with("sobol,gaussian:1.5,1.0000,"), "{text}");
        let c = curves(&pairs);
        let names: Vec<&str> = c.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["sobol, none", "sobol, gaussian:1.5", "stratified, gaussian:1.5"]);
        assert_eq!(c[0].points.len(), 2);
        assert_eq!(c.iter().map(|c| (c.colour, c.dash)).collect::<Vec<_>>(), [(0, 0), (0, 1), (1, 1)]);
    }
}
