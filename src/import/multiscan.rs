//! `partscene import multiscan DIR --out OUT`: a `MultiScan` scan (Mao et al., `NeurIPS` 2022
//! datasets track; github.com/3dlg-hcvc/multiscan, also published as smartscenes/multiscan) as a
//! part-segmented scan plus ground truth.
//!
//! **Input** (`DIR` = one scan folder, `scene_xxxxx_xx/`), as documented in `MultiScan`'s docs
//! (`docs/read-the-docs/dataset/index.rst`, `dataset/files/annotation.rst`) and read by its own
//! scripts (`dataset/core.py`, `visualization/annotation_visualize.py`):
//! - `scene_xxxxx_xx.ply`: the annotated mesh, binary little endian, `vertex` with double
//!   `x y z` (plus normals and colours, ignored), `face` with `list uchar int vertex_indices` and
//!   per-face `ushort objectId`, `ushort partId` ([`super::read_face_mesh`]; any PLY encoding and
//!   integer type is accepted). Metres, z up, the floor on the xy plane (`files/output.rst`).
//! - `scene_xxxxx_xx.annotations.json`: objects and parts with labels, parents and articulations
//!   (`multiscan_annotations.rs`). A face belongs to the part whose `objectId` *and* `partId` it
//!   carries, as in `MultiScan`'s own scripts (`part_triangles`).
//!
//! **Output** (`OUT/`): `scan.ply` + `scan.json` (the scan format, `write_scan`) and `gt.json`
//! ([`GroundTruth`], compact JSON) with one truth object per annotated object: its parts as
//! world-frame triangle meshes (the faces of the part), a joint per part with a `parentId`, and the
//! parent-child pairs as contact edges; then `partscene reconstruct OUT/scan.ply --out R` and
//! `partscene eval --scene R/scene.json --truth OUT/gt.json` score a real scan.
//!
//! **Conversions**:
//! - points: `--points N` (default [`DEFAULT_POINTS`]) drawn on the faces by area with seed
//!   `--seed` ([`super::sample_triangles`]): deterministic; no normals are written.
//! - ids: `MultiScan`'s `partId` and `objectId` are used as they are (part ids are unique per scan).
//! - labels: `door.1` → `door`, object `wall_cabinet.1` → category `wall_cabinet`.
//! - background: faces of objects with `mobilityType` `arch` (walls, floor, ceiling) and faces
//!   whose ids match no annotated part (counted in a warning); objects labelled `remove…` are
//!   dropped.
//! - joints: `rotation` → revolute, `translation` → prismatic, a part with a `parentId` and no
//!   articulation → fixed (origin at its faces' centroid); only the first articulation is used,
//!   as `MultiScan`'s scripts do. The truth is the scene as scanned (q = 0 at the annotated
//!   `state`), so limits are `[rangeMin − state, rangeMax − state]`. Axes are signed so that
//!   positive motion opens (this repository's convention): when the range reaches further below
//!   the joint's zero than above it (`|rangeMin| > |rangeMax|`), axis and limits are negated.
//!
//! **Not documented by `MultiScan`, chosen here** (each also said where it is done): the value of
//! `objectId`/`partId` on unannotated faces (any pair that names no annotated part is treated as
//! background); whether `rangeMin`/`rangeMax` are relative to the closed pose or to `state` (read
//! as the joint's coordinates, the frame in which `state` lies inside the range); that
//! "positive opens"; the floor height (the lowest vertex of the `floor` arch objects, else of the
//! whole mesh); which object supports which (none: `supported_by` is left empty).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::face_ply::{FaceMesh, read_face_mesh};
use super::multiscan_annotations::{AnnotatedObject, AnnotatedPart, Annotations, parse_annotations};
use super::{ImportError, sample_triangles};
use crate::io::atomic_write;
use crate::kinematics::{Joint, JointKind};
use crate::math::Vec3;
use crate::report::Warning;
use crate::scan::{ObjectId, PartId, Scan, ScanObject, ScanPart, write_scan};
use crate::truth::{GroundTruth, TRUTH_FORMAT, TruthMesh, TruthObject, TruthPart};

/// Points drawn on the mesh when `--points` is not given.
pub const DEFAULT_POINTS: usize = 200_000;

/// Most points `--points` may ask for.
pub const MAX_POINTS: usize = 50_000_000;

/// The file name ending of the annotations (`scene_xxxxx_xx.annotations.json`).
pub const ANNOTATIONS_SUFFIX: &str = ".annotations.json";

/// How to sample the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MultiScanOptions {
    pub points: usize,
    pub seed: u64,
}

