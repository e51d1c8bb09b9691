//! `MultiScan`'s `scanId.annotations.json`, as documented in the `MultiScan` docs (`dataset/files/
//! annotation.rst`, version `multiscan@0.0.1`):
//!
//! ```json
//! {"version": "multiscan@0.0.1", "`scanId`": "scene_00000_00",
//!  "objects": [{"`objectId`": 1, "label": "wall_cabinet.1", "`mobilityType`": "fixed",
//!               "`partIds`": [1, 19], "obb": {...}}],
//!  "parts": [{"`partId`": 1, "label": "door.1", "`parentId`": 19,
//!             "articulations": [{"type": "rotation", "origin": [x, y, z], "axis": [x, y, z],
//!                                "state": 0, "`rangeMin`": 0, "`rangeMax`": 1.5708, "isClosed": true}]},
//!            {"`partId`": 19, "label": "wall_cabinet.1"}]}
//! ```
//!
//! Read here: `objects[].objectId/label/mobilityType/partIds` and
//! `parts[].partId/label/parentId/articulations[].type/origin/axis/state/rangeMin/rangeMax`; the
//! OBBs and anything else are ignored. The docs list the ids as "(string)" while their example
//! and `MultiScan`'s own scripts use integers: both are accepted. Labels are `category.index`
//! (`door.1`). Objects whose label starts with `remove` are dropped, as `MultiScan`'s own
//! preprocessing scripts drop them (not in the docs). The docs' downloadable sample file
//! (`_static/dataset/scene_00000_00.annotations.json`) has an older layout (no ids, articulations
//! keyed by `object:part` label): it cannot be matched to a mesh's face ids and is refused with a
//! message saying so.

use std::collections::{BTreeMap, BTreeSet};

use serde::Deserialize;

use super::ImportError;

/// An object as annotated.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AnnotatedObject {
    pub id: i64,
    /// The label as written (`wall_cabinet.1`).
    pub label: String,
    /// The label without its instance index (`wall_cabinet`).
    pub category: String,
    /// `mobilityType` is `arch`: walls, floor, ceiling (scan background).
    pub arch: bool,
    /// The label starts with `remove`: annotated for removal, dropped.
    pub removed: bool,
    pub part_ids: Vec<i64>,
}

/// A part as annotated.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AnnotatedPart {
    pub id: i64,
    /// The label without its instance index (`door.1` → `door`).
    pub label: String,
    /// Position in `parts`, for messages.
    pub index: usize,
    pub parent: Option<i64>,
    /// The first articulation (`MultiScan`'s own scripts read only the first).
    pub articulation: Option<Articulation>,
    /// How many articulations the part has.
    pub articulation_count: usize,
}

/// One articulation, world frame, metres and radians; ranges relative to the joint's zero.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Articulation {
    /// `rotation` or `translation` (documented); anything else is kept for a warning.
    pub kind: String,
    pub origin: [f64; 3],
    pub axis: [f64; 3],
    /// The scanned state, within `[range_min, range_max]`.
    pub state: f64,
    pub range_min: f64,
    pub range_max: f64,
}

/// The annotations of one scan, checked: ids unique, every listed and parent part exists, each
/// part belongs to at most one object, parents form no cycle.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Annotations {
    pub objects: Vec<AnnotatedObject>,
    pub parts: BTreeMap<i64, AnnotatedPart>,
}

