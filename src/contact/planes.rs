//! Surface planes of a primitive: `(π, U)` with π = (n, d), n·u + d = 0, and U the polygon that
//! outlines the face.
//!
//! The paper extracts planes from the primitive mesh by RANSAC; for our analytic primitives the
//! planes are known exactly. Every kind contributes the six faces of its own bounding box (as the
//! authors' released code does); for cylinders and capsules the two end faces are outlined by a
//! 16-gon (the real cap of a cylinder), and curved sides keep their tangent box faces so a knob or
//! a rod lying on a board still registers its contact.

use crate::math::Vec3;
use crate::primitive::{Primitive, PrimitiveKind};

/// A planar face of a primitive, in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfacePlane {
    /// Outward unit normal.
    pub normal: Vec3,
    /// `d` in n·u + d = 0.
    pub offset: f32,
    /// Outline, counter-clockwise seen from outside (along −normal).
    pub outline: Vec<Vec3>,
    /// Which face of the primitive's box: axis (0 = x, 1 = y, 2 = z) and side (+1 / −1).
    pub axis: usize,
    pub side: f32,
    /// Area of the outline, m².
    pub area: f32,
}

impl SurfacePlane {
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.outline.iter().copied().sum::<Vec3>() / self.outline.len().max(1) as f32
    }

    /// Signed distance of a point to the plane (positive outside).
    #[must_use]
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) + self.offset
    }
}

const CAP_SEGMENTS: usize = 16;

/// The six faces of a primitive's box (caps of cylinders/capsules as polygons).
#[must_use]
pub fn surface_planes(prim: &Primitive) -> Vec<SurfacePlane> {
    let axes = prim.axes_world();
    let h = prim.size * 0.5;
    let half = [h.x, h.y, h.z];
    let c = prim.center();
    let round_caps = matches!(prim.kind, PrimitiveKind::Cylinder | PrimitiveKind::Capsule);
    let mut out = Vec::with_capacity(6);
    for axis in 0..3 {
        for side in [1.0_f32, -1.0] {
            let n = axes[axis] * side;
            let face_center = c + n * half[axis];
            // In-plane axes (u, v) with u × v = n so the outline is counter-clockwise.
            let u_axis = (axis + 1) % 3;
            let v_axis = (axis + 2) % 3;
            let (u, v) = (axes[u_axis], axes[v_axis] * side);
            let (hu, hv) = (half[u_axis], half[v_axis]);
            let outline: Vec<Vec3> = if round_caps && axis == 2 {
                (0..CAP_SEGMENTS)
                    .map(|k| {
                        let a = std::f32::consts::TAU * k as f32 / CAP_SEGMENTS as f32;
                        face_center + u * (hu * a.cos()) + v * (hv * a.sin())
                    })
                    .collect()
            } else {
                vec![
                    face_center - u * hu - v * hv,
                    face_center + u * hu - v * hv,
                    face_center + u * hu + v * hv,
                    face_center - u * hu + v * hv,
                ]
            };
            let area = if round_caps && axis == 2 {
                0.5 * CAP_SEGMENTS as f32 * hu * hv * (std::f32::consts::TAU / CAP_SEGMENTS as f32).sin()
            } else {
                4.0 * hu * hv
            };
            out.push(SurfacePlane { normal: n, offset: -n.dot(face_center), outline, axis, side, area });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_faces_are_outward_and_counter_clockwise() {
        let p = Primitive::cuboid_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 4.0, 6.0));
        let planes = surface_planes(&p);
        assert_eq!(planes.len(), 6);
        for pl in &planes {
            assert!(pl.signed_distance(p.center()) < 0.0, "normal must point outward");
            // Newell normal of the outline agrees with the plane normal.
            let mut nn = Vec3::ZERO;
            for i in 0..pl.outline.len() {
                let a = pl.outline[i];
                let b = pl.outline[(i + 1) % pl.outline.len()];
                nn += a.cross(b);
            }
            assert!(nn.normalize().dot(pl.normal) > 0.999);
            for u in &pl.outline {
                assert!(pl.signed_distance(*u).abs() < 1e-5);
            }
        }
        let top = planes.iter().find(|pl| pl.normal.z > 0.9).expect("top face");
        assert!((top.area - 8.0).abs() < 1e-5);
    }
}