impl Default for MultiScanOptions {
    fn default() -> Self {
        Self { points: DEFAULT_POINTS, seed: 0 }
    }
}

/// A converted scan.
#[derive(Clone, Debug)]
pub struct MultiScanImport {
    /// `scene_xxxxx_xx`.
    pub scan_id: String,
    pub scan: Scan,
    pub truth: GroundTruth,
    pub warnings: Vec<Warning>,
}

/// Where a face's points go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    Drop,
    Background,
    Part { object: ObjectId, part: PartId },
}

/// The scan id and the two input files of a `MultiScan` scan folder: the one
/// `*.annotations.json` in it and the PLY of the same scan id.
pub fn scan_files(dir: &Path) -> Result<(String, PathBuf, PathBuf), ImportError> {
    let entries = std::fs::read_dir(dir).map_err(|e| crate::io::IoError::new(dir, "list the folder", e))?;
    let mut ids: Vec<String> = entries
        .filter_map(Result::ok)
        .filter_map(|e| e.file_name().to_str().and_then(|n| n.strip_suffix(ANNOTATIONS_SUFFIX)).map(str::to_owned))
        .collect();
    ids.sort();
    let folder = |detail: String| ImportError::Folder { dir: dir.display().to_string(), detail };
    let scan_id = match ids.as_slice() {
        [one] => one.clone(),
        [] => return Err(folder(format!("no `*{ANNOTATIONS_SUFFIX}`; expected one MultiScan scan folder (scene_xxxxx_xx/)"))),
        many => return Err(folder(format!("several annotation files ({}); expected one scan per folder", many.join(", ")))),
    };
    let ply = dir.join(format!("{scan_id}.ply"));
    if !ply.is_file() {
        return Err(folder(format!(
            "no {scan_id}.ply beside {scan_id}{ANNOTATIONS_SUFFIX}; expected the annotated mesh with per-face objectId/partId"
        )));
    }
    let annotations = dir.join(format!("{scan_id}{ANNOTATIONS_SUFFIX}"));
    Ok((scan_id, ply, annotations))
}

/// Reads and converts the `MultiScan` scan in `dir`.
pub fn import_multiscan(dir: &Path, options: MultiScanOptions) -> Result<MultiScanImport, ImportError> {
    let (scan_id, ply_path, annotations_path) = scan_files(dir)?;
    let ply = crate::io::read_bytes(&ply_path)?;
    let text = std::fs::read_to_string(&annotations_path).map_err(|e| crate::io::IoError::new(&annotations_path, "read", e))?;
    import_multiscan_bytes(&ply, &ply_path.display().to_string(), &text, &annotations_path.display().to_string(), &scan_id, options)
}

/// Converts a `MultiScan` mesh (`ply`) and its annotations held in memory; the names are used in
/// errors, warnings and `Scan::source`.
pub fn import_multiscan_bytes(
    ply: &[u8],
    ply_name: &str,
    annotations: &str,
    annotations_name: &str,
    scan_id: &str,
    options: MultiScanOptions,
) -> Result<MultiScanImport, ImportError> {
    let mut warnings = Vec::new();
    let mesh = read_face_mesh(ply, ply_name, &mut warnings)?;
    let ann = parse_annotations(annotations, annotations_name)?;
    let targets = classify_faces(&mesh, &ann, ply_name, &mut warnings);
    let mut scan = sample_scan(&mesh, &targets, &ann, options, &mut warnings);
    scan.source = format!("{ply_name} (MultiScan {scan_id}, {} points, seed {})", options.points, options.seed);
    let truth = ground_truth(&mesh, &targets, &ann, &mut warnings);
    Ok(MultiScanImport { scan_id: scan_id.to_owned(), scan, truth, warnings })
}

/// Writes `OUT/scan.ply`, `OUT/scan.json` and `OUT/gt.json`, each atomically (temporary file,
/// then rename); creates `OUT`. Returns the three paths.
pub fn write_import(import: &MultiScanImport, out: &Path) -> Result<[PathBuf; 3], ImportError> {
    std::fs::create_dir_all(out).map_err(|e| crate::io::IoError::new(out, "create the folder", e))?;
    let scan_path = out.join("scan.ply");
    write_scan(&import.scan, &scan_path)?;
    let gt_path = out.join("gt.json");
    let json = serde_json::to_vec(&import.truth).map_err(|source| ImportError::Json { file: gt_path.display().to_string(), source })?;
    atomic_write(&gt_path, &json)?;
    Ok([scan_path.clone(), scan_path.with_extension("json"), gt_path])
}

