//! Saved editing sessions: where the scan came from plus every pinned correction. Loading one
//! re-runs the pipeline on the same scan with the same pins, which gives back the same scene.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::io::atomic_write;
use crate::pipeline::PinnedEdits;

use super::EditError;

/// The `format` field of a session file.
pub const SESSION_FORMAT: &str = "partscene-session/1";

/// Where a document's scan comes from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SceneSource {
    /// The built-in demo room, scanned virtually (deterministic for a seed).
    Demo { seed: u64, clean: bool },
    /// A part-segmented scan on disk (PLY with its labels JSON beside it).
    Scan { path: PathBuf },
}

impl SceneSource {
    /// A short name for titles and the `source` field of exports.
    #[must_use]
    pub fn title(&self) -> String {
        match self {
            SceneSource::Demo { seed, clean } => format!("demo room (seed {seed}{})", if *clean { ", clean scan" } else { "" }),
            SceneSource::Scan { path } => path.display().to_string(),
        }
    }
}

/// A saved session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Session {
    pub format: String,
    pub source: SceneSource,
    #[serde(default)]
    pub pins: PinnedEdits,
}

impl Session {
    #[must_use]
    pub fn new(source: SceneSource, pins: PinnedEdits) -> Self {
        Self { format: SESSION_FORMAT.to_owned(), source, pins }
    }

    /// Writes the session atomically (a crash mid-write leaves the old file). A scan path
    /// relative to the working directory is written absolute, so the session (and the autosave,
    /// which lives elsewhere) finds the scan from anywhere.
    pub fn save(&self, path: &Path) -> Result<(), EditError> {
        let mut session = self.clone();
        if let SceneSource::Scan { path: scan } = &mut session.source
            && scan.is_relative()
            && let Ok(absolute) = std::path::absolute(&*scan)
        {
            *scan = absolute;
        }
        let text =
            serde_json::to_string_pretty(&session).map_err(|e| EditError::Session { path: path.to_owned(), message: e.to_string() })?;
        atomic_write(path, text.as_bytes()).map_err(|e| EditError::Io { path: path.to_owned(), message: e.to_string() })
    }

    /// Reads a session; a relative scan path is taken relative to the session file.
    pub fn load(path: &Path) -> Result<Self, EditError> {
        let text = std::fs::read_to_string(path).map_err(|e| EditError::Io { path: path.to_owned(), message: e.to_string() })?;
        Self::parse(&text, path)
    }

    /// Parses session text as if it were the file `path` (named in errors; a relative scan path is
    /// taken relative to its folder).
    pub fn parse(text: &str, path: &Path) -> Result<Self, EditError> {
        let mut session: Session = serde_json::from_str(text)
            .map_err(|e| EditError::Session { path: path.to_owned(), message: format!("line {}, column {}: {e}", e.line(), e.column()) })?;
        if session.format != SESSION_FORMAT {
            return Err(EditError::Session {
                path: path.to_owned(),
                message: format!("field `format`: expected \"{SESSION_FORMAT}\", found \"{}\"", session.format),
            });
        }
        if let SceneSource::Scan { path: scan } = &mut session.source
            && scan.is_relative()
            && let Some(dir) = path.parent()
        {
            *scan = dir.join(&*scan);
        }
        Ok(session)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::JointKind;

    #[test]
    fn a_session_round_trips_and_resolves_scan_paths_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        let mut pins = PinnedEdits::default();
        pins.parent.insert(7, 3);
        pins.joint_kind.insert(7, JointKind::Revolute);
        // Saving writes a scan path given relative to the working directory as absolute ...
        let session = Session::new(SceneSource::Scan { path: PathBuf::from("room.ply") }, pins.clone());
        let path = dir.path().join("s.json");
        session.save(&path).unwrap();
        let back = Session::load(&path).unwrap();
        assert_eq!(back.pins, pins);
        assert_eq!(back.source, SceneSource::Scan { path: std::env::current_dir().unwrap().join("room.ply") });
        // ... and a relative path written by hand is taken beside the session file.
        let text = std::fs::read_to_string(&path).unwrap();
        let cwd = std::env::current_dir().unwrap().join("room.ply").display().to_string();
        std::fs::write(&path, text.replace(&serde_json::to_string(&cwd).unwrap(), "\"room.ply\"")).unwrap();
        let back = Session::load(&path).unwrap();
        assert_eq!(back.source, SceneSource::Scan { path: dir.path().join("room.ply") });
    }

    #[test]
    fn a_bad_session_names_the_file_and_what_was_expected() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.json");
        std::fs::write(&path, r#"{"format": "other/9", "source": {"kind": "demo", "seed": 0, "clean": false}}"#).unwrap();
        let e = Session::load(&path).unwrap_err().to_string();
        assert!(e.contains("bad.json") && e.contains("partscene-session/1"), "{e}");
        std::fs::write(&path, "{\"format\": ").unwrap();
        let e = Session::load(&path).unwrap_err().to_string();
        assert!(e.contains("bad.json") && e.contains("line 1"), "{e}");
    }
}
