//! Reading and writing scans, data-driven through `check`.

use std::fmt::Write as _;

use rand::Rng;

use super::*;
use crate::report::Warning;

/// What reading should give: a summary, or an error whose message contains the text.
enum Expect {
    Ok { parts: usize, points: usize, background: usize },
    Err(&'static str),
}

const PLY_NAME: &str = "t.ply";
const LABELS_NAME: &str = "t.json";

/// Reads `ply` (ascii text or binary bytes) with optional labels and checks the outcome. Errors
/// must also name the file they are about.
fn check(ply: impl AsRef<[u8]>, labels: Option<&str>, expected: Expect) -> Option<(Scan, Vec<Warning>)> {
    let result = read_scan_bytes(ply.as_ref(), PLY_NAME, labels, LABELS_NAME);
    match (result, expected) {
        (Ok((scan, warnings)), Expect::Ok { parts, points, background }) => {
            assert_eq!(
                (scan.parts.len(), scan.point_count(), scan.background.len()),
                (parts, points, background),
                "(parts, points, background); warnings: {warnings:?}"
            );
            assert!(scan.parts.windows(2).all(|w| w[0].id < w[1].id), "parts sorted by id");
            for part in &scan.parts {
                assert!(scan.objects.contains_key(&part.object), "object of part {}", part.id);
            }
            Some((scan, warnings))
        }
        (Err(e), Expect::Err(needle)) => {
            let message = e.to_string();
            assert!(message.contains(needle), "expected error containing {needle:?}, got: {message}");
            assert!(message.contains(PLY_NAME) || message.contains(LABELS_NAME), "error names the file: {message}");
            None
        }
        (Ok((scan, w)), Expect::Err(needle)) => {
            panic!("expected an error containing {needle:?}, read {} parts; warnings {w:?}", scan.parts.len())
        }
        (Err(e), Expect::Ok { .. }) => panic!("expected Ok, got error: {e}"),
    }
}

const HEADER_XYZ_OBJ_PART: &str = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
property float z\nproperty int object\nproperty int part\nend_header\n";

const BODY_5: &str = "0 0 0 3 17\n1 0 0 3 17\n0 1 0 3 18\n0 0 1 -1 -1\n2 2.5 -2e-1 3 18\n";

const LABELS: &str = r#"{"objects": {"3": {"category": "cabinet"}},
 "parts": {"17": {"object": 3, "label": "drawer"}, "18": {"object": 3, "label": "body"}}}"#;

fn ascii_5() -> String {
    format!("{HEADER_XYZ_OBJ_PART}{BODY_5}")
}

/// A binary PLY with float x y z, int object, int part.
fn binary_ply(encoding: &str, rows: &[([f32; 3], i32, i32)]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {encoding} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property int object\nproperty int part\nend_header\n",
        rows.len()
    )
    .into_bytes();
    let big = encoding == "binary_big_endian";
    for (p, object, part) in rows {
        for c in p {
            out.extend_from_slice(&if big { c.to_be_bytes() } else { c.to_le_bytes() });
        }
        for id in [object, part] {
            out.extend_from_slice(&if big { id.to_be_bytes() } else { id.to_le_bytes() });
        }
    }
    out
}

fn sample_rows() -> Vec<([f32; 3], i32, i32)> {
    vec![([0.0, 0.0, 0.0], 3, 17), ([1.0, 0.5, 0.25], 3, 17), ([0.0, 1.0, 0.0], 3, 18), ([9.0, 9.0, 9.0], -1, -1)]
}

#[test]
fn ascii_reads_parts_labels_and_background() {
    let (scan, warnings) = check(ascii_5(), Some(LABELS), Expect::Ok { parts: 2, points: 5, background: 1 }).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(scan.source, PLY_NAME);
    let drawer = scan.part(17).unwrap();
    assert_eq!((drawer.object, drawer.label.as_str()), (3, "drawer"));
    assert_eq!(drawer.points, vec![Vec3::ZERO, Vec3::X]);
    assert!(drawer.normals.is_none());
    let body = scan.part(18).unwrap();
    assert_eq!(body.label, "body");
    assert_eq!(body.points[1], Vec3::new(2.0, 2.5, -0.2));
    assert_eq!(scan.category(3), "cabinet");
    assert_eq!(scan.background, vec![Vec3::Z]);
}

