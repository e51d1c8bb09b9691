//! URDF import: `urdf-rs` reads the document after a tolerant pre-pass; forward kinematics at
//! q = 0 puts every link, geom and joint in the root frame.
//!
//! Pre-pass: `urdf-rs` splits vectors on whitespace only, so `xyz="0.01, -0.33, 0"` would fail.
//! The document is parsed with `roxmltree` first and the commas inside the values of the vector
//! attributes (`xyz`, `rpy`, `scale`, `size`, `rgba`) are replaced by spaces in place (same byte
//! length, so nothing else moves); then the normalised text goes to `urdf_rs::read_from_string`.
//!
//! Mesh file names are resolved relative to the URDF's folder; `package://pkg/` and `file://`
//! prefixes are stripped (a `package://` path is also tried one and two folders up, with and
//! without the package name). A mesh that cannot be found or read is a warning naming it; the
//! link is kept without that geom. Mesh formats: OBJ, STL, `MuJoCo` `.msh`, GLB/glTF (see
//! [`super::mesh`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::mesh::MeshFormat;
use super::model::{ArticulatedAsset, AssetGeom, AssetJoint, AssetLink, GeomRole};
use super::{AssetError, MeshCache};
use crate::kinematics::JointKind;
use crate::math::{Pose, Vec3, rpy_to_quat};
use crate::primitive::PrimitiveKind;
use crate::report::Warning;

/// The attributes whose values are vectors of numbers in URDF.
const VECTOR_ATTRIBUTES: [&str; 5] = ["xyz", "rpy", "scale", "size", "rgba"];

/// Reads a URDF file (see the module docs for the tolerated quirks).
pub fn load_urdf(path: &Path) -> Result<ArticulatedAsset, AssetError> {
    let text = super::read_text(path)?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let fallback_name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("urdf");
    parse_urdf(&text, path, base_dir, fallback_name)
}

