//! A frame of particles made a scene: radii and colours by kind, one material for every particle and each
//! particle's colour in the per-sphere colour store ([`SceneDesc::sphere_colors`], 8 bits a channel), and
//! the framing of `crate::io::xyzr::scene_framing` from the chosen view, with a white background
//! (`particle_scene`, which spheres given as arrays share).
//!
//! A radius is, first to last: `--radius` for the kind, then for every kind ([`WILDCARD`]), the types
//! sidecar's ([`super::types`]) alike, the file's radius for the particle, the table's for the element (÷ 10
//! in a file in nm), 0.5 for a LAMMPS type, `elements::FALLBACK_RADIUS` (÷ 10 in nm); then times the radius
//! scale. A colour is `--color` for the kind, then for every kind, the sidecar's alike, the file's colour for
//! the particle, the table's for the element, `TYPE_COLORS` for a LAMMPS type, `elements::FALLBACK_COLOR`.
//!
//! Virtual sites ([`is_virtual_site`]: the massless charge sites of four- and five-site water models, which no
//! element names) are left out unless the file, `--radius` or the sidecar gives them a radius; a warning
//! counts them.
//!
//! With [`ParticleOptions::draw_box`], the frame's periodic box is drawn as twelve open cylinders with a
//! sphere at each corner to close the joints, all of radius `box_radius` and the grey `BOX_COLOR`.

use glam::DVec3;
use rayon::prelude::*;

use super::elements::{self, FALLBACK_COLOR, FALLBACK_RADIUS};
use super::types::Types;
use super::{Cell, Frame, Kind, Particle, ParticleOptions, Unit};
use crate::io::xyzr;
use crate::kinds::cone::ConeDesc;
use crate::kinds::sphere::SphereDesc;
use crate::math::{Rgb, Rgb8};
use crate::scene::desc::{Material, SceneDesc};

/// Colours of LAMMPS types 1, 2, … (repeating): red, blue, yellow, green, orange, violet, cyan, grey.
pub(crate) const TYPE_COLORS: [u32; 8] =
    [0xE63232, 0x3264E6, 0xF0D732, 0x32B450, 0xF08C28, 0x9646C8, 0x32C8D2, 0xA0A0A0];

/// The radius of a LAMMPS type without a radius column or an override (half the unit length).
pub(crate) const TYPE_RADIUS: f64 = 0.5;

/// The names of virtual sites, letters only and upper case: TIP4P's `MW` (GROMACS), `M` (OpenMM) and `OM`
/// (CHARMM, in a water residue only: elsewhere an oxygen, `elements::from_atom_name`), AMBER's `EPW` and
/// `EP1`/`EP2` (TIP4P-Ew, TIP5P), GROMACS's TIP5P lone pairs `LP1`/`LP2`.
const VIRTUAL_SITE_NAMES: [&str; 6] = ["MW", "M", "OM", "EPW", "EP", "LP"];

/// Whether particles of `kind` are virtual sites: no element, not a LAMMPS type, and a name whose letters
/// are one of [`VIRTUAL_SITE_NAMES`]. They carry a charge, not an atom, and sit inside their oxygen's
/// sphere (TIP4P's `MW` 0.15 Å from it), so drawn at the unknown element's radius they would poke out of it.
fn is_virtual_site(kind: &Kind) -> bool {
    let letters: String = kind.name.chars().filter(char::is_ascii_alphabetic).collect();
    kind.element.is_none()
        && !kind.lammps_type
        && VIRTUAL_SITE_NAMES.iter().any(|v| v.eq_ignore_ascii_case(&letters))
}

/// The kind name of an override for every kind (`--radius '*=0.24'`): coarse-grained beads, whose names
/// read as elements or as nothing the table knows, all drawn alike.
const WILDCARD: &str = "*";

/// `items` with those named [`WILDCARD`] first, the rest in their order.
fn wildcard_first<T>(items: &[T], name: impl Fn(&T) -> &str) -> Vec<&T> {
    let mut sorted: Vec<&T> = items.iter().collect();
    sorted.sort_by_key(|t| name(t) != WILDCARD);
    sorted
}

/// The view when none is chosen: from +z.
pub(crate) const DEFAULT_VIEW: DVec3 = DVec3::Z;

/// The colour of the periodic box's cylinders: a neutral mid grey, seen on white and on most particles.
pub(crate) const BOX_COLOR: Rgb = Rgb::new(0.35, 0.35, 0.35);

/// The radius of the box's cylinders: this share of the box's longest diagonal, thin beside atoms (a
/// 10 nm box gets 0.03 nm against hydrogen's 0.12) yet a few pixels wide when the box fills the image.
pub(crate) const BOX_RADIUS_SHARE: f64 = 0.0015;

