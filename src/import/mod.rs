//! Importing scans made by others into the scan format (`../shared/spec/scan-format.md`) plus
//! ground truth (`gt.json`, [`crate::truth`]), so that `partscene reconstruct` and `eval` run on
//! real, annotated scans.
//!
//! - [`multiscan`]: `MultiScan` (Mao et al., `NeurIPS` 2022 datasets track): an annotated mesh PLY
//!   with per-face `objectId`/`partId` and `scanId.annotations.json` (part labels, parents and
//!   articulations) → points sampled on the faces, labels, truth joints.
//!
//! `face_ply.rs` reads triangle meshes whose faces carry integer ids; `sample.rs` draws seeded,
//! area-weighted points on triangles.

mod face_ply;
pub mod multiscan;
mod multiscan_annotations;
mod sample;
#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod tests;

use thiserror::Error;

use crate::io::IoError;
use crate::scan::ScanError;

pub use face_ply::{FaceMesh, MeshFace, OBJECT_ID, PART_ID, read_face_mesh};
pub use sample::sample_triangles;

/// Why an import failed. Every message names the file (or folder) and what was expected.
#[derive(Debug, Error)]
pub enum ImportError {
    #[error(transparent)]
    Io(#[from] IoError),

    /// A PLY problem shared with the scan reader (truncated body, element counts).
    #[error(transparent)]
    Scan(#[from] ScanError),

    /// The input folder does not hold what the importer needs.
    #[error("{dir}: {detail}")]
    Folder { dir: String, detail: String },

    /// The mesh PLY's header or body cannot be used.
    #[error("{file}: {detail}")]
    Ply { file: String, detail: String },

    /// A vertex coordinate is not finite or beyond any room.
    #[error("{file}: vertex {vertex} has {axis} = {value}; expected a finite coordinate with |{axis}| <= {limit:e} m")]
    Vertex { file: String, vertex: usize, axis: &'static str, value: f64, limit: f32 },

    /// A face refers to a vertex that does not exist, or has an id out of range.
    #[error("{file}: face {face}: {detail}")]
    Face { file: String, face: usize, detail: String },

    /// The annotations file is not JSON of the documented shape.
    #[error(
        "{file}: malformed MultiScan annotations (expected {{\"objects\": [{{\"objectId\", \"label\", \"partIds\", ...}}], \"parts\": [{{\"partId\", \"label\", \"parentId\"?, \"articulations\"?}}]}}): {source}"
    )]
    AnnotationsJson {
        file: String,
        #[source]
        source: serde_json::Error,
    },

    /// A field of the annotations has a value that cannot be used.
    #[error("{file}: `{field}`: {detail}")]
    Annotation { file: String, field: String, detail: String },

    /// Writing the ground truth failed to serialise.
    #[error("{file}: cannot write ground truth: {source}")]
    Json {
        file: String,
        #[source]
        source: serde_json::Error,
    },
}
