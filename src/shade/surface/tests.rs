//! The surfaces' lane forms (spheres, kinds, the split of a packet between them) against the lane-by-lane
//! path, bit for bit, the sides of grazing and eye-on-surface hits, and the checker.

use super::*;
use crate::compile::Scene;
use crate::geometry::DeparturePacket;
use crate::kinds::sphere::SphereDesc;

/// The lane-arithmetic sphere surface is the scalar one, bit for bit, in every found lane: point,
/// normal, side and material, for rays from outside and from inside the spheres and from the eye.
#[test]
fn sphere_lanes_give_the_scalar_surface() {
    use crate::geometry::Ray;
    use crate::math::SplitMix64;
    use crate::scene::desc::SceneDesc;
    use wide::f32x8;
    let mut rng = SplitMix64::new(11);
    let mut unit = move || rng.unit() * 2.0 - 1.0;
    let mut desc = SceneDesc::default();
    for _ in 0..300 {
        let center = glam::DVec3::new(unit(), unit(), unit());
        desc.spheres.push(SphereDesc { center, radius: 0.05 + 0.1 * unit().abs(), material: 0 });
    }
    let scene = Scene::compile(&desc).expect("scene");
    let tracer = Tracer::<f32x8>::new(&scene);
    let mut checked = 0;
    for p in 0..400 {
        let rays = RayPacket::<f32x8>::from_fn(|i| {
            let inside = desc.spheres[(p * 8 + i) % 300].center;
            let origin = if p % 2 == 0 { glam::DVec3::new(unit(), unit(), -3.0) } else { inside };
            // Rays are made in the file's space; the compiled scene is in rendering space, whose origin
            // is the eye.
            let origin = if p % 3 == 2 { V3::all(0.0) } else { V3::from(origin - scene.origin) };
            let dir = V3::new(unit() * 0.3, unit() * 0.3, 1.0);
            (Ray::new(origin.to_f32(), dir.to_f32()), f32::INFINITY, (p + i) % 7 != 0)
        });
        let hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
        let found = hit.found() & rays.active;
        let camera = p % 3 == 2;
        let Some(lanes) = tracer.sphere_surface(&rays, &hit, found, camera) else { continue };
        let scalar = tracer.surface_by_lane(&rays, &hit, found, camera);
        let bits = |v: V3<f32x8>, i: usize| [v.x, v.y, v.z].map(|c| c.lane(i).to_bits());
        for i in (0..8).filter(|&i| f32x8::mask_lane(found, i)) {
            assert_eq!(bits(lanes.point, i), bits(scalar.point, i), "packet {p} lane {i}");
            assert_eq!(bits(lanes.normal, i), bits(scalar.normal, i), "packet {p} lane {i}");
            assert_eq!(bits(lanes.base, i), bits(scalar.base, i), "packet {p} lane {i}");
            assert_eq!(f32x8::mask_lane(lanes.inside, i), f32x8::mask_lane(scalar.inside, i));
            let fields = |s: &Surface<f32x8>| {
                [s.ambient, s.diffuse, s.specular, s.shininess, s.reflect, s.transmit, s.ior]
                    .map(|f| f.lane(i).to_bits())
            };
            assert_eq!(fields(&lanes), fields(&scalar), "packet {p} lane {i}");
            checked += 1;
        }
    }
    assert!(checked > 1000, "only {checked} lanes checked");
}

