//! The command line's value enums for choices the library names in its own types (clap stays in `cli`, and
//! each enum converts to the library's type), and the parsers of counts: lanes, threads, samples, bytes.

use bareray::compile::{Accel, BvhPreset};
use bareray::scene::desc::Transfer;

/// `--lanes`: the scalar path, or a packet width.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(super) enum LanesArg {
    /// `scalar`: one ray against one box and one primitive at a time, over each BVH's binary tree (the scene
    /// is compiled with [`bareray::compile::CompileOptions::scalar`] and traced at K = 1).
    Scalar,
    /// Packets of this many rays: 1 (single-ray SIMD: one ray against a wide node's children, and a leaf's
    /// spheres, at once), 4, 8 or 16.
    Packet(usize),
}

impl LanesArg {
    /// The packet width the renderer runs at: 1 for the scalar path.
    pub(super) fn k(self) -> usize {
        match self {
            LanesArg::Scalar => 1,
            LanesArg::Packet(k) => k,
        }
    }

    /// Whether this is the scalar path.
    pub(super) fn is_scalar(self) -> bool {
        self == LanesArg::Scalar
    }
}

impl std::fmt::Display for LanesArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LanesArg::Scalar => f.pad("scalar"),
            LanesArg::Packet(k) => f.pad(&k.to_string()),
        }
    }
}

/// In JSON a packet width is its number and the scalar path the string `"scalar"`.
impl serde::Serialize for LanesArg {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            LanesArg::Scalar => s.serialize_str("scalar"),
            LanesArg::Packet(k) => s.serialize_u64(*k as u64),
        }
    }
}

impl<'de> serde::Deserialize<'de> for LanesArg {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Json {
            Width(usize),
            Name(String),
        }
        match Json::deserialize(d)? {
            Json::Width(k) => Ok(LanesArg::Packet(k)),
            Json::Name(name) => parse_lanes(&name).map_err(serde::de::Error::custom),
        }
    }
}

/// Parses `--lanes`: `scalar`, or a packet width of [`bareray::render::LANE_CHOICES`].
pub(super) fn parse_lanes(s: &str) -> Result<LanesArg, String> {
    match s.trim() {
        "scalar" => Ok(LanesArg::Scalar),
        k => match k.parse::<usize>() {
            Ok(k) if bareray::render::LANE_CHOICES.contains(&k) => Ok(LanesArg::Packet(k)),
            _ => Err(format!("lanes must be scalar, 1, 4, 8 or 16, got `{s}`")),
        },
    }
}

/// `--transfer`: [`Transfer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum TransferArg {
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

/// Parses `--spp`: a square number.
pub(super) fn parse_spp(s: &str) -> Result<u32, String> {
    let spp = s
        .trim()
        .parse::<u32>()
        .map_err(|_| format!("expected a square number (1, 4, 9, 16, ...), got `{s}`"))?;
    bareray::io::toml::grid_side(spp)?;
    Ok(spp)
}

/// Parses a thread count, 1 to 1024.
pub(super) fn parse_threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(t) if (1..=1024).contains(&t) => Ok(t),
        _ => Err("thread counts run from 1 to 1024".to_owned()),
    }
}

/// The name a value has on the command line (what `--help` lists and the user types), for reports.
pub(super) fn name(value: impl clap::ValueEnum) -> String {
    value.to_possible_value().map_or_else(String::new, |v| v.get_name().to_owned())
}

/// A byte count with an optional K, M, G or T suffix (powers of 1024): `--memory 8G`.
pub(super) fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (digits, shift) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(format!("'{s}': the suffix must be K, M, G or T")),
            };
            (&t[..i], shift)
        }
        _ => (t, 0),
    };
    let value: f64 = digits.parse().map_err(|_| format!("'{s}' is not a byte count such as 512M or 8G"))?;
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("'{s}': a byte count must be at least 1"));
    }
    Ok(bytes as u64)
}

/// `--accel`: [`Accel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum AccelArg {
    /// A BVH for each kind of primitive with 4 or more items, brute force below.
    Auto,
    /// A BVH for every kind with items.
    Bvh,
    /// Always brute force.
    Brute,
    /// Spheres in the particle tree (5 bytes per sphere beside the spheres, for fields too large for a
    /// BVH); an `.f32r` file is mapped, not read.
    Pkd,
}

impl From<AccelArg> for Accel {
    fn from(a: AccelArg) -> Self {
        match a {
            AccelArg::Auto => Accel::Auto,
            AccelArg::Bvh => Accel::Bvh,
            AccelArg::Brute => Accel::Brute,
            AccelArg::Pkd => Accel::Particles,
        }
    }
}

/// `--bvh-preset`: [`BvhPreset`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum BvhPresetArg {
    /// The default: the spheres' tree by Morton order down to ranges of 1024 spheres, by the binned SAH below;
    /// the other kinds' by the SAH.
    Morton,
    /// bareray's binned SAH builder at every level.
    Sah,
    /// obvhs `fastest_build`: leaves of one sphere, no reinsertion.
    Fastest,
    /// obvhs `very_fast_build`: the quickest build; on uniform random fields it also traces faster than
    /// `fast`, on sphereflakes slower (docs/perf-log/2026-11.md, "Tried, measured, not kept").
    VeryFast,
    /// obvhs `fast_build`.
    Fast,
    /// obvhs `medium_build`.
    Medium,
    /// obvhs `slow_build`.
    Slow,
}

impl From<BvhPresetArg> for BvhPreset {
    fn from(p: BvhPresetArg) -> Self {
        match p {
            BvhPresetArg::Morton => BvhPreset::Morton,
            BvhPresetArg::Sah => BvhPreset::Sah,
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

    #[test]
    fn lanes_parse_and_round_trip_through_json() {
        assert_eq!(parse_lanes("scalar"), Ok(LanesArg::Scalar));
        assert_eq!(parse_lanes(" 8 "), Ok(LanesArg::Packet(8)));
        for bad in ["0", "2", "32", "Scalar", "", "x"] {
            assert!(parse_lanes(bad).unwrap_err().contains("scalar, 1, 4, 8 or 16"), "{bad}");
        }
        for lanes in [LanesArg::Scalar, LanesArg::Packet(1), LanesArg::Packet(16)] {
            let json = serde_json::to_string(&lanes).unwrap();
            assert_eq!(serde_json::from_str::<LanesArg>(&json).unwrap(), lanes, "{json}");
        }
        assert_eq!(serde_json::to_string(&LanesArg::Scalar).unwrap(), "\"scalar\"");
        assert_eq!(serde_json::to_string(&LanesArg::Packet(4)).unwrap(), "4");
        assert_eq!((LanesArg::Scalar.k(), LanesArg::Packet(8).k()), (1, 8));
        assert_eq!(format!("{:>7}|{}", LanesArg::Scalar, LanesArg::Packet(4)), " scalar|4");
    }

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
