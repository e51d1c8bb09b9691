//! The editor's panels: menu, scene tree, inspector, joint sliders, contact graph, status line.
//! Each reads [`AppState`] and pushes [`AppCommand`]s; hover is shared through `state.hovered`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};

use super::state::{AppCommand, AppState};
use crate::edit::{EditCommand, SceneSource, is_pinned};
use crate::kinematics::JointKind;
use crate::model::SceneModel;
use crate::primitive::PrimitiveKind;
use crate::render::{PointColors, ViewPreset, part_color};
use crate::scan::{ObjectId, PartId};

/// A part being dragged onto a new parent (tree or graph).
#[derive(Clone, Copy, Debug)]
struct DraggedPart(PartId);

/// UI-only state of the panels (text being typed, open windows).
#[derive(Default)]
pub struct PanelState {
    pub show_export: bool,
    pub show_session: bool,
    /// Axis being edited: (part, document revision, value) — committed when the drag or typing
    /// ends; dropped when the scene changed meanwhile (undo, flip, another scene).
    axis_edit: Option<(PartId, u64, [f32; 3])>,
    limits_edit: Option<(PartId, u64, [f32; 2])>,
}

/// The name shown for a part everywhere (tree, inspector, graph): label and id.
#[must_use]
pub fn part_name(model: &SceneModel, id: PartId) -> String {
    model.part(id).map_or_else(|| format!("part {id}"), |p| format!("{} {}", p.label, p.id))
}

fn color32(rgb: [f32; 3]) -> Color32 {
    Color32::from_rgb((rgb[0] * 255.0) as u8, (rgb[1] * 255.0) as u8, (rgb[2] * 255.0) as u8)
}

fn kind_color(kind: JointKind) -> Color32 {
    color32(crate::model::joint_kind_color(kind))
}

fn children_map(model: &SceneModel) -> BTreeMap<PartId, Vec<PartId>> {
    let mut map: BTreeMap<PartId, Vec<PartId>> = BTreeMap::new();
    for j in &model.joints {
        map.entry(j.parent).or_default().push(j.child);
    }
    for v in map.values_mut() {
        v.sort_unstable();
    }
    map
}

/// File, Edit and View menus, plus undo/redo/export buttons.
pub fn menu_ui(ui: &mut egui::Ui, state: &mut AppState, panels: &mut PanelState, commands: &mut Vec<AppCommand>) {
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| {
            if ui.button("Open scan…").clicked() {
                if let Some(path) = pick_file("Part-segmented scan", &["ply", "npz"]) {
                    commands.push(AppCommand::Open(SceneSource::Scan { path }));
                }
                ui.close();
            }
            if ui.button("Open session…").clicked() {
                if let Some(path) = pick_file("partscene session", &["json"]) {
                    commands.push(AppCommand::OpenSession(path));
                }
                ui.close();
            }
            if ui.button("Open demo room").clicked() {
                commands.push(AppCommand::Open(SceneSource::Demo { seed: 0, clean: false }));
                ui.close();
            }
            ui.separator();
            if ui.button("Save session…").clicked() {
                panels.show_session = true;
                ui.close();
            }
            if ui.button("Export URDF, MJCF, glTF, scene.json…").clicked() {
                panels.show_export = true;
                ui.close();
            }
            ui.separator();
            if ui.button("Reality gap: analyse a recording…").clicked() {
                state.gap.open = true;
                ui.close();
            }
        });
        ui.menu_button("Edit", |ui| {
            let undo = state.doc.as_ref().and_then(|d| d.undo_label().map(str::to_owned));
            let redo = state.doc.as_ref().and_then(|d| d.redo_label().map(str::to_owned));
            if ui
                .add_enabled(undo.is_some(), egui::Button::new("Undo edit").shortcut_text("Ctrl+Z"))
                .on_hover_text(undo.unwrap_or_default())
                .clicked()
            {
                commands.push(AppCommand::Undo);
                ui.close();
            }
            if ui
                .add_enabled(redo.is_some(), egui::Button::new("Redo edit").shortcut_text("Ctrl+Shift+Z"))
                .on_hover_text(redo.unwrap_or_default())
                .clicked()
            {
                commands.push(AppCommand::Redo);
                ui.close();
            }
        });
        ui.menu_button("View", |ui| {
            let o = &mut state.options;
            let before = *o;
            ui.checkbox(&mut o.show_points, "Scan points");
            ui.checkbox(&mut o.show_primitives, "Primitives");
            ui.checkbox(&mut o.show_joints, "Joint axes and limits");
            ui.checkbox(&mut o.show_contacts, "Contact edges in 3D");
            ui.checkbox(&mut o.show_floor, "Floor grid");
            ui.separator();
            ui.radio_value(&mut o.point_colors, PointColors::ByPart, "Colour points by part");
            ui.radio_value(&mut o.point_colors, PointColors::ByFitError, "Colour points by fit error (0–3 cm)");
            ui.add(egui::Slider::new(&mut o.primitive_alpha, 0.1..=1.0).text("Primitive opacity"));
            if *o != before {
                state.touch();
            }
            ui.separator();
            for preset in ViewPreset::ALL {
                if ui.button(format!("View from {}", preset.name())).clicked() {
                    commands.push(AppCommand::SetView(preset));
                }
            }
            if ui.button("Frame all").clicked() {
                commands.push(AppCommand::FrameAll);
            }
        });
        ui.separator();
        let can_undo = state.doc.as_ref().is_some_and(|d| d.undo_label().is_some());
        let can_redo = state.doc.as_ref().is_some_and(|d| d.redo_label().is_some());
        if ui.add_enabled(can_undo, egui::Button::new("Undo")).clicked() {
            commands.push(AppCommand::Undo);
        }
        if ui.add_enabled(can_redo, egui::Button::new("Redo")).clicked() {
            commands.push(AppCommand::Redo);
        }
        if ui.button("Export…").clicked() {
            panels.show_export = true;
        }
        if let Some(doc) = &state.doc {
            ui.separator();
            ui.label(doc.source().title());
        }
    });
}

