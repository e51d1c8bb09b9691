//! Reading a scan: the PLY's vertices (or the `.npz` arrays) grouped by part, with the labels.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;

use super::error::ScanError;
use super::labels::{Labels, PartLabel, parse_labels};
use super::npz::read_npz;
use super::ply::{RawVertex, read_vertices};
use super::{ObjectId, PartId, Scan, ScanObject, ScanPart};
use crate::math::Vec3;
use crate::report::Warning;

/// The part (and object) id of points with no part: background, floor, walls, clutter.
pub const UNASSIGNED: i64 = -1;

/// Label of a part the labels file does not name.
pub const UNKNOWN_LABEL: &str = "unknown";

/// Category of an object the labels file does not name.
pub const UNKNOWN_CATEGORY: &str = "object";

/// Reads a scan, `NAME.ply` or `NAME.npz` (`NumPy` arrays, see [`read_scan_npz_bytes`]), and the
/// labels `NAME.json` beside it (see [`read_scan_bytes`] for the rules). A missing labels file is a
/// warning, not an error.
pub fn read_scan(path: &Path) -> Result<(Scan, Vec<Warning>), ScanError> {
    let bytes = crate::io::read_bytes(path)?;
    let labels_path = path.with_extension("json");
    let labels = crate::io::read_optional_string(&labels_path)?;
    let (name, labels_name) = (path.display().to_string(), labels_path.display().to_string());
    if is_npz_path(path) {
        read_scan_npz_bytes(&bytes, &name, labels.as_deref(), &labels_name)
    } else {
        read_scan_bytes(&bytes, &name, labels.as_deref(), &labels_name)
    }
}

/// Whether a scan path names a `NumPy` archive (`.npz`, any case) rather than a PLY.
#[must_use]
pub fn is_npz_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("npz"))
}

/// Reads a scan from memory: `ply` is the PLY file, `labels_json` the labels file (`None` when it
/// does not exist); the names are used in errors, warnings and `Scan::source`.
///
/// Points with part -1 (or any negative part id, with a warning) go to `background`; parts are sorted by id. A part's object is the labels'
/// `object` if given, else the majority `object` value of its points (a warning when they
/// disagree); a part whose object is -1 is reported and its points go to the background. Parts
/// without a label get "unknown", objects without a category "object" (each with a warning).
pub fn read_scan_bytes(
    ply: &[u8],
    ply_name: &str,
    labels_json: Option<&str>,
    labels_name: &str,
) -> Result<(Scan, Vec<Warning>), ScanError> {
    let mut warnings = Vec::new();
    let ply_data = read_vertices(ply, ply_name, &mut warnings)?;
    let labels = sidecar_labels(labels_json, labels_name, &mut warnings)?;
    assemble(&ply_data.vertices, ply_data.has_normals, labels.as_ref(), ply_name, labels_name, warnings)
}

/// Reads a `.npz` scan from memory (arrays `points`, `object_ids`, `part_ids`, optional
/// `normals` and label arrays: `scan::npz`), with the same rules as [`read_scan_bytes`]. Labels come
/// from the archive's label arrays or from `labels_json` (the file beside it), not both.
pub fn read_scan_npz_bytes(
    npz: &[u8],
    npz_name: &str,
    labels_json: Option<&str>,
    labels_name: &str,
) -> Result<(Scan, Vec<Warning>), ScanError> {
    let mut warnings = Vec::new();
    let data = read_npz(npz, npz_name)?;
    let (labels, labels_source) = match (data.labels, labels_json) {
        (Some(_), Some(_)) => return Err(ScanError::LabelsTwice { file: npz_name.to_owned(), labels: labels_name.to_owned() }),
        (Some(labels), None) => (Some(labels), format!("{npz_name} (label arrays)")),
        (None, json) => (sidecar_labels(json, labels_name, &mut warnings)?, labels_name.to_owned()),
    };
    assemble(&data.vertices, data.has_normals, labels.as_ref(), npz_name, &labels_source, warnings)
}

/// A scan held as arrays, one row per point (the Python binding's input): the arrays of a `.npz`
/// scan (`scan::npz`), already decoded.
#[derive(Clone, Copy, Debug)]
pub struct ScanArrays<'a> {
    /// x, y, z in metres, world frame, +z up.
    pub points: &'a [[f64; 3]],
    pub normals: Option<&'a [[f64; 3]]>,
    /// Object instance id per point; -1 = background.
    pub object_ids: &'a [i64],
    /// Part instance id per point; -1 = background.
    pub part_ids: &'a [i64],
    /// Part id → label (a part not named here is "unknown", with a warning).
    pub part_labels: &'a BTreeMap<PartId, String>,
    /// Object id → category.
    pub object_categories: &'a BTreeMap<ObjectId, String>,
}

