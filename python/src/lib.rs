//! The `bareray` Python module: spheres given as NumPy arrays, or a scene file, rendered into a NumPy image.
//!
//! A thin binding over the library's public API ([`bareray::api`], [`bareray::io::particles::arrays`]):
//! arrays are read in place where their layout allows (C-contiguous float32 or float64) and converted by
//! NumPy otherwise; the scene description is made with the GIL held (so no other Python thread can change
//! an array while it is read), and compiling and tracing run with the GIL released.

use std::path::PathBuf;

use bareray::api::{self, FileScene, Picture, RenderOptions};
use bareray::film::Image;
use bareray::io::particles::arrays::{Floats, SphereArrays};
use bareray::scene::desc::{CameraOverrides, Shade, Transfer};
use bareray::settings::Overrides;
use glam::DVec3;
use numpy::{
    PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyFileNotFoundError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// An array borrowed from NumPy as it is (C-contiguous float32 or float64), or NumPy's float64 copy of it.
enum Array<'py> {
    F32(PyReadonlyArrayDyn<'py, f32>),
    F64(PyReadonlyArrayDyn<'py, f64>),
}

impl Array<'_> {
    fn floats(&self) -> Floats<'_> {
        // Both are C-contiguous (checked when made), so the slices exist.
        match self {
            Array::F32(a) => Floats::F32(a.as_slice().expect("contiguous")),
            Array::F64(a) => Floats::F64(a.as_slice().expect("contiguous")),
        }
    }

    fn shape(&self) -> Vec<usize> {
        match self {
            Array::F32(a) => a.shape().to_vec(),
            Array::F64(a) => a.shape().to_vec(),
        }
    }
}

/// `value` as an array of floats: borrowed when it is a C-contiguous float32 or float64 ndarray, else
/// converted by `numpy.ascontiguousarray(value, dtype=float64)` (lists, other dtypes, strided views).
fn array<'py>(py: Python<'py>, value: &Bound<'py, PyAny>, name: &str) -> PyResult<Array<'py>> {
    if let Ok(a) = value.cast::<PyUntypedArray>() {
        if a.is_c_contiguous() {
            if let Ok(a) = value.cast::<PyArrayDyn<f32>>() {
                return Ok(Array::F32(a.try_readonly().map_err(|e| borrow_error(name, e))?));
            }
            if let Ok(a) = value.cast::<PyArrayDyn<f64>>() {
                return Ok(Array::F64(a.try_readonly().map_err(|e| borrow_error(name, e))?));
            }
        }
    }
    let numpy = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", numpy.getattr("float64")?)?;
    let converted = numpy
        .call_method("ascontiguousarray", (value,), Some(&kwargs))
        .map_err(|e| PyValueError::new_err(format!("{name}: not an array of numbers ({e})")))?;
    let a = converted
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?;
    Ok(Array::F64(a.try_readonly().map_err(|e| borrow_error(name, e))?))
}

fn borrow_error(name: &str, e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{name}: cannot be read ({e})"))
}

/// Checks that `a` has shape `(n, 3)`.
fn rows_of_three(a: &Array, name: &str) -> PyResult<usize> {
    match a.shape()[..] {
        [n, 3] => Ok(n),
        ref shape => Err(PyValueError::new_err(format!("{name} must have shape (n, 3), got {shape:?}"))),
    }
}

/// A point or direction from a sequence of three numbers.
fn vec3(value: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Option<DVec3>> {
    let Some(value) = value.filter(|v| !v.is_none()) else { return Ok(None) };
    let v: Vec<f64> = value
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{name} must be three numbers (x, y, z)")))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Some(DVec3::new(x, y, z))),
        _ => Err(PyValueError::new_err(format!("{name} must be three finite numbers (x, y, z), got {v:?}"))),
    }
}

