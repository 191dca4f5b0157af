//! Particle files (XYZ, extended XYZ, PDB, PQR, GRO, LAMMPS dumps), plain and compressed: small hand-written
//! samples read through `bareray::io::load_with`, with frames, overrides and the framing checked, errors
//! checked for their file and line (the renders through the binary are in `tests/particle_files.rs`).

use super::common;

use std::path::Path;

use bareray::io::{load_with, LoadOptions, SceneRead};
use bareray::math::Rgb;
use common::samples::{bzip, gzip, write, DUMP, EXTXYZ, GRO, PDB, PQR, XYZ};
use glam::DVec3;

fn read(dir: &Path, name: &str, text: &str, options: &LoadOptions) -> SceneRead {
    let path = write(dir, name, text.as_bytes());
    load_with(&path, options).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn radii(read: &SceneRead) -> Vec<f64> {
    read.desc.spheres.iter().map(|s| s.radius).collect()
}

/// A particle's colour: its entry in the per-sphere colour store (every particle has one).
fn colour(read: &SceneRead, sphere: usize) -> Rgb {
    assert_eq!(read.desc.sphere_colors.len(), read.desc.spheres.len(), "a colour per particle");
    read.desc.sphere_colors[sphere].to_rgb()
}

#[test]
fn each_format_reads_its_sample() {
    let dir = tempfile::tempdir().unwrap();
    let none = LoadOptions::default();
    let xyz = read(dir.path(), "w.xyz", XYZ, &none);
    assert_eq!(radii(&xyz), [1.5, 1.2, 1.2], "Alvarez 2013: O 1.50, H 1.20");
    assert_eq!(xyz.desc.materials.len(), 1, "one material; colours per particle");
    assert_eq!(colour(&xyz, 0), Rgb::new(1.0, 13.0 / 255.0, 13.0 / 255.0), "Jmol oxygen #FF0D0D");
    assert!(xyz.warnings.is_empty(), "{:?}", xyz.warnings);

    let ext = read(dir.path(), "e.extxyz", EXTXYZ, &none);
    assert_eq!(radii(&ext), [0.5, 0.25], "the file's radius column");
    assert_eq!((colour(&ext, 0), colour(&ext, 1)), (Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.0, 0.0, 1.0)));
    assert!(ext.warnings.is_empty(), "a radius for the unknown element is in the file: {:?}", ext.warnings);

    let pdb = read(dir.path(), "p.pdb", PDB, &none);
    assert_eq!(pdb.desc.spheres.len(), 3);
    assert_eq!(pdb.desc.spheres[0].center, DVec3::new(-1.0, 2.0, 3.0));
    assert_eq!(radii(&pdb), [1.66, 1.77, 2.44], "N, C and Fe (from the HETATM name)");

    let pqr = read(dir.path(), "p.pqr", PQR, &none);
    assert_eq!(radii(&pqr), [1.824, 1.7]);

    let gro = read(dir.path(), "w.gro", GRO, &none);
    assert_eq!(gro.desc.spheres[0].center, DVec3::new(0.126, 1.624, 1.679));
    let nm = radii(&gro);
    assert!((nm[0] - 0.15).abs() < 1e-12 && (nm[1] - 0.12).abs() < 1e-12, "table radii in nm: {nm:?}");

    let dump = read(dir.path(), "d.lammpstrj", DUMP, &none);
    assert_eq!(radii(&dump), [0.5, 0.5, 0.5], "LAMMPS types get 0.5");
    assert_eq!(dump.desc.materials.len(), 1, "one material; colours per particle");
    assert_ne!(colour(&dump, 0), colour(&dump, 1));
}