#[cfg(not(target_arch = "wasm32"))]
fn pick_file(what: &str, extensions: &[&str]) -> Option<PathBuf> {
    rfd::FileDialog::new().add_filter(what, extensions).pick_file()
}

#[cfg(target_arch = "wasm32")]
fn pick_file(_what: &str, _extensions: &[&str]) -> Option<PathBuf> {
    None
}

#[cfg(not(target_arch = "wasm32"))]
fn pick_folder() -> Option<PathBuf> {
    rfd::FileDialog::new().pick_folder()
}

#[cfg(target_arch = "wasm32")]
fn pick_folder() -> Option<PathBuf> {
    None
}

/// The export and save-session windows.
pub fn windows_ui(ctx: &egui::Context, state: &mut AppState, panels: &mut PanelState, commands: &mut Vec<AppCommand>) {
    let mut open = panels.show_export;
    egui::Window::new("Export").open(&mut open).collapsible(false).resizable(false).show(ctx, |ui| {
        ui.label("Writes scene.urdf, scene.json, scene.mjcf.xml and scene.glb into the folder (atomically).");
        ui.horizontal(|ui| {
            let label = ui.label("Export folder");
            ui.text_edit_singleline(&mut state.export_dir).labelled_by(label.id);
            if ui.button("Browse…").clicked()
                && let Some(dir) = pick_folder()
            {
                state.export_dir = dir.display().to_string();
            }
        });
        if ui.add_enabled(state.doc.is_some(), egui::Button::new("Export now")).clicked() {
            commands.push(AppCommand::Export(PathBuf::from(state.export_dir.trim())));
            panels.show_export = false;
        }
    });
    panels.show_export &= open;
    let mut open = panels.show_session;
    egui::Window::new("Save session").open(&mut open).collapsible(false).resizable(false).show(ctx, |ui| {
        ui.label("A session keeps the scan's origin and every pinned correction.");
        ui.horizontal(|ui| {
            let label = ui.label("Session file");
            ui.text_edit_singleline(&mut state.session_path).labelled_by(label.id);
        });
        if ui.add_enabled(state.doc.is_some(), egui::Button::new("Save now")).clicked() {
            commands.push(AppCommand::SaveSession(PathBuf::from(state.session_path.trim())));
            panels.show_session = false;
        }
    });
    panels.show_session &= open;
}

