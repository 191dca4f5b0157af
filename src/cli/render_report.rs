//! What `bareray render` prints: the progress bar, the summary line and the statistics of `--stats`.

use std::io::IsTerminal;
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};

use super::render::RenderArgs;
use bareray::compile::Scene;
use bareray::render::Traced;
use bareray::scene::SceneDesc;
use bareray::still::Job;

/// Wall-clock seconds of each stage.
#[derive(Default)]
pub(super) struct Timings {
    pub(super) parse: f64,
    pub(super) build: f64,
    /// Tracing, and the writing that overlaps it.
    pub(super) render: f64,
}

/// The summary line, or the statistics with `--stats`; nothing with `--quiet`.
pub(super) fn report(args: &RenderArgs, scene: &Scene, job: &Job, traced: &Traced, time: &Timings) {
    let to_stdout = bareray::output::is_stdout(&job.output);
    if args.stats {
        // With the image on standard output, the report goes to standard error.
        let mut out: Box<dyn std::io::Write> =
            if to_stdout { Box::new(std::io::stderr()) } else { Box::new(std::io::stdout()) };
        print_stats(&mut out, scene, job, traced, time);
    } else if !args.quiet {
        let line = summary(&job.output, job, traced, time);
        // With the image on standard output, the summary goes beside it, to standard error.
        if to_stdout {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    }
}

/// A progress bar counting a render's tiles (or a study's runs): the total is the bar's length, each one
/// done moves it by one.
pub(super) struct TileBar(pub(super) ProgressBar);

impl bareray::render::Progress for TileBar {
    fn start(&self, total: u64) {
        self.0.set_length(total);
    }
    fn tile_done(&self, _: u64, _: u64) {
        self.0.inc(1);
    }
}

/// The render's bar on standard error: hidden with `quiet` or when standard error is not a terminal.
pub(super) fn progress_bar(quiet: bool) -> TileBar {
    TileBar(styled_bar(quiet))
}

fn styled_bar(quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(0);
    let style =
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} tiles, eta {eta}")
            .expect("valid template");
    bar.set_style(style);
    bar
}

fn summary(output: &Path, job: &Job, r: &Traced, time: &Timings) -> String {
    let c = r.counts;
    let output = if bareray::output::is_stdout(output) { Path::new("<stdout>") } else { output };
    format!(
        "{}: {}x{} in {:.3} s (parse {:.3} s, build {:.3} s); {} rays ({} primary, {} shadow, {} reflection, \
         {} refraction, {} ao), {:.2} Mrays/s",
        output.display(),
        job.window.width(),
        job.window.height(),
        time.render,
        time.parse,
        time.build,
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction,
        c.ao,
        c.total() as f64 / r.seconds / 1e6
    )
}

fn print_stats(out: &mut dyn std::io::Write, scene: &Scene, job: &Job, r: &Traced, time: &Timings) {
    let _ = write!(out, "{}", bareray::still::describe(scene, job));
    let c = r.counts;
    let _ = writeln!(
        out,
        "rays: {} total: {} primary, {} shadow, {} reflection, {} refraction, {} ao",
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction,
        c.ao
    );
    let _ = writeln!(
        out,
        "intersection tests: {} packet-primitive, {} packet-box, at {} rays per packet",
        r.work.prim_tests, r.work.box_tests, job.lanes
    );
    let _ = writeln!(
        out,
        "time: parse {:.3} s, build {:.3} s (scene and BVH), render and write {:.3} s (tracing {:.3} s)",
        time.parse, time.build, time.render, r.seconds
    );
    let _ = writeln!(out, "throughput: {:.2} Mrays/s", c.total() as f64 / r.seconds / 1e6);
}

/// What a scene lacks that makes its image surely not what was meant: no primitives at all, or no lights
/// while some material has a diffuse or specular term (which only lights light).
pub(super) fn scene_warnings(desc: &SceneDesc) -> Vec<&'static str> {
    let mut warnings = Vec::new();
    if desc.spheres.is_empty() && desc.kinds.is_empty() {
        warnings.push("no objects");
    }
    if desc.lights.is_empty() && desc.materials.iter().any(|m| m.diffuse > 0.0 || m.specular > 0.0) {
        warnings.push("no lights");
    }
    warnings
}
