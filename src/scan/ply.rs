//! Reading the PLY half of a scan: header checks, then the `vertex` element straight into a small
//! struct (ply-rs-bw's `PropertyAccess`, no map per vertex). Elements after `vertex` (mesh faces)
//! are never parsed.

use std::io::{Cursor, ErrorKind};

use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType};

use super::error::ScanError;
use crate::report::Warning;

/// One vertex as read: only the properties the scan format uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RawVertex {
    pub position: [f32; 3],
    pub object: i64,
    pub part: i64,
    pub normal: [f32; 3],
}

impl RawVertex {
    fn set_real(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.position[0],
            "y" => &mut self.position[1],
            "z" => &mut self.position[2],
            "nx" => &mut self.normal[0],
            "ny" => &mut self.normal[1],
            "nz" => &mut self.normal[2],
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = value;
        PropertyAccessResult::Set
    }

    fn set_integer(&mut self, name: &str, value: i64) -> PropertyAccessResult {
        match name {
            "object" => self.object = value,
            "part" => self.part = value,
            // Integer coordinates or normals: lenient, the value is exact in f32 for small ints.
            _ => return self.set_real(name, value as f32),
        }
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for RawVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_char(&mut self, name: &str, value: i8) -> PropertyAccessResult {
        self.set_integer(name, i64::from(value))
    }
    fn set_uchar(&mut self, name: &str, value: u8) -> PropertyAccessResult {
        self.set_integer(name, i64::from(value))
    }
    fn set_short(&mut self, name: &str, value: i16) -> PropertyAccessResult {
        self.set_integer(name, i64::from(value))
    }
    fn set_ushort(&mut self, name: &str, value: u16) -> PropertyAccessResult {
        self.set_integer(name, i64::from(value))
    }
    fn set_int(&mut self, name: &str, value: i32) -> PropertyAccessResult {
        self.set_integer(name, i64::from(value))
    }
    fn set_uint(&mut self, name: &str, value: u32) -> PropertyAccessResult {
        self.set_integer(name, i64::from(value))
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set_real(name, value)
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        // A finite double beyond the f32 range becomes ±inf and is reported as non-finite.
        self.set_real(name, value as f32)
    }
}

/// Elements before `vertex` (rare): parsed to advance the reader, values dropped.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// The vertices of a PLY.
#[derive(Debug)]
pub(crate) struct PlyVertices {
    pub vertices: Vec<RawVertex>,
    /// `nx ny nz` are all declared (as scalars).
    pub has_normals: bool,
}

const COORDINATES: [&str; 3] = ["x", "y", "z"];
const IDS: [&str; 2] = ["object", "part"];
const NORMALS: [&str; 3] = ["nx", "ny", "nz"];

/// Reads the `vertex` element of a PLY held in memory. `file` names it in errors and warnings.
pub(crate) fn read_vertices(bytes: &[u8], file: &str, warnings: &mut Vec<Warning>) -> Result<PlyVertices, ScanError> {
    if bytes.is_empty() {
        return Err(ScanError::Header { file: file.to_owned(), detail: "the file is empty (0 bytes)".into() });
    }
    if !bytes.starts_with(b"ply") {
        let shown: String = String::from_utf8_lossy(&bytes[..bytes.len().min(16)]).escape_debug().collect();
        return Err(ScanError::Header { file: file.to_owned(), detail: format!("the file starts with \"{shown}\", not \"ply\"") });
    }
    let mut reader = Reader::new(Cursor::new(bytes));
    let header =
        Parser::<Skip>::new().read_header(&mut reader).map_err(|e| ScanError::Header { file: file.to_owned(), detail: one_line(&e) })?;
    let Some(vertex_def) = header.elements.get("vertex") else {
        let found: Vec<&str> = header.elements.keys().map(String::as_str).collect();
        let found = if found.is_empty() { "none".to_owned() } else { found.join(", ") };
        return Err(ScanError::NoVertexElement { file: file.to_owned(), found });
    };
    let has_normals = check_properties(vertex_def, file, warnings)?;
    if vertex_def.count == 0 {
        return Err(ScanError::Empty { file: file.to_owned() });
    }

    for (name, def) in &header.elements {
        if name != "vertex" {
            let position = usize::try_from(reader.get_ref().position()).unwrap_or(usize::MAX);
            let rest = bytes.len().saturating_sub(position);
            if !check_element_length(def, header.encoding, rest, file)? {
                continue;
            }
            let start_line = reader.line();
            Parser::<Skip>::new()
                .read_payload_for_element(&mut reader, def, &header)
                .map_err(|e| body_error(&e, file, def, start_line, &header))?;
            continue;
        }
        let start_line = reader.line();
        let start_byte = usize::try_from(reader.get_ref().position()).unwrap_or(usize::MAX);
        let body = bytes.get(start_byte..).unwrap_or_default();
        if header.encoding == Encoding::Ascii {
            check_ascii_length(def, body, file)?;
        } else {
            check_binary_length(def, body, file)?;
        }
        let vertices = Parser::<RawVertex>::new()
            .read_payload_for_element(&mut reader, def, &header)
            .map_err(|e| vertex_error(&e, file, def, start_line, body, &header))?;
        check_coordinates(&vertices, file)?;
        return Ok(PlyVertices { vertices, has_normals });
    }
    // `vertex` is among the elements (checked above), so the loop returned.
    Err(ScanError::NoVertexElement { file: file.to_owned(), found: "none".into() })
}

/// Longest parser message kept in an error (an ascii line of a binary body can be megabytes).
const MAX_DETAIL_CHARS: usize = 300;

/// The parser's multi-line message on one line, shortened.
pub(crate) fn one_line(e: &ParseError) -> String {
    let text = e.to_string();
    let mut out = text.split(['\n', '\t', '\r']).map(str::trim).filter(|s| !s.is_empty()).collect::<Vec<_>>().join(" ");
    if let Some((cut, _)) = out.char_indices().nth(MAX_DETAIL_CHARS) {
        out.truncate(cut);
        out.push_str("...");
    }
    out
}

pub(crate) fn type_name(data_type: &PropertyType) -> String {
    fn scalar(s: &ScalarType) -> &'static str {
        match s {
            ScalarType::Char => "char",
            ScalarType::UChar => "uchar",
            ScalarType::Short => "short",
            ScalarType::UShort => "ushort",
            ScalarType::Int => "int",
            ScalarType::UInt => "uint",
            ScalarType::Float => "float",
            ScalarType::Double => "double",
        }
    }
    match data_type {
        PropertyType::Scalar(s) => scalar(s).to_owned(),
        PropertyType::List(i, s) => format!("list {} {}", scalar(i), scalar(s)),
    }
}

