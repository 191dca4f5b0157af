//! What a camera ray's hit is shaded with ([`Shade`]): Whitted shading or ambient occlusion ([`Ao`]), and the
//! parsing of its forms on the command line and in TOML.

/// What a camera ray's hit is shaded with.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Shade {
    /// Whitted: ambient, Lambert and Phong from the point lights with hard shadows, mirror and refraction.
    #[default]
    Whitted,
    /// Ambient occlusion (Tachyon's and aobench's estimate, with rays of a chosen length where theirs are
    /// unlimited): at each camera ray's hit, `samples` cosine-weighted directions over the hemisphere
    /// around the shading normal, each an occlusion ray of length `distance`; the pixel is the surface's
    /// colour times the share of them that nothing blocks. No lights, no secondary rays; rays that hit
    /// nothing show the background.
    Ao(Ao),
}

/// The settings of [`Shade::Ao`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ao {
    /// Occlusion rays per camera ray's hit, from 1 to `Ao::MAX_SAMPLES`.
    pub samples: u32,
    /// The occlusion rays' length in scene units (positive); `None`: `Ao::DEFAULT_REACH` times the diagonal
    /// of the bounded primitives' box, which compiling fills in.
    pub distance: Option<f64>,
}

impl Ao {
    /// The most occlusion rays per hit.
    pub(crate) const MAX_SAMPLES: u32 = 4096;
    /// Occlusion rays per hit when none are given.
    pub(crate) const DEFAULT_SAMPLES: u32 = 16;
    /// The default distance as a share of the diagonal of the box around every bounded primitive: a quarter,
    /// so that occlusion is local (contacts, creases, cavities) rather than the whole scene's shadow.
    pub(crate) const DEFAULT_REACH: f64 = 0.25;
}

impl Shade {
    /// The forms `--shade` and the TOML key `shade` accept.
    pub(crate) const FORMS: &'static str = "whitted, ao, ao:SAMPLES or ao:SAMPLES,DISTANCE";

    /// Parses `whitted` or `ao[:SAMPLES[,DISTANCE]]` (SAMPLES from 1 to `Ao::MAX_SAMPLES`, default
    /// `Ao::DEFAULT_SAMPLES`; DISTANCE a length above 0 in scene units, default from the scene's size).
    pub fn parse(s: &str) -> Result<Shade, String> {
        let forms = Self::FORMS;
        let (mode, args) = match s.trim().split_once(':') {
            Some((m, a)) => (m.trim(), Some(a)),
            None => (s.trim(), None),
        };
        match (mode, args) {
            ("whitted", None) => return Ok(Shade::Whitted),
            ("whitted", Some(_)) => return Err(format!("`whitted` takes no arguments, got `{s}` ({forms})")),
            ("ao", _) => {}
            _ => return Err(format!("unknown shading `{mode}`: {forms}")),
        }
        let Some(args) = args else {
            return Ok(Shade::Ao(Ao { samples: Ao::DEFAULT_SAMPLES, distance: None }));
        };
        let (n, d) = match args.split_once(',') {
            Some((n, d)) => (n, Some(d)),
            None => (args, None),
        };
        let samples = match n.trim().parse::<u32>() {
            Ok(v) if (1..=Ao::MAX_SAMPLES).contains(&v) => v,
            _ => {
                let max = Ao::MAX_SAMPLES;
                return Err(format!("ao's SAMPLES runs from 1 to {max}, got `{}` ({forms})", n.trim()));
            }
        };
        let distance = match d.map(|d| (d, d.trim().parse::<f64>())) {
            None => None,
            Some((_, Ok(v))) if v > 0.0 && v.is_finite() => Some(v),
            Some((d, _)) => {
                let d = d.trim();
                return Err(format!("ao's DISTANCE is a length above 0 in scene units, got `{d}` ({forms})"));
            }
        };
        Ok(Shade::Ao(Ao { samples, distance }))
    }
}
