//! Surfaces and lights: the Whitted [`Material`] with its optional [`Checker`], and the point lights
//! ([`LightDesc`]) with their [`Falloff`].

use glam::DVec3;

use crate::math::Rgb;

/// A solid-texture checkerboard in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// The colour of the odd cells (the material's colour fills the even ones).
    pub(crate) color: Rgb,
    /// Edge length of a cell.
    pub(crate) size: f32,
}

/// Whitted surface description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Base colour (diffuse and ambient).
    pub color: Rgb,
    /// Optional checkerboard.
    pub checker: Option<Checker>,
    /// Ambient coefficient.
    pub ambient: f32,
    /// Lambert coefficient.
    pub diffuse: f32,
    /// Phong highlight coefficient.
    pub specular: f32,
    /// Phong exponent.
    pub shininess: f32,
    /// Mirror reflection weight.
    pub reflect: f32,
    /// Transmission weight.
    pub transmit: f32,
    /// Index of refraction (inside over outside).
    pub ior: f32,
    /// Split the transmitted weight by the dielectric Fresnel reflectance instead of fixed weights.
    pub fresnel: bool,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            color: Rgb::all(0.8),
            checker: None,
            ambient: 0.1,
            diffuse: 0.9,
            specular: 0.0,
            shininess: 32.0,
            reflect: 0.0,
            transmit: 0.0,
            ior: 1.5,
            fresnel: false,
        }
    }
}

/// How a light's intensity falls with distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Falloff {
    /// Constant (the classic Whitted light).
    #[default]
    None,
    /// 1/r² (a physical point light).
    InverseSquare,
}

/// A coloured point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightDesc {
    /// Where it is.
    pub position: DVec3,
    /// Colour times intensity.
    pub color: Rgb,
    /// Distance falloff.
    pub falloff: Falloff,
}
