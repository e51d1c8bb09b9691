//! The corrections a person can make. Each one becomes a pin ([`PinnedEdits`]) that every later
//! run of the pipeline honours, so undo/redo is a stack of pin sets.

use serde::{Deserialize, Serialize};

use crate::kinematics::JointKind;
use crate::math::Vec3;
use crate::pipeline::PinnedEdits;
use crate::primitive::PrimitiveKind;
use crate::scan::PartId;

/// One correction of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub enum EditCommand {
    /// Make `parent` the parent of `child` (same object; no cycles).
    SetParent { child: PartId, parent: PartId },
    /// Change the type of the joint above `child`.
    SetJointKind { child: PartId, kind: JointKind },
    /// Set the axis of the joint above `child` (world frame; normalised).
    SetAxis { child: PartId, axis_world: Vec3 },
    /// Reverse the axis of the joint above `child` (and mirror its limits, so the motion range stays).
    FlipAxis { child: PartId },
    /// Move the hinge of the door or lid `child` to the edge opposite the one it is on now (a
    /// pinned axis is reversed with it, so the door still opens the way it did). Only for movable
    /// joints hinged like a door or lid (templates `hinge`, `lid_hinge`).
    OtherHingeEdge { child: PartId },
    /// Set the limits of the joint above `child` (radians or metres).
    SetLimits { child: PartId, lower: f32, upper: f32 },
    /// Replace the primitive of `part` by the best fit of another kind.
    SetPrimitiveKind { part: PartId, kind: PrimitiveKind },
    /// Forget every pin on `part` (its parent, joint and primitive go back to the pipeline's choice).
    Unpin { part: PartId },
    /// The annotator agrees with the joint above `child`: its parent and type are pinned as they
    /// are, and a hinge's edge too (the joint leaves the review queue, and later runs keep it).
    Confirm { child: PartId },
}

impl EditCommand {
    /// The part the command is about (for selection and messages).
    #[must_use]
    pub fn part(&self) -> PartId {
        match *self {
            EditCommand::SetParent { child, .. }
            | EditCommand::SetJointKind { child, .. }
            | EditCommand::SetAxis { child, .. }
            | EditCommand::FlipAxis { child }
            | EditCommand::OtherHingeEdge { child }
            | EditCommand::SetLimits { child, .. }
            | EditCommand::Confirm { child } => child,
            EditCommand::SetPrimitiveKind { part, .. } | EditCommand::Unpin { part } => part,
        }
    }

    /// A short description for the undo history and status line.
    #[must_use]
    pub fn describe(&self) -> String {
        match *self {
            EditCommand::SetParent { child, parent } => format!("part {child}: parent -> part {parent}"),
            EditCommand::SetJointKind { child, kind } => format!("part {child}: joint -> {}", kind.name()),
            EditCommand::SetAxis { child, axis_world: a } => format!("part {child}: axis -> ({:.2}, {:.2}, {:.2})", a.x, a.y, a.z),
            EditCommand::FlipAxis { child } => format!("part {child}: axis flipped"),
            EditCommand::OtherHingeEdge { child } => format!("part {child}: hinge moved to the other edge"),
            EditCommand::SetLimits { child, lower, upper } => format!("part {child}: limits -> [{lower:.3}, {upper:.3}]"),
            EditCommand::SetPrimitiveKind { part, kind } => format!("part {part}: primitive -> {}", kind.name()),
            EditCommand::Unpin { part } => format!("part {part}: pins cleared"),
            EditCommand::Confirm { child } => format!("part {child}: parent and joint type confirmed"),
        }
    }
}

/// Whether `pins` pin anything on `part`.
#[must_use]
pub fn is_pinned(pins: &PinnedEdits, part: PartId) -> bool {
    pins.parent.contains_key(&part)
        || pins.joint_kind.contains_key(&part)
        || pins.primitive_kind.contains_key(&part)
        || pins.axis.contains_key(&part)
        || pins.limits.contains_key(&part)
        || pins.hinge_edge.contains_key(&part)
}

/// Removes every pin on `part` from `pins`.
pub fn unpin(pins: &mut PinnedEdits, part: PartId) {
    pins.parent.remove(&part);
    pins.joint_kind.remove(&part);
    pins.primitive_kind.remove(&part);
    pins.hinge_edge.remove(&part);
    pins.axis.remove(&part);
    pins.limits.remove(&part);
}
