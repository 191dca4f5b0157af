//! Whole renders in memory, for programs and language bindings (the Python module, `python/`): spheres
//! given as arrays or a scene file in, an image of linear f32 RGB out, with no file written. Each call
//! reads, compiles and renders as `bareray render` does, with the same search structure choice
//! ([`Accel::Auto`]: the particle tree when the BVH would not fit in memory), so the image is the bits the
//! command line writes for the same scene and camera.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;

use crate::accuracy::{self, Report};
use crate::camera::CameraError;
use crate::compile::load::{self, LoadError, Loaded};
use crate::compile::{memory, Accel, CompileOptions, Scene};
use crate::io::particles::arrays::{ArrayError, SphereArrays};
use crate::io::{LoadOptions, SceneError};
use crate::render::{self, Rendered, LANE_CHOICES};
use crate::scene::SceneDesc;
use crate::settings::{Overrides, SettingsError};

/// Why a render could not be made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad array (the first bad sphere named).
    #[error(transparent)]
    Arrays(#[from] ArrayError),
    /// The file could not be read (file and line named).
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The camera cannot form an image.
    #[error("camera: {0}")]
    Camera(#[from] CameraError),
    /// A setting out of range.
    #[error("{0}")]
    Options(String),
    /// The thread pool could not start, or the accuracy pass failed.
    #[error("{0}")]
    Other(String),
}

impl From<SettingsError> for Error {
    fn from(e: SettingsError) -> Self {
        Error::Options(e.to_string())
    }
}

impl From<SceneError> for Error {
    fn from(e: SceneError) -> Self {
        Error::Load(LoadError::Scene(e))
    }
}

/// How to render: the changes to the scene's settings (camera, shading, samples, …), threads and packet
/// width. The default keeps the scene's settings, on every core, in packets of 16.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Changes to the scene's camera and render settings.
    pub overrides: Overrides,
    /// Worker threads (`None`: every core).
    pub threads: Option<usize>,
    /// Rays per packet: 1, 4, 8 or 16; every width gives the same bits.
    pub lanes: usize,
    /// The scalar path (single rays over binary BVHs, one box and one primitive at a time): `lanes` must be 1.
    pub scalar: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { overrides: Overrides::default(), threads: None, lanes: 16, scalar: false }
    }
}

impl RenderOptions {
    /// Checks the settings and applies the overrides to `desc`.
    pub(crate) fn apply(&self, desc: &mut SceneDesc) -> Result<(), Error> {
        self.check()?;
        Ok(self.overrides.apply(desc)?)
    }

    /// Checks the packet width and the thread count (zero threads, which rayon would take for every core).
    fn check(&self) -> Result<(), Error> {
        if !LANE_CHOICES.contains(&self.lanes) || (self.scalar && self.lanes != 1) {
            let scalar = if self.scalar { " (the scalar path takes 1)" } else { "" };
            return Err(Error::Options(format!("lanes must be 1, 4, 8 or 16, got {}{scalar}", self.lanes)));
        }
        if self.threads == Some(0) {
            return Err(Error::Options("threads must be at least 1".to_owned()));
        }
        Ok(())
    }

    fn compile_options(&self) -> CompileOptions {
        CompileOptions { scalar: self.scalar, ..CompileOptions::default() }
    }
}

/// A render and what it cost.
#[derive(Clone, Debug)]
pub struct Picture {
    /// The image, the ray counts and the tracing time ([`Rendered::seconds`]).
    pub rendered: Rendered,
    /// Seconds spent compiling the scene (the BVH or particle tree build included).
    pub build_seconds: f64,
}

