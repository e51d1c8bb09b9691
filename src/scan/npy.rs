//! The `NumPy` `.npy` array format (`numpy.lib.format`, versions 1.0, 2.0 and 3.0), as far as scans
//! need it: the header, and plain arrays of floats, integers and fixed-width strings.
//!
//! A file is the magic `\x93NUMPY`, a major and minor version byte, the header length (`u16`
//! little endian in 1.0, `u32` in 2.0 and 3.0), then the header: a Python dict literal such as
//! `{'descr': '<f4', 'fortran_order': False, 'shape': (10, 3), }` (latin-1 in 1.0 and 2.0, UTF-8
//! in 3.0), padded with spaces and a newline. The data follow: `prod(shape)` items of `descr`, in
//! C (row-major) or Fortran (column-major) order.
//!
//! Why not the `npyz` crate: its header reader multiplies the shape without an overflow check (a
//! hostile `shape` panics in debug builds and wraps in release), it parses the header through
//! `py_literal` (pest and num-bigint, a dozen crates), and its `npz` feature pulls in zip 0.6 with
//! every compression method (bzip2 and zstd C libraries). The subset below is about 300 lines,
//! checks every size before it allocates, and returns errors instead of panicking.

use std::fmt::Write as _;

/// The item type of an array (`descr`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DType {
    /// IEEE float of 4 or 8 bytes.
    Float { bytes: usize, big_endian: bool },
    /// Integer of 1, 2, 4 or 8 bytes.
    Int { bytes: usize, signed: bool, big_endian: bool },
    /// `U`: fixed-width UCS-4 strings of `chars` code points, NUL-padded.
    Unicode { chars: usize, big_endian: bool },
    /// `S`: fixed-width byte strings of `bytes`, NUL-padded (read as UTF-8).
    Bytes { bytes: usize },
}

impl DType {
    /// Size of one item in bytes (`None` when it overflows).
    fn item_bytes(self) -> Option<usize> {
        match self {
            DType::Float { bytes, .. } | DType::Int { bytes, .. } | DType::Bytes { bytes } => Some(bytes),
            DType::Unicode { chars, .. } => chars.checked_mul(4),
        }
    }

    /// The `NumPy` name (`float32`, `uint16`, `<U10`), for messages.
    pub(crate) fn name(self) -> String {
        match self {
            DType::Float { bytes, .. } => format!("float{}", bytes * 8),
            DType::Int { bytes, signed, .. } => format!("{}int{}", if signed { "" } else { "u" }, bytes * 8),
            DType::Unicode { chars, .. } => format!("unicode string <U{chars}"),
            DType::Bytes { bytes } => format!("byte string |S{bytes}"),
        }
    }
}

/// One array of an archive: its header and its data bytes (exactly `len() * item size`).
#[derive(Debug)]
pub(crate) struct NpyArray<'a> {
    pub dtype: DType,
    /// The `descr` as written, for messages.
    pub descr: String,
    pub fortran_order: bool,
    pub shape: Vec<usize>,
    data: &'a [u8],
}

const MAGIC: &[u8] = b"\x93NUMPY";

/// Deepest nesting of tuples, lists and dicts accepted in a header (a real one nests two deep).
const MAX_DEPTH: usize = 8;

/// Parses a whole `.npy` file held in memory. Errors are details for the caller to place.
pub(crate) fn parse_npy(bytes: &[u8]) -> Result<NpyArray<'_>, String> {
    let Some(rest) = bytes.strip_prefix(MAGIC) else {
        let shown: String = String::from_utf8_lossy(&bytes[..bytes.len().min(8)]).escape_debug().collect();
        return Err(format!("not a .npy array: it starts with \"{shown}\", expected the magic \\x93NUMPY"));
    };
    let (Some(&major), Some(_minor)) = (rest.first(), rest.get(1)) else {
        return Err("the .npy header ends after the magic".into());
    };
    let rest = &rest[2..];
    let (len_bytes, utf8) = match major {
        1 => (2, false),
        2 => (4, false),
        3 => (4, true),
        v => return Err(format!(".npy format version {v}; expected 1, 2 or 3")),
    };
    let len_field = rest.get(..len_bytes).ok_or("the .npy header ends inside its length field")?;
    let header_len = len_field.iter().rev().fold(0_usize, |acc, &b| (acc << 8) | usize::from(b));
    let rest = &rest[len_bytes..];
    let Some(header) = rest.get(..header_len) else {
        return Err(format!("the .npy header declares {header_len} bytes, but only {} follow", rest.len()));
    };
    let text = if utf8 {
        std::str::from_utf8(header).map_err(|e| format!("the .npy header is not UTF-8: {e}"))?.to_owned()
    } else {
        header.iter().map(|&b| char::from(b)).collect()
    };
    let (dtype, descr, fortran_order, shape) = interpret_header(&text)?;
    let data = &rest[header_len..];
    let count = shape.iter().try_fold(1_usize, |acc, &d| acc.checked_mul(d)).ok_or("the shape's element count overflows")?;
    let needed = dtype.item_bytes().and_then(|b| b.checked_mul(count)).ok_or("the array's size in bytes overflows")?;
    if data.len() != needed {
        return Err(format!("holds {} bytes of data; its shape {} of {} needs {needed}", data.len(), shape_text(&shape), dtype.name()));
    }
    Ok(NpyArray { dtype, descr, fortran_order, shape, data })
}

