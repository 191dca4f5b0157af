//! The camera's description ([`CameraDesc`]: eye, aim, field, resolution, sweep) and the changes the command
//! line and the Python module make to it ([`CameraOverrides`]).

use glam::DVec3;

/// Where the camera looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    /// A point the view direction passes through.
    LookAt(DVec3),
    /// The view direction itself (any length).
    Direction(DVec3),
}

/// How wide the camera sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Field {
    /// Horizontal view angle θ in degrees: the window is `s_j = 2·d·tan(θ/2)` wide.
    HorizontalAngle(f64),
    /// Pixel size s on the image plane at distance d: the window is `s·h_res` wide, so the field of view
    /// grows with s and with the resolution.
    PixelSize(f64),
}

/// Where pixel (j, k) samples the image plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Sweep {
    /// Pixel centres at `(j + ½)/h_res` across the window (pbrt, Embree, POV-Ray).
    #[default]
    PixelCentre,
    /// The lecture's `j/(h_res − 1)`: the first and last pixel centres lie on the window's edges.
    WindowEdges,
}

/// The lecture's camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Eye point O.
    pub eye: DVec3,
    /// View direction Z_v, or a point it passes through.
    pub aim: Aim,
    /// Up vector Y_v: need be neither unit nor perpendicular to the view direction.
    pub up: DVec3,
    /// Image-plane distance d.
    pub distance: f64,
    /// View angle or pixel size.
    pub field: Field,
    /// Horizontal resolution h_res.
    pub width: u32,
    /// Vertical resolution v_res.
    pub height: u32,
    /// Pixel-centre or window-edge sampling.
    pub sweep: Sweep,
}

impl CameraDesc {
    /// A camera at `eye` looking at `look` with `up` up, a horizontal field of view of `hfov` degrees and
    /// `width` × `height` pixels, rays through the pixel centres (image plane at distance 1).
    pub(crate) fn looking_at(eye: DVec3, look: DVec3, up: DVec3, hfov: f64, width: u32, height: u32) -> Self {
        Self {
            eye,
            aim: Aim::LookAt(look),
            up,
            distance: 1.0,
            field: Field::HorizontalAngle(hfov),
            width,
            height,
            sweep: Sweep::PixelCentre,
        }
    }
}

/// Changes to a camera: the command line's `--eye --look --up --hfov --width --height`, and the Python
/// module's keywords of the same names.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraOverrides {
    /// Eye point.
    pub eye: Option<DVec3>,
    /// A point to look at.
    pub look: Option<DVec3>,
    /// Up vector.
    pub up: Option<DVec3>,
    /// Horizontal field of view in degrees (pixel-centre sweep).
    pub hfov: Option<f64>,
    /// Width in pixels; given alone, the height follows the camera's aspect ratio.
    pub width: Option<u32>,
    /// Height in pixels; given alone, the width follows the camera's aspect ratio.
    pub height: Option<u32>,
}

impl CameraOverrides {
    /// Applies the changes to `cam`.
    pub fn apply(&self, cam: &mut CameraDesc) {
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
    }
}

impl Default for CameraDesc {
    fn default() -> Self {
        Self {
            eye: DVec3::new(0.0, 0.0, -5.0),
            aim: Aim::LookAt(DVec3::ZERO),
            up: DVec3::Y,
            distance: 1.0,
            field: Field::HorizontalAngle(45.0),
            width: 640,
            height: 480,
            sweep: Sweep::PixelCentre,
        }
    }
}