/// Renders spheres given as arrays, seen as a particle file of them is
/// ([`SphereArrays::scene`]: from `view`, +z by default, a headlight, a white background; per-sphere
/// colours), with `options` applied.
///
/// ```
/// use bareray::api::{self, RenderOptions};
/// use bareray::io::particles::arrays::{Floats, SphereArrays};
/// use bareray::scene::desc::CameraOverrides;
/// use bareray::settings::Overrides;
///
/// let centers = [0.0f32, 0.0, 0.0, 1.5, 0.0, 0.0];
/// let arrays = SphereArrays {
///     centers: Floats::F32(&centers),
///     radii: Floats::F32(&[1.0, 0.5]),
///     colors: Some(Floats::F32(&[1.0, 0.0, 0.0, 0.0, 0.0, 1.0])),
/// };
/// let camera = CameraOverrides { width: Some(64), height: Some(36), ..Default::default() };
/// let overrides = Overrides { camera, ..Default::default() };
/// let options = RenderOptions { overrides, threads: Some(1), ..Default::default() };
/// let picture = api::render_spheres(&arrays, None, &options)?;
/// let image = &picture.rendered.image;
/// assert_eq!((image.width, image.height), (64, 36));
/// assert_eq!(image.pixels[0], bareray::math::Rgb::all(1.0)); // the white background in a corner
/// # Ok::<(), api::Error>(())
/// ```
pub fn render_spheres(
    arrays: &SphereArrays,
    view: Option<DVec3>,
    options: &RenderOptions,
) -> Result<Picture, Error> {
    let pool = pool(options)?;
    // The arrays are checked on the render's threads.
    let desc = pool.install(|| arrays.scene(view))?;
    render_desc(desc, options, &pool)
}

/// Renders a scene description with `options` applied, on the threads of `pool`
/// ([`crate::render::thread_pool`] with `options`' thread count: a caller that made one to read its input
/// renders on the same threads), its spheres in the BVH or, when the BVH would not fit in the memory
/// available, in the particle tree.
pub fn render_desc(
    mut desc: SceneDesc,
    options: &RenderOptions,
    pool: &rayon::ThreadPool,
) -> Result<Picture, Error> {
    options.apply(&mut desc)?;
    let loaded = load::loaded_desc(desc, Accel::Auto, memory::available());
    render_loaded(loaded, options, pool)
}

/// Compiles and renders what [`load::load`] read (`options` already applied to its description) on the
/// threads of `pool`.
fn render_loaded(
    loaded: Loaded,
    options: &RenderOptions,
    pool: &rayon::ThreadPool,
) -> Result<Picture, Error> {
    if loaded.accel == Accel::Particles {
        if let Some(why) = load::particles_unsupported(&loaded.desc) {
            return Err(Error::Options(why.to_owned()));
        }
    }
    let clock = Instant::now();
    let scene = pool.install(|| Scene::compile_loaded(loaded, options.compile_options()))?;
    let build_seconds = clock.elapsed().as_secs_f64();
    let rendered = render::render_lanes(&scene, options.lanes, pool, &());
    Ok(Picture { rendered, build_seconds })
}

/// A pool of `options.threads` worker threads (every core for `None`), once the options are checked.
fn pool(options: &RenderOptions) -> Result<rayon::ThreadPool, Error> {
    options.check()?;
    render::thread_pool(options.threads).map_err(|e| Error::Other(format!("thread pool: {e}")))
}

/// A scene file read once, rendered, compared and timed as often as asked: what `bareray.load` returns.
/// An `.f32r` field bound for the particle tree is mapped again for each render (the tree reorders its
/// records in the mapping's private pages), other files are kept as their description.
#[derive(Debug)]
pub struct FileScene {
    path: PathBuf,
    options: LoadOptions,
    /// The description; a mapped field's holds no spheres (they stay in the file).
    pub desc: SceneDesc,
    /// Whether the spheres are an `.f32r` field mapped for the particle tree.
    pub(crate) mapped: bool,
    /// How many spheres the scene has (a mapped field's included).
    spheres: usize,
    /// The reader's warnings (unknown elements, say).
    pub warnings: Vec<String>,
}