/// `(3, 4)`, `(5,)` or `()` as Python writes it.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    let mut out = String::from("(");
    for (i, d) in shape.iter().enumerate() {
        let _ = write!(out, "{}{d}", if i == 0 { "" } else { ", " });
    }
    out.push_str(if shape.len() == 1 { ",)" } else { ")" });
    out
}

type Header = (DType, String, bool, Vec<usize>);

/// The three keys of the header dict, checked.
fn interpret_header(text: &str) -> Result<Header, String> {
    let value = Parser { chars: text.chars().collect(), at: 0 }.parse_all()?;
    let Py::Dict(entries) = value else { return Err(format!("the .npy header is not a dict: {}", text.trim())) };
    let get = |key: &str| entries.iter().find(|(k, _)| matches!(k, Py::Str(s) if s == key)).map(|(_, v)| v);
    let descr = match get("descr") {
        Some(Py::Str(s)) => s.clone(),
        Some(Py::List(_)) => return Err("a structured dtype (a list `descr`); expected a plain numeric or string array".into()),
        Some(_) => return Err("the header's `descr` is not a string".into()),
        None => return Err("the .npy header has no `descr`".into()),
    };
    let fortran_order = match get("fortran_order") {
        Some(Py::Bool(b)) => *b,
        _ => return Err("the .npy header has no boolean `fortran_order`".into()),
    };
    let shape = match get("shape") {
        Some(Py::Tuple(items)) => items
            .iter()
            .map(|d| match d {
                Py::Int(n) => usize::try_from(*n).map_err(|_| format!("shape dimension {n} is too large")),
                _ => Err("the header's `shape` holds something other than non-negative integers".to_owned()),
            })
            .collect::<Result<Vec<usize>, String>>()?,
        _ => return Err("the .npy header has no tuple `shape`".into()),
    };
    Ok((parse_descr(&descr)?, descr, fortran_order, shape))
}

/// A type string such as `<f4`, `|u1`, `>i8`, `<U12`, `|S5`.
fn parse_descr(descr: &str) -> Result<DType, String> {
    let unsupported = |why: &str| Err(format!("dtype '{descr}' ({why}) is not supported"));
    let (order, rest) = match descr.chars().next() {
        Some(c @ ('<' | '>' | '|' | '=')) => (c, &descr[1..]),
        _ => ('|', descr),
    };
    let big_endian = order == '>' || (order == '=' && cfg!(target_endian = "big"));
    let mut chars = rest.chars();
    let kind = chars.next().ok_or_else(|| format!("empty dtype '{descr}'"))?;
    if kind == 'O' {
        return unsupported("Python objects, stored as a pickle");
    }
    let size: usize = match chars.as_str() {
        "" if kind == 'b' || kind == '?' => 1,
        digits => digits.parse().map_err(|_| format!("dtype '{descr}' has no size"))?,
    };
    match (kind, size) {
        ('f', 4 | 8) => Ok(DType::Float { bytes: size, big_endian }),
        ('f', _) => unsupported("a float size other than 4 or 8 bytes"),
        ('i' | 'u', 1 | 2 | 4 | 8) => Ok(DType::Int { bytes: size, signed: kind == 'i', big_endian }),
        ('b' | '?', 1) => Ok(DType::Int { bytes: 1, signed: false, big_endian: false }),
        ('U', n) => Ok(DType::Unicode { chars: n, big_endian }),
        ('S' | 'a', n) => Ok(DType::Bytes { bytes: n }),
        _ => unsupported("expected a float, an integer or a fixed-width string"),
    }
}

