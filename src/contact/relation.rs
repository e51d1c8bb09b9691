//! Align, Dist and Cont between surface planes (paper eq. 1, 2) and the weight of a candidate
//! parent → child edge.
//!
//! The paper weighs an edge by `max Cont` over the plane pairs that pass the Align/Dist tests. Two
//! refinements, both configurable and both off when their knobs are 0:
//! - `distance_penalty`: the weight drops linearly with the plane distance (to `1 − penalty` at
//!   θd), so a handle touching a drawer beats the body 2 cm behind the drawer, which also passes
//!   the Dist test.
//! - `face_significance`: the ratio is scaled by `(A(U_c) / A_max(c))^γ`, where `A_max(c)` is the
//!   child's largest face: contact through a thin edge face (two stacked drawers) is incidental
//!   adjacency, contact through a main face (a drawer front on a body) is attachment.

use serde::{Deserialize, Serialize};

use super::planes::{SurfacePlane, surface_planes};
use crate::math::{Vec2, Vec3};
use crate::polygon::{convex_intersection, polygon_area};
use crate::primitive::Primitive;

/// Thresholds of the contact test (θa, θd, θc) and the edge-weight refinements.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactConfig {
    /// θa: minimum |cos| between plane normals.
    pub align_min: f32,
    /// θd: maximum plane distance, metres.
    pub dist_max_m: f32,
    /// θc: minimum contact ratio.
    pub contact_min: f32,
    /// Weight lost at the distance limit (0 = the paper's weight).
    pub distance_penalty: f32,
    /// γ of the face-significance factor (0 = the paper's weight).
    pub face_significance: f32,
}

impl Default for ContactConfig {
    fn default() -> Self {
        Self { align_min: 0.97, dist_max_m: 0.03, contact_min: 0.05, distance_penalty: 0.5, face_significance: 0.5 }
    }
}

/// The best plane pair between a parent and a child.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairContact {
    /// Edge weight (see the module docs).
    pub weight: f32,
    /// Cont of the chosen pair.
    pub ratio: f32,
    /// Dist of the chosen pair, metres.
    pub distance_m: f32,
    /// Index into `surface_planes(parent)` / `surface_planes(child)`.
    pub parent_face: usize,
    pub child_face: usize,
}

/// `Align(π_p, π_c) = |n_pᵀ n_c|`.
#[must_use]
pub fn align(p: &SurfacePlane, c: &SurfacePlane) -> f32 {
    p.normal.dot(c.normal).abs()
}

/// `Dist(π_p, π_c)`: the absolute mean, over the child's outline `U_c`, of `n_pᵀu + d_p`.
#[must_use]
pub fn plane_distance(p: &SurfacePlane, c: &SurfacePlane) -> f32 {
    let n = c.outline.len().max(1) as f32;
    (c.outline.iter().map(|u| p.signed_distance(*u)).sum::<f32>() / n).abs()
}

/// `Cont(U_p, U_c) = A(U_p ∩ proj_p(U_c)) / A(U_c)`.
#[must_use]
pub fn contact_ratio(p: &SurfacePlane, c: &SurfacePlane) -> f32 {
    if c.area <= 0.0 || p.outline.len() < 3 {
        return 0.0;
    }
    let origin = p.outline[0];
    let u = (p.outline[1] - origin).normalize_or_zero();
    let v = p.normal.cross(u);
    // Projection onto π_p (eq. 2) followed by in-plane coordinates; the normal component drops out.
    let to2 = |x: Vec3| Vec2::new((x - origin).dot(u), (x - origin).dot(v));
    let pp: Vec<Vec2> = p.outline.iter().map(|x| to2(*x)).collect();
    let cc: Vec<Vec2> = c.outline.iter().map(|x| to2(*x)).collect();
    let overlap = polygon_area(&convex_intersection(&pp, &cc));
    (overlap / c.area).min(1.0)
}

