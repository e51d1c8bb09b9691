//! The editor's state, apart from the per-frame UI: the open document, selection, joint positions,
//! view settings and the background job. The UI only reads it and pushes [`AppCommand`]s, which
//! [`AppState::apply`] carries out after the frame — one place where things change, so undo/redo
//! and tests drive the same path as a person does.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};

use crate::edit::{Document, EditCommand, EditError, SceneSource, Session};
use crate::kinematics::{JointKind, part_motions};
use crate::math::Pose;
use crate::pipeline::{PinnedEdits, PipelineConfig, Progress};
use crate::render::{DrawOptions, OrbitCamera, ViewPreset};
use crate::scan::PartId;

/// Something the UI asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum AppCommand {
    /// A correction of the scene (pinned, undoable).
    Edit(EditCommand),
    Undo,
    Redo,
    Select(Option<PartId>),
    /// Open a scan or the demo (in the background).
    Open(SceneSource),
    /// Open a scan given as bytes (files dropped into the browser): the PLY and its labels JSON.
    OpenScanBytes {
        name: String,
        ply: Vec<u8>,
        labels: Option<String>,
    },
    OpenSession(PathBuf),
    SaveSession(PathBuf),
    /// Write scene.urdf, scene.json, scene.mjcf.xml and scene.glb into a folder (downloads of
    /// scene.urdf and scene.json in the browser).
    Export(PathBuf),
    /// Analyse a recording of the scene moving (reality gap) in the background.
    AnalyseRecording(PathBuf),
    /// Move a joint (articulation preview; not an edit).
    SetJointPosition {
        child: PartId,
        q: f32,
    },
    ResetJointPositions,
    /// Open the session left by a crash.
    RecoverAutosave,
    DiscardAutosave,
    FrameAll,
    SetView(ViewPreset),
    /// Select the next joint of the review queue (least confident first).
    ReviewNext,
    /// Confirm the selected joint as it is (pins its parent and type) and select the next one.
    ConfirmSelected,
    /// Move the selected door's or lid's hinge to its other edge.
    OtherEdgeSelected,
}

/// A line for the status bar.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Message {
    pub text: String,
    pub is_error: bool,
}

/// Progress of the background job, shared with its thread.
#[derive(Default)]
pub struct JobProgress {
    done: AtomicUsize,
    total: AtomicUsize,
}

impl Progress for JobProgress {
    fn update(&self, _stage: &str, done: usize, total: usize) {
        self.done.store(done, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }
}

impl JobProgress {
    /// Fraction done, 0..1.
    #[must_use]
    pub fn fraction(&self) -> f32 {
        let total = self.total.load(Ordering::Relaxed);
        if total == 0 { 0.0 } else { self.done.load(Ordering::Relaxed) as f32 / total as f32 }
    }
}

/// The pipeline running on another thread while the UI stays live.
pub struct LoadJob {
    pub what: String,
    pub progress: Arc<JobProgress>,
    result: Receiver<Result<Document, EditError>>,
}

/// Where the autosave of a session goes and whether one was left by a crash.
#[derive(Clone, Debug)]
pub struct Autosave {
    pub path: Option<PathBuf>,
    /// A session found at start-up that was not closed cleanly.
    pub recoverable: Option<Session>,
}

impl Autosave {
    /// The default place: `$XDG_STATE_HOME/partscene/autosave.json` (or `~/.local/state/...`).
    #[must_use]
    pub fn default_path() -> Option<PathBuf> {
        let state = std::env::var_os("XDG_STATE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local").join("state")))?;
        Some(state.join("partscene").join("autosave.json"))
    }

    /// Looks for a session left at `path` by a session that did not close cleanly.
    #[must_use]
    pub fn at(path: Option<PathBuf>) -> Self {
        let recoverable = path.as_deref().filter(|p| p.exists()).and_then(|p| Session::load(p).ok());
        Self { path, recoverable }
    }
}

