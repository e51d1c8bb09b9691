//! Triangle meshes in PLY whose faces carry `MultiScan`'s two ids, `objectId` and `partId`:
//! `vertex` with scalar `x y z`, `face` with a list `vertex_indices` (or `vertex_index`) and the
//! two id properties, any integer type (`MultiScan` writes `ushort`). Polygons are split into fans; other elements and
//! properties are ignored. Element counts are checked against the bytes left before anything is
//! parsed (as the scan reader does), coordinates are finite and within
//! [`crate::scan::MAX_COORDINATE_M`], every index names a vertex.

use std::io::Cursor;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType};

use super::ImportError;
use crate::math::Vec3;
use crate::report::Warning;
use crate::scan::{MAX_COORDINATE_M, check_element_length, one_line, type_name};

/// A triangle with the two ids of the face it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshFace {
    pub vertices: [u32; 3],
    /// The face's `objectId`.
    pub object: i64,
    /// The face's `partId`.
    pub part: i64,
    /// Index of the PLY face it came from (polygons give several triangles).
    pub source_face: usize,
}

/// A mesh as read: world-frame vertices and id-carrying triangles.
#[derive(Clone, Debug, Default)]
pub struct FaceMesh {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<MeshFace>,
}

#[derive(Default)]
struct RawVertex([f64; 3]);