/// Sorts every face into a part, the background or nothing; warns about faces whose ids name no
/// annotated part.
fn classify_faces(mesh: &FaceMesh, ann: &Annotations, file: &str, warnings: &mut Vec<Warning>) -> Vec<Target> {
    let objects: BTreeMap<ObjectId, &AnnotatedObject> = ann.objects.iter().map(|o| (o.id, o)).collect();
    let mut unmatched: BTreeMap<(i64, i64), usize> = BTreeMap::new();
    let targets = mesh
        .faces
        .iter()
        .map(|f| match objects.get(&f.object) {
            Some(o) if o.removed => Target::Drop,
            Some(o) if o.arch => Target::Background,
            Some(o) if o.part_ids.contains(&f.part) => Target::Part { object: o.id, part: f.part },
            _ => {
                *unmatched.entry((f.object, f.part)).or_default() += 1;
                Target::Background
            }
        })
        .collect();
    if !unmatched.is_empty() {
        let total: usize = unmatched.values().sum();
        let mut pairs = String::new();
        for ((o, p), n) in unmatched.iter().take(8) {
            let _ = write!(pairs, "{}objectId {o} partId {p} ({n})", if pairs.is_empty() { "" } else { ", " });
        }
        if unmatched.len() > 8 {
            pairs.push_str(", ...");
        }
        warnings.push(Warning::new(
            "import",
            file,
            format!("{total} triangles carry ids that name no annotated part (unannotated surface): treated as background: {pairs}"),
        ));
    }
    targets
}

fn triangle(mesh: &FaceMesh, face: usize) -> [Vec3; 3] {
    mesh.faces[face].vertices.map(|v| mesh.vertices[v as usize])
}

/// Points drawn on every face that is not dropped, grouped into parts and background.
fn sample_scan(mesh: &FaceMesh, targets: &[Target], ann: &Annotations, options: MultiScanOptions, warnings: &mut Vec<Warning>) -> Scan {
    let kept: Vec<usize> = (0..targets.len()).filter(|&f| targets[f] != Target::Drop).collect();
    let triangles: Vec<[Vec3; 3]> = kept.iter().map(|&f| triangle(mesh, f)).collect();
    let mut by_part: BTreeMap<PartId, (ObjectId, Vec<Vec3>)> = BTreeMap::new();
    let mut scan = Scan::default();
    for (i, point) in sample_triangles(&triangles, options.points, options.seed) {
        match targets[kept[i]] {
            Target::Part { object, part } => by_part.entry(part).or_insert_with(|| (object, Vec::new())).1.push(point),
            Target::Background | Target::Drop => scan.background.push(point),
        }
    }
    for (id, (object, points)) in by_part {
        let label = ann.parts.get(&id).map_or_else(|| "unknown".to_owned(), |p| p.label.clone());
        scan.parts.push(ScanPart { id, object, label, points, normals: None });
        if let Some(o) = ann.objects.iter().find(|o| o.id == object) {
            scan.objects.entry(object).or_insert_with(|| ScanObject { id: object, category: o.category.clone() });
        }
    }
    // Parts with faces but no points: too small for the number of points asked for.
    let with_faces: BTreeSet<PartId> =
        targets.iter().filter_map(|t| if let Target::Part { part, .. } = *t { Some(part) } else { None }).collect();
    let missed: Vec<String> = with_faces
        .into_iter()
        .filter(|&p| scan.part(p).is_none())
        .map(|p| format!("{p} ({})", ann.parts.get(&p).map_or("?", |q| q.label.as_str())))
        .collect();
    if !missed.is_empty() {
        warnings.push(Warning::new(
            "import",
            format!("parts {}", missed.join(", ")),
            format!(
                "have faces but got none of the {} points (too small): not in the scan; eval reports them as unobserved",
                options.points
            ),
        ));
    }
    scan
}

/// The truth objects: every annotated object with faces, its parts as meshes, its joints.
fn ground_truth(mesh: &FaceMesh, targets: &[Target], ann: &Annotations, warnings: &mut Vec<Warning>) -> GroundTruth {
    let mut faces_of: BTreeMap<PartId, Vec<usize>> = BTreeMap::new();
    for (f, t) in targets.iter().enumerate() {
        if let Target::Part { part, .. } = *t {
            faces_of.entry(part).or_default().push(f);
        }
    }
    let mut objects = Vec::new();
    for o in ann.objects.iter().filter(|o| !o.arch && !o.removed) {
        let mut parts = Vec::new();
        for &id in &o.part_ids {
            let (Some(part), Some(faces)) = (ann.parts.get(&id), faces_of.get(&id)) else {
                warnings.push(Warning::new(
                    "import",
                    format!("part {id}"),
                    format!("of object {} ({}) has no faces in the mesh: left out", o.id, o.label),
                ));
                continue;
            };
            parts.push(TruthPart { id, label: part.label.clone(), shapes: Vec::new(), meshes: vec![part_mesh(mesh, faces)] });
        }
        if parts.is_empty() {
            continue;
        }
        let joints = object_joints(o, &parts, ann, warnings);
        let contact_edges = joints.iter().map(|j| [j.parent.min(j.child), j.parent.max(j.child)]).collect();
        objects.push(TruthObject { id: o.id, category: o.category.clone(), supported_by: None, parts, joints, contact_edges });
    }
    GroundTruth { format: TRUTH_FORMAT.into(), objects, floor_z: floor_height(mesh, ann) }
}

