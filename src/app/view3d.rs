//! The 3D view: camera input, picking, and a paint callback that draws the scene with our wgpu
//! renderer inside egui's frame.

use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu;
use glam::Vec2;

use super::state::{AppCommand, AppState};
use crate::render::{DrawData, DrawOptions, FrameParams, PointInstance, SceneRenderer, SceneView, pick_part, scene_geometry, scene_points};

/// Draw data of the last frame, rebuilt only when what it shows changes. The scan points (up
/// to 400k) are kept apart: hovering changes the highlight, not the points.
#[derive(Default)]
pub struct ViewCache {
    key: Option<(u64, Option<i64>, Option<i64>, DrawOptions)>,
    data: Arc<DrawData>,
    generation: u64,
    points_key: Option<(u64, Option<i64>, DrawOptions)>,
    points: Arc<Vec<PointInstance>>,
    points_generation: u64,
}

impl ViewCache {
    /// The draw data for the current state (rebuilt if stale): everything but the points, and
    /// the points. `data().bounds` frames the scene.
    pub fn data(&mut self, state: &AppState) -> (Arc<DrawData>, Arc<Vec<PointInstance>>) {
        let highlighted = state.hovered.or(state.last_hovered);
        let key = (state.view_generation, state.selected, highlighted, state.options);
        let points_key = (state.view_generation, state.selected, state.options);
        let stale = self.key.as_ref() != Some(&key);
        let points_stale = self.points_key.as_ref() != Some(&points_key);
        if !(stale || points_stale) {
            return (Arc::clone(&self.data), Arc::clone(&self.points));
        }
        let motions = state.motions();
        let view = state.doc.as_ref().map(|doc| SceneView {
            model: doc.model(),
            scan: Some(doc.scan()),
            motions: &motions,
            selected: state.selected,
            hovered: highlighted,
        });
        if stale {
            self.data = Arc::new(view.as_ref().map(|v| scene_geometry(v, &state.options)).unwrap_or_default());
            self.generation += 1;
            self.key = Some(key);
        }
        if points_stale {
            self.points = Arc::new(view.as_ref().map(|v| scene_points(v, &state.options)).unwrap_or_default());
            self.points_generation += 1;
            self.points_key = Some(points_key);
        }
        (Arc::clone(&self.data), Arc::clone(&self.points))
    }
}

struct SceneCallback {
    data: Arc<DrawData>,
    generation: u64,
    points: Arc<Vec<PointInstance>>,
    points_generation: u64,
    frame: FrameParams,
}

impl egui_wgpu::CallbackTrait for SceneCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(renderer) = resources.get_mut::<SceneRenderer>() {
            renderer.upload_geometry(device, queue, &self.data, self.generation);
            renderer.upload_points(device, queue, &self.points, self.points_generation);
            renderer.render(device, queue, encoder, &self.frame);
        }
        Vec::new()
    }

    fn paint(&self, _info: egui::PaintCallbackInfo, pass: &mut wgpu::RenderPass<'static>, resources: &egui_wgpu::CallbackResources) {
        if let Some(renderer) = resources.get::<SceneRenderer>() {
            renderer.blit(pass);
        }
    }
}

/// Installs the renderer where the paint callback finds it. Returns false without wgpu.
#[must_use]
pub fn install_renderer(render_state: Option<&egui_wgpu::RenderState>) -> bool {
    let Some(rs) = render_state else { return false };
    let renderer = SceneRenderer::new(&rs.device, Some(rs.target_format));
    rs.renderer.write().callback_resources.insert(renderer);
    true
}