#[test]
fn compressed_files_read_as_the_plain_ones() {
    let dir = tempfile::tempdir().unwrap();
    let none = LoadOptions::default();
    for (name, text) in [("a.xyz", XYZ), ("a.pdb", PDB), ("a.pqr", PQR), ("a.gro", GRO), ("a.dump", DUMP)] {
        let plain = read(dir.path(), name, text, &none).desc;
        for (ext, bytes) in [("gz", gzip(text.as_bytes())), ("bz2", bzip(text.as_bytes()))] {
            let path = write(dir.path(), &format!("{name}.{ext}"), &bytes);
            let packed = load_with(&path, &none).unwrap_or_else(|e| panic!("{path:?}: {e}"));
            assert_eq!(packed.desc, plain, "{path:?}");
        }
    }
    // A cut gzip stream and a .gz that is not gzip are errors about the file.
    let cut = gzip(XYZ.as_bytes());
    let path = write(dir.path(), "cut.xyz.gz", &cut[..cut.len() / 2]);
    let e = load_with(&path, &none).unwrap_err();
    assert!(e.message.starts_with("bad gzip data"), "{e}");
    let path = write(dir.path(), "plain.xyz.gz", XYZ.as_bytes());
    assert!(load_with(&path, &none).unwrap_err().message.contains("does not hold gzip data"));
    // A tar archive named .bz2 (as some test-data sets ship) is told apart.
    let mut tar = vec![0u8; 1024];
    tar[..5].copy_from_slice(b"a.pdb");
    tar[257..263].copy_from_slice(b"ustar ");
    let path = write(dir.path(), "a.pdb.bz2", &tar);
    let e = load_with(&path, &none).unwrap_err();
    assert!(e.message.ends_with("does not hold bzip2 data (it is a tar archive: unpack it first)"), "{e}");
}

#[test]
fn frames_are_chosen_and_a_missing_one_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    let frame = |n| LoadOptions { frame: Some(n), ..LoadOptions::default() };
    assert_eq!(radii(&read(dir.path(), "w.xyz", XYZ, &frame(1))), [1.77, 1.82]);
    assert_eq!(read(dir.path(), "p.pdb", PDB, &frame(1)).desc.spheres[0].center, DVec3::ONE);
    assert_eq!(radii(&read(dir.path(), "d.dump", DUMP, &frame(1))), [0.75]);
    for (name, text, count) in [("w.xyz", XYZ, 2), ("p.pdb", PDB, 2), ("w.gro", GRO, 1), ("d.dump", DUMP, 2)]
    {
        let path = write(dir.path(), name, text.as_bytes());
        let e = load_with(&path, &frame(7)).unwrap_err();
        let has =
            if count == 1 { "1 frame (frame 0)".to_owned() } else { format!("{count} frames (0 to 1)") };
        assert!(e.message.ends_with(&format!("the file has {has}")), "{name}: {e}");
    }
    // A frame is for particle files only.
    let path = write(dir.path(), "s.xyzr", b"0 0 0 1\n");
    assert!(load_with(&path, &frame(0)).is_err());
}

#[test]
fn overrides_beat_the_file_and_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let options = LoadOptions {
        radius: vec![("h".to_owned(), 0.3), ("2".to_owned(), 1.0)],
        color: vec![("O".to_owned(), Rgb::new(0.0, 1.0, 0.0)), ("Xe".to_owned(), Rgb::all(0.5))],
        radius_scale: Some(2.0),
        ..LoadOptions::default()
    };
    let xyz = read(dir.path(), "w.xyz", XYZ, &options);
    assert_eq!(radii(&xyz), [3.0, 0.6, 0.6], "H by the override, all doubled");
    assert_eq!(colour(&xyz, 0), Rgb::new(0.0, 1.0, 0.0));
    assert_eq!(xyz.warnings.len(), 2, "type 2 and Xe are in no frame: {:?}", xyz.warnings);
    let dump = read(dir.path(), "d.dump", DUMP, &options);
    assert_eq!(radii(&dump), [1.0, 2.0, 1.0], "type 2 by the override, all doubled");
}

#[test]
fn unknown_elements_get_the_fallback_and_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let read = read(dir.path(), "u.xyz", "3\n\nQq 0 0 0\nQq 1 0 0\nC 2 0 0\n", &LoadOptions::default());
    assert_eq!(radii(&read), [1.5, 1.5, 1.77]);
    assert_eq!(colour(&read, 0), Rgb::new(1.0, 20.0 / 255.0, 147.0 / 255.0), "pink #FF1493");
    assert_eq!(read.warnings.len(), 1);
    assert!(read.warnings[0].contains("`Qq` (2 particles)"), "{:?}", read.warnings);
    // A GRO atom without a name.
    let blank = "x\n    1\n    1SOL          1   0.126   1.624   1.679\n   1.0   1.0   1.0\n";
    let read = super::particle_files::read(dir.path(), "b.gro", blank, &LoadOptions::default());
    assert_eq!(read.warnings.len(), 1);
    assert!(
        read.warnings[0].starts_with("a blank name (1 particle) is not an element"),
        "{:?}",
        read.warnings
    );
}

