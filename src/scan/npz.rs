//! Scans as `NumPy` `.npz` archives, for ML pipelines: `numpy.savez` / `numpy.savez_compressed` of
//!
//! | array | shape, dtype | meaning |
//! | --- | --- | --- |
//! | `points` | (N, 3) float32 or float64 | x, y, z in metres, world frame, +z up |
//! | `object_ids` | (N,) any integer dtype | object instance id per point; -1 = background |
//! | `part_ids` | (N,) any integer dtype | part instance id per point; -1 = background |
//! | `normals` | (N, 3) float32 or float64, optional | per-point normals |
//! | `label_part_ids` + `label_names` | (K,) integer + (K,) string, optional | part id → label |
//! | `category_object_ids` + `category_names` | (M,) integer + (M,) string, optional | object id → category |
//!
//! Strings are fixed-width `NumPy` strings, no pickles: `np.array(["door", "body"])` (dtype `<U..`)
//! or bytes (`S..`, UTF-8). The two label pairs carry what the labels JSON carries
//! (`../shared/spec/scan-format.md` §1) and follow its rules (a label pair that names a part not
//! in the scan is an error, as in the JSON). Without them, a labels JSON beside the archive
//! (`NAME.json` beside `NAME.npz`) is read as for a PLY; both at once is an error. Other arrays are
//! ignored, as other PLY properties are. C and Fortran order are both read.
//!
//! ```python
//! np.savez_compressed("room.npz", points=xyz, object_ids=obj, part_ids=part,
//!                     label_part_ids=np.array([17, 18]), label_names=np.array(["drawer", "body"]),
//!                     category_object_ids=np.array([3]), category_names=np.array(["cabinet"]))
//! ```
//!
//! Bounds: an array is read only up to its declared uncompressed size, the arrays read from one
//! archive inflate to at most [`MAX_INFLATED_BYTES`] together, memory grows with the bytes
//! actually inflated, and an array's header must match its data's length exactly before anything
//! is decoded. Coordinates obey the PLY reader's
//! [`MAX_COORDINATE_M`].

use std::collections::BTreeMap;
use std::io::{Cursor, Read};

use zip::ZipArchive;

use super::error::ScanError;
use super::labels::{Labels, PartLabel};
use super::npy::{DType, NpyArray, parse_npy, shape_text};
use super::ply::{MAX_COORDINATE_M, RawVertex};

/// Most bytes the arrays read from one archive may inflate to, together (4 GiB: 120 million
/// points as float64 with 64-bit ids).
pub const MAX_INFLATED_BYTES: u64 = 1 << 32;

const POINTS: &str = "points";
const AXES: [&str; 3] = ["x", "y", "z"];
const EXPECT_POINTS: &str = "a float32 or float64 array of shape (N, 3), N >= 1";
const EXPECT_IDS: &str = "an integer array of shape (N,): one id per row of `points`";
const EXPECT_NORMALS: &str = "a float32 or float64 array of shape (N, 3), like `points`";
const EXPECT_KEYS: &str = "an integer array of shape (K,), each id once";
const EXPECT_NAMES: &str = "a string array (numpy str `<U..` or bytes `S..`) of shape (K,), one per id";

/// What an archive holds, before grouping by part.
pub(crate) struct NpzScan {
    pub vertices: Vec<RawVertex>,
    pub has_normals: bool,
    /// From `label_part_ids`/`label_names` and `category_object_ids`/`category_names`.
    pub labels: Option<Labels>,
}

/// Reads a `.npz` scan held in memory; `file` names it in errors.
pub(crate) fn read_npz(bytes: &[u8], file: &str) -> Result<NpzScan, ScanError> {
    let mut archive = Archive::open(bytes, file)?;
    let points_bytes = archive.required(POINTS, EXPECT_POINTS)?;
    let points = archive.parse(POINTS, &points_bytes)?;
    let n = check_rows3(&points, POINTS, EXPECT_POINTS, file)?;
    if n == 0 {
        return Err(array_error(file, POINTS, "has 0 rows (an empty scan)", "at least one point"));
    }
    let object_bytes = archive.required("object_ids", EXPECT_IDS)?;
    let objects = ids(&archive.parse("object_ids", &object_bytes)?, "object_ids", Some(n), EXPECT_IDS, file)?;
    let part_bytes = archive.required("part_ids", EXPECT_IDS)?;
    let parts = ids(&archive.parse("part_ids", &part_bytes)?, "part_ids", Some(n), EXPECT_IDS, file)?;
    let normal_bytes = archive.optional("normals")?;
    let normals = match &normal_bytes {
        Some(bytes) => {
            let array = archive.parse("normals", bytes)?;
            let rows = check_rows3(&array, "normals", EXPECT_NORMALS, file)?;
            if rows != n {
                return Err(array_error(file, "normals", &format!("has {rows} rows, `points` has {n}"), EXPECT_NORMALS));
            }
            Some(array)
        }
        None => None,
    };
    let mut vertices = Vec::with_capacity(n);
    for row in 0..n {
        let mut v = RawVertex { object: objects[row], part: parts[row], ..RawVertex::default() };
        for axis in 0..3 {
            v.position[axis] = coordinate(&points, row, axis, file)?;
            if let Some(normals) = &normals {
                v.normal[axis] = normals.float(normals.index_2d(row, axis)).unwrap_or(f64::NAN) as f32;
            }
        }
        vertices.push(v);
    }
    let labels = archive_labels(&mut archive)?;
    Ok(NpzScan { vertices, has_normals: normals.is_some(), labels })
}

