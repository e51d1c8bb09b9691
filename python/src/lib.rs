//! `partscene._native`: the Python binding of the partscene core (no GUI, no simulator).
//!
//! The Python package `partscene` (`pysrc/partscene/`) wraps this module: it checks dtypes and
//! shapes of the NumPy arrays, names the offending array, and turns the JSON documents returned
//! here into plain Python data. This module does the work with the GIL released and raises
//! `partscene.PartsceneError` carrying the core's messages (file, array, row, field).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use partscene::export::{DynamicsTable, UrdfConfig, scene_from_json, scene_json, scene_mjcf, scene_urdf, scene_usda, write_scene_files};
use partscene::model::SceneModel;
use partscene::pipeline::{PinnedEdits, PipelineConfig, Quiet, reconstruct as run_pipeline};
use partscene::report::Warning;
use partscene::scan::{Scan, ScanArrays, scan_from_arrays};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(_native, PartsceneError, PyException, "An error reported by partscene (bad input, unreadable file).");

fn err(e: impl std::fmt::Display) -> PyErr {
    PartsceneError::new_err(e.to_string())
}

fn warning_texts(warnings: &[Warning]) -> Vec<String> {
    warnings.iter().map(ToString::to_string).collect()
}

/// A scan read from a file or built from arrays, as the core holds it.
#[pyclass(module = "partscene._native", frozen)]
struct NativeScan {
    scan: Scan,
    /// What reading it reported.
    warnings: Vec<Warning>,
}

#[pymethods]
impl NativeScan {
    #[getter]
    fn source(&self) -> String {
        self.scan.source.clone()
    }

    #[getter]
    fn warnings(&self) -> Vec<String> {
        warning_texts(&self.warnings)
    }

    /// (points float32 (N, 3), normals float32 (N, 3) or None, object_ids int64 (N,),
    /// part_ids int64 (N,)): the parts' points in part order, then the background (ids -1;
    /// normals NaN there, as a scan keeps none for the background).
    #[allow(clippy::type_complexity)]
    fn arrays<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray2<f32>>, Option<Bound<'py, PyArray2<f32>>>, Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>) {
        let n = self.scan.point_count();
        let has_normals = self.scan.parts.iter().any(|p| p.normals.is_some());
        let mut points = Array2::<f32>::zeros((n, 3));
        let mut normals = Array2::<f32>::from_elem((n, 3), f32::NAN);
        let mut objects = Array1::<i64>::from_elem(n, -1);
        let mut parts = Array1::<i64>::from_elem(n, -1);
        let mut row = 0;
        for part in &self.scan.parts {
            for (k, p) in part.points.iter().enumerate() {
                points.row_mut(row).assign(&numpy::ndarray::arr1(&p.to_array()));
                if let Some(ns) = &part.normals
                    && let Some(nv) = ns.get(k)
                {
                    normals.row_mut(row).assign(&numpy::ndarray::arr1(&nv.to_array()));
                }
                objects[row] = part.object;
                parts[row] = part.id;
                row += 1;
            }
        }
        for p in &self.scan.background {
            points.row_mut(row).assign(&numpy::ndarray::arr1(&p.to_array()));
            row += 1;
        }
        (points.into_pyarray(py), has_normals.then(|| normals.into_pyarray(py)), objects.into_pyarray(py), parts.into_pyarray(py))
    }

    /// (part id → label, object id → category).
    fn labels(&self) -> (BTreeMap<i64, String>, BTreeMap<i64, String>) {
        (
            self.scan.parts.iter().map(|p| (p.id, p.label.clone())).collect(),
            self.scan.objects.values().map(|o| (o.id, o.category.clone())).collect(),
        )
    }
}

/// A reconstructed scene.
#[pyclass(module = "partscene._native", frozen)]
struct NativeScene {
    scene: SceneModel,
}

#[pymethods]
impl NativeScene {
    /// `scene.json` text.
    fn json(&self) -> String {
        scene_json(&self.scene)
    }

    /// `scene.urdf` text.
    fn urdf(&self) -> PyResult<String> {
        scene_urdf(&self.scene, &UrdfConfig::default()).map_err(err)
    }

