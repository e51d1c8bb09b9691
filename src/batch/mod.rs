//! `partscene batch`: many scans reconstructed in one run that can be left overnight.
//!
//! Every scan gets its own output folder (`OUT/<name>/`, the files of `partscene reconstruct`)
//! and, written last, `batch-entry.json`: the scan's fingerprint (SHA-256 of the scan, its
//! labels file, the partscene version and the pipeline configuration) and what came out. A
//! re-run skips every scan whose entry says it finished with the same fingerprint (same inputs →
//! same outputs), so an interrupted batch resumes; a scan that failed is tried again. One bad
//! scan never stops the rest: its error (or panic) is recorded and the batch goes on. Scans run
//! in parallel on the local cores (rayon). `OUT/batch.json` and `OUT/batch.md` summarise the
//! run: per scan the parts, joints, warnings, time and failure.

mod inputs;
mod run;

pub use inputs::{BatchInput, resolve_inputs};
pub use run::{BATCH_ENTRY_FILE, BATCH_FORMAT, BatchReport, ScanOutcome, ScanStatus, run_batch, run_one};

use std::path::PathBuf;

/// Why a batch could not start (a scan that fails is an outcome, not an error).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    #[error("{input}: {problem}")]
    Input { input: PathBuf, problem: String },
    #[error("no scans given: expected scan files, folders, glob patterns or .txt manifests")]
    NoScans,
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    #[error("cannot write the batch summary: {0}")]
    Json(#[from] serde_json::Error),
}