/// Four- and five-site water models' charge sites (GROMACS's `MW`, AMBER's `EPW`, TIP5P's `LP1`/`LP2`) are
/// no atoms: left out with a warning counting them, drawn when given a radius; a file of nothing else is an
/// error that says why. A real element whose name starts alike (`MG`, magnesium) is drawn.
#[test]
fn virtual_sites_are_left_out_unless_given_a_radius() {
    let dir = tempfile::tempdir().unwrap();
    let tip4p = concat!(
        "tip4p\n    5\n",
        "    1SOL     OW    1   0.126   1.624   1.679\n",
        "    1SOL    HW1    2   0.190   1.661   1.747\n",
        "    1SOL    HW2    3   0.177   1.568   1.613\n",
        "    1SOL     MW    4   0.140   1.621   1.683\n",
        "    2MG      MG    5   0.500   0.500   0.500\n",
        "   1.86206   1.86206   1.86206\n"
    );
    let none = LoadOptions::default();
    let read_default = read(dir.path(), "w.gro", tip4p, &none);
    assert_eq!(read_default.desc.spheres.len(), 4, "O, H, H, Mg: the MW site left out");
    assert!((radii(&read_default)[3] - 0.251).abs() < 1e-12, "magnesium 2.51 Å in nm");
    assert_eq!(read_default.warnings.len(), 1, "{:?}", read_default.warnings);
    let warning = &read_default.warnings[0];
    assert!(warning.contains("`MW` (1 particle)") && warning.contains("--radius MW=R"), "{warning}");
    let given = LoadOptions { radius: vec![("mw".to_owned(), 0.01)], ..LoadOptions::default() };
    let drawn = read(dir.path(), "w.gro", tip4p, &given);
    assert_eq!(drawn.desc.spheres.len(), 5, "--radius draws them");
    assert_eq!(drawn.desc.spheres[3].radius, 0.01);
    assert!(drawn.warnings.is_empty(), "{:?}", drawn.warnings);
    // PDB names of AMBER's and TIP5P's sites, without an element column.
    let pdb = concat!(
        "ATOM      1  O   WAT     1       0.000   0.000   0.000  1.00  0.00\n",
        "ATOM      2  EPW WAT     1       0.150   0.000   0.000  1.00  0.00\n",
        "ATOM      3  LP1 WAT     2       5.000   0.000   0.000  1.00  0.00\n",
        "ATOM      4  LP2 WAT     2       5.000   0.500   0.000  1.00  0.00\n",
        "ATOM      5  OM  TIP4    3       9.000   0.000   0.000  1.00  0.00\n",
    );
    let sites = read(dir.path(), "s.pdb", pdb, &none);
    assert_eq!(radii(&sites), [1.5], "the oxygen alone");
    assert_eq!(sites.warnings.len(), 4, "one a kind (EPW, LP1, LP2, CHARMM's OM): {:?}", sites.warnings);
    assert!(sites.warnings[1].contains("`LP1` (1 particle)"), "{:?}", sites.warnings);
    let only = write(dir.path(), "m.pdb", pdb.lines().nth(1).unwrap().as_bytes());
    let e = load_with(&only, &none).unwrap_err();
    assert!(e.message.contains("no particles but 1 virtual site, not drawn"), "{e}");
}