/// The radius of `cell`'s cylinders: [`BOX_RADIUS_SHARE`] of its longest diagonal.
pub(crate) fn box_radius(cell: &Cell) -> f64 {
    let [a, b, c] = cell.edges;
    let longest =
        [a + b + c, a + b - c, a - b + c, -a + b + c].iter().map(|d| d.length()).fold(0.0, f64::max);
    longest * BOX_RADIUS_SHARE
}

/// The scene of `frame` with a types sidecar's and `options`' overrides; the strings are warnings (unknown
/// elements, overrides that name no kind in the frame, a box asked of a frame without one). The error is a
/// message about the whole file.
pub(crate) fn scene(
    frame: Frame,
    options: &ParticleOptions,
    sidecar: Option<&Types>,
) -> Result<(SceneDesc, Vec<String>), String> {
    let mut warnings = Vec::new();
    // Particles of each kind without a radius of their own: those the fallback may be for.
    let counts = kind_counts(&frame);
    let (radius_over, color_over) = overrides(&frame, options, sidecar, &mut warnings);
    let unit = match frame.unit {
        Unit::Angstrom => 1.0,
        Unit::Nanometre => 0.1,
    };
    let mut defaults = Vec::with_capacity(frame.kinds.len());
    // Kinds whose particles are left out where the file gives them no radius: virtual sites without a
    // radius given for their kind.
    let mut left_out = vec![false; frame.kinds.len()];
    let mut sites = 0;
    for (i, kind) in frame.kinds.iter().enumerate() {
        let (radius, color, known) = by_kind(kind, unit);
        if is_virtual_site(kind) && radius_over[i].is_none() {
            left_out[i] = true;
            sites += counts[i];
            if counts[i] > 0 {
                warnings.push(virtual_sites(kind, counts[i]));
            }
        } else if !known && counts[i] > 0 && radius_over[i].is_none() {
            warnings.push(unknown(kind, counts[i], FALLBACK_RADIUS * unit));
        }
        defaults.push((radius_over[i].unwrap_or(radius), color_over[i].unwrap_or(color)));
    }
    let scale = options.radius_scale.unwrap_or(1.0);
    let sphere = |p: &Particle| {
        let k = p.kind as usize;
        let radius = radius_over[k].or(p.radius).unwrap_or(defaults[k].0) * scale;
        let color = color_over[k].or(p.color).unwrap_or(defaults[k].1);
        (SphereDesc { center: p.center, radius, material: 0 }, Rgb8::quantize(color))
    };
    // Room for the box's eight corners too.
    let room = frame.particles.len() + 8;
    let (mut spheres, mut colors) = (Vec::with_capacity(room), Vec::with_capacity(room));
    if left_out.contains(&true) {
        let kept = |p: &&Particle| !(left_out[p.kind as usize] && p.radius.is_none());
        for (s, c) in frame.particles.iter().filter(kept).map(sphere) {
            spheres.push(s);
            colors.push(c);
        }
    } else {
        // Into the vectors as allocated: their room for the corners stays.
        frame.particles.par_iter().map(sphere).unzip_into_vecs(&mut spheres, &mut colors);
    }
    if spheres.is_empty() {
        return Err(match sites {
            0 => "no particles".to_owned(),
            1 => "no particles but 1 virtual site, not drawn (--radius NAME=R draws it)".to_owned(),
            n => format!("no particles but {n} virtual sites, not drawn (--radius NAME=R draws them)"),
        });
    }
    let cell = match (options.draw_box, frame.cell) {
        (false, _) => None,
        (true, Some(cell)) if cell.is_solid() => Some(cell),
        (true, Some(_)) => {
            warnings.push("--box: the file's box is flat or empty, so none is drawn".to_owned());
            None
        }
        (true, None) => {
            warnings.push("--box: the file gives no periodic box for this frame".to_owned());
            None
        }
    };
    // The corners join the spheres before the framing, so that the box is framed with the particles.
    let corners = cell.map(|cell| {
        let radius = box_radius(&cell);
        for center in cell.corners() {
            spheres.push(SphereDesc { center, radius, material: 1 });
            colors.push(Rgb8::quantize(BOX_COLOR));
        }
        (cell, radius)
    });
    let mut desc = particle_scene(spheres, colors, options.view.unwrap_or(DEFAULT_VIEW));
    if let Some((cell, radius)) = corners {
        desc.materials.push(material_of(BOX_COLOR));
        let c = cell.corners();
        desc.kinds.cones.extend(Cell::edge_corners().iter().map(|&(i, j)| ConeDesc {
            base: c[i],
            base_radius: radius,
            apex: c[j],
            apex_radius: radius,
            material: 1,
        }));
    }
    Ok((desc, warnings))
}

