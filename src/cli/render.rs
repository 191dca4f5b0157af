//! `bareray render`: its arguments and their parsers; [`super::render_run`] runs it.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::camera_args::CameraArgs;
use super::particle_args::ParticleArgs;
use super::values::{parse_lanes, AccelArg, BvhPresetArg, LanesArg, TransferArg};
use bareray::aov::{self, AovList};
use bareray::output::Format;
use bareray::render::Window;
use bareray::scene::desc::Pattern;

/// The demo scene rendered when no scene file is given.
pub(super) const DEMO_SCENE: &str = include_str!("../../scenes/whitted.toml");

/// Arguments of `bareray render`.
#[derive(Args, Debug)]
#[command(
    after_help = "Examples:\n  bareray render                       # the built-in demo scene -> demo.png\n  \
bareray render scenes/transforms.toml -o out.exr --spp 16\n  \
bareray render scenes/balls3.nff -o balls3.ppm --width 1024\n  \
bareray render scenes/field.toml --width 1920 --threads 2\n\n\
Exit codes: 0 success; 2 argument errors (nothing rendered); 1 scene, render or write errors."
)]
pub(super) struct RenderArgs {
    /// Scene file: .toml (bareray's format), .nff (SPD's Neutral File Format), .xyzr (`x y z r` per
    /// line), .f32r (binary x y z r records), or a particle file: .xyz/.extxyz, .pdb/.ent, .pqr, .gro,
    /// .dump/.lammpstrj, each maybe compressed (.gz, .bz2); `-` reads the scene from standard input (name
    /// its format with --format). Without it, the built-in demo scene (scenes/whitted.toml) is rendered.
    pub(super) scene: Option<PathBuf>,
    /// The format of a scene read from standard input (`render -`): toml, nff, xyzr, f32r, or a particle
    /// format: xyz, pdb, pqr, gro, lammpstrj (compressed input is recognised by its first bytes).
    #[arg(long, value_parser = ["toml", "nff", "xyzr", "f32r", "xyz", "extxyz", "pdb", "ent", "pqr", "gro", "dump", "lammpstrj"])]
    pub(super) format: Option<String>,
    /// Output image; the extension picks the format: .png (8-bit), .exr (linear float RGB), .ppm or .pnm
    /// (binary 8-bit PPM, P6), .hdr (Radiance), .tif/.tiff (uncompressed RGB), .jpg/.jpeg (quality 92);
    /// `-` writes PPM to standard output (the summary then goes
    /// to standard error). Default: the scene's name with .png, in the current directory.
    #[arg(short, long, value_parser = parse_output)]
    pub(super) output: Option<PathBuf>,
    #[command(flatten)]
    pub(super) camera: CameraArgs,
    #[command(flatten)]
    pub(super) particles: ParticleArgs,
    /// Samples per pixel on a regular n×n grid (1, 4, 9, 16, ...); overrides the scene.
    #[arg(long, value_parser = super::values::parse_spp, conflicts_with = "aa")]
    pub(super) spp: Option<u32>,
    /// Sampling method and samples per pixel N, overriding the scene: `grid:N` (regular √N×√N grid of
    /// stratum centres), `stratified:N` (one jittered sample per stratum of a √N×√N grid), `r2:N` (N points
    /// of the R2 low-discrepancy sequence, rotated per pixel), `sobol:N` (N points of the Sobol' sequence,
    /// Owen-scrambled per pixel; a (0, 2)-net at powers of two), `lecture` (the 9-point half-pixel grid shared
    /// with the neighbours), `adaptive[:THRESHOLD,DEPTH]` (after Whitted: pixel corners shared, squares split where
    /// their corners see different primitives or depths, down to DEPTH levels, or differ by more than
    /// THRESHOLD in a channel, down to DEPTH − 1; default 0.1,2),
    /// `coverage` (prefiltering: each sphere's exact covered area of the pixel, one ray per covered part and
    /// one for the rest). Jitter and rotation are seeded by the pixel, so every width and thread count
    /// gives the same image.
    #[arg(long, value_parser = super::sampling_values::parse_aa)]
    pub(super) aa: Option<Pattern>,
    /// Shading, overriding the scene: `whitted` (lights, shadows, mirrors, refraction) or
    /// `ao[:SAMPLES[,DISTANCE]]`, ambient occlusion: at each camera ray's hit SAMPLES (1 to 4096, default
    /// 16) cosine-weighted occlusion rays of length DISTANCE (scene units; default a quarter of the
    /// diagonal of the box around the bounded primitives); the pixel is the surface colour times the share
    /// of them that nothing blocks. Every antialiasing sample gets its own set.
    #[arg(long, value_name = "MODE", value_parser = super::sampling_values::parse_shade)]
    pub(super) shade: Option<bareray::scene::desc::Shade>,
    /// Reconstruction filter over the samples, overriding the scene: `box`, `tent`, `gaussian` or `mitchell`,
    /// optionally with a radius in pixels (`tent:1.5`; defaults 0.5, 1, 1.5, 2). Each sample counts in every
    /// pixel whose centre is within the radius; without a filter a pixel averages its own samples.
    #[arg(long, value_parser = super::sampling_values::parse_filter)]
    pub(super) filter: Option<bareray::scene::desc::Filter>,
    /// Postfilter over the finished image, overriding the scene: `lecture` or `lecture-3x3` (the lecture's 3×3 kernel, ½ at
    /// the centre and 1/16 at each neighbour, renormalised at the border) or `none`.
    #[arg(long, value_parser = ["none", "lecture", "lecture-3x3"])]
    pub(super) postfilter: Option<String>,
    /// Bits per channel of a PNG or TIFF: 8 or 16 (16 keeps the shading's gradients without banding).
    #[arg(long, default_value_t = 8, value_parser = parse_bit_depth)]
    pub(super) bit_depth: u8,
    /// Reflection/refraction depth limit; overrides the scene.
    #[arg(long)]
    pub(super) depth: Option<u32>,
    /// How values become 8-bit PNG/PPM pixels: `srgb` encodes them as linear light with the sRGB curve
    /// (TOML scenes' default), `linear` writes them as they are, clamped, ×255 (NFF's and xyzr's default,
    /// as SPD, POV-Ray and Tachyon write NFF colours). Overrides the scene; PNG records it. EXR holds
    /// linear floats either way.
    #[arg(long, value_enum)]
    pub(super) transfer: Option<TransferArg>,
    /// Ambient coefficients of the scene's materials, overriding the scene: one value for every material,
    /// or a comma list with one value per material: an NFF's `f` lines in file order, a TOML's `default`
    /// material and then its named ones alphabetically. NFF has no ambient term and its materials get 0.1, as SPD's own NFF reader gives them; SPD's
    /// POV-Ray output carries the generator's values (balls: `--ambient 0.2,0`, the floor and the spheres).
    #[arg(long, value_name = "A[,A...]", value_parser = super::sampling_values::parse_ambient)]
    pub(super) ambient: Option<super::sampling_values::AmbientList>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub(super) threads: Option<u64>,
    /// Also write raw primary-ray results (one sample per pixel at pixel centres) as float EXR channels
    /// to OUT's name with `.aov.exr`: a comma list of depth (channel Z), normal (N.X, N.Y, N.Z), id.
    #[arg(long, value_parser = aov::parse_list)]
    pub(super) aov: Option<AovList>,
    /// Render only the pixels X0..X1, Y0..Y1 of the full image (X1, Y1 exclusive), with the full image's
    /// camera: regions rendered apart and pasted together (`bareray merge`) are the full image's bits. The
    /// file records where it belongs (PNG `Region` text, EXR data window, PPM header comment).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_region, conflicts_with = "crop")]
    pub(super) region: Option<[u32; 4]>,
    /// Render a region given as fractions of the image, as pbrt's --cropwindow: columns from ⌈X0·width⌉ to
    /// ⌈X1·width⌉, rows from ⌈Y0·height⌉ to ⌈Y1·height⌉.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = parse_crop)]
    pub(super) crop: Option<[f64; 4]>,
    /// Keep the finished rows in a side file beside the output (`.NAME.resume`) as the render goes, and
    /// use one an interrupted run of the same command left: only the rest is traced, and the image is the
    /// bytes of an uninterrupted render. Ctrl-C stops such a render at the next band, keeping the side file.
    #[arg(long)]
    pub(super) resume: bool,
    /// Rows per band: the image is traced and written band by band, so memory holds a few bands of this
    /// many rows (rounded up to whole 16-row tiles). Default: about 32 MiB of pixels per band.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) band_rows: Option<u32>,
    /// Print a scene summary, rays by kind and the time split (parse, build, render and write).
    #[arg(long)]
    pub(super) stats: bool,
    /// Rays per packet: 1 (single-ray SIMD: one ray against a BVH node's children, and a leaf's spheres, at
    /// once), 4, 8 or 16 (the default; which width is fastest on which scene: PERF.md, "Standing speed
    /// numbers"); or `scalar`: one ray against one box and one primitive at a time, over binary BVHs. The
    /// image is identical at every width and on the scalar path.
    #[arg(long, default_value = "16", value_parser = parse_lanes)]
    pub(super) lanes: LanesArg,
    /// The BVH builder: bareray's Morton order over binned SAH (the default) or binned SAH alone, or an obvhs
    /// PLOC preset (PERF.md, "Tree builder").
    #[arg(long, value_enum, default_value_t = BvhPresetArg::Morton)]
    pub(super) bvh_preset: BvhPresetArg,
    /// How the spheres are searched: `auto` (a BVH, or the particle tree when the BVH would not fit in
    /// memory), `bvh`, `brute` or `pkd` (the particle tree: 5 bytes per sphere beside the spheres; an .f32r
    /// file is mapped, not read). The image is the same bits whichever is used.
    #[arg(long, value_enum, default_value_t = AccelArg::Auto)]
    pub(super) accel: AccelArg,
    /// The memory a render may plan for, in bytes with an optional K, M, G or T suffix (powers of 1024).
    /// Default: what the system has available (MemAvailable, or a container's limit). Decides what `auto`
    /// picks; a field that fits neither structure is refused before it is loaded.
    #[arg(long, value_name = "BYTES", value_parser = super::values::parse_bytes)]
    pub(super) memory: Option<u64>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub(super) quiet: bool,
}