/// Checks the required properties and their types; returns whether normals are present.
fn check_properties(def: &ElementDef, file: &str, warnings: &mut Vec<Warning>) -> Result<bool, ScanError> {
    for property in COORDINATES.into_iter().chain(IDS) {
        if !def.properties.contains_key(property) {
            return Err(ScanError::MissingProperty { file: file.to_owned(), property });
        }
    }
    for property in COORDINATES {
        if let Some(p) = def.properties.get(property)
            && matches!(p.data_type, PropertyType::List(..))
        {
            return Err(ScanError::PropertyType {
                file: file.to_owned(),
                property: property.to_owned(),
                found: type_name(&p.data_type),
                expected: "float or double",
            });
        }
    }
    for property in IDS {
        if let Some(p) = def.properties.get(property)
            && !matches!(
                p.data_type,
                PropertyType::Scalar(
                    ScalarType::Char | ScalarType::UChar | ScalarType::Short | ScalarType::UShort | ScalarType::Int | ScalarType::UInt
                )
            )
        {
            return Err(ScanError::PropertyType {
                file: file.to_owned(),
                property: property.to_owned(),
                found: type_name(&p.data_type),
                expected: "an integer type (char, uchar, short, ushort, int, uint or int8..uint32)",
            });
        }
    }
    let present: Vec<&str> = NORMALS.into_iter().filter(|n| def.properties.contains_key(*n)).collect();
    let scalar = NORMALS.into_iter().all(|n| def.properties.get(n).is_some_and(|p| matches!(p.data_type, PropertyType::Scalar(_))));
    if present.len() == NORMALS.len() && scalar {
        return Ok(true);
    }
    if !present.is_empty() {
        warnings.push(Warning::new(
            "scan",
            file,
            format!("normals ignored: found {} of nx, ny, nz as scalars; expected all three", present.join(", ")),
        ));
    }
    Ok(false)
}

