//! The labels JSON beside a scan's PLY:
//! `{"objects": {"3": {"category": "cabinet"}}, "parts": {"17": {"object": 3, "label": "drawer"}}}`.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Deserialize;

use super::error::ScanError;
use super::{ObjectId, PartId, Scan};

/// The labels of one part. Either field may be absent.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PartLabel {
    pub object: Option<ObjectId>,
    pub label: Option<String>,
}

/// A parsed labels file with integer keys.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Labels {
    /// Object id → category (`None` when the entry has no `category`).
    pub objects: BTreeMap<ObjectId, Option<String>>,
    pub parts: BTreeMap<PartId, PartLabel>,
}

#[derive(Deserialize)]
struct LabelsFile {
    #[serde(default)]
    objects: BTreeMap<String, ObjectEntry>,
    #[serde(default)]
    parts: BTreeMap<String, PartEntry>,
}

#[derive(Deserialize)]
struct ObjectEntry {
    #[serde(default)]
    category: Option<String>,
}

#[derive(Deserialize)]
struct PartEntry {
    #[serde(default)]
    object: Option<ObjectId>,
    #[serde(default)]
    label: Option<String>,
}

fn parse_key(key: &str, section: &'static str, file: &str) -> Result<i64, ScanError> {
    key.parse::<i64>().map_err(|_| ScanError::LabelKey { file: file.to_owned(), section, key: key.to_owned() })
}

/// Parses a labels file; `file` names it in errors.
pub(crate) fn parse_labels(text: &str, file: &str) -> Result<Labels, ScanError> {
    // Some editors on Windows start UTF-8 files with a byte order mark.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let raw: LabelsFile = serde_json::from_str(text).map_err(|source| ScanError::LabelsJson { file: file.to_owned(), source })?;
    let mut labels = Labels::default();
    for (key, entry) in raw.objects {
        labels.objects.insert(parse_key(&key, "objects", file)?, entry.category);
    }
    for (key, entry) in raw.parts {
        labels.parts.insert(parse_key(&key, "parts", file)?, PartLabel { object: entry.object, label: entry.label });
    }
    Ok(labels)
}

/// A JSON string literal (quoted, escaped).
fn json_string(s: &str) -> String {
    serde_json::Value::String(s.to_owned()).to_string()
}

/// The labels JSON of a scan (objects and parts in id order), as written beside its PLY.
#[must_use]
pub fn labels_json(scan: &Scan) -> String {
    let mut out = String::from("{\n  \"objects\": {");
    for (i, (id, object)) in scan.objects.iter().enumerate() {
        let sep = if i == 0 { "" } else { "," };
        // Writing into a String cannot fail.
        let _ = write!(out, "{sep}\n    \"{id}\": {{\"category\": {}}}", json_string(&object.category));
    }
    out.push_str(if scan.objects.is_empty() { "},\n  \"parts\": {" } else { "\n  },\n  \"parts\": {" });
    for (i, part) in scan.parts.iter().enumerate() {
        let sep = if i == 0 { "" } else { "," };
        let _ = write!(out, "{sep}\n    \"{}\": {{\"object\": {}, \"label\": {}}}", part.id, part.object, json_string(&part.label));
    }
    out.push_str(if scan.parts.is_empty() { "}\n}\n" } else { "\n  }\n}\n" });
    out
}

#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::scan::{ScanObject, ScanPart};

    #[test]
    fn labels_json_parses_back() {
        let mut scan = Scan::default();
        scan.objects.insert(3, ScanObject { id: 3, category: "cab\"inet".into() });
        for id in [9, 10] {
            scan.parts.push(ScanPart { id, object: 3, label: "drawer".into(), points: vec![], normals: None });
        }
        let text = labels_json(&scan);
        let labels = parse_labels(&text, "l.json").unwrap();
        assert_eq!(labels.objects[&3].as_deref(), Some("cab\"inet"));
        assert_eq!(labels.parts.keys().copied().collect::<Vec<_>>(), vec![9, 10]);
        assert_eq!(labels.parts[&10], PartLabel { object: Some(3), label: Some("drawer".into()) });
        // Numeric, not lexicographic, order in the file.
        assert!(text.find("\"9\"").unwrap() < text.find("\"10\"").unwrap(), "{text}");
        assert!(parse_labels(&labels_json(&Scan::default()), "e.json").unwrap().parts.is_empty());
        let with_bom = format!("\u{feff}{text}");
        assert_eq!(parse_labels(&with_bom, "b.json").unwrap(), labels);
    }
}