impl NpyArray<'_> {
    fn item(&self, i: usize) -> &[u8] {
        let size = self.dtype.item_bytes().unwrap_or(0);
        &self.data[i * size..(i + 1) * size]
    }

    /// The storage index of element (row, col) of a 2-D array with `cols` columns.
    pub(crate) fn index_2d(&self, row: usize, col: usize) -> usize {
        let rows = self.shape.first().copied().unwrap_or(0);
        let cols = self.shape.get(1).copied().unwrap_or(1);
        if self.fortran_order { col * rows + row } else { row * cols + col }
    }

    /// Item `i` as a float (float arrays only).
    pub(crate) fn float(&self, i: usize) -> Option<f64> {
        let DType::Float { bytes, big_endian } = self.dtype else { return None };
        let b = self.item(i);
        Some(match (bytes, big_endian) {
            (4, false) => f64::from(f32::from_le_bytes(b.try_into().ok()?)),
            (4, true) => f64::from(f32::from_be_bytes(b.try_into().ok()?)),
            (_, false) => f64::from_le_bytes(b.try_into().ok()?),
            (_, true) => f64::from_be_bytes(b.try_into().ok()?),
        })
    }

    /// Item `i` as an integer (integer arrays only); `Err` with the value when an unsigned
    /// 64-bit value does not fit an `i64`.
    pub(crate) fn int(&self, i: usize) -> Option<Result<i64, u64>> {
        let DType::Int { signed, big_endian, .. } = self.dtype else { return None };
        let b = self.item(i);
        // Widen to 8 bytes, most significant first, sign-extending signed values.
        let negative = signed && (if big_endian { b.first() } else { b.last() }).is_some_and(|&m| m & 0x80 != 0);
        let mut be = [if negative { 0xff } else { 0 }; 8];
        let start = 8 - b.len();
        for (k, &byte) in b.iter().enumerate() {
            be[start + if big_endian { k } else { b.len() - 1 - k }] = byte;
        }
        if signed {
            return Some(Ok(i64::from_be_bytes(be)));
        }
        let value = u64::from_be_bytes(be);
        Some(i64::try_from(value).map_err(|_| value))
    }

    /// Item `i` as text (string arrays only): trailing NULs removed; `Err` with a reason when the
    /// bytes are not valid text.
    pub(crate) fn string(&self, i: usize) -> Option<Result<String, String>> {
        let b = self.item(i);
        match self.dtype {
            DType::Bytes { .. } => {
                let end = b.iter().rposition(|&c| c != 0).map_or(0, |p| p + 1);
                Some(String::from_utf8(b[..end].to_vec()).map_err(|e| format!("not UTF-8: {e}")))
            }
            DType::Unicode { big_endian, .. } => {
                let mut out = String::new();
                for unit in b.chunks_exact(4) {
                    let bytes: [u8; 4] = unit.try_into().ok()?;
                    let code = if big_endian { u32::from_be_bytes(bytes) } else { u32::from_le_bytes(bytes) };
                    match char::from_u32(code) {
                        Some(c) => out.push(c),
                        None => return Some(Err(format!("code point {code:#x} is not a character"))),
                    }
                }
                Some(Ok(out.trim_end_matches('\0').to_owned()))
            }
            _ => None,
        }
    }
}

/// The Python values a `.npy` header uses.
#[derive(Debug, PartialEq)]
enum Py {
    Str(String),
    Bool(bool),
    Int(u64),
    None,
    Tuple(Vec<Py>),
    List(Vec<Py>),
    Dict(Vec<(Py, Py)>),
}

/// A recursive-descent reader of the Python literal subset above.
struct Parser {
    chars: Vec<char>,
    at: usize,
}

impl Parser {
    fn parse_all(mut self) -> Result<Py, String> {
        let value = self.value(0)?;
        self.skip_space();
        if self.at < self.chars.len() {
            return Err(format!("unexpected text after the .npy header dict at character {}", self.at));
        }
        Ok(value)
    }

    fn skip_space(&mut self) {
        while self.chars.get(self.at).is_some_and(|c| c.is_whitespace()) {
            self.at += 1;
        }
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_space();
        self.chars.get(self.at).copied()
    }

    fn error(&self, what: &str) -> String {
        format!("malformed .npy header: {what} at character {}", self.at)
    }

