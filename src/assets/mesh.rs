//! Triangle meshes referenced by URDF and MJCF files: Wavefront OBJ (tobj, polygons
//! triangulated, all objects of a file merged), STL (`stl_io`, ASCII or binary) and `MuJoCo`'s legacy
//! binary `.msh`, and glTF (`.glb`, or `.gltf` with buffers in files beside it) via `gltf`: the
//! triangles of every mesh node of the default scene, node transforms applied, in the file's own
//! axes (no Y-up → Z-up turn: URDFs that reference GLBs are written in the GLB's frame).

use std::io::Cursor;
use std::path::Path;

use gltf::accessor::{DataType, Dimensions};

use super::AssetError;
use crate::math::Vec3;

/// A triangle mesh in its file's own frame and units.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The mesh formats this module reads, by file extension (case-insensitive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Stl,
    /// `MuJoCo`'s legacy binary format: four `i32` counts (vertices, normals, texture coordinates,
    /// faces), then `f32` positions, normals, texture coordinates and `i32` face indices.
    Msh,
    /// glTF 2.0, binary (`.glb`) or JSON (`.gltf`).
    Gltf,
}

impl MeshFormat {
    /// The format for a file name's extension, if supported.
    #[must_use]
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(Self::Obj),
            "stl" => Some(Self::Stl),
            "msh" => Some(Self::Msh),
            "glb" | "gltf" => Some(Self::Gltf),
            _ => None,
        }
    }
}

impl TriMesh {
    /// Scales vertices component-wise (URDF `scale`, MJCF mesh `scale`).
    #[must_use]
    pub fn scaled(mut self, scale: Vec3) -> Self {
        for v in &mut self.vertices {
            *v *= scale;
        }
        self
    }
}

/// Reads a mesh file, choosing the reader by extension. Errors name the file.
pub fn load_mesh(path: &Path) -> Result<TriMesh, AssetError> {
    let Some(format) = MeshFormat::from_path(path) else {
        return Err(mesh_error(path, "unsupported mesh format (OBJ, STL and MuJoCo .msh are read)"));
    };
    let bytes = crate::io::read_bytes(path)?;
    parse_mesh(&bytes, format, path)
}

/// Decodes a mesh held in memory as if it were the file `path`: `path` names it in errors, and a
/// `.gltf`'s external buffers are read from its folder. Vertices are checked finite and triangle
/// indices in range.
pub fn parse_mesh(bytes: &[u8], format: MeshFormat, path: &Path) -> Result<TriMesh, AssetError> {
    let mesh = match format {
        MeshFormat::Obj => parse_obj(bytes),
        MeshFormat::Stl => parse_stl(bytes),
        MeshFormat::Msh => parse_msh(bytes),
        // The gltf crate can panic on some malformed documents instead of returning an error;
        // contain that here so a bad mesh file is an error naming it, never a crash.
        MeshFormat::Gltf => std::panic::catch_unwind(|| parse_gltf(bytes, path.parent().unwrap_or(Path::new("."))))
            .unwrap_or_else(|_| Err("glTF: malformed document (the glTF reader gave up)".to_owned())),
    }
    .map_err(|message| mesh_error(path, message))?;
    validate(&mesh).map_err(|message| mesh_error(path, message))?;
    Ok(mesh)
}

fn mesh_error(path: &Path, message: impl Into<String>) -> AssetError {
    AssetError::Mesh { path: path.to_path_buf(), message: message.into() }
}

fn validate(mesh: &TriMesh) -> Result<(), String> {
    let n = mesh.vertices.len();
    if let Some(v) = mesh.vertices.iter().position(|v| !v.is_finite()) {
        return Err(format!("vertex {v} is not finite"));
    }
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(format!("triangle {t} indexes past the {n} vertices"));
    }
    Ok(())
}

