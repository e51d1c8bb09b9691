//! The review queue and the evidence of a joint: an annotator correcting hundreds of objects
//! fixes the doubtful joints first. Every joint whose parent and type the annotator has not yet
//! pinned (by fixing or confirming it), or whose hinge edge is in doubt and not yet chosen, is in
//! the queue, least confident first; `N` selects the
//! next one, `A` confirms the selected joint as it is and moves on, `E` moves a door's or lid's
//! hinge to its other edge (the doubt of a door with no handle). The inspector shows why the
//! tool chose what it chose ([`evidence_ui`]).

use eframe::egui::{self, Color32, RichText};

use super::panels::part_name;
use super::state::{AppCommand, AppState};
use crate::edit::EditCommand;
use crate::kinematics::JointEvidence;
use crate::model::SceneModel;
use crate::pipeline::PinnedEdits;
use crate::scan::PartId;

/// Confidence below which a joint is shown as doubtful (the bench's "confident" line is 0.9).
const DOUBTFUL: f32 = 0.9;

/// Most queue entries listed at once (the keys step through all of them).
const LISTED: usize = 8;

/// One joint waiting for review.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReviewItem {
    /// The joint's child part.
    pub child: PartId,
    /// The tool's confidence in the joint's type, parent and axis.
    pub confidence: f32,
}

/// The joints not yet reviewed (neither parent nor type pinned, or a hinge whose edge is in
/// doubt and not chosen by a person), least confident first; ties by part id. A joint without
/// evidence (an older scene file) counts as fully doubtful.
#[must_use]
pub fn review_queue(model: &SceneModel, pins: &PinnedEdits) -> Vec<ReviewItem> {
    let edge_in_doubt =
        |child: PartId| evidence_of(model, child).is_some_and(|e| e.axis_confidence < 1.0) && !pins.hinge_edge.contains_key(&child);
    let mut queue: Vec<ReviewItem> = model
        .joints
        .iter()
        .filter(|j| (!pins.parent.contains_key(&j.child) && !pins.joint_kind.contains_key(&j.child)) || edge_in_doubt(j.child))
        .map(|j| ReviewItem { child: j.child, confidence: evidence_of(model, j.child).map_or(0.0, |e| e.confidence) })
        .collect();
    queue.sort_by(|a, b| a.confidence.total_cmp(&b.confidence).then(a.child.cmp(&b.child)));
    queue
}

/// The queue entry after `current` (the first when `current` is not queued), wrapping around.
#[must_use]
pub fn next_in_queue(queue: &[ReviewItem], current: Option<PartId>) -> Option<PartId> {
    let at = current.and_then(|c| queue.iter().position(|q| q.child == c));
    match at {
        Some(i) => queue.get((i + 1) % queue.len()).map(|q| q.child),
        None => queue.first().map(|q| q.child),
    }
}

/// The evidence recorded for the joint above `child`.
#[must_use]
pub fn evidence_of(model: &SceneModel, child: PartId) -> Option<&JointEvidence> {
    model.evidence.iter().find(|e| e.child == child)
}

fn confidence_color(confidence: f32) -> Color32 {
    if confidence >= DOUBTFUL {
        Color32::from_rgb(120, 200, 120)
    } else if confidence >= 0.6 {
        Color32::from_rgb(230, 190, 90)
    } else {
        Color32::from_rgb(235, 110, 100)
    }
}

/// The queue: how many joints are left, the least certain ones, and the two keys.
pub fn review_ui(ui: &mut egui::Ui, state: &AppState, commands: &mut Vec<AppCommand>) {
    let Some(doc) = &state.doc else { return };
    let model = doc.model();
    let queue = review_queue(model, doc.pins());
    let doubtful = queue.iter().filter(|q| q.confidence < DOUBTFUL).count();
    ui.heading(format!("Review queue: {} joints left, {doubtful} doubtful", queue.len()));
    ui.horizontal(|ui| {
        if ui.add_enabled(!queue.is_empty(), egui::Button::new("Next doubtful (N)")).clicked() {
            commands.push(AppCommand::ReviewNext);
        }
        let selected_queued = state.selected.is_some_and(|s| queue.iter().any(|q| q.child == s));
        if ui.add_enabled(selected_queued, egui::Button::new("Confirm joint (A)")).clicked() {
            commands.push(AppCommand::ConfirmSelected);
        }
        let hinged = state.selected.is_some_and(|s| doc.hinge_edge_of(s).is_some());
        if ui.add_enabled(hinged, egui::Button::new("Other hinge edge (E)")).clicked() {
            commands.push(AppCommand::OtherEdgeSelected);
        }
    });
    egui::Grid::new("review queue").num_columns(3).striped(true).show(ui, |ui| {
        for item in queue.iter().take(LISTED) {
            let kind = model.joint_of(item.child).map_or("?", |j| j.kind.name());
            ui.label(RichText::new(format!("{:.2}", item.confidence)).color(confidence_color(item.confidence)));
            let name = format!("review: {}", part_name(model, item.child));
            if ui.selectable_label(state.selected == Some(item.child), name).clicked() {
                commands.push(AppCommand::Select(Some(item.child)));
            }
            ui.label(format!("as {kind}"));
            ui.end_row();
        }
    });
    if queue.len() > LISTED {
        ui.label(format!("… and {} more", queue.len() - LISTED));
    }
}