/// Size in bytes of one element when it has only scalar properties.
fn binary_stride(def: &ElementDef) -> Option<usize> {
    def.properties
        .values()
        .map(|p| match p.data_type {
            PropertyType::Scalar(ScalarType::Char | ScalarType::UChar) => Some(1),
            PropertyType::Scalar(ScalarType::Short | ScalarType::UShort) => Some(2),
            PropertyType::Scalar(ScalarType::Int | ScalarType::UInt | ScalarType::Float) => Some(4),
            PropertyType::Scalar(ScalarType::Double) => Some(8),
            PropertyType::List(..) => None,
        })
        .sum()
}

/// Fewest bytes one element can take: binary, each scalar's size and each list's count; ascii,
/// one line (a newline) with at least one character per property.
fn min_element_bytes(def: &ElementDef, encoding: Encoding) -> usize {
    if encoding == Encoding::Ascii {
        return def.properties.len().max(1);
    }
    def.properties
        .values()
        .map(|p| match p.data_type {
            PropertyType::Scalar(ref s) | PropertyType::List(ref s, _) => match s {
                ScalarType::Char | ScalarType::UChar => 1,
                ScalarType::Short | ScalarType::UShort => 2,
                ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
                ScalarType::Double => 8,
            },
        })
        .sum()
}

/// An element before `vertex` (skipped, not stored) must fit in the bytes left, at its smallest
/// size: a count the file cannot hold is refused before the parser loops over it. Returns
/// whether the element has to be parsed at all: a binary element without properties takes no
/// bytes, so any count of it is skipped at once instead of counted through one by one.
pub(crate) fn check_element_length(def: &ElementDef, encoding: Encoding, rest: usize, file: &str) -> Result<bool, ScanError> {
    let min_bytes = min_element_bytes(def, encoding);
    if min_bytes == 0 {
        return Ok(false);
    }
    if def.count <= rest / min_bytes {
        return Ok(true);
    }
    Err(ScanError::Truncated {
        file: file.to_owned(),
        detail: format!(
            "the header declares {} `{}` elements of at least {min_bytes} bytes each, but only {rest} bytes follow",
            def.count, def.name
        ),
    })
}

/// A precise truncation error before parsing when the vertex layout has a fixed size.
fn check_binary_length(def: &ElementDef, body: &[u8], file: &str) -> Result<(), ScanError> {
    let Some(stride) = binary_stride(def) else { return Ok(()) };
    let needed = def.count.saturating_mul(stride);
    if stride == 0 || body.len() >= needed {
        return Ok(());
    }
    Err(ScanError::Truncated {
        file: file.to_owned(),
        detail: format!(
            "the header declares {} vertices of {stride} bytes ({needed} bytes), but only {} bytes follow the header ({} complete vertices)",
            def.count,
            body.len(),
            body.len() / stride
        ),
    })
}

fn body_error(e: &ParseError, file: &str, def: &ElementDef, start_line: usize, header: &Header) -> ScanError {
    let index = e.line().map(|l| l.saturating_sub(start_line));
    if e.kind() == ErrorKind::UnexpectedEof {
        let detail = match (header.encoding, index) {
            (Encoding::Ascii, Some(i)) => {
                format!("expected {} `{}` elements, the file ends after {i}", def.count, def.name)
            }
            _ => format!("expected {} `{}` elements: {}", def.count, def.name, one_line(e)),
        };
        return ScanError::Truncated { file: file.to_owned(), detail };
    }
    let at = match index {
        Some(i) => format!("`{}` element {i}", def.name),
        None => format!("element `{}`", def.name),
    };
    ScanError::Body { file: file.to_owned(), at, detail: one_line(e) }
}