#[test]
fn ascii_round_trip_through_bytes() {
    let (scan, _) = check(ascii_5(), Some(LABELS), Expect::Ok { parts: 2, points: 5, background: 1 }).unwrap();
    let bytes = scan_to_ply_bytes(&scan);
    let json = labels_json(&scan);
    let (again, warnings) = check(&bytes, Some(&json), Expect::Ok { parts: 2, points: 5, background: 1 }).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_same(&scan, &again);
}

pub(super) fn assert_same(a: &Scan, b: &Scan) {
    assert_eq!(a.objects, b.objects);
    assert_eq!(a.background, b.background);
    assert_eq!(a.parts.len(), b.parts.len());
    for (p, q) in a.parts.iter().zip(&b.parts) {
        assert_eq!((p.id, p.object, &p.label), (q.id, q.object, &q.label));
        assert_eq!(p.points, q.points, "part {}", p.id);
        assert_eq!(p.normals, q.normals, "part {}", p.id);
    }
}

#[test]
fn binary_round_trip_through_files_with_normals() {
    let mut scan = Scan { source: "made".into(), ..Scan::default() };
    scan.objects.insert(3, ScanObject { id: 3, category: "cabinet".into() });
    scan.objects.insert(70_000, ScanObject { id: 70_000, category: "chair \"big\"".into() });
    for (id, object, label, n) in [(17, 3, "drawer", 4), (5, 70_000, "leg", 3), (-0, 3, "body", 2)] {
        let points: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32 * 0.1, id as f32, -1.5e-3)).collect();
        let normals = Some(points.iter().map(|p| (*p + Vec3::ONE).normalize()).collect());
        scan.parts.push(ScanPart { id, object, label: label.into(), points, normals });
    }
    scan.parts.sort_by_key(|p| p.id);
    scan.background = vec![Vec3::new(1.0, 2.0, 3.0), Vec3::splat(-4.25)];

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.ply");
    write_scan(&scan, &path).unwrap();
    assert!(dir.path().join("room.json").exists());
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    let (again, warnings) = read_scan(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(again.source, path.display().to_string());
    assert_same(&scan, &again);
    assert_eq!(again.point_count(), 11);

    // Without normals on every part, none are written.
    scan.parts[0].normals = None;
    write_scan(&scan, &path).unwrap();
    let (again, _) = read_scan(&path).unwrap();
    assert!(again.parts.iter().all(|p| p.normals.is_none()));
}

#[test]
fn write_rejects_what_the_format_cannot_hold() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.ply");
    let part = |id, points| ScanPart { id, object: 1, label: "x".into(), points, normals: None };
    let mut scan = Scan::default();
    scan.parts.push(part(1 << 40, vec![Vec3::ZERO]));
    let e = write_scan(&scan, &path).unwrap_err().to_string();
    assert!(e.contains("bad.ply") && e.contains("part 1099511627776"), "{e}");
    scan.parts = vec![part(1, vec![Vec3::ZERO, Vec3::NAN])];
    let e = write_scan(&scan, &path).unwrap_err().to_string();
    assert!(e.contains("point 1 is not finite"), "{e}");
    assert!(!path.exists());
}

