//! Where a part's points end along its primitive's axes.
//!
//! One primitive per part is the paper's model, but not every part is one box: a door whose mesh
//! carries its handle is fitted best by a box that runs from the panel's front face to the
//! handle's, and the panel's sides reach centimetres behind that box. Rules that need where the
//! part's material ends (a door turns about a line at its back) read it from the points.

use super::{quantile_in_place, subsample_stride};
use crate::math::Vec3;
use crate::primitive::Primitive;

/// Share of the points ignored at each end of an axis where the points reach past the box
/// (stray points, scanner noise).
const REACH_QUANTILE: f32 = 0.02;
/// How far past a face of its box a point must lie to be material the box missed, as a share
/// of the box's size across that face: the scanner's noise and points of a neighbour given the
/// part's label at its border lie closer.
const PAST_FACE_SIZE_SHARE: f32 = 0.25;
/// Least share of the part's points that must lie that far past a face for the box to stop
/// short of the part's material there (the panel's sides behind a door's box hold a third).
const MIN_SHARE_PAST_FACE: f32 = 0.1;
/// At most this many points (a stride subsample) are measured.
const MAX_SPAN_POINTS: usize = 20_000;

/// Where a part's points end along its primitive's three axes, in the primitive's frame (metres
/// from its origin, per axis; the 2nd and 98th percentiles), and the share of the points lying
/// well past each face of the primitive ([`PAST_FACE_SIZE_SHARE`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSpan {
    pub min_local: Vec3,
    pub max_local: Vec3,
    /// Per axis: the share of the points well past the face on the negative side.
    pub share_past_min: Vec3,
    /// Per axis: the same on the positive side.
    pub share_past_max: Vec3,
}

impl PointSpan {
    /// How far the part's material reaches behind the primitive's origin against its local
    /// `axis` (0, 1, 2) taken with `sign` (the axis itself for a positive sign, its opposite for
    /// a negative one), metres: the span's end on the far side, where enough of the points lie
    /// well past the primitive's face there ([`MIN_SHARE_PAST_FACE`]); `None` where the
    /// primitive holds the part's material that way.
    #[must_use]
    pub fn reach_behind(&self, axis: usize, sign: f32) -> Option<f32> {
        let (reach, share) = if sign >= 0.0 {
            (-self.min_local[axis], self.share_past_min[axis])
        } else {
            (self.max_local[axis], self.share_past_max[axis])
        };
        (share >= MIN_SHARE_PAST_FACE).then_some(reach)
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
    let n = local.len() as f32;
    let half = primitive.size * 0.5;
    let mut span = PointSpan { min_local: Vec3::ZERO, max_local: Vec3::ZERO, share_past_min: Vec3::ZERO, share_past_max: Vec3::ZERO };
    for a in 0..3 {
        let mut values: Vec<f32> = local.iter().map(|p| p[a]).collect();
        let margin = PAST_FACE_SIZE_SHARE * primitive.size[a];
        span.share_past_min[a] = values.iter().filter(|&&v| v < -half[a] - margin).count() as f32 / n;
        span.share_past_max[a] = values.iter().filter(|&&v| v > half[a] + margin).count() as f32 / n;
        span.min_local[a] = quantile_in_place(&mut values, REACH_QUANTILE)?;
        span.max_local[a] = quantile_in_place(&mut values, 1.0 - REACH_QUANTILE)?;
    }
    Some(span)
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
        assert!((span.min_local - Vec3::new(-0.2, -0.1, -0.3)).abs().max_element() < 0.02, "{span:?}");
        assert!((span.max_local - Vec3::new(0.2, 0.1, 0.3)).abs().max_element() < 0.02, "{span:?}");
        // The box holds the points: nothing reaches past it.
        assert_eq!(span.reach_behind(1, 1.0), None);
        assert_eq!(span.reach_behind(1, -1.0), None);
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
        let back_y = front_box.center().y + span.reach_behind(1, -1.0).expect("the panel's sides reach past the box");
        assert!((back_y + 0.137).abs() < 0.004, "back face at y = {back_y}");
        // In front, the box holds the handle.
        assert_eq!(span.reach_behind(1, 1.0), None);
    }

    #[test]
    fn noise_and_a_few_stray_points_behind_a_box_are_not_material() {
        // A door's front face scanned with 2 mm of noise, and 3 % of its points taken from the
        // cabinet behind it by the labelling (regression: a demo door's pin moved 2 cm back).
        let mut points = Vec::new();
        let mut state = 12_345_u64;
        let mut normal = || {
            // A deterministic, roughly normal draw (sum of uniforms).
            (0..12)
                .map(|_| {
                    state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                    (state >> 40) as f32 / (1u64 << 24) as f32
                })
                .sum::<f32>()
                - 6.0
        };
        for i in 0..60 {
            for j in 0..60 {
                points.push(Vec3::new(i as f32 * 0.006, 0.002 * normal(), j as f32 * 0.01));
            }
        }
        for i in 0..108 {
            points.push(Vec3::new(0.36, 0.01 + 0.0002 * i as f32, 0.3));
        }
        let door = Primitive::cuboid_at(Vec3::new(0.18, 0.0, 0.3), Vec3::new(0.36, 0.02, 0.6));
        let span = point_span(&points, &door).expect("points");
        assert_eq!(span.reach_behind(1, -1.0), None, "{span:?}");
    }

    #[test]
    fn no_finite_points_have_no_span() {
        let prim = Primitive::cuboid_at(Vec3::ZERO, Vec3::ONE);
        assert_eq!(point_span(&[], &prim), None);
        assert_eq!(point_span(&[Vec3::NAN], &prim), None);
    }
}