/// Packets mixing spheres of one plain material and a flat polygon floor, or an ellipsoid, get the
/// lane-by-lane surface's bits from the split form, at K = 4, 8 and 16, for camera rays and for rays
/// leaving the hits, with the materials apart in every field and with spheres' own colours; a floor with a
/// checker, or with vertex normals, is never split.
#[test]
fn split_surfaces_give_the_lane_by_lane_bits() {
    use crate::kinds::polygon::PolygonDesc;
    use crate::math::Rgb8;
    use crate::scene::desc::{Checker, SceneDesc};
    use glam::{DAffine3, DVec3};
    let floor = |normals: Option<Vec<DVec3>>| PolygonDesc {
        vertices: [(-4.0, -4.0), (4.0, -4.0), (4.0, 4.0), (-4.0, 4.0)]
            .map(|(x, z)| DVec3::new(x, -1.0, z))
            .to_vec(),
        normals,
        material: 1,
    };
    let mut desc = SceneDesc::default();
    let glass = Material {
        color: Rgb::new(0.3, 0.6, 0.9),
        ambient: 0.15,
        diffuse: 0.7,
        specular: 0.3,
        shininess: 20.0,
        reflect: 0.25,
        transmit: 0.5,
        ior: 1.33,
        fresnel: true,
        checker: None,
    };
    let matte =
        Material { color: Rgb::new(0.9, 0.7, 0.5), ambient: 0.05, shininess: 64.0, ..Material::default() };
    desc.materials.extend([glass, matte]);
    let mut rng = crate::math::SplitMix64::new(21);
    for _ in 0..60 {
        let center = DVec3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 0.8 - 0.6, rng.unit() * 4.0 + 1.0);
        desc.spheres.push(SphereDesc { center, radius: 0.05 + 0.2 * rng.unit(), material: 0 });
    }
    desc.kinds.polygons.push(floor(None));
    let mut colored = desc.clone();
    colored.sphere_colors = (0..60u8).map(|i| Rgb8([i * 4, 255 - i * 4, 128])).collect();
    let mut ellipsoid = desc.clone();
    ellipsoid.kinds.polygons.clear();
    let stretch = DAffine3::from_scale_rotation_translation(
        DVec3::new(3.0, 0.6, 2.0),
        glam::DQuat::from_rotation_y(0.4),
        DVec3::new(0.0, -1.2, 3.5),
    );
    ellipsoid.kinds.push_shape(crate::geometry::ShapeKind::Sphere, stretch);
    ellipsoid.kinds.ellipsoids[0].material = 1;
    for (name, d) in [("floor", &desc), ("own colours", &colored), ("ellipsoid", &ellipsoid)] {
        let scene = Scene::compile(d).expect("scene");
        assert!(scene.split_surfaces, "{name}");
        let compared = check_split::<wide::f32x4>(&scene)
            + check_split::<wide::f32x8>(&scene)
            + check_split::<wide::f32x16>(&scene);
        assert!(compared > 500, "{name}: only {compared} lanes compared");
    }
    let mut checked = desc.clone();
    checked.materials[1].checker = Some(Checker { color: Rgb::new(0.1, 0.2, 0.3), size: 0.5 });
    assert!(!Scene::compile(&checked).expect("scene").split_surfaces);
    let mut smooth = desc.clone();
    smooth.kinds.polygons[0] = floor(Some(vec![DVec3::Y; 4]));
    let smooth = Scene::compile(&smooth).expect("scene");
    assert!(!smooth.split_surfaces);
    assert_eq!(check_split::<wide::f32x8>(&smooth), 0, "a floor with vertex normals was split");
}