/// Kinds up to this many are counted in parallel, each thread's job with a count per kind; a frame with
/// more (a hostile file can name a million LAMMPS types) is counted in one pass.
const PARALLEL_COUNT_KINDS: usize = 1024;

/// The number of particles of each kind without a radius of their own.
fn kind_counts(frame: &Frame) -> Vec<usize> {
    let n = frame.kinds.len();
    let add = |mut counts: Vec<usize>, p: &Particle| {
        counts[p.kind as usize] += usize::from(p.radius.is_none());
        counts
    };
    if n > PARALLEL_COUNT_KINDS {
        return frame.particles.iter().fold(vec![0; n], add);
    }
    let sum = |mut a: Vec<usize>, b: Vec<usize>| {
        a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        a
    };
    frame.particles.par_iter().fold(|| vec![0; n], add).reduce(|| vec![0; n], sum)
}

/// Each kind's radius and colour overrides, by the sidecar and the flags (warning of flags that name no kind
/// in the frame).
fn overrides(
    frame: &Frame,
    options: &ParticleOptions,
    sidecar: Option<&Types>,
    warnings: &mut Vec<String>,
) -> (Vec<Option<f64>>, Vec<Option<Rgb>>) {
    // The kinds an override names: `*` every kind but the virtual sites (which only their own name draws),
    // else the one of that name, if the frame has it.
    let kinds = |name: &str| -> Vec<usize> {
        match name {
            WILDCARD => (0..frame.kinds.len()).filter(|&i| !is_virtual_site(&frame.kinds[i])).collect(),
            _ => frame.kinds.iter().position(|k| k.name.eq_ignore_ascii_case(name)).into_iter().collect(),
        }
    };
    let mut radius_over = vec![None; frame.kinds.len()];
    let mut color_over = vec![None; frame.kinds.len()];
    // The sidecar first, so that the flags' values replace its; in each, `*` first, so that a named kind's
    // value replaces it.
    let entries = sidecar.map_or(&[][..], |t| &t.entries[..]);
    for entry in wildcard_first(entries, |e| &e.name) {
        for i in kinds(&entry.name) {
            radius_over[i] = entry.radius.or(radius_over[i]);
            color_over[i] = entry.color.or(color_over[i]);
        }
    }
    by_flag("radius", &options.radius, &kinds, &mut radius_over, warnings);
    by_flag("color", &options.color, &kinds, &mut color_over, warnings);
    (radius_over, color_over)
}

/// The values `--flag` gives by kind name into `over`, `*` first, warning of names no kind in the frame has.
fn by_flag<T: Copy>(
    flag: &str,
    given: &[(String, T)],
    kinds: &dyn Fn(&str) -> Vec<usize>,
    over: &mut [Option<T>],
    warnings: &mut Vec<String>,
) {
    for (name, value) in wildcard_first(given, |(name, _)| name) {
        match kinds(name)[..] {
            [] => warnings.push(format!("--{flag} {name}: no particle of that kind in the frame")),
            ref found => found.iter().for_each(|&i| over[i] = Some(*value)),
        }
    }
}

/// The scene of particles: `spheres` (each with material 0) and their colours (empty, or one per sphere),
/// seen from the side `view` points to ([`xyzr::scene_framing`]: the bounding sphere framed at 1920×1080,
/// a headlight), on a white background, with one material ([`material_of`] bareray's default grey, which
/// shows only without colours).
pub(crate) fn particle_scene(spheres: Vec<SphereDesc>, colors: Vec<Rgb8>, view: DVec3) -> SceneDesc {
    let (lo, hi) = crate::kinds::sphere::sphere_bounds(&spheres);
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
    let name = match kind.name.is_empty() {
        true => "a blank name".to_owned(),
        false => format!("`{}`", kind.name),
    };
    format!("{name} ({count} particle{s}) {what} (--radius and --color set others)")
}

/// The warning for virtual sites left out.
fn virtual_sites(kind: &Kind, count: usize) -> String {
    let s = if count == 1 { "" } else { "s" };
    format!(
        "`{}` ({count} particle{s}) named as a virtual site (a water model's charge site, no atom): not drawn \
         (--radius {}=R draws them)",
        kind.name, kind.name
    )
}

/// The material of particles of `color`: diffuse with a little highlight.
pub(crate) fn material_of(color: Rgb) -> Material {
    Material { color, ambient: 0.2, diffuse: 0.8, specular: 0.3, shininess: 40.0, ..Material::default() }
}
