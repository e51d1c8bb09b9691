//! `scene.json`: the part-level contact graph as `../shared/spec/scan-format.md` §2 specifies it,
//! plus objects, their relations, the candidate contact edges and warnings.

use serde::{Deserialize, Serialize};

use crate::kinematics::{Joint, JointEvidence};
use crate::model::{ContactEdge, ObjectModel, ObjectRelation, PartModel, SceneModel};
use crate::primitive::Primitive;
use crate::report::Warning;
use crate::scan::{ObjectId, PartId};

pub const SCENE_FORMAT: &str = "partscene-scene/1";

#[derive(Serialize, Deserialize)]
struct SceneJson {
    format: String,
    source: String,
    floor_z: f32,
    parts: Vec<PartJson>,
    joints: Vec<Joint>,
    /// Per joint (by child): why its type, parent and axis, and a confidence.
    #[serde(default)]
    joint_evidence: Vec<JointEvidence>,
    objects: Vec<ObjectModel>,
    relations: Vec<ObjectRelation>,
    contact_edges: Vec<ContactEdge>,
    #[serde(default)]
    warnings: Vec<Warning>,
    #[serde(default)]
    skipped_parts: Vec<PartId>,
}

#[derive(Serialize, Deserialize)]
struct PartJson {
    id: PartId,
    object: ObjectId,
    label: String,
    urdf_link: String,
    primitive: Primitive,
    fit_error: f32,
    #[serde(default)]
    point_count: usize,
}

#[derive(Debug, thiserror::Error)]
pub enum SceneJsonError {
    #[error("{path}: not a partscene scene.json: {message}")]
    Parse { path: String, message: String },
    #[error("{path}: format is {found:?}, expected {SCENE_FORMAT:?}")]
    Format { path: String, found: String },
    #[error("{path}: cannot read: {source}")]
    Io { path: String, source: std::io::Error },
    /// The document parsed but refers to something it does not hold (or holds twice).
    #[error("{path}: {field}: {problem}")]
    Reference { path: String, field: String, problem: String },
}

/// `scene.json` text of a scene.
#[must_use]
pub fn scene_json(scene: &SceneModel) -> String {
    let doc = SceneJson {
        format: SCENE_FORMAT.to_owned(),
        source: scene.source.clone(),
        floor_z: scene.floor_z,
        parts: scene
            .parts
            .iter()
            .map(|p| PartJson {
                id: p.id,
                object: p.object,
                label: p.label.clone(),
                urdf_link: super::link_name(scene, p),
                primitive: p.primitive,
                fit_error: p.fit_error,
                point_count: p.point_count,
            })
            .collect(),
        joints: scene.joints.clone(),
        joint_evidence: scene.evidence.clone(),
        objects: scene.objects.clone(),
        relations: scene.relations.clone(),
        contact_edges: scene.contact_edges.clone(),
        warnings: scene.warnings.clone(),
        skipped_parts: scene.skipped_parts.clone(),
    };
    // Serialising plain data to a string cannot fail.
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}

/// Parses `scene.json` text back into a scene (`path` names it in errors).
pub fn scene_from_json(text: &str, path: &str) -> Result<SceneModel, SceneJsonError> {
    let doc: SceneJson = serde_json::from_str(text).map_err(|e| SceneJsonError::Parse { path: path.to_owned(), message: e.to_string() })?;
    if doc.format != SCENE_FORMAT {
        return Err(SceneJsonError::Format { path: path.to_owned(), found: doc.format });
    }
    let mut parts: Vec<PartModel> = doc
        .parts
        .into_iter()
        .map(|p| PartModel {
            id: p.id,
            object: p.object,
            label: p.label,
            primitive: p.primitive,
            fit_error: p.fit_error,
            point_count: p.point_count,
            points_span: None,
        })
        .collect();
    parts.sort_by_key(|p| p.id);
    let reference = |field: String, problem: String| SceneJsonError::Reference { path: path.to_owned(), field, problem };
    check_references(&parts, &doc.joints, &doc.objects).map_err(|(field, problem)| reference(field, problem))?;
    Ok(SceneModel {
        source: doc.source,
        parts,
        joints: doc.joints,
        evidence: doc.joint_evidence,
        contact_edges: doc.contact_edges,
        objects: doc.objects,
        relations: doc.relations,
        floor_z: doc.floor_z,
        warnings: doc.warnings,
        skipped_parts: doc.skipped_parts,
    })
}

/// What a scene's exporters and editor rely on: primitives and joints finite and within the
/// scans' coordinate limit (`scan::MAX_COORDINATE_M`), part ids unique, every joint joining two
/// parts of the document, an object standing on a part the document holds. Returns the field
/// and the problem of the first breach (parts sorted by id).
fn check_references(parts: &[PartModel], joints: &[Joint], objects: &[ObjectModel]) -> Result<(), (String, String)> {
    if let Some(w) = parts.windows(2).find(|w| w[0].id == w[1].id) {
        return Err(("parts".to_owned(), format!("part id {} appears more than once", w[0].id)));
    }
    let limit = crate::scan::MAX_COORDINATE_M;
    let plausible = |v: crate::math::Vec3, bound: f32| v.is_finite() && v.abs().max_element() <= bound;
    for p in parts {
        let prim = &p.primitive;
        if !plausible(prim.size, 2.0 * limit) || prim.size.min_element() < 0.0 {
            return Err((
                format!("parts[id {}].primitive.size", p.id),
                format!("{:?} is not a size; expected sizes in [0, {}] m", prim.size.to_array(), 2.0 * limit),
            ));
        }
        if !plausible(prim.center(), limit) || !prim.rotation().is_finite() {
            return Err((
                format!("parts[id {}].primitive.world_from_primitive", p.id),
                format!("expected a finite pose within {limit} m of the origin"),
            ));
        }
    }
    for (i, j) in joints.iter().enumerate() {
        if !plausible(j.origin_world, limit) || !j.axis_world.is_finite() || !j.lower.is_finite() || !j.upper.is_finite() {
            return Err((format!("joints[{i}]"), format!("expected a finite axis, limits and an origin within {limit} m of the origin")));
        }
    }
    let known = |id: PartId| parts.binary_search_by_key(&id, |p| p.id).is_ok();
    for (i, j) in joints.iter().enumerate() {
        for (end, id) in [("parent", j.parent), ("child", j.child)] {
            if !known(id) {
                return Err((format!("joints[{i}].{end}"), format!("part {id} is not among the scene's parts")));
            }
        }
    }
    for (i, o) in objects.iter().enumerate() {
        if let Some(support) = o.supported_by_part.filter(|s| !known(*s)) {
            return Err((format!("objects[{i}].supported_by_part"), format!("part {support} is not among the scene's parts")));
        }
    }
    Ok(())
}

/// Reads `scene.json` from a file.
pub fn read_scene_json(path: &std::path::Path) -> Result<SceneModel, SceneJsonError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| SceneJsonError::Io { path: name.clone(), source })?;
    scene_from_json(&text, &name)
}