/// OBJ text: every object and group merged, polygons fan-triangulated, materials not read.
fn parse_obj(bytes: &[u8]) -> Result<TriMesh, String> {
    check_obj_face_indices(bytes)?;
    let options = tobj::LoadOptions { single_index: false, triangulate: true, ignore_points: true, ignore_lines: true };
    let mut reader = Cursor::new(bytes);
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| Ok((Vec::new(), std::collections::HashMap::new())))
        .map_err(|e| format!("OBJ: {e}"))?;
    let mut mesh = TriMesh::default();
    for model in models {
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend(model.mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        mesh.triangles.extend(model.mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
    }
    Ok(mesh)
}

/// Checks every face index of an OBJ file against the positions, texture coordinates and normals
/// the file declares, before `tobj` reads it: `tobj` 4.0.5 multiplies an index by the element
/// width unchecked (an index near `usize::MAX` overflows). Positive indices may point anywhere in
/// the file; negative ones count back from the elements declared so far, as the format says.
fn check_obj_face_indices(bytes: &[u8]) -> Result<(), String> {
    const KINDS: [&str; 3] = ["positions", "texture coordinates", "normals"];
    // Which element a line declares: 0 position, 1 texture coordinate, 2 normal.
    let element = |keyword: Option<&str>| match keyword {
        Some("v") => Some(0),
        Some("vt") => Some(1),
        Some("vn") => Some(2),
        _ => None,
    };
    let text = String::from_utf8_lossy(bytes);
    let mut total = [0_i64; 3];
    for k in text.lines().filter_map(|line| element(line.split_whitespace().next())) {
        total[k] += 1;
    }
    let mut so_far = [0_i64; 3];
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let keyword = words.next();
        if let Some(k) = element(keyword) {
            so_far[k] += 1;
        }
        if keyword != Some("f") {
            continue;
        }
        for corner in words {
            for (k, index) in corner.split('/').enumerate().take(3) {
                let Ok(i) = index.parse::<i64>() else { continue }; // empty or malformed: tobj reports it
                let fits = if i > 0 { i <= total[k] } else { i < 0 && i.checked_neg().is_some_and(|n| n <= so_far[k]) };
                if !fits {
                    let declared = if i > 0 { total[k] } else { so_far[k] };
                    return Err(format!("OBJ line {}: face index {i} outside the {declared} {} declared", number + 1, KINDS[k]));
                }
            }
        }
    }
    Ok(())
}

/// STL, ASCII or binary (`stl_io` merges identical vertices).
fn parse_stl(bytes: &[u8]) -> Result<TriMesh, String> {
    let mut reader = Cursor::new(bytes);
    let stl = stl_io::read_stl(&mut reader).map_err(|e| format!("STL: {e}"))?;
    Ok(TriMesh {
        vertices: stl.vertices.iter().map(|v| Vec3::new(v[0], v[1], v[2])).collect(),
        triangles: stl.faces.iter().map(|f| [f.vertices[0] as u32, f.vertices[1] as u32, f.vertices[2] as u32]).collect(),
    })
}

/// `MuJoCo` legacy `.msh` (little-endian).
fn parse_msh(bytes: &[u8]) -> Result<TriMesh, String> {
    let word = |i: usize| -> Option<[u8; 4]> { bytes.get(4 * i..4 * i + 4).and_then(|s| s.try_into().ok()) };
    let mut counts = [0usize; 4];
    for (i, c) in counts.iter_mut().enumerate() {
        let w = word(i).ok_or("MSH: file shorter than its 16-byte header")?;
        *c = usize::try_from(i32::from_le_bytes(w)).map_err(|_| format!("MSH: negative count {} in the header", i32::from_le_bytes(w)))?;
    }
    let [nv, nn, nt, nf] = counts;
    let expected_words = 4 + 3 * nv + 3 * nn + 2 * nt + 3 * nf;
    if bytes.len() != 4 * expected_words {
        return Err(format!(
            "MSH: {nv} vertices, {nn} normals, {nt} texture coordinates and {nf} faces need {} bytes, the file has {}",
            4 * expected_words,
            bytes.len()
        ));
    }
    let float = |i: usize| word(i).map_or(f32::NAN, f32::from_le_bytes);
    let vertices = (0..nv).map(|v| Vec3::new(float(4 + 3 * v), float(5 + 3 * v), float(6 + 3 * v))).collect();
    let face_start = 4 + 3 * nv + 3 * nn + 2 * nt;
    let mut triangles = Vec::with_capacity(nf);
    for f in 0..nf {
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let raw = word(face_start + 3 * f + k).map_or(-1, i32::from_le_bytes);
            *slot = u32::try_from(raw).map_err(|_| format!("MSH: face {f} has negative index {raw}"))?;
        }
        triangles.push(tri);
    }
    Ok(TriMesh { vertices, triangles })
}

