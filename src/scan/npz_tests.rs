//! `.npz` scans: archives written here (several dtypes, both orders, stored and deflated), archives
//! written by numpy (`tests/fixtures/npz/`), and errors through one data-driven `check`.

use std::io::Write as _;
use std::path::Path;

use rand::Rng;
use zip::CompressionMethod;
use zip::write::SimpleFileOptions;

use super::npy::npy_bytes;
use super::tests::assert_same;
use super::*;
use crate::report::Warning;

const NPZ_NAME: &str = "t.npz";
const LABELS_NAME: &str = "t.json";

/// The scan of `tests/fixtures/npz/room.ply`: two parts of object 3, one of object 5, one
/// background point. Every value is exact in float32.
const POINTS: [[f64; 3]; 6] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 2.5, -0.25], [0.0, 0.0, 1.0], [0.5, 0.5, 0.5]];
const OBJECTS: [i64; 6] = [3, 3, 3, 3, -1, 5];
const PARTS: [i64; 6] = [17, 17, 18, 18, -1, 4];

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/npz").join(name)
}

/// The reference: the same scan as an ascii PLY with its labels JSON.
fn reference() -> Scan {
    read_scan(&fixture("room.ply")).unwrap().0
}

/// A zip of `NAME.npy` members, as `numpy.savez` (stored) or `savez_compressed` (deflated) writes.
fn npz(members: &[(&str, Vec<u8>)], method: CompressionMethod) -> Vec<u8> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    for (name, npy) in members {
        zip.start_file(format!("{name}.npy"), SimpleFileOptions::default().compression_method(method)).unwrap();
        zip.write_all(npy).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

/// Encodes numbers with `to_bytes` into a `.npy` of `descr` and `shape`.
fn array<T: Copy>(descr: &str, shape: &[usize], values: &[T], to_bytes: impl Fn(T) -> Vec<u8>) -> Vec<u8> {
    let data: Vec<u8> = values.iter().flat_map(|&v| to_bytes(v)).collect();
    npy_bytes(descr, false, shape, &data)
}

/// Points as float32 or float64, C or Fortran order.
fn points(double: bool, fortran: bool, rows: &[[f64; 3]]) -> Vec<u8> {
    let ordered: Vec<f64> =
        if fortran { (0..3).flat_map(|c| rows.iter().map(move |r| r[c])).collect() } else { rows.iter().flatten().copied().collect() };
    let data: Vec<u8> = if double {
        ordered.iter().flat_map(|v| v.to_le_bytes()).collect()
    } else {
        ordered.iter().flat_map(|&v| (v as f32).to_le_bytes()).collect()
    };
    npy_bytes(if double { "<f8" } else { "<f4" }, fortran, &[rows.len(), 3], &data)
}

fn i16s(values: &[i64]) -> Vec<u8> {
    array("<i2", &[values.len()], values, |v| (v as i16).to_le_bytes().to_vec())
}

fn i64s_be(values: &[i64]) -> Vec<u8> {
    array(">i8", &[values.len()], values, |v| v.to_be_bytes().to_vec())
}

fn u32s(values: &[i64]) -> Vec<u8> {
    array("<u4", &[values.len()], values, |v| (v as u32).to_le_bytes().to_vec())
}

/// Fixed-width UCS-4 strings (`<U{width}`), as `np.array(["door", ...])` stores them.
fn unicode(values: &[&str]) -> Vec<u8> {
    let width = values.iter().map(|s| s.chars().count()).max().unwrap_or(1).max(1);
    let mut data = Vec::new();
    for s in values {
        let mut chars: Vec<u32> = s.chars().map(u32::from).collect();
        chars.resize(width, 0);
        data.extend(chars.iter().flat_map(|c| c.to_le_bytes()));
    }
    npy_bytes(&format!("<U{width}"), false, &[values.len()], &data)
}

/// Byte strings (`|S{width}`).
fn bytes(values: &[&str]) -> Vec<u8> {
    let width = values.iter().map(|s| s.len()).max().unwrap_or(1).max(1);
    let mut data = Vec::new();
    for s in values {
        let mut b = s.as_bytes().to_vec();
        b.resize(width, 0);
        data.extend(b);
    }
    npy_bytes(&format!("|S{width}"), false, &[values.len()], &data)
}

/// The reference scan with its labels as arrays in the archive.
fn labelled_members() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("points", points(true, false, &POINTS)),
        ("object_ids", i16s(&OBJECTS)),
        ("part_ids", i64s_be(&PARTS)),
        ("label_part_ids", u32s(&[4, 17, 18])),
        ("label_names", unicode(&["lid", "drawer", "body"])),
        ("category_object_ids", i16s(&[3, 5])),
        ("category_names", bytes(&["cabinet", "box"])),
    ]
}

