//! The joint type shared by reconstruction, ground truth, export and the editor.

use serde::{Deserialize, Serialize};

use crate::math::Vec3;
use crate::scan::PartId;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    Fixed,
    Prismatic,
    Revolute,
}

impl JointKind {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            JointKind::Fixed => "fixed",
            JointKind::Prismatic => "prismatic",
            JointKind::Revolute => "revolute",
        }
    }

    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        [JointKind::Fixed, JointKind::Prismatic, JointKind::Revolute].into_iter().find(|k| k.name() == name)
    }

    #[must_use]
    pub fn is_movable(self) -> bool {
        self != JointKind::Fixed
    }
}

/// A joint between two parts, in world coordinates (the scene at rest, q = 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    pub parent: PartId,
    pub child: PartId,
    #[serde(rename = "type")]
    pub kind: JointKind,
    /// Unit axis; positive motion opens (a door swings out, a drawer slides out).
    pub axis_world: Vec3,
    /// A point on the axis (the hinge line for revolute joints).
    pub origin_world: Vec3,
    /// Limits in metres (prismatic) or radians (revolute); 0 for fixed joints.
    pub lower: f32,
    pub upper: f32,
}