/// The best contact from `parent` to `child`, if any plane pair passes all three tests.
#[must_use]
pub fn contact(parent: &Primitive, child: &Primitive, cfg: &ContactConfig) -> Option<PairContact> {
    // Cheap rejection: bounding boxes farther apart than θd cannot touch.
    let (plo, phi) = parent.aabb();
    let (clo, chi) = child.aabb();
    let gap = (clo - phi).max(plo - chi).max(Vec3::ZERO);
    if gap.length() > cfg.dist_max_m {
        return None;
    }
    let pp = surface_planes(parent);
    let cp = surface_planes(child);
    contact_between_planes(&pp, &cp, cfg)
}

/// [`contact`] on precomputed planes.
#[must_use]
pub fn contact_between_planes(pp: &[SurfacePlane], cp: &[SurfacePlane], cfg: &ContactConfig) -> Option<PairContact> {
    let max_child_area = cp.iter().map(|c| c.area).fold(0.0_f32, f32::max).max(1e-12);
    let mut best: Option<PairContact> = None;
    for (i, p) in pp.iter().enumerate() {
        for (j, c) in cp.iter().enumerate() {
            if align(p, c) < cfg.align_min {
                continue;
            }
            let dist = plane_distance(p, c);
            if dist > cfg.dist_max_m {
                continue;
            }
            let ratio = contact_ratio(p, c);
            if ratio < cfg.contact_min {
                continue;
            }
            let closeness = 1.0 - cfg.distance_penalty * (dist / cfg.dist_max_m.max(1e-9));
            let significance = (c.area / max_child_area).powf(cfg.face_significance);
            let weight = ratio * closeness * significance;
            if best.is_none_or(|b| weight > b.weight) {
                best = Some(PairContact { weight, ratio, distance_m: dist, parent_face: i, child_face: j });
            }
        }
    }
    best
}