fn members_without(name: &str) -> Vec<(&'static str, Vec<u8>)> {
    labelled_members().into_iter().filter(|(n, _)| *n != name).collect()
}

fn members_with(name: &'static str, npy: Vec<u8>) -> Vec<(&'static str, Vec<u8>)> {
    let mut members = members_without(name);
    members.push((name, npy));
    members
}

/// What reading should give.
enum Expect {
    /// The reference scan.
    Reference,
    /// An error whose message contains the text (and names the file).
    Err(&'static str),
}

/// Reads an archive held in memory (with an optional labels JSON beside it) and checks the
/// outcome.
fn check(archive: &[u8], labels: Option<&str>, expected: Expect) -> Option<Vec<Warning>> {
    let result = read_scan_npz_bytes(archive, NPZ_NAME, labels, LABELS_NAME);
    match (result, expected) {
        (Ok((scan, warnings)), Expect::Reference) => {
            assert_same(&reference(), &scan);
            assert_eq!(scan.source, NPZ_NAME);
            Some(warnings)
        }
        (Err(e), Expect::Err(needle)) => {
            let message = e.to_string();
            assert!(message.contains(needle), "expected an error containing {needle:?}, got: {message}");
            assert!(message.contains(NPZ_NAME) || message.contains(LABELS_NAME), "error names the file: {message}");
            None
        }
        (Ok((scan, w)), Expect::Err(needle)) => panic!("expected an error containing {needle:?}, read {scan:?}; warnings {w:?}"),
        (Err(e), Expect::Reference) => panic!("expected the reference scan, got error: {e}"),
    }
}

#[test]
fn npz_reads_like_the_equivalent_ply() {
    // Labels in the archive; float64 points; int16, big-endian int64 and uint32 ids; deflated.
    let warnings = check(&npz(&labelled_members(), CompressionMethod::Deflated), None, Expect::Reference).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    // float32 points in Fortran order, stored; labels from the JSON beside the archive.
    let members = vec![
        ("points", points(false, true, &POINTS)),
        ("object_ids", i64s_be(&OBJECTS)),
        ("part_ids", i16s(&PARTS)),
        ("extra", bytes(&["ignored"])),
    ];
    let json = std::fs::read_to_string(fixture("room.json")).unwrap();
    let warnings = check(&npz(&members, CompressionMethod::Stored), Some(&json), Expect::Reference).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    // Without any labels: the PLY's warning, every part "unknown".
    let (scan, warnings) = read_scan_npz_bytes(&npz(&members, CompressionMethod::Stored), NPZ_NAME, None, LABELS_NAME).unwrap();
    assert!(scan.parts.iter().all(|p| p.label == UNKNOWN_LABEL));
    assert!(warnings.iter().any(|w| w.message.contains("labels file not found")), "{warnings:?}");
}

#[test]
fn normals_and_unsigned_ids_are_read() {
    let rows = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let normals = points(false, false, &[[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
    let members = vec![
        ("points", points(true, true, &rows)),
        ("object_ids", array("|u1", &[3], &[200_u8; 3], |v| vec![v])),
        ("part_ids", array("<u8", &[3], &[7_u64; 3], |v| v.to_le_bytes().to_vec())),
        ("normals", normals),
    ];
    let (scan, _) = read_scan_npz_bytes(&npz(&members, CompressionMethod::Deflated), NPZ_NAME, None, LABELS_NAME).unwrap();
    assert_eq!((scan.parts.len(), scan.parts[0].id, scan.parts[0].object), (1, 7, 200));
    assert_eq!(scan.parts[0].normals, Some(vec![Vec3::Z, Vec3::Y, Vec3::X]));
    assert_eq!(scan.parts[0].points[1], Vec3::X);
}

/// Archives written by numpy 2.4 (`tests/fixtures/npz/`): `room_compressed.npz` is
/// `np.savez_compressed` of float64 points in Fortran order, `<i2` object ids, `>i4` part ids,
/// label arrays (`<i8` + `<U6`, `|u1` + `|S7`) and an ignored `colors` array; `room_plain.npz`
/// is `np.savez` of float32 points and int64 ids with `room_plain.json` beside it.
#[test]
fn archives_written_by_numpy_read_like_the_ply() {
    let reference = reference();
    for name in ["room_compressed.npz", "room_plain.npz"] {
        let (scan, warnings) = read_scan(&fixture(name)).unwrap();
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        assert_same(&reference, &scan);
    }
}

/// Cross-check with the numpy on this machine when there is one (CI does not need it): a fresh
/// archive with every integer width. Skips, saying so, without python3 + numpy.
#[test]
fn numpy_on_this_machine_if_any() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fresh.npz");
    let script = format!(
        "import numpy as np\n\
         p = np.array({POINTS:?}, dtype=np.float64)\n\
         np.savez_compressed(r'{}', points=p.astype('>f8'), object_ids=np.array({OBJECTS:?}, dtype=np.int8),\n\
             part_ids=np.array({PARTS:?}, dtype='>i2'), label_part_ids=np.array([17, 18, 4], dtype=np.uint16),\n\
             label_names=np.array(['drawer', 'body', 'lid']), category_object_ids=np.array([3, 5], dtype=np.int32),\n\
             category_names=np.array(['cabinet', 'box']))\n",
        path.display()
    );
    let ran = std::process::Command::new("python3").args(["-c", &script]).output();
    match ran {
        Ok(out) if out.status.success() => {}
        Ok(out) => {
            let why = String::from_utf8_lossy(&out.stderr).lines().last().unwrap_or_default().to_owned();
            eprintln!("SKIPPED numpy cross-check: python3 has no numpy ({why})");
            return;
        }
        Err(e) => {
            eprintln!("SKIPPED numpy cross-check: no python3 ({e})");
            return;
        }
    }
    let (scan, warnings) = read_scan(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_same(&reference(), &scan);
}

#[test]
fn npz_paths_go_through_read_scan_with_the_labels_beside_them() {
    let dir = tempfile::tempdir().unwrap();
    let members: Vec<_> = labelled_members().into_iter().take(3).collect();
    let path = dir.path().join("Room.NPZ");
    std::fs::write(&path, npz(&members, CompressionMethod::Deflated)).unwrap();
    std::fs::copy(fixture("room.json"), dir.path().join("Room.json")).unwrap();
    assert!(is_npz_path(&path) && !is_npz_path(Path::new("room.ply")));
    let (scan, warnings) = read_scan(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_same(&reference(), &scan);
    // A PLY named .npz is read as an archive, and says so.
    std::fs::copy(fixture("room.ply"), &path).unwrap();
    let e = read_scan(&path).unwrap_err().to_string();
    assert!(e.contains("Room.NPZ: not a readable NumPy .npz archive"), "{e}");
}

#[test]
fn errors_name_the_file_the_array_and_what_was_expected() {
    let deflated = |members: &[(&str, Vec<u8>)]| npz(members, CompressionMethod::Deflated);
    let four = &POINTS[..4];
    let mut nan = POINTS;
    nan[2][1] = f64::NAN;
    let mut huge = POINTS;
    huge[0][0] = 1e39;
    let mut far = POINTS;
    far[1][2] = -2e4;
    let json = std::fs::read_to_string(fixture("room.json")).unwrap();
    let cases: Vec<(Vec<u8>, Option<&str>, &str)> = vec![
        (Vec::new(), None, "not a readable NumPy .npz archive (a zip of .npy arrays, as numpy.savez writes): the file is empty"),
        (std::fs::read(fixture("room.ply")).unwrap(), None, "not a readable NumPy .npz archive"),
        (deflated(&members_without("points")), None, "no array `points` in the .npz (it holds: category_names, category_object_ids,"),
        (deflated(&members_without("part_ids")), None, "no array `part_ids`"),
        (
            deflated(&members_with("points", array("<f8", &[6, 2], &[0.0_f64; 12], |v| v.to_le_bytes().to_vec()))),
            None,
            "array `points` has shape (6, 2); expected a float32 or float64 array of shape (N, 3), N >= 1",
        ),
        (
            deflated(&members_with("points", array("<i4", &[6, 3], &[0_i32; 18], |v| v.to_le_bytes().to_vec()))),
            None,
            "has dtype int32 ('<i4')",
        ),
        (deflated(&members_with("points", points(true, false, &[]))), None, "has 0 rows (an empty scan)"),
        (deflated(&members_with("points", points(true, false, four))), None, "array `object_ids` has 6 elements, `points` has 4 rows"),
        (
            deflated(&members_with("part_ids", array("<f4", &[6], &[1.0_f32; 6], |v| v.to_le_bytes().to_vec()))),
            None,
            "array `part_ids` has dtype float32 ('<f4'); expected an integer array of shape (N,)",
        ),
        (deflated(&members_with("part_ids", array("<i8", &[6, 1], &PARTS, |v| v.to_le_bytes().to_vec()))), None, "has shape (6, 1)"),
        (deflated(&members_with("points", points(true, false, &nan))), None, "array `points` row 2 has a non-finite y (NaN)"),
        (
            deflated(&members_with("points", points(true, false, &huge))),
            None,
            "row 0 has a non-finite x (1000000000000000000000000000000000000000)",
        ),
        (deflated(&members_with("points", points(false, true, &far))), None, "row 1 has z = -2e4 m; expected |z| <= 1e4 m"),
        (
            deflated(&members_with("object_ids", array("<u8", &[6], &[u64::MAX; 6], |v| v.to_le_bytes().to_vec()))),
            None,
            "array `object_ids` element 0 is 18446744073709551615; expected ids within the signed 64-bit range",
        ),
        (
            deflated(&members_with("part_ids", npy_bytes("|O", false, &[6], &[0; 48]))),
            None,
            "dtype '|O' (Python objects, stored as a pickle)",
        ),
        (deflated(&members_without("label_names")), None, "no array `label_names`"),
        (deflated(&members_without("category_object_ids")), None, "no array `category_object_ids`"),
        (deflated(&members_with("label_names", unicode(&["lid", "drawer"]))), None, "array `label_names` has shape (2,), its ids have 3"),
        (deflated(&members_with("label_names", i16s(&[1, 2, 3]))), None, "array `label_names` has dtype int16"),
        (deflated(&members_with("label_part_ids", u32s(&[17, 18, 17]))), None, "array `label_part_ids` repeats id 17 (element 2)"),
        (deflated(&members_with("label_part_ids", u32s(&[17, 18, 99]))), None, "t.npz (label arrays): the labels name part 99"),
        (deflated(&labelled_members()), Some(&json), "and t.json exists beside it"),
        (deflated(&members_with("points", b"PK not npy".to_vec())), None, "array `points` not a .npy array"),
        (
            deflated(&members_with("points", npy_bytes("<f4", false, &[6, 3], &[0; 36]))),
            None,
            "array `points` holds 36 bytes of data; its shape (6, 3) of float32 needs 72",
        ),
        (deflated(&members_with("normals", points(false, false, four))), None, "array `normals` has 4 rows, `points` has 6"),
        (deflated(&labelled_members()[..3]), Some("{\"parts\": 3}"), "t.json: malformed labels JSON"),
    ];
    for (archive, labels, needle) in cases {
        check(&archive, labels, Expect::Err(needle));
    }
}

/// A member whose zip entry understates its size, or whose data were damaged after writing.
#[test]
fn damaged_members_are_errors() {
    let whole = npz(&labelled_members(), CompressionMethod::Stored);
    // Flip a byte inside the points' data: the CRC no longer matches.
    let at = whole.windows(6).position(|w| w == b"\x93NUMPY").unwrap() + 200;
    let mut flipped = whole.clone();
    flipped[at] ^= 0x55;
    check(&flipped, None, Expect::Err("member points.npy"));
    for cut in [whole.len() / 2, whole.len() - 30, 10] {
        check(&whole[..cut], None, Expect::Err("t.npz"));
    }
}

#[test]
fn garbage_never_panics() {
    let mut rng = crate::math::rng(11);
    for method in [CompressionMethod::Stored, CompressionMethod::Deflated] {
        let seed = npz(&labelled_members(), method);
        for _ in 0..300 {
            let mut bytes = seed.clone();
            for _ in 0..rng.random_range(1..6) {
                let i = rng.random_range(0..bytes.len());
                bytes[i] = rng.random();
            }
            if rng.random_bool(0.2) {
                bytes.truncate(rng.random_range(0..bytes.len()));
            }
            let _ = read_scan_npz_bytes(&bytes, NPZ_NAME, None, LABELS_NAME);
        }
    }
}