/// Builds a scan from arrays with the rules of a `.npz` scan ([`read_scan_npz_bytes`]): as many
/// rows in every array, finite coordinates within `MAX_COORDINATE_M`, every labelled part in
/// the scan. `name` stands for the file in errors and becomes `Scan::source`.
pub fn scan_from_arrays(arrays: &ScanArrays, name: &str) -> Result<(Scan, Vec<Warning>), ScanError> {
    let n = arrays.points.len();
    let rows_error = |array: &str, rows: usize| ScanError::NpzArray {
        file: name.to_owned(),
        array: array.to_owned(),
        detail: format!("has {rows} rows, `points` has {n}"),
        expected: "one row per point".to_owned(),
    };
    if n == 0 {
        return Err(ScanError::NpzArray {
            file: name.to_owned(),
            array: "points".to_owned(),
            detail: "has 0 rows (an empty scan)".to_owned(),
            expected: "at least one point".to_owned(),
        });
    }
    for (array, rows) in [("object_ids", arrays.object_ids.len()), ("part_ids", arrays.part_ids.len())] {
        if rows != n {
            return Err(rows_error(array, rows));
        }
    }
    if let Some(normals) = arrays.normals.filter(|v| v.len() != n) {
        return Err(rows_error("normals", normals.len()));
    }
    let mut vertices = Vec::with_capacity(n);
    for (row, point) in arrays.points.iter().enumerate() {
        let mut v = RawVertex { object: arrays.object_ids[row], part: arrays.part_ids[row], ..RawVertex::default() };
        for axis in 0..3 {
            v.position[axis] = super::npz::checked_coordinate(point[axis], row, axis, name)?;
            if let Some(normals) = arrays.normals {
                v.normal[axis] = normals[row][axis] as f32;
            }
        }
        vertices.push(v);
    }
    let labels = Labels {
        objects: arrays.object_categories.iter().map(|(&id, c)| (id, Some(c.clone()))).collect(),
        parts: arrays.part_labels.iter().map(|(&id, l)| (id, PartLabel { object: None, label: Some(l.clone()) })).collect(),
    };
    let labels = (!labels.objects.is_empty() || !labels.parts.is_empty()).then_some(labels);
    let mut warnings = Vec::new();
    if labels.is_none() {
        warnings.push(Warning::new("scan", name, "no labels given: every part is labelled \"unknown\" and every object \"object\""));
    }
    assemble(&vertices, arrays.normals.is_some(), labels.as_ref(), name, &format!("{name} (labels)"), warnings)
}

/// The labels file beside a scan, parsed; a warning when there is none.
fn sidecar_labels(labels_json: Option<&str>, labels_name: &str, warnings: &mut Vec<Warning>) -> Result<Option<Labels>, ScanError> {
    if let Some(text) = labels_json {
        return parse_labels(text, labels_name).map(Some);
    }
    warnings.push(Warning::new(
        "scan",
        labels_name,
        "labels file not found: every part is labelled \"unknown\" and every object \"object\"",
    ));
    Ok(None)
}

/// Groups the points by part and applies the labels (`labels_name` names their source in errors).
fn assemble(
    vertices: &[RawVertex],
    has_normals: bool,
    labels: Option<&Labels>,
    scan_name: &str,
    labels_name: &str,
    mut warnings: Vec<Warning>,
) -> Result<(Scan, Vec<Warning>), ScanError> {
    let mut groups = group_by_part(vertices, has_normals, &mut warnings, scan_name);
    if let Some(labels) = labels
        && let Some(&part) = labels.parts.keys().find(|&&id| groups.parts.binary_search_by_key(&id, |g| g.id).is_err())
    {
        return Err(ScanError::UnknownLabelPart { file: labels_name.to_owned(), part, ply: scan_name.to_owned() });
    }

    let mut scan = Scan { source: scan_name.to_owned(), ..Scan::default() };
    scan.background = std::mem::take(&mut groups.background);
    for group in groups.parts.drain(..) {
        let Some(part) = build_part(group, labels, &mut warnings, &mut scan.background) else {
            continue;
        };
        scan.objects
            .entry(part.object)
            .or_insert_with(|| ScanObject { id: part.object, category: object_category(part.object, labels, &mut warnings) });
        scan.parts.push(part);
    }
    if scan.parts.is_empty() {
        warnings.push(Warning::new("scan", scan_name, "the scan has no parts: every point is background"));
    }
    Ok((scan, warnings))
}

/// The points of one part id as read, before labels are applied.
struct PartGroup {
    id: PartId,
    points: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// (object id, point count), in order of first appearance.
    object_votes: Vec<(ObjectId, usize)>,
}

struct Groups {
    /// Sorted by id.
    parts: Vec<PartGroup>,
    background: Vec<Vec3>,
}

