//! Small hand-written particle files of every format, and helpers that write them (plain, gzip, bzip2).

use std::io::Write;
use std::path::{Path, PathBuf};

/// Water and a methane-ish fragment in two XYZ frames.
pub const XYZ: &str =
    "3\nwater\nO 0.0 0.0 0.0\nH 0.96 0.0 0.0\nH -0.24 0.93 0.0\n2\nsecond frame\nC 0 0 0\nCl 1.8 0 0\n";
pub const EXTXYZ: &str =
    "2\nLattice=\"10 0 0 0 10 0 0 0 10\" Properties=species:S:1:pos:R:3:radius:R:1:color:R:3 pbc=\"T T T\"\n\
                      Si 0 0 0 0.5 1 0 0\nXq 1 2 3 0.25 0 0 1\n";
pub const PDB: &str = "\
HEADER    TEST
MODEL        1
ATOM      1  N   GLY A   1      -1.000   2.000   3.000  1.00  0.00           N
ATOM      2  CA  GLY A   1       0.000   0.000   0.000  1.00  0.00           C
HETATM    3 FE   HEM A   2       5.000   5.000   5.000  1.00  0.00
ENDMDL
MODEL        2
ATOM      1  N   GLY A   1       1.000   1.000   1.000  1.00  0.00           N
ENDMDL
END
";
pub const PQR: &str = "ATOM      1  N   MET     1      1.0   2.0   3.0 -0.30 1.824\nATOM      2  O   MET     1      0.0   0.0   0.0 -0.50 1.7\n";
pub const GRO: &str = concat!(
    "water\n    3\n",
    "    1SOL     OW    1   0.126   1.624   1.679\n",
    "    1SOL    HW1    2   0.190   1.661   1.747\n",
    "    1SOL    HW2    3   0.177   1.568   1.613\n",
    "   1.86206   1.86206   1.86206\n"
);
pub const DUMP: &str = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n0 10\n\
                    ITEM: ATOMS id type x y z\n1 1 1 1 1\n2 2 2 2 2\n3 1 3 3 3\n\
                    ITEM: TIMESTEP\n100\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n0 10\n\
                    ITEM: ATOMS id type x y z radius\n1 3 5 5 5 0.75\n";

pub fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}

pub fn bzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}