/// `view`: `"+x"`, `"-y"`, … (as the command line's `--view`) or a direction of three numbers.
fn view_of(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<DVec3>> {
    match value.filter(|v| !v.is_none()) {
        Some(v) if v.is_instance_of::<PyString>() => {
            let axis = match v.extract::<String>()?.trim().to_ascii_lowercase().as_str() {
                "+x" | "x" => DVec3::X,
                "-x" => DVec3::NEG_X,
                "+y" | "y" => DVec3::Y,
                "-y" => DVec3::NEG_Y,
                "+z" | "z" => DVec3::Z,
                "-z" => DVec3::NEG_Z,
                s => {
                    return Err(PyValueError::new_err(format!(
                        "view must be +x, -x, +y, -y, +z, -z or (x, y, z), got {s:?}"
                    )))
                }
            };
            Ok(Some(axis))
        }
        v => match vec3(v, "view")? {
            Some(d) if d.length() == 0.0 => Err(PyValueError::new_err("view must not be the zero vector")),
            d => Ok(d),
        },
    }
}

/// The render settings from the keywords.
#[allow(clippy::too_many_arguments)]
fn options(
    width: Option<u32>,
    height: Option<u32>,
    eye: Option<&Bound<'_, PyAny>>,
    look: Option<&Bound<'_, PyAny>>,
    up: Option<&Bound<'_, PyAny>>,
    hfov: Option<f64>,
    shade: Option<&str>,
    spp: Option<u32>,
    threads: Option<usize>,
    lanes: &Bound<'_, PyAny>,
) -> PyResult<RenderOptions> {
    for (name, v) in [("width", width), ("height", height)] {
        if v == Some(0) || v.is_some_and(|v| v > 65536) {
            return Err(PyValueError::new_err(format!("{name} must be from 1 to 65536")));
        }
    }
    if threads == Some(0) {
        return Err(PyValueError::new_err("threads must be at least 1"));
    }
    if let Some(h) = hfov.filter(|h| !(*h > 0.0 && *h < 180.0)) {
        return Err(PyValueError::new_err(format!("hfov must be in (0, 180) degrees, got {h}")));
    }
    let camera = CameraOverrides {
        eye: vec3(eye, "eye")?,
        look: vec3(look, "look")?,
        up: vec3(up, "up")?,
        hfov,
        width,
        height,
    };
    let shade =
        shade.map(Shade::parse).transpose().map_err(|e| PyValueError::new_err(format!("shade: {e}")))?;
    let (lanes, scalar) = match lanes.extract::<String>() {
        Ok(s) if s == "scalar" => (1, true),
        Ok(s) => {
            return Err(PyValueError::new_err(format!("lanes must be 1, 4, 8, 16 or \"scalar\", got {s:?}")))
        }
        Err(_) => (lanes.extract::<usize>()?, false),
    };
    let overrides = Overrides { camera, shade, spp, ..Overrides::default() };
    Ok(RenderOptions { overrides, threads, lanes, scalar })
}

fn api_error(e: api::Error) -> PyErr {
    match e {
        api::Error::Other(m) => PyRuntimeError::new_err(m),
        e => PyValueError::new_err(e.to_string()),
    }
}

/// The image as a float32 array of shape (height, width, 3): its pixel buffer, handed to NumPy without a
/// copy ([`Image::into_rgb_values`]).
fn to_numpy(py: Python<'_>, image: Image) -> PyResult<Bound<'_, PyArrayDyn<f32>>> {
    let shape = vec![image.height as usize, image.width as usize, 3];
    PyArray1::from_vec(py, image.into_rgb_values()).reshape(shape)
}

/// Renders spheres: `centers` of shape (n, 3), `radii` of shape (n,) or one number, `colors` of shape
/// (n, 3) with channels in [0, 1] (default: grey). Without a camera the spheres are framed as bareray frames
/// a particle file: seen from `view` ("+z" by default; "-x", … or a direction), a light at the eye, on
/// white. `eye`, `look`, `up` (three numbers) and `hfov` (degrees) change that camera (a new `eye` takes
/// the light along). `shade` is
/// "whitted" or "ao[:SAMPLES[,DISTANCE]]", `spp` a square number of samples per pixel on a grid.
///
/// Returns float32 linear RGB of shape (height, width, 3): the values bareray writes to EXR, and, clamped
/// to [0, 1], times 255 and rounded (`to_uint8`), the 8-bit PNG of the command line. Bad arrays raise
/// ValueError naming the array and the first bad sphere. The GIL is released while the scene is built and
/// traced.
#[pyfunction]
#[pyo3(signature = (centers, radii, colors=None, *, width, height, eye=None, look=None, up=None, hfov=None,
    view=None, shade="whitted", spp=1, threads=None, lanes=None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    centers: &Bound<'py, PyAny>,
    radii: &Bound<'py, PyAny>,
    colors: Option<&Bound<'py, PyAny>>,
    width: u32,
    height: u32,
    eye: Option<&Bound<'py, PyAny>>,
    look: Option<&Bound<'py, PyAny>>,
    up: Option<&Bound<'py, PyAny>>,
    hfov: Option<f64>,
    view: Option<&Bound<'py, PyAny>>,
    shade: &str,
    spp: u32,
    threads: Option<usize>,
    lanes: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let sixteen = 16usize.into_pyobject(py)?.into_any();
    let lanes = lanes.unwrap_or(&sixteen);
    let options =
        options(Some(width), Some(height), eye, look, up, hfov, Some(shade), Some(spp), threads, lanes)?;
    let centers = array(py, centers, "centers")?;
    let n = rows_of_three(&centers, "centers")?;
    let radii = match radii.extract::<f64>() {
        Ok(r) => Array::F64(PyArray1::from_vec(py, vec![r; n]).to_dyn().readonly()),
        Err(_) => array(py, radii, "radii")?,
    };
    if radii.shape() != [n] {
        let shape = radii.shape();
        return Err(PyValueError::new_err(format!(
            "radii must have shape ({n},) or be one number, got {shape:?}"
        )));
    }
    let colors = colors.filter(|c| !c.is_none()).map(|c| array(py, c, "colors")).transpose()?;
    if let Some(c) = &colors {
        if rows_of_three(c, "colors")? != n {
            return Err(PyValueError::new_err(format!(
                "colors must have shape ({n}, 3), got {:?}",
                c.shape()
            )));
        }
    }
    let arrays = SphereArrays {
        centers: centers.floats(),
        radii: radii.floats(),
        colors: colors.as_ref().map(Array::floats),
    };
    // The check and the spheres' copies run on the render's `threads` threads.
    let pool = bareray::render::thread_pool(threads).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    // Checked and read with the GIL held: no Python thread can write an array between its check and its read
    // (the check and the read run in parallel on the pool's threads, which do not touch Python).
    let view = view_of(view)?;
    let desc = pool.install(|| arrays.scene(view)).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // Rendered on the threads that read the arrays.
    let picture: Picture = py.detach(|| api::render_desc(desc, &options, &pool)).map_err(api_error)?;
    to_numpy(py, picture.rendered.image)
}

/// 8-bit codes of a float image of shape (height, width, 3) as bareray writes PNG and PPM: "linear" clamps to
/// [0, 1], multiplies by 255 and rounds (particle files, xyzr and NFF scenes); "srgb" encodes with the sRGB
/// curve (TOML scenes; `Scene.transfer` names a file's).
#[pyfunction]
#[pyo3(signature = (image, transfer="linear"))]
fn to_uint8<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    transfer: &str,
) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    let transfer = match transfer {
        "linear" => Transfer::Linear,
        "srgb" => Transfer::Srgb,
        t => {
            return Err(PyValueError::new_err(format!("transfer must be \"linear\" or \"srgb\", got {t:?}")))
        }
    };
    let numpy = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", numpy.getattr("float32")?)?;
    let a =
        numpy.call_method("ascontiguousarray", (image,), Some(&kwargs))?.cast_into::<PyArrayDyn<f32>>()?;
    let a = a.readonly();
    let [height, width, 3] = a.shape()[..] else {
        return Err(PyValueError::new_err(format!(
            "image must have shape (height, width, 3), got {:?}",
            a.shape()
        )));
    };
    let values = a.as_slice()?;
    let pixels = values.chunks_exact(3).map(|p| bareray::math::Rgb::new(p[0], p[1], p[2])).collect();
    let img = Image { width: width as u32, height: height as u32, pixels };
    let rgb = bareray::output::to_rgb8(&img, transfer);
    PyArray1::from_vec(py, rgb.into_raw()).reshape(vec![height, width, 3])
}

