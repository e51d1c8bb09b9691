//! The reality-gap panel: open a recording of the current scene moving, analyse it against the
//! scene's URDF in the background, and plot recording vs simulation vs fitted model and the
//! residual per joint (`egui_plot`).

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, TryRecvError};

use eframe::egui;
use egui::Color32;
use egui_plot::{HLine, Legend, Line, Plot, PlotPoints, Points};

use crate::export::{UrdfConfig, scene_urdf};
use crate::gap::{GapConfig, GapModel, GapReport, analyze, load_model, parse_model, read_recording};
use crate::model::SceneModel;

use super::state::AppCommand;

/// A finished analysis.
pub struct GapOutcome {
    pub recording: PathBuf,
    /// Which model was analysed: the current scene, or the URDF the recording names.
    pub model_source: String,
    pub report: GapReport,
}

/// Analyses in flight and their results.
#[derive(Default)]
pub struct GapState {
    pub open: bool,
    pub recording_text: String,
    job: Option<Receiver<Result<GapOutcome, String>>>,
    pub outcome: Option<GapOutcome>,
    pub error: Option<String>,
    /// Index of the joint shown in the plots.
    pub joint: usize,
}

impl GapState {
    #[must_use]
    pub fn running(&self) -> bool {
        self.job.is_some()
    }

    /// Starts analysing `recording` against `scene` (exported to URDF) on another thread. When the
    /// recording's columns name joints the scene does not have but its `# model:` line names a
    /// URDF, that model is used instead.
    pub fn start(&mut self, scene: Option<&SceneModel>, recording: PathBuf) {
        let urdf = match scene.map(|s| scene_urdf(s, &UrdfConfig::default())) {
            Some(Err(e)) => {
                self.error = Some(format!("cannot export the current scene to URDF: {e}"));
                return;
            }
            Some(Ok(text)) => Some(text),
            None => None,
        };
        let (tx, rx) = std::sync::mpsc::channel();
        let work = move || {
            let result = run_analysis(urdf, &recording);
            // The receiver is gone only when the app closed.
            let _ = tx.send(result);
        };
        #[cfg(not(target_arch = "wasm32"))]
        std::thread::spawn(work);
        #[cfg(target_arch = "wasm32")]
        work();
        self.job = Some(rx);
        self.error = None;
    }

    /// Takes a finished result. Returns whether anything changed.
    pub fn poll(&mut self) -> bool {
        let Some(rx) = &self.job else { return false };
        let result = match rx.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => return false,
            Err(TryRecvError::Disconnected) => Err("the analysis stopped unexpectedly".to_owned()),
        };
        self.job = None;
        match result {
            Ok(outcome) => {
                self.joint = 0;
                self.outcome = Some(outcome);
            }
            Err(e) => self.error = Some(e),
        }
        true
    }

    /// Waits for the analysis (tests).
    pub fn wait(&mut self) {
        while self.job.is_some() {
            if !self.poll() {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
        }
    }
}

fn run_analysis(scene_urdf: Option<String>, recording: &Path) -> Result<GapOutcome, String> {
    let rec = read_recording(recording).map_err(|e| e.to_string())?;
    let named_model = || -> Option<(GapModel, String)> {
        let path = rec.named_model_path()?;
        load_model(&path).ok().map(|m| (m, path.display().to_string()))
    };
    let scene_model = scene_urdf.and_then(|text| parse_model(&text, Path::new("current scene (scene.urdf)")).ok());
    let cfg = GapConfig::default();
    let first = match &scene_model {
        Some(m) => analyze(m, &rec, &cfg).map(|r| (r, "the current scene".to_owned())),
        None => Err(crate::gap::GapError::Analysis { file: recording.to_owned(), message: "no scene is open".into() }),
    };
    match first {
        Ok((report, model_source)) => Ok(GapOutcome { recording: recording.to_owned(), model_source, report }),
        Err(scene_err) => match named_model() {
            Some((model, source)) => analyze(&model, &rec, &cfg)
                .map(|report| GapOutcome { recording: recording.to_owned(), model_source: source, report })
                .map_err(|e| e.to_string()),
            None => Err(scene_err.to_string()),
        },
    }
}

/// Per joint: how it was analysed and what was considered and not reported, with the reason —
/// so a user can see that friction was weighed and refused, not forgotten.
fn considered_ui(ui: &mut egui::Ui, r: &crate::gap::GapReport) {
    for (joint, a) in &r.joints {
        let effort = a.effort_residual.map_or(String::new(), |e| {
            format!(", held-out residual effort {:.4} -> {:.4} of {:.4} RMS", e.rmse_before, e.rmse_after, a.effort_rms.unwrap_or(0.0))
        });
        egui::CollapsingHeader::new(format!("{joint}: {} space{effort}; {} terms considered and not reported", a.mode, a.rejected.len()))
            .id_salt(("gap considered", joint))
            .show(ui, |ui| {
                ui.weak(&a.why);
                for why in &a.rejected {
                    ui.label(format!("not reported — {why}"));
                }
            });
    }
}