    /// `scene.mjcf.xml` text (no fitted dynamics).
    fn mjcf(&self) -> PyResult<String> {
        scene_mjcf(&self.scene, &UrdfConfig::default(), &DynamicsTable::new()).map_err(err)
    }

    /// `scene.usda` text (`UsdPhysics`, no fitted dynamics).
    fn usda(&self) -> PyResult<String> {
        scene_usda(&self.scene, &UrdfConfig::default(), &DynamicsTable::new()).map_err(err)
    }

    /// Writes the CLI's files into `dir`; returns their paths.
    fn save(&self, py: Python<'_>, dir: PathBuf) -> PyResult<Vec<PathBuf>> {
        let files = py.detach(|| write_scene_files(&dir, &self.scene, &UrdfConfig::default())).map_err(err)?;
        Ok(files.all().into_iter().map(Path::to_path_buf).collect())
    }
}

/// Reads a scan file (PLY or .npz, with its labels JSON beside it).
#[pyfunction]
fn read_scan(py: Python<'_>, path: PathBuf) -> PyResult<NativeScan> {
    let (scan, warnings) = py.detach(|| partscene::scan::read_scan(&path)).map_err(err)?;
    Ok(NativeScan { scan, warnings })
}

/// Builds a scan from arrays (float64 points and normals, int64 ids; the Python layer converts).
#[pyfunction]
#[pyo3(signature = (points, object_ids, part_ids, part_labels, object_categories, normals, source))]
#[allow(clippy::too_many_arguments, clippy::needless_pass_by_value)]
fn scan_from_numpy(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    object_ids: PyReadonlyArray1<'_, i64>,
    part_ids: PyReadonlyArray1<'_, i64>,
    part_labels: BTreeMap<i64, String>,
    object_categories: BTreeMap<i64, String>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    source: String,
) -> PyResult<NativeScan> {
    let rows = |a: &numpy::ndarray::ArrayView2<'_, f64>| -> Vec<[f64; 3]> { a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect() };
    let pts = rows(&points.as_array());
    let nrm = normals.as_ref().map(|n| rows(&n.as_array()));
    let objects = object_ids.as_array().to_vec();
    let parts = part_ids.as_array().to_vec();
    let (scan, warnings) = py
        .detach(|| {
            let arrays = ScanArrays {
                points: &pts,
                normals: nrm.as_deref(),
                object_ids: &objects,
                part_ids: &parts,
                part_labels: &part_labels,
                object_categories: &object_categories,
            };
            scan_from_arrays(&arrays, &source)
        })
        .map_err(err)?;
    Ok(NativeScan { scan, warnings })
}

/// Runs the pipeline on a scan; `vocabulary` is an optional TOML file laid over the built-in
/// part vocabulary (the CLI's `--vocab`). The scan's warnings come first, as in the CLI.
#[pyfunction]
#[pyo3(signature = (scan, vocabulary=None))]
fn reconstruct(py: Python<'_>, scan: &NativeScan, vocabulary: Option<PathBuf>) -> PyResult<NativeScene> {
    let cfg = pipeline_config(vocabulary.as_deref())?;
    let mut scene = py.detach(|| run_pipeline(&scan.scan, &cfg, &PinnedEdits::default(), &Quiet));
    // The scan's warnings lead, as `partscene reconstruct` puts them.
    scene.warnings.splice(0..0, scan.warnings.iter().cloned());
    Ok(NativeScene { scene })
}

/// Reads `scene.json`.
#[pyfunction]
fn scene_from_json_text(text: &str, name: &str) -> PyResult<NativeScene> {
    scene_from_json(text, name).map(|scene| NativeScene { scene }).map_err(err)
}

/// The paper's metrics of a scene against ground truth (`gt.json` text); JSON text.
#[pyfunction]
fn evaluate(py: Python<'_>, scene: &NativeScene, truth_json: &str, truth_name: &str) -> PyResult<String> {
    let truth: partscene::truth::GroundTruth =
        serde_json::from_str(truth_json).map_err(|e| err(format!("{truth_name}: not a partscene gt.json: {e}")))?;
    let metrics = py.detach(|| partscene::eval::evaluate(&scene.scene, &truth));
    serde_json::to_string(&metrics).map_err(err)
}

