//! The fuzz harness: one function per reader of untrusted input, each feeding raw bytes to the
//! library's entry point for that format and then to what consumes the result, bounded in size.
//!
//! Shared by the libFuzzer targets (`fuzz/fuzz_targets/*.rs`, nightly, `cargo fuzz run NAME`) and
//! by the stable regression test of the main crate (`tests/fuzz_regressions.rs` includes this file
//! as a module and replays every file of `fuzz/regressions/NAME/`). A harness function returns
//! normally for any input, `true` when the reader accepted it (and what consumes the result ran):
//! an error from the reader is the expected answer to a bad file; a panic, an abort, a hang or a
//! huge allocation is a finding.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::OnceLock;

use partscene::assets::mesh::{MeshFormat, parse_mesh};
use partscene::assets::{ArticulatedAsset, mjcf, urdf};
use partscene::bench::truth::{AssetTruthOptions, asset_truth};
use partscene::edit::Session;
use partscene::export::{DynamicsTable, UrdfConfig, scene_from_json, scene_glb, scene_json, scene_mjcf, scene_urdf};
use partscene::import::multiscan::{MultiScanOptions, import_multiscan_bytes};
use partscene::math::DVec3;
use partscene::model::SceneModel;
use partscene::pipeline::{FittedParts, FloorHint, PinnedEdits, PipelineConfig, Quiet, assemble, fit_parts, reconstruct};
use partscene::scan::{MAX_COORDINATE_M, ObjectId, Scan, read_scan_bytes, read_scan_npz_bytes};
use partscene::truth::{GroundTruth, TRUTH_FORMAT, TruthObject, TruthPart};
use partscene::{eval, gap};

/// A harness: the input's bytes in, whether the reader accepted them out.
pub type Harness = fn(&[u8]) -> bool;

/// Every target: its name (the `fuzz_targets/NAME.rs` file, the corpus and regression folders)
/// and its harness.
pub const TARGETS: &[(&str, Harness)] = &[
    ("scan_ply", scan_ply),
    ("gap_recording", gap_recording),
    ("gap_mcap", gap_mcap),
    ("gap_model", gap_model),
    ("asset_urdf", asset_urdf),
    ("asset_mjcf", asset_mjcf),
    ("mesh_obj", mesh_obj),
    ("mesh_stl", mesh_stl),
    ("mesh_glb", mesh_glb),
    ("mesh_msh", mesh_msh),
    ("session", session),
    ("scene_json", scene_json_target),
    ("gt_json", gt_json),
    ("scan_npz", scan_npz),
    ("multiscan", multiscan),
];

/// In a `scan_ply` input, the labels JSON follows the PLY after this line (no such line: the scan
/// has no labels file).
pub const LABELS_SEPARATOR: &[u8] = b"\n#labels#\n";

/// Scans up to this many points are reconstructed (the pipeline's cost grows with the points; the
/// reader is what is fuzzed at any size).
pub const MAX_RECONSTRUCT_POINTS: usize = 2_000;

/// Scenes and ground truths with up to this many parts are evaluated (Chamfer samples and 32³ voxel
/// grids per object cost milliseconds each; the reader is what is fuzzed at any size).
pub const MAX_EVAL_PARTS: usize = 16;

/// Where the fuzzed files pretend to live: a folder that does not exist, so references to other
/// files (meshes, includes, glTF buffers) resolve to nothing.
const NOWHERE: &str = "/nonexistent/partscene-fuzz";

/// Splits a `scan_ply` input into the PLY and the labels text (see [`LABELS_SEPARATOR`]).
#[must_use]
pub fn split_labels(data: &[u8]) -> (&[u8], Option<&[u8]>) {
    match data.windows(LABELS_SEPARATOR.len()).position(|w| w == LABELS_SEPARATOR) {
        Some(at) => (&data[..at], Some(&data[at + LABELS_SEPARATOR.len()..])),
        None => (data, None),
    }
}

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// Every export of a scene; each may refuse it with an error, none may crash.
fn export_all(scene: &SceneModel) {
    let cfg = UrdfConfig::default();
    let _ = scene_urdf(scene, &cfg);
    let _ = scene_mjcf(scene, &cfg, &DynamicsTable::new());
    let _ = scene_glb(scene);
    let _ = scene_json(scene);
}

/// PLY bytes (+ labels JSON after [`LABELS_SEPARATOR`]) → scan; a scan that reads is within the
/// coordinate limit, and up to [`MAX_RECONSTRUCT_POINTS`] points it is reconstructed and exported.
pub fn scan_ply(data: &[u8]) -> bool {
    let (ply, labels) = split_labels(data);
    let labels = match labels.map(text) {
        Some(None) => return false,
        Some(Some(t)) => Some(t),
        None => None,
    };
    let Ok((scan, _warnings)) = read_scan_bytes(ply, "fuzz.ply", labels, "fuzz.json") else { return false };
    check_and_reconstruct(&scan);
    true
}