/// The panel: choose a recording, then findings and plots.
pub fn gap_ui(ui: &mut egui::Ui, gap: &mut GapState, commands: &mut Vec<AppCommand>) {
    ui.horizontal(|ui| {
        let label = ui.label("Recording (CSV)");
        ui.text_edit_singleline(&mut gap.recording_text).labelled_by(label.id);
        #[cfg(not(target_arch = "wasm32"))]
        if ui.button("Browse…").clicked()
            && let Some(path) = rfd::FileDialog::new().add_filter("recording", &["csv"]).pick_file()
        {
            gap.recording_text = path.display().to_string();
        }
        if ui.add_enabled(!gap.running(), egui::Button::new("Analyse")).clicked() {
            commands.push(AppCommand::AnalyseRecording(PathBuf::from(gap.recording_text.trim())));
        }
        if gap.running() {
            ui.spinner();
        }
    });
    if let Some(e) = &gap.error {
        ui.colored_label(Color32::from_rgb(255, 110, 100), e);
    }
    let Some(outcome) = &gap.outcome else {
        ui.weak("Analyses a recording of the scene moving (spec: shared/spec/gap-recording.md) against the scene's URDF.");
        return;
    };
    let r = &outcome.report;
    ui.label(format!(
        "{} against {}: RMSE {:.4} -> {:.4} (all samples); held out from {:.2} s",
        outcome.recording.display(),
        outcome.model_source,
        r.fit.rmse_before,
        r.fit.rmse_after,
        r.held_out.t_start
    ));
    if r.effects.is_empty() && r.mismatches.is_empty() {
        ui.label("Simulation and recording agree within the measurement noise: nothing is missing.");
    }
    for m in &r.mismatches {
        ui.label(format!("mismatch on {} from {:.2} s to {:.2} s (RMSE {:.4}): {}", m.joint, m.t_start, m.t_end, m.rmse, m.description));
    }
    for e in &r.effects {
        let params: Vec<String> = e.params.iter().map(|(k, v)| format!("{k} = {v:.4}")).collect();
        ui.label(format!("found on {}: {} ({}), confidence {:.2}", e.joint, e.kind, params.join(", "), e.confidence))
            .on_hover_text(&e.description);
    }
    for (link, d) in &r.com_shift_m {
        ui.weak(format!(
            "{link}: centre of mass moved by ({:.1}, {:.1}, {:.1}) mm, the model's own accuracy (fitted beside the effects, not one)",
            1e3 * d[0],
            1e3 * d[1],
            1e3 * d[2]
        ))
        .on_hover_text("written into the fitted URDF's <inertial><origin>; a first-moment error within the few percent a model's weights are trusted to");
    }
    considered_ui(ui, r);
    if r.series.is_empty() {
        return;
    }
    gap.joint = gap.joint.min(r.series.len() - 1);
    egui::ComboBox::from_label("Joint").selected_text(&r.series[gap.joint].joint).show_ui(ui, |ui| {
        for (i, s) in r.series.iter().enumerate() {
            ui.selectable_value(&mut gap.joint, i, &s.joint);
        }
    });
    let s = &r.series[gap.joint];
    let pairs = |y: &[f64]| -> Vec<[f64; 2]> { s.time_s.iter().zip(y).filter(|(_, v)| v.is_finite()).map(|(t, v)| [*t, *v]).collect() };
    let height = (ui.available_height() * 0.5 - 10.0).max(80.0);
    Plot::new("gap trajectory").height(height).legend(Legend::default()).y_axis_label(format!("q ({})", s.unit)).show(ui, |p| {
        p.points(Points::new("recording", PlotPoints::from(pairs(&s.measured))).radius(1.2).color(Color32::LIGHT_GRAY));
        p.line(Line::new("model as written", PlotPoints::from(pairs(&s.simulated_before))).color(Color32::from_rgb(240, 90, 80)));
        p.line(Line::new("fitted model", PlotPoints::from(pairs(&s.simulated_after))).color(Color32::from_rgb(90, 200, 120)));
    });
    Plot::new("gap residual").height(height).legend(Legend::default()).x_axis_label("time (s)").show(ui, |p| {
        p.line(Line::new("residual before", PlotPoints::from(pairs(&s.residual_before))).color(Color32::from_rgb(240, 90, 80)));
        p.line(Line::new("residual after", PlotPoints::from(pairs(&s.residual_after))).color(Color32::from_rgb(90, 200, 120)));
        p.hline(HLine::new("+3σ noise", 3.0 * s.noise_sigma).color(Color32::GRAY));
        p.hline(HLine::new("-3σ noise", -3.0 * s.noise_sigma).color(Color32::GRAY));
    });
}
