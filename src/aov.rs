//! Arbitrary output variables: per-pixel raw results of the primary rays, one sample per pixel at pixel
//! centres, for comparing bareray with other tracers. Written as float EXR channels:
//! `Z` (hit distance t, +inf on a miss), `N.X`/`N.Y`/`N.Z` (unit outward geometric normal, 0 on a miss) and
//! `id` (primitive index, −1 on a miss; as 32-bit float while every index is exact in it, that is for scenes of
//! at most 2^24 primitives, and as a 32-bit unsigned channel with 0xFFFFFFFF on a miss beyond that).

use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec, WritableImage,
};
use rayon::prelude::*;

use crate::compile::Scene;
use crate::geometry::NO_PRIM;
use crate::output::{write_atomic, BoxError};
use crate::render::primary_hits_lanes;

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

/// Primary-ray results, row-major, row 0 at the top.
#[derive(Clone, Debug, Default)]
pub struct AovImage {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Hit distance, +inf on a miss.
    pub depth: Vec<f32>,
    /// Unit outward normal, zero on a miss.
    pub normal: Vec<[f32; 3]>,
    /// Primitive id, [`NO_PRIM`] on a miss.
    pub id: Vec<u32>,
}

/// Traces one ray through every pixel centre in packets of `lanes`, and looks up the normals.
pub fn render_aovs(scene: &Scene, lanes: usize, pool: &rayon::ThreadPool) -> AovImage {
    let hits = primary_hits_lanes(scene, lanes, pool);
    let w = hits.width as usize;
    let normal = pool.install(|| {
        (0..hits.t.len())
            .into_par_iter()
            .map(|i| {
                if hits.prim[i] == NO_PRIM {
                    return [0.0; 3];
                }
                let ray = scene.camera_f64.ray_f32((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                let n = scene.geometry.surface(&ray, hits.t[i], hits.prim[i]).normal;
                [n.x, n.y, n.z]
            })
            .collect()
    });
    // `file_id` leaves NO_PRIM (no primitive) as it is.
    let id = hits.prim.iter().map(|&p| scene.geometry.file_id(p)).collect();
    AovImage { width: hits.width, height: hits.height, depth: hits.t, normal, id }
}

/// The AOV file for an image output: `out.png` → `out.aov.exr`.
pub fn aov_path(output: &Path) -> PathBuf {
    output.with_extension("aov.exr")
}

/// Writes the chosen channels to an EXR file, atomically. `prim_count` decides the id channel's type.
pub fn write_exr(img: &AovImage, which: &[Aov], prim_count: usize, path: &Path) -> Result<(), BoxError> {
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for aov in which {
        match aov {
            Aov::Depth => channels.push(AnyChannel::new("Z", FlatSamples::F32(img.depth.clone()))),
            Aov::Normal => {
                for (axis, name) in ["N.X", "N.Y", "N.Z"].into_iter().enumerate() {
                    let v = img.normal.iter().map(|n| n[axis]).collect();
                    channels.push(AnyChannel::new(name, FlatSamples::F32(v)));
                }
            }
            Aov::Id if prim_count <= 1 << 24 => {
                let v = img.id.iter().map(|&i| if i == NO_PRIM { -1.0 } else { i as f32 }).collect();
                channels.push(AnyChannel::new("id", FlatSamples::F32(v)));
            }
            Aov::Id => channels.push(AnyChannel::new("id", FlatSamples::U32(img.id.clone()))),
        }
    }
    let size = (img.width as usize, img.height as usize);
    let layer =
        Layer::new(size, LayerAttributes::default(), Encoding::FAST_LOSSLESS, AnyChannels::sort(channels));
    write_atomic(path, |tmp| Ok(Image::from_layer(layer).write().to_file(tmp)?))
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
