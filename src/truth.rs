//! Ground truth of a scene (`gt.json`): what the demo generator and asset scanner know, and what
//! `eval` compares a reconstruction with.

use serde::{Deserialize, Serialize};

use crate::kinematics::Joint;
use crate::math::Vec3;
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
    /// Geometry as triangle meshes in the world frame (imported assets), beside `shapes`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<TruthMesh>,
}

/// A triangle mesh in the world frame (metres).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TruthMesh {
    pub vertices: Vec<Vec3>,
    /// Vertex indices, counter-clockwise seen from outside where the source says so.
    pub triangles: Vec<[u32; 3]>,
}

impl TruthMesh {
    /// World-frame bounds of the vertices that triangles use; `None` without a triangle.
    #[must_use]
    pub fn aabb(&self) -> Option<(Vec3, Vec3)> {
        let mut out: Option<(Vec3, Vec3)> = None;
        for &i in self.triangles.iter().flatten() {
            let v = *self.vertices.get(i as usize)?;
            out = Some(out.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
        }
        out
    }

    /// The triangles as vertex triples; triangles with an index out of range are skipped.
    pub fn triangle_vertices(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.triangles.iter().filter_map(|t| {
            Some([*self.vertices.get(t[0] as usize)?, *self.vertices.get(t[1] as usize)?, *self.vertices.get(t[2] as usize)?])
        })
    }
}

impl TruthPart {
    /// World-frame bounds of every primitive and mesh of the part; `None` without geometry.
    #[must_use]
    pub fn aabb(&self) -> Option<(Vec3, Vec3)> {
        bounds(&self.shapes, self.meshes.iter())
    }
}

/// World-frame bounds of primitives and meshes together; `None` without geometry.
pub fn bounds<'a>(primitives: &[Primitive], meshes: impl Iterator<Item = &'a TruthMesh>) -> Option<(Vec3, Vec3)> {
    primitives.iter().map(Primitive::aabb).chain(meshes.filter_map(TruthMesh::aabb)).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
}

impl TruthObject {
    /// World-frame bounds of every part; `None` without geometry.
    #[must_use]
    pub fn aabb(&self) -> Option<(Vec3, Vec3)> {
        self.parts.iter().filter_map(TruthPart::aabb).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }
}
