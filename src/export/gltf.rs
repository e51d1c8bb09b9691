//! `scene.glb`: the primitive scene as binary glTF 2.0, for any viewer. One node per part, named
//! like its URDF link, nested along the kinematic tree (an object under the world or under the
//! part that supports it), each carrying its primitive as a triangle mesh
//! ([`crate::primitive::Primitive::local_mesh`]) with a material per label
//! ([`super::label_color`]). Node frames are the URDF's link frames (world-aligned, at the joint
//! origin), so a viewer that animates a node about its joint axis moves the part as the URDF does;
//! each node's `extras` carry the part id, label and joint (type, axis, limits).
//!
//! glTF is y-up and our scenes are z-up: one root node `partscene` turns the scene (−90° about x),
//! so it stands upright in viewers; everything below it is in the scene's own z-up coordinates.

use std::collections::BTreeMap;

use serde_json::{Value, json};

use super::tree::ExportTree;
use super::urdf::{label_color, sanitize};
use crate::math::Vec3;
use crate::model::{PartModel, SceneModel};
use crate::scan::PartId;

/// Segments around the axis of round primitives.
const SEGMENTS: usize = 32;

const ARRAY_BUFFER: u32 = 34_962;
const ELEMENT_ARRAY_BUFFER: u32 = 34_963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Why the glTF could not be written.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// A part's geometry holds NaN or infinity.
    #[error("cannot write glTF: part {part} ({link}) has a non-finite {what}")]
    NonFinite { part: PartId, link: String, what: &'static str },
    /// More geometry than a glTF buffer can address (4 GiB).
    #[error("cannot write glTF: the scene's meshes exceed 4 GiB")]
    TooLarge,
}

/// Vertex data (positions then normals, per part) and indices, with accessor bookkeeping.
#[derive(Default)]
struct Buffers {
    vertices: Vec<u8>,
    indices: Vec<u8>,
    accessors: Vec<Value>,
}

impl Buffers {
    fn vec3s(&mut self, data: &[Vec3], with_bounds: bool) -> Result<usize, GltfError> {
        let offset = u32::try_from(self.vertices.len()).map_err(|_| GltfError::TooLarge)?;
        for v in data {
            for c in v.to_array() {
                self.vertices.extend_from_slice(&c.to_le_bytes());
            }
        }
        let mut acc = json!({"bufferView": 0, "byteOffset": offset, "componentType": FLOAT, "count": data.len(), "type": "VEC3"});
        if with_bounds {
            let (lo, hi) = data.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
            acc["min"] = json!(lo.to_array());
            acc["max"] = json!(hi.to_array());
        }
        self.accessors.push(acc);
        Ok(self.accessors.len() - 1)
    }

    fn triangles(&mut self, tris: &[[u32; 3]]) -> Result<usize, GltfError> {
        let offset = u32::try_from(self.indices.len()).map_err(|_| GltfError::TooLarge)?;
        for i in tris.iter().flatten() {
            self.indices.extend_from_slice(&i.to_le_bytes());
        }
        self.accessors
            .push(json!({"bufferView": 1, "byteOffset": offset, "componentType": UNSIGNED_INT, "count": tris.len() * 3, "type": "SCALAR"}));
        Ok(self.accessors.len() - 1)
    }
}

/// `scene.glb` bytes.
pub fn scene_glb(scene: &SceneModel) -> Result<Vec<u8>, GltfError> {
    let tree = ExportTree::new(scene);
    if let Some((part, what)) = tree.first_non_finite(scene) {
        return Err(GltfError::NonFinite { part, link: tree.name[&part].clone(), what });
    }
    let mut buffers = Buffers::default();
    let mut materials: Vec<Value> = Vec::new();
    let mut material_of: BTreeMap<String, usize> = BTreeMap::new();
    let mut meshes = Vec::new();
    // Node 0 is the y-up root; part nodes follow in depth-first order.
    let mut nodes: Vec<Value> = vec![json!({
        "name": "partscene",
        "rotation": [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2],
        "extras": {"source": scene.source, "up": "z (turned to glTF's y-up by this node)"},
    })];
    let mut root_children = Vec::new();
    for root in &tree.roots {
        let index = add_node(&tree, root, Vec3::ZERO, &mut nodes, &mut meshes, &mut buffers, &mut materials, &mut material_of)?;
        root_children.push(index);
    }
    if !root_children.is_empty() {
        nodes[0]["children"] = json!(root_children);
    }
    while !buffers.vertices.len().is_multiple_of(4) {
        buffers.vertices.push(0);
    }
    let vertex_len = buffers.vertices.len();
    let index_len = buffers.indices.len();
    let mut bin = std::mem::take(&mut buffers.vertices);
    bin.extend_from_slice(&buffers.indices);
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "partscene"},
        "scene": 0,
        "scenes": [{"name": "partscene", "nodes": [0]}],
        "nodes": nodes,
    });
    // glTF forbids empty top-level arrays and empty buffers: a scene without parts has neither.
    if !meshes.is_empty() {
        doc["meshes"] = json!(meshes);
        doc["materials"] = json!(materials);
        doc["accessors"] = json!(buffers.accessors);
        doc["bufferViews"] = json!([
            {"buffer": 0, "byteOffset": 0, "byteLength": vertex_len, "byteStride": 12, "target": ARRAY_BUFFER},
            {"buffer": 0, "byteOffset": vertex_len, "byteLength": index_len, "target": ELEMENT_ARRAY_BUFFER},
        ]);
        doc["buffers"] = json!([{"byteLength": bin.len()}]);
    }
    glb(&doc.to_string(), bin)
}