/// Everything the editor keeps between frames.
pub struct AppState {
    pub doc: Option<Document>,
    pub job: Option<LoadJob>,
    pub config: PipelineConfig,
    pub selected: Option<PartId>,
    /// Hovered in any view this frame (3D view, tree, graph).
    pub hovered: Option<PartId>,
    /// Hovered in the previous frame: what the views highlight (hover in one shows in all).
    pub last_hovered: Option<PartId>,
    /// Articulation preview: joint position by child part.
    pub joint_q: BTreeMap<PartId, f32>,
    pub options: DrawOptions,
    pub camera: OrbitCamera,
    /// Frame the scene at the next draw (after opening).
    pub needs_framing: bool,
    pub message: Option<Message>,
    pub autosave: Autosave,
    /// Text of the export and session path fields.
    pub export_dir: String,
    pub session_path: String,
    /// Bumped whenever what the 3D view draws changes.
    pub view_generation: u64,
    /// The reality-gap panel's analysis.
    pub gap: super::gap_panel::GapState,
    /// The platform's seam (downloads in the browser).
    pub platform: Arc<dyn super::Platform>,
}

impl AppState {
    #[must_use]
    pub fn new(config: PipelineConfig, autosave: Autosave) -> Self {
        Self {
            doc: None,
            job: None,
            config,
            selected: None,
            hovered: None,
            last_hovered: None,
            joint_q: BTreeMap::new(),
            options: DrawOptions::default(),
            camera: OrbitCamera::default(),
            needs_framing: true,
            message: None,
            autosave,
            export_dir: "out/export".to_owned(),
            session_path: "out/session.json".to_owned(),
            view_generation: 0,
            gap: super::gap_panel::GapState::default(),
            platform: Arc::new(super::platform::Desktop),
        }
    }

    fn info(&mut self, text: impl Into<String>) {
        self.message = Some(Message { text: text.into(), is_error: false });
    }

    fn error(&mut self, text: impl Into<String>) {
        self.message = Some(Message { text: text.into(), is_error: true });
    }

    /// Starts opening `source` (with `pins`) in the background.
    pub fn open(&mut self, source: SceneSource, pins: PinnedEdits) {
        let progress = Arc::new(JobProgress::default());
        let what = format!("opening {}", source.title());
        let (tx, rx) = std::sync::mpsc::channel();
        let config = self.config.clone();
        let job_progress = Arc::clone(&progress);
        let work = move || {
            let result = Document::open(source, config, pins, &*job_progress);
            // The receiver is gone only when the app closed; nothing to report then.
            let _ = tx.send(result);
        };
        #[cfg(not(target_arch = "wasm32"))]
        std::thread::spawn(work);
        #[cfg(target_arch = "wasm32")]
        work();
        self.job = Some(LoadJob { what, progress, result: rx });
    }

    /// Opens `source` and waits (tests, and the first frame of headless runs).
    pub fn open_blocking(&mut self, source: SceneSource, pins: PinnedEdits) {
        self.open(source, pins);
        while self.job.is_some() {
            if !self.poll_job() {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
        }
    }

    /// Takes the result of the background job when it is ready. Returns whether anything changed.
    pub fn poll_job(&mut self) -> bool {
        let Some(job) = &self.job else { return false };
        let result = match job.result.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => return false,
            Err(TryRecvError::Disconnected) => Err(EditError::Refused("the pipeline stopped unexpectedly".into())),
        };
        self.job = None;
        match result {
            Ok(doc) => {
                let parts = doc.model().parts.len();
                let joints = doc.model().joints.iter().filter(|j| j.kind.is_movable()).count();
                self.info(format!("opened {}: {parts} parts, {joints} movable joints", doc.source().title()));
                self.doc = Some(doc);
                self.selected = None;
                self.hovered = None;
                self.last_hovered = None;
                self.gap.outcome = None;
                self.joint_q.clear();
                self.needs_framing = true;
                self.touch();
                self.write_autosave();
            }
            Err(e) => self.error(e.to_string()),
        }
        true
    }

    /// Marks the view as changed.
    pub fn touch(&mut self) {
        self.view_generation += 1;
    }