/// Maps a parse error in the vertex element; for ascii, names a `nan`/`inf` token precisely.
fn vertex_error(e: &ParseError, file: &str, def: &ElementDef, start_line: usize, body: &[u8], header: &Header) -> ScanError {
    if header.encoding == Encoding::Ascii
        && e.kind() != ErrorKind::UnexpectedEof
        && let Some(vertex) = e.line().map(|l| l.saturating_sub(start_line))
        && let Some(line) = body.split(|&b| b == b'\n').nth(vertex)
        && let Some((property, token)) = non_finite_token(&String::from_utf8_lossy(line), def)
    {
        return ScanError::NonFinite { file: file.to_owned(), vertex, property, value: token };
    }
    body_error(e, file, def, start_line, header)
}

/// The first token of an ascii vertex line that spells a non-finite number, with its property
/// (the grammar of ply-rs-bw rejects such tokens, so this only runs on the error path).
fn non_finite_token(line: &str, def: &ElementDef) -> Option<(String, String)> {
    let all_scalar = def.properties.values().all(|p| matches!(p.data_type, PropertyType::Scalar(_)));
    for (i, token) in line.split_ascii_whitespace().enumerate() {
        let lower = token.to_ascii_lowercase();
        let unsigned = lower.trim_start_matches(['+', '-']);
        let spelled = matches!(unsigned, "nan" | "inf" | "infinity" | "1.#inf" | "1.#qnan" | "1.#ind");
        if spelled || token.parse::<f64>().is_ok_and(|v| !v.is_finite()) {
            let property = if all_scalar {
                def.properties.keys().nth(i).cloned().unwrap_or_else(|| format!("value {i}"))
            } else {
                format!("value {i}")
            };
            return Some((property, token.to_owned()));
        }
    }
    None
}

/// Largest coordinate magnitude accepted, metres. A scan of a room or a building spans tens of
/// metres; 10 km leaves room for georeferenced offsets while keeping every size derived from the
/// points (boxes, areas, sample counts, grids) far from overflow, and f32 still resolves a
/// millimetre there. Anything larger is a unit or encoding error, not a scan.
pub const MAX_COORDINATE_M: f32 = 1.0e4;

/// Every coordinate finite and within [`MAX_COORDINATE_M`]; the first that is not is named.
fn check_coordinates(vertices: &[RawVertex], file: &str) -> Result<(), ScanError> {
    for (vertex, v) in vertices.iter().enumerate() {
        for (axis, c) in v.position.iter().enumerate() {
            let property = COORDINATES[axis].to_owned();
            if !c.is_finite() {
                return Err(ScanError::NonFinite { file: file.to_owned(), vertex, property, value: c.to_string() });
            }
            if c.abs() > MAX_COORDINATE_M {
                return Err(ScanError::OutOfRange { file: file.to_owned(), vertex, property, value: *c, limit: MAX_COORDINATE_M });
            }
        }
    }
    Ok(())
}

/// An ascii vertex takes at least one byte per property: a header that declares more vertices
/// than the body can hold is refused before anything is allocated (the parser's own message,
/// with the line where the file ends, covers the counts in between).
fn check_ascii_length(def: &ElementDef, body: &[u8], file: &str) -> Result<(), ScanError> {
    let min_bytes = def.properties.len().max(1);
    let most = body.len() / min_bytes;
    if def.count <= most {
        return Ok(());
    }
    Err(ScanError::Truncated {
        file: file.to_owned(),
        detail: format!(
            "the header declares {} vertices, but the {} bytes after the header hold at most {most} ascii vertices of {} properties",
            def.count,
            body.len(),
            def.properties.len()
        ),
    })
}