fn array_error(file: &str, array: &str, detail: &str, expected: &str) -> ScanError {
    ScanError::NpzArray { file: file.to_owned(), array: array.to_owned(), detail: detail.to_owned(), expected: expected.to_owned() }
}

/// The zip container: `.npy` members by array name (`points.npy` → `points`).
struct Archive<'a> {
    zip: ZipArchive<Cursor<&'a [u8]>>,
    members: BTreeMap<String, usize>,
    file: &'a str,
    /// Inflated bytes still allowed ([`MAX_INFLATED_BYTES`] less what was read).
    budget: u64,
}

impl<'a> Archive<'a> {
    fn open(bytes: &'a [u8], file: &'a str) -> Result<Self, ScanError> {
        let npz = |detail: String| ScanError::Npz { file: file.to_owned(), detail };
        if bytes.is_empty() {
            return Err(npz("the file is empty (0 bytes)".into()));
        }
        let zip = ZipArchive::new(Cursor::new(bytes)).map_err(|e| npz(e.to_string()))?;
        // Member names are unique in the zip reader's index, in the order `by_index` uses.
        let members = zip
            .file_names()
            .enumerate()
            .filter_map(|(index, name)| name.strip_suffix(".npy").map(|array| (array.to_owned(), index)))
            .collect();
        Ok(Self { zip, members, file, budget: MAX_INFLATED_BYTES })
    }

    /// The array names, for messages.
    fn names(&self) -> String {
        if self.members.is_empty() { "no .npy arrays".into() } else { self.members.keys().cloned().collect::<Vec<_>>().join(", ") }
    }

    fn missing(&self, array: &'static str, expected: &'static str) -> ScanError {
        ScanError::NpzMissingArray { file: self.file.to_owned(), array, found: self.names(), expected }
    }

    fn required(&mut self, array: &'static str, expected: &'static str) -> Result<Vec<u8>, ScanError> {
        match self.optional(array)? {
            Some(bytes) => Ok(bytes),
            None => Err(self.missing(array, expected)),
        }
    }

    /// The bytes of `array.npy`, inflated; `None` when the archive has no such array.
    fn optional(&mut self, array: &str) -> Result<Option<Vec<u8>>, ScanError> {
        let Some(&index) = self.members.get(array) else { return Ok(None) };
        let file = self.file;
        let npz = |detail: String| ScanError::Npz { file: file.to_owned(), detail: format!("member {array}.npy: {detail}") };
        let mut entry = self.zip.by_index(index).map_err(|e| npz(e.to_string()))?;
        let declared = entry.size();
        if declared > self.budget {
            let read = MAX_INFLATED_BYTES - self.budget;
            let detail = format!("is {declared} bytes uncompressed, after {read} bytes of other arrays");
            return Err(array_error(file, array, &detail, "at most 4 GiB for all arrays of a scan together"));
        }
        self.budget -= declared;
        let mut out = Vec::new();
        // One byte past the declared size, to notice a member that inflates to more.
        (&mut entry).take(declared + 1).read_to_end(&mut out).map_err(|e| npz(e.to_string()))?;
        if out.len() as u64 != declared {
            return Err(npz(format!("inflates to {} bytes, its zip entry declares {declared}", out.len())));
        }
        Ok(Some(out))
    }

    fn parse<'b>(&self, array: &str, bytes: &'b [u8]) -> Result<NpyArray<'b>, ScanError> {
        parse_npy(bytes).map_err(|detail| array_error(self.file, array, &detail, "a .npy array as numpy.save writes it"))
    }
}

/// Checks a (N, 3) float array; returns N.
fn check_rows3(array: &NpyArray, name: &str, expected: &str, file: &str) -> Result<usize, ScanError> {
    if !matches!(array.dtype, DType::Float { .. }) {
        return Err(array_error(file, name, &format!("has dtype {} ('{}')", array.dtype.name(), array.descr), expected));
    }
    match array.shape.as_slice() {
        &[rows, 3] => Ok(rows),
        shape => Err(array_error(file, name, &format!("has shape {}", shape_text(shape)), expected)),
    }
}

/// A point coordinate as `f32`, finite and within [`MAX_COORDINATE_M`].
fn coordinate(points: &NpyArray, row: usize, axis: usize, file: &str) -> Result<f32, ScanError> {
    checked_coordinate(points.float(points.index_2d(row, axis)).unwrap_or(f64::NAN), row, axis, file)
}