#[test]
fn integer_id_types_of_every_width() {
    for (object_type, part_type, object, part) in [
        ("uchar", "uchar", "3", "200"),
        ("short", "short", "-1", "-1"),
        ("uint", "uint", "4000000000", "7"),
        ("char", "int8", "-5", "12"),
        ("char", "int8", "5", "12"),
        ("ushort", "uint16", "65535", "9"),
        ("int32", "uint32", "3", "17"),
        ("uint8", "int16", "3", "-300"),
    ] {
        let ply = format!(
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
             property {object_type} object\nproperty {part_type} part\nend_header\n0 0 0 {object} {part}\n1 1 1 {object} {part}\n"
        );
        // Negative ids (not only -1) are unassigned: background.
        let background = usize::from(part.starts_with('-') || object.starts_with('-')) * 2;
        let parts = usize::from(background == 0);
        let (scan, _) = check(&ply, None, Expect::Ok { parts, points: 2, background }).unwrap();
        if parts == 1 {
            assert_eq!(scan.parts[0].id, part.parse::<i64>().unwrap(), "{object_type}/{part_type}");
            assert_eq!(scan.parts[0].object, object.parse::<i64>().unwrap());
        }
    }
    // The same through binary: uchar ids.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
property float z\nproperty uchar object\nproperty uchar part\nend_header\n"
        .to_vec();
    for c in [1.0_f32, 2.0, 3.0] {
        ply.extend_from_slice(&c.to_le_bytes());
    }
    ply.extend_from_slice(&[250, 251]);
    let (scan, _) = check(&ply, None, Expect::Ok { parts: 1, points: 1, background: 0 }).unwrap();
    assert_eq!((scan.parts[0].id, scan.parts[0].object), (251, 250));
    assert_eq!(scan.parts[0].points[0], Vec3::new(1.0, 2.0, 3.0));
}

#[test]
fn double_coordinates_extra_properties_and_colors() {
    let ply = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 2\nproperty double x\nproperty float64 y\n\
property double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty float confidence\n\
property int object\nproperty int part\nend_header\n0.1 0.2 0.30000000000000004 255 0 10 0.9 1 2\n-1e-3 5 6 0 0 0 1 1 2\n";
    let (scan, _) = check(ply, None, Expect::Ok { parts: 1, points: 2, background: 0 }).unwrap();
    assert_eq!(scan.parts[0].points, vec![Vec3::new(0.1, 0.2, 0.3), Vec3::new(-0.001, 5.0, 6.0)]);
}

#[test]
fn ascii_normals_are_read() {
    let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\nproperty int object\nproperty int part\nend_header\n\
0 0 0 0 0 1 1 4\n1 0 0 0 1 0 1 4\n";
    let (scan, _) = check(ply, None, Expect::Ok { parts: 1, points: 2, background: 0 }).unwrap();
    assert_eq!(scan.parts[0].normals, Some(vec![Vec3::Z, Vec3::Y]));
}

