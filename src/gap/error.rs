//! Errors of the reality-gap analysis: every one names the file and, for recordings, the line,
//! column and field, and what was expected.

use std::path::PathBuf;

use thiserror::Error;

/// Why a model or recording could not be read or analysed.
#[derive(Debug, Error)]
pub enum GapError {
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// A recording cell, header or metadata line is malformed (line and column are 1-based).
    #[error("{}:{line}:{column}: {field}: expected {expected}, found {found:?}", file.display())]
    Csv {
        /// The recording.
        file: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based column (cell) number; 1 for whole-line problems.
        column: usize,
        /// The column header or metadata key concerned.
        field: String,
        /// What the reader expected.
        expected: String,
        /// What it found.
        found: String,
    },
    /// An MCAP recording cannot be read.
    #[error(
        "{}{}{}: {message}",
        file.display(),
        if topic.is_empty() { String::new() } else { format!(": topic {topic}") },
        index.map_or(String::new(), |i| format!(", message {i}"))
    )]
    Mcap {
        /// The recording.
        file: PathBuf,
        /// The topic concerned (empty when none was chosen yet).
        topic: String,
        /// 0-based among the topic's messages in log-time order, when one message is at fault.
        index: Option<usize>,
        message: String,
    },
    /// The URDF could not be parsed.
    #[error("{}: not a readable URDF: {message}", file.display())]
    Urdf {
        /// The model file.
        file: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// The URDF parses but its structure cannot be simulated.
    #[error("{}: {field}: {message}", file.display())]
    Model {
        /// The model file.
        file: PathBuf,
        /// The link, joint or attribute concerned.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The recording is well formed but cannot be analysed (too few samples, nothing observed).
    #[error("{}: {message}", file.display())]
    Analysis {
        /// The recording.
        file: PathBuf,
        /// What is missing.
        message: String,
    },
}
