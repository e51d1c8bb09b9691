//! `scene.srdf` and `objects/<name>.srdf`: the self-collision filter of the `MoveIt`/SAPIEN
//! convention (`<disable_collisions link1 link2 reason>`), for links that are parent and child
//! (`Adjacent`) or touch at rest (`Default`), from [`super::clearance::collision_set`]. And
//! `scene_objects.json`: which file holds each object, where it stands and what holds it up.

use std::collections::BTreeMap;

use serde::Serialize;

use super::clearance::CollisionSet;
use super::urdf::{link_name, object_name};
use super::xml::XmlWriter;
use crate::model::SceneModel;
use crate::scan::{ObjectId, PartId};

/// The SRDF of robot `robot_name` listing the pairs of `collisions` for which `keep` holds.
#[must_use]
pub fn srdf(scene: &SceneModel, robot_name: &str, collisions: &CollisionSet, keep: impl Fn(PartId, PartId) -> bool) -> String {
    let names: BTreeMap<PartId, String> = scene.parts.iter().map(|p| (p.id, link_name(scene, p))).collect();
    let mut xml = XmlWriter::new();
    xml.comment(
        " partscene: collision pairs a planner or simulator should ignore: links joined by a joint (Adjacent) and links \
         touching in the rest pose (Default). The URDF's collision shapes already keep 'collision_clearance_m' apart where \
         such parts touch. ",
    );
    xml.open("robot", &[("name", robot_name.to_owned())]);
    for &(a, b, dist_m) in &collisions.unresolved {
        let (Some(na), Some(nb)) = (names.get(&a), names.get(&b)) else { continue };
        if keep(a, b) {
            let dropped = [(a, na), (b, nb)].into_iter().find(|(id, _)| collisions.without_collision.contains(id));
            let note = dropped.map_or(String::new(), |(_, n)| format!("; the URDF gives {n} no collision shape"));
            xml.comment(&format!(
                " in contact at rest or as a joint moves ({:.1} mm deep; trimming would cut too much{note}): {na} {nb} ",
                -dist_m * 1000.0
            ));
        }
    }
    for &(a, b, reason) in &collisions.disabled {
        let (Some(na), Some(nb)) = (names.get(&a), names.get(&b)) else { continue };
        if keep(a, b) {
            xml.empty("disable_collisions", &[("link1", na.clone()), ("link2", nb.clone()), ("reason", reason.srdf_name().to_owned())]);
        }
    }
    xml.close();
    xml.finish()
}

/// The format tag of `scene_objects.json`.
pub const SCENE_OBJECTS_FORMAT: &str = "partscene-scene-objects/1";

/// One entry of `scene_objects.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ObjectEntry {
    pub id: ObjectId,
    /// Robot name and file stem.
    pub name: String,
    pub category: String,
    /// Paths relative to the folder of `scene_objects.json`.
    pub urdf: String,
    pub srdf: String,
    /// The object's own MJCF (`MuJoCo`), body names as in the URDF.
    pub mjcf: String,
    /// The object's root link (its frame is the object's frame).
    pub root_link: String,
    /// The object frame in the world: position (m) and a rotation, which is always the identity
    /// (link frames are world-aligned); given as xyzw quaternion and URDF roll-pitch-yaw.
    pub world_xyz: [f32; 3],
    pub world_quat_xyzw: [f32; 4],
    pub world_rpy: [f32; 3],
    /// The object and link it stands on; `null` on the floor.
    pub supported_by: Option<Support>,
    pub movable_joints: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct Support {
    pub object: ObjectId,
    pub link: String,
}

#[derive(Serialize)]
struct ObjectsFile<'a> {
    format: &'static str,
    objects: &'a [ObjectEntry],
}

/// The entries of `scene_objects.json`, in object id order (objects without parts are left out).
#[must_use]
pub fn object_entries(scene: &SceneModel, objects_dir: &str) -> Vec<ObjectEntry> {
    scene
        .objects
        .iter()
        .filter_map(|obj| {
            let root = scene.part(obj.root_part).or_else(|| scene.parts.iter().find(|p| p.object == obj.id))?;
            let name = object_name(scene, obj.id);
            let origin = super::tree::link_origin(scene, root);
            let supported_by = obj
                .supported_by_part
                .and_then(|p| scene.part(p))
                .filter(|p| p.object != obj.id)
                .map(|p| Support { object: p.object, link: link_name(scene, p) });
            let movable_joints =
                scene.joints.iter().filter(|j| j.kind.is_movable() && scene.part(j.child).is_some_and(|p| p.object == obj.id)).count();
            Some(ObjectEntry {
                id: obj.id,
                urdf: format!("{objects_dir}/{name}.urdf"),
                srdf: format!("{objects_dir}/{name}.srdf"),
                mjcf: format!("{objects_dir}/{name}.xml"),
                name,
                category: obj.category.clone(),
                root_link: link_name(scene, root),
                world_xyz: origin.to_array(),
                world_quat_xyzw: [0.0, 0.0, 0.0, 1.0],
                world_rpy: [0.0, 0.0, 0.0],
                supported_by,
                movable_joints,
            })
        })
        .collect()
}

/// `scene_objects.json` as text.
pub fn scene_objects_json(entries: &[ObjectEntry]) -> Result<String, serde_json::Error> {
    let mut text = serde_json::to_string_pretty(&ObjectsFile { format: SCENE_OBJECTS_FORMAT, objects: entries })?;
    text.push('\n');
    Ok(text)
}