impl FileScene {
    /// Reads `path` (any format `bareray render` reads; frame `frame` of a particle file with several).
    /// Errors name the file and line.
    pub fn open(path: &Path, frame: Option<usize>) -> Result<FileScene, Error> {
        let options = LoadOptions { frame, ..LoadOptions::default() };
        let loaded = load::load(path, Accel::Auto, memory::available(), &options)?;
        Ok(FileScene {
            path: path.to_owned(),
            options,
            spheres: loaded.desc.spheres.len() + loaded.mapped.as_ref().map_or(0, |m| m.len()),
            mapped: loaded.mapped.is_some(),
            desc: loaded.desc,
            warnings: loaded.warnings,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How many spheres the scene has (a mapped field's included).
    pub fn spheres(&self) -> usize {
        self.spheres
    }

    /// What [`load::load`] gives for this file with `options` applied: the description (a clone) and, for
    /// a mapped field, a new mapping.
    fn loaded(&self, options: &RenderOptions) -> Result<Loaded, Error> {
        let mut loaded = match self.mapped {
            true => load::load(&self.path, Accel::Auto, memory::available(), &self.options)?,
            false => load::loaded_desc(self.desc.clone(), Accel::Auto, memory::available()),
        };
        options.apply(&mut loaded.desc)?;
        Ok(loaded)
    }

    /// Renders the scene with `options` applied.
    pub fn render(&self, options: &RenderOptions) -> Result<Picture, Error> {
        render_loaded(self.loaded(options)?, options, &pool(options)?)
    }

    /// Compares the f32 renderer's rays with the f64 twin's (`bareray accuracy`): primary rays at every
    /// pixel centre and, with `secondary`, shadow and mirror rays. `options`' camera and packet width apply.
    pub fn accuracy(&self, options: &RenderOptions, secondary: bool) -> Result<Report, Error> {
        let mut desc = match self.mapped {
            // The twin needs the spheres in the description: read the field whole.
            true => crate::io::load_with(&self.path, &self.options)?.desc,
            false => self.desc.clone(),
        };
        options.apply(&mut desc)?;
        let opts = accuracy::Options {
            lanes: options.lanes,
            scalar: options.scalar,
            secondary,
            threads: options.threads,
            ..accuracy::Options::default()
        };
        accuracy::run(&self.path.display().to_string(), &desc, &opts).map_err(|e| Error::Other(e.to_string()))
    }

    /// Times `reps` renders (after one untimed) of the compiled scene with `options` applied, as
    /// `bareray bench` does for one setting; with `by_kind`, also four more runs that split the render by
    /// ray kind, as its per-ray-kind report does ([`Bench::by_kind`]).
    pub fn bench(&self, options: &RenderOptions, reps: usize, by_kind: bool) -> Result<Bench, Error> {
        let loaded = self.loaded(options)?;
        let pool = pool(options)?;
        let clock = Instant::now();
        let mut scene = pool.install(|| Scene::compile_loaded(loaded, options.compile_options()))?;
        let build_seconds = clock.elapsed().as_secs_f64();
        let reps = u32::try_from(reps.max(1)).unwrap_or(u32::MAX);
        let (trace, width) = (crate::bench::Trace::Render, (options.lanes, options.scalar));
        let setting = crate::bench::measure_setting(&mut scene, trace, width, &pool, reps, by_kind)
            .map_err(Error::Other)?;
        let m = &setting.measured;
        Ok(Bench {
            build_seconds,
            min: m.min_s,
            median: m.seconds,
            max: m.max_s,
            rays: m.rays,
            mrays_per_s: m.mrays_per_s(),
            threads: pool.current_num_threads(),
            lanes: options.lanes,
            by_kind: setting.kinds.map(|p| crate::bench::ByKind::of(&p)),
        })
    }
}

/// What [`FileScene::bench`] measured.
#[derive(Clone, Debug)]
pub struct Bench {
    /// Seconds to compile the scene (builds included).
    pub build_seconds: f64,
    /// The fastest render's tracing seconds.
    pub min: f64,
    /// The median render's.
    pub median: f64,
    /// The slowest render's.
    pub max: f64,
    /// Rays per render.
    pub rays: u64,
    /// Millions of rays per second at the median.
    pub mrays_per_s: f64,
    /// Worker threads.
    pub threads: usize,
    /// Rays per packet.
    pub lanes: usize,
    /// The render split by ray kind, when asked for.
    pub by_kind: Option<crate::bench::ByKind>,
}
