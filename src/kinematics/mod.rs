//! Joints from part labels and geometry: type, axis, pivot and limits.

mod articulate;
mod assign;
mod joint;

pub use articulate::{joint_motion, part_motions};
pub use assign::{
    KinematicsConfig, estimate_joint, is_base_label, is_handle_label, is_movable_label, is_typical_parent, joint_from_handle,
    joint_kind_for_label, label_tokens, outward_direction,
};
pub use joint::{Joint, JointKind};
