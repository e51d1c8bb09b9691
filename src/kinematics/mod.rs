//! Joints from part labels and geometry: type, axis, pivot and limits.

mod joint;

pub use joint::{Joint, JointKind};