/// Reads URDF text; `path` is only used in messages, meshes are looked up from `base_dir`.
pub fn parse_urdf(text: &str, path: &Path, base_dir: &Path, fallback_name: &str) -> Result<ArticulatedAsset, AssetError> {
    let (normalised, fixed) = normalise_vector_commas(text, path)?;
    let robot =
        urdf_rs::read_from_string(&normalised).map_err(|e| AssetError::Urdf { path: path.to_path_buf(), message: e.to_string() })?;
    let mut asset = ArticulatedAsset {
        name: if robot.name.is_empty() { fallback_name.to_owned() } else { robot.name.clone() },
        ..ArticulatedAsset::default()
    };
    if fixed > 0 {
        asset.warnings.push(Warning::new(
            "assets",
            path.display().to_string(),
            format!("{fixed} vector attribute(s) written with commas were read as space-separated"),
        ));
    }
    let structure = |message: String| AssetError::Structure { path: path.to_path_buf(), message };

    let mut index_of: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, link) in robot.links.iter().enumerate() {
        if index_of.insert(link.name.as_str(), i).is_some() {
            return Err(structure(format!("link {:?} is defined twice", link.name)));
        }
    }
    // Parent joint of each link, checked to form a forest.
    let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        let lookup = |name: &str, role: &str| {
            index_of.get(name).copied().ok_or_else(|| structure(format!("joint {:?} names unknown {role} link {name:?}", joint.name)))
        };
        lookup(&joint.parent.link, "parent")?;
        let child = lookup(&joint.child.link, "child")?;
        if let Some(previous) = parent_joint[child] {
            return Err(structure(format!(
                "link {:?} is the child of two joints ({:?} and {:?})",
                joint.child.link, robot.joints[previous].name, joint.name
            )));
        }
        parent_joint[child] = Some(j);
    }

    // Forward kinematics at q = 0: resolve each link by walking up to a root (memoised).
    let mut world_from_link: Vec<Option<Pose>> = vec![None; robot.links.len()];
    for start in 0..robot.links.len() {
        let mut chain = Vec::new();
        let mut cursor = start;
        while world_from_link[cursor].is_none() {
            if chain.contains(&cursor) {
                return Err(structure(format!("the joints form a cycle through link {:?}", robot.links[cursor].name)));
            }
            chain.push(cursor);
            if let Some(j) = parent_joint[cursor] {
                cursor = index_of[robot.joints[j].parent.link.as_str()];
            } else {
                world_from_link[cursor] = Some(Pose::IDENTITY);
                chain.pop();
                break;
            }
        }
        for &link in chain.iter().rev() {
            let Some(j) = parent_joint[link] else { continue };
            let joint = &robot.joints[j];
            let parent_pose = world_from_link[index_of[joint.parent.link.as_str()]].unwrap_or(Pose::IDENTITY);
            world_from_link[link] = Some(parent_pose * pose_of(&joint.origin));
        }
    }

    for joint in &robot.joints {
        let parent_pose = world_from_link[index_of[joint.parent.link.as_str()]].unwrap_or(Pose::IDENTITY);
        let world_from_joint = parent_pose * pose_of(&joint.origin);
        let (kind, limited) = match joint.joint_type {
            urdf_rs::JointType::Revolute => (JointKind::Revolute, true),
            urdf_rs::JointType::Continuous => (JointKind::Revolute, false),
            urdf_rs::JointType::Prismatic => (JointKind::Prismatic, true),
            urdf_rs::JointType::Fixed => (JointKind::Fixed, false),
            ref other => {
                asset.warnings.push(Warning::new(
                    "assets",
                    format!("joint {}", joint.name),
                    format!("{other:?} joints are not supported; imported as fixed"),
                ));
                (JointKind::Fixed, false)
            }
        };
        let axis_joint = vec3(&joint.axis.xyz);
        let axis_world = if kind == JointKind::Fixed {
            Vec3::X
        } else if axis_joint.length() < 1e-9 {
            asset.warnings.push(Warning::new("assets", format!("joint {}", joint.name), "zero axis; +X used"));
            world_from_joint.rotation * Vec3::X
        } else {
            world_from_joint.rotation * axis_joint.normalize()
        };
        let (lower, upper) = match (kind, limited) {
            (JointKind::Fixed, _) => (0.0, 0.0),
            (_, true) => (joint.limit.lower as f32, joint.limit.upper as f32),
            (_, false) => (f32::NEG_INFINITY, f32::INFINITY),
        };
        asset.joints.push(AssetJoint {
            name: joint.name.clone(),
            kind,
            parent: joint.parent.link.clone(),
            child: joint.child.link.clone(),
            axis_world,
            origin_world: world_from_joint.translation,
            lower,
            upper,
        });
    }

    let mut meshes = MeshCache::default();
    for (link, pose) in robot.links.iter().zip(&world_from_link) {
        let world_from_link = pose.unwrap_or(Pose::IDENTITY);
        let mut geoms = Vec::new();
        let parts = link
            .visual
            .iter()
            .map(|v| (GeomRole::Visual, &v.origin, &v.geometry, v.name.as_deref(), v.material.as_ref().map(|m| m.name.as_str())))
            .chain(link.collision.iter().map(|c| (GeomRole::Collision, &c.origin, &c.geometry, c.name.as_deref(), None)));
        for (role, origin, geometry, name, material) in parts {
            let world_from_geom = world_from_link * pose_of(origin);
            let mesh_stem = match geometry {
                urdf_rs::Geometry::Mesh { filename, .. } => Path::new(filename).file_stem().and_then(|s| s.to_str()),
                _ => None,
            };
            match geometry_to_geom(geometry, world_from_geom, role, base_dir, &mut meshes) {
                Ok(geom) => geoms.push(geom.named([name, mesh_stem, material].into_iter().flatten())),
                Err(message) => asset.warnings.push(Warning::new("assets", format!("link {}", link.name), message)),
            }
        }
        asset.links.push(AssetLink { name: link.name.clone(), named: true, world_from_link, geoms });
    }
    Ok(asset)
}

fn vec3(v: &urdf_rs::Vec3) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

