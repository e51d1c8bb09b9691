//! Benchmark on articulated objects made by others: import a URDF/MJCF asset
//! ([`crate::assets`]), turn it into ground truth ([`truth`]), scan it virtually
//! ([`crate::synth::scanner::scan`] over its primitives and meshes), reconstruct it and score the
//! part-level reconstruction and the object-level baseline ([`run`]).

pub mod manifest;
pub mod run;
pub mod truth;

use std::path::PathBuf;

use thiserror::Error;

pub use manifest::{AssetEntry, find_assets, manifest_entry_for};
pub use run::{BenchConfig, BenchReport, ObjectResult, SettingResult, bench_asset, bench_dir, load_asset_truth, scan_asset, scan_truth};
pub use truth::{AssetTruth, AssetTruthOptions, UpAxis, asset_truth, coarse_label};

/// Why a benchmark step failed.
#[derive(Debug, Error)]
pub enum BenchError {
    /// The asset could not be read (boxed: asset errors are large).
    #[error(transparent)]
    Asset(Box<crate::assets::AssetError>),
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// The reconstruction could not be exported (`--export`).
    #[error("asset `{asset}`: cannot export the reconstruction: {source}")]
    Export { asset: String, source: Box<crate::export::ExportError> },
    /// The truth could not be written as JSON (`--export`).
    #[error("asset `{asset}`: cannot write its truth as JSON: {message}")]
    TruthJson { asset: String, message: String },
    /// The asset has no link with geometry.
    #[error("asset `{asset}`: no link has geometry to scan")]
    NoGeometry { asset: String },
    /// `MANIFEST.tsv` lacks a column or a row is short.
    #[error("{}:{line}: {message}", path.display())]
    Manifest { path: PathBuf, line: usize, message: String },
    /// No asset file could be chosen in a folder.
    #[error("{}: {message}", path.display())]
    NoAsset { path: PathBuf, message: String },
}

impl From<crate::assets::AssetError> for BenchError {
    fn from(e: crate::assets::AssetError) -> Self {
        Self::Asset(Box::new(e))
    }
}