/// A scene file read by `load`: render it, compare its f32 rays with the f64 twin, time it.
#[pyclass(name = "Scene", module = "bareray", frozen)]
struct PyScene {
    inner: FileScene,
}

#[pymethods]
impl PyScene {
    /// Renders the scene, with the file's camera, shading and samples unless given (a new `eye` takes a light
    /// at the file's eye along, as `--eye` does); float32 linear RGB of shape (height, width, 3)
    /// (`to_uint8(image, scene.transfer)` gives the command line's 8-bit image).
    #[pyo3(signature = (*, width=None, height=None, eye=None, look=None, up=None, hfov=None, shade=None,
        spp=None, threads=None, lanes=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: Option<u32>,
        height: Option<u32>,
        eye: Option<&Bound<'py, PyAny>>,
        look: Option<&Bound<'py, PyAny>>,
        up: Option<&Bound<'py, PyAny>>,
        hfov: Option<f64>,
        shade: Option<&str>,
        spp: Option<u32>,
        threads: Option<usize>,
        lanes: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let sixteen = 16usize.into_pyobject(py)?.into_any();
        let options =
            options(width, height, eye, look, up, hfov, shade, spp, threads, lanes.unwrap_or(&sixteen))?;
        let picture = py.detach(|| self.inner.render(&options)).map_err(api_error)?;
        to_numpy(py, picture.rendered.image)
    }

    /// `bareray accuracy`: every pixel centre's f32 primary ray against the f64 twin's (and with `secondary`
    /// the shadow and mirror rays); the report as a dict (the command's `--json` object).
    #[pyo3(signature = (*, secondary=false, width=None, height=None, threads=None, lanes=None))]
    fn accuracy<'py>(
        &self,
        py: Python<'py>,
        secondary: bool,
        width: Option<u32>,
        height: Option<u32>,
        threads: Option<usize>,
        lanes: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let sixteen = 16usize.into_pyobject(py)?.into_any();
        let options =
            options(width, height, None, None, None, None, None, None, threads, lanes.unwrap_or(&sixteen))?;
        let report = py.detach(|| self.inner.accuracy(&options, secondary)).map_err(api_error)?;
        py.import("json")?.call_method1("loads", (report.to_json(),))
    }

    /// Times `reps` renders after one untimed, as `bareray bench` does for one setting (`shade` and `spp` as
    /// `render` takes them): a dict of the build seconds, the min, median and max tracing seconds, rays per
    /// render, Mrays/s at the median, threads and lanes (`"scalar"` for the scalar path). With `by_kind`,
    /// four more runs split the render by ray kind: `by_kind` then holds what `bareray bench --json` writes
    /// in its field of that name (per kind: rays, share of the time, Mrays/s, tests and live rays per test).
    #[pyo3(signature = (*, reps=3, width=None, height=None, shade=None, spp=None, threads=None, lanes=None,
        by_kind=false))]
    #[allow(clippy::too_many_arguments)]
    fn bench<'py>(
        &self,
        py: Python<'py>,
        reps: usize,
        width: Option<u32>,
        height: Option<u32>,
        shade: Option<&str>,
        spp: Option<u32>,
        threads: Option<usize>,
        lanes: Option<&Bound<'py, PyAny>>,
        by_kind: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let sixteen = 16usize.into_pyobject(py)?.into_any();
        let options =
            options(width, height, None, None, None, None, shade, spp, threads, lanes.unwrap_or(&sixteen))?;
        let b = py.detach(|| self.inner.bench(&options, reps, by_kind)).map_err(api_error)?;
        let d = PyDict::new(py);
        d.set_item("build_seconds", b.build_seconds)?;
        d.set_item("min", b.min)?;
        d.set_item("median", b.median)?;
        d.set_item("max", b.max)?;
        d.set_item("rays", b.rays)?;
        d.set_item("mrays_per_s", b.mrays_per_s)?;
        d.set_item("threads", b.threads)?;
        d.set_item(
            "lanes",
            if options.scalar {
                "scalar".into_pyobject(py)?.into_any()
            } else {
                b.lanes.into_pyobject(py)?.into_any()
            },
        )?;
        if let Some(split) = &b.by_kind {
            d.set_item("by_kind", py.import("json")?.call_method1("loads", (split.to_json(),))?)?;
        }
        Ok(d)
    }

    /// The camera's resolution, (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.inner.desc.camera.width, self.inner.desc.camera.height)
    }

    /// Spheres in the scene (a mapped .f32r field's included).
    #[getter]
    fn spheres(&self) -> usize {
        self.inner.spheres()
    }

    /// How 8-bit images of the scene are encoded: "linear" or "srgb" (pass it to `to_uint8`).
    #[getter]
    fn transfer(&self) -> &'static str {
        self.inner.desc.render.transfer.name()
    }

    /// The reader's warnings (unknown elements, say).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }

    fn __repr__(&self) -> String {
        let (w, h) = self.size();
        format!("<bareray.Scene {}: {} spheres, {w}x{h}>", self.inner.path().display(), self.spheres())
    }
}