/// Recovery banner, status message and job progress.
pub fn status_ui(ui: &mut egui::Ui, state: &AppState, commands: &mut Vec<AppCommand>) {
    if let Some(session) = &state.autosave.recoverable {
        ui.horizontal(|ui| {
            ui.colored_label(
                Color32::from_rgb(240, 190, 60),
                format!("Unsaved edits from a session that did not close cleanly ({}).", session.source.title()),
            );
            if ui.button("Recover").clicked() {
                commands.push(AppCommand::RecoverAutosave);
            }
            if ui.button("Discard").clicked() {
                commands.push(AppCommand::DiscardAutosave);
            }
        });
    }
    ui.horizontal(|ui| {
        if let Some(job) = &state.job {
            ui.spinner();
            ui.add(egui::ProgressBar::new(job.progress.fraction()).desired_width(160.0).show_percentage());
            ui.label(&job.what);
        }
        if let Some(m) = &state.message {
            let color = if m.is_error { Color32::from_rgb(255, 110, 100) } else { ui.visuals().text_color() };
            ui.colored_label(color, &m.text);
        }
    });
}

/// The kinematic forest as a tree: drag a part onto another to make it the parent.
pub fn tree_ui(ui: &mut egui::Ui, state: &mut AppState, commands: &mut Vec<AppCommand>) {
    let Some(doc) = &state.doc else {
        ui.label("No scene open.");
        return;
    };
    let model = doc.model();
    let children = children_map(model);
    let mut hovered = None;
    egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
        for object in &model.objects {
            let header = format!("{} (object {})", object.category, object.id);
            let open_by_default = model.objects.len() <= 12;
            egui::CollapsingHeader::new(header).id_salt(("object", object.id)).default_open(open_by_default).show(ui, |ui| {
                tree_node_ui(ui, state, model, &children, object.root_part, commands, &mut hovered);
            });
        }
        if !model.skipped_parts.is_empty() {
            ui.separator();
            ui.label(format!("Not fitted (too few points): {:?}", model.skipped_parts));
        }
    });
    if hovered.is_some() {
        state.hovered = hovered;
    }
}

fn tree_node_ui(
    ui: &mut egui::Ui,
    state: &AppState,
    model: &SceneModel,
    children: &BTreeMap<PartId, Vec<PartId>>,
    part: PartId,
    commands: &mut Vec<AppCommand>,
    hovered: &mut Option<PartId>,
) {
    let kids = children.get(&part).cloned().unwrap_or_default();
    let row = |ui: &mut egui::Ui, hovered: &mut Option<PartId>, commands: &mut Vec<AppCommand>| {
        ui.horizontal(|ui| {
            let (swatch, _) = ui.allocate_exact_size(Vec2::splat(10.0), Sense::hover());
            ui.painter().rect_filled(swatch, 2.0, color32(part_color(part)));
            // Movable joints: a disc for revolute, a bar for prismatic (no font needs the glyph).
            if let Some(j) = model.joint_of(part)
                && j.kind.is_movable()
            {
                let (mark, _) = ui.allocate_exact_size(Vec2::splat(10.0), Sense::hover());
                if j.kind.rotates() {
                    ui.painter().circle_filled(mark.center(), 4.0, kind_color(j.kind));
                } else {
                    ui.painter().rect_filled(Rect::from_center_size(mark.center(), Vec2::new(10.0, 4.0)), 1.0, kind_color(j.kind));
                }
            }
            let resp = ui.selectable_label(state.selected == Some(part), part_name(model, part)).interact(Sense::drag());
            resp.dnd_set_drag_payload(DraggedPart(part));
            if let Some(dragged) = resp.dnd_hover_payload::<DraggedPart>()
                && dragged.0 != part
            {
                ui.painter().rect_stroke(resp.rect, 2.0, Stroke::new(1.5, Color32::from_rgb(255, 200, 80)), egui::StrokeKind::Outside);
            }
            if let Some(dragged) = resp.dnd_release_payload::<DraggedPart>()
                && dragged.0 != part
            {
                commands.push(AppCommand::Edit(EditCommand::SetParent { child: dragged.0, parent: part }));
            }
            if resp.clicked() {
                commands.push(AppCommand::Select(Some(part)));
            }
            if resp.hovered() {
                *hovered = Some(part);
            } else if state.last_hovered == Some(part) {
                ui.painter().rect_stroke(resp.rect, 2.0, Stroke::new(1.0, Color32::from_gray(200)), egui::StrokeKind::Outside);
            }
            if state.doc.as_ref().is_some_and(|d| is_pinned(d.pins(), part)) {
                ui.weak("pinned").on_hover_text("re-runs of the pipeline keep this correction");
            }
        });
    };
    if kids.is_empty() {
        row(ui, hovered, commands);
    } else {
        let id = ui.make_persistent_id(("tree", part));
        egui::collapsing_header::CollapsingState::load_with_default_open(ui.ctx(), id, true)
            .show_header(ui, |ui| row(ui, hovered, commands))
            .body(|ui| {
                for k in kids {
                    tree_node_ui(ui, state, model, children, k, commands, hovered);
                }
            });
    }
}

