//! File system helpers shared by every writer: atomic writes (temp file in the same folder, fsync,
//! rename) so that a crash or a full disk never leaves a half-written output, and reads whose
//! errors name the path.

use std::fs::{self, File, OpenOptions};
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use thiserror::Error;

/// A file system operation failed on `path`.
#[derive(Debug, Error)]
#[error("cannot {action} {}: {source}", path.display())]
pub struct IoError {
    /// The file (or folder) the operation was about.
    pub path: PathBuf,
    /// What was being done: "read", "create temporary file for", "rename into place", ...
    pub action: &'static str,
    /// The operating system's error.
    #[source]
    pub source: std::io::Error,
}

impl IoError {
    #[must_use]
    pub fn new(path: &Path, action: &'static str, source: std::io::Error) -> Self {
        Self { path: path.to_path_buf(), action, source }
    }
}

/// How many temp names to try before giving up (stale temp files of crashed runs, or another
/// process writing the same file at the same moment).
const TEMP_NAME_ATTEMPTS: u64 = 1000;

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

#[cfg(not(target_arch = "wasm32"))]
fn process_id() -> u32 {
    std::process::id()
}

/// `std::process::id` panics on wasm32-unknown-unknown; the counter alone keeps names unique there.
#[cfg(target_arch = "wasm32")]
fn process_id() -> u32 {
    0
}

/// Writes `bytes` to `path` atomically: they go to a temporary file in the same folder, which is
/// flushed to disk (`fsync`) and then renamed over `path`. Readers see either the old file or the
/// complete new one, never a partial write; on failure the temporary file is removed.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let Some(file_name) = path.file_name() else {
        return Err(IoError::new(path, "write", std::io::Error::new(ErrorKind::InvalidInput, "the path names no file")));
    };
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let (temp_path, mut file) = create_temp(folder, &file_name.to_string_lossy())?;
    let written = file
        .write_all(bytes)
        .map_err(|e| IoError::new(&temp_path, "write", e))
        .and_then(|()| file.sync_all().map_err(|e| IoError::new(&temp_path, "fsync", e)));
    drop(file);
    if let Err(e) = written {
        // Best effort: the write already failed, a failed clean-up adds nothing to report.
        let _ = fs::remove_file(&temp_path);
        return Err(e);
    }
    if let Err(e) = fs::rename(&temp_path, path) {
        let _ = fs::remove_file(&temp_path);
        return Err(IoError::new(path, "rename into place", e));
    }
    // Persist the rename itself. Not every file system can fsync a folder (and Windows cannot open
    // one as a file); the data is already safe, so this is best effort.
    if let Ok(dir) = File::open(folder) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Creates a fresh, uniquely named temporary file `.NAME.tmp-PID-N` in `folder`.
fn create_temp(folder: &Path, file_name: &str) -> Result<(PathBuf, File), IoError> {
    let pid = process_id();
    let mut last_error = None;
    for _ in 0..TEMP_NAME_ATTEMPTS {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let temp_path = folder.join(format!(".{file_name}.tmp-{pid}-{n}"));
        match OpenOptions::new().write(true).create_new(true).open(&temp_path) {
            Ok(file) => return Ok((temp_path, file)),
            Err(e) if e.kind() == ErrorKind::AlreadyExists => last_error = Some(e),
            Err(e) => return Err(IoError::new(&temp_path, "create temporary file", e)),
        }
    }
    let source = last_error.unwrap_or_else(|| std::io::Error::from(ErrorKind::AlreadyExists));
    Err(IoError::new(folder, "find a free temporary file name in", source))
}

/// Reads a whole file.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, IoError> {
    fs::read(path).map_err(|e| IoError::new(path, "read", e))
}

/// Reads a whole UTF-8 text file; `Ok(None)` when it does not exist.
pub fn read_optional_string(path: &Path) -> Result<Option<String>, IoError> {
    match fs::read_to_string(path) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(None),
        Err(e) => Err(IoError::new(path, "read", e)),
    }
}

#[cfg(test)]
// Tests: a failed unwrap is the failure report.
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_creates_and_replaces_without_leftovers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        atomic_write(&path, b"first").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"first");
        atomic_write(&path, b"second, longer").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second, longer");
        let names: Vec<_> = fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        assert_eq!(names, vec!["out.txt".to_owned()], "no temp files left behind");
    }

    #[test]
    fn atomic_write_into_missing_folder_names_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no_such_folder").join("out.txt");
        let err = atomic_write(&path, b"x").unwrap_err();
        assert!(err.to_string().contains("no_such_folder"), "{err}");
        assert!(!path.exists());
    }

    #[test]
    fn read_optional_string_missing_is_none() {
        let dir = tempfile::tempdir().unwrap();
        assert!(read_optional_string(&dir.path().join("absent.json")).unwrap().is_none());
        let err = read_bytes(&dir.path().join("absent.ply")).unwrap_err();
        assert!(err.to_string().contains("absent.ply"), "{err}");
    }
}
