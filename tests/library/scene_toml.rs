//! The TOML scene reader: what it builds, and errors that name the file, the line and what was expected.

use std::path::Path;

use bareray::io::{toml, SceneError};
use bareray::scene::desc::{Falloff, Pattern, PostFilter};
use bareray::scene::SceneDesc;

fn parse(src: &str) -> Result<SceneDesc, SceneError> {
    toml::parse(Path::new("dir/s.toml"), src)
}

/// Parses, expecting an error on `line` whose message contains `needle`.
fn error_at(src: &str, line: usize, needle: &str) {
    let e = parse(src).expect_err("scene should be rejected");
    let text = e.to_string();
    assert!(text.starts_with(&format!("dir/s.toml:{line}:")), "wrong place: {text}");
    assert!(text.contains(needle), "message lacks {needle:?}: {text}");
}

#[test]
fn empty_file_gives_defaults() {
    let d = parse("").unwrap();
    assert_eq!(d.camera.width, 640);
    assert_eq!(d.materials.len(), 1);
    assert!(d.spheres.is_empty() && d.kinds.is_empty());
}

#[test]
fn full_scene_is_read() {
    let d = parse(
        r#"
        [render]
        samples = 9
        postfilter = "lecture-3x3"
        [materials.a]
        color = [1, 0, 0]
        [materials.b]
        transmit = 0.5
        [[lights]]
        position = [1, 2, 3]
        color = [1, 0.5, 0]
        intensity = 2
        falloff = "inverse-square"
        [[spheres]]
        center = [0, 0, 0]
        radius = 1
        material = "b"
        [[spheres]]
        center = [0, 0, 0]
        radius = 1
        transform = [{ scale = [2, 1, 1] }, { rotate = { axis = [0, 0, 1], degrees = 90 } }]
        [[planes]]
        normal = [0, 1, 0]
        material = "a"
    "#,
    )
    .unwrap();
    assert_eq!(d.render.pattern, Pattern::Grid(3));
    assert_eq!(d.render.postfilter, PostFilter::Lecture3x3);
    assert_eq!(d.lights[0].color.y, 1.0);
    assert_eq!(d.lights[0].falloff, Falloff::InverseSquare);
    assert_eq!(d.spheres.len(), 1);
    assert_eq!(d.materials[d.spheres[0].material as usize].transmit, 0.5);
    assert_eq!((d.kinds.ellipsoids.len(), d.kinds.planes.len()), (1, 1));
    // Scaled 2× along x, then turned 90° about z: the long axis now lies along y.
    let long = d.kinds.ellipsoids[0].world_from_object.transform_vector3(glam::DVec3::X);
    assert!((long - glam::DVec3::new(0.0, 2.0, 0.0)).length() < 1e-12, "{long}");
    let n = d.kinds.planes[0].world_from_object.transform_vector3(glam::DVec3::Z);
    assert!((n - glam::DVec3::Y).length() < 1e-12);
}

#[test]
fn syntax_error_names_the_line() {
    error_at("[camera]\nwidth = 10\nheight = = 3\n", 3, "");
}

#[test]
fn unknown_key_is_an_error() {
    error_at("[[spheres]]\ncenter = [0,0,0]\nradus = 1\n", 3, "unknown field `radus`");
}

#[test]
fn unknown_table_is_an_error() {
    error_at("[camera]\nwidth = 3\n\n[lamps]\nx = 1\n", 4, "unknown field `lamps`");
}

#[test]
fn wrong_type_says_what_was_expected() {
    error_at("[camera]\nwidth = \"wide\"\n", 2, "u32");
    error_at("[[spheres]]\ncenter = [0, 0]\nradius = 1\n", 2, "3");
}

#[test]
fn missing_radius_is_an_error() {
    let e = parse("\n[[spheres]]\ncenter = [0,0,0]\n").unwrap_err();
    assert!(e.to_string().contains("missing field `radius`"), "{e}");
    assert!(e.line >= 2, "{e}");
}

#[test]
fn unknown_material_lists_the_known_ones() {
    error_at(
        "[materials.red]\n[[spheres]]\ncenter = [0,0,0]\nradius = 1\nmaterial = \"blue\"\n",
        5,
        "unknown material `blue`, expected one of default, red",
    );
}

#[test]
fn bad_values_name_their_line() {
    error_at("[[spheres]]\ncenter = [0,0,0]\nradius = -1\n", 3, "radius must be positive");
    error_at("[render]\nsamples = 5\n", 2, "square number");
    error_at("[render]\npattern = \"half-pixel\"\nsamples = 4\n", 3, "9 samples");
    error_at("[render]\nbackground = [0, -1, 0]\n", 2, "non-negative");
    error_at("[materials.x]\nior = 0\n", 2, "ior must be positive");
    error_at("[render]\npattern = \"jitter\"\n", 2, "grid");
    error_at("[[planes]]\nnormal = [0, 0, 0]\n", 2, "non-zero");
    error_at("[[ellipsoids]]\ncenter = [0,0,0]\nradii = [1, 0, 2]\n", 3, "radii must be positive");
    error_at("[[ellipsoids]]\ncenter = [0,0,1e39]\nradii = [1, 1, 1]\n", 2, "center must be finite");
    error_at(
        "[[ellipsoids]]\ncenter = [0,0,0]\nradii = [1, 1, 1]\ntransform = [{ rotate = { axis = [0, 0, 0], degrees = 9 } }]\n",
        4,
        "non-zero",
    );
    error_at(
        "[[spheres]]\ncenter = [0,0,0]\nradius = 1\ntransform = [{ scale = [1, 0, 1] }]\n",
        4,
        "singular",
    );
}

