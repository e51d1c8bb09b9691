//! Exports of the interactive scene. File-format types stay in here.
//!
//! `scene.urdf` ([`scene_urdf`]), `scene.json` ([`scene_json`]), `scene.mjcf.xml` for `MuJoCo`
//! ([`scene_mjcf`], optionally with the reality-gap module's fitted joint dynamics) and
//! `scene.glb` for any glTF viewer ([`scene_glb`]) all share link names ([`link_name`]) and the
//! kinematic tree (`tree.rs`).

mod gltf;
mod mjcf;
mod scene_json;
mod tree;
mod urdf;
mod xml;

pub use gltf::{GltfError, scene_glb};
pub use mjcf::{
    DynamicsTable, FittedEffect, JointDynamics, MjcfError, dynamics_from_effects, fitted_effects_from_json, joint_name,
    read_fitted_effects, scene_mjcf,
};
pub use scene_json::{SCENE_FORMAT, SceneJsonError, read_scene_json, scene_from_json, scene_json};
pub use urdf::{UrdfConfig, UrdfError, label_color, link_name, scene_urdf, scene_urdf_robot};

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
    Io(#[from] crate::io::IoError),
}

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
}

impl SceneFiles {
    /// All paths, in the order written.
    #[must_use]
    pub fn all(&self) -> [&Path; 4] {
        [&self.urdf, &self.json, &self.mjcf, &self.glb]
    }
}

/// Writes `scene.urdf`, `scene.json`, `scene.mjcf.xml` (no fitted dynamics) and `scene.glb` into
/// `dir` (created if missing), each atomically. Returns the paths written.
pub fn write_scene_files(dir: &Path, scene: &SceneModel, cfg: &UrdfConfig) -> Result<SceneFiles, ExportError> {
    std::fs::create_dir_all(dir).map_err(|e| crate::io::IoError::new(dir, "create", e))?;
    let files = SceneFiles {
        urdf: dir.join("scene.urdf"),
        json: dir.join("scene.json"),
        mjcf: dir.join("scene.mjcf.xml"),
        glb: dir.join("scene.glb"),
    };
    // Build everything before writing anything, so a failing format leaves no half set.
    let urdf = scene_urdf(scene, cfg)?;
    let mjcf = scene_mjcf(scene, cfg, &DynamicsTable::new())?;
    let glb = scene_glb(scene)?;
    crate::io::atomic_write(&files.urdf, urdf.as_bytes())?;
    crate::io::atomic_write(&files.json, scene_json(scene).as_bytes())?;
    crate::io::atomic_write(&files.mjcf, mjcf.as_bytes())?;
    crate::io::atomic_write(&files.glb, &glb)?;
    Ok(files)
}
