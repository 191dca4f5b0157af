//! The command line's value enums for choices the library names in its own types: clap stays in `cli`, and
//! each enum converts to the library's type.

use crate::compile::{Accel, BvhPreset};
use crate::scene::desc::Transfer;

/// `--transfer`: [`Transfer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TransferArg {
    /// The values are linear radiance, encoded with the sRGB curve (clamped to [0, 1]): TOML scenes.
    Srgb,
    /// The values are written as they are: clamped to [0, 1], times 255, rounded. What SPD's, POV-Ray's
    /// and Tachyon's renders of NFF scenes do, whose colours are display values: NFF and xyzr scenes.
    Linear,
}

impl From<TransferArg> for Transfer {
    fn from(t: TransferArg) -> Self {
        match t {
            TransferArg::Srgb => Transfer::Srgb,
            TransferArg::Linear => Transfer::Linear,
        }
    }
}

/// The name a value has on the command line (what `--help` lists and the user types), for reports.
pub fn name(value: impl clap::ValueEnum) -> String {
    value.to_possible_value().map_or_else(String::new, |v| v.get_name().to_owned())
}

/// `--accel`: [`Accel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AccelArg {
    /// A BVH for each kind of primitive with 4 or more items, brute force below.
    Auto,
    /// A BVH for every kind with items.
    Bvh,
    /// Always brute force.
    Brute,
}

impl From<AccelArg> for Accel {
    fn from(a: AccelArg) -> Self {
        match a {
            AccelArg::Auto => Accel::Auto,
            AccelArg::Bvh => Accel::Bvh,
            AccelArg::Brute => Accel::Brute,
        }
    }
}

/// `--bvh-preset`: [`BvhPreset`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BvhPresetArg {
    /// obvhs `fastest_build`: leaves of one sphere, no reinsertion.
    Fastest,
    /// obvhs `very_fast_build`: the quickest build; on uniform random fields it also traces faster than
    /// `fast`, on sphereflakes 8–10% slower (docs/perf-log/2026-11.md).
    VeryFast,
    /// obvhs `fast_build`, the default: the best traced speed on structured scenes.
    Fast,
    /// obvhs `medium_build`.
    Medium,
    /// obvhs `slow_build`.
    Slow,
}

impl From<BvhPresetArg> for BvhPreset {
    fn from(p: BvhPresetArg) -> Self {
        match p {
            BvhPresetArg::Fastest => BvhPreset::Fastest,
            BvhPresetArg::VeryFast => BvhPreset::VeryFast,
            BvhPresetArg::Fast => BvhPreset::Fast,
            BvhPresetArg::Medium => BvhPreset::Medium,
            BvhPresetArg::Slow => BvhPreset::Slow,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn every_value_names_the_library_value_of_the_same_name() {
        for t in TransferArg::value_variants() {
            let name = t.to_possible_value().expect("not skipped").get_name().to_owned();
            assert_eq!(Transfer::from(*t).name(), name);
        }
        for p in BvhPresetArg::value_variants() {
            let name = p.to_possible_value().expect("not skipped").get_name().replace('-', "");
            assert_eq!(format!("{:?}", BvhPreset::from(*p)).to_lowercase(), name);
        }
    }
}
