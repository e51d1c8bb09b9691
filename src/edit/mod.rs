//! The editing document behind the viewer-editor, with no GUI in it: a scan, its fitted parts,
//! the pinned corrections and the scene they give. Every [`EditCommand`] becomes a pin, then the
//! relational half of the pipeline (contact graph, tree, refinement, scene graph, joints) re-runs
//! on the cached fits — a few milliseconds — so the editor shows the corrected, refined scene in
//! the same frame. Undo/redo swap whole pin sets, so they are exact.

mod command;
mod session;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use command::{EditCommand, is_pinned, unpin};
pub use session::{SESSION_FORMAT, SceneSource, Session};

use crate::export::{ExportError, SceneFiles, UrdfConfig, write_scene_files};
use crate::kinematics::JointKind;
use crate::math::Vec3;
use crate::model::{PartModel, SceneModel};
use crate::pipeline::{FittedParts, FloorHint, PinnedEdits, PipelineConfig, Progress, assemble, fit_one_part, fit_parts};
use crate::primitive::PrimitiveKind;
use crate::refine::RefineStats;
use crate::report::Warning;
use crate::scan::{ObjectId, PartId, Scan, ScanError};

/// Why a document could not be opened, edited or saved.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    #[error("{}: {message}", path.display())]
    Io { path: PathBuf, message: String },
    #[error("{}: not a partscene session: {message}", path.display())]
    Session { path: PathBuf, message: String },
    #[error(transparent)]
    Scan(#[from] ScanError),
    #[error(transparent)]
    Export(#[from] ExportError),
    #[error("part {0} is not in the scene")]
    UnknownPart(PartId),
    #[error("part {0} is the root of its object and has no joint")]
    NoJoint(PartId),
    #[error("a part cannot be its own parent (part {0})")]
    SelfParent(PartId),
    #[error("parts {child} and {parent} belong to different objects")]
    DifferentObjects { child: PartId, parent: PartId },
    #[error("refused: part {parent} hangs below part {child}, so making it the parent would close a cycle")]
    Cycle { child: PartId, parent: PartId },
    #[error("{field}: {message}")]
    BadValue { field: &'static str, message: String },
    #[error("refused: {0}")]
    Refused(String),
}

/// One entry of the undo or redo history: the pins before the edit and what the edit was.
#[derive(Clone, Debug)]
struct HistoryEntry {
    pins: PinnedEdits,
    what: String,
}

/// The scene being edited.
#[derive(Clone)]
pub struct Document {
    source: SceneSource,
    scan: Arc<Scan>,
    config: PipelineConfig,
    categories: BTreeMap<ObjectId, String>,
    /// The pipeline's own fits (no kind pinned), cached: re-fitting is the expensive half.
    auto_fit: FittedParts,
    /// Fits of a pinned kind, cached per (part, kind).
    kind_fits: BTreeMap<(PartId, PrimitiveKind), Result<PartModel, Warning>>,
    pins: PinnedEdits,
    model: SceneModel,
    last_refine: RefineStats,
    /// The floor height estimated from the scan's background on the first run; edits do not move
    /// the floor, so re-runs reuse it.
    floor_z: Option<f32>,
    /// Warnings from reading the scan, kept in front of every re-run's.
    read_warnings: Vec<Warning>,
    undo: Vec<HistoryEntry>,
    redo: Vec<HistoryEntry>,
    /// Bumped on every change of the model (views cache on it).
    revision: u64,
}

impl Document {
    /// Loads the scan of `source`, fits every part and assembles the scene under `pins`.
    pub fn open(source: SceneSource, config: PipelineConfig, pins: PinnedEdits, progress: &dyn Progress) -> Result<Self, EditError> {
        let (scan, warnings) = match &source {
            SceneSource::Demo { seed, clean } => {
                let (_truth, scan) = if *clean { crate::synth::demo_clean(*seed) } else { crate::synth::demo(*seed) };
                (scan, Vec::new())
            }
            SceneSource::Scan { path } => crate::scan::read_scan(path)?,
        };
        Ok(Self::from_scan(source, Arc::new(scan), config, pins, progress).with_warnings(warnings))
    }

    /// Opens a saved session (its scan is read again and the pins re-applied).
    pub fn open_session(path: &Path, config: PipelineConfig, progress: &dyn Progress) -> Result<Self, EditError> {
        let session = Session::load(path)?;
        Self::open(session.source, config, session.pins, progress)
    }

    /// A document over a scan already in memory.
    #[must_use]
    pub fn from_scan(source: SceneSource, scan: Arc<Scan>, config: PipelineConfig, pins: PinnedEdits, progress: &dyn Progress) -> Self {
        let auto_fit = fit_parts(&scan, &config, &PinnedEdits::default(), progress);
        let categories = scan.objects.iter().map(|(id, o)| (*id, o.category.clone())).collect();
        let mut doc = Self {
            source,
            scan,
            config,
            categories,
            auto_fit,
            kind_fits: BTreeMap::new(),
            pins,
            model: SceneModel::default(),
            last_refine: RefineStats::default(),
            floor_z: None,
            read_warnings: Vec::new(),
            undo: Vec::new(),
            redo: Vec::new(),
            revision: 0,
        };
        doc.reassemble();
        doc
    }

    /// Adds warnings from reading the scan in front of the pipeline's.
    #[must_use]
    pub fn with_warnings(mut self, warnings: Vec<Warning>) -> Self {
        self.model.warnings.splice(0..0, warnings.iter().cloned());
        self.read_warnings = warnings;
        self
    }

    #[must_use]
    pub fn model(&self) -> &SceneModel {
        &self.model
    }

    #[must_use]
    pub fn scan(&self) -> &Scan {
        &self.scan
    }

    #[must_use]
    pub fn source(&self) -> &SceneSource {
        &self.source
    }

    #[must_use]
    pub fn pins(&self) -> &PinnedEdits {
        &self.pins
    }

    #[must_use]
    pub fn config(&self) -> &PipelineConfig {
        &self.config
    }

    /// What the last re-run of refinement changed.
    #[must_use]
    pub fn last_refine(&self) -> RefineStats {
        self.last_refine
    }

    #[must_use]
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// The session that gives back this document.
    #[must_use]
    pub fn session(&self) -> Session {
        Session::new(self.source.clone(), self.pins.clone())
    }

    /// What undo would take back, if anything.
    #[must_use]
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|h| h.what.as_str())
    }

    /// What redo would apply again, if anything.
    #[must_use]
    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|h| h.what.as_str())
    }

    /// Parts below `part` in the kinematic tree (not including it).
    #[must_use]
    pub fn descendants(&self, part: PartId) -> Vec<PartId> {
        let mut out = Vec::new();
        let mut stack = vec![part];
        while let Some(p) = stack.pop() {
            for j in self.model.joints.iter().filter(|j| j.parent == p) {
                if j.child != part && !out.contains(&j.child) {
                    out.push(j.child);
                    stack.push(j.child);
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// Applies a correction: checks it, pins it, and re-runs the relational stages.
    /// A refused edit changes nothing.
    pub fn apply(&mut self, cmd: EditCommand) -> Result<(), EditError> {
        if let EditCommand::SetPrimitiveKind { part, kind } = cmd
            && let Some(Err(w)) = self.kind_fit(part, kind)
        {
            return Err(EditError::Refused(format!("a {} does not fit part {part}: {}", kind.name(), w.message)));
        }
        let before = self.pins.clone();
        let mut pins = before.clone();
        self.pin(&mut pins, cmd)?;
        if pins == before {
            return Ok(());
        }
        self.pins = pins;
        self.reassemble();
        // The tree builder honours parent pins; check that it could, and take the edit back if not.
        if let EditCommand::SetParent { child, parent } = cmd
            && self.model.joint_of(child).is_none_or(|j| j.parent != parent)
        {
            self.pins = before;
            self.reassemble();
            return Err(EditError::Refused(format!("the kinematic tree cannot hang part {child} below part {parent}")));
        }
        self.undo.push(HistoryEntry { pins: before, what: cmd.describe() });
        self.redo.clear();
        Ok(())
    }

    /// Takes back the last edit. Returns what it was, or `None` when there is nothing to undo.
    pub fn undo(&mut self) -> Option<String> {
        let entry = self.undo.pop()?;
        let current = std::mem::replace(&mut self.pins, entry.pins);
        self.redo.push(HistoryEntry { pins: current, what: entry.what.clone() });
        self.reassemble();
        Some(entry.what)
    }

    /// Applies again the last edit taken back.
    pub fn redo(&mut self) -> Option<String> {
        let entry = self.redo.pop()?;
        let current = std::mem::replace(&mut self.pins, entry.pins);
        self.undo.push(HistoryEntry { pins: current, what: entry.what.clone() });
        self.reassemble();
        Some(entry.what)
    }

    /// Writes `scene.urdf`, `scene.json`, `scene.mjcf.xml` and `scene.glb` into `dir`; returns
    /// the paths of the first two (the rest lie beside them).
    pub fn export(&self, dir: &Path) -> Result<SceneFiles, EditError> {
        Ok(write_scene_files(dir, &self.model, &UrdfConfig::default())?)
    }

    /// Checks `cmd` against the current scene and writes it into `pins`.
    fn pin(&self, pins: &mut PinnedEdits, cmd: EditCommand) -> Result<(), EditError> {
        let part = cmd.part();
        let Some(child_model) = self.model.part(part) else { return Err(EditError::UnknownPart(part)) };
        let joint = self.model.joint_of(part).copied();
        let needs_joint = || joint.ok_or(EditError::NoJoint(part));
        match cmd {
            EditCommand::SetParent { child, parent } => {
                let Some(parent_model) = self.model.part(parent) else { return Err(EditError::UnknownPart(parent)) };
                if child == parent {
                    return Err(EditError::SelfParent(child));
                }
                if parent_model.object != child_model.object {
                    return Err(EditError::DifferentObjects { child, parent });
                }
                if self.descendants(child).contains(&parent) {
                    return Err(EditError::Cycle { child, parent });
                }
                pins.parent.insert(child, parent);
            }
            EditCommand::SetJointKind { child, kind } => {
                needs_joint()?;
                pins.joint_kind.insert(child, kind);
            }
            EditCommand::SetAxis { child, axis_world } => {
                needs_joint()?;
                if !axis_world.is_finite() || axis_world.length() < 1e-6 {
                    return Err(EditError::BadValue {
                        field: "axis",
                        message: format!("expected a non-zero direction, found {axis_world}"),
                    });
                }
                pins.axis.insert(child, axis_world.normalize());
            }
            EditCommand::FlipAxis { child } => {
                let j = needs_joint()?;
                pins.axis.insert(child, -j.axis_world);
                if j.kind != JointKind::Fixed {
                    pins.limits.insert(child, (-j.upper, -j.lower));
                }
            }
            EditCommand::OtherHingeEdge { child } => {
                needs_joint()?;
                let Some(edge) = self.hinge_edge_of(child) else {
                    return Err(EditError::Refused(format!("part {child} is not hinged like a door or lid: it has no other edge")));
                };
                pins.hinge_edge.insert(child, -edge);
                // Mirrored through the door's centre, the hinge opens outward about the reversed
                // axis: a pinned axis turns with it, so the pinned limits keep their meaning.
                if let Some(axis) = pins.axis.get_mut(&child) {
                    *axis = -*axis;
                }
            }
            EditCommand::SetLimits { child, lower, upper } => {
                needs_joint()?;
                if !lower.is_finite() || !upper.is_finite() || lower > upper {
                    return Err(EditError::BadValue {
                        field: "limits",
                        message: format!("expected lower <= upper, found [{lower}, {upper}]"),
                    });
                }
                pins.limits.insert(child, (lower, upper));
            }
            EditCommand::SetPrimitiveKind { part, kind } => {
                if child_model.primitive.kind == kind && !pins.primitive_kind.contains_key(&part) {
                    return Ok(());
                }
                pins.primitive_kind.insert(part, kind);
            }
            EditCommand::Unpin { part } => unpin(pins, part),
            EditCommand::Confirm { child } => {
                let j = needs_joint()?;
                pins.parent.insert(child, j.parent);
                pins.joint_kind.insert(child, j.kind);
                if let Some(edge) = self.hinge_edge_of(child) {
                    pins.hinge_edge.insert(child, edge);
                }
            }
        }
        Ok(())
    }

    /// Where the hinge of the door or lid `child` stands now: a world direction from the part's
    /// centre towards its edge, or `None` when its joint is not a movable door or lid hinge (then
    /// [`EditCommand::OtherHingeEdge`] is refused).
    #[must_use]
    pub fn hinge_edge_of(&self, child: PartId) -> Option<Vec3> {
        let joint = self.model.joint_of(child).filter(|j| j.kind.is_movable())?;
        let hinged = self.model.evidence.iter().any(|e| e.child == child && e.template.is_hinge());
        let centre = self.model.part(child)?.primitive.center();
        let r = joint.origin_world - centre;
        let across = r - joint.axis_world * r.dot(joint.axis_world);
        (hinged && across.length() > 1e-4).then(|| across.normalize())
    }

    /// The fit of `part` as a `kind` (cached), or `None` when the scan has no such part.
    fn kind_fit(&mut self, part: PartId, kind: PrimitiveKind) -> Option<&Result<PartModel, Warning>> {
        let scan_part = self.scan.part(part)?;
        Some(self.kind_fits.entry((part, kind)).or_insert_with(|| fit_one_part(scan_part, &self.config, Some(kind))))
    }

    /// The fitted parts under the current pins: cached automatic fits, with pinned kinds re-fitted
    /// (once per part and kind).
    fn fitted(&mut self) -> FittedParts {
        let mut fitted = self.auto_fit.clone();
        let pinned: Vec<(PartId, PrimitiveKind)> = self.pins.primitive_kind.iter().map(|(p, k)| (*p, *k)).collect();
        for (part, kind) in pinned {
            let Some(fit) = self.kind_fit(part, kind) else { continue };
            match fit {
                Ok(model) => {
                    if let Some(slot) = fitted.parts.iter_mut().find(|p| p.id == part) {
                        *slot = model.clone();
                    }
                }
                Err(w) => fitted.warnings.push(w.clone()),
            }
        }
        fitted
    }

    fn reassemble(&mut self) {
        let fitted = self.fitted();
        let floor = self.floor_z.map_or(FloorHint::Points(&self.scan.background), FloorHint::Height);
        let (mut model, stats) = assemble(&fitted, &self.categories, floor, &self.config, &self.pins);
        self.floor_z = Some(model.floor_z);
        model.source.clone_from(&self.scan.source);
        model.warnings.splice(0..0, self.read_warnings.iter().cloned());
        self.model = model;
        self.last_refine = stats;
        self.revision += 1;
    }
}

#[cfg(test)]
mod tests;
