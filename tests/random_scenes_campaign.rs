//! The random-scene campaign as a test binary of its own, so that the whole campaign runs by the name of its
//! file without building the rest of the suite: `cargo test --release --test random_scenes -- --ignored
//! --nocapture`. `cargo test` does not build this target (`test = false` in Cargo.toml): the CI share of
//! the campaign runs once, in the `suite` binary.

mod common;

#[path = "random_scenes.rs"]
mod random_scenes;