impl RenderArgs {
    /// The pixels to render: `--region`, `--crop` (pbrt's rounding: ⌈fraction × size⌉ at both ends), or
    /// the whole `width × height` image. A region outside the image or empty is an argument error.
    pub(super) fn window(&self, width: u32, height: u32) -> Result<Window> {
        let window = match (self.region, self.crop) {
            (Some([x0, y0, x1, y1]), _) => Window { x0, y0, x1, y1 },
            (None, Some([x0, x1, y0, y1])) => {
                let at = |f: f64, size: u32| (f * f64::from(size)).ceil() as u32;
                Window { x0: at(x0, width), y0: at(y0, height), x1: at(x1, width), y1: at(y1, height) }
            }
            (None, None) => return Ok(Window::whole(width, height)),
        };
        let Window { x0, y0, x1, y1 } = window;
        if x0 >= x1 || y0 >= y1 || x1 > width || y1 > height {
            return Err(super::usage(format!(
                "the region {x0},{y0},{x1},{y1} is empty or reaches outside the {width}x{height} image"
            )));
        }
        Ok(window)
    }
}

/// Parses `--output`: the extension must name an image format.
fn parse_output(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    Format::from_extension(&path).map_err(|_| {
        "unknown image format (use .png, .exr, .ppm or .pnm, .hdr, or - for PPM to standard output)"
            .to_owned()
    })?;
    Ok(path)
}

/// Parses `--region X0,Y0,X1,Y1`: four pixel coordinates.
fn parse_region(s: &str) -> Result<[u32; 4], String> {
    let v: Option<Vec<u32>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match v.as_deref() {
        Some(&[x0, y0, x1, y1]) if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        _ => {
            Err(format!("expected X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1 (pixels, ends exclusive), got `{s}`"))
        }
    }
}

/// Parses `--crop X0,X1,Y0,Y1`: four fractions in [0, 1].
fn parse_crop(s: &str) -> Result<[f64; 4], String> {
    let v: Option<Vec<f64>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match v.as_deref() {
        Some(&[x0, x1, y0, y1])
            if [x0, x1, y0, y1].iter().all(|f| (0.0..=1.0).contains(f)) && x0 < x1 && y0 < y1 =>
        {
            Ok([x0, x1, y0, y1])
        }
        _ => Err(format!("expected X0,X1,Y0,Y1, fractions in [0, 1] with X0 < X1 and Y0 < Y1, got `{s}`")),
    }
}

/// Parses `--bit-depth`: 8 or 16.
fn parse_bit_depth(s: &str) -> Result<u8, String> {
    match s.trim() {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("PNG takes 8 or 16 bits per channel, got `{s}`")),
    }
}