/// Adds a part's node (and its children's) whose parent frame is at `parent_origin`; returns its index.
#[allow(clippy::too_many_arguments)] // one recursive walk over the tree threading the document's lists
fn add_node(
    tree: &ExportTree,
    part: &PartModel,
    parent_origin: Vec3,
    nodes: &mut Vec<Value>,
    meshes: &mut Vec<Value>,
    buffers: &mut Buffers,
    materials: &mut Vec<Value>,
    material_of: &mut BTreeMap<String, usize>,
) -> Result<usize, GltfError> {
    let name = tree.name[&part.id].clone();
    let origin = tree.origin_world[&part.id];
    let prim = &part.primitive;
    // The mesh in the link frame: the primitive's pose relative to the link origin baked in.
    let mut mesh = prim.local_mesh(SEGMENTS);
    let rot = prim.rotation();
    let offset = prim.center() - origin;
    for p in &mut mesh.positions {
        *p = rot * *p + offset;
    }
    for n in &mut mesh.normals {
        *n = (rot * *n).normalize_or(Vec3::Z);
    }
    let position = buffers.vec3s(&mesh.positions, true)?;
    let normal = buffers.vec3s(&mesh.normals, false)?;
    let indices = buffers.triangles(&mesh.triangles)?;
    let material_name = format!("mat_{}", sanitize(&part.label));
    let material = *material_of.entry(material_name.clone()).or_insert_with(|| {
        let c = label_color(&part.label);
        materials.push(json!({
            "name": material_name,
            "pbrMetallicRoughness": {"baseColorFactor": c, "metallicFactor": 0.0, "roughnessFactor": 0.8},
        }));
        materials.len() - 1
    });
    meshes.push(json!({
        "name": name,
        "primitives": [{"attributes": {"POSITION": position, "NORMAL": normal}, "indices": indices, "material": material}],
    }));
    let joint = tree
        .joint_into
        .get(&part.id)
        .map(|j| json!({"type": j.kind.name(), "axis": j.axis_world.to_array(), "lower": j.lower, "upper": j.upper}));
    let index = nodes.len();
    let t = origin - parent_origin;
    nodes.push(json!({
        "name": name,
        "mesh": meshes.len() - 1,
        "translation": t.to_array(),
        "extras": {"part": part.id, "object": part.object, "label": part.label, "primitive": prim.kind.name(), "joint": joint},
    }));
    let mut children = Vec::new();
    for child in tree.children_of(part.id) {
        children.push(add_node(tree, child, origin, nodes, meshes, buffers, materials, material_of)?);
    }
    if !children.is_empty() {
        nodes[index]["children"] = json!(children);
    }
    Ok(index)
}

/// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded; left out when empty).
fn glb(json_text: &str, mut bin: Vec<u8>) -> Result<Vec<u8>, GltfError> {
    let mut json_bytes = json_text.as_bytes().to_vec();
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json_bytes.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let len = |n: usize| u32::try_from(n).map_err(|_| GltfError::TooLarge);
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2_u32.to_le_bytes());
    out.extend_from_slice(&len(total)?.to_le_bytes());
    out.extend_from_slice(&len(json_bytes.len())?.to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    if !bin.is_empty() {
        out.extend_from_slice(&len(bin.len())?.to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    Ok(out)
}