    fn value(&mut self, depth: usize) -> Result<Py, String> {
        if depth > MAX_DEPTH {
            return Err(self.error("nesting too deep"));
        }
        match self.peek() {
            Some(q @ ('\'' | '"')) => self.string(q),
            Some('(') => Ok(Py::Tuple(self.sequence(')', depth)?)),
            Some('[') => Ok(Py::List(self.sequence(']', depth)?)),
            Some('{') => self.dict(depth),
            Some(c) if c.is_ascii_digit() => self.int(),
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.at;
                while self.chars.get(self.at).is_some_and(char::is_ascii_alphanumeric) {
                    self.at += 1;
                }
                match self.chars[start..self.at].iter().collect::<String>().as_str() {
                    "True" => Ok(Py::Bool(true)),
                    "False" => Ok(Py::Bool(false)),
                    "None" => Ok(Py::None),
                    word => Err(self.error(&format!("unknown word `{word}`"))),
                }
            }
            Some(_) => Err(self.error("unexpected character")),
            None => Err(self.error("unexpected end")),
        }
    }

    fn string(&mut self, quote: char) -> Result<Py, String> {
        self.at += 1;
        let mut out = String::new();
        loop {
            match self.chars.get(self.at).copied() {
                None => return Err(self.error("unterminated string")),
                Some(c) if c == quote => {
                    self.at += 1;
                    return Ok(Py::Str(out));
                }
                Some('\\') => {
                    let escaped = self.chars.get(self.at + 1).copied().ok_or_else(|| self.error("unterminated string"))?;
                    out.push(escaped);
                    self.at += 2;
                }
                Some(c) => {
                    out.push(c);
                    self.at += 1;
                }
            }
        }
    }

    fn int(&mut self) -> Result<Py, String> {
        let start = self.at;
        while self.chars.get(self.at).is_some_and(char::is_ascii_digit) {
            self.at += 1;
        }
        let digits: String = self.chars[start..self.at].iter().collect();
        // Python 2 wrote long integers with an `L` suffix.
        if matches!(self.chars.get(self.at), Some('L' | 'l')) {
            self.at += 1;
        }
        digits.parse().map(Py::Int).map_err(|_| self.error(&format!("integer {digits} out of range")))
    }

    /// Items up to `close`, comma separated, a trailing comma allowed.
    fn sequence(&mut self, close: char, depth: usize) -> Result<Vec<Py>, String> {
        self.at += 1;
        let mut items = Vec::new();
        loop {
            if self.peek() == Some(close) {
                self.at += 1;
                return Ok(items);
            }
            items.push(self.value(depth + 1)?);
            match self.peek() {
                Some(',') => self.at += 1,
                Some(c) if c == close => {}
                _ => return Err(self.error(&format!("expected `,` or `{close}`"))),
            }
        }
    }

    fn dict(&mut self, depth: usize) -> Result<Py, String> {
        self.at += 1;
        let mut entries = Vec::new();
        loop {
            if self.peek() == Some('}') {
                self.at += 1;
                return Ok(Py::Dict(entries));
            }
            let key = self.value(depth + 1)?;
            if self.peek() != Some(':') {
                return Err(self.error("expected `:`"));
            }
            self.at += 1;
            entries.push((key, self.value(depth + 1)?));
            match self.peek() {
                Some(',') => self.at += 1,
                Some('}') => {}
                _ => return Err(self.error("expected `,` or `}`")),
            }
        }
    }
}

