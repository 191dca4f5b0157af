//! Tests of the TOML reader: errors at their line and column, kinds with their materials, patterns and
//! shading.

use super::*;
use crate::scene::desc::{Ao, Pattern, Shade};

fn parse_str(s: &str) -> Result<SceneDesc, SceneError> {
    parse(Path::new("t.toml"), s)
}

#[test]
fn overlong_dotted_keys_name_their_line() {
    let key = vec!["a"; 100].join(".");
    for line in [format!("{key} = 1"), format!("[{key}]"), format!("[[{key}]]")] {
        let e = parse_str(&format!("[camera]\nwidth = 64\n\n  {line}\n")).unwrap_err();
        assert_eq!((e.line, e.column), (4, 3), "{e}");
        assert!(e.message.contains("100 parts"), "{e}");
    }
}

#[test]
fn cones_are_read_with_their_material() {
    let d = parse_str(
        "[materials.red]\ncolor = [1, 0, 0]\n\n[[cones]]\nbase = [0, 0, 0]\nbase_radius = 1\n\
         apex = [0, 2, 0]\napex_radius = 0\nmaterial = \"red\"\n\n[[cones]]\nbase = [1, 1, 1]\n\
         base_radius = 0.5\napex = [1, 1, 3]\napex_radius = 0.5\n",
    )
    .unwrap();
    assert_eq!(d.kinds.cones.len(), 2);
    let c = d.kinds.cones[0];
    assert_eq!((c.base, c.base_radius, c.apex, c.apex_radius), (DVec3::ZERO, 1.0, DVec3::Y * 2.0, 0.0));
    assert_eq!(d.materials[c.material as usize].color, Rgb::new(1.0, 0.0, 0.0));
    assert_eq!(d.kinds.cones[1].material, 0);
}

#[test]
fn the_coverage_pattern_takes_no_samples() {
    let d = parse_str("[render]\npattern = \"coverage\"\n").unwrap();
    assert_eq!(d.render.pattern, Pattern::Coverage);
    let e = parse_str("[render]\npattern = \"coverage\"\nsamples = 4\n").unwrap_err();
    assert_eq!((e.line, e.column), (3, 11), "{e}");
    assert!(e.message.contains("takes no samples"), "{e}");
}

#[test]
fn shade_reads_whitted_and_ambient_occlusion() {
    assert_eq!(parse_str("[render]\n").unwrap().render.shade, Shade::Whitted);
    let d = parse_str("[render]\nshade = \"ao:8,2.5\"\n").unwrap();
    assert_eq!(d.render.shade, Shade::Ao(Ao { samples: 8, distance: Some(2.5) }));
    let d = parse_str("[render]\nshade = \"ao\"\n").unwrap();
    assert_eq!(d.render.shade, Shade::Ao(Ao { samples: Ao::DEFAULT_SAMPLES, distance: None }));
    for (text, says) in [("ao:0", "SAMPLES"), ("ao:4,-1", "DISTANCE"), ("phong", "unknown shading")] {
        let e = parse_str(&format!("[render]\nmax_depth = 2\nshade = \"{text}\"\n")).unwrap_err();
        assert_eq!((e.line, e.column), (3, 9), "{e}");
        assert!(e.message.contains(says) && e.message.contains("ao:SAMPLES,DISTANCE"), "{e}");
    }
}

#[test]
fn bad_cones_name_line_and_column() {
    let cone = |body: &str| format!("[[cones]]\n{body}");
    for (body, line, column, says) in [
        ("base = [0,0,0]\nbase_radius = -1\napex = [0,0,1]\napex_radius = 1\n", 3, 15, "non-negative"),
        ("base = [0,0,0]\nbase_radius = 1\napex = [0,0,0]\napex_radius = 1\n", 4, 8, "differ"),
        ("base = [0,0,0]\nbase_radius = 0\napex = [0,0,1]\napex_radius = 0\n", 3, 15, "positive radius"),
        ("base = [0,0,0]\nbase_radius = 1\napex = [0,0,1]\n", 1, 1, "missing field `apex_radius`"),
        ("base = [0,0,0]\nradius = 1\n", 3, 1, "unknown field `radius`, expected one of `base`"),
        ("base = [0,0,1e39]\nbase_radius = 1\napex = [0,0,1]\napex_radius = 1\n", 2, 8, "within f32"),
    ] {
        let e = parse_str(&cone(body)).unwrap_err();
        assert_eq!((e.line, e.column), (line, column), "{body:?}: {e}");
        assert!(e.message.contains(says), "{body:?}: {e}");
    }
}