impl PropertyAccess for RawVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set_double(name, f64::from(value))
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        match ["x", "y", "z"].iter().position(|a| *a == name) {
            Some(axis) => {
                self.0[axis] = value;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

/// The per-face object id property (`MultiScan`).
pub const OBJECT_ID: &str = "objectId";
/// The per-face part id property (`MultiScan`).
pub const PART_ID: &str = "partId";

/// A face as read: its vertex indices and its two ids.
struct RawFace {
    indices: Vec<i64>,
    object: i64,
    part: i64,
}

impl RawFace {
    fn set_id(&mut self, name: &str, value: i64) -> PropertyAccessResult {
        match name {
            OBJECT_ID => self.object = value,
            PART_ID => self.part = value,
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }

    fn set_indices(&mut self, name: &str, values: impl Iterator<Item = i64>) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        self.indices = values.collect();
        PropertyAccessResult::Set
    }
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl PropertyAccess for RawFace {
    fn new() -> Self {
        Self { indices: Vec::new(), object: 0, part: 0 }
    }
    fn set_char(&mut self, name: &str, value: i8) -> PropertyAccessResult {
        self.set_id(name, i64::from(value))
    }
    fn set_uchar(&mut self, name: &str, value: u8) -> PropertyAccessResult {
        self.set_id(name, i64::from(value))
    }
    fn set_short(&mut self, name: &str, value: i16) -> PropertyAccessResult {
        self.set_id(name, i64::from(value))
    }
    fn set_ushort(&mut self, name: &str, value: u16) -> PropertyAccessResult {
        self.set_id(name, i64::from(value))
    }
    fn set_int(&mut self, name: &str, value: i32) -> PropertyAccessResult {
        self.set_id(name, i64::from(value))
    }
    fn set_uint(&mut self, name: &str, value: u32) -> PropertyAccessResult {
        self.set_id(name, i64::from(value))
    }
    fn set_list_char(&mut self, name: &str, value: Vec<i8>) -> PropertyAccessResult {
        self.set_indices(name, value.into_iter().map(i64::from))
    }
    fn set_list_uchar(&mut self, name: &str, value: Vec<u8>) -> PropertyAccessResult {
        self.set_indices(name, value.into_iter().map(i64::from))
    }
    fn set_list_short(&mut self, name: &str, value: Vec<i16>) -> PropertyAccessResult {
        self.set_indices(name, value.into_iter().map(i64::from))
    }
    fn set_list_ushort(&mut self, name: &str, value: Vec<u16>) -> PropertyAccessResult {
        self.set_indices(name, value.into_iter().map(i64::from))
    }
    fn set_list_int(&mut self, name: &str, value: Vec<i32>) -> PropertyAccessResult {
        self.set_indices(name, value.into_iter().map(i64::from))
    }
    fn set_list_uint(&mut self, name: &str, value: Vec<u32>) -> PropertyAccessResult {
        self.set_indices(name, value.into_iter().map(i64::from))
    }
}

/// Elements neither `vertex` nor `face`: parsed to advance the reader, values dropped.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// What a property must be.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Want {
    Coordinate,
    Integer,
    IntegerList,
}

fn is_integer(s: &ScalarType) -> bool {
    !matches!(s, ScalarType::Float | ScalarType::Double)
}

/// Checks that `def` has the property `name` of the wanted type.
fn check_property(def: &ElementDef, name: &str, want: Want, file: &str) -> Result<(), ImportError> {
    let Some(p) = def.properties.get(name) else {
        let found: Vec<&str> = def.properties.keys().map(String::as_str).collect();
        return Err(ImportError::Ply {
            file: file.to_owned(),
            detail: format!("the `{}` element has no property `{name}` (it has: {})", def.name, found.join(", ")),
        });
    };
    let ok = match (&p.data_type, want) {
        (PropertyType::Scalar(ScalarType::Float | ScalarType::Double), Want::Coordinate) => true,
        (PropertyType::Scalar(s), Want::Integer) | (PropertyType::List(_, s), Want::IntegerList) => is_integer(s),
        _ => false,
    };
    if ok {
        return Ok(());
    }
    let expected = match want {
        Want::Coordinate => "float or double",
        Want::Integer => "an integer type (char, uchar, short, ushort, int, uint)",
        Want::IntegerList => "a list of integers",
    };
    Err(ImportError::Ply {
        file: file.to_owned(),
        detail: format!("`{}` property `{name}` has type {}; expected {expected}", def.name, type_name(&p.data_type)),
    })
}

/// Reads a mesh PLY held in memory whose faces carry [`OBJECT_ID`] and [`PART_ID`]. `file` names
/// it in errors; faces with fewer than three vertices are skipped with a warning.
pub fn read_face_mesh(bytes: &[u8], file: &str, warnings: &mut Vec<Warning>) -> Result<FaceMesh, ImportError> {
    let ply_error = |detail: String| ImportError::Ply { file: file.to_owned(), detail };
    if !bytes.starts_with(b"ply") {
        return Err(ply_error("not a PLY file (it does not start with `ply`)".into()));
    }
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = Parser::<Skip>::new().read_header(&mut reader).map_err(|e| ply_error(format!("unreadable header: {}", one_line(&e))))?;
    let (Some(vertex_def), Some(face_def)) = (header.elements.get("vertex"), header.elements.get("face")) else {
        let found: Vec<&str> = header.elements.keys().map(String::as_str).collect();
        return Err(ply_error(format!("expected `vertex` and `face` elements (a triangle mesh), found: {}", found.join(", "))));
    };
    for axis in ["x", "y", "z"] {
        check_property(vertex_def, axis, Want::Coordinate, file)?;
    }
    let index_list = if face_def.properties.contains_key("vertex_index") { "vertex_index" } else { "vertex_indices" };
    check_property(face_def, index_list, Want::IntegerList, file)?;
    for id in [OBJECT_ID, PART_ID] {
        check_property(face_def, id, Want::Integer, file)?;
    }

    let mut mesh = FaceMesh::default();
    let mut raw_faces = Vec::new();
    for (name, def) in &header.elements {
        let position = usize::try_from(reader.get_ref().position()).unwrap_or(usize::MAX);
        let rest = bytes.len().saturating_sub(position);
        if !check_element_length(def, header.encoding, rest, file)? {
            continue;
        }
        let parse_error = |e: ply_rs_bw::parser::ParseError| ply_error(format!("malformed `{name}` element: {}", one_line(&e)));
        match name.as_str() {
            "vertex" => {
                let raw = Parser::<RawVertex>::new().read_payload_for_element(&mut reader, def, &header).map_err(parse_error)?;
                mesh.vertices = checked_vertices(&raw, file)?;
            }
            "face" => raw_faces = Parser::<RawFace>::new().read_payload_for_element(&mut reader, def, &header).map_err(parse_error)?,
            _ => {
                Parser::<Skip>::new().read_payload_for_element(&mut reader, def, &header).map_err(parse_error)?;
            }
        }
    }
    mesh.faces = triangles(&raw_faces, mesh.vertices.len(), file, warnings)?;
    Ok(mesh)
}

/// The vertices as `f32`, each coordinate finite and within [`MAX_COORDINATE_M`].
fn checked_vertices(raw: &[RawVertex], file: &str) -> Result<Vec<Vec3>, ImportError> {
    let mut out = Vec::with_capacity(raw.len());
    for (vertex, v) in raw.iter().enumerate() {
        for (axis, &value) in ["x", "y", "z"].iter().zip(&v.0) {
            if !value.is_finite() || value.abs() > f64::from(MAX_COORDINATE_M) {
                return Err(ImportError::Vertex { file: file.to_owned(), vertex, axis, value, limit: MAX_COORDINATE_M });
            }
        }
        out.push(Vec3::new(v.0[0] as f32, v.0[1] as f32, v.0[2] as f32));
    }
    Ok(out)
}

/// Faces split into triangle fans; indices checked against the vertex count.
fn triangles(raw: &[RawFace], vertex_count: usize, file: &str, warnings: &mut Vec<Warning>) -> Result<Vec<MeshFace>, ImportError> {
    let mut out = Vec::with_capacity(raw.len());
    let mut degenerate = 0_usize;
    for (face, f) in raw.iter().enumerate() {
        if f.indices.len() < 3 {
            degenerate += 1;
            continue;
        }
        let mut index = Vec::with_capacity(f.indices.len());
        for &i in &f.indices {
            match u32::try_from(i) {
                Ok(v) if (v as usize) < vertex_count => index.push(v),
                _ => {
                    return Err(ImportError::Face {
                        file: file.to_owned(),
                        face,
                        detail: format!("vertex index {i}; expected 0..{vertex_count} (the `vertex` count)"),
                    });
                }
            }
        }
        for k in 1..index.len() - 1 {
            out.push(MeshFace { vertices: [index[0], index[k], index[k + 1]], object: f.object, part: f.part, source_face: face });
        }
    }
    if degenerate > 0 {
        warnings.push(Warning::new("import", file, format!("{degenerate} faces with fewer than 3 vertices skipped")));
    }
    Ok(out)
}