/// The selected part: primitive, joint (parent, type, axis, limits), articulation, pins.
pub fn inspector_ui(ui: &mut egui::Ui, state: &AppState, panels: &mut PanelState, commands: &mut Vec<AppCommand>) {
    let (Some(doc), Some(id)) = (&state.doc, state.selected) else {
        ui.label("Select a part in the 3D view, the tree or the graph.");
        return;
    };
    let model = doc.model();
    let Some(part) = model.part(id) else { return };
    ui.heading(&part.label);
    egui::Grid::new("part facts").num_columns(2).show(ui, |ui| {
        ui.label("part id");
        ui.label(id.to_string());
        ui.end_row();
        ui.label("object");
        ui.label(model.objects.iter().find(|o| o.id == part.object).map_or("?".into(), |o| format!("{} {}", o.category, o.id)));
        ui.end_row();
        ui.label("points");
        ui.label(part.point_count.to_string());
        ui.end_row();
        ui.label("fit error");
        ui.label(format!("{:.1} mm", part.fit_error * 1000.0));
        ui.end_row();
        ui.label("size");
        let s = part.primitive.size;
        ui.label(format!("{:.3} × {:.3} × {:.3} m", s.x, s.y, s.z));
        ui.end_row();
    });
    let mut kind = part.primitive.kind;
    egui::ComboBox::from_label("Primitive").selected_text(kind.name()).show_ui(ui, |ui| {
        for k in PrimitiveKind::ALL {
            ui.selectable_value(&mut kind, k, k.name());
        }
    });
    if kind != part.primitive.kind {
        commands.push(AppCommand::Edit(EditCommand::SetPrimitiveKind { part: id, kind }));
    }
    ui.separator();
    let Some(joint) = model.joint_of(id).copied() else {
        ui.label("Root of its object: no joint.");
        pins_ui(ui, state, id, commands);
        return;
    };
    // Parent: any part of the same object outside this part's subtree.
    let below = doc.descendants(id);
    let candidates: Vec<PartId> =
        model.parts_of(part.object).map(|p| p.id).filter(|p| *p != id && !below.contains(p) && *p != joint.parent).collect();
    egui::ComboBox::from_label("Parent").selected_text(part_name(model, joint.parent)).show_ui(ui, |ui| {
        for c in candidates {
            if ui.selectable_label(false, format!("make parent: {}", part_name(model, c))).clicked() {
                commands.push(AppCommand::Edit(EditCommand::SetParent { child: id, parent: c }));
            }
        }
    });
    let mut jkind = joint.kind;
    egui::ComboBox::from_label("Joint type").selected_text(jkind.name()).show_ui(ui, |ui| {
        for k in JointKind::ALL {
            ui.selectable_value(&mut jkind, k, k.name());
        }
    });
    if jkind != joint.kind {
        commands.push(AppCommand::Edit(EditCommand::SetJointKind { child: id, kind: jkind }));
    }
    super::review::evidence_ui(ui, model, id);
    if joint.kind.is_movable() {
        // Axis: edited in a buffer, committed when the drag or typing ends (one undo step).
        let revision = doc.revision();
        let mut axis = match panels.axis_edit {
            Some((p, r, a)) if p == id && r == revision => a,
            _ => joint.axis_world.to_array(),
        };
        let mut commit = false;
        ui.horizontal(|ui| {
            ui.label("Axis");
            for (v, name) in axis.iter_mut().zip(["x", "y", "z"]) {
                let r = ui.add(egui::DragValue::new(v).speed(0.01).range(-1.0..=1.0).prefix(format!("{name} ")));
                commit |= r.drag_stopped() || r.lost_focus();
            }
            if ui.button("Flip axis").clicked() {
                commands.push(AppCommand::Edit(EditCommand::FlipAxis { child: id }));
            }
        });
        panels.axis_edit = Some((id, revision, axis));
        if commit {
            panels.axis_edit = None;
            commands.push(AppCommand::Edit(EditCommand::SetAxis { child: id, axis_world: glam::Vec3::from_array(axis) }));
        }
        let unit = if joint.kind.rotates() { "rad" } else { "m" };
        let mut limits = match panels.limits_edit {
            Some((p, r, l)) if p == id && r == revision => l,
            _ => [joint.lower, joint.upper],
        };
        let mut commit = false;
        ui.horizontal(|ui| {
            ui.label(format!("Limits ({unit})"));
            let r = ui.add(egui::DragValue::new(&mut limits[0]).speed(0.01).prefix("lower "));
            commit |= r.drag_stopped() || r.lost_focus();
            let r = ui.add(egui::DragValue::new(&mut limits[1]).speed(0.01).prefix("upper "));
            commit |= r.drag_stopped() || r.lost_focus();
        });
        panels.limits_edit = Some((id, revision, limits));
        if commit {
            panels.limits_edit = None;
            commands.push(AppCommand::Edit(EditCommand::SetLimits { child: id, lower: limits[0], upper: limits[1] }));
        }
        let o = joint.origin_world;
        ui.horizontal(|ui| {
            ui.label(format!("Pivot ({:.3}, {:.3}, {:.3}) m", o.x, o.y, o.z));
            if doc.hinge_edge_of(id).is_some()
                && ui.button("Other edge").on_hover_text("Move the hinge to the part's other edge (E)").clicked()
            {
                commands.push(AppCommand::Edit(EditCommand::OtherHingeEdge { child: id }));
            }
        });
        let mut q = state.joint_q.get(&id).copied().unwrap_or(0.0);
        if ui.add(egui::Slider::new(&mut q, joint.lower..=joint.upper).text("Position")).changed() {
            commands.push(AppCommand::SetJointPosition { child: id, q });
        }
    }
    pins_ui(ui, state, id, commands);
}

