//! The command line's value enums for choices the library names in its own types: clap stays in `cli`, and
//! each enum converts to the library's type.

use crate::compile::{Accel, BvhPreset};
use crate::scene::desc::{Filter, FilterKind, Pattern, Shade, Transfer};

/// `--lanes`: the scalar path, or a packet width.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LanesArg {
    /// `scalar`: one ray against one box and one primitive at a time, over each BVH's binary tree (the scene
    /// is compiled with [`crate::compile::CompileOptions::scalar`] and traced at K = 1).
    Scalar,
    /// Packets of this many rays: 1 (single-ray SIMD: one ray against a wide node's children, and a leaf's
    /// spheres, at once), 4, 8 or 16.
    Packet(usize),
}

impl LanesArg {
    /// The packet width the renderer runs at: 1 for the scalar path.
    pub fn k(self) -> usize {
        match self {
            LanesArg::Scalar => 1,
            LanesArg::Packet(k) => k,
        }
    }

    /// Whether this is the scalar path.
    pub fn is_scalar(self) -> bool {
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

/// Parses `--lanes`: `scalar`, or a packet width of [`crate::render::LANE_CHOICES`].
pub fn parse_lanes(s: &str) -> Result<LanesArg, String> {
    match s.trim() {
        "scalar" => Ok(LanesArg::Scalar),
        k => match k.parse::<usize>() {
            Ok(k) if crate::render::LANE_CHOICES.contains(&k) => Ok(LanesArg::Packet(k)),
            _ => Err(format!("lanes must be scalar, 1, 4, 8 or 16, got `{s}`")),
        },
    }
}

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

/// Parses `--aa METHOD[:N]`: `grid:N` and `stratified:N` (N a square number of samples per pixel), `r2:N`
/// and `sobol:N` (any N from 1), `lecture` (the half-pixel pattern, no N), `adaptive[:T,D]`, `coverage` (no N).
pub fn parse_aa(s: &str) -> Result<Pattern, String> {
    let (method, count) = match s.trim().split_once(':') {
        Some((m, n)) => (m, Some(n)),
        None => (s.trim(), None),
    };
    let samples = || -> Result<u32, String> {
        let n = count.ok_or_else(|| format!("`{method}` takes a sample count: `{method}:N`"))?;
        match n.trim().parse::<u32>() {
            Ok(n) if (1..=65_536).contains(&n) => Ok(n),
            _ => Err(format!("samples per pixel run from 1 to 65536, got `{n}`")),
        }
    };
    let side = |n: u32| {
        crate::io::toml::grid_side(n).map_err(|_| {
            let (lo, hi) = ((n as f64).sqrt().floor() as u32, (n as f64).sqrt().ceil() as u32);
            format!("`{method}:{n}`: N is samples per pixel, a square ({method}:{} is {lo}×{lo}, {method}:{} is {hi}×{hi})", lo * lo, hi * hi)
        })
    };
    match method {
        "grid" => Ok(Pattern::Grid(side(samples()?)?)),
        "stratified" => Ok(Pattern::Stratified(side(samples()?)?)),
        "r2" => Ok(Pattern::R2(samples()?)),
        "sobol" => Ok(Pattern::Sobol(samples()?)),
        "adaptive" => adaptive(count),
        "lecture" if count.is_none() => Ok(Pattern::HalfPixel),
        "lecture" => Err("`lecture` is the 9-point half-pixel grid and takes no count".to_owned()),
        "coverage" if count.is_none() => Ok(Pattern::Coverage),
        "coverage" => Err("`coverage` computes each pixel's covered areas and takes no count".to_owned()),
        _ => Err(format!(
            "unknown method `{method}`: grid:N, stratified:N, r2:N, sobol:N, adaptive[:T,D], lecture or coverage"
        )),
    }
}

/// `adaptive[:THRESHOLD,DEPTH]`: a threshold above 0 (a channel difference of linear values) and a depth
/// from 1 to 6; default 0.1 and 2.
fn adaptive(args: Option<&str>) -> Result<Pattern, String> {
    let Some(args) = args else { return Ok(Pattern::Adaptive { threshold: 0.1, depth: 2 }) };
    let (t, d) =
        args.split_once(',').ok_or_else(|| format!("adaptive takes THRESHOLD,DEPTH, got `{args}`"))?;
    let threshold = match t.trim().parse::<f32>() {
        Ok(v) if v > 0.0 && v.is_finite() => v,
        _ => return Err(format!("adaptive's threshold is a channel difference above 0, got `{t}`")),
    };
    match d.trim().parse::<u32>() {
        Ok(depth) if (1..=6).contains(&depth) => Ok(Pattern::Adaptive { threshold, depth }),
        _ => Err(format!("adaptive's depth runs from 1 to 6, got `{d}`")),
    }
}

/// Parses `--filter KIND[:RADIUS]`: `box`, `tent`, `gaussian` or `mitchell`, with a radius in pixels above 0
/// up to [`Filter::MAX_RADIUS`] (default: [`Filter::default_radius`]).
pub fn parse_filter(s: &str) -> Result<Filter, String> {
    let (name, radius) = match s.trim().split_once(':') {
        Some((n, r)) => (n, Some(r)),
        None => (s.trim(), None),
    };
    let kind = match name {
        "box" => FilterKind::Box,
        "tent" => FilterKind::Tent,
        "gaussian" => FilterKind::Gaussian,
        "mitchell" => FilterKind::Mitchell,
        _ => return Err(format!("unknown filter `{name}`: box, tent, gaussian or mitchell")),
    };
    let radius = match radius {
        None => Filter::default_radius(kind),
        Some(r) => match r.trim().parse::<f32>() {
            Ok(v) if v > 0.0 && v <= Filter::MAX_RADIUS => v,
            _ => {
                return Err(format!("the radius runs above 0 up to {} pixels, got `{r}`", Filter::MAX_RADIUS))
            }
        },
    };
    Ok(Filter { kind, radius })
}

/// One of `converge --filters`: a reconstruction filter, or none (each pixel averages its own samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterChoice(pub Option<Filter>);

impl FilterChoice {
    /// The name reports give it: `none`, or the kind and its radius in pixels (`gaussian:1.5`), as
    /// `--filter` takes it.
    pub fn name(self) -> String {
        let Some(f) = self.0 else { return "none".to_owned() };
        let kind = match f.kind {
            FilterKind::Box => "box",
            FilterKind::Tent => "tent",
            FilterKind::Gaussian => "gaussian",
            FilterKind::Mitchell => "mitchell",
        };
        format!("{kind}:{}", f.radius)
    }
}

/// Parses one of `converge --filters`: `none` or `KIND[:RADIUS]` as [`parse_filter`].
pub fn parse_filter_choice(s: &str) -> Result<FilterChoice, String> {
    match s.trim() {
        "none" => Ok(FilterChoice(None)),
        _ => parse_filter(s)
            .map(|f| FilterChoice(Some(f)))
            .map_err(|e| format!("{e} (or `none`: each pixel averages its own samples)")),
    }
}

/// `--ambient`: ambient coefficients, one for every material or one per material.
#[derive(Clone, Debug, PartialEq)]
pub struct AmbientList(pub Vec<f32>);

/// Parses `--ambient`: a comma list of ambient coefficients, each in [0, 1].
pub fn parse_ambient(s: &str) -> Result<AmbientList, String> {
    s.split(',')
        .map(|v| match v.trim().parse::<f32>() {
            Ok(a) if (0.0..=1.0).contains(&a) => Ok(a),
            _ => Err(format!("ambient coefficients are numbers from 0 to 1, separated by commas; got `{v}`")),
        })
        .collect::<Result<_, _>>()
        .map(AmbientList)
}

/// Parses `--shade whitted|ao[:SAMPLES[,DISTANCE]]`: [`Shade::parse`].
pub fn parse_shade(s: &str) -> Result<Shade, String> {
    Shade::parse(s)
}

/// The name of a shading mode as `--shade` spells it, with its settings (`ao:16,0.5`; a default distance,
/// not yet resolved by compiling, is left out).
pub fn shade_name(shade: Shade) -> String {
    match shade {
        Shade::Whitted => "whitted".to_owned(),
        Shade::Ao(ao) => match ao.distance {
            Some(d) => format!("ao:{},{d}", ao.samples),
            None => format!("ao:{}", ao.samples),
        },
    }
}

/// The name a value has on the command line (what `--help` lists and the user types), for reports.
pub fn name(value: impl clap::ValueEnum) -> String {
    value.to_possible_value().map_or_else(String::new, |v| v.get_name().to_owned())
}

/// A byte count with an optional K, M, G or T suffix (powers of 1024): `--memory 8G`.
pub fn parse_bytes(s: &str) -> Result<u64, String> {
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
pub enum AccelArg {
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
pub enum BvhPresetArg {
    /// bareray's binned SAH builder, the default: the least memory and the quickest build.
    Sah,
    /// obvhs `fastest_build`: leaves of one sphere, no reinsertion.
    Fastest,
    /// obvhs `very_fast_build`: the quickest build; on uniform random fields it also traces faster than
    /// `fast`, on sphereflakes 8–10% slower (docs/perf-log/2026-11.md).
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
    fn aa_methods_parse_with_their_counts() {
        assert_eq!(parse_aa("grid:16"), Ok(Pattern::Grid(4)));
        assert_eq!(parse_aa("stratified:9"), Ok(Pattern::Stratified(3)));
        assert_eq!(parse_aa("r2:5"), Ok(Pattern::R2(5)));
        assert_eq!(parse_aa("sobol:16"), Ok(Pattern::Sobol(16)));
        assert_eq!(parse_aa("sobol:3"), Ok(Pattern::Sobol(3)));
        let e = parse_aa("sobol:0").unwrap_err();
        assert!(e.contains("from 1 to 65536") && e.contains("`0`"), "{e}");
        assert!(parse_aa("sobol").unwrap_err().contains("`sobol:N`"));
        assert!(parse_aa("halton:4").unwrap_err().contains("sobol:N"));
        assert_eq!(parse_aa("lecture"), Ok(Pattern::HalfPixel));
        assert_eq!(parse_aa("coverage"), Ok(Pattern::Coverage));
        assert!(parse_aa("coverage:4").unwrap_err().contains("takes no count"));
        assert_eq!(parse_aa("adaptive"), Ok(Pattern::Adaptive { threshold: 0.1, depth: 2 }));
        assert_eq!(parse_aa("adaptive:0.05,3"), Ok(Pattern::Adaptive { threshold: 0.05, depth: 3 }));
        for bad in [
            "grid:5",
            "grid",
            "r2:0",
            "r2:x",
            "lecture:9",
            "sobol:x",
            "sobol:65537",
            "",
            "adaptive:0,2",
            "adaptive:0.1,9",
            "adaptive:0.1",
        ] {
            assert!(parse_aa(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_filter("tent"), Ok(Filter { kind: FilterKind::Tent, radius: 1.0 }));
        assert_eq!(parse_filter("mitchell:1.5"), Ok(Filter { kind: FilterKind::Mitchell, radius: 1.5 }));
        for bad in ["sinc", "tent:0", "tent:9", "box:x"] {
            assert!(parse_filter(bad).is_err(), "{bad}");
            assert!(parse_filter_choice(bad).unwrap_err().contains("`none`"), "{bad}");
        }
        assert_eq!(parse_filter_choice("none"), Ok(FilterChoice(None)));
        let gaussian = parse_filter_choice("gaussian").unwrap();
        assert_eq!(gaussian, FilterChoice(Some(Filter { kind: FilterKind::Gaussian, radius: 1.5 })));
        assert_eq!(gaussian.name(), "gaussian:1.5");
        assert_eq!(parse_filter_choice("box:0.5").unwrap().name(), "box:0.5");
        assert_eq!(FilterChoice(None).name(), "none");
        let e = parse_aa("grid:3").unwrap_err();
        assert!(
            e.contains("samples per pixel") && e.contains("grid:1 is 1×1") && e.contains("grid:4 is 2×2"),
            "{e}"
        );
    }
    #[test]
    fn shade_modes_parse_and_bad_ones_list_the_forms() {
        use crate::scene::desc::Ao;
        assert_eq!(parse_shade("whitted"), Ok(Shade::Whitted));
        assert_eq!(parse_shade("ao"), Ok(Shade::Ao(Ao { samples: 16, distance: None })));
        assert_eq!(parse_shade("ao:4"), Ok(Shade::Ao(Ao { samples: 4, distance: None })));
        assert_eq!(parse_shade(" ao:4, 0.5 "), Ok(Shade::Ao(Ao { samples: 4, distance: Some(0.5) })));
        for bad in
            ["ao:0", "ao:abc", "ao:4,-1", "ao:4,0", "ao:4,inf", "ao:4,x", "ao:5000", "whitted:2", "", "path"]
        {
            let e = parse_shade(bad).unwrap_err();
            assert!(e.contains("whitted, ao, ao:SAMPLES or ao:SAMPLES,DISTANCE"), "{bad}: {e}");
        }
        assert!(parse_shade("ao:0").unwrap_err().contains("SAMPLES runs from 1"));
        assert!(parse_shade("ao:2,-1").unwrap_err().contains("DISTANCE is a length above 0"));
        assert!(parse_shade("toon").unwrap_err().contains("unknown shading `toon`"));
        assert_eq!(shade_name(parse_shade("ao:8,1.5").unwrap()), "ao:8,1.5");
    }

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
