//! Camera and resolution overrides shared by every command that renders.

use clap::Args;
use glam::DVec3;

use bareray::scene::desc::CameraOverrides;

/// `--eye --look --up --hfov --width --height`.
#[derive(Args, Debug, Clone, Default)]
pub(super) struct CameraArgs {
    /// Eye point, `x,y,z`.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub(super) eye: Option<DVec3>,
    /// Point to look at, `x,y,z`.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub(super) look: Option<DVec3>,
    /// Up vector, `x,y,z` (need be neither unit nor perpendicular to the view).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub(super) up: Option<DVec3>,
    /// Horizontal field of view in degrees, across the outer pixel edges (pixel-centre sampling).
    #[arg(long, value_parser = parse_hfov)]
    pub(super) hfov: Option<f64>,
    /// Image width in pixels. Given alone, the height follows the scene's aspect ratio. On a scene that sets
    /// the camera's `pixel_size` the pixels keep their size, so the view widens or narrows with the
    /// resolution (the framing changes); add --hfov to keep a fixed view.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub(super) width: Option<u32>,
    /// Image height in pixels. Given alone, the width follows the scene's aspect ratio. On a scene that sets
    /// `pixel_size` the framing changes with the resolution, as for --width.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub(super) height: Option<u32>,
}

/// Parses `x,y,z`.
pub(super) fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let nums: Result<Vec<f64>, _> = parts.iter().map(|p| p.parse::<f64>()).collect();
    match nums {
        Ok(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => Ok(DVec3::new(v[0], v[1], v[2])),
        _ => Err(format!("expected three finite numbers `x,y,z`, got `{s}`")),
    }
}

/// Parses a horizontal field of view in degrees, in (0, 180).
pub(super) fn parse_hfov(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(h) if h > 0.0 && h < 180.0 => Ok(h),
        _ => Err("the field of view must be a number of degrees in (0, 180)".to_owned()),
    }
}

impl CameraArgs {
    /// The overrides as the library takes them.
    pub(super) fn overrides(&self) -> CameraOverrides {
        let CameraArgs { eye, look, up, hfov, width, height } = self.clone();
        CameraOverrides { eye, look, up, hfov, width, height }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vectors_parse_with_signs_and_exponents() {
        assert_eq!(parse_vec3("0,-4,1e1").unwrap(), DVec3::new(0.0, -4.0, 10.0));
        assert!(parse_vec3("1,2").is_err());
        assert!(parse_vec3("1,2,x").is_err());
        assert!(parse_vec3("1,2,inf").is_err());
    }

    #[test]
    fn field_of_view_lies_strictly_between_0_and_180() {
        assert_eq!(parse_hfov("45"), Ok(45.0));
        for bad in ["0", "180", "-10", "nan", "x"] {
            assert!(parse_hfov(bad).is_err(), "{bad}");
        }
    }
}
