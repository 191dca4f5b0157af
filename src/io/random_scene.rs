//! Random valid TOML scenes from a seed, for the random-scene campaign (`tests/library/random_scenes.rs`): the same
//! seed always gives the same text.
//!
//! A scene is a cluster of 3 to 14 primitives of every kind the TOML format has: spheres over three decades
//! of radius (some touching a neighbour, some nested in another), ellipsoids (`[[ellipsoids]]`, and
//! `[[spheres]]` with a stretching transform), planes, open cones and cylinders, convex polygons (some with
//! vertex normals) and tori (some given by a transform); matte, mirror, checkered and glass materials (ior 0.75 to 2.4, some with Fresnel weights);
//! one to three point lights. The whole scene is drawn at a random scale (1e-3 to 1e3) and moved by a random
//! offset (up to 1e6 from the origin). The camera looks at the cluster from outside (near or up to 2000
//! cluster sizes away), from among the primitives, or from inside one (a sphere, an ellipsoid, a torus's
//! tube, a cone), or from inside a large sphere around the whole cluster. Numbers are written in Rust's
//! shortest round-trip form, so the file is the scene exactly.

use std::fmt::Write as _;

use glam::DVec3;

use crate::math::SplitMix64;

/// The materials every random scene defines (its `[materials.NAME]` tables), by name.
pub(crate) const MATERIALS: [&str; 8] =
    ["matte", "mirror", "shiny", "checker", "glass", "water", "dense", "thin"];

/// The TOML text of random scene `seed` at `width` × `height` pixels.
pub fn random_scene_toml(seed: u64, width: u32, height: u32) -> String {
    let mut g = Gen { rng: SplitMix64::new(seed), out: String::new(), holds_eye: false };
    g.scene(seed, width, height);
    g.out
}

/// Where the camera is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum View {
    /// Outside the cluster, 1.5 to 50 cluster radii from its centre.
    Outside,
    /// 50 to 2000 cluster radii away, or 50 to 10⁶ for a scene without planes (from 64 bounding radii on,
    /// such a scene gets the far-scene frame, `crate::compile::RenderingFrame`; with a plane it keeps the
    /// eye's, whose f32 steps far away the campaign does not hold to its bounds).
    Far,
    /// Among the primitives.
    Among,
    /// Inside the first primitive that has an inside.
    InsideOne,
    /// Inside a sphere of 5 to 50 cluster radii around the cluster.
    InsideAll,
}

/// A primitive the eye can be put inside: a point inside it.
type Inside = Option<DVec3>;

/// The primitives' kinds, each as often as it is listed.
const PRIMITIVES: [&str; 13] = [
    "sphere",
    "sphere",
    "sphere",
    "touching",
    "nested",
    "ellipsoid",
    "plane",
    "cone",
    "cone",
    "polygon",
    "polygon",
    "torus",
    "torus",
];

/// The cluster being written.
struct Cluster {
    centre: DVec3,
    radius: f64,
    /// Where the eye goes if a primitive holds it.
    inside: Inside,
    /// The spheres so far (centre, radius), for touching and nested ones.
    spheres: Vec<(DVec3, f64)>,
    /// Planes so far (at most two).
    planes: u32,
}

struct Gen {
    rng: SplitMix64,
    out: String,
    /// The next primitive with an inside holds the eye: it gets a material the eye sees out through or
    /// reflects in (glass or mirror), and [`Gen::primitives`] returns a point inside it.
    holds_eye: bool,
}

/// A TOML float: Rust's shortest round-trip form (always with a `.` or an exponent).
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn vec3(v: DVec3) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