fn group_by_part(vertices: &[RawVertex], has_normals: bool, warnings: &mut Vec<Warning>, ply_name: &str) -> Groups {
    let mut parts: Vec<PartGroup> = Vec::new();
    let mut index_of: HashMap<PartId, usize> = HashMap::new();
    let mut background = Vec::new();
    let mut other_negative: BTreeMap<PartId, usize> = BTreeMap::new();
    // Scans usually store a part's points together: remember the last part looked up.
    let mut last: Option<(PartId, usize)> = None;
    for v in vertices {
        let point = Vec3::from_array(v.position);
        if v.part < 0 {
            if v.part != UNASSIGNED {
                *other_negative.entry(v.part).or_default() += 1;
            }
            background.push(point);
            continue;
        }
        let index = match last {
            Some((id, i)) if id == v.part => i,
            _ => {
                let i = *index_of.entry(v.part).or_insert_with(|| {
                    parts.push(PartGroup { id: v.part, points: Vec::new(), normals: Vec::new(), object_votes: Vec::new() });
                    parts.len() - 1
                });
                last = Some((v.part, i));
                i
            }
        };
        let group = &mut parts[index];
        group.points.push(point);
        if has_normals {
            group.normals.push(Vec3::from_array(v.normal));
        }
        match group.object_votes.iter_mut().find(|(o, _)| *o == v.object) {
            Some((_, n)) => *n += 1,
            None => group.object_votes.push((v.object, 1)),
        }
    }
    if !other_negative.is_empty() {
        let mut list = String::new();
        for (id, n) in &other_negative {
            let _ = write!(list, "{}{id} ({n} points)", if list.is_empty() { "" } else { ", " });
        }
        warnings.push(Warning::new("scan", ply_name, format!("negative part ids other than -1 treated as background: {list}")));
    }
    // Part ids are unique, so an unstable sort is deterministic.
    parts.sort_unstable_by_key(|p| p.id);
    Groups { parts, background }
}

fn describe_votes(votes: &[(ObjectId, usize)]) -> String {
    votes.iter().map(|(o, n)| format!("{o} ({n} points)")).collect::<Vec<_>>().join(", ")
}

/// Applies the labels to one part; `None` (points moved to `background`) when its object is -1.
fn build_part(mut group: PartGroup, labels: Option<&Labels>, warnings: &mut Vec<Warning>, background: &mut Vec<Vec3>) -> Option<ScanPart> {
    let subject = format!("part {}", group.id);
    // Majority object of the points; ties go to an assigned id, then the smallest.
    group.object_votes.sort_by_key(|&(o, n)| (std::cmp::Reverse(n), o == UNASSIGNED, o));
    let majority = group.object_votes.first().map_or(UNASSIGNED, |&(o, _)| o);
    let entry = labels.and_then(|l| l.parts.get(&group.id));
    let object = if let Some(labelled) = entry.and_then(|e| e.object) {
        if group.object_votes.iter().any(|&(o, _)| o != labelled) {
            warnings.push(Warning::new(
                "scan",
                subject.as_str(),
                format!("the labels say object {labelled}, its points say {}; using {labelled}", describe_votes(&group.object_votes)),
            ));
        }
        labelled
    } else {
        if group.object_votes.len() > 1 {
            warnings.push(Warning::new(
                "scan",
                subject.as_str(),
                format!("its points disagree on the object: {}; using the majority, {majority}", describe_votes(&group.object_votes)),
            ));
        }
        majority
    };
    if object < 0 {
        warnings.push(Warning::new(
            "scan",
            subject,
            format!("belongs to object {object} (unassigned): its {} points are treated as background", group.points.len()),
        ));
        background.append(&mut group.points);
        return None;
    }
    let labelled = entry.and_then(|e| e.label.as_deref()).filter(|l| !l.trim().is_empty());
    let label = if let Some(l) = labelled {
        l.to_owned()
    } else {
        if labels.is_some() {
            warnings.push(Warning::new("scan", subject.as_str(), "no label in the labels file: using \"unknown\""));
        }
        UNKNOWN_LABEL.to_owned()
    };
    let normals = if group.normals.is_empty() {
        None
    } else if let Some(bad) = group.normals.iter().position(|n| !n.is_finite()) {
        warnings.push(Warning::new("scan", subject, format!("normal {bad} is not finite: the part's normals are dropped")));
        None
    } else {
        Some(group.normals)
    };
    Some(ScanPart { id: group.id, object, label, points: group.points, normals })
}

fn object_category(object: ObjectId, labels: Option<&Labels>, warnings: &mut Vec<Warning>) -> String {
    match labels.and_then(|l| l.objects.get(&object)) {
        Some(Some(category)) if !category.trim().is_empty() => category.clone(),
        found => {
            if labels.is_some() {
                let why = if found.is_some() { "has no category" } else { "is not in the labels file" };
                warnings.push(Warning::new("scan", format!("object {object}"), format!("{why}: using \"{UNKNOWN_CATEGORY}\"")));
            }
            UNKNOWN_CATEGORY.to_owned()
        }
    }
}