/// glTF / GLB: triangle primitives of the default scene's node tree (all scenes' roots when no
/// default is set), with node transforms. Buffers: the GLB `BIN` chunk or files next to the
/// glTF; embedded `data:` URIs are not read.
fn parse_gltf(bytes: &[u8], dir: &Path) -> Result<TriMesh, String> {
    check_glb_header(bytes)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| format!("glTF: {e}"))?;
    let root = document.into_json();
    check_attribute_indices(&root)?;
    let document = gltf::Document::from_json(root).map_err(|e| format!("glTF: {e}"))?;
    let mut buffers: Vec<Option<Vec<u8>>> = Vec::new();
    for buffer in document.buffers() {
        buffers.push(match buffer.source() {
            gltf::buffer::Source::Bin => blob.clone(),
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                Some(std::fs::read(dir.join(uri)).map_err(|e| format!("glTF buffer {uri}: {e}"))?)
            }
            gltf::buffer::Source::Uri(_) => None,
        });
    }
    let roots: Vec<gltf::Node> = match document.default_scene() {
        Some(scene) => scene.nodes().collect(),
        None => document.scenes().flat_map(|s| s.nodes().collect::<Vec<_>>()).collect(),
    };
    let mut mesh = TriMesh::default();
    let mut stack: Vec<(gltf::Node, glam::Mat4)> = roots.into_iter().rev().map(|n| (n, glam::Mat4::IDENTITY)).collect();
    let mut visited = 0usize;
    while let Some((node, parent_from_root)) = stack.pop() {
        visited += 1;
        if visited > 100_000 {
            return Err("glTF: node hierarchy too deep or cyclic".into());
        }
        let root_from_node = parent_from_root * glam::Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(m) = node.mesh() {
            for primitive in m.primitives().filter(|p| p.mode() == gltf::mesh::Mode::Triangles) {
                let Some(position) = primitive.get(&gltf::Semantic::Positions) else { continue };
                // Buffers in `data:` URIs are not read: the primitive is skipped, as before.
                if position.view().is_some_and(|v| buffers.get(v.buffer().index()).is_none_or(Option::is_none)) {
                    continue;
                }
                check_accessor(&position, "POSITION", &[(Dimensions::Vec3, DataType::F32)], &buffers)?;
                let index_types =
                    [(Dimensions::Scalar, DataType::U8), (Dimensions::Scalar, DataType::U16), (Dimensions::Scalar, DataType::U32)];
                if let Some(indices) = primitive.indices() {
                    check_accessor(&indices, "indices", &index_types, &buffers)?;
                }
                let added = position.count().saturating_add(primitive.indices().map_or(position.count(), |ix| ix.count()) / 3);
                if mesh.vertices.len() + mesh.triangles.len() + added > MAX_GLTF_ELEMENTS {
                    return Err(format!(
                        "glTF: more than {MAX_GLTF_ELEMENTS} vertices and triangles with every mesh instance placed ({visited} nodes so far)"
                    ));
                }
                let reader = primitive.reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
                let Some(positions) = reader.read_positions() else { continue };
                let base = mesh.vertices.len() as u32;
                mesh.vertices.extend(positions.map(|p| root_from_node.transform_point3(Vec3::from(p))));
                let count = mesh.vertices.len() as u32 - base;
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(ix) => ix.into_u32().collect(),
                    None => (0..count).collect(),
                };
                if indices.iter().any(|&i| i >= count) {
                    return Err(format!("glTF: mesh {} indexes past its {count} vertices", m.index()));
                }
                mesh.triangles.extend(indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
            }
        }
        stack.extend(node.children().map(|c| (c, root_from_node)));
    }
    Ok(mesh)
}

