//! Scenes far from the eye (compile's rendering frame, `bareray::compile::RenderingFrame`): one cluster of
//! 24 near-touching mirror spheres (gaps 0.01–0.05, radii 0.25–1) placed 10, 1e4, 1e5 and 1e6 from the eye
//! along (0.48, 0.6, 0.64), filling the view (scenes/stress/cluster-*.toml, written by make_clusters.py
//! there). Far away the scene is compiled around its own centre and camera rays start just short of it, so
//! its reflections are as exact as near the eye. Bits across widths and threads, and the bounds every
//! stress scene meets, are checked with the other stress scenes (tests/library/render.rs, tests/library/accuracy.rs).

use std::path::Path;

use bareray::accuracy::{run, Options, Report};
use bareray::aov::{samples, Aov};
use bareray::compile::Scene;
use bareray::render::{thread_pool, Window};

fn cluster(distance: &str) -> bareray::scene::SceneDesc {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/stress/cluster-{distance}.toml"));
    bareray::io::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn report(distance: &str) -> Report {
    let opts = Options { lanes: 8, secondary: true, threads: Some(2), ..Options::default() };
    run(distance, &cluster(distance), &opts).expect("report")
}

/// The reflection rays' relative t error p99 at 1e4, 1e5 and 1e6 from the eye stays within twice the
/// cluster's 10 units from the eye, with no unexplained disagreement and no self-hit of any ray kind (with
/// the eye as origin at 1e6, p99 was 1.0 and 34 reflection rays re-hit their own sphere).
#[test]
fn a_cluster_far_from_the_eye_reflects_as_it_does_near() {
    let near = report("10");
    let near_p99 = near.reflection.as_ref().expect("secondary").t_rel_err.p99;
    eprint!("{}", near.table());
    let mut failures = Vec::new();
    for distance in ["1e4", "1e5", "1e6"] {
        let r = report(distance);
        eprint!("{}", r.table());
        let reflection = r.reflection.as_ref().expect("secondary");
        let p99 = reflection.t_rel_err.p99;
        if r.unexplained() != 0 || r.self_hits() != 0 || p99 > 2.0 * near_p99 || reflection.rays < 4000 {
            failures.push(format!(
                "{distance}: {} unexplained, {} self-hits, {} reflection rays, reflection t p99 {p99:.3e} \
                 against {near_p99:.3e} at 10",
                r.unexplained(),
                r.self_hits(),
                reflection.rays
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Only the far clusters move the frame; there camera rays start short of the nearest sphere, and the
/// depth AOV still measures from the eye: the centre pixel sees the cluster (at most 6 units across) at the
/// cluster's distance.
#[test]
fn far_clusters_are_centred_and_depth_is_from_the_eye() {
    let pool = thread_pool(Some(1)).unwrap();
    for (distance, d) in [("10", 10.0), ("1e4", 1e4), ("1e6", 1e6)] {
        let scene = Scene::compile(&cluster(distance)).expect("compiles");
        let (w, h) = (scene.camera.width, scene.camera.height);
        let window = Window { x0: w / 2, y0: h / 2, x1: w / 2 + 1, y1: h / 2 + 1 };
        let bytes = samples(&scene, 8, &pool, window, &[Aov::Depth]);
        let depth = f64::from(f32::from_le_bytes(bytes[..4].try_into().unwrap()));
        let start = scene.camera_f64.start;
        assert_eq!(start > 0.0, d > 10.0, "{distance}: start {start}");
        assert!(start < depth && (depth - d).abs() < 6.0, "{distance}: start {start}, depth {depth}");
    }
}