/// Lanes of split surfaces compared with [`Tracer::surface_by_lane`] over packets aimed at the scene's
/// spheres and floor, from the eye and from the spheres' hits.
fn check_split<F: Lanes>(scene: &Scene) -> usize {
    use crate::geometry::Ray;
    let tracer = Tracer::<F>::new(scene);
    let mut rng = crate::math::SplitMix64::new(22);
    let mut compared = 0;
    for p in 0..1500 {
        let camera = p % 2 == 0;
        let rays = RayPacket::<F>::from_fn(|_| {
            let dir = V3::new(rng.unit() * 1.6 - 0.8, rng.unit() * 0.9 - 0.7, 1.0).to_f32();
            (Ray::new(V3::all(0.0), dir), f32::INFINITY, rng.unit() < 0.9)
        });
        let mut hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
        let mut rays = rays;
        if !camera {
            // Mirror rays from the camera rays' hits: they leave spheres and the floor.
            let found = hit.found() & rays.active;
            let s = tracer.surface_by_lane(&rays, &hit, found, true);
            let d = rays.ray.dir - s.normal * (F::splat_f32(2.0) * s.normal.dot(rays.ray.dir));
            rays = RayPacket::new(s.point, d, F::splat_f32(f32::INFINITY), found);
            let from = DeparturePacket { prim: hit.prim, inward: s.inside };
            hit = scene.geometry.intersect_k(&rays, &from);
        }
        let found = hit.found() & rays.active;
        let Some(lanes) = tracer.split_surface(&rays, &hit, found, camera) else { continue };
        let scalar = tracer.surface_by_lane(&rays, &hit, found, camera);
        let bits = |v: V3<F>, i: usize| [v.x, v.y, v.z].map(|c| c.lane(i).to_bits());
        for i in (0..F::K).filter(|&i| F::mask_lane(found, i)) {
            assert_eq!(bits(lanes.point, i), bits(scalar.point, i), "packet {p} lane {i}");
            assert_eq!(bits(lanes.normal, i), bits(scalar.normal, i), "packet {p} lane {i}");
            assert_eq!(bits(lanes.base, i), bits(scalar.base, i), "packet {p} lane {i}");
            assert_eq!(F::mask_lane(lanes.inside, i), F::mask_lane(scalar.inside, i));
            assert_eq!(F::mask_lane(lanes.fresnel, i), F::mask_lane(scalar.fresnel, i));
            let fields = |s: &Surface<F>| {
                [s.ambient, s.diffuse, s.specular, s.shininess, s.reflect, s.transmit, s.ior]
                    .map(|f| f.lane(i).to_bits())
            };
            assert_eq!(fields(&lanes), fields(&scalar), "packet {p} lane {i}");
            compared += 1;
        }
    }
    compared
}

/// Camera rays grazing a unit sphere, and an ellipsoid, 1e6 away: the rounded hit point often puts the
/// outward normal on the ray's side (`n·d > 0`), yet the eye is outside, so no hit is taken as from
/// inside.
#[test]
fn grazing_camera_hits_on_a_distant_sphere_are_outside() {
    use crate::geometry::ShapeKind;
    use crate::math::SplitMix64;
    use crate::scene::desc::SceneDesc;
    use wide::f32x8;
    let centre = glam::DVec3::new(0.0, 0.0, 1e6);
    // Semi-axes: 1 and 1 for the sphere, 1 and 1.5 across the view for the ellipsoid.
    for stretch in [1.0, 1.5] {
        let mut desc = SceneDesc::default();
        if stretch == 1.0 {
            desc.spheres.push(SphereDesc { center: centre, radius: 1.0, material: 0 });
        } else {
            let world_from_object = glam::DAffine3::from_scale_rotation_translation(
                glam::DVec3::new(1.0, stretch, 1.0),
                glam::DQuat::IDENTITY,
                centre,
            );
            desc.kinds.push_shape(ShapeKind::Sphere, world_from_object);
        }
        // A plane behind the eye keeps the eye's frame (alone, the far shape would be compiled around its
        // own centre, `crate::compile::RenderingFrame`): camera rays from the eye are what this checks.
        let behind = glam::DAffine3::from_translation(glam::DVec3::new(0.0, 0.0, -10.0));
        desc.kinds.push_shape(ShapeKind::Plane, behind);
        let scene = Scene::compile(&desc).expect("scene");
        assert_eq!(scene.camera_f64.start, 0.0, "the eye's frame");
        let tracer = Tracer::<f32x8>::new(&scene);
        let mut rng = SplitMix64::new(5);
        let (mut found_lanes, mut normal_wrong_side) = (0, 0);
        for _ in 0..500 {
            let rays = RayPacket::<f32x8>::from_fn(|_| {
                // Aimed within a relative 1e-3 of the rim, all around it.
                let a = rng.unit() * std::f64::consts::TAU;
                let rim = 1.0 - 1e-3 * rng.unit();
                let dir = V3::new(rim * a.cos(), stretch * rim * a.sin(), 1e6 - scene.origin.z).to_f32();
                (crate::geometry::Ray::new(V3::all(0.0), dir), f32::INFINITY, true)
            });
            let hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
            let found = hit.found() & rays.active;
            let outward_dot = |s: &Surface<f32x8>, i: usize| {
                let d = |v: wide::f32x8| v.lane(i);
                // The flipped normal points back out where `inside` is set.
                let sign = if f32x8::mask_lane(s.inside, i) { -1.0 } else { 1.0 };
                sign * (d(s.normal.x) * d(rays.ray.dir.x)
                    + d(s.normal.y) * d(rays.ray.dir.y)
                    + d(s.normal.z) * d(rays.ray.dir.z))
            };
            let lanes = tracer.sphere_surface(&rays, &hit, found, true);
            assert_eq!(lanes.is_some(), stretch == 1.0 && found.any());
            for s in lanes.into_iter().chain([tracer.surface_by_lane(&rays, &hit, found, true)]) {
                for i in (0..8).filter(|&i| f32x8::mask_lane(found, i)) {
                    assert!(!f32x8::mask_lane(s.inside, i), "a camera hit taken as from inside");
                    found_lanes += 1;
                    normal_wrong_side += usize::from(outward_dot(&s, i) > 0.0);
                }
            }
        }
        assert!(found_lanes > 2000, "stretch {stretch}: {found_lanes} hits");
        assert!(normal_wrong_side > 0, "stretch {stretch}: no hit had its normal on the ray's side");
    }
}

