//! Reading a scene for compiling, with the search structure its spheres get decided first: an `.f32r` field
//! bound for the particle tree is mapped rather than read (`crate::io::f32r::map`), and one too large for
//! the memory is refused before anything is loaded ([`super::memory`]).

use std::path::{Path, PathBuf};

use super::memory::{self, FieldChoice, TooLarge};
use super::{Accel, CameraError, CompileOptions, Scene};
use crate::io::f32r::{self, MappedRecords};
use crate::io::{LoadOptions, SceneError, SceneFormat};
use crate::scene::desc::{Pattern, SceneDesc};

/// A scene read for compiling.
#[derive(Debug)]
pub struct Loaded {
    /// The description (without the mapped field's spheres).
    pub desc: SceneDesc,
    /// A mapped `.f32r` field, for the particle tree.
    pub mapped: Option<MappedRecords>,
    /// How the spheres are searched.
    pub accel: Accel,
    /// Why the particle tree, when `auto` chose it.
    pub(crate) note: Option<String>,
    /// The reader's warnings (unknown elements in a particle file, say).
    pub warnings: Vec<String>,
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The reader's error.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The field fits in no search structure.
    #[error("{}: {}", .0.display(), .1)]
    TooLarge(PathBuf, TooLarge),
}

/// Reads `path` for a render with `accel`, planning for `available` bytes of memory
/// ([`memory::available`] by default). With [`Accel::Auto`] a sphere field too large for the BVH goes to the
/// particle tree; an `.f32r` field bound for the tree is mapped, and one that fits neither is refused after
/// reading only its header. `options` are the reader's ([`crate::io::load_with`]).
pub fn load(path: &Path, accel: Accel, available: u64, options: &LoadOptions) -> Result<Loaded, LoadError> {
    let plan = |spheres: u64| match accel {
        Accel::Auto | Accel::Particles => memory::choose(spheres, accel == Accel::Particles, available),
        _ => Ok(FieldChoice::Bvh),
    };
    if SceneFormat::from_extension(path) == Some(SceneFormat::F32r)
        && !path.is_dir()
        && !options.chooses_particles()
    {
        let count = f32r::header_count(path)?;
        match plan(count).map_err(|e| LoadError::TooLarge(path.to_owned(), e))? {
            FieldChoice::Bvh => {}
            FieldChoice::Particles { for_memory } => {
                let mapped = f32r::map(path)?;
                let [lo, hi] = mapped.bounds();
                let desc = crate::io::xyzr::scene_framing(lo, hi, options.view);
                let note = for_memory.then(|| note(count, available));
                let warnings = Vec::new();
                return Ok(Loaded { desc, mapped: Some(mapped), accel: Accel::Particles, note, warnings });
            }
        }
    }
    let read = crate::io::load_with(path, options)?;
    Ok(Loaded { warnings: read.warnings, ..loaded_desc(read.desc, accel, available) })
}

/// A description read otherwise (standard input, built in) as [`load`] would give it: with [`Accel::Auto`],
/// spheres too many for the BVH in `available` bytes go to the particle tree.
pub fn loaded_desc(desc: SceneDesc, accel: Accel, available: u64) -> Loaded {
    let spheres = desc.spheres.len() as u64;
    // Already in memory: a field too large for either structure gets the tree and its chance.
    let (accel, note) = match memory::choose(spheres, false, available) {
        Ok(FieldChoice::Particles { .. }) | Err(_) if accel == Accel::Auto => {
            (Accel::Particles, Some(note(spheres, available)))
        }
        _ => (accel, None),
    };
    Loaded { desc, mapped: None, accel, note, warnings: Vec::new() }
}

/// The reason `auto` gives for the particle tree.
fn note(spheres: u64, available: u64) -> String {
    format!(
        "the particle tree, as the BVH would need about {:.1} GB for {spheres} spheres and {:.1} GB is available",
        (spheres * memory::BVH_BYTES_PER_SPHERE) as f64 / 1e9,
        available as f64 / 1e9
    )
}

/// What the particle tree cannot do for a description, if anything: the coverage pattern prefilters spheres
/// from the BVH's arrays.
pub fn particles_unsupported(desc: &SceneDesc) -> Option<&'static str> {
    (desc.render.pattern == Pattern::Coverage).then_some(
        "the coverage pattern prefilters spheres found in a BVH: use --accel bvh or another pattern",
    )
}

impl Scene {
    /// Compiles what [`load`] read, with its search structure for the spheres (`options.accel` is replaced).
    pub fn compile_loaded(loaded: Loaded, options: CompileOptions) -> Result<Scene, CameraError> {
        let options = CompileOptions { accel: loaded.accel, ..options };
        let mut scene = match loaded.mapped {
            Some(mapped) => Scene::compile_mapped(loaded.desc, mapped, options),
            None => Scene::compile_owned(loaded.desc, options),
        }?;
        scene.accel_note = loaded.note;
        Ok(scene)
    }
}
