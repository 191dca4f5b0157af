//! Helpers shared by the binary's tests (the `suite` and `mpi` binaries): the one call of the binary, its
//! standard error as text and scene-file listing.

// The suite and the MPI tests each compile this module and use only part of it.
#![allow(dead_code, unused_imports)]

#[path = "../library/common/files.rs"]
mod files;
#[path = "../library/common/samples.rs"]
pub mod samples;
#[path = "../library/common/watchdog.rs"]
pub mod watchdog;

pub use files::scene_files;

use std::process::{Command, Output};

/// Runs the `bareray` binary built with the tests.
pub fn bareray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bareray")).args(args).output().expect("bareray runs")
}

/// The binary's standard error as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}
