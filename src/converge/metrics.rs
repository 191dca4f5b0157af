//! How far an image is from a reference: RMSE over the whole image, RMSE over the edge pixels (where the
//! reference's visible primitive changes between neighbours: where antialiasing matters), and PSNR.

use crate::film::Image;

/// The error of one image against the reference, on linear film values clamped to [0, 1] (what an 8-bit
/// image can show), over the three channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// Root mean square difference over every pixel and channel.
    pub rmse: f64,
    /// Root mean square difference over the edge pixels only (0 when there are none).
    pub rmse_edges: f64,
    /// Peak signal-to-noise ratio in dB for a peak of 1: `−20·log10(rmse)` (infinite for identical images).
    pub psnr: f64,
}

/// The edge pixels of an image whose primary hits (pixel centres) are `prims` (row-major, `width` columns):
/// a pixel is an edge pixel when one of its 4 neighbours sees another primitive (or background).
pub(crate) fn edge_mask(prims: &[u32], width: u32) -> Vec<bool> {
    let w = width as usize;
    let h = prims.len() / w.max(1);
    (0..prims.len())
        .map(|i| {
            let (x, y, p) = (i % w, i / w, prims[i]);
            let differs = |j: usize| prims[j] != p;
            (x > 0 && differs(i - 1))
                || (x + 1 < w && differs(i + 1))
                || (y > 0 && differs(i - w))
                || (y + 1 < h && differs(i + w))
        })
        .collect()
}

/// The errors of `image` against `reference` (same size); `edges` marks the edge pixels ([`edge_mask`]).
pub(crate) fn errors(image: &Image, reference: &Image, edges: &[bool]) -> Errors {
    assert_eq!((image.width, image.height), (reference.width, reference.height), "images of one size");
    let (mut all, mut edge, mut edge_pixels) = (0.0f64, 0.0f64, 0usize);
    for ((a, b), &is_edge) in image.pixels.iter().zip(&reference.pixels).zip(edges) {
        let d = |u: f32, v: f32| f64::from(u.clamp(0.0, 1.0)) - f64::from(v.clamp(0.0, 1.0));
        let sq = d(a.x, b.x).powi(2) + d(a.y, b.y).powi(2) + d(a.z, b.z).powi(2);
        all += sq;
        if is_edge {
            edge += sq;
            edge_pixels += 1;
        }
    }
    let rmse = (all / (3 * image.pixels.len().max(1)) as f64).sqrt();
    let rmse_edges = if edge_pixels == 0 { 0.0 } else { (edge / (3 * edge_pixels) as f64).sqrt() };
    Errors { rmse, rmse_edges, psnr: -20.0 * rmse.log10() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rgb;

    #[test]
    fn edges_are_where_neighbours_see_another_primitive() {
        // Two columns of primitive 1, two of primitive 2: the middle columns are edges.
        let prims = [1, 1, 2, 2, 1, 1, 2, 2];
        let mask = edge_mask(&prims, 4);
        assert_eq!(mask, [false, true, true, false, false, true, true, false]);
    }

    #[test]
    fn errors_of_a_known_difference() {
        let mut a = Image::new(2, 1);
        let b = Image::new(2, 1);
        a.set(0, 0, Rgb::new(0.3, 0.3, 0.3));
        // Values past 1 are clamped: 2.0 shows as 1.0.
        a.set(1, 0, Rgb::new(2.0, 0.0, 0.0));
        let e = errors(&a, &b, &[true, false]);
        let want = ((3.0 * 0.09 + 1.0) / 6.0f64).sqrt();
        assert!((e.rmse - want).abs() < 1e-6, "{e:?}");
        assert!((e.rmse_edges - 0.3).abs() < 1e-6, "{e:?}");
        assert!((e.psnr + 20.0 * want.log10()).abs() < 1e-5);
        assert_eq!(errors(&b, &b, &[true, true]).psnr, f64::INFINITY);
    }
}
