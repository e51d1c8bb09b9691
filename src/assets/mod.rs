//! Importing articulated objects made by other projects (URDF, MJCF) into one in-memory model
//! ([`ArticulatedAsset`]) at rest, in the model root frame: links with their geometry, joints
//! with world axes and hinge points. The groundwork for scanning such objects virtually and
//! comparing reconstructions with their own annotation.
//!
//! - [`urdf`]: `urdf-rs` after a tolerant pre-pass (vectors written with commas), forward
//!   kinematics at q = 0, meshes relative to the URDF's folder.
//! - [`mjcf`]: `MuJoCo` XML via `roxmltree`: includes, default classes, compiler angle units.
//! - [`mesh`]: OBJ, STL and `MuJoCo` `.msh` meshes.
//!
//! Missing or unreadable meshes, unsupported geoms and joint types are warnings in
//! [`ArticulatedAsset::warnings`]; malformed XML, bad numbers and broken structure are errors
//! naming the file (and element and attribute).

pub mod mesh;
pub mod mjcf;
pub mod model;
pub mod urdf;

use std::path::{Path, PathBuf};

use thiserror::Error;

pub use model::{ArticulatedAsset, AssetGeom, AssetJoint, AssetLink, GeomRole, GeomShape};

/// Why an asset could not be read.
#[derive(Debug, Error)]
pub enum AssetError {
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// Not well-formed XML (or not UTF-8).
    #[error("{}: not well-formed XML: {message}", path.display())]
    Xml { path: PathBuf, message: String },
    /// `urdf-rs` rejected the (normalised) document.
    #[error("{}: not a valid URDF: {message}", path.display())]
    Urdf { path: PathBuf, message: String },
    /// An attribute that could not be parsed.
    #[error("{}:{line}: <{element}> attribute `{attribute}` = {value:?}: expected {expected}", path.display())]
    BadAttribute { path: PathBuf, line: u32, element: String, attribute: String, value: String, expected: String },
    /// The model is inconsistent: a joint names an unknown link, includes loop, no root element.
    #[error("{}: {message}", path.display())]
    Structure { path: PathBuf, message: String },
    /// A mesh file that could not be decoded.
    #[error("{}: cannot read mesh: {message}", path.display())]
    Mesh { path: PathBuf, message: String },
    /// Neither `.urdf` nor `.xml`.
    #[error("{}: unknown asset format (expected .urdf or MJCF .xml)", path.display())]
    UnknownFormat { path: PathBuf },
}

/// Reads an articulated asset, choosing the reader by extension: `.urdf` → [`urdf::load_urdf`],
/// `.xml` / `.mjcf` → [`mjcf::load_mjcf`].
pub fn load_asset(path: &Path) -> Result<ArticulatedAsset, AssetError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("urdf") => urdf::load_urdf(path),
        Some("xml" | "mjcf") => mjcf::load_mjcf(path),
        _ => Err(AssetError::UnknownFormat { path: path.to_path_buf() }),
    }
}

/// Reads a text file, with errors naming it.
fn read_text(path: &Path) -> Result<String, AssetError> {
    let bytes = crate::io::read_bytes(path)?;
    String::from_utf8(bytes).map_err(|e| AssetError::Xml { path: path.to_path_buf(), message: format!("not UTF-8: {e}") })
}

/// Loads a mesh once per path (the same file is often referenced by several geoms).
#[derive(Default)]
struct MeshCache {
    loaded: std::collections::BTreeMap<PathBuf, Result<mesh::TriMesh, String>>,
}

impl MeshCache {
    fn get(&mut self, path: &Path) -> Result<&mesh::TriMesh, String> {
        self.loaded
            .entry(path.to_path_buf())
            .or_insert_with(|| mesh::load_mesh(path).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(Clone::clone)
    }
}
