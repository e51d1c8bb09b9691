//! Pairwise contact between primitives (paper eq. 1): surface planes with polygon outlines,
//! Align / Dist / Cont, and the directed candidate parent → child edges.

mod planes;
mod relation;

pub use crate::polygon::{convex_intersection, polygon_area};
pub use planes::{SurfacePlane, surface_planes};
pub use relation::{ContactConfig, PairContact, align, contact, contact_ratio, plane_distance, through_contact};
