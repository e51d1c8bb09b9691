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
    /// A revolute joint without limits (wheels, casters, turntables); its `lower`/`upper` are a
    /// display range only.
    Continuous,
}

impl JointKind {
    pub const ALL: [JointKind; 4] = [JointKind::Fixed, JointKind::Prismatic, JointKind::Revolute, JointKind::Continuous];

    /// Whether the joint turns (revolute or continuous).
    #[must_use]
    pub fn rotates(self) -> bool {
        matches!(self, JointKind::Revolute | JointKind::Continuous)
    }

    /// The motion a joint allows, for comparing types across conventions: a URDF `continuous`
    /// joint is read as revolute without limits, so a continuous and a revolute joint move alike.
    #[must_use]
    pub fn motion_class(self) -> JointKind {
        if self == JointKind::Continuous { JointKind::Revolute } else { self }
    }

    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            JointKind::Fixed => "fixed",
            JointKind::Prismatic => "prismatic",
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
        }
    }

    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        JointKind::ALL.into_iter().find(|k| k.name() == name)
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