/// The eye exactly on a sphere's surface (eye term 0): camera rays heading into the sphere hit it from
/// outside at t = 0, rays heading away hit it from inside (its exit, also at t = 0); the side comes from
/// the normal there, not from the eye term's sign.
#[test]
fn eye_on_a_sphere_takes_the_side_from_the_normal() {
    use crate::scene::desc::SceneDesc;
    use wide::f32x8;
    let mut desc = SceneDesc::default();
    // The default eye is (0, 0, −5): on this sphere, exactly.
    desc.spheres.push(SphereDesc { center: glam::DVec3::ZERO, radius: 5.0, material: 0 });
    let scene = Scene::compile(&desc).expect("scene");
    assert_eq!(scene.geometry.spheres.c_eye[0], 0.0);
    let tracer = Tracer::<f32x8>::new(&scene);
    let rays = RayPacket::<f32x8>::from_fn(|i| {
        let z = if i % 2 == 0 { 1.0 } else { -1.0 };
        let dir = V3::new(0.1 * i as f32 - 0.35, 0.05, z);
        (crate::geometry::Ray::new(V3::all(0.0), dir), f32::INFINITY, true)
    });
    let hit = scene.geometry.intersect_k(&rays, &DeparturePacket::camera());
    let found = hit.found() & rays.active;
    assert!(found.all());
    for s in [
        tracer.sphere_surface(&rays, &hit, found, true).expect("one material"),
        tracer.surface_by_lane(&rays, &hit, found, true),
    ] {
        for i in 0..8 {
            assert_eq!(f32x8::mask_lane(s.inside, i), i % 2 == 1, "lane {i}");
        }
    }
}

#[test]
fn checker_alternates_across_cells_and_zero() {
    let m = Material {
        checker: Some(crate::scene::desc::Checker { color: Rgb::all(0.0), size: 1.0 }),
        ..Material::default()
    };
    assert_eq!(surface_color(&m, m.color, V3::new(0.5, 0.5, 0.0)), m.color);
    assert_eq!(surface_color(&m, m.color, V3::new(1.5, 0.5, 0.0)), Rgb::all(0.0));
    assert_eq!(surface_color(&m, m.color, V3::new(-0.5, 0.5, 0.0)), Rgb::all(0.0));
}
