//! `--frame --view --radius --color --radius-scale --types --box`: how a particle file is read and seen, shared by the
//! commands that load scenes to render them.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use glam::DVec3;

use crate::io::LoadOptions;
use crate::math::Rgb;
use crate::scene::SceneDesc;

/// The particle-file options.
#[derive(Args, Debug, Clone, Default)]
pub(crate) struct ParticleArgs {
    /// The frame of a particle file with several (XYZ frames, PDB models, GRO and LAMMPS timesteps in file
    /// order), from 0; default the first. A frame past the end is an error naming the file's frame count.
    #[arg(long, value_name = "N")]
    pub(crate) frame: Option<usize>,
    /// The side from which a file without a camera (.xyzr, .f32r, particle files) is seen: `+x`, `-x`,
    /// `+y`, `-y`, `+z`, `-z` or a direction `x,y,z`. The eye sits on that side of the particles' bounding
    /// sphere, looking back at its centre, far enough for the sphere to fit with a margin; up is +y (−z from
    /// +y, +z from −y). Default for particle files: +z; .xyzr and .f32r keep their benchmark camera.
    #[arg(long, value_name = "DIR", value_parser = parse_view, allow_hyphen_values = true)]
    pub(crate) view: Option<DVec3>,
    /// The radius of a kind of particle, `TYPE=R` in the file's unit (Å; nm for .gro), TYPE an element
    /// symbol (any case), a LAMMPS type number, or `*` for every kind (coarse-grained beads) but water
    /// models' virtual sites; beats the file's and the table's radius, a named TYPE beats `*`. Repeatable.
    #[arg(long, value_name = "TYPE=R", value_parser = parse_radius)]
    pub(crate) radius: Vec<(String, f64)>,
    /// The colour of a kind of particle, `TYPE=R,G,B` with channels from 0 to 1 (TYPE as for `--radius`,
    /// `*` too); beats the file's and the table's colour. Repeatable.
    #[arg(long, value_name = "TYPE=R,G,B", value_parser = parse_color)]
    pub(crate) color: Vec<(String, Rgb)>,
    /// Multiplies every particle radius (after the overrides).
    #[arg(long, value_name = "S", value_parser = parse_scale)]
    pub(crate) radius_scale: Option<f64>,
    /// A types sidecar: a TOML file of radii and colours by kind (`[C]`, `[1]`, each with `radius = R`
    /// and `color = [R, G, B]`), beaten by `--radius` and `--color`. Without it, `FILE.types.toml` beside
    /// the particle file is read when it exists.
    #[arg(long, value_name = "FILE.toml")]
    pub(crate) types: Option<PathBuf>,
    /// Draw the particle file's periodic box (GRO box line, LAMMPS box bounds, extended XYZ `Lattice=`,
    /// PDB `CRYST1`) as thin grey cylinders.
    #[arg(long = "box")]
    pub(crate) draw_box: bool,
}

impl ParticleArgs {
    /// The reader's options.
    pub(crate) fn options(&self) -> LoadOptions {
        LoadOptions {
            frame: self.frame,
            view: self.view,
            radius: self.radius.clone(),
            color: self.color.clone(),
            radius_scale: self.radius_scale,
            types: self.types.clone(),
            draw_box: self.draw_box,
        }
    }
}

/// Reads a scene file with `options` on `pool`'s threads, printing the reader's warnings.
pub(crate) fn load_scene_with(
    path: &Path,
    pool: &rayon::ThreadPool,
    options: &LoadOptions,
) -> Result<SceneDesc> {
    let read = pool.install(|| crate::io::load_with(path, options))?;
    print_warnings(path, &read.warnings);
    Ok(read.desc)
}

/// Prints a reader's warnings to standard error.
pub(crate) fn print_warnings(path: &Path, warnings: &[String]) {
    for warning in warnings {
        eprintln!("warning: {}: {warning}", path.display());
    }
}

/// Parses `--view`: an axis with its sign, or a non-zero direction `x,y,z`.
pub(crate) fn parse_view(s: &str) -> Result<DVec3, String> {
    let axis = match s.trim().to_ascii_lowercase().as_str() {
        "+x" | "x" => Some(DVec3::X),
        "-x" => Some(DVec3::NEG_X),
        "+y" | "y" => Some(DVec3::Y),
        "-y" => Some(DVec3::NEG_Y),
        "+z" | "z" => Some(DVec3::Z),
        "-z" => Some(DVec3::NEG_Z),
        _ => None,
    };
    if let Some(axis) = axis {
        return Ok(axis);
    }
    match super::camera_args::parse_vec3(s) {
        Ok(v) if v.length() > 0.0 => Ok(v),
        _ => Err(format!("expected +x, -x, +y, -y, +z, -z or a non-zero direction `x,y,z`, got `{s}`")),
    }
}

/// `TYPE=VALUE`, with a non-empty TYPE.
fn split_type(s: &str) -> Result<(String, &str), String> {
    match s.split_once('=') {
        Some((kind, value)) if !kind.trim().is_empty() => Ok((kind.trim().to_owned(), value.trim())),
        _ => Err(format!("expected TYPE=VALUE (an element symbol or LAMMPS type number), got `{s}`")),
    }
}

/// Parses `--radius TYPE=R`.
pub(crate) fn parse_radius(s: &str) -> Result<(String, f64), String> {
    let (kind, value) = split_type(s)?;
    Ok((kind, parse_scale(value).map_err(|_| format!("{s}: the radius must be a positive number"))?))
}

/// Parses `--color TYPE=R,G,B`, channels in [0, 1].
pub(crate) fn parse_color(s: &str) -> Result<(String, Rgb), String> {
    let (kind, value) = split_type(s)?;
    let v: Vec<f32> = value.split(',').filter_map(|c| c.trim().parse().ok()).collect();
    match v[..] {
        [r, g, b] if v.iter().all(|c| (0.0..=1.0).contains(c)) => Ok((kind, Rgb::new(r, g, b))),
        _ => Err(format!("{s}: expected TYPE=R,G,B with channels from 0 to 1")),
    }
}

/// Parses a positive finite number.
pub(crate) fn parse_scale(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("expected a positive number, got `{s}`")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_overrides_and_their_errors() {
        assert_eq!(parse_view("-x"), Ok(DVec3::NEG_X));
        assert_eq!(parse_view("1,1,1"), Ok(DVec3::ONE));
        assert!(parse_view("0,0,0").is_err() && parse_view("up").is_err());
        assert_eq!(parse_radius("C=1.7"), Ok(("C".to_owned(), 1.7)));
        assert_eq!(parse_radius("2 = 0.5"), Ok(("2".to_owned(), 0.5)));
        assert!(parse_radius("C=-1").is_err() && parse_radius("=1").is_err() && parse_radius("C").is_err());
        assert_eq!(parse_color("O=1,0,0.5"), Ok(("O".to_owned(), Rgb::new(1.0, 0.0, 0.5))));
        assert!(parse_color("O=255,0,0").is_err() && parse_color("O=1,0").is_err());
        assert!(parse_scale("0").is_err() && parse_scale("nan").is_err());
    }
}