    /// The motion of every moved part under the articulation preview.
    #[must_use]
    pub fn motions(&self) -> BTreeMap<PartId, Pose> {
        match &self.doc {
            Some(doc) if !self.joint_q.is_empty() => part_motions(&doc.model().joints, &self.joint_q),
            _ => BTreeMap::new(),
        }
    }

    /// Carries out the commands of one frame, in order.
    pub fn apply_all(&mut self, commands: Vec<AppCommand>) {
        for c in commands {
            self.apply(c);
        }
    }

    pub fn apply(&mut self, command: AppCommand) {
        match command {
            AppCommand::Edit(edit) => {
                let Some(doc) = &mut self.doc else { return };
                match doc.apply(edit) {
                    Ok(()) => {
                        // The edited joint's preview position may mean something else now (another
                        // type, flipped axis, new limits): it goes back to rest.
                        self.joint_q.remove(&edit.part());
                        let stats = doc.last_refine();
                        let text = format!(
                            "{} · refinement re-ran: {} parts rotated (max {:.1}°), {} moved (max {:.1} cm)",
                            edit.describe(),
                            stats.parts_rotated,
                            stats.max_rotation_deg,
                            stats.parts_moved,
                            stats.max_translation_m * 100.0
                        );
                        self.after_edit();
                        self.info(text);
                    }
                    Err(e) => self.error(e.to_string()),
                }
            }
            AppCommand::Undo => match self.doc.as_mut().and_then(Document::undo) {
                Some(what) => {
                    self.after_edit();
                    self.info(format!("undid: {what}"));
                }
                None => self.info("nothing to undo"),
            },
            AppCommand::Redo => match self.doc.as_mut().and_then(Document::redo) {
                Some(what) => {
                    self.after_edit();
                    self.info(format!("redid: {what}"));
                }
                None => self.info("nothing to redo"),
            },
            AppCommand::Select(part) => {
                self.selected = part;
                self.touch();
            }
            AppCommand::Open(source) => self.open(source, PinnedEdits::default()),
            AppCommand::OpenScanBytes { name, ply, labels } => {
                let labels_name = format!("{}.json", name.trim_end_matches(".ply"));
                match crate::scan::read_scan_bytes(&ply, &name, labels.as_deref(), &labels_name) {
                    Ok((scan, warnings)) => {
                        let source = SceneSource::Scan { path: PathBuf::from(&name) };
                        let progress = JobProgress::default();
                        let doc = Document::from_scan(source, Arc::new(scan), self.config.clone(), PinnedEdits::default(), &progress)
                            .with_warnings(warnings);
                        let (tx, rx) = std::sync::mpsc::channel();
                        // Hand it over through the job channel so opening ends the same way everywhere.
                        let _ = tx.send(Ok(doc));
                        self.job = Some(LoadJob { what: format!("opening {name}"), progress: Arc::new(progress), result: rx });
                        self.poll_job();
                    }
                    Err(e) => self.error(e.to_string()),
                }
            }
            AppCommand::OpenSession(path) => match Session::load(&path) {
                Ok(session) => self.open(session.source, session.pins),
                Err(e) => self.error(e.to_string()),
            },
            AppCommand::SaveSession(path) => self.save_session(&path),
            #[cfg(target_arch = "wasm32")]
            AppCommand::Export(_) => {
                // In the browser the files are downloads.
                let Some(doc) = &self.doc else { return self.error("nothing to export: no scene is open") };
                let urdf = crate::export::scene_urdf(doc.model(), &crate::export::UrdfConfig::default());
                let result = urdf.map_err(|e| e.to_string()).and_then(|urdf| {
                    self.platform.download("scene.urdf", urdf.as_bytes())?;
                    self.platform.download("scene.json", crate::export::scene_json(doc.model()).as_bytes())
                });
                match result {
                    Ok(()) => self.info("downloaded scene.urdf and scene.json"),
                    Err(e) => self.error(format!("download failed: {e}")),
                }
            }
            #[cfg(not(target_arch = "wasm32"))]
            AppCommand::Export(dir) => {
                let Some(doc) = &self.doc else { return self.error("nothing to export: no scene is open") };
                match doc.export(&dir) {
                    Ok(files) => self.info(format!(
                        "exported {}, {}, {} and {}",
                        files.urdf.display(),
                        files.json.display(),
                        files.mjcf.display(),
                        files.glb.display()
                    )),
                    Err(e) => self.error(e.to_string()),
                }
            }
            AppCommand::AnalyseRecording(path) => {
                self.gap.open = true;
                self.gap.recording_text = path.display().to_string();
                self.gap.start(self.doc.as_ref().map(Document::model), path);
            }
            AppCommand::SetJointPosition { child, q } => {
                let Some(j) = self.doc.as_ref().and_then(|d| d.model().joint_of(child).copied()) else { return };
                if j.kind != JointKind::Fixed {
                    self.joint_q.insert(child, q.clamp(j.lower.min(j.upper), j.upper.max(j.lower)));
                    self.touch();
                }
            }
            AppCommand::ResetJointPositions => {
                self.joint_q.clear();
                self.touch();
            }
            AppCommand::RecoverAutosave => {
                if let Some(session) = self.autosave.recoverable.take() {
                    self.open(session.source, session.pins);
                }
            }
            AppCommand::DiscardAutosave => {
                self.autosave.recoverable = None;
                self.remove_autosave();
            }
            AppCommand::FrameAll => self.needs_framing = true,
            AppCommand::SetView(preset) => {
                let framed = OrbitCamera::framing(glam::Vec3::ZERO, glam::Vec3::ONE, preset);
                self.camera.yaw_rad = framed.yaw_rad;
                self.camera.pitch_rad = framed.pitch_rad;
                self.needs_framing = true;
            }
            AppCommand::ReviewNext | AppCommand::ConfirmSelected | AppCommand::OtherEdgeSelected => super::review::apply(self, &command),
        }
    }

