//! Which scans a batch runs: `partscene batch INPUT...` where each input is a scan file, a folder
//! (its `.ply` and `.npz` scans, not recursive), a glob pattern (`scans/**/*.ply`, quoted so the
//! shell leaves it) or a manifest (`.txt`/`.list`: one scan path per line, relative to the
//! manifest; `#` comments and blank lines skipped).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::BatchError;
use crate::scan::is_npz_path;

/// One scan of a batch and the folder its outputs go to (a name unique within the batch).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BatchInput {
    pub scan: PathBuf,
    /// Sub-folder of the batch's output folder.
    pub name: String,
}

fn is_scan(path: &Path) -> bool {
    is_npz_path(path) || path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"))
}

fn is_manifest(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("txt") || e.eq_ignore_ascii_case("list"))
}

/// The scans named by `inputs`, sorted by path, each once, with output names: the file stem,
/// and the parent folders' names before it where two stems clash (`kitchen/scan`, `office/scan`
/// → `kitchen__scan`, `office__scan`).
pub fn resolve_inputs(inputs: &[PathBuf]) -> Result<Vec<BatchInput>, BatchError> {
    let mut scans = Vec::new();
    for input in inputs {
        collect(input, &mut scans)?;
    }
    scans.sort();
    scans.dedup();
    Ok(name_outputs(&scans))
}

fn collect(input: &Path, out: &mut Vec<PathBuf>) -> Result<(), BatchError> {
    let text = input.to_string_lossy();
    if input.is_dir() {
        let entries = std::fs::read_dir(input).map_err(|e| BatchError::Input { input: input.to_path_buf(), problem: e.to_string() })?;
        let before = out.len();
        for entry in entries {
            let path = entry.map_err(|e| BatchError::Input { input: input.to_path_buf(), problem: e.to_string() })?.path();
            if path.is_file() && is_scan(&path) {
                out.push(path);
            }
        }
        if out.len() == before {
            return Err(BatchError::Input { input: input.to_path_buf(), problem: "a folder with no .ply or .npz scan".to_owned() });
        }
    } else if input.is_file() && is_manifest(input) {
        let listing =
            std::fs::read_to_string(input).map_err(|e| BatchError::Input { input: input.to_path_buf(), problem: e.to_string() })?;
        let base = input.parent().unwrap_or(Path::new("."));
        for (number, line) in listing.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let path = base.join(line);
            if !path.is_file() {
                return Err(BatchError::Input {
                    input: input.to_path_buf(),
                    problem: format!(
                        "line {}: {} is not a file; expected one scan path per line, relative to the manifest",
                        number + 1,
                        path.display()
                    ),
                });
            }
            out.push(path);
        }
    } else if input.is_file() {
        if !is_scan(input) {
            return Err(BatchError::Input {
                input: input.to_path_buf(),
                problem: "expected a .ply or .npz scan, a folder, a glob or a .txt manifest".to_owned(),
            });
        }
        out.push(input.to_path_buf());
    } else if text.contains(['*', '?', '[']) {
        let paths =
            glob::glob(&text).map_err(|e| BatchError::Input { input: input.to_path_buf(), problem: format!("not a glob pattern: {e}") })?;
        let before = out.len();
        for path in paths.flatten() {
            if path.is_file() && is_scan(&path) {
                out.push(path);
            }
        }
        if out.len() == before {
            return Err(BatchError::Input { input: input.to_path_buf(), problem: "the pattern matches no .ply or .npz scan".to_owned() });
        }
    } else {
        return Err(BatchError::Input { input: input.to_path_buf(), problem: "no such file or folder".to_owned() });
    }
    Ok(())
}

/// Output names for sorted, distinct scan paths: the stem, prefixed by as many parent folder
/// names as it takes to make every name unique (then a numeric suffix, which paths that differ
/// only in case or extension need).
fn name_outputs(scans: &[PathBuf]) -> Vec<BatchInput> {
    let parts = |p: &Path, depth: usize| -> String {
        let stem = p.file_stem().map_or_else(|| "scan".to_owned(), |s| sanitize(&s.to_string_lossy()));
        let mut names = vec![stem];
        let mut at = p.parent();
        for _ in 0..depth {
            match at.and_then(|a| a.file_name().map(|n| (a, n))) {
                Some((a, n)) => {
                    names.push(sanitize(&n.to_string_lossy()));
                    at = a.parent();
                }
                None => break,
            }
        }
        names.reverse();
        names.join("__")
    };
    let mut depth = vec![0_usize; scans.len()];
    for _ in 0..8 {
        let mut count: BTreeMap<String, usize> = BTreeMap::new();
        for (i, s) in scans.iter().enumerate() {
            *count.entry(parts(s, depth[i])).or_default() += 1;
        }
        let mut changed = false;
        for (i, s) in scans.iter().enumerate() {
            if count[&parts(s, depth[i])] > 1 {
                depth[i] += 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    scans
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let base = parts(s, depth[i]);
            let k = seen.entry(base.clone()).or_default();
            *k += 1;
            let name = if *k == 1 { base } else { format!("{base}-{k}") };
            BatchInput { scan: s.clone(), name }
        })
        .collect()
}

/// A file-name-safe version of a name (letters, digits, `-`, `_`, `.`).
fn sanitize(s: &str) -> String {
    let out: String = s.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' }).collect();
    if out.is_empty() || out.starts_with('.') { format!("_{out}") } else { out }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(paths: &[&str], expected: &[&str]) {
        let scans: Vec<PathBuf> = paths.iter().map(PathBuf::from).collect();
        let names: Vec<String> = name_outputs(&scans).into_iter().map(|b| b.name).collect();
        assert_eq!(names, expected);
    }

    #[test]
    fn output_names_are_stems_made_unique_by_their_folders() {
        check(&["a/room1.ply", "a/room2.npz"], &["room1", "room2"]);
        check(&["kitchen/scan.ply", "office/scan.ply"], &["kitchen__scan", "office__scan"]);
        check(&["x/k/scan.ply", "y/k/scan.ply", "z/other.ply"], &["x__k__scan", "y__k__scan", "other"]);
        check(&["a/scan.ply", "a/scan.npz"], &["a__scan", "a__scan-2"]);
        check(&["a/my room.ply"], &["my_room"]);
    }
}
