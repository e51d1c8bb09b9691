//! The reconstructed interactive scene: what the pipeline produces, the editor shows, `eval`
//! scores and the exporters write.

use serde::{Deserialize, Serialize};

use crate::fit::PointSpan;
use crate::kinematics::{Joint, JointEvidence};
use crate::primitive::Primitive;
use crate::report::Warning;
use crate::scan::{ObjectId, PartId};

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SceneModel {
    pub source: String,
    /// Fitted parts, sorted by id.
    pub parts: Vec<PartModel>,
    /// The kinematic forest: one joint per non-root part (parent → child), sorted by child.
    pub joints: Vec<Joint>,
    /// Why each joint has its type, parent and axis, with a confidence; sorted by child. Empty
    /// for scenes not made by the pipeline (ground truth, old files).
    #[serde(default)]
    pub evidence: Vec<JointEvidence>,
    /// Candidate contact edges (the directed graph before Edmonds), sorted by (parent, child).
    pub contact_edges: Vec<ContactEdge>,
    /// Objects, sorted by id.
    pub objects: Vec<ObjectModel>,
    /// Object-level relations (support, proximity), sorted.
    pub relations: Vec<ObjectRelation>,
    /// Floor height (z), metres.
    pub floor_z: f32,
    pub warnings: Vec<Warning>,
    /// Parts of the input scan that could not be fitted (reported in `warnings`), sorted.
    #[serde(default)]
    pub skipped_parts: Vec<PartId>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PartModel {
    pub id: PartId,
    pub object: ObjectId,
    pub label: String,
    pub primitive: Primitive,
    /// Mean distance from the part's points to the primitive surface, metres.
    pub fit_error: f32,
    pub point_count: usize,
    /// Where the part's points end along the primitive's axes, when the points were at hand
    /// (joint fitting reads a door's back from it); not written to `scene.json`.
    #[serde(skip)]
    pub points_span: Option<PointSpan>,
}

/// A candidate parent → child contact (paper eq. 1–2): weight = max contact ratio Cont.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactEdge {
    pub parent: PartId,
    pub child: PartId,
    pub weight: f32,
    /// Whether Edmonds kept it in the tree.
    pub in_tree: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ObjectModel {
    pub id: ObjectId,
    pub category: String,
    /// Root part of the object's kinematic tree.
    pub root_part: PartId,
    /// What the object stands on: `None` for the floor, else the supporting part.
    pub supported_by_part: Option<PartId>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RelationKind {
    /// `from` supports `to` (None = the floor).
    Support,
    /// `from` and `to` are near each other (no support).
    Proximity,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ObjectRelation {
    pub kind: RelationKind,
    /// None = the floor.
    pub from: Option<ObjectId>,
    pub to: ObjectId,
}

impl SceneModel {
    #[must_use]
    pub fn part(&self, id: PartId) -> Option<&PartModel> {
        self.parts.binary_search_by_key(&id, |p| p.id).ok().map(|i| &self.parts[i])
    }

    /// The joint whose child is `child`.
    #[must_use]
    pub fn joint_of(&self, child: PartId) -> Option<&Joint> {
        self.joints.iter().find(|j| j.child == child)
    }

    /// Parts of one object, in id order.
    pub fn parts_of(&self, object: ObjectId) -> impl Iterator<Item = &PartModel> {
        self.parts.iter().filter(move |p| p.object == object)
    }
}

/// A distinct, stable colour for a part (golden-ratio hues), sRGB 0..1: the same in the editor,
/// headless renders and Rerun recordings.
#[must_use]
pub fn part_color(id: PartId) -> [f32; 3] {
    let h = (id as f64 * 0.618_033_988_749_895).rem_euclid(1.0) as f32;
    let (s, v) = (0.55f32, 0.92f32);
    let i = (h * 6.0).floor();
    let f = h * 6.0 - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - f * s), v * (1.0 - (1.0 - f) * s));
    match i as i32 % 6 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    }
}

/// The colour of a joint type wherever joints are drawn (editor, headless renders, Rerun), sRGB
/// 0..1: revolute magenta, continuous violet, prismatic cyan, fixed light grey.
#[must_use]
pub const fn joint_kind_color(kind: crate::kinematics::JointKind) -> [f32; 3] {
    match kind {
        crate::kinematics::JointKind::Revolute => [0.85, 0.24, 0.85],
        crate::kinematics::JointKind::Continuous => [0.55, 0.35, 0.95],
        crate::kinematics::JointKind::Prismatic => [0.1, 0.75, 0.95],
        crate::kinematics::JointKind::Fixed => [0.78, 0.78, 0.78],
    }
}