/// Why the joint above `child` has its type, parent and axis, and how sure the tool is.
pub fn evidence_ui(ui: &mut egui::Ui, model: &SceneModel, child: PartId) {
    let Some(e) = evidence_of(model, child) else {
        ui.label("No evidence recorded for this joint (a scene from an older version).");
        return;
    };
    ui.label(RichText::new(format!("Evidence · confidence {:.2}", e.confidence)).strong().color(confidence_color(e.confidence)));
    egui::Grid::new("joint evidence").num_columns(2).show(ui, |ui| {
        let row = |ui: &mut egui::Ui, name: &str, value: String| {
            ui.label(name);
            ui.add(egui::Label::new(value).wrap());
            ui.end_row();
        };
        row(ui, "type", format!("{:.2} — {}", e.type_confidence, e.label_rule));
        row(ui, "parent", format!("{:.2} — {}", e.parent_confidence, e.parent_rule));
        row(ui, "runner-up", e.runner_up.map_or_else(|| "none".to_owned(), |k| format!("{} (second choice)", k.name())));
        row(ui, "axis from", format!("{:?}", e.template).to_lowercase());
        if !e.axis_rule.is_empty() {
            row(ui, "axis", format!("{:.2} — {}", e.axis_confidence, e.axis_rule));
        }
        for (i, test) in e.tests.iter().enumerate() {
            row(ui, if i == 0 { "tests" } else { "" }, test.clone());
        }
    });
}

/// Applies the review commands to the state (called from [`AppState::apply`]).
pub(super) fn apply(state: &mut AppState, command: &AppCommand) {
    let Some(doc) = &state.doc else { return };
    match command {
        AppCommand::ReviewNext => {
            let queue = review_queue(doc.model(), doc.pins());
            match next_in_queue(&queue, state.selected) {
                Some(next) => state.apply(AppCommand::Select(Some(next))),
                None => state.apply(AppCommand::Select(None)),
            }
        }
        AppCommand::ConfirmSelected => {
            let Some(child) = state.selected.filter(|s| doc.model().joint_of(*s).is_some()) else { return };
            let queue = review_queue(doc.model(), doc.pins());
            let next = next_in_queue(&queue, Some(child)).filter(|n| *n != child);
            state.apply(AppCommand::Edit(EditCommand::Confirm { child }));
            state.apply(AppCommand::Select(next));
        }
        AppCommand::OtherEdgeSelected => {
            let Some(child) = state.selected.filter(|s| doc.hinge_edge_of(*s).is_some()) else { return };
            state.apply(AppCommand::Edit(EditCommand::OtherHingeEdge { child }));
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(queue: &[(PartId, f32)], current: Option<PartId>, expected: Option<PartId>) {
        let items: Vec<ReviewItem> = queue.iter().map(|&(child, confidence)| ReviewItem { child, confidence }).collect();
        assert_eq!(next_in_queue(&items, current), expected, "queue {queue:?} after {current:?}");
    }

    #[test]
    fn the_next_key_steps_through_the_queue_and_wraps() {
        check(&[(4, 0.2), (2, 0.5), (9, 0.95)], None, Some(4));
        check(&[(4, 0.2), (2, 0.5), (9, 0.95)], Some(4), Some(2));
        check(&[(4, 0.2), (2, 0.5), (9, 0.95)], Some(9), Some(4));
        // A selection outside the queue (a reviewed joint) starts over at the least certain.
        check(&[(4, 0.2), (2, 0.5)], Some(7), Some(4));
        check(&[], Some(7), None);
    }
}