/// The faces as a mesh of their own (vertices in first-use order).
fn part_mesh(mesh: &FaceMesh, faces: &[usize]) -> TruthMesh {
    let mut index: HashMap<u32, u32> = HashMap::new();
    let mut out = TruthMesh::default();
    for &f in faces {
        let tri = mesh.faces[f].vertices.map(|v| {
            *index.entry(v).or_insert_with(|| {
                out.vertices.push(mesh.vertices[v as usize]);
                (out.vertices.len() - 1) as u32
            })
        });
        out.triangles.push(tri);
    }
    out
}

/// One joint per part of the object with a parent among the object's truth parts.
fn object_joints(object: &AnnotatedObject, parts: &[TruthPart], ann: &Annotations, warnings: &mut Vec<Warning>) -> Vec<Joint> {
    let mut joints = Vec::new();
    for truth_part in parts {
        let Some(part) = ann.parts.get(&truth_part.id) else { continue };
        if part.articulation_count > 1 {
            warnings.push(Warning::new(
                "import",
                format!("part {}", part.id),
                format!("has {} articulations: the first is used", part.articulation_count),
            ));
        }
        let Some(parent) = part.parent else { continue };
        if !parts.iter().any(|p| p.id == parent) {
            let why = if object.part_ids.contains(&parent) { "has no faces" } else { "belongs to another object" };
            warnings.push(Warning::new("import", format!("part {}", part.id), format!("its parent, part {parent}, {why}: no truth joint")));
            continue;
        }
        let centroid =
            truth_part.meshes.first().map_or(Vec3::ZERO, |m| m.vertices.iter().copied().sum::<Vec3>() / m.vertices.len().max(1) as f32);
        joints.push(truth_joint(part, parent, centroid, warnings));
    }
    joints
}

/// A `MultiScan` articulation as a truth joint (see the module doc for the conventions).
fn truth_joint(part: &AnnotatedPart, parent: PartId, centroid: Vec3, warnings: &mut Vec<Warning>) -> Joint {
    let fixed =
        Joint { parent, child: part.id, kind: JointKind::Fixed, axis_world: Vec3::X, origin_world: centroid, lower: 0.0, upper: 0.0 };
    let Some(a) = &part.articulation else { return fixed };
    let kind = match a.kind.as_str() {
        "rotation" => JointKind::Revolute,
        "translation" => JointKind::Prismatic,
        other => {
            warnings.push(Warning::new(
                "import",
                format!("part {}", part.id),
                format!("articulation type \"{other}\" (expected rotation or translation): fixed"),
            ));
            return fixed;
        }
    };
    let mut axis = a.axis;
    let (mut lower, mut upper) = (a.range_min - a.state, a.range_max - a.state);
    if a.range_min.abs() > a.range_max.abs() {
        axis = axis.map(|v| -v);
        (lower, upper) = (-upper, -lower);
    }
    Joint {
        parent,
        child: part.id,
        kind,
        axis_world: Vec3::new(axis[0] as f32, axis[1] as f32, axis[2] as f32),
        origin_world: Vec3::new(a.origin[0] as f32, a.origin[1] as f32, a.origin[2] as f32),
        lower: lower as f32,
        upper: upper as f32,
    }
}

/// The lowest vertex of the `floor` arch objects' faces, else of the whole mesh (0 without faces).
fn floor_height(mesh: &FaceMesh, ann: &Annotations) -> f32 {
    let floors: Vec<ObjectId> = ann.objects.iter().filter(|o| o.arch && o.category.eq_ignore_ascii_case("floor")).map(|o| o.id).collect();
    let lowest = |faces: &mut dyn Iterator<Item = &super::MeshFace>| {
        faces.flat_map(|f| f.vertices).map(|v| mesh.vertices[v as usize].z).reduce(f32::min)
    };
    lowest(&mut mesh.faces.iter().filter(|f| floors.contains(&f.object))).or_else(|| lowest(&mut mesh.faces.iter())).unwrap_or(0.0)
}