/// A child passing through the parent (a latch or spindle through a door, a knob's shaft through
/// a panel): the child's box spans the parent's whole thickness along one of the parent's axes
/// while its cross-section lies at least `contact_min` on the parent's face. Face contact (the
/// paper's test) sees nothing there — no face of one lies on a face of the other — yet the child
/// is mounted on the parent. The weight is the share of the child's cross-section on the parent's
/// face (as a contact ratio at distance 0); the parent face is the crossed one, the child face
/// the one most parallel to it. The thinnest crossed axis wins. Boxes of the primitives (round
/// kinds by their bounding box) are compared in the parent's frame.
#[must_use]
pub fn through_contact(parent: &Primitive, child: &Primitive, cfg: &ContactConfig) -> Option<PairContact> {
    let axes = parent.axes_world();
    let h = parent.size * 0.5;
    let centre = parent.center();
    // The child's box corners in the parent's frame.
    let ch = child.size * 0.5;
    let caxes = child.axes_world();
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for corner in 0..8 {
        let sign = |bit: usize| if corner >> bit & 1 == 1 { 1.0 } else { -1.0 };
        let world = child.center() + caxes[0] * (sign(0) * ch.x) + caxes[1] * (sign(1) * ch.y) + caxes[2] * (sign(2) * ch.z);
        let local = world - centre;
        for k in 0..3 {
            let x = local.dot(axes[k]);
            lo[k] = lo[k].min(x);
            hi[k] = hi[k].max(x);
        }
    }
    if !lo.iter().chain(&hi).all(|x| x.is_finite()) {
        return None;
    }
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| h[a].total_cmp(&h[b]));
    for k in order {
        if !(lo[k] <= -h[k] && hi[k] >= h[k]) {
            continue;
        }
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let overlap = |a: usize| (hi[a].min(h[a]) - lo[a].max(-h[a])).max(0.0);
        let section = (hi[u] - lo[u]) * (hi[v] - lo[v]);
        if section <= 0.0 {
            continue;
        }
        let ratio = (overlap(u) * overlap(v) / section).min(1.0);
        // The parent inside the child's section (the parent passes through the child) is not a mount.
        let parent_face_area = 4.0 * h[u] * h[v];
        if ratio < cfg.contact_min || section >= parent_face_area {
            continue;
        }
        let parent_face = surface_planes(parent).iter().position(|f| f.axis == k && f.side > 0.0)?;
        let child_face = surface_planes(child)
            .iter()
            .enumerate()
            .max_by(|(_, a), (_, b)| a.normal.dot(axes[k]).total_cmp(&b.normal.dot(axes[k])))
            .map(|(i, _)| i)?;
        return Some(PairContact { weight: ratio, ratio, distance_m: 0.0, parent_face, child_face });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> ContactConfig {
        ContactConfig::default()
    }

    /// Regression: ADROIT's latch, fitted as one box through its door, touched nothing by the
    /// face test and hung off the frame.
    #[test]
    fn a_latch_through_a_door_is_mounted_on_it() {
        let door = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.25), Vec3::new(0.49, 0.1, 0.5));
        let latch = Primitive::cuboid_at(Vec3::new(-0.14, -0.01, 0.23), Vec3::new(0.44, 0.28, 0.07));
        assert!(contact(&door, &latch, &cfg()).is_none(), "no face of one lies on a face of the other");
        let c = through_contact(&door, &latch, &cfg()).expect("through the door's thickness");
        assert!(c.weight > 0.5 && c.weight <= 1.0, "{c:?}");
        let planes = surface_planes(&door);
        assert!(planes[c.parent_face].normal.y.abs() > 0.99, "the crossed face is the door's front");
        let beside = Primitive::cuboid_at(Vec3::new(0.5, 0.0, 0.25), Vec3::new(0.1, 0.3, 0.1));
        assert!(through_contact(&door, &beside, &cfg()).is_none(), "beside the door, not through it");
    }

    #[test]
    fn stacked_boxes_touch_fully() {
        let bottom = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::splat(1.0));
        let top = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 1.1), Vec3::new(0.5, 0.5, 0.2));
        let c = contact(&bottom, &top, &cfg()).expect("contact");
        assert!((c.ratio - 1.0).abs() < 1e-5);
        assert!(c.distance_m < 1e-5);
        // The reverse direction sees only a quarter of the big face covered.
        let r = contact(&top, &bottom, &cfg()).expect("contact");
        assert!((r.ratio - 0.25).abs() < 1e-4, "{r:?}");
    }

    #[test]
    fn partial_overlap_gives_the_area_ratio() {
        let a = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::splat(1.0));
        let b = Primitive::cuboid_at(Vec3::new(0.5, 0.0, 1.5), Vec3::splat(1.0));
        let c = contact(&a, &b, &ContactConfig { face_significance: 0.0, ..cfg() }).expect("contact");
        assert!((c.ratio - 0.5).abs() < 1e-4, "{c:?}");
    }

    #[test]
    fn gap_larger_than_threshold_is_no_contact() {
        let a = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::splat(1.0));
        let b = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 1.6), Vec3::splat(1.0));
        assert!(contact(&a, &b, &cfg()).is_none());
    }

    #[test]
    fn tilted_child_fails_alignment() {
        let a = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::splat(1.0));
        let q = crate::math::Quat::from_rotation_x(0.5);
        let b = Primitive::new(
            crate::primitive::PrimitiveKind::Cuboid,
            Vec3::splat(0.2),
            crate::math::Pose::from_parts(Vec3::new(0.0, 0.0, 1.12), q),
        );
        assert!(contact(&a, &b, &cfg()).is_none());
    }

    #[test]
    fn handle_prefers_the_drawer_over_the_body_behind_it() {
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.5, 1.0));
        let drawer = Primitive::cuboid_at(Vec3::new(0.0, 0.26, 0.8), Vec3::new(0.6, 0.02, 0.2));
        let handle = Primitive::cuboid_at(Vec3::new(0.0, 0.28, 0.8), Vec3::new(0.12, 0.02, 0.02));
        let from_drawer = contact(&drawer, &handle, &cfg()).expect("drawer contact");
        let from_body = contact(&body, &handle, &cfg()).expect("body passes the Dist test too");
        assert!(from_drawer.weight > from_body.weight);
    }
}
