//! Exports of the interactive scene. File-format types stay in here.

mod scene_json;
mod urdf;

pub use scene_json::{SCENE_FORMAT, SceneJsonError, read_scene_json, scene_from_json, scene_json};
pub use urdf::{UrdfConfig, UrdfError, link_name, scene_urdf, scene_urdf_robot};