/// `partscene gap` on a model URDF and a recording: a CSV file, or CSV text (`csv_text`, named
/// `recording` in errors); the report as JSON text.
#[pyfunction]
#[pyo3(signature = (model, recording, csv_text=None))]
fn gap_analyze(py: Python<'_>, model: PathBuf, recording: PathBuf, csv_text: Option<String>) -> PyResult<String> {
    use partscene::gap;
    let report = py
        .detach(|| -> Result<gap::GapReport, String> {
            let rec = match &csv_text {
                Some(text) => gap::parse_recording(text, &recording),
                None => gap::read_recording(&recording),
            }
            .map_err(|e| e.to_string())?;
            let model = gap::load_model(&model).map_err(|e| e.to_string())?;
            gap::analyze(&model, &rec, &gap::GapConfig::default()).map_err(|e| e.to_string())
        })
        .map_err(err)?;
    serde_json::to_string(&report).map_err(err)
}

/// The pipeline configuration with an optional vocabulary file laid over the built-in one.
fn pipeline_config(vocabulary: Option<&Path>) -> PyResult<PipelineConfig> {
    let mut cfg = PipelineConfig::default();
    if let Some(path) = vocabulary {
        cfg.vocabulary = std::sync::Arc::new(cfg.vocabulary.extended_with_file(path).map_err(err)?);
    }
    Ok(cfg)
}

/// The scans named by inputs (files, folders, globs, manifests) with their output names, as
/// `partscene batch` resolves them: [(scan path, name)].
#[pyfunction]
fn batch_inputs(inputs: Vec<PathBuf>) -> PyResult<Vec<(PathBuf, String)>> {
    Ok(partscene::batch::resolve_inputs(&inputs).map_err(err)?.into_iter().map(|b| (b.scan, b.name)).collect())
}

/// One scan of a batch into `out/<name>/` exactly as `partscene batch` does it (skip when done
/// with the same inputs, never raising for the scan's own failure); the outcome as JSON text.
#[pyfunction]
#[pyo3(signature = (scan, name, out, vocabulary=None))]
fn batch_run_one(py: Python<'_>, scan: PathBuf, name: String, out: PathBuf, vocabulary: Option<PathBuf>) -> PyResult<String> {
    let cfg = pipeline_config(vocabulary.as_deref())?;
    let input = partscene::batch::BatchInput { scan, name };
    let outcome = py.detach(|| partscene::batch::run_one(&input, &out, &cfg));
    serde_json::to_string(&outcome).map_err(err)
}

/// Writes `batch.json` and `batch.md` for outcomes (JSON texts from `batch_run_one`); returns the
/// report as JSON text.
#[pyfunction]
fn batch_write_report(outcomes: Vec<String>, out: PathBuf, seconds: f64, threads: usize) -> PyResult<String> {
    let scans =
        outcomes.iter().map(|t| serde_json::from_str::<partscene::batch::ScanOutcome>(t).map_err(err)).collect::<PyResult<Vec<_>>>()?;
    let report = partscene::batch::BatchReport::of(scans, seconds, threads);
    report.write(&out).map_err(err)?;
    serde_json::to_string(&report).map_err(err)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("PartsceneError", m.py().get_type::<PartsceneError>())?;
    m.add_class::<NativeScan>()?;
    m.add_class::<NativeScene>()?;
    m.add_function(wrap_pyfunction!(read_scan, m)?)?;
    m.add_function(wrap_pyfunction!(scan_from_numpy, m)?)?;
    m.add_function(wrap_pyfunction!(reconstruct, m)?)?;
    m.add_function(wrap_pyfunction!(scene_from_json_text, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(gap_analyze, m)?)?;
    m.add_function(wrap_pyfunction!(batch_inputs, m)?)?;
    m.add_function(wrap_pyfunction!(batch_run_one, m)?)?;
    m.add_function(wrap_pyfunction!(batch_write_report, m)?)?;
    Ok(())
}
