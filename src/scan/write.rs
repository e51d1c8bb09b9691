//! Writing a scan: a `binary_little_endian` PLY (float x y z, int object, int part, and float
//! nx ny nz when every part has normals) plus the labels JSON beside it.

use std::path::Path;

use super::Scan;
use super::error::ScanError;
use super::labels::labels_json;
use super::read::UNASSIGNED;
use crate::io::atomic_write;
use crate::math::Vec3;

/// Whether every part carries one normal per point (then normals are written).
fn writes_normals(scan: &Scan) -> bool {
    !scan.parts.is_empty() && scan.parts.iter().all(|p| p.normals.as_ref().is_some_and(|n| n.len() == p.points.len()))
}

/// An id as the PLY `int` it is written as: ids beyond the 32-bit range saturate
/// (`write_scan` rejects them before this runs).
fn id_i32(id: i64) -> i32 {
    i32::try_from(id).unwrap_or(if id < 0 { i32::MIN } else { i32::MAX })
}

fn push_vertex(out: &mut Vec<u8>, point: Vec3, object: i32, part: i32, normal: Option<Vec3>) {
    for c in point.to_array() {
        out.extend_from_slice(&c.to_le_bytes());
    }
    out.extend_from_slice(&object.to_le_bytes());
    out.extend_from_slice(&part.to_le_bytes());
    if let Some(n) = normal {
        for c in n.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}

/// The scan as a `binary_little_endian` PLY: parts in order, then the background points as
/// object -1 / part -1 (with zero normals when normals are written). Ids outside the 32-bit
/// range saturate; `write_scan` rejects such scans.
#[must_use]
pub fn scan_to_ply_bytes(scan: &Scan) -> Vec<u8> {
    let normals = writes_normals(scan);
    let count = scan.point_count();
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment partscene scan (format v1)\nelement vertex {count}\n\
         property float x\nproperty float y\nproperty float z\nproperty int object\nproperty int part\n"
    );
    if normals {
        header.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    header.push_str("end_header\n");
    let stride = if normals { 32 } else { 20 };
    let mut out = Vec::with_capacity(header.len() + count * stride);
    out.extend_from_slice(header.as_bytes());
    for part in &scan.parts {
        let (object, id) = (id_i32(part.object), id_i32(part.id));
        let part_normals = part.normals.as_deref().filter(|_| normals);
        for (i, &point) in part.points.iter().enumerate() {
            push_vertex(&mut out, point, object, id, part_normals.map(|n| n[i]));
        }
    }
    let background_normal = normals.then_some(Vec3::ZERO);
    let unassigned = id_i32(UNASSIGNED);
    for &point in &scan.background {
        push_vertex(&mut out, point, unassigned, unassigned, background_normal);
    }
    out
}

/// Checks what the PLY cannot hold or the reader would reject: ids beyond 32 bits, non-finite
/// points.
fn validate(scan: &Scan, file: &str) -> Result<(), ScanError> {
    for part in &scan.parts {
        for (what, id) in [("part", part.id), ("object", part.object)] {
            if i32::try_from(id).is_err() {
                return Err(ScanError::IdOutOfRange { file: file.to_owned(), what, id });
            }
        }
        if let Some(index) = part.points.iter().position(|p| !p.is_finite()) {
            return Err(ScanError::NonFinitePoint { file: file.to_owned(), part: part.id, index });
        }
    }
    if let Some(index) = scan.background.iter().position(|p| !p.is_finite()) {
        return Err(ScanError::NonFinitePoint { file: file.to_owned(), part: UNASSIGNED, index });
    }
    Ok(())
}

/// Writes `NAME.ply` (binary little endian) and the labels `NAME.json` beside it, each atomically.
pub fn write_scan(scan: &Scan, ply_path: &Path) -> Result<(), ScanError> {
    validate(scan, &ply_path.display().to_string())?;
    atomic_write(ply_path, &scan_to_ply_bytes(scan))?;
    atomic_write(&ply_path.with_extension("json"), labels_json(scan).as_bytes())?;
    Ok(())
}
