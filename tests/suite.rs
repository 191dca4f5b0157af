//! The tests of the `bareray` binary, compiled as one binary: each file of `tests/` is a module here, run one
//! file's tests with `cargo test --test suite NAME::`, e.g. `cargo test --test suite layers::`. The tests of
//! the library's own items are in `tests/library/`, compiled into the library's test build (`cargo test
//! --lib NAME::`), where its crate-private items are in reach. The MPI tests (`tests/mpi.rs`, feature `mpi`)
//! stay a binary of their own.

mod common;

#[path = "accuracy.rs"]
mod accuracy;
#[path = "bench_kinds.rs"]
mod bench_kinds;
#[path = "cli.rs"]
mod cli;
#[path = "fuzz_merge.rs"]
mod fuzz_merge;
#[path = "layers.rs"]
mod layers;
#[path = "particle_files.rs"]
mod particle_files;
#[path = "readers.rs"]
mod readers;
#[path = "sphere_colors.rs"]
mod sphere_colors;
#[path = "stills.rs"]
mod stills;
#[path = "tori.rs"]
mod tori;
