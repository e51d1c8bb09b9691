//! Finding assets to benchmark: `MANIFEST.tsv` rows (`local_dir`, `category`, `source_repo`) or
//! a folder walk, and the one asset file per object folder.

use std::path::{Path, PathBuf};

use super::BenchError;
use super::truth::UpAxis;

/// One asset to benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct AssetEntry {
    /// A short name (`MANIFEST.tsv` `local_dir`, else the folder relative to the benchmark root).
    pub name: String,
    /// The URDF or MJCF file.
    pub path: PathBuf,
    /// `MANIFEST.tsv` `category`, else `None` (derived from the file name later).
    pub category: Option<String>,
    /// +y up for habitat-sim assets (glTF convention), else +z.
    pub up: UpAxis,
}

/// The URDF/MJCF file of an object folder: `*_obj.urdf` (habitat OBJ conversions), else
/// `*_standalone.xml` (franka kitchen), else the single `.urdf` / `.xml` in the folder or its
/// `urdf/` sub-folder.
pub fn choose_asset_file(folder: &Path) -> Result<PathBuf, BenchError> {
    let mut files = Vec::new();
    for dir in [folder.to_path_buf(), folder.join("urdf")] {
        let Ok(read) = std::fs::read_dir(&dir) else { continue };
        for entry in read.flatten() {
            let p = entry.path();
            let ext = p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
            if p.is_file() && matches!(ext.as_deref(), Some("urdf" | "xml")) {
                files.push(p);
            }
        }
    }
    files.sort();
    let name = |p: &PathBuf| p.file_name().and_then(|n| n.to_str()).unwrap_or("").to_owned();
    if let Some(p) = files.iter().find(|p| name(p).ends_with("_obj.urdf")) {
        return Ok(p.clone());
    }
    if let Some(p) = files.iter().find(|p| name(p).ends_with("_standalone.xml")) {
        return Ok(p.clone());
    }
    match files.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(BenchError::NoAsset { path: folder.to_path_buf(), message: "no .urdf or .xml file".into() }),
        many => Err(BenchError::NoAsset {
            path: folder.to_path_buf(),
            message: format!("{} candidate files and none is *_obj.urdf or *_standalone.xml", many.len()),
        }),
    }
}

/// A parsed `MANIFEST.tsv`: header names and rows of cells.
struct Manifest {
    path: PathBuf,
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Manifest {
    fn read(path: &Path) -> Result<Self, BenchError> {
        let bytes = crate::io::read_bytes(path)?;
        let text = String::from_utf8_lossy(&bytes);
        let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
        let Some((_, head)) = lines.next() else {
            return Err(BenchError::Manifest { path: path.to_path_buf(), line: 1, message: "empty file".into() });
        };
        let header: Vec<String> = head.split('\t').map(|s| s.trim().to_owned()).collect();
        let rows = lines.map(|(i, l)| (i + 1, l.split('\t').map(|s| s.trim().to_owned()).collect())).collect();
        let m = Self { path: path.to_path_buf(), header, rows };
        m.column("local_dir")?;
        Ok(m)
    }

    fn column(&self, name: &str) -> Result<usize, BenchError> {
        self.header.iter().position(|h| h == name).ok_or_else(|| BenchError::Manifest {
            path: self.path.clone(),
            line: 1,
            message: format!("no `{name}` column (have: {})", self.header.join(", ")),
        })
    }

    fn cell<'a>(&self, row: &'a [String], name: &str) -> Option<&'a str> {
        let i = self.header.iter().position(|h| h == name)?;
        row.get(i).map(String::as_str).filter(|s| !s.is_empty())
    }

    fn entry(&self, root: &Path, line: usize, row: &[String]) -> Result<AssetEntry, BenchError> {
        let local = self.cell(row, "local_dir").ok_or_else(|| BenchError::Manifest {
            path: self.path.clone(),
            line,
            message: "empty `local_dir`".into(),
        })?;
        let habitat = self.cell(row, "source_repo").is_some_and(|s| s.contains("habitat"));
        Ok(AssetEntry {
            name: local.to_owned(),
            path: choose_asset_file(&root.join(local))?,
            category: self.cell(row, "category").map(str::to_owned),
            up: if habitat { UpAxis::Y } else { UpAxis::Z },
        })
    }
}

/// Every asset under `dir`: one per `MANIFEST.tsv` row when the folder has one, else one per
/// folder (walked in name order) that holds an asset file directly or in `urdf/`.
pub fn find_assets(dir: &Path) -> Result<Vec<AssetEntry>, BenchError> {
    let manifest = dir.join("MANIFEST.tsv");
    if manifest.is_file() {
        let m = Manifest::read(&manifest)?;
        return m.rows.iter().map(|(line, row)| m.entry(dir, *line, row)).collect();
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out, 0);
    if out.is_empty() {
        return Err(BenchError::NoAsset { path: dir.to_path_buf(), message: "no MANIFEST.tsv and no folder with an asset file".into() });
    }
    Ok(out)
}

fn walk(root: &Path, dir: &Path, out: &mut Vec<AssetEntry>, depth: usize) {
    if depth > 6 {
        return;
    }
    if let Ok(path) = choose_asset_file(dir) {
        let name = dir.strip_prefix(root).map_or_else(|_| dir.display().to_string(), |p| p.display().to_string());
        out.push(AssetEntry { name: if name.is_empty() { ".".into() } else { name }, path, category: None, up: UpAxis::Z });
        return;
    }
    let Ok(read) = std::fs::read_dir(dir) else { return };
    let mut subdirs: Vec<PathBuf> = read.flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
    subdirs.sort();
    for sub in subdirs {
        walk(root, &sub, out, depth + 1);
    }
}

/// The `MANIFEST.tsv` row of an asset file, found in the asset's ancestor folders: the row whose
/// `local_dir` folder contains the file. `None` when there is no such manifest or row.
#[must_use]
pub fn manifest_entry_for(asset: &Path) -> Option<AssetEntry> {
    for root in asset.ancestors().skip(1) {
        let path = root.join("MANIFEST.tsv");
        if !path.is_file() {
            continue;
        }
        let m = Manifest::read(&path).ok()?;
        for (line, row) in &m.rows {
            let local = m.cell(row, "local_dir")?;
            if asset.starts_with(root.join(local)) {
                let mut entry = m.entry(root, *line, row).ok()?;
                entry.path = asset.to_path_buf();
                return Some(entry);
            }
        }
        return None;
    }
    None
}