/// Reads a scene file (TOML, NFF, xyzr, f32r, or a particle file: XYZ, PDB/PQR, GRO, LAMMPS dump, maybe .gz
/// or .bz2), frame `frame` of a particle file with several (frame 0, the first, of any file); a particle
/// file's types sidecar (`FILE.types.toml`) is read when it exists. A file that does not exist raises
/// FileNotFoundError (errno and filename set, as `open` raises it); a reader's error raises ValueError naming
/// the file and the line.
#[pyfunction]
#[pyo3(signature = (path, frame=0))]
fn load(py: Python<'_>, path: PathBuf, frame: usize) -> PyResult<PyScene> {
    // Told apart before reading, as Python code tells a missing file from a bad one by its exception.
    if let Err(e) = std::fs::metadata(&path) {
        if e.kind() == std::io::ErrorKind::NotFound {
            let errno = e.raw_os_error().unwrap_or(2);
            let filename = path.to_string_lossy().into_owned();
            return Err(PyFileNotFoundError::new_err((errno, "No such file or directory", filename)));
        }
    }
    // Frame 0 is the first, which every file has: asked of a scene or sphere list too, it is no error.
    let frame = (frame > 0).then_some(frame);
    let inner = py.detach(|| FileScene::open(&path, frame)).map_err(api_error)?;
    Ok(PyScene { inner })
}

/// bareray: render sphere fields and particle files with a SIMD packet ray tracer, into NumPy arrays.
#[pymodule]
#[pyo3(name = "bareray")]
fn bareray_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(to_uint8, m)?)?;
    m.add_class::<PyScene>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
