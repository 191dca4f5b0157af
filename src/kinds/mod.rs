//! The primitive kinds: each registered kind lives in one folder that holds everything about it (its
//! description and TOML form, its f32 store, its kernel generic over lanes, bounds, surface, departure rule
//! and its f64 form for the accuracy twin), behind the `Kind` trait. One list, `registry!`, names the
//! kinds; the scene description ([`KindDescs`]), the TOML reader, compile, the queries over the geometry
//! (`KindStores`) and the twin (`KindTwins`) are written once over it.
//!
//! Adding a kind: a folder here with a type implementing `Kind`, and its name in `registry!`. Its
//! primitive ids follow the spheres' (and the particle tree's) in the list's order.
//!
//! Files: `kind.rs` (the `Kind` trait), `items.rs` (one kind's compiled items and tree), `registered.rs` (the
//! structures and loops generated over the list); one folder per kind. Spheres have their folder
//! ([`sphere`]) but no place in the list: the scene's geometry queries them on paths of its own.
//!
//! ```
//! use bareray::kinds::KindDescs;
//! // Every registered kind has a list of descriptions, empty by default.
//! let descs = KindDescs::default();
//! assert_eq!(descs.len(), 0);
//! assert!(descs.is_empty());
//! ```

pub(crate) mod cone;
pub(crate) mod ellipsoid;
mod items;
mod kind;
pub(crate) mod placed;
pub(crate) mod placement;
pub(crate) mod plane;
pub(crate) mod polygon;
mod registered;
pub mod sphere;
pub(crate) mod torus;

use items::Ids;
pub(crate) use items::{KindItems, VisitItems};
use kind::nudge;
pub(crate) use kind::{Kind, KindError, Stray};
pub use registered::KindDescs;
pub(crate) use registered::{KindStores, KindTwins};
pub(crate) use registered::{COUNT, NAMES};

/// The registry: every kind, as `field: type`, the field naming its TOML array of tables and its list in
/// the description. Called with the name of a macro, it calls that macro with the list; the structures of
/// `registered.rs` and the TOML reader are generated that way, so this list is the only place a kind is
/// registered.
macro_rules! registry {
    ($then:ident) => {
        $then! {
            polygons: $crate::kinds::polygon::Polygon,
            ellipsoids: $crate::kinds::ellipsoid::Ellipsoid,
            planes: $crate::kinds::plane::Plane,
            cones: $crate::kinds::cone::OpenCone,
            tori: $crate::kinds::torus::Torus,
        }
    };
}
pub(crate) use registry;
