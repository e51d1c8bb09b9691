//! `MultiScan` import on the fixture `tests/fixtures/multiscan/scene_00000_00/` (written to the
//! documented layout, ascii for reading): a cabinet (body + a door hinged on a vertical axis), a
//! table, a floor (`arch`), a triangle of an object labelled `remove.1` and two unannotated wall
//! triangles (`objectId` 0, `partId` 0).

use std::path::{Path, PathBuf};

use super::multiscan::{MultiScanOptions, import_multiscan, import_multiscan_bytes, scan_files, write_import};
use super::*;
use crate::kinematics::JointKind;
use crate::math::Vec3;
use crate::truth::GroundTruth;

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/multiscan/scene_00000_00")
}

fn fixture_ply() -> String {
    std::fs::read_to_string(fixture_dir().join("scene_00000_00.ply")).unwrap()
}

fn fixture_annotations() -> String {
    std::fs::read_to_string(fixture_dir().join("scene_00000_00.annotations.json")).unwrap()
}

const OPTIONS: MultiScanOptions = MultiScanOptions { points: 6000, seed: 3 };

fn import(ply: &[u8], annotations: &str) -> Result<multiscan::MultiScanImport, ImportError> {
    import_multiscan_bytes(ply, "m.ply", annotations, "m.annotations.json", "scene_00000_00", OPTIONS)
}

#[test]
fn the_fixture_becomes_a_scan_and_its_truth() {
    let out = import_multiscan(&fixture_dir(), OPTIONS).unwrap();
    assert_eq!(out.scan_id, "scene_00000_00");
    let scan = &out.scan;
    let parts: Vec<(i64, i64, &str)> = scan.parts.iter().map(|p| (p.id, p.object, p.label.as_str())).collect();
    assert_eq!(parts, [(1, 1, "cabinet"), (2, 1, "door"), (3, 2, "table")]);
    assert_eq!((scan.category(1), scan.category(2)), ("cabinet", "table"));
    assert_eq!(scan.point_count(), OPTIONS.points, "every point lands on a kept face");
    // Floor and the unannotated wall are background; the removed triangle (z = 1, x, y in [1, 1.1]) is dropped.
    assert!(scan.background.iter().any(|p| p.z == 0.0) && scan.background.iter().any(|p| (p.y - 2.0).abs() < 1e-6));
    let in_removed = |p: &Vec3| (p.z - 1.0).abs() < 1e-6 && p.x >= 1.0 && p.x <= 1.1 && p.y <= 1.1;
    assert!(!scan.background.iter().chain(scan.parts.iter().flat_map(|p| &p.points)).any(in_removed));
    // Door points lie on the door panel.
    assert!(scan.part(2).unwrap().points.iter().all(|p| p.y <= 1e-6 && p.y >= -0.02 - 1e-6 && p.x <= 0.58 + 1e-6));
    let unannotated = out.warnings.iter().find(|w| w.message.contains("name no annotated part")).unwrap();
    assert!(unannotated.message.contains("2 triangles") && unannotated.message.contains("objectId 0 partId 0 (2)"), "{unannotated}");

    let truth = &out.truth;
    assert_eq!(truth.objects.iter().map(|o| (o.id, o.category.as_str())).collect::<Vec<_>>(), [(1, "cabinet"), (2, "table")]);
    let cabinet = &truth.objects[0];
    assert_eq!(
        cabinet.parts.iter().map(|p| (p.id, p.meshes[0].triangles.len(), p.meshes[0].vertices.len())).collect::<Vec<_>>(),
        [(1, 12, 8), (2, 12, 8)]
    );
    assert_eq!(cabinet.joints.len(), 1);
    let door = cabinet.joints[0];
    assert_eq!((door.parent, door.child, door.kind), (1, 2, JointKind::Revolute));
    assert_eq!((door.axis_world, door.origin_world), (Vec3::NEG_Z, Vec3::new(0.0, -0.01, 0.4)));
    assert_eq!((door.lower, door.upper), (0.0, std::f32::consts::FRAC_PI_2));
    assert_eq!(cabinet.contact_edges, vec![[1, 2]]);
    assert!(truth.objects[1].joints.is_empty());
    assert!(truth.floor_z.abs() < 1e-9, "{}", truth.floor_z);
}

#[test]
fn the_same_seed_gives_the_same_files() {
    let dir = tempfile::tempdir().unwrap();
    let written: Vec<Vec<Vec<u8>>> = (0..2)
        .map(|i| {
            let out = dir.path().join(format!("run{i}"));
            let paths = write_import(&import_multiscan(&fixture_dir(), OPTIONS).unwrap(), &out).unwrap();
            paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
        })
        .collect();
    assert_eq!(written[0], written[1]);
    let other = import_multiscan(&fixture_dir(), MultiScanOptions { seed: 4, ..OPTIONS }).unwrap();
    assert_ne!(other.scan.parts[0].points, import_multiscan(&fixture_dir(), OPTIONS).unwrap().scan.parts[0].points);
    // Nothing but the three outputs in the folder: temporary files were renamed into place.
    let mut names: Vec<String> =
        std::fs::read_dir(dir.path().join("run0")).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    assert_eq!(names, ["gt.json", "scan.json", "scan.ply"]);
}

