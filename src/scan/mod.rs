//! Part-segmented scans (`../shared/spec/scan-format.md`): the in-memory type, and the only place
//! that reads or writes them (PLY + labels JSON; `NumPy` `.npz` archives are read too, see `npz.rs`).

use std::collections::BTreeMap;

use crate::math::Vec3;

mod error;
mod labels;
mod npy;
mod npz;
#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod npz_tests;
mod ply;
mod read;
#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod tests;
mod write;

pub use error::ScanError;
pub use labels::labels_json;
pub use npz::MAX_INFLATED_BYTES;
pub use ply::MAX_COORDINATE_M;
/// PLY helpers shared with the mesh importers (`crate::import`).
pub(crate) use ply::{check_element_length, one_line, type_name};
pub use read::{
    ScanArrays, UNASSIGNED, UNKNOWN_CATEGORY, UNKNOWN_LABEL, is_npz_path, read_scan, read_scan_bytes, read_scan_npz_bytes, scan_from_arrays,
};
pub use write::{scan_to_ply_bytes, write_scan};

/// A part instance id as written in the scan (`part` property); unique in the file.
pub type PartId = i64;
/// An object instance id (`object` property).
pub type ObjectId = i64;

/// A scan, grouped by part.
#[derive(Clone, Debug, Default)]
pub struct Scan {
    /// Where it came from (a path, or "demo seed 0").
    pub source: String,
    /// Parts, sorted by id.
    pub parts: Vec<ScanPart>,
    /// Objects by id with their category.
    pub objects: BTreeMap<ObjectId, ScanObject>,
    /// Points with no part (part = -1): floor, walls, clutter.
    pub background: Vec<Vec3>,
}

/// An object instance and its category (from the labels `objects` map).
#[derive(Clone, Debug, PartialEq)]
pub struct ScanObject {
    pub id: ObjectId,
    /// `cabinet`, `chair`, ...; "object" when the labels do not say.
    pub category: String,
}

/// The points of one part instance.
#[derive(Clone, Debug)]
pub struct ScanPart {
    pub id: PartId,
    pub object: ObjectId,
    /// Coarse semantic word (`drawer`, `door`, `leg`, ...); unknown words are kept.
    pub label: String,
    pub points: Vec<Vec3>,
    /// Per-point normals when the scan has them.
    pub normals: Option<Vec<Vec3>>,
}

impl Scan {
    /// All points: parts and background.
    #[must_use]
    pub fn point_count(&self) -> usize {
        self.background.len() + self.parts.iter().map(|p| p.points.len()).sum::<usize>()
    }

    /// The part with this id (parts are sorted by id).
    #[must_use]
    pub fn part(&self, id: PartId) -> Option<&ScanPart> {
        self.parts.binary_search_by_key(&id, |p| p.id).ok().map(|i| &self.parts[i])
    }

    /// The object's category, "object" when unknown.
    #[must_use]
    pub fn category(&self, object: ObjectId) -> &str {
        self.objects.get(&object).map_or("object", |o| o.category.as_str())
    }
}
