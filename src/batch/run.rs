//! Running a batch: one scan at a time per core, resuming from `batch-entry.json` files.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{BatchError, BatchInput};
use crate::export::{UrdfConfig, write_scene_files};
use crate::pipeline::{PinnedEdits, PipelineConfig, Quiet, reconstruct};

/// The format tag of `batch.json` and of every `batch-entry.json`.
pub const BATCH_FORMAT: &str = "partscene-batch/1";
/// Written last into a scan's output folder: it finished (or failed), with which inputs.
pub const BATCH_ENTRY_FILE: &str = "batch-entry.json";

/// What happened to one scan.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScanStatus {
    /// Reconstructed in this run.
    Done,
    /// Finished by an earlier run with the same inputs: left as it was.
    Skipped,
    /// Could not be read or reconstructed; the error says why.
    Failed,
}

/// One scan's line of the summary (also its `batch-entry.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScanOutcome {
    pub scan: PathBuf,
    pub name: String,
    pub out: PathBuf,
    pub status: ScanStatus,
    /// SHA-256 of the partscene version, the configuration, the scan and its labels file.
    pub fingerprint: String,
    pub objects: usize,
    pub parts: usize,
    pub joints: usize,
    pub movable_joints: usize,
    pub warnings: usize,
    /// Reading, reconstructing and writing, seconds (of the run that did it).
    pub seconds: f64,
    pub error: Option<String>,
}

/// `batch.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BatchReport {
    pub format: String,
    pub scans: Vec<ScanOutcome>,
    pub done: usize,
    pub skipped: usize,
    pub failed: usize,
    /// Wall-clock seconds of this run.
    pub seconds: f64,
    /// Threads the scans ran on.
    pub threads: usize,
}

impl BatchReport {
    /// The report of a run's outcomes (in input order), `seconds` long on `threads` threads.
    #[must_use]
    pub fn of(scans: Vec<ScanOutcome>, seconds: f64, threads: usize) -> Self {
        let count = |s: ScanStatus| scans.iter().filter(|o| o.status == s).count();
        Self {
            format: BATCH_FORMAT.to_owned(),
            done: count(ScanStatus::Done),
            skipped: count(ScanStatus::Skipped),
            failed: count(ScanStatus::Failed),
            scans,
            seconds,
            threads,
        }
    }

    /// Writes `batch.json` and `batch.md` into `out`.
    pub fn write(&self, out: &Path) -> Result<(), BatchError> {
        crate::io::atomic_write(&out.join("batch.json"), serde_json::to_string_pretty(self)?.as_bytes())?;
        crate::io::atomic_write(&out.join("batch.md"), self.markdown().as_bytes())?;
        Ok(())
    }

    /// The summary table (Markdown).
    #[must_use]
    pub fn markdown(&self) -> String {
        let mut out = String::from("| scan | status | objects | parts | joints (movable) | warnings | seconds | error |\n");
        out.push_str("| --- | --- | ---: | ---: | ---: | ---: | ---: | --- |\n");
        for s in &self.scans {
            let status = match s.status {
                ScanStatus::Done => "done",
                ScanStatus::Skipped => "skipped (done before)",
                ScanStatus::Failed => "FAILED",
            };
            let error = s.error.as_deref().unwrap_or("").replace('|', "\\|").replace('\n', " ");
            let _ = writeln!(
                out,
                "| {} | {status} | {} | {} | {} ({}) | {} | {:.2} | {error} |",
                s.name, s.objects, s.parts, s.joints, s.movable_joints, s.warnings, s.seconds
            );
        }
        let _ = writeln!(
            out,
            "\n{} scans: {} done, {} skipped, {} failed in {:.1} s on {} threads",
            self.scans.len(),
            self.done,
            self.skipped,
            self.failed,
            self.seconds,
            self.threads
        );
        out
    }
}

/// The fingerprint of a scan's inputs: what makes its outputs what they are.
fn fingerprint(scan: &Path, cfg: &PipelineConfig) -> Result<String, crate::io::IoError> {
    let mut h = Sha256::new();
    h.update(env!("CARGO_PKG_VERSION").as_bytes());
    h.update(format!("{cfg:?}").as_bytes());
    h.update(crate::io::read_bytes(scan)?);
    match crate::io::read_optional_string(&scan.with_extension("json"))? {
        Some(labels) => {
            h.update(b"labels");
            h.update(labels.as_bytes());
        }
        None => h.update(b"no labels"),
    }
    Ok(h.finalize().iter().fold(String::with_capacity(64), |mut hex, b| {
        let _ = write!(hex, "{b:02x}");
        hex
    }))
}