/// The 3D view. Drag: orbit; right or middle drag (or shift-drag): pan; scroll: zoom;
/// click: select; double-click: frame all.
pub fn view3d_ui(ui: &mut egui::Ui, state: &mut AppState, cache: &mut ViewCache, commands: &mut Vec<AppCommand>, has_gpu: bool) {
    let (rect, response) = ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
    let aspect = rect.width() / rect.height().max(1.0);
    let height = rect.height().max(1.0);
    // Camera input.
    let delta = response.drag_delta();
    let shift = ui.input(|i| i.modifiers.shift);
    if response.dragged_by(egui::PointerButton::Primary) && !shift {
        state.camera.orbit(Vec2::new(delta.x, delta.y) / height);
    } else if response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
        || (response.dragged_by(egui::PointerButton::Primary) && shift)
    {
        state.camera.pan(Vec2::new(delta.x, delta.y) / height);
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            state.camera.zoom((scroll * 0.002).exp());
        }
    }
    if response.double_clicked() {
        commands.push(AppCommand::FrameAll);
    }
    // Picking under the pointer.
    let hit = response.hover_pos().and_then(|pos| {
        let doc = state.doc.as_ref()?;
        let ndc = Vec2::new((pos.x - rect.left()) / rect.width() * 2.0 - 1.0, 1.0 - (pos.y - rect.top()) / rect.height() * 2.0);
        let (origin, dir) = state.camera.ray(ndc, aspect);
        pick_part(doc.model(), &state.motions(), origin, dir).map(|h| h.0)
    });
    if response.hovered() {
        state.hovered = hit;
    }
    if response.clicked() {
        commands.push(AppCommand::Select(hit));
    }
    let (data, points) = cache.data(state);
    if state.needs_framing
        && let Some((lo, hi)) = data.bounds
    {
        state.camera.frame(lo, hi);
        state.needs_framing = false;
    }
    if has_gpu {
        let ppp = ui.ctx().pixels_per_point();
        let size_px = [(rect.width() * ppp).round().max(1.0) as u32, (rect.height() * ppp).round().max(1.0) as u32];
        let frame = FrameParams {
            clip_from_world: state.camera.clip_from_world(aspect),
            eye_world: state.camera.eye_world(),
            size_px,
            point_size_px: 1.6 * ppp,
        };
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(
            rect,
            SceneCallback { data, generation: cache.generation, points, points_generation: cache.points_generation, frame },
        ));
    } else {
        ui.painter().rect_filled(rect, 0.0, egui::Color32::from_gray(30));
        ui.painter().text(
            rect.center(),
            egui::Align2::CENTER_CENTER,
            "3D view needs the wgpu renderer",
            egui::FontId::proportional(16.0),
            egui::Color32::LIGHT_GRAY,
        );
    }
    ui.painter().text(
        rect.left_bottom() + egui::vec2(8.0, -6.0),
        egui::Align2::LEFT_BOTTOM,
        "drag: orbit · right-drag: pan · scroll: zoom · click: select · double-click: frame all",
        egui::FontId::proportional(11.0),
        egui::Color32::from_gray(140),
    );
    // Name of the part under the pointer.
    if let (Some(id), Some(pos), Some(doc)) = (hit, response.hover_pos(), state.doc.as_ref())
        && let Some(part) = doc.model().part(id)
    {
        let text = format!("{} {} · {} · fit {:.1} mm", part.label, part.id, part.primitive.kind.name(), part.fit_error * 1000.0);
        ui.painter().text(
            pos + egui::vec2(14.0, 14.0),
            egui::Align2::LEFT_TOP,
            text,
            egui::FontId::proportional(13.0),
            egui::Color32::WHITE,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::state::Autosave;
    use crate::edit::SceneSource;
    use crate::pipeline::{PinnedEdits, PipelineConfig};

    #[test]
    fn hovering_rebuilds_the_highlight_but_not_the_scan_points() {
        let mut state = AppState::new(PipelineConfig::default(), Autosave::at(None));
        state.open_blocking(SceneSource::Demo { seed: 0, clean: false }, PinnedEdits::default());
        let mut cache = ViewCache::default();
        let (data, points) = cache.data(&state);
        assert!(!points.is_empty() && !data.opaque.is_empty());
        let part = state.doc.as_ref().unwrap().model().parts[3].id;
        state.hovered = Some(part);
        let (hovered, same_points) = cache.data(&state);
        assert!(!Arc::ptr_eq(&data, &hovered), "the highlight is redrawn");
        assert!(Arc::ptr_eq(&points, &same_points), "the points are kept");
        // Selecting highlights the part's points too: they are rebuilt.
        state.selected = Some(part);
        let (_, selected_points) = cache.data(&state);
        assert!(!Arc::ptr_eq(&points, &selected_points));
        // Nothing changed: nothing rebuilt.
        let (again, again_points) = cache.data(&state);
        assert!(Arc::ptr_eq(&again_points, &selected_points) && Arc::ptr_eq(&again, &cache.data(&state).0));
    }
}