/// A scan that a reader accepted is within the coordinate limit; up to
/// [`MAX_RECONSTRUCT_POINTS`] points it is reconstructed and exported.
fn check_and_reconstruct(scan: &Scan) -> Option<SceneModel> {
    let points = scan.parts.iter().flat_map(|p| &p.points).chain(&scan.background);
    for p in points {
        assert!(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE_M, "the reader let {p} through");
    }
    (scan.point_count() <= MAX_RECONSTRUCT_POINTS).then(|| {
        let scene = reconstruct(scan, &PipelineConfig::default(), &PinnedEdits::default(), &Quiet);
        export_all(&scene);
        scene
    })
}

/// `NumPy` `.npz` bytes (+ labels JSON after [`LABELS_SEPARATOR`]) → scan → as for [`scan_ply`].
pub fn scan_npz(data: &[u8]) -> bool {
    let (npz, labels) = split_labels(data);
    let labels = match labels.map(text) {
        Some(None) => return false,
        Some(Some(t)) => Some(t),
        None => None,
    };
    let Ok((scan, _warnings)) = read_scan_npz_bytes(npz, "fuzz.npz", labels, "fuzz.json") else { return false };
    check_and_reconstruct(&scan);
    true
}

/// Points a fuzzed `MultiScan` mesh is sampled into (small: the reader and the conversion are
/// what is fuzzed, not the pipeline at scale).
pub const MULTISCAN_POINTS: usize = 1_500;

/// A `MultiScan` face-annotated mesh PLY, then the annotations JSON after [`LABELS_SEPARATOR`] →
/// scan and ground truth → the scan reconstructed and (up to [`MAX_EVAL_PARTS`] parts) evaluated
/// against the truth.
pub fn multiscan(data: &[u8]) -> bool {
    let (ply, annotations) = split_labels(data);
    let Some(Some(annotations)) = annotations.map(text) else { return false };
    let options = MultiScanOptions { points: MULTISCAN_POINTS, seed: 0 };
    let Ok(import) = import_multiscan_bytes(ply, "fuzz.ply", annotations, "fuzz.annotations.json", "scene_00000_00", options) else {
        return false;
    };
    let scene = check_and_reconstruct(&import.scan);
    if let Some(scene) = scene
        && import.truth.objects.iter().map(|o| o.parts.len()).sum::<usize>() <= MAX_EVAL_PARTS
    {
        let _ = eval::evaluate(&scene, &import.truth);
    }
    true
}

/// Gap recording CSV text → recording.
pub fn gap_recording(data: &[u8]) -> bool {
    text(data).is_some_and(|text| gap::parse_recording(text, Path::new("fuzz.csv")).is_ok())
}

/// A ROS recording (MCAP: `JointState` and TF, for a model whose root is `base` and whose moved
/// links are `door` and `drawer`) → recording CSV → recording.
pub fn gap_mcap(data: &[u8]) -> bool {
    let frames = gap::mcap::TfFrames { root: "base".to_owned(), tracked: ["door".to_owned(), "drawer".to_owned()].into() };
    gap::mcap::mcap_to_csv(data, Path::new("fuzz.mcap"), None, Some(&frames))
        .is_ok_and(|csv| gap::parse_recording(&csv, Path::new("fuzz.mcap")).is_ok())
}

/// URDF text → gap model → multibody → one inverse dynamics call (at rest and moving).
pub fn gap_model(data: &[u8]) -> bool {
    let Some(text) = text(data) else { return false };
    let Ok(model) = gap::parse_model(text, Path::new("fuzz.urdf")) else { return false };
    let Ok((tree, _bodies)) = model.multibody() else { return false };
    let n = tree.dof_count();
    let gravity = DVec3::new(0.0, 0.0, -9.81);
    let efforts = tree.inverse_dynamics(&vec![0.3; n], &vec![0.5; n], &vec![1.0; n], gravity);
    efforts.len() == n
}

/// An imported asset, then the ground truth the benchmark makes of it.
fn asset_consumers(asset: &ArticulatedAsset) {
    let _ = asset.primitives();
    let _ = asset.root_links();
    let _ = asset_truth(asset, &AssetTruthOptions { category: "fuzz".into(), ..AssetTruthOptions::default() });
}

/// URDF text → articulated asset → ground truth (meshes resolve nowhere).
pub fn asset_urdf(data: &[u8]) -> bool {
    let Some(text) = text(data) else { return false };
    let Ok(asset) = urdf::parse_urdf(text, Path::new("fuzz.urdf"), Path::new(NOWHERE), "fuzz") else { return false };
    asset_consumers(&asset);
    true
}