/// gltf-json 1.4 validates a primitive by looking up its `POSITION` accessor before checking that
/// the index exists, and panics on one past the end: attribute indices are checked first.
fn check_attribute_indices(root: &gltf::json::Root) -> Result<(), String> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive.attributes.values().find(|i| i.value() >= root.accessors.len()) {
                return Err(format!(
                    "glTF: mesh {m} primitive {p} names accessor {}, but the file has {} accessors",
                    index.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    Ok(())
}

/// Most vertices plus triangles a glTF file may expand to. Nodes can place one mesh many times
/// (and a node tree can reference a subtree repeatedly), so the output is not bounded by the file
/// size; 10 million (about 240 MB of geometry) is far above any furniture asset.
const MAX_GLTF_ELEMENTS: usize = 10_000_000;

/// Checks what gltf's accessor reader assumes without checking (it asserts in debug builds and
/// can index out of range in release): the element type, at least one element, a stride of at
/// least one element, every element inside the buffer view and the view inside its buffer's data.
/// Sparse accessors are refused (exporters use them for morph targets, not base geometry).
fn check_accessor(
    accessor: &gltf::Accessor,
    what: &str,
    types: &[(Dimensions, DataType)],
    buffers: &[Option<Vec<u8>>],
) -> Result<(), String> {
    let index = accessor.index();
    let found = (accessor.dimensions(), accessor.data_type());
    if !types.contains(&found) {
        let expected: Vec<String> = types.iter().map(|(d, t)| format!("{d:?} of {t:?}")).collect();
        return Err(format!("glTF: {what} accessor {index} holds {:?} of {:?}; expected {}", found.0, found.1, expected.join(" or ")));
    }
    if accessor.sparse().is_some() {
        return Err(format!("glTF: {what} accessor {index} is sparse; sparse geometry is not read"));
    }
    let Some(view) = accessor.view() else {
        return Err(format!("glTF: {what} accessor {index} has no buffer view"));
    };
    if accessor.count() == 0 {
        return Err(format!("glTF: {what} accessor {index} has no elements; expected at least one"));
    }
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!("glTF: {what} accessor {index}: buffer view stride {stride} is less than its {size}-byte elements"));
    }
    let end = (accessor.count() - 1).checked_mul(stride).and_then(|n| n.checked_add(size)).and_then(|n| n.checked_add(accessor.offset()));
    let view_end = view.offset().checked_add(view.length());
    let data = buffers.get(view.buffer().index()).and_then(Option::as_ref).map_or(0, Vec::len);
    if end.is_none_or(|end| end > view.length()) || view_end.is_none_or(|view_end| view_end > data) {
        return Err(format!(
            "glTF: {what} accessor {index}: {} elements of {size} bytes (stride {stride}) from byte {} do not fit in buffer view {} \
             ({} bytes from byte {} of buffer {}, which holds {data} bytes)",
            accessor.count(),
            accessor.offset(),
            view.index(),
            view.length(),
            view.offset(),
            view.buffer().index(),
        ));
    }
    Ok(())
}

/// Size of the GLB header: magic `glTF`, version, total length (`u32` little-endian each).
const GLB_HEADER_BYTES: usize = 12;