/// A `.npy` file (version 1.0) of `shape` and `descr` around raw little/big-endian `data`: what
/// `numpy.save` writes, for tests.
#[cfg(test)]
pub(crate) fn npy_bytes(descr: &str, fortran_order: bool, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let order = if fortran_order { "True" } else { "False" };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {}, }}", shape_text(shape));
    // Padded with spaces so that magic + version + length + header is a multiple of 64, newline last.
    while !(MAGIC.len() + 4 + header.len() + 1).is_multiple_of(64) {
        header.push(' ');
    }
    header.push('\n');
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn headers_of_every_version_and_order() {
        let data: Vec<u8> = [1.0_f32, 2.0, 3.0, 4.0, 5.0, 6.0].iter().flat_map(|v| v.to_le_bytes()).collect();
        let file = npy_bytes("<f4", false, &[2, 3], &data);
        assert_eq!((file.len() - data.len()) % 64, 0, "header padded to 64 bytes");
        let a = parse_npy(&file).unwrap();
        assert_eq!((a.dtype, a.shape.clone()), (DType::Float { bytes: 4, big_endian: false }, vec![2, 3]));
        assert_eq!(a.float(a.index_2d(1, 0)), Some(4.0));
        // Fortran order: the same bytes are the columns.
        let f = npy_bytes("<f4", true, &[2, 3], &data);
        let a = parse_npy(&f).unwrap();
        assert_eq!((a.float(a.index_2d(1, 0)), a.float(a.index_2d(0, 1))), (Some(2.0), Some(3.0)));
        // Version 3 (UTF-8 header, u32 length), a Python 2 long and double quotes.
        let header = "{\"descr\": \">i2\", \"fortran_order\": False, \"shape\": (2L,), }\n";
        let mut v3 = MAGIC.to_vec();
        v3.extend_from_slice(&[3, 0]);
        v3.extend_from_slice(&(header.len() as u32).to_le_bytes());
        v3.extend_from_slice(header.as_bytes());
        v3.extend_from_slice(&[0xff, 0xfe, 0x01, 0x00]);
        let a = parse_npy(&v3).unwrap();
        assert_eq!((a.int(0), a.int(1)), (Some(Ok(-2)), Some(Ok(256))));
    }

    #[test]
    fn integers_of_every_width_and_sign() {
        let cases: [(&str, Vec<u8>, i64); 8] = [
            ("|i1", vec![0x80], -128),
            ("|u1", vec![0xff], 255),
            ("<i2", vec![0xfe, 0xff], -2),
            (">u2", vec![0x01, 0x02], 258),
            ("<i4", (-70_000_i32).to_le_bytes().to_vec(), -70_000),
            ("<u4", u32::MAX.to_le_bytes().to_vec(), i64::from(u32::MAX)),
            (">i8", (-5_i64).to_be_bytes().to_vec(), -5),
            ("|b1", vec![1], 1),
        ];
        for (descr, bytes, want) in cases {
            let file = npy_bytes(descr, false, &[1], &bytes);
            assert_eq!(parse_npy(&file).unwrap().int(0), Some(Ok(want)), "{descr}");
        }
        let file = npy_bytes("<u8", false, &[1], &u64::MAX.to_le_bytes());
        let a = parse_npy(&file).unwrap();
        assert_eq!(a.int(0), Some(Err(u64::MAX)));
    }

    #[test]
    fn strings_unicode_and_bytes() {
        let mut ucs4 = Vec::new();
        for word in ["door", "gäste"] {
            let mut chars: Vec<u32> = word.chars().map(u32::from).collect();
            chars.resize(5, 0);
            ucs4.extend(chars.iter().flat_map(|c| c.to_le_bytes()));
        }
        let file = npy_bytes("<U5", false, &[2], &ucs4);
        let a = parse_npy(&file).unwrap();
        assert_eq!((a.string(0), a.string(1)), (Some(Ok("door".into())), Some(Ok("gäste".into()))));
        let file = npy_bytes("|S4", false, &[2], b"lid\0knob");
        let a = parse_npy(&file).unwrap();
        assert_eq!((a.string(0), a.string(1)), (Some(Ok("lid".into())), Some(Ok("knob".into()))));
        assert!(a.float(0).is_none() && a.int(0).is_none());
    }

    #[test]
    fn bad_headers_are_errors_never_panics() {
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"PK\x03\x04".to_vec(), "not a .npy array"),
            (MAGIC.to_vec(), "ends after the magic"),
            ([MAGIC, &[9, 0, 0, 0]].concat(), "version 9"),
            ([MAGIC, &[1, 0, 200, 0], b"{}"].concat(), "declares 200 bytes"),
            (npy_bytes("<f2", false, &[1], &[0, 0]), "'<f2'"),
            (npy_bytes("|O", false, &[1], &[0; 8]), "pickle"),
            (npy_bytes("<c16", false, &[1], &[0; 16]), "'<c16'"),
            (npy_bytes("<f4", false, &[3], &[0; 8]), "holds 8 bytes of data; its shape (3,) of float32 needs 12"),
            (npy_bytes("<f8", false, &[usize::MAX, 2], &[]), "overflows"),
        ];
        for (bytes, needle) in cases {
            let e = parse_npy(&bytes).unwrap_err();
            assert!(e.contains(needle), "{needle:?} not in {e:?}");
        }
        for header in [
            "{'descr': [('x', '<f4')], 'fortran_order': False, 'shape': (1,)}",
            "{'descr': '<f4', 'shape': (1,)}",
            "{'descr': '<f4', 'fortran_order': 0, 'shape': (1,)}",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (-1,)}",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999999,)}",
            "{'descr': '<f4' 'fortran_order': False}",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (1,)} trailing",
            "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[",
            "{'descr': 'unterminated",
            "",
        ] {
            let mut bytes = [MAGIC, &[1, 0]].concat();
            bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
            bytes.extend_from_slice(header.as_bytes());
            assert!(parse_npy(&bytes).is_err(), "{header}");
        }
    }
}