#[test]
fn errors_name_the_file_and_what_was_expected() {
    let h = |props: &str, n: usize| format!("ply\nformat ascii 1.0\nelement vertex {n}\n{props}end_header\n");
    let xyz = "property float x\nproperty float y\nproperty float z\n";
    let ids = "property int object\nproperty int part\n";
    let cases: Vec<(String, Option<&str>, &str)> = vec![
        (String::new(), None, "empty (0 bytes)"),
        (h(&format!("{xyz}{ids}"), 0), None, "0 vertices"),
        ("solid cube\nfacet normal 0 0 1\n".into(), None, "not \"ply\""),
        ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n".into(), None, "end_header"),
        ("ply\nelement vertex 1\nend_header\n".into(), None, "format"),
        (
            "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n".into(),
            None,
            "found elements: face",
        ),
        (format!("{}0 0 0 1\n", h(&format!("{xyz}property int object\n"), 1)), None, "no property `part`"),
        (format!("{}0 0 1 1\n", h(&format!("property float x\nproperty float y\n{ids}"), 1)), None, "no property `z`"),
        (
            format!("{}0 0 0 1 1.5\n", h(&format!("{xyz}property int object\nproperty float part\n"), 1)),
            None,
            "`part` has type float; expected an integer type",
        ),
        (format!("{}0 0 0 1 1\n", h(&format!("{xyz}property double object\nproperty int part\n"), 1)), None, "`object` has type double"),
        (
            format!("{}0 0 0 1 1\n", h(&format!("property float x\nproperty float y\nproperty list uchar float z\n{ids}"), 1)),
            None,
            "`z` has type list uchar float; expected float or double",
        ),
        (format!("{}0 0 0 1 1\n1 1 1 1 1\n0 0 nan 1 1\n", h(&format!("{xyz}{ids}"), 3)), None, "vertex 2 has a non-finite `z` (nan)"),
        (format!("{}0 0 0 1 1\n-inf 0 0 1 1\n", h(&format!("{xyz}{ids}"), 2)), None, "vertex 1 has a non-finite `x` (-inf)"),
        (format!("{}0 0 0 1 1\n0 1e39 0 1 1\n", h(&format!("{xyz}{ids}"), 2)), None, "vertex 1 has a non-finite `y` (inf)"),
        (format!("{}0 0 0 1 1\n0 0 -3e37 1 1\n", h(&format!("{xyz}{ids}"), 2)), None, "vertex 1 has `z` = -3e37 m; expected |z| <= 1e4 m"),
        (format!("{}0 0 0 1 1\n", h(&format!("{xyz}{ids}"), 4_000_000_000)), None, "declares 4000000000 vertices"),
        (format!("{}0 0 0 1 1\n0 0 0 1\n", h(&format!("{xyz}{ids}"), 2)), None, "at `vertex` element 1"),
        (format!("{}0 0 0 1 1\nzero 0 0 1 1\n", h(&format!("{xyz}{ids}"), 2)), None, "at `vertex` element 1"),
        (format!("{}0 0 0 1 1\n1 1 1 1 1\n", h(&format!("{xyz}{ids}"), 4)), None, "expected 4 `vertex` elements, the file ends after 2"),
        (format!("{}0 0 0 1 -1\n", h(&format!("{xyz}property uchar object\nproperty uchar part\n"), 1)), None, "at `vertex` element 0"),
        (
            ascii_5(),
            Some(r#"{"objects": {}, "parts": {"17": {"object": 3, "label": "drawer"}, "99": {"label": "lid"}}}"#),
            "labels name part 99, which is not in the scan t.ply",
        ),
        (ascii_5(), Some(r#"{"parts": {"-1": {"label": "floor"}}}"#), "part -1"),
        (
            ascii_5(),
            Some("{\"objects\": {\"3\": {\"category\": \"cabinet\"}},\n \"parts\": {\"17\": {\"object\": 3 \"label\": 1}}}"),
            "line 2 column",
        ),
        (ascii_5(), Some(r#"{"parts": {"17": {"object": "three"}}}"#), "malformed labels JSON"),
        (ascii_5(), Some("[1, 2]"), "malformed labels JSON"),
        (ascii_5(), Some(r#"{"parts": {"drawer": {"object": 3}}}"#), "key \"drawer\" in `parts` is not an integer id"),
        (ascii_5(), Some(r#"{"objects": {"3.0": {"category": "cabinet"}}}"#), "key \"3.0\" in `objects`"),
    ];
    for (ply, labels, needle) in cases {
        check(&ply, labels, Expect::Err(needle));
    }
}

#[test]
fn binary_nan_and_truncation_are_errors() {
    let mut rows = sample_rows();
    rows[2].0[1] = f32::NAN;
    check(binary_ply("binary_little_endian", &rows), None, Expect::Err("vertex 2 has a non-finite `y` (NaN)"));

    let whole = binary_ply("binary_little_endian", &sample_rows());
    check(
        &whole[..whole.len() - 3],
        None,
        Expect::Err("truncated: the header declares 4 vertices of 20 bytes (80 bytes), but only 77 bytes"),
    );
    let header_len = whole.len() - 80;
    check(&whole[..header_len], None, Expect::Err("only 0 bytes follow the header"));
    check(&whole[..header_len - 5], None, Expect::Err("end_header"));
    // Trailing bytes after the declared vertices are ignored.
    let mut longer = whole.clone();
    longer.extend_from_slice(b"junk");
    check(&longer, None, Expect::Ok { parts: 2, points: 4, background: 1 });
}

#[test]
fn big_endian_binary_reads_the_same() {
    let little = check(binary_ply("binary_little_endian", &sample_rows()), None, Expect::Ok { parts: 2, points: 4, background: 1 });
    let big = check(binary_ply("binary_big_endian", &sample_rows()), None, Expect::Ok { parts: 2, points: 4, background: 1 });
    assert_same(&little.unwrap().0, &big.unwrap().0);
}

#[test]
fn a_part_with_three_points_is_read() {
    let ply = format!("{HEADER_XYZ_OBJ_PART}0 0 0 1 5\n1 0 0 1 5\n0 1 0 1 5\n0 0 9 -1 -1\n0 0 8 -1 -1\n");
    let (scan, _) = check(&ply, None, Expect::Ok { parts: 1, points: 5, background: 2 }).unwrap();
    assert_eq!(scan.parts[0].points.len(), 3);
}

#[test]
fn mesh_ply_reads_its_vertices() {
    let faces_after = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
property int object\nproperty int part\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 1 2\n1 0 0 1 2\n0 1 0 1 2\n3 0 1 2\n";
    check(faces_after, None, Expect::Ok { parts: 1, points: 3, background: 0 });
    // A broken face list after the vertices does not matter: faces are never parsed.
    check(faces_after.replace("3 0 1 2\n", "3 0 oops"), None, Expect::Ok { parts: 1, points: 3, background: 0 });
    // Faces before the vertices are skipped.
    let faces_first = "ply\nformat ascii 1.0\nelement face 2\nproperty list uchar int vertex_indices\n\
element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty int object\nproperty int part\n\
end_header\n3 0 1 2\n4 0 1 2 3\n0 0 0 1 2\n0 1 nan 1 2\n";
    check(faces_first, None, Expect::Err("vertex 1 has a non-finite `z`"));
    check(faces_first.replace("nan", "7"), None, Expect::Ok { parts: 1, points: 2, background: 0 });

    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\n\
element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty short object\nproperty short part\n\
end_header\n"
        .to_vec();
    binary.push(3);
    for i in [0_i32, 1, 2] {
        binary.extend_from_slice(&i.to_le_bytes());
    }
    for c in [0.5_f32, 0.0, 0.0] {
        binary.extend_from_slice(&c.to_le_bytes());
    }
    binary.extend_from_slice(&7_i16.to_le_bytes());
    check(&binary, None, Expect::Err("truncated"));
    binary.extend_from_slice(&8_i16.to_le_bytes());
    let (scan, _) = check(&binary, None, Expect::Ok { parts: 1, points: 1, background: 0 }).unwrap();
    assert_eq!((scan.parts[0].id, scan.parts[0].points[0]), (8, Vec3::new(0.5, 0.0, 0.0)));
}

#[test]
fn missing_labels_warn_once_and_label_unknown() {
    let (scan, warnings) = check(ascii_5(), None, Expect::Ok { parts: 2, points: 5, background: 1 }).unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].message.contains("labels file not found"), "{warnings:?}");
    assert_eq!(warnings[0].subject, LABELS_NAME);
    assert!(scan.parts.iter().all(|p| p.label == UNKNOWN_LABEL && p.object == 3));
    assert_eq!(scan.category(3), UNKNOWN_CATEGORY);
}

#[test]
fn partial_labels_warn_per_part_and_object() {
    let labels = r#"{"objects": {"4": {"category": "desk"}}, "parts": {"17": {"label": "drawer"}}}"#;
    let (scan, warnings) = check(ascii_5(), Some(labels), Expect::Ok { parts: 2, points: 5, background: 1 }).unwrap();
    assert_eq!(scan.part(17).unwrap().label, "drawer");
    assert_eq!(scan.part(17).unwrap().object, 3, "object from the points");
    assert_eq!(scan.part(18).unwrap().label, UNKNOWN_LABEL);
    assert_eq!(scan.category(3), UNKNOWN_CATEGORY);
    assert!(!scan.objects.contains_key(&4), "objects without parts are not kept");
    let subjects: Vec<&str> = warnings.iter().map(|w| w.subject.as_str()).collect();
    assert_eq!(subjects, vec!["object 3", "part 18"], "{warnings:?}");
}

#[test]
fn object_majority_disagreement_and_unassigned_objects() {
    let body = "0 0 0 3 1\n0 0 1 3 1\n0 0 2 5 1\n1 0 0 -1 2\n1 0 1 -1 2\n2 0 0 6 3\n2 0 1 7 3\n";
    let ply = format!("{HEADER_XYZ_OBJ_PART}{body}").replace("vertex 5", "vertex 7");
    let (scan, warnings) = check(&ply, None, Expect::Ok { parts: 2, points: 7, background: 2 }).unwrap();
    assert_eq!(scan.part(1).unwrap().object, 3, "majority");
    assert_eq!(scan.part(3).unwrap().object, 6, "tie goes to the smaller id");
    assert!(scan.part(2).is_none(), "object -1: background");
    assert_eq!(scan.background, vec![Vec3::X, Vec3::new(1.0, 0.0, 1.0)]);
    let text: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert!(text.iter().any(|w| w.contains("part 1") && w.contains("3 (2 points), 5 (1 points)")), "{text:?}");
    assert!(text.iter().any(|w| w.contains("part 2") && w.contains("treated as background")), "{text:?}");

    // The labels' object wins over the points, with a warning; object -1 in the labels → background.
    let labels = r#"{"objects": {"5": {"category": "box"}}, "parts": {"1": {"object": 5, "label": "lid"}, "3": {"object": -1}}}"#;
    let (scan, warnings) = check(&ply, Some(labels), Expect::Ok { parts: 1, points: 7, background: 4 }).unwrap();
    assert_eq!((scan.parts[0].id, scan.parts[0].object, scan.category(5)), (1, 5, "box"));
    assert!(warnings.iter().any(|w| w.message.contains("the labels say object 5")), "{warnings:?}");
}

/// Fuzzing (issue 14): a binary element without properties before the vertices, declared 10¹²
/// times, made the parser count through it for hours; such an element takes no bytes and is
/// skipped at once, and any element before the vertices must fit in the bytes left.
#[test]
fn elements_before_the_vertices_are_bounded_by_the_file_length() {
    let vertex = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty int object\nproperty int part\n";
    let row: Vec<u8> =
        [0.5_f32.to_le_bytes(), 0.0_f32.to_le_bytes(), 0.0_f32.to_le_bytes(), 3_i32.to_le_bytes(), 4_i32.to_le_bytes()].concat();
    let with = |element: &str| {
        let mut ply = format!("ply\nformat binary_little_endian 1.0\n{element}{vertex}end_header\n").into_bytes();
        ply.extend_from_slice(&row);
        ply
    };
    let start = std::time::Instant::now();
    check(with("element empty 1000000000000\n"), None, Expect::Ok { parts: 1, points: 1, background: 0 });
    assert!(start.elapsed().as_secs_f32() < 1.0, "took {:?}", start.elapsed());
    check(
        with("element face 1000000000000\nproperty list uchar int vertex_indices\n"),
        None,
        Expect::Err("declares 1000000000000 `face` elements of at least 1 bytes each, but only 20 bytes follow"),
    );
    check(with("element extra 5\nproperty short a\nproperty double b\n"), None, Expect::Err("`extra` elements of at least 10 bytes"));
    check(
        "ply\nformat ascii 1.0\nelement face 9999999999\nproperty list uchar int vertex_indices\nelement vertex 1\nproperty float x\n\
property float y\nproperty float z\nproperty int object\nproperty int part\nend_header\n3 0 1 2\n0 0 0 1 2\n",
        None,
        Expect::Err("declares 9999999999 `face` elements of at least 1 bytes each"),
    );
}

#[test]
fn garbage_never_panics() {
    check([0xff_u8, 0xfe, 0x00, 0x12, 0x80, b'\n', 0xc3], None, Expect::Err("not \"ply\""));
    check(b"ply\n\xff\xfe\x00garbage\n", None, Expect::Err("unreadable header"));
    check(b"ply", None, Expect::Err("unreadable header"));
    check("ply\nformat ascii 1.0\nelement vertex 99999999999999999999\nend_header\n", None, Expect::Err("unreadable header"));

    // Mutations and truncations of valid files: any error is fine, a panic is not.
    let mut rng = crate::math::rng(7);
    let seeds = [ascii_5().into_bytes(), binary_ply("binary_little_endian", &sample_rows())];
    for seed in &seeds {
        for _ in 0..400 {
            let mut bytes = seed.clone();
            for _ in 0..rng.random_range(1..4) {
                let i = rng.random_range(0..bytes.len());
                bytes[i] = rng.random();
            }
            if rng.random_bool(0.3) {
                bytes.truncate(rng.random_range(0..bytes.len()));
            }
            let _ = read_scan_bytes(&bytes, PLY_NAME, Some(LABELS), LABELS_NAME);
        }
    }
}

/// Reading speed: `cargo test --release --no-default-features --lib scan::tests::read_500k -- --ignored --nocapture`.
#[test]
#[ignore = "timing; run by hand in release"]
fn read_500k_points_timing() {
    let mut scan = Scan::default();
    let mut rng = crate::math::rng(1);
    for id in 0..150 {
        scan.objects.entry(id / 5).or_insert(ScanObject { id: id / 5, category: "cabinet".into() });
        let points = (0..3000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random())).collect();
        scan.parts.push(ScanPart { id, object: id / 5, label: "door".into(), points, normals: None });
    }
    scan.background = (0..50_000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random())).collect();
    let bytes = scan_to_ply_bytes(&scan);
    let json = labels_json(&scan);
    let start = std::time::Instant::now();
    let (again, _) = read_scan_bytes(&bytes, "big.ply", Some(&json), "big.json").unwrap();
    let binary_s = start.elapsed().as_secs_f64();
    assert_eq!(again.point_count(), 500_000);

    let mut ascii = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property int object\nproperty int part\nend_header\n",
        scan.point_count()
    );
    for part in &scan.parts {
        for p in &part.points {
            let _ = writeln!(ascii, "{} {} {} {} {}", p.x, p.y, p.z, part.object, part.id);
        }
    }
    for p in &scan.background {
        let _ = writeln!(ascii, "{} {} {} -1 -1", p.x, p.y, p.z);
    }
    let start = std::time::Instant::now();
    let (again_ascii, _) = read_scan_bytes(ascii.as_bytes(), "big.ply", Some(&json), "big.json").unwrap();
    let ascii_s = start.elapsed().as_secs_f64();
    assert_same(&again, &again_ascii);
    println!("500k points: binary {binary_s:.3} s, ascii {ascii_s:.3} s");
    assert!(binary_s < 0.5, "binary read took {binary_s} s");
}

/// Arrays (the Python binding's input) follow the `.npz` rules: every array one row per point,
/// finite coordinates, labels only for parts the scan has; the errors name the array and row.
#[test]
fn arrays_build_a_scan_and_bad_arrays_are_named() {
    use std::collections::BTreeMap;
    let points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.2], [1.0, 1.0, 0.0]];
    let labels = BTreeMap::from([(5, "door".to_owned())]);
    let categories = BTreeMap::from([(2, "cabinet".to_owned())]);
    let arrays = ScanArrays {
        points: &points,
        normals: None,
        object_ids: &[2, 2, 2, -1],
        part_ids: &[5, 5, 5, -1],
        part_labels: &labels,
        object_categories: &categories,
    };
    let (scan, warnings) = scan_from_arrays(&arrays, "arrays").expect("a scan");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!((scan.parts.len(), scan.parts[0].label.as_str(), scan.background.len()), (1, "door", 1));
    assert_eq!(scan.objects[&2].category, "cabinet");
    let err = |a: ScanArrays| scan_from_arrays(&a, "arrays").expect_err("bad arrays").to_string();
    assert!(err(ScanArrays { part_ids: &[5, 5], ..arrays }).contains("array `part_ids` has 2 rows, `points` has 4"));
    let nan = [[0.0, 0.0, 0.0], [0.1, f64::NAN, 0.0], [0.0, 0.1, 0.2], [1.0, 1.0, 0.0]];
    assert!(err(ScanArrays { points: &nan, ..arrays }).contains("row 1 has a non-finite y"));
    let unknown = BTreeMap::from([(9, "door".to_owned())]);
    assert!(err(ScanArrays { part_labels: &unknown, ..arrays }).contains("the labels name part 9"));
}
