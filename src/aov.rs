//! Arbitrary output variables: per-pixel raw results of the primary rays, one sample per pixel at pixel
//! centres, for comparing bareray with other tracers. Written as float EXR channels:
//! `Z` (hit distance t, +inf on a miss), `N.X`/`N.Y`/`N.Z` (unit outward geometric normal, 0 on a miss) and
//! `id` (primitive index, −1 on a miss; as 32-bit float while every index is exact in it, that is for scenes of
//! at most 2^24 primitives, and as a 32-bit unsigned channel with 0xFFFFFFFF on a miss beyond that).

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::compile::Scene;
use crate::geometry::NO_PRIM;
use crate::output::exr::Channel;
use crate::render::{trace_primary_window_lanes, Window};

/// One kind of AOV.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aov {
    /// Hit distance t.
    Depth,
    /// Unit normal.
    Normal,
    /// Primitive id.
    Id,
}

/// A set of AOVs in the order asked for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AovList(pub Vec<Aov>);

/// Parses a comma-separated list such as `depth,normal,id`.
pub fn parse_list(list: &str) -> Result<AovList, String> {
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        let aov = match name {
            "depth" => Aov::Depth,
            "normal" => Aov::Normal,
            "id" => Aov::Id,
            other => return Err(format!("unknown AOV `{other}`, expected depth, normal or id")),
        };
        if !out.contains(&aov) {
            out.push(aov);
        }
    }
    Ok(AovList(out))
}

/// The EXR channels of `which`, in that order: `Z`; `N.X`, `N.Y`, `N.Z`; `id` (float while every index of
/// a scene of `prim_count` primitives is exact in an f32, else unsigned).
pub(crate) fn channels(which: &[Aov], prim_count: usize) -> Vec<Channel> {
    let mut out = Vec::new();
    for aov in which {
        match aov {
            Aov::Depth => out.push(Channel { name: "Z", float: true }),
            Aov::Normal => out.extend(["N.X", "N.Y", "N.Z"].map(|name| Channel { name, float: true })),
            Aov::Id => out.push(Channel { name: "id", float: prim_count <= 1 << 24 }),
        }
    }
    out
}

/// The AOVs of `window`'s pixels (one camera ray per pixel centre, in packets of `lanes`), row-major, each
/// pixel the little-endian 4-byte samples of `channels``(which, …)` in order: the rows an EXR of them
/// takes (`output::write_channels`).
pub(crate) fn samples(
    scene: &Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
    window: Window,
    which: &[Aov],
) -> Vec<u8> {
    let hits = trace_primary_window_lanes(scene, lanes, pool, window);
    let w = hits.width as usize;
    let float_id = scene.geometry.len() <= 1 << 24;
    let start = scene.camera_f64.start;
    let per_pixel = channels(which, scene.geometry.len()).len() * 4;
    let mut out = vec![0u8; hits.t.len() * per_pixel];
    pool.install(|| {
        out.par_chunks_mut(per_pixel).enumerate().for_each(|(i, out)| {
            let (t, prim) = (hits.t[i], hits.prim[i]);
            let normal = || {
                if prim == NO_PRIM {
                    return [0.0; 3];
                }
                let (x, y) = (window.x0 + (i % w) as u32, window.y0 + (i / w) as u32);
                let ray = scene.camera_f64.ray_f32(x as f32 + 0.5, y as f32 + 0.5);
                let n = scene.geometry.surface(&ray, t, prim).normal;
                [n.x, n.y, n.z]
            };
            // `file_id` leaves NO_PRIM (no primitive) as it is.
            let id = scene.geometry.file_id(prim);
            let mut values = Vec::with_capacity(5);
            for aov in which {
                match aov {
                    // From the eye: a far scene's camera rays start `start` along (compile's frame).
                    Aov::Depth if start == 0.0 => values.push(t.to_bits()),
                    Aov::Depth => values.push(((start + f64::from(t)) as f32).to_bits()),
                    Aov::Normal => values.extend(normal().map(f32::to_bits)),
                    Aov::Id if float_id => {
                        values.push(if id == NO_PRIM { -1.0f32 } else { id as f32 }.to_bits())
                    }
                    Aov::Id => values.push(id),
                }
            }
            for (o, v) in out.chunks_exact_mut(4).zip(values) {
                o.copy_from_slice(&v.to_le_bytes());
            }
        });
    });
    out
}

/// The AOV file for an image output: `out.png` → `out.aov.exr`.
pub fn aov_path(output: &Path) -> PathBuf {
    output.with_extension("aov.exr")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lists_and_rejects_unknown_names() {
        assert_eq!(parse_list("depth,id").unwrap().0, vec![Aov::Depth, Aov::Id]);
        assert_eq!(parse_list("normal, normal").unwrap().0, vec![Aov::Normal]);
        assert!(parse_list("depth,alpha").unwrap_err().contains("`alpha`"));
    }

    #[test]
    fn aov_file_sits_beside_the_image() {
        assert_eq!(aov_path(Path::new("a/b.png")), PathBuf::from("a/b.aov.exr"));
    }
}