/// `[[ellipsoids]]`: the unit sphere stretched by `radii`, then transformed about its centre, then moved to
/// `center`; listed before the transformed `[[spheres]]`, and the same ellipsoid either way.
#[test]
fn ellipsoids_are_read_and_equal_a_stretched_sphere() {
    let d = parse(
        r#"
        [[spheres]]
        center = [1, 2, 3]
        radius = 2
        transform = [{ scale = [1, 0.5, 1.5] }, { rotate = { axis = [0, 0, 1], degrees = 90 } }]
        [[ellipsoids]]
        center = [1, 2, 3]
        radii = [2, 1, 3]
        transform = [{ rotate = { axis = [0, 0, 1], degrees = 90 } }]
    "#,
    )
    .unwrap();
    let e = &d.kinds.ellipsoids;
    assert_eq!(e.len(), 2);
    // The table's own ellipsoid first: its long axis (3 along z) stays on z; its x semi-axis 2 turns onto y.
    let m = e[0].world_from_object;
    assert!((m.transform_vector3(glam::DVec3::X) - glam::DVec3::new(0.0, 2.0, 0.0)).length() < 1e-12);
    assert!((m.transform_point3(glam::DVec3::Z) - glam::DVec3::new(1.0, 2.0, 6.0)).length() < 1e-12);
    let (a, b) = (e[0].world_from_object, e[1].world_from_object);
    assert!((a.matrix3 - b.matrix3).abs().to_cols_array().iter().all(|x| *x < 1e-12), "{a:?} {b:?}");
    assert_eq!(a.translation, b.translation);
}

#[test]
fn camera_errors_point_at_the_camera_table() {
    error_at("# c\n[camera]\nup = [0, 0, 1]\nlook_at = [0, 0, 10]\neye = [0, 0, 0]\n", 2, "parallel");
    error_at("[camera]\nhfov = 40\npixel_size = 0.1\n", 1, "not both");
    error_at("[camera]\nhfov = 200\n", 1, "(0, 180)");
}

/// `[render]` sampling patterns and filters: stratified, R2 and Sobol' with their counts (Sobol' from 1), a filter with its default
/// radius or a given one; a radius without a filter, a radius out of range and a non-square stratified count
/// are errors at their line.
#[test]
fn patterns_and_filters_are_read() {
    use bareray::scene::desc::{Filter, FilterKind};
    let d = parse("[render]\npattern = \"stratified\"\nsamples = 16\nfilter = \"tent\"\n").unwrap();
    assert_eq!(d.render.pattern, Pattern::Stratified(4));
    assert_eq!(d.render.filter, Some(Filter { kind: FilterKind::Tent, radius: 1.0 }));
    let d = parse("[render]\npattern = \"r2\"\nsamples = 5\nfilter = \"mitchell\"\nfilter_radius = 1.5\n")
        .unwrap();
    assert_eq!(d.render.pattern, Pattern::R2(5));
    assert_eq!(d.render.filter, Some(Filter { kind: FilterKind::Mitchell, radius: 1.5 }));
    assert_eq!(
        parse("[render]\npattern = \"sobol\"\nsamples = 16\n").unwrap().render.pattern,
        Pattern::Sobol(16)
    );
    assert_eq!(parse("[render]\npattern = \"sobol\"\n").unwrap().render.pattern, Pattern::Sobol(1));
    error_at("[render]\npattern = \"sobol\"\nsamples = 0\n", 3, "at least 1 sample");
    assert_eq!(parse("").unwrap().render.filter, None);
    error_at("[render]\nfilter_radius = 1.0\n", 2, "needs a filter");
    error_at("[render]\nfilter = \"box\"\nfilter_radius = 9.0\n", 3, "filter_radius");
    error_at("[render]\npattern = \"stratified\"\nsamples = 5\n", 3, "square");
}

/// `[[polygons]]`: vertices in order, optional per-vertex normals, a material; ids after the shapes, as NFF's.
/// Too few vertices, vertices that do not span a plane, and a normal list of the wrong length are errors at
/// their line.
#[test]
fn polygons_are_read() {
    let d = parse(
        "[materials.red]\ncolor = [1, 0, 0]\n\n[[polygons]]\nvertices = [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]\n\
         material = \"red\"\n\n[[polygons]]\nvertices = [[0, 0, 2], [1, 0, 2], [0, 1, 2]]\n\
         normals = [[0, 0, 1], [0.1, 0, 1], [0, 0.1, 1]]\n",
    )
    .unwrap();
    assert_eq!(d.kinds.polygons.len(), 2);
    assert_eq!(d.kinds.polygons[0].vertices.len(), 4);
    assert_eq!(d.kinds.polygons[0].vertices[2], glam::DVec3::new(1.0, 1.0, 1.0));
    assert_eq!((d.kinds.polygons[0].material, d.kinds.polygons[1].material), (1, 0));
    assert!(d.kinds.polygons[0].normals.is_none());
    assert_eq!(d.kinds.polygons[1].normals.as_ref().map(Vec::len), Some(3));
    error_at("[[polygons]]\nvertices = [[0, 0, 0], [1, 0, 0]]\n", 2, "at least three");
    error_at("[[polygons]]\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]\n", 2, "polygon");
    error_at(
        "[[polygons]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nnormals = [[0, 0, 1]]\n",
        3,
        "one per vertex",
    );
}
