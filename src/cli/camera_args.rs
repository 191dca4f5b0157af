//! Camera and resolution overrides shared by every command that renders.

use anyhow::{bail, Result};
use clap::Args;
use glam::DVec3;

use crate::scene::desc::{Aim, Field, SceneDesc, Sweep};

/// `--eye --look --up --hfov --width --height`.
#[derive(Args, Debug, Clone, Default)]
pub struct CameraArgs {
    /// Eye point, `x,y,z`.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point to look at, `x,y,z`.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub look: Option<DVec3>,
    /// Up vector, `x,y,z` (need be neither unit nor perpendicular to the view).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<DVec3>,
    /// Horizontal field of view in degrees, across the outer pixel edges (pixel-centre sampling).
    #[arg(long)]
    pub hfov: Option<f64>,
    /// Image width in pixels. Given alone, the height follows the scene's aspect ratio.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height in pixels. Given alone, the width follows the scene's aspect ratio.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
}

/// Parses `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let nums: Result<Vec<f64>, _> = parts.iter().map(|p| p.parse::<f64>()).collect();
    match nums {
        Ok(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => Ok(DVec3::new(v[0], v[1], v[2])),
        _ => Err(format!("expected three finite numbers `x,y,z`, got `{s}`")),
    }
}

impl CameraArgs {
    /// Applies the overrides to a scene.
    pub fn apply(&self, desc: &mut SceneDesc) -> Result<()> {
        let cam = &mut desc.camera;
        if let Some(eye) = self.eye {
            cam.eye = eye;
        }
        if let Some(look) = self.look {
            cam.aim = Aim::LookAt(look);
        }
        if let Some(up) = self.up {
            cam.up = up;
        }
        if let Some(hfov) = self.hfov {
            if !(hfov > 0.0 && hfov < 180.0) {
                bail!("--hfov must be in (0, 180) degrees, got {hfov}");
            }
            cam.field = Field::HorizontalAngle(hfov);
            cam.sweep = Sweep::PixelCentre;
        }
        let aspect = f64::from(cam.width) / f64::from(cam.height);
        match (self.width, self.height) {
            (Some(w), Some(h)) => (cam.width, cam.height) = (w, h),
            (Some(w), None) => (cam.width, cam.height) = (w, ((f64::from(w) / aspect).round() as u32).max(1)),
            (None, Some(h)) => (cam.width, cam.height) = (((f64::from(h) * aspect).round() as u32).max(1), h),
            (None, None) => {}
        }
        Ok(())
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
}