/// The written scan reads back, reconstructs, and `eval` scores it against the written truth.
#[test]
fn the_written_scan_reconstructs_and_evaluates() {
    let dir = tempfile::tempdir().unwrap();
    let [scan_path, _, gt_path] = write_import(&import_multiscan(&fixture_dir(), OPTIONS).unwrap(), dir.path()).unwrap();
    let (scan, warnings) = crate::scan::read_scan(&scan_path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(scan.parts.len(), 3);
    let truth: GroundTruth = serde_json::from_slice(&std::fs::read(&gt_path).unwrap()).unwrap();
    let model = crate::pipeline::reconstruct(
        &scan,
        &crate::pipeline::PipelineConfig::default(),
        &crate::pipeline::PinnedEdits::default(),
        &crate::pipeline::Quiet,
    );
    let metrics = crate::eval::evaluate(&model, &truth);
    assert_eq!(metrics.objects.len(), 2);
    let cabinet = &metrics.objects[0];
    assert_eq!((cabinet.truth_parts, cabinet.predicted_parts, cabinet.joints.len()), (2, 2, 1));
    assert!(cabinet.chamfer.is_some() && cabinet.iou.is_some(), "{cabinet:?}");
    assert!(metrics.summary.unmatched_model_objects.is_empty(), "{:?}", metrics.summary);
}

/// The documented binary layout (double coordinates, `ushort` ids) reads as the ascii fixture.
#[test]
fn binary_little_endian_reads_like_ascii() {
    let ascii = fixture_ply();
    let (header, body) = ascii.split_once("end_header\n").unwrap();
    let mut binary = header.replace("format ascii 1.0", "format binary_little_endian 1.0").into_bytes();
    binary.extend_from_slice(b"end_header\n");
    for line in body.lines() {
        let v: Vec<&str> = line.split_whitespace().collect();
        if v.len() == 10 {
            for x in &v[..6] {
                binary.extend_from_slice(&x.parse::<f64>().unwrap().to_le_bytes());
            }
            binary.extend(v[6..].iter().map(|c| c.parse::<u8>().unwrap()));
        } else {
            binary.push(3);
            for i in &v[1..4] {
                binary.extend_from_slice(&i.parse::<i32>().unwrap().to_le_bytes());
            }
            for id in &v[4..] {
                binary.extend_from_slice(&id.parse::<u16>().unwrap().to_le_bytes());
            }
        }
    }
    let a = import(ascii.as_bytes(), &fixture_annotations()).unwrap();
    let b = import(&binary, &fixture_annotations()).unwrap();
    assert_eq!(format!("{:?}", a.scan), format!("{:?}", b.scan));
    assert_eq!(serde_json::to_string(&a.truth).unwrap(), serde_json::to_string(&b.truth).unwrap());
}

#[test]
fn joint_conventions() {
    // (articulation JSON, expected kind, axis, lower, upper)
    let cases = [
        (
            r#"{"type": "translation", "origin": [0, 0, 0], "axis": [0, 1, 0], "state": 0, "rangeMin": -0.4, "rangeMax": 0}"#,
            JointKind::Prismatic,
            Vec3::NEG_Y,
            0.0,
            0.4,
        ),
        (
            r#"{"type": "rotation", "origin": [0, 0, 0], "axis": [0, 0, 2], "state": 0.5, "rangeMin": 0, "rangeMax": 1.5}"#,
            JointKind::Revolute,
            Vec3::Z,
            -0.5,
            1.0,
        ),
        (
            r#"{"type": "rotation", "origin": [0, 0, 0], "axis": [1, 0, 0], "state": -1, "rangeMin": -1.5, "rangeMax": 0.5}"#,
            JointKind::Revolute,
            Vec3::NEG_X,
            -1.5,
            0.5,
        ),
        (r#"{"type": "spin", "origin": [0, 0, 0], "axis": [1, 0, 0], "rangeMin": 0, "rangeMax": 1}"#, JointKind::Fixed, Vec3::X, 0.0, 0.0),
    ];
    let annotations = fixture_annotations();
    let kind = annotations.find("\"type\": \"rotation\"").unwrap();
    let door = annotations[..kind].rfind('{').unwrap();
    let end = kind + annotations[kind..].find('}').unwrap() + 1;
    for (articulation, kind, axis, lower, upper) in cases {
        let text = format!("{}{articulation}{}", &annotations[..door], &annotations[end..]);
        let out = import(fixture_ply().as_bytes(), &text).unwrap();
        let j = out.truth.objects[0].joints[0];
        assert_eq!((j.kind, j.axis_world, j.lower, j.upper), (kind, axis, lower, upper), "{articulation}");
        if kind == JointKind::Fixed {
            assert!(out.warnings.iter().any(|w| w.message.contains("\"spin\"")), "{:?}", out.warnings);
            assert!((j.origin_world - Vec3::new(0.29, -0.01, 0.4)).length() < 1e-5, "fixed joints sit at the part's centroid");
        }
    }
    // No articulation: fixed; two: the first, with a warning; no parent: no joint.
    let two = format!(
        "{}, {{\"type\": \"translation\", \"origin\": [0, 0, 0], \"axis\": [1, 0, 0], \"rangeMin\": 0, \"rangeMax\": 1}}{}",
        &annotations[..end],
        &annotations[end..]
    );
    let out = import(fixture_ply().as_bytes(), &two).unwrap();
    assert_eq!(out.truth.objects[0].joints[0].kind, JointKind::Revolute);
    assert!(out.warnings.iter().any(|w| w.message.contains("has 2 articulations")), "{:?}", out.warnings);
    let orphan = annotations.replace("\"parentId\": 1,", "");
    assert!(import(fixture_ply().as_bytes(), &orphan).unwrap().truth.objects[0].joints.is_empty());
}

/// Replaces the first occurrence of `from` in the fixture PLY.
fn ply_with(from: &str, to: &str) -> Vec<u8> {
    let ply = fixture_ply();
    assert!(ply.contains(from), "{from}");
    ply.replacen(from, to, 1).into_bytes()
}

#[test]
fn errors_name_the_file_and_what_was_expected() {
    let annotations = fixture_annotations();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"solid x\n".to_vec(), "m.ply: not a PLY file"),
        (
            ply_with("property ushort objectId\n", ""),
            "m.ply: the `face` element has no property `objectId` (it has: vertex_indices, partId)",
        ),
        (ply_with("property ushort partId", "property float partId"), "`face` property `partId` has type float; expected an integer type"),
        (ply_with("property double x", "property int x"), "`vertex` property `x` has type int; expected float or double"),
        (ply_with("property list uchar int vertex_indices", "property list uchar float vertex_indices"), "expected a list of integers"),
        (
            ply_with("element face 41\nproperty list uchar int vertex_indices\nproperty ushort objectId\nproperty ushort partId\n", ""),
            "expected `vertex` and `face` elements",
        ),
        (ply_with("3 0 2 3 1 1", "3 0 2 99 1 1"), "m.ply: face 0: vertex index 99; expected 0..35"),
        (ply_with("3 0 2 3 1 1", "3 0 2 -1 1 1"), "face 0: vertex index -1"),
        (ply_with("0 0 0 0 0 1", "0 0 2e5 0 0 1"), "m.ply: vertex 0 has z = 200000; expected a finite coordinate with |z| <= 1e4 m"),
        (ply_with("element face 41", "element face 9000"), "m.ply: the PLY body is truncated"),
        (ply_with("3 0 2 3 1 1", "3 0 2 x 1 1"), "m.ply: malformed `face` element"),
    ];
    for (ply, needle) in cases {
        let e = import(&ply, &annotations).unwrap_err().to_string();
        assert!(e.contains(needle), "{needle:?} not in {e}");
    }
    let e = import(fixture_ply().as_bytes(), "{").unwrap_err().to_string();
    assert!(e.starts_with("m.annotations.json: malformed MultiScan annotations"), "{e}");
    // A face with two vertices is skipped with a warning.
    let out = import(&ply_with("3 0 2 3 1 1", "2 0 2 1 1"), &annotations).unwrap();
    assert!(out.warnings.iter().any(|w| w.message.contains("1 faces with fewer than 3 vertices skipped")), "{:?}", out.warnings);
}