fn pins_ui(ui: &mut egui::Ui, state: &AppState, id: PartId, commands: &mut Vec<AppCommand>) {
    if state.doc.as_ref().is_some_and(|d| is_pinned(d.pins(), id)) {
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("Pinned: every re-run keeps these corrections.");
            if ui.button("Unpin").clicked() {
                commands.push(AppCommand::Edit(EditCommand::Unpin { part: id }));
            }
        });
    }
}

/// Sliders that move every movable joint of the selected part's object through its limits.
pub fn joints_ui(ui: &mut egui::Ui, state: &AppState, commands: &mut Vec<AppCommand>) {
    let Some(doc) = &state.doc else { return };
    let model = doc.model();
    let object = state.selected.and_then(|id| model.part(id)).map(|p| p.object);
    let joints: Vec<_> = model
        .joints
        .iter()
        .filter(|j| j.kind.is_movable() && object.is_none_or(|o| model.part(j.child).is_some_and(|p| p.object == o)))
        .collect();
    ui.horizontal(|ui| {
        ui.strong(if object.is_some() { "Joints of this object" } else { "All joints" });
        if ui.button("Close all").clicked() {
            commands.push(AppCommand::ResetJointPositions);
        }
    });
    egui::ScrollArea::vertical().id_salt("joint sliders").show(ui, |ui| {
        for j in joints {
            let mut q = state.joint_q.get(&j.child).copied().unwrap_or(0.0);
            let text = format!("{} ({})", part_name(model, j.child), j.kind.name());
            if ui.add(egui::Slider::new(&mut q, j.lower..=j.upper).text(text)).changed() {
                commands.push(AppCommand::SetJointPosition { child: j.child, q });
            }
        }
    });
}

/// A line from `from` to `to` with a fixed-size arrowhead at `to`.
fn arrow(painter: &egui::Painter, from: Pos2, to: Pos2, stroke: Stroke) {
    painter.line_segment([from, to], stroke);
    let dir = (to - from).normalized();
    if !dir.is_finite() {
        return;
    }
    let side = egui::vec2(-dir.y, dir.x);
    let back = to - dir * 9.0;
    painter.add(egui::Shape::convex_polygon(vec![to, back + side * 4.5, back - side * 4.5], stroke.color, Stroke::NONE));
}