/// MJCF text → articulated asset → ground truth (includes and meshes resolve nowhere).
pub fn asset_mjcf(data: &[u8]) -> bool {
    let Some(text) = text(data) else { return false };
    let Ok(asset) = mjcf::parse_mjcf(text, &Path::new(NOWHERE).join("fuzz.xml")) else { return false };
    asset_consumers(&asset);
    true
}

fn mesh(data: &[u8], format: MeshFormat, name: &str) -> bool {
    let Ok(mesh) = parse_mesh(data, format, &Path::new(NOWHERE).join(name)) else { return false };
    let n = mesh.vertices.len();
    assert!(mesh.vertices.iter().all(|v| v.is_finite()), "a non-finite vertex was let through");
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n), "an index past the vertices was let through");
    true
}

/// OBJ bytes → triangle mesh.
pub fn mesh_obj(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Obj, "fuzz.obj")
}

/// STL bytes (ASCII or binary) → triangle mesh.
pub fn mesh_stl(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Stl, "fuzz.stl")
}

/// GLB bytes → triangle mesh.
pub fn mesh_glb(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Gltf, "fuzz.glb")
}

/// `MuJoCo` `.msh` bytes → triangle mesh.
pub fn mesh_msh(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Msh, "fuzz.msh")
}

/// A small fitted object (the first object of the clean demo scan) and its category, fitted once
/// per process: what the `session` target applies a session's pins to.
pub fn fitted_object() -> &'static (FittedParts, BTreeMap<ObjectId, String>) {
    static FITTED: OnceLock<(FittedParts, BTreeMap<ObjectId, String>)> = OnceLock::new();
    FITTED.get_or_init(|| {
        let (_truth, mut scan) = partscene::synth::demo_clean(0);
        let object = scan.parts.first().map_or(0, |p| p.object);
        scan.parts.retain(|p| p.object == object);
        scan.objects.retain(|&id, _| id == object);
        scan.background.clear();
        let fitted = fit_parts(&scan, &PipelineConfig::default(), &PinnedEdits::default(), &Quiet);
        let categories = scan.objects.values().map(|o| (o.id, o.category.clone())).collect();
        (fitted, categories)
    })
}

/// Session JSON → session; its pins are applied to a small fitted object (the scan it names is not
/// opened) and the result exported.
pub fn session(data: &[u8]) -> bool {
    let Some(text) = text(data) else { return false };
    let Ok(session) = Session::parse(text, &Path::new(NOWHERE).join("fuzz.session.json")) else { return false };
    let (fitted, categories) = fitted_object();
    let (scene, _stats) = assemble(fitted, categories, FloorHint::Height(0.0), &PipelineConfig::default(), &session.pins);
    export_all(&scene);
    true
}

/// A ground truth with the scene's own parts: what `eval` compares a scene with.
fn truth_of(scene: &SceneModel) -> GroundTruth {
    let mut objects: BTreeMap<ObjectId, TruthObject> = BTreeMap::new();
    for part in &scene.parts {
        let object = objects.entry(part.object).or_insert_with(|| TruthObject {
            id: part.object,
            category: "object".into(),
            supported_by: None,
            parts: Vec::new(),
            joints: scene.joints.clone(),
            contact_edges: Vec::new(),
        });
        object.parts.push(TruthPart { id: part.id, label: part.label.clone(), shapes: vec![part.primitive], meshes: Vec::new() });
    }
    GroundTruth { format: TRUTH_FORMAT.into(), objects: objects.into_values().collect(), floor_z: scene.floor_z }
}

/// `scene.json` text → scene → exports, and (up to [`MAX_EVAL_PARTS`] parts) `eval` of the scene
/// against itself.
pub fn scene_json_target(data: &[u8]) -> bool {
    let Some(text) = text(data) else { return false };
    let Ok(scene) = scene_from_json(text, "fuzz.scene.json") else { return false };
    export_all(&scene);
    if scene.parts.len() <= MAX_EVAL_PARTS {
        let _ = eval::evaluate(&scene, &truth_of(&scene));
    }
    true
}

/// `gt.json` text → ground truth (as `partscene eval` reads it) → (up to [`MAX_EVAL_PARTS`]
/// parts) `eval` of an empty scene and of the truth's own primitives against it.
pub fn gt_json(data: &[u8]) -> bool {
    let Some(text) = text(data) else { return false };
    let Ok(truth) = serde_json::from_str::<GroundTruth>(text) else { return false };
    if truth.objects.iter().map(|o| o.parts.len()).sum::<usize>() > MAX_EVAL_PARTS {
        return true;
    }
    let _ = eval::evaluate(&SceneModel::default(), &truth);
    let own: Vec<(ObjectId, Vec<_>)> =
        truth.objects.iter().map(|o| (o.id, o.parts.iter().flat_map(|p| p.shapes.iter().copied()).collect())).collect();
    let _ = eval::evaluate_geometry(&own, &truth);
    true
}