/// `value`, row `row` and axis `axis` of `points`, as `f32`, finite and within [`MAX_COORDINATE_M`].
pub(crate) fn checked_coordinate(value: f64, row: usize, axis: usize, file: &str) -> Result<f32, ScanError> {
    // A finite double beyond the f32 range becomes ±inf and is reported as non-finite.
    let c = value as f32;
    if !c.is_finite() {
        return Err(ScanError::NpzNonFinite { file: file.to_owned(), row, axis: AXES[axis], value: value.to_string() });
    }
    if c.abs() > MAX_COORDINATE_M {
        return Err(ScanError::NpzOutOfRange { file: file.to_owned(), row, axis: AXES[axis], value, limit: MAX_COORDINATE_M });
    }
    Ok(c)
}

/// A 1-D integer array as `i64` ids, of length `len` when given.
fn ids(array: &NpyArray, name: &str, len: Option<usize>, expected: &str, file: &str) -> Result<Vec<i64>, ScanError> {
    if !matches!(array.dtype, DType::Int { .. }) {
        return Err(array_error(file, name, &format!("has dtype {} ('{}')", array.dtype.name(), array.descr), expected));
    }
    let n = match (array.shape.as_slice(), len) {
        (&[n], Some(want)) if n != want => {
            return Err(array_error(file, name, &format!("has {n} elements, `points` has {want} rows"), expected));
        }
        (&[n], _) => n,
        (shape, _) => return Err(array_error(file, name, &format!("has shape {}", shape_text(shape)), expected)),
    };
    (0..n)
        .map(|i| match array.int(i) {
            Some(Ok(v)) => Ok(v),
            Some(Err(big)) => Err(array_error(file, name, &format!("element {i} is {big}"), "ids within the signed 64-bit range")),
            None => Err(array_error(file, name, "is not an integer array", expected)),
        })
        .collect()
}

/// A 1-D string array of length `len`.
fn strings(array: &NpyArray, name: &str, len: usize, file: &str) -> Result<Vec<String>, ScanError> {
    if !matches!(array.dtype, DType::Unicode { .. } | DType::Bytes { .. }) {
        return Err(array_error(file, name, &format!("has dtype {} ('{}')", array.dtype.name(), array.descr), EXPECT_NAMES));
    }
    if array.shape.as_slice() != [len] {
        return Err(array_error(file, name, &format!("has shape {}, its ids have {len}", shape_text(&array.shape)), EXPECT_NAMES));
    }
    (0..len)
        .map(|i| match array.string(i) {
            Some(Ok(s)) => Ok(s),
            Some(Err(why)) => Err(array_error(file, name, &format!("element {i} is {why}"), EXPECT_NAMES)),
            None => Err(array_error(file, name, "is not a string array", EXPECT_NAMES)),
        })
        .collect()
}

/// One (ids, names) pair of the archive as a map; `None` when neither array is there.
fn label_pair(archive: &mut Archive, ids_name: &'static str, names_name: &'static str) -> Result<Option<BTreeMap<i64, String>>, ScanError> {
    let file = archive.file;
    let (id_bytes, name_bytes) = (archive.optional(ids_name)?, archive.optional(names_name)?);
    let (id_bytes, name_bytes) = match (id_bytes, name_bytes) {
        (None, None) => return Ok(None),
        (Some(i), Some(n)) => (i, n),
        (Some(_), None) => return Err(archive.missing(names_name, "beside `label_part_ids` / `category_object_ids`: their names")),
        (None, Some(_)) => return Err(archive.missing(ids_name, "beside `label_names` / `category_names`: the ids they name")),
    };
    let keys = ids(&archive.parse(ids_name, &id_bytes)?, ids_name, None, EXPECT_KEYS, file)?;
    let names = strings(&archive.parse(names_name, &name_bytes)?, names_name, keys.len(), file)?;
    let mut map = BTreeMap::new();
    for (row, (id, name)) in keys.into_iter().zip(names).enumerate() {
        if map.insert(id, name).is_some() {
            return Err(array_error(file, ids_name, &format!("repeats id {id} (element {row})"), EXPECT_KEYS));
        }
    }
    Ok(Some(map))
}

/// The labels the archive carries, in the form of the labels JSON.
fn archive_labels(archive: &mut Archive) -> Result<Option<Labels>, ScanError> {
    let parts = label_pair(archive, "label_part_ids", "label_names")?;
    let objects = label_pair(archive, "category_object_ids", "category_names")?;
    if parts.is_none() && objects.is_none() {
        return Ok(None);
    }
    let mut labels = Labels::default();
    for (id, category) in objects.unwrap_or_default() {
        labels.objects.insert(id, Some(category));
    }
    for (id, label) in parts.unwrap_or_default() {
        labels.parts.insert(id, PartLabel { object: None, label: Some(label) });
    }
    Ok(Some(labels))
}
