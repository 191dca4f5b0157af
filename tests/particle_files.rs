//! Particle files rendered through the binary: framed on white, the periodic box and the types sidecar
//! (the readers are tested in `library/particle_files.rs`).

use crate::common::samples::{gzip, write, GRO, PDB};
use crate::common::{bareray, stderr};

#[test]
fn box_and_types_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let gro = write(dir.path(), "w.gro", GRO.as_bytes());
    let out = dir.path().join("w.png");
    let (gro_s, out_s) = (gro.to_str().unwrap(), out.to_str().unwrap());
    let size = ["--width", "96", "--height", "54", "-q"];
    let run = bareray(&[&["render", gro_s, "-o", out_s, "--box"][..], &size].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&out).unwrap().into_rgb8();
    // The box fills the image's tighter direction: its front face, nearer, spans about 62% of it.
    let grey = |p: &image::Rgb<u8>| p.0[0] < 200 && p.0[0] == p.0[1] && p.0[1] == p.0[2];
    let rows_with_grey = (0..54).filter(|&y| (0..96).any(|x| grey(img.get_pixel(x, y)))).count();
    assert!(rows_with_grey > 25, "the front face spans about 33 of 54 rows: {rows_with_grey}");

    let types = write(dir.path(), "t.toml", b"[O]\nradius = 0.5\ncolor = [0, 0, 1]\n[H]\nradius = -0.1\n");
    let before = std::fs::read(&out).unwrap();
    let run =
        bareray(&[&["render", gro_s, "-o", out_s, "--types", types.to_str().unwrap()][..], &size].concat());
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains(&format!("{}:5:", types.display())), "{}", stderr(&run));
    assert!(!stderr(&run).contains("panicked"), "{}", stderr(&run));
    assert_eq!(std::fs::read(&out).unwrap(), before, "a failed run leaves the output as it was");
    std::fs::write(&types, "[O]\nradius = 0.5\ncolor = [0, 0, 1]\n").unwrap();
    let run =
        bareray(&[&["render", gro_s, "-o", out_s, "--types", types.to_str().unwrap()][..], &size].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&out).unwrap().into_rgb8();
    let px = img.get_pixel(48, 27).0;
    assert!(px[2] > 200 && px[0] < 100 && px[1] < 100, "the big blue oxygen fills the middle: {px:?}");
}

#[test]
fn particle_files_render_framed_on_white_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = write(dir.path(), "m.pdb.gz", &gzip(PDB.as_bytes()));
    let out = dir.path().join("m.png");
    let (pdb_s, out_s) = (pdb.to_str().unwrap(), out.to_str().unwrap());
    let run =
        bareray(&["render", pdb_s, "-o", out_s, "--width", "96", "--height", "54", "--view", "-x", "-q"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&out).unwrap().into_rgb8();
    assert_eq!(img.get_pixel(0, 0).0, [255, 255, 255], "white background");
    let centre = img.get_pixel(48, 27).0;
    assert_ne!(centre, [255, 255, 255], "the molecule fills the middle");
    let args = ["--frame", "1", "--radius", "N=2", "--color", "N=0,0,1", "--radius-scale", "0.5", "-q"];
    let run = bareray(&[&["render", pdb_s, "-o", out_s, "--width", "32"][..], &args].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let px = image::open(&out).unwrap().into_rgb8().get_pixel(16, 9).0;
    assert!(px[2] > px[0] && px[2] > px[1], "the one blue nitrogen fills the middle: {px:?}");

    let bad = write(dir.path(), "bad.gro", b"t\n 1\n    1SOL     OW    1   0.126   x.624   1.679\n 1 1 1\n");
    let run = bareray(&["render", bad.to_str().unwrap(), "-o", out_s, "-q"]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains(&format!("{}:3: ", bad.display())), "{}", stderr(&run));
    let run = bareray(&["render", pdb_s, "-o", out_s, "--frame", "2", "-q"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("the file has 2 frames"), "{}", stderr(&run));
}
