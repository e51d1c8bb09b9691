//! The viewer-editor (egui/eframe on wgpu): see the scan, primitives, joints and contact graph;
//! correct the tree, joints and primitives; watch refinement re-run; articulate; export.
//! App state ([`state`]) is kept apart from the per-frame UI ([`panels`], [`view3d`]); the UI
//! sends [`AppCommand`]s that the state applies after the frame. Feature `gui`.

pub mod gap_panel;
pub mod panels;
pub mod platform;
pub mod review;
pub mod state;
pub mod view3d;

use std::path::PathBuf;
use std::sync::Arc;

use eframe::egui;

pub use panels::{PanelState, part_name};
pub use platform::Platform;
pub use state::{AppCommand, AppState, Autosave, Message};
pub use view3d::ViewCache;

use crate::edit::SceneSource;
use crate::pipeline::{PinnedEdits, PipelineConfig};

/// What the editor opens with.
#[derive(Clone, Debug)]
pub struct LaunchOptions {
    /// A scan or the demo; `None` with no session opens the demo room.
    pub source: Option<SceneSource>,
    /// A saved session (takes precedence over `source`).
    pub session: Option<PathBuf>,
    /// Where edits are autosaved for crash recovery (`None`: no autosave).
    pub autosave: Option<PathBuf>,
    pub config: PipelineConfig,
    /// The platform's seam (title, asynchronous file reads, downloads).
    pub platform: Arc<dyn Platform>,
}

impl Default for LaunchOptions {
    fn default() -> Self {
        Self {
            source: None,
            session: None,
            autosave: Autosave::default_path(),
            config: PipelineConfig::default(),
            platform: Arc::new(platform::Desktop),
        }
    }
}

/// The eframe application.
pub struct PartsceneApp {
    pub state: AppState,
    pub panels: PanelState,
    cache: ViewCache,
    has_gpu: bool,
    /// Files dropped into the browser, read asynchronously: (name, bytes).
    #[cfg(target_arch = "wasm32")]
    web_files: (std::sync::mpsc::Sender<(String, Vec<u8>)>, std::sync::mpsc::Receiver<(String, Vec<u8>)>),
    #[cfg(target_arch = "wasm32")]
    web_pending: std::collections::BTreeMap<String, Vec<u8>>,
    /// Files of the last drop still being read: the scan opens once all have arrived (a PLY must
    /// not open before the labels JSON dropped with it).
    #[cfg(target_arch = "wasm32")]
    web_awaited: usize,
}

impl PartsceneApp {
    /// Creates the app and starts opening what `launch` names in the background.
    #[must_use]
    pub fn new(cc: &eframe::CreationContext<'_>, launch: LaunchOptions) -> Self {
        let has_gpu = view3d::install_renderer(cc.wgpu_render_state.as_ref());
        // The 3D view, the graph and the joint colours are designed for a dark background.
        cc.egui_ctx.set_theme(egui::Theme::Dark);
        let mut state = AppState::new(launch.config.clone(), Autosave::at(launch.autosave.clone()));
        state.platform = launch.platform.clone();
        match (&launch.session, launch.source) {
            (Some(path), _) => state.apply(AppCommand::OpenSession(path.clone())),
            (None, Some(source)) => state.open(source, PinnedEdits::default()),
            (None, None) => state.open(SceneSource::Demo { seed: 0, clean: false }, PinnedEdits::default()),
        }
        Self {
            state,
            panels: PanelState::default(),
            cache: ViewCache::default(),
            has_gpu,
            #[cfg(target_arch = "wasm32")]
            web_files: std::sync::mpsc::channel(),
            #[cfg(target_arch = "wasm32")]
            web_pending: std::collections::BTreeMap::new(),
            #[cfg(target_arch = "wasm32")]
            web_awaited: 0,
        }
    }

    /// One frame of UI; the commands it produced are applied at its end.
    pub fn frame_ui(&mut self, ui: &mut egui::Ui) {
        if self.state.poll_job() | self.state.gap.poll() {
            ui.ctx().request_repaint();
        }
        if self.state.job.is_some() || self.state.gap.running() {
            ui.ctx().request_repaint_after(std::time::Duration::from_millis(50));
        }
        let mut commands = Vec::new();
        shortcuts(ui.ctx(), &mut commands);
        #[cfg(not(target_arch = "wasm32"))]
        dropped_files(ui.ctx(), &mut commands);
        #[cfg(target_arch = "wasm32")]
        self.web_dropped_files(ui.ctx(), &mut commands);
        self.state.last_hovered = self.state.hovered.take();
        let state = &mut self.state;
        let panels = &mut self.panels;
        egui::Panel::top("menu").show(ui, |ui| panels::menu_ui(ui, state, panels, &mut commands));
        egui::Panel::bottom("status").show(ui, |ui| panels::status_ui(ui, state, &mut commands));
        egui::Panel::left("scene tree").resizable(true).default_size(240.0).show(ui, |ui| {
            ui.heading("Scene");
            panels::tree_ui(ui, state, &mut commands);
        });
        egui::Panel::right("inspector").resizable(true).default_size(300.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                review::review_ui(ui, state, &mut commands);
                ui.separator();
                ui.heading("Inspector");
                panels::inspector_ui(ui, state, panels, &mut commands);
                ui.separator();
                panels::joints_ui(ui, state, &mut commands);
            });
        });
        egui::Panel::bottom("graph")
            .resizable(true)
            .default_size(200.0)
            .min_size(140.0)
            .show(ui, |ui| panels::graph_ui(ui, state, &mut commands));
        egui::CentralPanel::no_frame().show(ui, |ui| view3d::view3d_ui(ui, state, &mut self.cache, &mut commands, self.has_gpu));
        panels::windows_ui(ui.ctx(), state, panels, &mut commands);
        let mut open = state.gap.open;
        egui::Window::new("Reality gap").open(&mut open).default_size([720.0, 560.0]).show(ui.ctx(), |ui| {
            gap_panel::gap_ui(ui, &mut state.gap, &mut commands);
        });
        state.gap.open &= open;
        self.state.apply_all(commands);
    }
}

