//! Triangle meshes referenced by URDF and MJCF files: Wavefront OBJ (tobj, polygons
//! triangulated, all objects of a file merged), STL (`stl_io`, ASCII or binary) and `MuJoCo`'s legacy
//! binary `.msh`, and glTF (`.glb`, or `.gltf` with buffers in files beside it) via `gltf`: the
//! triangles of every mesh node of the default scene, node transforms applied, in the file's own
//! axes (no Y-up → Z-up turn: URDFs that reference GLBs are written in the GLB's frame).

use std::io::Cursor;
use std::path::Path;

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
    let mesh = match format {
        MeshFormat::Obj => parse_obj(&bytes),
        MeshFormat::Stl => parse_stl(&bytes),
        MeshFormat::Msh => parse_msh(&bytes),
        // The gltf crate can panic on some malformed documents instead of returning an error;
        // contain that here so a bad mesh file is an error naming it, never a crash.
        MeshFormat::Gltf => std::panic::catch_unwind(|| parse_gltf(&bytes, path.parent().unwrap_or(Path::new("."))))
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
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| format!("glTF: {e}"))?;
    let mut buffers: Vec<Option<Vec<u8>>> = Vec::new();
    for buffer in gltf.document.buffers() {
        buffers.push(match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone(),
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                Some(std::fs::read(dir.join(uri)).map_err(|e| format!("glTF buffer {uri}: {e}"))?)
            }
            gltf::buffer::Source::Uri(_) => None,
        });
    }
    let roots: Vec<gltf::Node> = match gltf.document.default_scene() {
        Some(scene) => scene.nodes().collect(),
        None => gltf.document.scenes().flat_map(|s| s.nodes().collect::<Vec<_>>()).collect(),
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
