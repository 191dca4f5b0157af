//! Mutated particle files: small valid samples of each particle format (XYZ, extended XYZ, PDB, PQR, GRO
//! with a water model's virtual site, LAMMPS dump, a gzip-compressed XYZ and a bzip2-compressed PDB) with
//! bytes flipped, lines cut, duplicated or dropped, and the whole cut short, parsed with a random frame and with or without the periodic box drawn; and mutated types
//! sidecars. Every input must give a scene or an error naming the file and a line within the text (or the
//! file as a whole); none may panic.
//!
//! Each input is a function of (sample, index) alone. The default test runs [`CI_RUN`] inputs per sample;
//! the ignored one [`FULL_RUN`]: `cargo test --lib fuzz_particles:: -- --ignored --nocapture`, which prints
//! the count per sample.

use std::io::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use bareray::io::{parse_with, LoadOptions, SceneFormat};
use bareray::math::SplitMix64;

const FULL_RUN: u64 = 100_000;
const CI_RUN: u64 = 2_000;

const SAMPLES: &[(&str, &str)] = &[
    ("s.xyz", "3\nwater\nO 0.0 0.0 0.0\nH 0.96 0.0 0.0\nH -0.24 0.93 0.0\n2\nnext\nC 0 0 0\nCl 1.8 0 0\n"),
    ("s.extxyz", "2\nLattice=\"5 0 0 1 5 0 0 0 5\" Origin=\"0 0 -1\" Properties=species:S:1:pos:R:3:radius:R:1:color:R:3 t=1\nSi 0 0 0 0.5 1 0 0\nXq 1 2 3 0.25 0 0 1\n"),
    (
        "s.pdb",
        "CRYST1   10.000   20.000   30.000  90.00 100.00  90.00 P 1           1\nMODEL        1\n\
         ATOM      1  N   GLY A   1      -1.000   2.000   3.000  1.00  0.00           N\n\
         HETATM    3 FE   HEM A   2       5.000   5.000   5.000  1.00  0.00\n\
         ENDMDL\nMODEL        2\n\
         ATOM      1  N   GLY A   1       1.000   1.000   1.000  1.00  0.00           N\nENDMDL\nEND\n",
    ),
    ("s.pqr", "CRYST1 5 5 5 90 90 120\nATOM      1  N   MET     1      1.0   2.0   3.0 -0.30 1.824\nATOM      2  O   MET A   1      0.0   0.0   0.0 -0.50 1.7\n"),
    (
        "s.gro",
        "water\n    3\n    1SOL     OW    1   0.126   1.624   1.679\n    1SOL    HW1    2   0.190   1.661   1.747\n    1SOL     MW    3   0.140   1.621   1.683\n   1.86206   1.86206   1.86206\n",
    ),
    (
        "s.lammpstrj",
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS xy xz yz pp pp pp\n0 13 2\n-1 8 1\n0 6 -1\n\
         ITEM: ATOMS id type xs ys zs diameter\n1 1 0.1 0.2 0.3 1.0\n2 2 0.5 0.5 0.5 2.0\n\
         ITEM: TIMESTEP\n1\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n0 1\nITEM: ATOMS element x y z\nO 0 0 0\n",
    ),
];

/// Bytes a flip writes: the ones that change how a reader splits and reads a line.
const INTERESTING: &[u8] = b" \n\t.-+e0123456789nNaAIiMTXxyzsu:=\"#\xff\xc3";

fn mutate(sample: &[u8], rng: &mut SplitMix64) -> Vec<u8> {
    let mut bytes = sample.to_vec();
    let pick = |rng: &mut SplitMix64, n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    for _ in 0..1 + pick(rng, 4) {
        let lines: Vec<usize> = std::iter::once(0)
            .chain(bytes.iter().enumerate().filter(|(_, &b)| b == b'\n').map(|(i, _)| i + 1))
            .collect();
        match pick(rng, 6) {
            0 | 1 if !bytes.is_empty() => {
                let at = pick(rng, bytes.len());
                bytes[at] = INTERESTING[pick(rng, INTERESTING.len())];
            }
            2 => bytes.truncate(pick(rng, bytes.len() + 1)),
            3 | 4 if lines.len() > 1 => {
                let k = pick(rng, lines.len() - 1);
                let line = bytes[lines[k]..lines[k + 1]].to_vec();
                if pick(rng, 2) == 0 {
                    bytes.splice(lines[k]..lines[k], line);
                } else {
                    bytes.drain(lines[k]..lines[k + 1]);
                }
            }
            _ => {
                let at = pick(rng, bytes.len() + 1);
                bytes.insert(at, INTERESTING[pick(rng, INTERESTING.len())]);
            }
        }
    }
    bytes
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}

