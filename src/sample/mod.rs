//! Antialiasing: where samples go inside a pixel (supersampling) and filters over the finished image
//! (postfiltering).

pub(crate) mod filter;
mod postfilter;
pub(crate) mod sequence;

pub(crate) use postfilter::{lecture_3x3, lecture_3x3_pixel};

/// Offsets in [0, 1)² of an n×n regular grid: the centres of the n² equal sub-squares, row by row.
pub(crate) fn grid_offsets(n: u32) -> Vec<(f32, f32)> {
    let step = 1.0 / n as f32;
    (0..n).flat_map(|b| (0..n).map(move |a| ((a as f32 + 0.5) * step, (b as f32 + 0.5) * step))).collect()
}

/// Weights of the lecture's 9-sample half-pixel grid (corner, edge midpoint, centre), the trapezoid rule
/// for the box filter over the pixel: 1/16 at corners, 1/8 at edge midpoints, 1/4 at the centre.
pub(crate) const HALF_PIXEL_WEIGHTS: [[f32; 3]; 3] = [
    [1.0 / 16.0, 1.0 / 8.0, 1.0 / 16.0],
    [1.0 / 8.0, 1.0 / 4.0, 1.0 / 8.0],
    [1.0 / 16.0, 1.0 / 8.0, 1.0 / 16.0],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_offsets_are_stratum_centres() {
        assert_eq!(grid_offsets(1), vec![(0.5, 0.5)]);
        assert_eq!(grid_offsets(2), vec![(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]);
    }

    #[test]
    fn half_pixel_weights_sum_to_one() {
        let sum: f32 = HALF_PIXEL_WEIGHTS.iter().flatten().sum();
        assert_eq!(sum, 1.0);
    }
}