/// `*` names every kind: a coarse-grained file's beads (Martini's `NC3` reads as nitrogen, `GL1` as
/// nothing, `W` as tungsten) drawn alike, a named kind's value beating it whatever the order, the sidecar's
/// `["*"]` beneath the flags; virtual sites stay out.
#[test]
fn a_wildcard_sets_every_kind_but_virtual_sites() {
    let dir = tempfile::tempdir().unwrap();
    let martini = concat!(
        "cg\n    4\n",
        "    1DPPC   NC3    1   1.000   1.000   1.000\n",
        "    1DPPC   GL1    2   1.000   1.000   1.400\n",
        "    2W        W    3   2.000   2.000   2.000\n",
        "    3SOL     MW    4   3.000   3.000   3.000\n",
        "   5.0   5.0   5.0\n"
    );
    let flags = LoadOptions {
        radius: vec![("W".to_owned(), 0.26), ("*".to_owned(), 0.235)],
        color: vec![("*".to_owned(), Rgb::new(0.0, 0.5, 1.0))],
        ..LoadOptions::default()
    };
    let read = read(dir.path(), "cg.gro", martini, &flags);
    assert_eq!(radii(&read), [0.235, 0.235, 0.26], "W named beats `*` given after it; MW left out");
    assert!((0..3).all(|i| colour(&read, i) == Rgb::new(0.0, 128.0 / 255.0, 1.0)), "every bead coloured");
    assert_eq!(read.warnings.len(), 1, "only the virtual site's: {:?}", read.warnings);
    assert!(read.warnings[0].contains("`MW`"), "{:?}", read.warnings);
    // The sidecar's `*` and a named kind; the flags' `*` beats both.
    let sidecar = write(dir.path(), "cg.types.toml", b"[\"*\"]\nradius = 0.2\n\n[GL1]\nradius = 0.3\n");
    let by_sidecar = LoadOptions { types: Some(sidecar), ..LoadOptions::default() };
    assert_eq!(radii(&read_with(dir.path(), martini, &by_sidecar)), [0.2, 0.3, 0.2]);
    let both = LoadOptions { radius: vec![("*".to_owned(), 0.25)], ..by_sidecar };
    assert_eq!(radii(&read_with(dir.path(), martini, &both)), [0.25, 0.25, 0.25]);
}

fn read_with(dir: &Path, text: &str, options: &LoadOptions) -> SceneRead {
    read(dir, "cg.gro", text, options)
}

#[test]
fn triclinic_scaled_coordinates_land_on_the_known_point() {
    // lx 10, ly 8, lz 6 from the origin, tilts xy 2, xz -1, yz 1; LAMMPS writes the bounding box's bounds.
    let (xy, xz, yz) = (2.0f64, -1.0f64, 1.0f64);
    let xlo_b = 0f64.min(xy).min(xz).min(xy + xz);
    let xhi_b = 10.0 + 0f64.max(xy).max(xz).max(xy + xz);
    let (ylo_b, yhi_b) = (0f64.min(yz), 8.0 + 0f64.max(yz));
    let text = format!(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS xy xz yz pp pp pp\n{xlo_b} {xhi_b} {xy}\n\
         {ylo_b} {yhi_b} {xz}\n0 6 {yz}\nITEM: ATOMS ys id zs type xs\n0.25 1 0.5 1 0.5\n"
    );
    let dir = tempfile::tempdir().unwrap();
    let read = read(dir.path(), "t.dump", &text, &LoadOptions::default());
    // a = (10,0,0), b = (2,8,0), c = (-1,1,6): 0.5 a + 0.25 b + 0.5 c.
    let want = DVec3::new(5.0 + 0.5 - 0.5, 2.0 + 0.5, 3.0);
    assert!((read.desc.spheres[0].center - want).length() < 1e-12, "{:?}", read.desc.spheres[0].center);
}

#[test]
fn hostile_inputs_are_errors_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str, usize, &str)] = &[
        ("a.xyz", "2\nc\nC 0 0 0\nC 0 nan 0\n", 4, "expected y"),
        ("b.xyz", "5\nc\nC 0 0 0\n", 3, "the file ends here"),
        ("c.xyz", "x\nc\n", 1, "particle count"),
        ("d.extxyz", "1\nProperties=species:S:1:pos:R:3:radius:R:1\nC 0 0 0 -1\n", 3, "positive"),
        ("e.pdb", "ATOM      1  N   GLY A   1      -1.000   2.0\n", 1, "columns 31-54"),
        ("f.pdb", "ATOM      1  N   GLY A   1      -1.000   2.000   3.0x0\n", 1, "z in columns 47-54"),
        ("g.pqr", "ATOM 1 N MET 1 0 0 0 0.1\n", 1, "fields"),
        ("h.gro", "t\n 2\n    1SOL     OW    1   0.126   1.624   1.679\n", 3, "the file ends here"),
        ("i.gro", "t\n 1\n    1SOL     OW    1   0.126   1.624   1.679\n 1 1\n", 4, "box line"),
        ("j.dump", "ITEM: NUMBER OF ATOMS\n1\nITEM: ATOMS id type q\n1 1 0\n", 3, "no x y z"),
        ("k.dump", "ITEM: NUMBER OF ATOMS\n2\nITEM: ATOMS x y z\n1 1 1\nITEM: TIMESTEP\n", 5, "said 2"),
        ("l.dump", "ITEM: ATOMS x y z\n1 1 1\n", 1, "before ITEM: NUMBER OF ATOMS"),
        ("m.dump", "ITEM: NUMBER OF ATOMS\n1\nITEM: ATOMS xs ys zs\n0 0 0\n", 3, "need the box"),
        ("n.dump", "ITEM: NUMBER OF ATOMS\n1\nITEM: ATOMS x y z diameter\n0 0 0 -2\n", 4, "positive"),
    ];
    for &(name, text, line, message) in cases {
        let path = write(dir.path(), name, text.as_bytes());
        let e = load_with(&path, &LoadOptions::default()).expect_err(name);
        assert_eq!(e.line, line, "{name}: {e}");
        assert!(e.message.contains(message), "{name}: {e}");
        assert!(e.to_string().starts_with(&format!("{}:{line}: ", path.display())), "{e}");
    }
}

