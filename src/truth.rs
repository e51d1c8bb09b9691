//! Ground truth of a scene (`gt.json`): what the demo generator and asset scanner know, and what
//! `eval` compares a reconstruction with.

use serde::{Deserialize, Serialize};

use crate::kinematics::Joint;
use crate::primitive::Primitive;
use crate::scan::{ObjectId, PartId};

pub const TRUTH_FORMAT: &str = "partscene-truth/1";

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GroundTruth {
    pub format: String,
    pub objects: Vec<TruthObject>,
    /// Height of the floor (z), metres.
    pub floor_z: f32,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TruthObject {
    pub id: ObjectId,
    pub category: String,
    /// The object this one stands on (None: the floor).
    pub supported_by: Option<ObjectId>,
    pub parts: Vec<TruthPart>,
    /// Kinematic tree of the object: one joint per non-root part, parent → child.
    pub joints: Vec<Joint>,
    /// Annotated undirected contact edges (pairs of part ids, smaller id first), as the paper's
    /// kinematic-edge mAP uses them.
    pub contact_edges: Vec<[PartId; 2]>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TruthPart {
    pub id: PartId,
    pub label: String,
    /// Geometry as one or more primitives (a part may be modelled by several).
    pub shapes: Vec<Primitive>,
}
