//! Errors of reading and writing scans. Every message names the file and what was expected.

use thiserror::Error;

use super::PartId;
use crate::io::IoError;

/// Why a scan could not be read or written.
#[derive(Debug, Error)]
pub enum ScanError {
    /// The file could not be read or written.
    #[error(transparent)]
    Io(#[from] IoError),

    /// Not a PLY file, or its header cannot be parsed.
    #[error(
        "{file}: not a PLY file or unreadable header (expected a `ply` line, a `format ascii|binary_little_endian|binary_big_endian 1.0` line, element and property lines, and `end_header`): {detail}"
    )]
    Header { file: String, detail: String },

    /// The header declares no `vertex` element.
    #[error("{file}: no `vertex` element in the PLY header (found elements: {found}); expected `element vertex N`")]
    NoVertexElement { file: String, found: String },

    /// A required vertex property is not declared.
    #[error("{file}: the vertex element has no property `{property}`; expected x, y, z (float or double), object and part (integer)")]
    MissingProperty { file: String, property: &'static str },

    /// A vertex property has a type the format does not allow (a float id, a list coordinate).
    #[error("{file}: vertex property `{property}` has type {found}; expected {expected}")]
    PropertyType { file: String, property: String, found: String, expected: &'static str },

    /// The header declares zero vertices.
    #[error("{file}: the PLY has 0 vertices (an empty scan); expected at least one point")]
    Empty { file: String },

    /// A coordinate is NaN or infinite (or a double beyond the `f32` range).
    #[error("{file}: vertex {vertex} has a non-finite `{property}` ({value}); expected finite coordinates within the f32 range")]
    NonFinite { file: String, vertex: usize, property: String, value: String },

    /// A coordinate is finite but beyond any room (see `scan::ply::MAX_COORDINATE_M`).
    #[error(
        "{file}: vertex {vertex} has `{property}` = {value:e} m; expected |{property}| <= {limit:e} m (a room-scale scan; check the units)"
    )]
    OutOfRange { file: String, vertex: usize, property: String, value: f32, limit: f32 },

    /// The body ends before all declared elements were read.
    #[error("{file}: the PLY body is truncated: {detail}")]
    Truncated { file: String, detail: String },

    /// The body cannot be parsed (a bad ascii number, a wrong count of values on a line, ...).
    #[error("{file}: malformed PLY body at {at}: {detail}")]
    Body { file: String, at: String, detail: String },

    /// The labels file is not valid JSON of the expected shape.
    #[error(
        "{file}: malformed labels JSON (expected {{\"objects\": {{\"ID\": {{\"category\": \"...\"}}}}, \"parts\": {{\"ID\": {{\"object\": ID, \"label\": \"...\"}}}}}}): {source}"
    )]
    LabelsJson {
        file: String,
        #[source]
        source: serde_json::Error,
    },

    /// A key of the labels `objects` or `parts` map is not a decimal integer.
    #[error("{file}: key \"{key}\" in `{section}` is not an integer id; expected a decimal string like \"17\"")]
    LabelKey { file: String, section: &'static str, key: String },

    /// The labels name a part that has no points in the PLY.
    #[error(
        "{file}: the labels name part {part}, which is not in the scan {ply}; expected only part ids that occur in the scan's `part` property (PLY) or `part_ids` array (.npz)"
    )]
    UnknownLabelPart { file: String, part: PartId, ply: String },

    /// Not a zip archive, or a member of it cannot be read.
    #[error("{file}: not a readable NumPy .npz archive (a zip of .npy arrays, as numpy.savez writes): {detail}")]
    Npz { file: String, detail: String },

    /// A required array is not in the archive.
    #[error("{file}: no array `{array}` in the .npz (it holds: {found}); expected {expected}")]
    NpzMissingArray { file: String, array: &'static str, found: String, expected: &'static str },

    /// An array has the wrong dtype, shape or length, or holds a value that cannot be used.
    #[error("{file}: array `{array}` {detail}; expected {expected}")]
    NpzArray { file: String, array: String, detail: String, expected: String },

    /// A point coordinate is NaN or infinite (or a float64 beyond the `f32` range).
    #[error("{file}: array `points` row {row} has a non-finite {axis} ({value}); expected finite coordinates within the f32 range")]
    NpzNonFinite { file: String, row: usize, axis: &'static str, value: String },

    /// A point coordinate is beyond any room (see `scan::ply::MAX_COORDINATE_M`).
    #[error(
        "{file}: array `points` row {row} has {axis} = {value:e} m; expected |{axis}| <= {limit:e} m (a room-scale scan; check the units)"
    )]
    NpzOutOfRange { file: String, row: usize, axis: &'static str, value: f64, limit: f32 },

    /// Labels both inside the archive and in a labels file beside it.
    #[error(
        "{file}: the archive holds labels (`label_part_ids`/`label_names` or `category_object_ids`/`category_names`) and {labels} exists beside it; expected one source of labels (remove one)"
    )]
    LabelsTwice { file: String, labels: String },

    /// A scan to be written has an id the PLY `int` type cannot hold.
    #[error("{file}: cannot write {what} {id}; expected ids within the 32-bit signed range")]
    IdOutOfRange { file: String, what: &'static str, id: i64 },

    /// A scan to be written has a non-finite point.
    #[error("{file}: cannot write part {part}: point {index} is not finite; expected finite coordinates")]
    NonFinitePoint { file: String, part: PartId, index: usize },
}