/// Checks a GLB header before the glTF reader sees it: gltf 1.4 subtracts the header size from
/// the declared length unchecked, so a length under 12 overflows there (a panic with overflow
/// checks, a wrapped length without). JSON glTF (no `glTF` magic) passes through.
fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |i: usize| bytes.get(4 * i..4 * i + 4).and_then(|s| s.try_into().ok()).map(u32::from_le_bytes);
    let (Some(version), Some(length)) = (word(1), word(2)) else {
        return Err(format!("GLB: the file ends inside its {GLB_HEADER_BYTES}-byte header ({} bytes)", bytes.len()));
    };
    if version != 2 {
        return Err(format!("GLB: version {version} in the header; expected 2"));
    }
    let length = length as usize;
    if !(GLB_HEADER_BYTES..=bytes.len()).contains(&length) {
        return Err(format!(
            "GLB: the header declares a length of {length} bytes; expected at least its own {GLB_HEADER_BYTES} and at most the file's {}",
            bytes.len()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_quads_are_triangulated_and_objects_merged() {
        let text = "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5 6 7\n";
        let mesh = parse_obj(text.as_bytes()).unwrap();
        assert_eq!(mesh.vertices.len(), 7);
        assert_eq!(mesh.triangles.len(), 3);
        assert!(mesh.triangles.iter().flatten().all(|&i| i < 7));
        assert_eq!(mesh.vertices[mesh.triangles[2][0] as usize], Vec3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn msh_round_trip_and_truncation() {
        let mut bytes = Vec::new();
        for c in [3i32, 0, 0, 1] {
            bytes.extend(c.to_le_bytes());
        }
        for f in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0] {
            bytes.extend(f.to_le_bytes());
        }
        for i in [0i32, 1, 2] {
            bytes.extend(i.to_le_bytes());
        }
        let mesh = parse_msh(&bytes).unwrap();
        assert_eq!(mesh.vertices[2], Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert!(parse_msh(&bytes[..bytes.len() - 4]).unwrap_err().contains("need 64 bytes"));
    }

    #[test]
    fn stl_ascii_is_read() {
        let text = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let mesh = parse_stl(text.as_bytes()).unwrap();
        assert_eq!(mesh.vertices.len(), 3);
        assert_eq!(mesh.triangles.len(), 1);
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("broken.msh");
        std::fs::write(&path, [1u8, 2, 3]).unwrap();
        let err = load_mesh(&path).unwrap_err().to_string();
        assert!(err.contains("broken.msh"), "{err}");
        let missing = load_mesh(&dir.path().join("nope.stl")).unwrap_err().to_string();
        assert!(missing.contains("nope.stl"), "{missing}");
    }

    /// Fuzzing (issue 14): a GLB whose header declares a length under the header's own 12 bytes
    /// overflowed a subtraction inside the glTF reader.
    #[test]
    fn glb_header_length_shorter_than_the_header_is_refused_before_the_gltf_reader() {
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(b"\x10\0\0\0JSON{}");
        let err = parse_gltf(&glb, Path::new(".")).unwrap_err();
        assert!(err.contains("declares a length of 2 bytes"), "{err}");
        glb[4..8].copy_from_slice(&0x4654_6c67u32.to_le_bytes());
        let err = parse_gltf(&glb, Path::new(".")).unwrap_err();
        assert!(err.contains("version 1179937895"), "{err}");
        assert!(parse_gltf(b"glTF\x02\0", Path::new(".")).unwrap_err().contains("ends inside"));
    }

    /// A GLB with one buffer holding three `f32` vertices, its POSITION the accessor `position`;
    /// `accessor` and `view` are spliced into the JSON of the accessor and the buffer view.
    fn one_triangle_glb(position: usize, accessor: &str, view: &str) -> Vec<u8> {
        let mut json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":{position}}}}}]}}],"accessors":[{{"bufferView":0,"componentType":5126,"type":"VEC3","min":[0,0,0],"max":[1,1,0]{accessor}}}],"bufferViews":[{{"buffer":0,"byteLength":36{view}}}],"buffers":[{{"byteLength":36}}]}}"#
        )
        .into_bytes();
        json.resize(json.len().next_multiple_of(4), b' ');
        let bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|f| f.to_le_bytes()).collect();
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(&json);
        glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"BIN\0");
        glb.extend_from_slice(&bin);
        glb
    }

    /// Fuzzing (issue 14): accessors the glTF reader trusts (no elements, a stride shorter than an
    /// element, elements past the buffer view) made it panic; they are refused before it reads.
    #[test]
    fn glb_accessors_are_checked_before_the_gltf_reader_reads_them() {
        let mesh = parse_gltf(&one_triangle_glb(0, r#","count":3"#, ""), Path::new(".")).unwrap();
        assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (3, 1));
        for (position, accessor, view, expected) in [
            (0, r#","count":0"#, "", "has no elements"),
            (0, r#","count":3"#, r#","byteStride":4"#, "stride 4 is less than its 12-byte elements"),
            (0, r#","count":4"#, "", "4 elements of 12 bytes (stride 12) from byte 0 do not fit"),
            (0, r#","count":3,"byteOffset":4"#, "", "do not fit"),
            // A POSITION index past the accessors panicked inside gltf-json's own validation.
            (1, r#","count":3"#, "", "names accessor 1, but the file has 1 accessors"),
        ] {
            let err = parse_gltf(&one_triangle_glb(position, accessor, view), Path::new(".")).unwrap_err();
            assert!(err.contains(expected), "{accessor} {view}: {err}");
        }
    }

    #[test]
    fn corrupt_glb_files_are_errors_not_crashes() {
        let dir = tempfile::tempdir().unwrap();
        // A GLB header, then a JSON chunk whose document points at accessors that do not exist,
        // then cut short; and plain garbage after a valid magic.
        let json = br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}  "#;
        let mut glb = Vec::new();
        glb.extend_from_slice(b"glTF");
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&((12 + 8 + json.len()) as u32).to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(json);
        for (name, bytes) in
            [("dangling.glb", glb.clone()), ("cut.glb", glb[..30].to_vec()), ("junk.glb", b"glTF\x02\0\0\0garbage".to_vec())]
        {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let err = load_mesh(&path).expect_err("corrupt glb").to_string();
            assert!(err.contains(name), "{err}");
        }
    }
}