#[test]
fn folders_name_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let e = scan_files(dir.path()).unwrap_err().to_string();
    assert!(e.contains("no `*.annotations.json`"), "{e}");
    std::fs::write(dir.path().join("scene_1.annotations.json"), "{}").unwrap();
    let e = scan_files(dir.path()).unwrap_err().to_string();
    assert!(e.contains("no scene_1.ply beside scene_1.annotations.json"), "{e}");
    std::fs::write(dir.path().join("scene_2.annotations.json"), "{}").unwrap();
    let e = scan_files(dir.path()).unwrap_err().to_string();
    assert!(e.contains("several annotation files (scene_1, scene_2)"), "{e}");
    let e = scan_files(&dir.path().join("absent")).unwrap_err().to_string();
    assert!(e.contains("absent"), "{e}");
}

#[test]
fn garbage_never_panics() {
    use rand::Rng;
    let mut rng = crate::math::rng(5);
    let annotations = fixture_annotations();
    let seed = fixture_ply().into_bytes();
    for _ in 0..200 {
        let mut bytes = seed.clone();
        for _ in 0..rng.random_range(1..5) {
            let i = rng.random_range(0..bytes.len());
            bytes[i] = rng.random();
        }
        let _ = import(&bytes, &annotations);
        let mut text = annotations.clone().into_bytes();
        let i = rng.random_range(0..text.len());
        text[i] = b"0123456789,:{}[]\"-"[rng.random_range(0..18)];
        if let Ok(text) = String::from_utf8(text) {
            let _ = import(&seed, &text);
        }
    }
}