#[cfg(target_arch = "wasm32")]
impl PartsceneApp {
    /// Browsers give dropped files' bytes asynchronously: start the reads, and once a PLY is in,
    /// open it with the labels JSON dropped beside it.
    fn web_dropped_files(&mut self, ctx: &egui::Context, commands: &mut Vec<AppCommand>) {
        let title = self.state.doc.as_ref().map_or_else(|| "partscene".to_owned(), |d| format!("partscene — {}", d.source().title()));
        self.state.platform.set_title(&title);
        let dropped: Vec<_> = ctx.input(|i| i.raw.dropped_files.clone());
        if !dropped.is_empty() {
            self.web_awaited += dropped.len();
            self.state.platform.read_dropped(dropped, self.web_files.0.clone());
        }
        while let Ok((name, bytes)) = self.web_files.1.try_recv() {
            self.web_pending.insert(name, bytes);
            self.web_awaited = self.web_awaited.saturating_sub(1);
            ctx.request_repaint();
        }
        if self.web_awaited > 0 {
            return;
        }
        let ply = self.web_pending.keys().find(|n| n.to_ascii_lowercase().ends_with(".ply")).cloned();
        if let Some(name) = ply
            && let Some(bytes) = self.web_pending.remove(&name)
        {
            let stem = name.trim_end_matches(".ply").trim_end_matches(".PLY").to_owned();
            let labels_name = self.web_pending.keys().find(|n| n.starts_with(&stem) && n.ends_with(".json")).cloned();
            let labels = labels_name.and_then(|n| self.web_pending.remove(&n)).map(|b| String::from_utf8_lossy(&b).into_owned());
            commands.push(AppCommand::OpenScanBytes { name, ply: bytes, labels });
        }
    }
}

fn shortcuts(ctx: &egui::Context, commands: &mut Vec<AppCommand>) {
    use egui::{Key, KeyboardShortcut, Modifiers};
    // The review keys are plain letters: only while no text field has the keyboard.
    if !ctx.egui_wants_keyboard_input() {
        ctx.input_mut(|i| {
            if i.consume_key(Modifiers::NONE, Key::N) {
                commands.push(AppCommand::ReviewNext);
            }
            if i.consume_key(Modifiers::NONE, Key::A) {
                commands.push(AppCommand::ConfirmSelected);
            }
            if i.consume_key(Modifiers::NONE, Key::E) {
                commands.push(AppCommand::OtherEdgeSelected);
            }
        });
    }
    let redo = KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    let redo_y = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);
    let undo = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
    ctx.input_mut(|i| {
        // The shift variant first: consume_shortcut ignores extra modifiers.
        if i.consume_shortcut(&redo) || i.consume_shortcut(&redo_y) {
            commands.push(AppCommand::Redo);
        } else if i.consume_shortcut(&undo) {
            commands.push(AppCommand::Undo);
        }
    });
}

#[cfg(not(target_arch = "wasm32"))]
fn dropped_files(ctx: &egui::Context, commands: &mut Vec<AppCommand>) {
    let dropped: Vec<PathBuf> =
        ctx.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).filter(|p| !p.as_os_str().is_empty()).collect());
    for path in dropped {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        commands.push(match ext.as_str() {
            "json" => AppCommand::OpenSession(path),
            "csv" => AppCommand::AnalyseRecording(path),
            _ => AppCommand::Open(SceneSource::Scan { path }),
        });
    }
}

impl eframe::App for PartsceneApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.frame_ui(ui);
    }

    fn on_exit(&mut self) {
        self.state.on_exit();
    }
}

/// Opens the editor window.
#[cfg(not(target_arch = "wasm32"))]
pub fn run(launch: LaunchOptions) -> Result<(), eframe::Error> {
    let options = eframe::NativeOptions {
        renderer: eframe::Renderer::Wgpu,
        viewport: egui::ViewportBuilder::default().with_title("partscene").with_inner_size([1440.0, 900.0]).with_drag_and_drop(true),
        ..Default::default()
    };
    eframe::run_native("partscene", options, Box::new(|cc| Ok(Box::new(PartsceneApp::new(cc, launch)))))
}
