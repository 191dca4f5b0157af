//! A frame of particles made a scene: radii and colours by kind, one material for every particle and each
//! particle's colour in the per-sphere colour store ([`SceneDesc::sphere_colors`], 8 bits a channel), and
//! the framing of [`crate::io::xyzr::scene_framing`] from the chosen view, with a white background
//! ([`particle_scene`], which spheres given as arrays share).
//!
//! A radius is, first to last: `--radius` for the kind, the file's radius for the particle, the table's
//! for the element (÷ 10 in a file in nm), 0.5 for a LAMMPS type, [`elements::FALLBACK_RADIUS`] (÷ 10 in
//! nm); then times the radius scale. A colour is `--color` for the kind, the file's colour for the
//! particle, the table's for the element, [`TYPE_COLORS`] for a LAMMPS type, [`elements::FALLBACK_COLOR`].

use glam::DVec3;

use super::elements::{self, FALLBACK_COLOR, FALLBACK_RADIUS};
use super::{Frame, Kind, ParticleOptions, Unit};
use crate::io::xyzr;
use crate::math::{Rgb, Rgb8};
use crate::scene::desc::{Material, SceneDesc, SphereDesc};

/// Colours of LAMMPS types 1, 2, … (repeating): red, blue, yellow, green, orange, violet, cyan, grey.
pub const TYPE_COLORS: [u32; 8] =
    [0xE63232, 0x3264E6, 0xF0D732, 0x32B450, 0xF08C28, 0x9646C8, 0x32C8D2, 0xA0A0A0];

/// The radius of a LAMMPS type without a radius column or an override (half the unit length).
pub const TYPE_RADIUS: f64 = 0.5;

/// The view when none is chosen: from +z.
pub const DEFAULT_VIEW: DVec3 = DVec3::Z;

/// The scene of `frame` with `options`' overrides; the strings are warnings (unknown elements, overrides
/// that name no kind in the frame). The error is a message about the whole file.
pub fn scene(frame: Frame, options: &ParticleOptions) -> Result<(SceneDesc, Vec<String>), String> {
    let mut warnings = Vec::new();
    // Particles of each kind without a radius of their own: those the fallback may be for.
    let mut counts = vec![0usize; frame.kinds.len()];
    frame.particles.iter().filter(|p| p.radius.is_none()).for_each(|p| counts[p.kind as usize] += 1);
    let find = |name: &str| frame.kinds.iter().position(|k| k.name.eq_ignore_ascii_case(name));
    let mut radius_over = vec![None; frame.kinds.len()];
    let mut color_over = vec![None; frame.kinds.len()];
    for (name, r) in &options.radius {
        match find(name) {
            Some(i) => radius_over[i] = Some(*r),
            None => warnings.push(format!("--radius {name}: no particle of that kind in the frame")),
        }
    }
    for (name, c) in &options.color {
        match find(name) {
            Some(i) => color_over[i] = Some(*c),
            None => warnings.push(format!("--color {name}: no particle of that kind in the frame")),
        }
    }
    let unit = match frame.unit {
        Unit::Angstrom => 1.0,
        Unit::Nanometre => 0.1,
    };
    let mut defaults = Vec::with_capacity(frame.kinds.len());
    for (i, kind) in frame.kinds.iter().enumerate() {
        let (radius, color, known) = by_kind(kind, unit);
        if !known && counts[i] > 0 && radius_over[i].is_none() {
            warnings.push(unknown(kind, counts[i], FALLBACK_RADIUS * unit));
        }
        defaults.push((radius_over[i].unwrap_or(radius), color_over[i].unwrap_or(color)));
    }
    let scale = options.radius_scale.unwrap_or(1.0);
    let mut spheres = Vec::with_capacity(frame.particles.len());
    let mut colors = Vec::with_capacity(frame.particles.len());
    for p in &frame.particles {
        let k = p.kind as usize;
        let radius = radius_over[k].or(p.radius).unwrap_or(defaults[k].0) * scale;
        let color = color_over[k].or(p.color).unwrap_or(defaults[k].1);
        spheres.push(SphereDesc { center: p.center, radius, material: 0 });
        colors.push(Rgb8::quantize(color));
    }
    if spheres.is_empty() {
        return Err("no particles".to_owned());
    }
    Ok((particle_scene(spheres, colors, options.view.unwrap_or(DEFAULT_VIEW)), warnings))
}

/// The scene of particles: `spheres` (each with material 0) and their colours (empty, or one per sphere),
/// seen from the side `view` points to ([`xyzr::scene_framing`]: the bounding sphere framed at 1920×1080,
/// a headlight), on a white background, with one material ([`material_of`] bareray's default grey, which
/// shows only without colours).
pub fn particle_scene(spheres: Vec<SphereDesc>, colors: Vec<Rgb8>, view: DVec3) -> SceneDesc {
    let (lo, hi) = xyzr::bounds(&spheres);
    let mut desc = xyzr::scene_framing(lo, hi, Some(view));
    desc.render.background = Rgb::all(1.0);
    desc.materials = vec![material_of(Material::default().color)];
    desc.spheres = spheres;
    desc.sphere_colors = colors;
    desc
}

/// A kind's radius and colour by default, and whether the table knew it.
fn by_kind(kind: &Kind, unit: f64) -> (f64, Rgb, bool) {
    if kind.lammps_type {
        let n: usize = kind.name.parse().unwrap_or(1);
        return (TYPE_RADIUS, elements::rgb(TYPE_COLORS[n.saturating_sub(1) % TYPE_COLORS.len()]), true);
    }
    match kind.element {
        Some(e) => match elements::radius(e) {
            Some(r) => (r * unit, elements::rgb(e.2), true),
            None => (FALLBACK_RADIUS * unit, elements::rgb(e.2), false),
        },
        None => (FALLBACK_RADIUS * unit, elements::rgb(FALLBACK_COLOR), false),
    }
}

/// The warning for particles of an element the table lacks, or lacks a radius for.
fn unknown(kind: &Kind, count: usize, radius: f64) -> String {
    // 0.15 nm, not the 0.15000000000000002 that 1.5 × 0.1 makes.
    let radius = (radius * 1e9).round() / 1e9;
    let what = match kind.element {
        Some(_) => format!("has no van der Waals radius in the table: radius {radius}"),
        None => format!("is not an element the table knows: radius {radius}, colour #{FALLBACK_COLOR:06X}"),
    };
    let s = if count == 1 { "" } else { "s" };
    format!("`{}` ({count} particle{s}) {what} (--radius and --color set others)", kind.name)
}

/// The material of particles of `color`: diffuse with a little highlight.
pub fn material_of(color: Rgb) -> Material {
    Material { color, ambient: 0.2, diffuse: 0.8, specular: 0.3, shininess: 40.0, ..Material::default() }
}
