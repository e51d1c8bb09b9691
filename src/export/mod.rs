//! Exports of the interactive scene. File-format types stay in here.

mod scene_json;
mod urdf;

pub use scene_json::{SCENE_FORMAT, SceneJsonError, read_scene_json, scene_from_json, scene_json};
pub use urdf::{UrdfConfig, UrdfError, link_name, scene_urdf, scene_urdf_robot};

use std::path::{Path, PathBuf};

use crate::model::SceneModel;

/// Why the scene files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
}

/// Writes `scene.urdf` and `scene.json` into `dir` (created if missing), each atomically.
/// Returns the paths written.
pub fn write_scene_files(dir: &Path, scene: &SceneModel, cfg: &UrdfConfig) -> Result<[PathBuf; 2], ExportError> {
    std::fs::create_dir_all(dir).map_err(|e| crate::io::IoError::new(dir, "create", e))?;
    let urdf_path = dir.join("scene.urdf");
    let json_path = dir.join("scene.json");
    crate::io::atomic_write(&urdf_path, scene_urdf(scene, cfg)?.as_bytes())?;
    crate::io::atomic_write(&json_path, scene_json(scene).as_bytes())?;
    Ok([urdf_path, json_path])
}
