//! Part-segmented scans (`../shared/spec/scan-format.md`): the in-memory type, and the only place
//! that reads or writes them (PLY + labels JSON).

use std::collections::BTreeMap;

use crate::math::Vec3;

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

#[derive(Clone, Debug, PartialEq)]
pub struct ScanObject {
    pub id: ObjectId,
    pub category: String,
}

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
    #[must_use]
    pub fn point_count(&self) -> usize {
        self.background.len() + self.parts.iter().map(|p| p.points.len()).sum::<usize>()
    }

    #[must_use]
    pub fn part(&self, id: PartId) -> Option<&ScanPart> {
        self.parts.binary_search_by_key(&id, |p| p.id).ok().map(|i| &self.parts[i])
    }

    #[must_use]
    pub fn category(&self, object: ObjectId) -> &str {
        self.objects.get(&object).map_or("object", |o| o.category.as_str())
    }
}
