//! Types sidecars: radii and colours by kind in a small TOML file, for particle files whose kinds are LAMMPS
//! type numbers or elements whose table values do not suit. Each table is a kind, named as `--radius` names
//! it (an element symbol in any case, a LAMMPS type number, or `["*"]` for every kind beneath the named
//! ones), with an optional `radius` (positive, in the particle file's unit) and an optional `color` (`[r, g,
//! b]`, channels from 0 to 1):
//!
//! ```toml
//! [1]
//! radius = 0.5
//! color = [0.9, 0.2, 0.2]
//!
//! [O]
//! color = [1, 0, 0]
//! ```
//!
//! A sidecar's values beat the file's and the tables' and are beaten by `--radius` and `--color`. It is the
//! file `render --types` names, or else the particle file's own when it exists (`sidecar_of`). Kinds it
//! names that a frame lacks are not warned about (one sidecar may serve several files). Unknown keys, values
//! of the wrong type or out of range are errors naming the sidecar's line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::io::SceneError;
use crate::math::Rgb;

/// One kind's entry.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TypeEntry {
    /// The kind, as `--radius` names it.
    pub(crate) name: String,
    /// Its radius, in the particle file's unit.
    pub(crate) radius: Option<f64>,
    /// Its colour, channels in [0, 1].
    pub(crate) color: Option<Rgb>,
}

/// A sidecar read: its kinds, in the order of their names.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Types {
    /// The kinds.
    pub(crate) entries: Vec<TypeEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EntryToml {
    radius: Option<Spanned<f64>>,
    color: Option<Spanned<Vec<f64>>>,
}

/// The sidecar beside a particle file, if it exists: `<file>.types.toml` (`conf.gro.types.toml` for
/// `conf.gro`), or for a compressed file also the name without `.gz` or `.bz2` (`run.dump.types.toml` for
/// `run.dump.gz`).
pub(crate) fn sidecar_of(path: &Path) -> Option<PathBuf> {
    let with = |p: &Path| {
        let mut name = p.as_os_str().to_owned();
        name.push(".types.toml");
        PathBuf::from(name)
    };
    let own = with(path);
    if own.is_file() {
        return Some(own);
    }
    let compressed = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if matches!(compressed.as_deref(), Some("gz" | "bz2")) {
        let plain = with(&path.with_extension(""));
        if plain.is_file() {
            return Some(plain);
        }
    }
    None
}

/// Reads a sidecar.
pub(crate) fn read(path: &Path) -> Result<Types, SceneError> {
    let bytes = std::fs::read(path)
        .map_err(|e| SceneError::whole_file(path, format!("cannot read types file: {e}")))?;
    parse(path, &crate::io::error::text(path, bytes)?)
}

/// Parses a sidecar's text; `path` names it in errors.
pub(crate) fn parse(path: &Path, source: &str) -> Result<Types, SceneError> {
    let at = |offset: usize, message: String| SceneError::at_offset(path, source, offset, message);
    let file: BTreeMap<String, Spanned<EntryToml>> = toml::from_str(source).map_err(|e| {
        let message =
            format!("{} (expected tables such as `[C]` or `[1]` with radius and color)", e.message().trim());
        at(e.span().map_or(0, |s| s.start), message)
    })?;
    let mut entries = Vec::with_capacity(file.len());
    for (name, entry) in file {
        let start = entry.span().start;
        let entry = entry.into_inner();
        if name.trim().is_empty() {
            return Err(at(start, "a kind with an empty name".to_owned()));
        }
        let radius = match entry.radius {
            Some(r) if !(r.get_ref().is_finite() && *r.get_ref() > 0.0 && (*r.get_ref() as f32) > 0.0) => {
                return Err(at(
                    r.span().start,
                    format!("[{name}] radius must be positive, got {}", r.get_ref()),
                ));
            }
            r => r.map(Spanned::into_inner),
        };
        let color = match entry.color {
            Some(c) => {
                let v = c.get_ref();
                if v.len() != 3 || !v.iter().all(|x| (0.0..=1.0).contains(x)) {
                    let message =
                        format!("[{name}] color must be [r, g, b] with channels from 0 to 1, got {v:?}");
                    return Err(at(c.span().start, message));
                }
                Some(Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32))
            }
            None => None,
        };
        entries.push(TypeEntry { name: name.trim().to_owned(), radius, color });
    }
    Ok(Types { entries })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> Result<Types, SceneError> {
        parse(Path::new("t.types.toml"), text)
    }

    #[test]
    fn kinds_with_radius_and_colour() {
        let t =
            parsed("[1]\nradius = 0.5\ncolor = [0.9, 0.2, 0]\n\n[O]\ncolor = [1, 0, 0]\n[c]\nradius = 2\n")
                .unwrap();
        let names: Vec<&str> = t.entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["1", "O", "c"]);
        assert_eq!(t.entries[0].radius, Some(0.5));
        assert_eq!(t.entries[0].color, Some(Rgb::new(0.9, 0.2, 0.0)));
        assert_eq!((t.entries[1].radius, t.entries[1].color), (None, Some(Rgb::new(1.0, 0.0, 0.0))));
        assert_eq!(t.entries[2].radius, Some(2.0));
        assert_eq!(parsed("").unwrap(), Types::default());
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            ("[C]\nradius = 1.7\n[O]\nradius = -1\n", 4, "radius must be positive"),
            ("[C]\ncolor = [1, 2, 0]\n", 2, "channels from 0 to 1"),
            ("[C]\ncolor = [1, 0]\n", 2, "channels from 0 to 1"),
            ("[C]\nradius = 1\n\nsize = 2\n", 4, "unknown field `size`"),
            ("[C]\nradius = \"big\"\n", 2, "invalid type"),
            ("C = 1.7\n", 1, "expected tables"),
            ("[C]\nradius = 1\n[C]\n", 3, "duplicate"),
        ];
        for (text, line, says) in cases {
            let e = parsed(text).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e}");
            assert!(e.to_string().contains(says), "{text:?}: {e}");
            assert!(e.to_string().starts_with("t.types.toml:"), "{e}");
        }
    }

    #[test]
    fn sidecars_are_found_beside_the_file() {
        let dir = std::env::temp_dir().join(format!("bareray-types-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let data = dir.join("run.dump.gz");
        assert_eq!(sidecar_of(&data), None);
        std::fs::write(dir.join("run.dump.types.toml"), "").unwrap();
        assert_eq!(sidecar_of(&data), Some(dir.join("run.dump.types.toml")));
        std::fs::write(dir.join("run.dump.gz.types.toml"), "").unwrap();
        assert_eq!(sidecar_of(&data), Some(dir.join("run.dump.gz.types.toml")));
        assert_eq!(sidecar_of(&dir.join("other.dump")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