/// The contact graph of one object as a node-link diagram: candidate contacts (grey, labelled by
/// weight) and the tree Edmonds kept (coloured by joint type). Drag a node onto another to make it
/// the parent; click to select.
pub fn graph_ui(ui: &mut egui::Ui, state: &mut AppState, commands: &mut Vec<AppCommand>) {
    let Some(doc) = &state.doc else { return };
    let model = doc.model();
    let object: Option<ObjectId> = state
        .selected
        .or(state.last_hovered)
        .and_then(|id| model.part(id))
        .map(|p| p.object)
        .or_else(|| model.objects.first().map(|o| o.id));
    let Some(object) = object else { return };
    let Some(root) = model.objects.iter().find(|o| o.id == object).map(|o| o.root_part) else { return };
    // Layers by depth in the tree, in id order within a layer.
    let children = children_map(model);
    let mut layers: Vec<Vec<PartId>> = Vec::new();
    let mut frontier = vec![root];
    while !frontier.is_empty() && layers.len() < 64 {
        let next: Vec<PartId> = frontier.iter().flat_map(|p| children.get(p).cloned().unwrap_or_default()).collect();
        layers.push(frontier);
        frontier = next;
    }
    let (rect, _) = ui.allocate_exact_size(ui.available_size(), Sense::hover());
    let painter = ui.painter_at(rect);
    painter.text(
        rect.left_top() + Vec2::new(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        format!("contact graph · {}", model.objects.iter().find(|o| o.id == object).map_or("", |o| o.category.as_str())),
        egui::FontId::proportional(12.0),
        ui.visuals().weak_text_color(),
    );
    let node_size = Vec2::new(104.0, 22.0);
    let mut pos: BTreeMap<PartId, Pos2> = BTreeMap::new();
    let rows = layers.len().max(1) as f32;
    for (d, layer) in layers.iter().enumerate() {
        let y = rect.top() + 28.0 + (rect.height() - 40.0) * (d as f32 + 0.5) / rows;
        for (i, p) in layer.iter().enumerate() {
            let x = rect.left() + rect.width() * (i as f32 + 0.5) / layer.len() as f32;
            pos.insert(*p, Pos2::new(x, y));
        }
    }
    // Candidate edges first (under the tree edges).
    for e in model.contact_edges.iter().filter(|e| !e.in_tree) {
        let (Some(a), Some(b)) = (pos.get(&e.parent), pos.get(&e.child)) else { continue };
        painter.line_segment([*a, *b], Stroke::new(1.0, Color32::from_gray(110)));
        painter.text(
            a.lerp(*b, 0.5),
            egui::Align2::CENTER_CENTER,
            format!("{:.2}", e.weight),
            egui::FontId::proportional(10.0),
            Color32::from_gray(150),
        );
    }
    for j in &model.joints {
        let (Some(a), Some(b)) = (pos.get(&j.parent), pos.get(&j.child)) else { continue };
        arrow(
            &painter,
            *a + Vec2::new(0.0, node_size.y * 0.5),
            *b - Vec2::new(0.0, node_size.y * 0.5),
            Stroke::new(2.0, kind_color(j.kind)),
        );
    }
    let mut hovered = None;
    for (&p, &centre) in &pos {
        let r = Rect::from_center_size(centre, node_size);
        let resp = ui.interact(r, ui.scope_id().with(("graph node", p)), Sense::click_and_drag());
        let name = part_name(model, p);
        resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Button, true, format!("graph node {name}")));
        resp.dnd_set_drag_payload(DraggedPart(p));
        if let Some(dragged) = resp.dnd_release_payload::<DraggedPart>()
            && dragged.0 != p
        {
            commands.push(AppCommand::Edit(EditCommand::SetParent { child: dragged.0, parent: p }));
        }
        if resp.clicked() {
            commands.push(AppCommand::Select(Some(p)));
        }
        if resp.hovered() {
            hovered = Some(p);
        }
        let selected = state.selected == Some(p);
        let fill = if selected { Color32::from_rgb(255, 140, 25) } else { color32(part_color(p)).gamma_multiply(0.85) };
        let stroke = if resp.dnd_hover_payload::<DraggedPart>().is_some() || state.last_hovered == Some(p) {
            Stroke::new(2.0, Color32::WHITE)
        } else {
            Stroke::new(1.0, Color32::from_gray(60))
        };
        painter.rect(r, 4.0, fill, stroke, egui::StrokeKind::Inside);
        painter.text(centre, egui::Align2::CENTER_CENTER, name, egui::FontId::proportional(12.0), Color32::BLACK);
        if resp.dragged()
            && let Some(pointer) = resp.interact_pointer_pos()
        {
            painter.line_segment([centre, pointer], Stroke::new(1.5, Color32::from_rgb(255, 200, 80)));
        }
    }
    if hovered.is_some() {
        state.hovered = hovered;
    }
}