/// A finished entry from an earlier run, if the folder has one with this fingerprint.
fn finished_before(out: &Path, fingerprint: &str) -> Option<ScanOutcome> {
    let text = std::fs::read_to_string(out.join(BATCH_ENTRY_FILE)).ok()?;
    let entry: ScanOutcome = serde_json::from_str(&text).ok()?;
    (entry.status == ScanStatus::Done && entry.fingerprint == fingerprint).then_some(ScanOutcome { status: ScanStatus::Skipped, ..entry })
}

/// Reads, reconstructs and writes one scan; `Err` carries the message of what failed.
fn process(input: &BatchInput, out: &Path, cfg: &PipelineConfig, outcome: &mut ScanOutcome) -> Result<(), String> {
    let (scan, scan_warnings) = crate::scan::read_scan(&input.scan).map_err(|e| e.to_string())?;
    let mut scene = reconstruct(&scan, cfg, &PinnedEdits::default(), &Quiet);
    scene.warnings.splice(0..0, scan_warnings);
    write_scene_files(out, &scene, &UrdfConfig::default()).map_err(|e| e.to_string())?;
    outcome.objects = scene.objects.len();
    outcome.parts = scene.parts.len();
    outcome.joints = scene.joints.len();
    outcome.movable_joints = scene.joints.iter().filter(|j| j.kind.is_movable()).count();
    outcome.warnings = scene.warnings.len();
    Ok(())
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_owned())
}

/// One scan, start to finish, never failing the batch: skipped when an earlier run finished it
/// with the same fingerprint, else read, reconstructed and written into `out_root/<name>/` with its
/// `batch-entry.json` last. What `run_batch` runs per scan and the Python/Ray path runs per task.
#[must_use]
pub fn run_one(input: &BatchInput, out_root: &Path, cfg: &PipelineConfig) -> ScanOutcome {
    let started = Instant::now();
    let out = out_root.join(&input.name);
    let mut outcome = ScanOutcome {
        scan: input.scan.clone(),
        name: input.name.clone(),
        out: out.clone(),
        status: ScanStatus::Failed,
        fingerprint: String::new(),
        objects: 0,
        parts: 0,
        joints: 0,
        movable_joints: 0,
        warnings: 0,
        seconds: 0.0,
        error: None,
    };
    match fingerprint(&input.scan, cfg) {
        Ok(f) => outcome.fingerprint = f,
        Err(e) => {
            outcome.error = Some(e.to_string());
            return outcome;
        }
    }
    if let Some(before) = finished_before(&out, &outcome.fingerprint) {
        return ScanOutcome { scan: input.scan.clone(), name: input.name.clone(), out, ..before };
    }
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| process(input, &out, cfg, &mut outcome)))
        .unwrap_or_else(|payload| Err(format!("internal error (panic): {}", panic_message(&*payload))));
    outcome.seconds = started.elapsed().as_secs_f64();
    match result {
        Ok(()) => outcome.status = ScanStatus::Done,
        Err(message) => outcome.error = Some(message),
    }
    // The entry goes last: a folder without one (a run killed half-way) is redone. A failed scan's
    // entry records the error; the next run tries it again.
    if let Ok(text) = serde_json::to_string_pretty(&outcome)
        && let Err(e) = std::fs::create_dir_all(&out)
            .map_err(|e| e.to_string())
            .and_then(|()| crate::io::atomic_write(&out.join(BATCH_ENTRY_FILE), text.as_bytes()).map_err(|e| e.to_string()))
    {
        outcome.status = ScanStatus::Failed;
        outcome.error = Some(format!("cannot record the outcome: {e}"));
    }
    outcome
}

/// Runs `inputs` into `out` (created if missing), in parallel, reporting `(done, total, name)` as
/// scans finish; writes `batch.json` and `batch.md` there. Scans are listed in input order.
pub fn run_batch(
    inputs: &[BatchInput],
    out: &Path,
    cfg: &PipelineConfig,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> Result<BatchReport, BatchError> {
    if inputs.is_empty() {
        return Err(BatchError::NoScans);
    }
    std::fs::create_dir_all(out).map_err(|e| crate::io::IoError::new(out, "create", e))?;
    let started = Instant::now();
    let finished = AtomicUsize::new(0);
    progress(0, inputs.len(), "");
    let scans: Vec<ScanOutcome> = inputs
        .par_iter()
        .map(|input| {
            let outcome = run_one(input, out, cfg);
            progress(finished.fetch_add(1, Ordering::SeqCst) + 1, inputs.len(), &input.name);
            outcome
        })
        .collect();
    let report = BatchReport::of(scans, started.elapsed().as_secs_f64(), rayon::current_num_threads());
    report.write(out)?;
    Ok(report)
}
