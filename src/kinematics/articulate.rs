//! Forward kinematics of a reconstructed scene: where every part is when its joints move.
//!
//! Joints are stated in the world frame at rest (q = 0), so a joint's motion is a rigid motion of
//! the world, and a part moves by the product of the motions of the joints above it, outermost
//! first: `world_from_part(q) = M(j₁, q₁) · M(j₂, q₂) · … · M(jₖ, qₖ) · world_from_part(0)`.

use std::collections::BTreeMap;

use crate::math::{Pose, Quat};
use crate::scan::PartId;

use super::{Joint, JointKind};

/// The rigid motion of the world that joint `joint` at position `q` (radians or metres) applies to
/// its child's subtree. Fixed joints do not move.
#[must_use]
pub fn joint_motion(joint: &Joint, q: f32) -> Pose {
    let axis = joint.axis_world.normalize_or_zero();
    match joint.kind {
        JointKind::Fixed => Pose::IDENTITY,
        JointKind::Prismatic => Pose::from_translation(axis * q),
        JointKind::Revolute | JointKind::Continuous => {
            // Rotation about the line through `origin_world`: translate to it, rotate, translate back.
            let rotation = Quat::from_axis_angle(axis, q);
            let origin = joint.origin_world;
            Pose::from_parts(origin - rotation * origin, rotation)
        }
    }
}

/// The motion of every part (keyed by part id) for joint positions `q_by_child` (keyed by the
/// joint's child part; missing joints stay at 0). Parts that move with no joint are absent: their
/// motion is the identity. Cycles in `joints` (which a valid model never has) are cut.
#[must_use]
pub fn part_motions(joints: &[Joint], q_by_child: &BTreeMap<PartId, f32>) -> BTreeMap<PartId, Pose> {
    let by_child: BTreeMap<PartId, &Joint> = joints.iter().map(|j| (j.child, j)).collect();
    let mut out: BTreeMap<PartId, Pose> = BTreeMap::new();
    for &child in by_child.keys() {
        // Walk up to the root, then compose downwards.
        let mut chain = Vec::new();
        let mut at = child;
        while let Some(j) = by_child.get(&at) {
            if chain.len() > by_child.len() {
                break;
            }
            chain.push(*j);
            at = j.parent;
        }
        let motion =
            chain.iter().rev().fold(Pose::IDENTITY, |acc, j| acc * joint_motion(j, q_by_child.get(&j.child).copied().unwrap_or(0.0)));
        out.insert(child, motion);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn joint(parent: PartId, child: PartId, kind: JointKind, axis: Vec3, origin: Vec3) -> Joint {
        Joint { parent, child, kind, axis_world: axis, origin_world: origin, lower: -1.0, upper: 1.0 }
    }

    #[test]
    fn a_door_turns_about_its_hinge_line_and_carries_its_handle() {
        // Cabinet 1, door 2 hinged on the vertical line x = 1, y = 0; handle 3 on the door at (0, 0, 1).
        let joints =
            [joint(1, 2, JointKind::Revolute, Vec3::Z, Vec3::new(1.0, 0.0, 0.0)), joint(2, 3, JointKind::Fixed, Vec3::X, Vec3::ZERO)];
        let q = BTreeMap::from([(2, std::f32::consts::FRAC_PI_2)]);
        let m = part_motions(&joints, &q);
        let handle = m[&3].transform_point(Vec3::new(0.0, 0.0, 1.0));
        // Quarter turn about z through (1, 0): (0, 0) → (1, -1).
        assert!((handle - Vec3::new(1.0, -1.0, 1.0)).length() < 1e-5, "{handle}");
        // A point on the hinge line does not move.
        assert!((m[&2].transform_point(Vec3::new(1.0, 0.0, 5.0)) - Vec3::new(1.0, 0.0, 5.0)).length() < 1e-5);
        assert!(!m.contains_key(&1), "the root does not move");
    }

    #[test]
    fn a_drawer_on_a_sliding_carriage_adds_both_motions() {
        let joints = [joint(1, 2, JointKind::Prismatic, Vec3::X, Vec3::ZERO), joint(2, 3, JointKind::Prismatic, Vec3::Y, Vec3::ZERO)];
        let q = BTreeMap::from([(2, 0.5), (3, 0.25)]);
        let p = part_motions(&joints, &q)[&3].transform_point(Vec3::ZERO);
        assert!((p - Vec3::new(0.5, 0.25, 0.0)).length() < 1e-6, "{p}");
    }
}
