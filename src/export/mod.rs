//! Exports of the interactive scene. File-format types stay in here.
//!
//! `scene.urdf` ([`scene_urdf`]), `scene.json` ([`scene_json`]), `scene.mjcf.xml` for `MuJoCo`
//! ([`scene_mjcf`], optionally with the reality-gap module's fitted joint dynamics) and
//! `scene.glb` for any glTF viewer ([`scene_glb`]) and `scene.usda` for Isaac Sim ([`scene_usda`],
//! `UsdPhysics`, fitted dynamics too) all share link names ([`link_name`]) and the
//! kinematic tree (`tree.rs`). Beside them: `scene.srdf` (self-collision filter, [`srdf`]),
//! `objects/<name>.urdf` + `.srdf` + `.xml` (one articulation per object, [`object_urdf`], [`object_mjcf`]) and
//! `scene_objects.json` ([`object_entries`]). Collision shapes keep a clearance where parts that
//! are not parent and child touch ([`collision_set`]).

mod check_urdf;
mod clearance;
mod gltf;
mod mjcf;
mod scene_json;
mod srdf;
mod tree;
mod urdf;
mod usd;
mod xml;

pub use check_urdf::{UrdfCheck, check_urdf, check_urdf_file};
pub use clearance::{CollisionSet, DisableReason, MAX_TRIM_M, MAX_TRIM_SHARE, collision_set};
pub use srdf::{ObjectEntry, SCENE_OBJECTS_FORMAT, Support, object_entries, scene_objects_json, srdf};

pub use gltf::{GltfError, scene_glb};
pub use mjcf::{
    DynamicsTable, FittedEffect, JointDynamics, MjcfError, dynamics_from_effects, fitted_effects_from_json, joint_name, object_mjcf,
    read_fitted_effects, scene_mjcf,
};
pub use scene_json::{SCENE_FORMAT, SceneJsonError, read_scene_json, scene_from_json, scene_json};
pub use urdf::{
    UrdfConfig, UrdfError, label_color, link_name, object_name, object_urdf, object_urdf_robot, robot_to_string, scene_urdf,
    scene_urdf_robot,
};
pub use usd::{USD_ROOT, UsdError, scene_usda};

use std::path::{Path, PathBuf};

use crate::model::SceneModel;

/// Why the scene files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    #[error(transparent)]
    Mjcf(#[from] MjcfError),
    #[error(transparent)]
    Gltf(#[from] GltfError),
    #[error(transparent)]
    Usd(#[from] UsdError),
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    #[error("cannot write scene_objects.json: {0}")]
    Json(#[from] serde_json::Error),
}

/// The folder, beside `scene.urdf`, that holds one URDF and SRDF per object.
pub const OBJECTS_DIR: &str = "objects";

/// The files [`write_scene_files`] writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneFiles {
    /// `scene.urdf`.
    pub urdf: PathBuf,
    /// `scene.json`.
    pub json: PathBuf,
    /// `scene.mjcf.xml`.
    pub mjcf: PathBuf,
    /// `scene.glb`.
    pub glb: PathBuf,
    /// `scene.usda`: text USD with `UsdPhysics`, one articulation per object.
    pub usd: PathBuf,
    /// `scene.srdf`: the self-collision filter of `scene.urdf`.
    pub srdf: PathBuf,
    /// `scene_objects.json`: each object's file, world pose and support.
    pub objects_json: PathBuf,
    /// `objects/<name>.urdf`, `.srdf` and `.xml` (MJCF), per object, in object order.
    pub objects: Vec<PathBuf>,
}

impl SceneFiles {
    /// All paths, in the order written.
    #[must_use]
    pub fn all(&self) -> Vec<&Path> {
        let mut out: Vec<&Path> = vec![&self.urdf, &self.json, &self.mjcf, &self.glb, &self.usd, &self.srdf, &self.objects_json];
        out.extend(self.objects.iter().map(PathBuf::as_path));
        out
    }
}

/// Writes `scene.urdf`, `scene.srdf`, `scene.json`, `scene.mjcf.xml` and `scene.usda` (no fitted
/// dynamics), `scene.glb`, and per object `objects/<name>.urdf` + `.srdf` + `.xml` with `scene_objects.json`, into
/// `dir` (created if missing), each atomically. Returns the paths written.
pub fn write_scene_files(dir: &Path, scene: &SceneModel, cfg: &UrdfConfig) -> Result<SceneFiles, ExportError> {
    let objects_dir = dir.join(OBJECTS_DIR);
    std::fs::create_dir_all(&objects_dir).map_err(|e| crate::io::IoError::new(&objects_dir, "create", e))?;
    // Build everything before writing anything, so a failing format leaves no half set.
    let collisions = collision_set(scene, cfg.collision_clearance_m);
    let urdf = urdf::scene_urdf_with(scene, cfg, &collisions)?;
    let mjcf = mjcf::scene_mjcf_with(scene, cfg, &DynamicsTable::new(), &collisions)?;
    let glb = scene_glb(scene)?;
    let usd = usd::scene_usda_with(scene, cfg, &DynamicsTable::new(), &collisions)?;
    let scene_srdf = srdf(scene, "partscene", &collisions, |_, _| true);
    let entries = object_entries(scene, OBJECTS_DIR);
    let objects_json = scene_objects_json(&entries)?;
    let mut per_object = Vec::new();
    for entry in &entries {
        let Some(text) = urdf::object_urdf_with(scene, entry.id, cfg, &collisions)? else { continue };
        let in_object = |id| scene.part(id).is_some_and(|p| p.object == entry.id);
        let object_srdf = srdf(scene, &entry.name, &collisions, |a, b| in_object(a) && in_object(b));
        per_object.push((dir.join(&entry.urdf), text));
        per_object.push((dir.join(&entry.srdf), object_srdf));
        if let Some(xml) = object_mjcf(scene, entry.id, cfg, &DynamicsTable::new(), &collisions)? {
            per_object.push((dir.join(&entry.mjcf), xml));
        }
    }
    let files = SceneFiles {
        urdf: dir.join("scene.urdf"),
        json: dir.join("scene.json"),
        mjcf: dir.join("scene.mjcf.xml"),
        glb: dir.join("scene.glb"),
        usd: dir.join("scene.usda"),
        srdf: dir.join("scene.srdf"),
        objects_json: dir.join("scene_objects.json"),
        objects: per_object.iter().map(|(p, _)| p.clone()).collect(),
    };
    crate::io::atomic_write(&files.urdf, urdf.as_bytes())?;
    crate::io::atomic_write(&files.json, scene_json(scene).as_bytes())?;
    crate::io::atomic_write(&files.mjcf, mjcf.as_bytes())?;
    crate::io::atomic_write(&files.glb, &glb)?;
    crate::io::atomic_write(&files.usd, usd.as_bytes())?;
    crate::io::atomic_write(&files.srdf, scene_srdf.as_bytes())?;
    for (path, text) in &per_object {
        crate::io::atomic_write(path, text.as_bytes())?;
    }
    crate::io::atomic_write(&files.objects_json, objects_json.as_bytes())?;
    Ok(files)
}