/// An id: documented as a string, written as an integer.
#[derive(Deserialize)]
#[serde(untagged)]
enum RawId {
    Int(i64),
    Text(String),
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct RawObject {
    object_id: RawId,
    label: String,
    #[serde(default)]
    mobility_type: Option<String>,
    #[serde(default)]
    part_ids: Vec<RawId>,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct RawArticulation {
    #[serde(rename = "type")]
    kind: String,
    origin: [f64; 3],
    axis: [f64; 3],
    #[serde(default)]
    state: f64,
    range_min: f64,
    range_max: f64,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct RawPart {
    part_id: RawId,
    label: String,
    #[serde(default)]
    parent_id: Option<RawId>,
    #[serde(default)]
    articulations: Vec<RawArticulation>,
}

#[derive(Deserialize)]
struct RawFile {
    objects: Vec<RawObject>,
    #[serde(default)]
    parts: Vec<RawPart>,
}

/// `door.1` → `door`; a label without a numeric suffix is kept whole.
pub(crate) fn label_word(label: &str) -> String {
    match label.rsplit_once('.') {
        Some((word, index)) if !word.is_empty() && !index.is_empty() && index.bytes().all(|b| b.is_ascii_digit()) => word.to_owned(),
        _ => label.to_owned(),
    }
}

/// Largest id accepted: ids become PLY `int` part and object ids.
const MAX_ID: i64 = i32::MAX as i64;

fn field_error(file: &str, field: impl Into<String>, detail: impl Into<String>) -> ImportError {
    ImportError::Annotation { file: file.to_owned(), field: field.into(), detail: detail.into() }
}

fn id(raw: &RawId, field: impl Fn() -> String, file: &str) -> Result<i64, ImportError> {
    let value = match raw {
        RawId::Int(v) => *v,
        RawId::Text(t) => t.trim().parse().map_err(|_| field_error(file, field(), format!("\"{t}\" is not an integer id")))?,
    };
    if (0..=MAX_ID).contains(&value) {
        Ok(value)
    } else {
        Err(field_error(file, field(), format!("{value}; expected an id in 0..={MAX_ID}")))
    }
}

/// Parses and checks an annotations file; `file` names it in errors.
pub(crate) fn parse_annotations(text: &str, file: &str) -> Result<Annotations, ImportError> {
    let raw: RawFile = serde_json::from_str(text)
        .map_err(|source| older_layout(text, file).unwrap_or(ImportError::AnnotationsJson { file: file.to_owned(), source }))?;
    let mut out = Annotations::default();
    for (i, p) in raw.parts.iter().enumerate() {
        let part_id = id(&p.part_id, || format!("parts[{i}].partId"), file)?;
        let parent = p.parent_id.as_ref().map(|r| id(r, || format!("parts[{i}].parentId"), file)).transpose()?;
        let articulation = p.articulations.first().map(|a| articulation(a, i, file)).transpose()?;
        let part = AnnotatedPart {
            id: part_id,
            label: label_word(&p.label),
            index: i,
            parent,
            articulation,
            articulation_count: p.articulations.len(),
        };
        if out.parts.insert(part_id, part).is_some() {
            return Err(field_error(file, format!("parts[{i}].partId"), format!("{part_id} appears twice; expected unique part ids")));
        }
    }
    let mut owner: BTreeMap<i64, i64> = BTreeMap::new();
    let mut object_ids = BTreeSet::new();
    for (i, o) in raw.objects.iter().enumerate() {
        let object_id = id(&o.object_id, || format!("objects[{i}].objectId"), file)?;
        if !object_ids.insert(object_id) {
            return Err(field_error(
                file,
                format!("objects[{i}].objectId"),
                format!("{object_id} appears twice; expected unique object ids"),
            ));
        }
        let mut part_ids = Vec::with_capacity(o.part_ids.len());
        for (j, raw_part) in o.part_ids.iter().enumerate() {
            let field = || format!("objects[{i}].partIds[{j}]");
            let part = id(raw_part, field, file)?;
            if !out.parts.contains_key(&part) {
                return Err(field_error(file, field(), format!("part {part} is not in `parts`")));
            }
            if let Some(other) = owner.insert(part, object_id) {
                return Err(field_error(
                    file,
                    field(),
                    format!("part {part} is listed by objects {other} and {object_id}; expected one owner"),
                ));
            }
            part_ids.push(part);
        }
        out.objects.push(AnnotatedObject {
            id: object_id,
            label: o.label.clone(),
            category: label_word(&o.label),
            arch: o.mobility_type.as_deref().is_some_and(|m| m.eq_ignore_ascii_case("arch")),
            removed: o.label.to_ascii_lowercase().starts_with("remove"),
            part_ids,
        });
    }
    check_parents(&out, file)?;
    Ok(out)
}

fn articulation(a: &RawArticulation, part: usize, file: &str) -> Result<Articulation, ImportError> {
    let field = |name: &str| format!("parts[{part}].articulations[0].{name}");
    let limit = f64::from(crate::scan::MAX_COORDINATE_M);
    let named = [
        ("origin", &a.origin[..]),
        ("axis", &a.axis[..]),
        ("state", &[a.state][..]),
        ("rangeMin", &[a.range_min][..]),
        ("rangeMax", &[a.range_max][..]),
    ];
    for (name, values) in named {
        if let Some(v) = values.iter().find(|v| !v.is_finite() || v.abs() > limit) {
            return Err(field_error(file, field(name), format!("{v}; expected finite values within {limit:e} (metres or radians)")));
        }
    }
    let length = a.axis.iter().map(|v| v * v).sum::<f64>().sqrt();
    if length < 1e-9 {
        return Err(field_error(file, field("axis"), format!("{:?} has no direction; expected a unit vector", a.axis)));
    }
    if a.range_min > a.range_max {
        return Err(field_error(file, field("rangeMin"), format!("{} exceeds rangeMax {}", a.range_min, a.range_max)));
    }
    Ok(Articulation {
        kind: a.kind.clone(),
        origin: a.origin,
        axis: a.axis.map(|v| v / length),
        state: a.state,
        range_min: a.range_min,
        range_max: a.range_max,
    })
}

/// Every parent exists and no chain of parents returns to where it started.
fn check_parents(annotations: &Annotations, file: &str) -> Result<(), ImportError> {
    for part in annotations.parts.values() {
        let field = || format!("parts[{}].parentId", part.index);
        if let Some(parent) = part.parent
            && !annotations.parts.contains_key(&parent)
        {
            return Err(field_error(file, field(), format!("part {parent} is not in `parts`")));
        }
        let mut current = part.parent;
        for _ in 0..=annotations.parts.len() {
            match current {
                Some(p) if p == part.id => {
                    return Err(field_error(file, field(), format!("the parents of part {} lead back to it (a cycle)", part.id)));
                }
                Some(p) => current = annotations.parts.get(&p).and_then(|q| q.parent),
                None => break,
            }
        }
    }
    Ok(())
}

/// The older layout of the docs' sample file, recognised to say why it cannot be used.
fn older_layout(text: &str, file: &str) -> Option<ImportError> {
    let value: serde_json::Value = serde_json::from_str(text).ok()?;
    let first = value.get("objects")?.get(0)?;
    (value.get("articulations").is_some_and(serde_json::Value::is_object) && first.get("objectId").is_none()).then(|| {
        field_error(
            file,
            "objects[0].objectId",
            "missing: this is the older annotation layout (objects without ids, `articulations` keyed by `object:part` label), \
             whose objects cannot be matched to the mesh's per-face `objectId`/`partId`; expected the documented layout with \
             `objects[].objectId`/`partIds` and `parts[].partId`",
        )
    })
}

#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    const DOC_EXAMPLE: &str = r#"{"version": "multiscan@0.0.1", "scanId": "scene_00000_00",
      "objects": [{"objectId": 1, "label": "wall_cabinet.1", "mobilityType": "fixed", "partIds": [1, 19],
                   "obb": {"centroid": [0, 0, 0]}},
                  {"objectId": "2", "label": "bag.1", "mobilityType": "movable", "partIds": [14]}],
      "parts": [{"partId": 1, "label": "door.1", "parentId": 19,
                 "articulations": [{"type": "rotation", "origin": [-1.48, 0.85, 0.98], "state": 0,
                                    "axis": [0.0297, 0, -0.9995], "rangeMin": 0, "rangeMax": 1.5707963267948966, "isClosed": true}]},
                {"partId": 14, "label": "bag.1"},
                {"partId": 19, "label": "wall_cabinet.1"}]}"#;

    #[test]
    fn the_documented_example_parses() {
        let a = parse_annotations(DOC_EXAMPLE, "a.json").unwrap();
        assert_eq!(a.objects.len(), 2);
        assert_eq!((a.objects[0].category.as_str(), a.objects[0].part_ids.clone()), ("wall_cabinet", vec![1, 19]));
        assert_eq!((a.objects[1].id, a.objects[1].arch, a.objects[1].removed), (2, false, false));
        let door = &a.parts[&1];
        assert_eq!((door.label.as_str(), door.parent, door.articulation_count), ("door", Some(19), 1));
        let art = door.articulation.as_ref().unwrap();
        assert_eq!((art.kind.as_str(), art.range_max), ("rotation", std::f64::consts::FRAC_PI_2));
        assert!((art.axis.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12, "axis normalised");
        assert_eq!(label_word("door_frame.12"), "door_frame");
        assert_eq!(label_word("v1.2.x"), "v1.2.x");
        assert_eq!(label_word("remove"), "remove");
    }

    #[test]
    fn errors_name_the_file_and_field() {
        let cases = [
            (DOC_EXAMPLE.replace("\"partId\": 14", "\"partId\": 1"), "a.json: `parts[1].partId`: 1 appears twice"),
            (DOC_EXAMPLE.replace("\"objectId\": \"2\"", "\"objectId\": 1"), "`objects[1].objectId`: 1 appears twice"),
            (DOC_EXAMPLE.replace("[14]", "[14, 77]"), "`objects[1].partIds[1]`: part 77 is not in `parts`"),
            (DOC_EXAMPLE.replace("[14]", "[14, 19]"), "`objects[1].partIds[1]`: part 19 is listed by objects 1 and 2"),
            (DOC_EXAMPLE.replace("\"parentId\": 19", "\"parentId\": 5"), "`parts[0].parentId`: part 5 is not in `parts`"),
            (
                DOC_EXAMPLE
                    .replace("{\"partId\": 19, \"label\": \"wall_cabinet.1\"}", "{\"partId\": 19, \"label\": \"w.1\", \"parentId\": 1}"),
                "the parents of part 1 lead back to it",
            ),
            (DOC_EXAMPLE.replace("\"objectId\": \"2\"", "\"objectId\": \"two\""), "`objects[1].objectId`: \"two\" is not an integer id"),
            (DOC_EXAMPLE.replace("\"objectId\": \"2\"", "\"objectId\": -3"), "-3; expected an id in 0..=2147483647"),
            (
                DOC_EXAMPLE.replace("\"axis\": [0.0297, 0, -0.9995]", "\"axis\": [0, 0, 0]"),
                "`parts[0].articulations[0].axis`: [0.0, 0.0, 0.0] has no direction",
            ),
            (DOC_EXAMPLE.replace("\"rangeMin\": 0,", "\"rangeMin\": 2,"), "`parts[0].articulations[0].rangeMin`: 2 exceeds rangeMax"),
            (
                DOC_EXAMPLE.replace("[-1.48, 0.85, 0.98]", "[-1.48, 3e7, 0.98]"),
                "`parts[0].articulations[0].origin`: 30000000; expected finite",
            ),
            (DOC_EXAMPLE.replace("\"label\": \"bag.1\", \"mobilityType\"", "\"mobilityType\""), "missing field `label`"),
            (DOC_EXAMPLE.replace("\"rangeMax\": 1.5707963267948966,", ""), "missing field `rangeMax`"),
            ("[1, 2]".to_owned(), "malformed MultiScan annotations"),
            (
                r#"{"objects": [{"label": "bag.1", "type": "movable"}], "articulations": {"door.1:door.1": {}}}"#.to_owned(),
                "`objects[0].objectId`: missing: this is the older annotation layout",
            ),
        ];
        for (text, needle) in cases {
            let e = parse_annotations(&text, "a.json").unwrap_err().to_string();
            assert!(e.contains(needle) && e.starts_with("a.json"), "{needle:?} not in {e}");
        }
    }
}
