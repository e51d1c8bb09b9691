//! Warnings: problems reported and carried past (a part skipped, a label unknown), never fatal.

use serde::{Deserialize, Serialize};

/// Something the pipeline reported and carried on past.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// The stage that reported it: "scan", "fit", "contact", "kinematics", "scene", ...
    pub stage: String,
    /// What it is about, e.g. "part 17" or "object 3".
    pub subject: String,
    pub message: String,
}

impl Warning {
    #[must_use]
    pub fn new(stage: &str, subject: impl Into<String>, message: impl Into<String>) -> Self {
        Self { stage: stage.to_owned(), subject: subject.into(), message: message.into() }
    }
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{}] {}: {}", self.stage, self.subject, self.message)
    }
}