impl Gen {
    /// Uniform in [0, 1) with 53 random bits.
    fn unit(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    /// Log-uniform in [lo, hi).
    fn log(&mut self, lo: f64, hi: f64) -> f64 {
        lo * (hi / lo).powf(self.unit())
    }
    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[(self.unit() * xs.len() as f64) as usize % xs.len()]
    }
    /// A uniform unit vector.
    fn dir(&mut self) -> DVec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f64::consts::TAU);
        let s = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
    /// A point in the cube of half-side `h` around `c`.
    fn around(&mut self, c: DVec3, h: f64) -> DVec3 {
        c + DVec3::new(self.range(-h, h), self.range(-h, h), self.range(-h, h))
    }
    fn material(&mut self) -> &'static str {
        if self.holds_eye {
            return self.pick(&["glass", "water", "dense", "thin", "mirror"]);
        }
        // Matte and mirror surfaces most often, glass in a quarter of the primitives.
        self.pick(&[
            "matte", "matte", "mirror", "mirror", "shiny", "checker", "glass", "glass", "water", "dense",
            "thin",
        ])
    }
    fn line(&mut self, s: impl AsRef<str>) {
        self.out.push_str(s.as_ref());
        self.out.push('\n');
    }

    fn scene(&mut self, seed: u64, width: u32, height: u32) {
        let scale = self.log(1e-3, 1e3);
        let offset =
            if self.chance(0.5) { self.dir() * self.log(1.0, 1e6) } else { self.around(DVec3::ZERO, 4.0) };
        let centre = offset;
        let radius = scale * self.range(1.0, 4.0);
        let view = self.pick(&[
            View::Outside,
            View::Outside,
            View::Outside,
            View::Far,
            View::Among,
            View::Among,
            View::InsideOne,
            View::InsideOne,
            View::InsideAll,
        ]);
        self.line(format!("# Random scene {seed}: scale {scale:.3e}, {view:?}, centre {}", vec3(centre)));
        let mut body = Gen { rng: self.rng.clone(), out: String::new(), holds_eye: false };
        let (inside, planes) =
            body.primitives(centre, scale, radius, view == View::InsideAll, view == View::InsideOne);
        self.rng = body.rng.clone();
        let (eye, look) = self.eye(view, centre, radius, inside, planes);
        self.camera(eye, look, view, radius, width, height);
        self.render(scale);
        self.lights(eye, centre, radius);
        self.out.push_str(&body.out);
    }

    fn camera(&mut self, eye: DVec3, look: DVec3, view: View, radius: f64, width: u32, height: u32) {
        let forward = (look - eye).normalize();
        let mut up = self.dir();
        while up.cross(forward).length() < 0.2 {
            up = self.dir();
        }
        let hfov = match view {
            View::Outside | View::Far => {
                (2.0 * (1.3 * radius / (look - eye).length()).atan()).to_degrees().clamp(1e-3, 120.0)
            }
            _ => self.range(30.0, 110.0),
        };
        self.line("\n[camera]");
        self.line(format!("eye = {}", vec3(eye)));
        if self.chance(0.5) {
            self.line(format!("look_at = {}", vec3(look)));
        } else {
            self.line(format!("direction = {}", vec3(forward)));
        }
        self.line(format!("up = {}", vec3(up)));
        self.line(format!("hfov = {}", num(hfov)));
        self.line(format!("width = {width}\nheight = {height}"));
    }

    /// Where the eye is and a point it looks at.
    fn eye(
        &mut self,
        view: View,
        centre: DVec3,
        radius: f64,
        inside: Inside,
        planes: bool,
    ) -> (DVec3, DVec3) {
        let aim = |g: &mut Gen| g.around(centre, 0.3 * radius);
        match (view, inside) {
            (View::Outside, _) => (centre + self.dir() * radius * self.log(1.5, 50.0), aim(self)),
            (View::Far, _) => {
                let most = if planes { 2000.0 } else { 1e6 };
                (centre + self.dir() * radius * self.log(50.0, most), aim(self))
            }
            (View::InsideOne, Some(p)) => (p, if self.chance(0.5) { aim(self) } else { p + self.dir() }),
            (View::InsideAll, _) | (View::Among, _) | (View::InsideOne, None) => {
                let eye = self.around(centre, radius);
                (eye, if self.chance(0.5) { aim(self) } else { eye + self.dir() })
            }
        }
    }

    fn render(&mut self, scale: f64) {
        self.line("\n[render]");
        let depth = self.pick(&[1, 2, 2, 3, 4]);
        self.line(format!("max_depth = {depth}"));
        self.line("background = [0.3, 0.38, 0.5]");
        let materials = [
            ("matte", "color = [0.8, 0.7, 0.6]\ndiffuse = 0.8"),
            ("mirror", "color = [0.9, 0.9, 0.9]\ndiffuse = 0.2\nreflect = 0.8"),
            (
                "shiny",
                "color = [0.3, 0.5, 0.9]\ndiffuse = 0.6\nspecular = 0.5\nshininess = 60.0\nreflect = 0.3",
            ),
            ("checker", ""),
            (
                "glass",
                "color = [1.0, 1.0, 1.0]\ndiffuse = 0.0\nspecular = 0.8\nshininess = 200.0\nreflect = 0.1\n\
                 transmit = 0.9\nior = 1.5",
            ),
            ("water", "color = [0.9, 0.95, 1.0]\ndiffuse = 0.05\nreflect = 0.05\ntransmit = 0.9\nior = 1.33"),
            ("dense", "color = [1.0, 1.0, 1.0]\ndiffuse = 0.0\ntransmit = 0.85\nior = 2.4\nfresnel = true"),
            ("thin", "color = [1.0, 1.0, 1.0]\ndiffuse = 0.1\ntransmit = 0.9\nior = 0.75"),
        ];
        debug_assert!(materials.iter().map(|m| m.0).eq(MATERIALS));
        for (name, body) in materials {
            self.line(format!("\n[materials.{name}]"));
            if name == "checker" {
                let size = scale * self.log(0.05, 2.0);
                self.line(format!(
                    "color = [0.8, 0.8, 0.8]\nchecker = {{ color = [0.2, 0.2, 0.25], size = {} }}",
                    num(size)
                ));
            } else {
                self.line(body);
            }
        }
    }

    fn lights(&mut self, eye: DVec3, centre: DVec3, radius: f64) {
        let n = self.pick(&[1, 1, 2, 3]);
        for k in 0..n {
            let position = if k == 1 && self.chance(0.3) {
                // A headlight: at the eye when the direction drawn points up (camera hits then send it no
                // shadow rays), else just off it.
                let off = self.dir();
                match off.z > 0.0 {
                    true => eye,
                    false => eye + off * radius * 1e-3,
                }
            } else {
                centre + self.dir() * radius * self.log(0.5, 5.0)
            };
            self.line(format!("\n[[lights]]\nposition = {}", vec3(position)));
        }
    }

    /// The primitives, written to `self.out`, around `centre` within `radius`; with `enclose`, first a sphere
    /// around them all. With `eye_inside`, a primitive chosen at random (or the next one with an inside)
    /// holds the eye: the point inside it is returned, and whether there is a plane.
    fn primitives(
        &mut self,
        centre: DVec3,
        scale: f64,
        radius: f64,
        enclose: bool,
        eye_inside: bool,
    ) -> (Inside, bool) {
        let mut cluster = Cluster { centre, radius, inside: None, spheres: Vec::new(), planes: 0 };
        if enclose {
            let r = radius * self.log(5.0, 50.0);
            let c = self.around(centre, 0.5 * radius);
            self.sphere(c, r);
        }
        let n = 3 + (self.unit() * 12.0) as usize;
        let holder = (self.unit() * n as f64) as usize;
        for i in 0..n {
            self.holds_eye |= eye_inside && i == holder;
            let kind = self.pick(&PRIMITIVES);
            let c = self.around(centre, radius);
            let size = scale * self.log(0.1, 1.5);
            match kind {
                "sphere" => self.free_sphere(&mut cluster, c, scale),
                "touching" | "nested" if !cluster.spheres.is_empty() => {
                    self.sphere_at_another(&mut cluster, kind == "nested")
                }
                "ellipsoid" => self.ellipsoid(&mut cluster, c, size),
                "plane" if cluster.planes < 2 => self.plane(&mut cluster),
                "cone" => self.cone(&mut cluster, c, size),
                "polygon" => self.polygon(c, size),
                "torus" => self.torus(&mut cluster, c, size),
                _ => {
                    self.sphere(c, size);
                    cluster.spheres.push((c, size));
                }
            }
        }
        (cluster.inside, cluster.planes > 0)
    }

    /// Records `p` as the eye's place if this primitive holds the eye.
    fn hold(&mut self, cluster: &mut Cluster, p: DVec3) {
        if self.holds_eye {
            cluster.inside = Some(p);
            self.holds_eye = false;
        }
    }

    /// A sphere at `c` of radius from 1e-3 to 3 times `scale`.
    fn free_sphere(&mut self, cluster: &mut Cluster, c: DVec3, scale: f64) {
        let r = scale * self.pick(&[1e-3, 0.01, 0.1, 0.3, 1.0, 3.0]) * self.range(0.5, 1.5);
        self.sphere(c, r);
        let p = c + self.dir() * r * 0.5;
        self.hold(cluster, p);
        cluster.spheres.push((c, r));
    }

    /// A sphere touching one of the spheres so far from outside, or (`nested`) inside it, touching it from
    /// within or with a gap.
    fn sphere_at_another(&mut self, cluster: &mut Cluster, nested: bool) {
        let (c0, r0) = self.pick(&cluster.spheres);
        let d = self.dir();
        let (c, r) = if nested {
            let r = r0 * self.range(0.1, 0.8);
            let gap = if self.chance(0.5) { 0.0 } else { self.range(0.0, r0 - r) };
            (c0 + d * (r0 - r - gap), r)
        } else {
            let r = r0 * self.log(0.1, 2.0);
            (c0 + d * (r0 + r), r)
        };
        self.sphere(c, r);
        self.hold(cluster, c);
        cluster.spheres.push((c, r));
    }

    /// A unit sphere scaled by `size`, stretched on each axis by 0.2 to 2, and turned: half of them (by
    /// the angle, so that the choice draws nothing) as an `[[ellipsoids]]` table with its radii, the rest as
    /// a `[[spheres]]` table with a transform.
    fn ellipsoid(&mut self, cluster: &mut Cluster, c: DVec3, size: f64) {
        let s = [self.log(0.2, 2.0), self.log(0.2, 2.0), self.log(0.2, 2.0)];
        let (axis, deg) = (self.dir(), self.range(0.0, 180.0));
        let material = self.material();
        let rotate = format!("{{ rotate = {{ axis = {}, degrees = {} }} }}", vec3(axis), num(deg));
        let table = if deg < 90.0 {
            let radii = vec3(DVec3::from(s) * size);
            format!("[[ellipsoids]]\ncenter = {}\nradii = {radii}\ntransform = [{rotate}]", vec3(c))
        } else {
            let transform = format!("[{{ scale = {} }}, {rotate}]", vec3(DVec3::from(s)));
            format!("[[spheres]]\ncenter = {}\nradius = {}\ntransform = {transform}", vec3(c), num(size))
        };
        self.line(format!("\n{table}\nmaterial = \"{material}\""));
        self.hold(cluster, c);
    }

    /// A plane one to two cluster radii from the centre, facing it.
    fn plane(&mut self, cluster: &mut Cluster) {
        cluster.planes += 1;
        let normal = self.dir();
        let point = cluster.centre - normal * cluster.radius * self.range(1.0, 2.0);
        let material = self.material();
        self.line(format!(
            "\n[[planes]]\npoint = {}\nnormal = {}\nmaterial = \"{material}\"",
            vec3(point),
            vec3(normal)
        ));
    }

    /// An open cone, cylinder or pointed cone around `c`, 0.5 to 10 times `size` long.
    fn cone(&mut self, cluster: &mut Cluster, c: DVec3, size: f64) {
        let axis = self.dir() * size * self.log(0.5, 10.0);
        let base_r = size * self.log(0.05, 1.0);
        let apex_r = match self.pick(&[0, 1, 2]) {
            0 => 0.0,
            1 => base_r,
            _ => size * self.log(0.05, 1.0),
        };
        let material = self.material();
        self.line(format!(
            "\n[[cones]]\nbase = {}\nbase_radius = {}\napex = {}\napex_radius = {}\n\
             material = \"{material}\"",
            vec3(c - axis * 0.5),
            num(base_r),
            vec3(c + axis * 0.5),
            num(apex_r)
        ));
        let p = c + axis * 0.25 * self.range(-1.0, 1.0);
        self.hold(cluster, p);
    }

    /// A ring torus of major radius `size` (minor 0.05 to 0.7 of it), given by its axis or by a transform.
    fn torus(&mut self, cluster: &mut Cluster, c: DVec3, size: f64) {
        let major = size;
        let minor = major * self.log(0.05, 0.7);
        let axis = self.dir();
        let material = self.material();
        let mut text = format!(
            "\n[[tori]]\ncenter = {}\nmajor_radius = {}\nminor_radius = {}\nmaterial = \"{material}\"",
            vec3(c),
            num(major),
            num(minor)
        );
        if self.chance(0.3) {
            let k = self.log(0.5, 2.0);
            let deg = self.range(0.0, 180.0);
            let _ = write!(
                text,
                "\ntransform = [{{ rotate = {{ axis = {}, degrees = {} }} }}, {{ scale = {} }}]",
                vec3(axis),
                num(deg),
                num(k)
            );
        } else {
            let _ = write!(text, "\naxis = {}", vec3(axis));
            // A point on the tube's centre circle.
            let side = axis.any_orthonormal_vector();
            self.hold(cluster, c + side * major);
        }
        self.line(text);
    }

    fn sphere(&mut self, c: DVec3, r: f64) {
        let m = self.material();
        self.line(format!("\n[[spheres]]\ncenter = {}\nradius = {}\nmaterial = \"{m}\"", vec3(c), num(r)));
    }

    /// A convex polygon of 3 to 7 vertices on an ellipse (sorted angles), in a random plane through `c`.
    fn polygon(&mut self, c: DVec3, size: f64) {
        let normal = self.dir();
        let u = normal.any_orthonormal_vector();
        let v = normal.cross(u);
        let (a, b) = (size * self.log(0.3, 3.0), size * self.log(0.3, 3.0));
        let n = 3 + (self.unit() * 5.0) as usize;
        let mut angles: Vec<f64> =
            (0..n).map(|k| (k as f64 + self.range(0.1, 0.9)) / n as f64 * std::f64::consts::TAU).collect();
        angles.sort_by(f64::total_cmp);
        let vertices: Vec<DVec3> = angles.iter().map(|t| c + u * a * t.cos() + v * b * t.sin()).collect();
        let list = |vs: &[DVec3]| vs.iter().map(|&p| vec3(p)).collect::<Vec<_>>().join(", ");
        let material = self.material();
        self.line(format!("\n[[polygons]]\nvertices = [{}]\nmaterial = \"{material}\"", list(&vertices)));
        if self.chance(0.3) {
            let normals: Vec<DVec3> =
                vertices.iter().map(|_| (normal + self.dir() * 0.3).normalize()).collect();
            self.line(format!("normals = [{}]", list(&normals)));
        }
    }
}
