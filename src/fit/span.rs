//! Where a part's points end along its primitive's axes.
//!
//! One primitive per part is the paper's model, but not every part is one box: a door whose mesh
//! carries its handle is fitted best by a box that runs from the panel's front face to the
//! handle's, and the panel's sides reach centimetres behind that box. Rules that need where the
//! part's material ends (a door turns about a line at its back) read it from the points.

use super::{quantile_in_place, subsample_stride};
use crate::math::Vec3;
use crate::primitive::Primitive;

/// Share of the points ignored at each end of each axis (stray points, scanner noise).
const SPAN_QUANTILE: f32 = 0.01;
/// At most this many points (a stride subsample) are measured.
const MAX_SPAN_POINTS: usize = 20_000;

/// Robust extent of a part's points along its primitive's three axes, in the primitive's frame
/// (metres from its origin, per axis): the 1st and 99th percentiles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSpan {
    pub min_local: Vec3,
    pub max_local: Vec3,
}

impl PointSpan {
    /// How far the points reach behind the primitive's origin against its local `axis` (0, 1,
    /// 2) taken with `sign` (the axis itself for a positive sign, its opposite for a negative
    /// one), metres: the span's end on the far side.
    #[must_use]
    pub fn reach_behind(&self, axis: usize, sign: f32) -> f32 {
        if sign >= 0.0 { -self.min_local[axis] } else { self.max_local[axis] }
    }
}

/// The [`PointSpan`] of `points` (world) in `primitive`'s frame; `None` without finite points.
#[must_use]
pub fn point_span(points: &[Vec3], primitive: &Primitive) -> Option<PointSpan> {
    let local: Vec<Vec3> = subsample_stride(points, MAX_SPAN_POINTS)
        .into_iter()
        .filter(|p| p.is_finite())
        .map(|p| primitive.world_from_primitive.inverse_transform_point(p))
        .collect();
    let mut min_local = Vec3::ZERO;
    let mut max_local = Vec3::ZERO;
    for a in 0..3 {
        let mut values: Vec<f32> = local.iter().map(|p| p[a]).collect();
        min_local[a] = quantile_in_place(&mut values, SPAN_QUANTILE)?;
        max_local[a] = quantile_in_place(&mut values, 1.0 - SPAN_QUANTILE)?;
    }
    Some(PointSpan { min_local, max_local })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Pose, Quat};

    /// Points on a grid over an axis-aligned box `[lo, hi]`'s surface.
    fn box_surface(lo: Vec3, hi: Vec3, n: usize) -> Vec<Vec3> {
        let mut out = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                for axis in 0..3 {
                    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                    for side in [lo[axis], hi[axis]] {
                        let mut p = Vec3::ZERO;
                        p[axis] = side;
                        p[b] = lo[b] + u * (hi[b] - lo[b]);
                        p[c] = lo[c] + v * (hi[c] - lo[c]);
                        out.push(p);
                    }
                }
            }
        }
        out
    }

    #[test]
    fn the_span_of_a_box_s_surface_is_the_box_in_its_frame() {
        let rotation = Quat::from_rotation_z(0.3);
        let pose = Pose::from_parts(Vec3::new(1.0, 2.0, 0.5), rotation);
        let local = box_surface(Vec3::new(-0.2, -0.1, -0.3), Vec3::new(0.2, 0.1, 0.3), 20);
        let world: Vec<Vec3> = local.iter().map(|p| pose.transform_point(*p)).collect();
        let prim = Primitive::new(crate::primitive::PrimitiveKind::Cuboid, Vec3::new(0.4, 0.2, 0.6), pose);
        let span = point_span(&world, &prim).expect("points");
        assert!((span.min_local - Vec3::new(-0.2, -0.1, -0.3)).abs().max_element() < 1e-4, "{span:?}");
        assert!((span.max_local - Vec3::new(0.2, 0.1, 0.3)).abs().max_element() < 1e-4, "{span:?}");
        // Behind the centre against the box's y axis, and against its opposite: its half-depth.
        assert!((span.reach_behind(1, 1.0) - 0.1).abs() < 1e-4);
        assert!((span.reach_behind(1, -1.0) - 0.1).abs() < 1e-4);
    }

    #[test]
    fn points_reaching_behind_a_box_fitted_short_of_them_set_the_depth() {
        // A door panel 4.8 cm deep with a handle 6 cm in front, and the box a fit made of its front
        // face and handle (regression: the microwave's hinge stood 4.6 cm in front of its pin).
        let mut points = box_surface(Vec3::new(-0.25, -0.185, 0.0), Vec3::new(0.25, -0.137, 0.37), 30);
        points.extend(box_surface(Vec3::new(0.11, -0.263, 0.05), Vec3::new(0.15, -0.223, 0.32), 10));
        let front_box = Primitive::cuboid_at(Vec3::new(0.0, -0.217, 0.185), Vec3::new(0.5, 0.071, 0.37));
        let span = point_span(&points, &front_box).expect("points");
        // The door opens towards -y: its back is behind the centre against -y.
        let back_y = front_box.center().y + span.reach_behind(1, -1.0);
        assert!((back_y + 0.137).abs() < 0.002, "back face at y = {back_y}");
        assert!(span.reach_behind(1, -1.0) > 0.5 * front_box.size.y + 0.04);
    }

    #[test]
    fn no_finite_points_have_no_span() {
        let prim = Primitive::cuboid_at(Vec3::ZERO, Vec3::ONE);
        assert_eq!(point_span(&[], &prim), None);
        assert_eq!(point_span(&[Vec3::NAN], &prim), None);
    }
}