/// Runs `inputs` mutations of every sample (and of the gzip-compressed XYZ and bzip2-compressed PDB samples);
/// panics on a panic or a badly placed error.
fn run(inputs: u64) {
    let mut samples: Vec<(String, Vec<u8>)> =
        SAMPLES.iter().map(|(n, t)| (n.to_string(), t.as_bytes().to_vec())).collect();
    samples.push(("s.xyz.gz".to_owned(), gzip(SAMPLES[0].1.as_bytes())));
    samples.push(("s.pdb.bz2".to_owned(), super::common::samples::bzip(SAMPLES[2].1.as_bytes())));
    for (k, (name, sample)) in samples.iter().enumerate() {
        let path = Path::new(name.as_str());
        let format = SceneFormat::from_extension(path).expect("a particle extension");
        let (mut read, mut errors) = (0u64, 0u64);
        for i in 0..inputs {
            let mut rng = SplitMix64::new(0x5EED_0000 ^ (k as u64) << 40 ^ i);
            let input = mutate(sample, &mut rng);
            let frame = Some((rng.next_u64() % 3) as usize);
            let options =
                LoadOptions { frame, draw_box: rng.next_u64().is_multiple_of(2), ..LoadOptions::default() };
            let text_lines = input.iter().filter(|&&b| b == b'\n').count() + 1;
            let result = catch_unwind(AssertUnwindSafe(|| parse_with(format, path, input.clone(), &options)));
            match result {
                Err(_) => panic!("{name}: input {i} panicked: {:?}", String::from_utf8_lossy(&input)),
                Ok(Ok(_)) => read += 1,
                Ok(Err(e)) => {
                    errors += 1;
                    assert!(e.path == path, "{name}: input {i}: {e}");
                    // Line numbers of a compressed file count its decompressed lines.
                    assert!(
                        name.ends_with(".gz") || name.ends_with(".bz2") || e.line <= text_lines,
                        "{name}: input {i}: line {} of {text_lines}: {e}",
                        e.line
                    );
                }
            }
        }
        println!("fuzz: {name}: {inputs} inputs, {read} read, {errors} errors, no panic");
    }
    let sidecar = b"[1]\nradius = 0.5\ncolor = [0.9, 0.2, 0.2]\n\n[O]\ncolor = [1, 0, 0]\n";
    let path = Path::new("s.types.toml");
    let (mut read, mut errors) = (0u64, 0u64);
    for i in 0..inputs {
        let mut rng = SplitMix64::new(0x5EED_7000 ^ i);
        let input = String::from_utf8_lossy(&mutate(sidecar, &mut rng)).into_owned();
        let text_lines = input.matches('\n').count() + 1;
        match catch_unwind(|| bareray::io::particles::types::parse(path, &input)) {
            Err(_) => panic!("s.types.toml: input {i} panicked: {input:?}"),
            Ok(Ok(_)) => read += 1,
            Ok(Err(e)) => {
                errors += 1;
                assert!(e.path == path && e.line <= text_lines, "s.types.toml: input {i}: {e}");
            }
        }
    }
    println!("fuzz: s.types.toml: {inputs} inputs, {read} read, {errors} errors, no panic");
}

#[test]
fn mutated_particle_files_give_scenes_or_located_errors() {
    run(CI_RUN);
}

#[test]
#[ignore = "the full run: 1e5 inputs per sample"]
fn mutated_particle_files_full_run() {
    run(FULL_RUN);
}
