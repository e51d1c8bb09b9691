//! Joints from part labels and geometry: the vocabulary (label → class → allowed types), the
//! evidence that chooses a type, and the templates that fit axis, pivot and limits.

mod articulate;
mod assign;
pub mod evidence;
mod joint;
pub mod vocabulary;

pub use articulate::{joint_motion, part_motions};
pub use assign::{
    CENTRED_ON_PARENT, HingeEdge, HingePlacement, JointSpec, KinematicsConfig, fit_joint, joint_from_handle, outward_direction,
};
pub use evidence::{Decision, JointContext, JointEvidence, decide, hinge_edge_evidence, parent_confidence};
pub use joint::{Joint, JointKind};
pub use vocabulary::{PartClass, Role, Template, Vocabulary, VocabularyError, label_tokens};
