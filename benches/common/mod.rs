//! Helpers shared by the benchmarks.

use bareray::io::generate::FieldParams;
use bareray::kinds::sphere::SphereDesc;
use bareray::scene::desc::SceneDesc;
use glam::DVec3;

/// The contract field of `count` spheres, from bareray's own generator, as a description with the default
/// camera and material.
pub fn field_desc(count: u64) -> SceneDesc {
    let params = FieldParams { count, ..FieldParams::default() };
    let mut desc = SceneDesc::default();
    for [x, y, z, r] in params.spheres().expect("valid field") {
        let center = DVec3::new(x.into(), y.into(), z.into());
        desc.spheres.push(SphereDesc { center, radius: r.into(), material: 0 });
    }
    desc
}
