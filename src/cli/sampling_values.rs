//! Parsers of the sampling, filter, shading and ambient values the commands that render take.

use bareray::scene::desc::{Filter, FilterKind, Pattern, Shade};

/// Parses `--aa METHOD[:N]`: `grid:N` and `stratified:N` (N a square number of samples per pixel), `r2:N`
/// and `sobol:N` (any N from 1), `lecture` (the half-pixel pattern, no N), `adaptive[:T,D]`, `coverage` (no N).
pub(super) fn parse_aa(s: &str) -> Result<Pattern, String> {
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
        bareray::io::toml::grid_side(n).map_err(|_| {
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
pub(super) fn parse_filter(s: &str) -> Result<Filter, String> {
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
pub(super) struct FilterChoice(pub Option<Filter>);

impl FilterChoice {
    /// The name reports give it: `none`, or the kind and its radius in pixels (`gaussian:1.5`), as
    /// `--filter` takes it.
    pub(super) fn name(self) -> String {
        bareray::settings::filter_name(self.0)
    }
}

/// Parses one of `converge --filters`: `none` or `KIND[:RADIUS]` as [`parse_filter`].
pub(super) fn parse_filter_choice(s: &str) -> Result<FilterChoice, String> {
    match s.trim() {
        "none" => Ok(FilterChoice(None)),
        _ => parse_filter(s)
            .map(|f| FilterChoice(Some(f)))
            .map_err(|e| format!("{e} (or `none`: each pixel averages its own samples)")),
    }
}

/// `--ambient`: ambient coefficients, one for every material or one per material.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct AmbientList(pub Vec<f32>);

/// Parses `--ambient`: a comma list of ambient coefficients, each in [0, 1].
pub(super) fn parse_ambient(s: &str) -> Result<AmbientList, String> {
    s.split(',')
        .map(|v| match v.trim().parse::<f32>() {
            Ok(a) if (0.0..=1.0).contains(&a) => Ok(a),
            _ => Err(format!("ambient coefficients are numbers from 0 to 1, separated by commas; got `{v}`")),
        })
        .collect::<Result<_, _>>()
        .map(AmbientList)
}

/// Parses `--shade whitted|ao[:SAMPLES[,DISTANCE]]`: [`Shade::parse`].
pub(super) fn parse_shade(s: &str) -> Result<Shade, String> {
    Shade::parse(s)
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
        use bareray::scene::desc::Ao;
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
        assert_eq!(bareray::settings::shade_name(parse_shade("ao:8,1.5").unwrap()), "ao:8,1.5");
    }
}