    fn after_edit(&mut self) {
        // Joint positions of joints that are gone or no longer movable are dropped, the others
        // kept within their (possibly new) limits.
        if let Some(doc) = &self.doc {
            let model = doc.model();
            self.joint_q.retain(|child, q| match model.joint_of(*child) {
                Some(j) if j.kind.is_movable() => {
                    *q = q.clamp(j.lower.min(j.upper), j.upper.max(j.lower));
                    true
                }
                _ => false,
            });
        }
        self.touch();
        self.write_autosave();
    }

    fn save_session(&mut self, path: &Path) {
        let Some(doc) = &self.doc else { return self.error("nothing to save: no scene is open") };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
            && let Err(e) = std::fs::create_dir_all(dir)
        {
            return self.error(format!("cannot create {}: {e}", dir.display()));
        }
        match doc.session().save(path) {
            Ok(()) => self.info(format!("saved session {}", path.display())),
            Err(e) => self.error(e.to_string()),
        }
    }

    /// Saves the session to the autosave file after every edit (pins are small), or removes it
    /// when nothing is pinned. A clean exit removes it ([`Self::on_exit`]).
    fn write_autosave(&mut self) {
        // A crash's autosave stays untouched until the user recovers or discards it.
        if self.autosave.recoverable.is_some() {
            return;
        }
        let (Some(path), Some(doc)) = (self.autosave.path.clone(), &self.doc) else { return };
        if *doc.pins() == PinnedEdits::default() {
            self.remove_autosave();
            return;
        }
        let result = path.parent().map_or(Ok(()), std::fs::create_dir_all).map_err(|e| e.to_string());
        if let Err(e) = result.and_then(|()| doc.session().save(&path).map_err(|e| e.to_string())) {
            self.error(format!("autosave failed: {e}"));
        }
    }

    fn remove_autosave(&self) {
        if let Some(path) = &self.autosave.path {
            // Absent already is fine.
            let _ = std::fs::remove_file(path);
        }
    }

    /// A clean exit: nothing to recover next time (unless a crash's autosave is still unanswered).
    pub fn on_exit(&self) {
        if self.autosave.recoverable.is_none() {
            self.remove_autosave();
        }
    }
}