#[test]
fn a_types_sidecar_sits_between_the_file_and_the_flags() {
    let dir = tempfile::tempdir().unwrap();
    let none = LoadOptions::default();
    // Found beside the file: type 1 gets the sidecar's radius and colour, type 2 its radius only.
    let sidecar = "[1]\nradius = 0.3\ncolor = [0, 1, 0]\n\n[2]\nradius = 0.8\n\n[7]\nradius = 9\n";
    write(dir.path(), "d.dump.types.toml", sidecar.as_bytes());
    let dump = read(dir.path(), "d.dump", DUMP, &none);
    assert_eq!(radii(&dump), [0.3, 0.8, 0.3]);
    assert_eq!(colour(&dump, 0), Rgb::new(0.0, 1.0, 0.0));
    assert_eq!(colour(&dump, 1), Rgb::new(50.0 / 255.0, 100.0 / 255.0, 230.0 / 255.0), "type 2's default");
    assert!(dump.warnings.is_empty(), "a kind the frame lacks is no warning: {:?}", dump.warnings);
    // The flags beat it; a compressed file finds the plain name's sidecar.
    let flags = LoadOptions { radius: vec![("1".to_owned(), 0.4)], ..LoadOptions::default() };
    let packed = write(dir.path(), "d.dump.gz", &gzip(DUMP.as_bytes()));
    assert_eq!(radii(&load_with(&packed, &flags).unwrap()), [0.4, 0.8, 0.4]);
    // A sidecar named with `types` replaces the one beside the file, and beats the file's own radius.
    let other = write(dir.path(), "other.toml", b"[Si]\nradius = 2\n[XQ]\ncolor = [1, 1, 1]\n");
    let named = LoadOptions { types: Some(other.clone()), ..LoadOptions::default() };
    assert_eq!(radii(&load_with(&dir.path().join("d.dump"), &named).unwrap()), [0.5, 0.5, 0.5]);
    let ext = read(dir.path(), "e.extxyz", EXTXYZ, &named);
    assert_eq!(radii(&ext), [2.0, 0.25]);
    assert_eq!(colour(&ext, 1), Rgb::all(1.0), "kinds match in any case");

    // Its errors name it and the line; a named sidecar that is missing is an error too.
    write(dir.path(), "w.xyz.types.toml", b"[O]\nradius = 1\n[H]\ncolour = [1, 0, 0]\n");
    let e = load_with(&write(dir.path(), "w.xyz", XYZ.as_bytes()), &none).unwrap_err();
    assert_eq!((e.path.file_name().unwrap().to_str(), e.line), (Some("w.xyz.types.toml"), 4), "{e}");
    assert!(e.message.contains("unknown field `colour`"), "{e}");
    let gone = LoadOptions { types: Some(dir.path().join("gone.toml")), ..LoadOptions::default() };
    let e = load_with(&dir.path().join("d.dump"), &gone).unwrap_err();
    assert!(e.path.ends_with("gone.toml") && e.message.starts_with("cannot read types file"), "{e}");
    // Like every particle choice, a sidecar is an error for other formats.
    let xyzr = write(dir.path(), "s.xyzr", b"0 0 0 1\n");
    assert!(load_with(&xyzr, &named).is_err());
}