fn pose_of(p: &urdf_rs::Pose) -> Pose {
    Pose::from_parts(vec3(&p.xyz), rpy_to_quat(p.rpy.0))
}

fn geometry_to_geom(
    geometry: &urdf_rs::Geometry,
    world_from_geom: Pose,
    role: GeomRole,
    base_dir: &Path,
    meshes: &mut MeshCache,
) -> Result<AssetGeom, String> {
    let f = |x: f64| x as f32;
    Ok(match geometry {
        urdf_rs::Geometry::Box { size } => AssetGeom::primitive(PrimitiveKind::Cuboid, vec3(size), world_from_geom, role),
        urdf_rs::Geometry::Cylinder { radius, length } => {
            AssetGeom::primitive(PrimitiveKind::Cylinder, Vec3::new(2.0 * f(*radius), 2.0 * f(*radius), f(*length)), world_from_geom, role)
        }
        urdf_rs::Geometry::Sphere { radius } => {
            AssetGeom::primitive(PrimitiveKind::Sphere, Vec3::splat(2.0 * f(*radius)), world_from_geom, role)
        }
        // URDF capsule length is the straight part; ours is the total length.
        urdf_rs::Geometry::Capsule { radius, length } => AssetGeom::primitive(
            PrimitiveKind::Capsule,
            Vec3::new(2.0 * f(*radius), 2.0 * f(*radius), f(*length) + 2.0 * f(*radius)),
            world_from_geom,
            role,
        ),
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let path = resolve_mesh_path(base_dir, filename)
                .ok_or_else(|| format!("mesh {filename:?} not found (looked in {})", base_dir.display()))?;
            if MeshFormat::from_path(&path).is_none() {
                return Err(format!("mesh {} has an unsupported format (OBJ, STL, MSH, GLB/glTF are read); geom skipped", path.display()));
            }
            let mesh = meshes.get(&path)?;
            let scale = scale.as_ref().map_or(Vec3::ONE, vec3);
            let scaled: Vec<Vec3> = mesh.vertices.iter().map(|&v| v * scale).collect();
            AssetGeom::mesh(&scaled, mesh.triangles.clone(), world_from_geom, role)
        }
    })
}

/// Where a URDF mesh reference points, if the file exists (see the module docs).
#[must_use]
pub fn resolve_mesh_path(base_dir: &Path, filename: &str) -> Option<PathBuf> {
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(rest) = filename.strip_prefix("package://") {
        let without_package = rest.split_once('/').map(|(_, r)| r);
        for dir in base_dir.ancestors().take(3) {
            candidates.push(dir.join(rest));
            if let Some(r) = without_package {
                candidates.push(dir.join(r));
            }
        }
    } else {
        let plain = filename.strip_prefix("file://").unwrap_or(filename);
        candidates.push(base_dir.join(plain));
    }
    candidates.into_iter().find(|p| p.is_file())
}

/// Replaces commas by spaces inside vector attribute values; returns the text and how many
/// attributes were changed. Errors if the text is not well-formed XML.
pub fn normalise_vector_commas(text: &str, path: &Path) -> Result<(String, usize), AssetError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| AssetError::Xml { path: path.to_path_buf(), message: e.to_string() })?;
    let mut ranges = Vec::new();
    for node in doc.descendants().filter(roxmltree::Node::is_element) {
        for attr in node.attributes() {
            if VECTOR_ATTRIBUTES.contains(&attr.name()) && attr.value().contains(',') {
                ranges.push(attr.range_value());
            }
        }
    }
    let mut bytes = text.as_bytes().to_vec();
    for range in &ranges {
        for b in &mut bytes[range.clone()] {
            if *b == b',' {
                *b = b' ';
            }
        }
    }
    // Only ASCII commas were replaced by ASCII spaces, so the text is still UTF-8.
    let normalised = String::from_utf8(bytes).map_err(|e| AssetError::Xml { path: path.to_path_buf(), message: e.to_string() })?;
    Ok((normalised, ranges.len()))
}