#[test]
fn the_periodic_box_is_drawn_as_cylinders_and_framed() {
    let dir = tempfile::tempdir().unwrap();
    let boxed = LoadOptions { draw_box: true, ..LoadOptions::default() };
    let cryst = "CRYST1   20.000   20.000   20.000  90.00  90.00  90.00 P 1           1\n";
    let triclinic = "ITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS xy xz yz pp pp pp\n0 13 2\n-1 8 1\n0 6 -1\n\
                     ITEM: ATOMS type x y z\n1 1 1 1\n";
    let cases: [(&str, String, usize, [DVec3; 2]); 5] = [
        ("w.gro", GRO.to_owned(), 3, [DVec3::ZERO, DVec3::splat(1.86206)]),
        ("d.dump", DUMP.to_owned(), 3, [DVec3::ZERO, DVec3::splat(10.0)]),
        ("e.extxyz", EXTXYZ.to_owned(), 2, [DVec3::ZERO, DVec3::splat(10.0)]),
        ("p.pdb", format!("{cryst}{PDB}"), 3, [DVec3::ZERO, DVec3::splat(20.0)]),
        // a = (10,0,0), b = (2,8,0), c = (1,-1,6) from (0,0,0): the far corner is a + b + c.
        ("t.dump", triclinic.to_owned(), 1, [DVec3::ZERO, DVec3::new(13.0, 7.0, 6.0)]),
    ];
    for (name, text, particles, [near, far]) in cases {
        let plain = read(dir.path(), name, &text, &LoadOptions::default()).desc;
        assert!(
            plain.kinds.cones.is_empty() && plain.spheres.len() == particles,
            "{name}: no box unless asked"
        );
        let read = read(dir.path(), name, &text, &boxed);
        let desc = &read.desc;
        assert!(read.warnings.is_empty(), "{name}: {:?}", read.warnings);
        assert_eq!(
            (desc.kinds.cones.len(), desc.spheres.len()),
            (12, particles + 8),
            "{name}: 12 edges, 8 corners"
        );
        assert_eq!(desc.sphere_colors.len(), desc.spheres.len(), "{name}: the corners have colours too");
        let corners: Vec<DVec3> = desc.spheres[particles..].iter().map(|s| s.center).collect();
        for corner in [near, far] {
            assert!(corners.iter().any(|c| (*c - corner).length() < 1e-9), "{name}: {corner} in {corners:?}");
        }
        let r = desc.kinds.cones[0].base_radius;
        let diagonal = (far - near).length();
        assert!(
            (r - 0.0015 * diagonal).abs() < 1e-9 * diagonal,
            "{name}: radius {r} for diagonal {diagonal}"
        );
        for cone in &desc.kinds.cones {
            assert_eq!((cone.base_radius, cone.apex_radius, cone.material), (r, r, 1), "{name}");
            let on_corner = |p: DVec3| corners.iter().any(|c| (*c - p).length() < 1e-9);
            assert!(on_corner(cone.base) && on_corner(cone.apex), "{name}: an edge between corners");
        }
        assert_eq!(desc.materials.len(), 2, "{name}: the particles' material and the box's");
        // Seen from +z, the eye is over the centre of what is drawn: the particles and the box's corners.
        let lo = desc.spheres.iter().fold(DVec3::INFINITY, |lo, s| lo.min(s.center - s.radius));
        let hi = desc.spheres.iter().fold(DVec3::NEG_INFINITY, |hi, s| hi.max(s.center + s.radius));
        let centre = (lo + hi) * 0.5;
        assert!(lo.cmple(near).all() && hi.cmpge(far).all(), "{name}: the box is framed");
        let eye = desc.camera.eye;
        assert!((eye.x - centre.x).abs() < 1e-9 && (eye.y - centre.y).abs() < 1e-9, "{name}: {eye}");
    }
    // A file without a box, or with an empty one, draws none and says so.
    for (name, text) in
        [("q.pqr", PQR.to_owned()), ("z.gro", GRO.replace("   1.86206   1.86206   1.86206", "0 0 0"))]
    {
        let read = read(dir.path(), name, &text, &boxed);
        assert!(read.desc.kinds.cones.is_empty(), "{name}");
        assert_eq!(read.warnings.len(), 1, "{name}: {:?}", read.warnings);
        assert!(read.warnings[0].starts_with("--box: "), "{:?}", read.warnings);
    }
}
