//! Kinematic metrics: the paper's kinematic-edge AP (Table II) and joint type / axis accuracy.

use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use crate::kinematics::JointKind;
use crate::math::{Vec3, line_angle_deg};
use crate::model::SceneModel;
use crate::scan::PartId;
use crate::truth::{TruthObject, TruthPart};

/// Non-interpolated average precision of a ranked list: `Σ_k (R_k − R_{k−1}) · P_k`, where
/// `ranked_hits[k]` says whether the k-th prediction (best first) is a true positive and recall
/// counts all `truth_count` truth items, so missed items lower the AP. `None` when there is no
/// truth item; 0 when nothing is predicted.
#[must_use]
pub fn average_precision(ranked_hits: &[bool], truth_count: usize) -> Option<f32> {
    if truth_count == 0 {
        return None;
    }
    let mut true_positives = 0_usize;
    let mut ap = 0.0_f64;
    for (k, hit) in ranked_hits.iter().enumerate() {
        if *hit && true_positives < truth_count {
            true_positives += 1;
            let precision = true_positives as f64 / (k + 1) as f64;
            ap += precision / truth_count as f64;
        }
    }
    Some(ap as f32)
}

/// An undirected edge with the smaller id first.
fn undirected(a: PartId, b: PartId) -> [PartId; 2] {
    if a <= b { [a, b] } else { [b, a] }
}

/// Kinematic-edge AP of one object: the model's tree edges between parts of the object, ranked by
/// the contact weight of that parent → child pair (0 if the model lists no such contact edge),
/// against the truth's undirected contact edges. Returns (AP, number of predicted edges).
pub(crate) fn edge_ap(model: &SceneModel, truth: &TruthObject, model_parts: &BTreeSet<PartId>) -> (Option<f32>, usize) {
    let unobserved = unobserved_parts(model, truth);
    let truth_edges: BTreeSet<[PartId; 2]> = truth
        .contact_edges
        .iter()
        .filter(|e| !unobserved.contains(&e[0]) && !unobserved.contains(&e[1]))
        .map(|e| undirected(e[0], e[1]))
        .collect();
    // (weight, edge); duplicates of one undirected edge keep their best weight.
    let mut predicted: Vec<(f32, [PartId; 2])> = Vec::new();
    for joint in &model.joints {
        if !(model_parts.contains(&joint.parent) && model_parts.contains(&joint.child)) {
            continue;
        }
        let weight = model
            .contact_edges
            .iter()
            .find(|c| c.parent == joint.parent && c.child == joint.child)
            .map_or(0.0, |c| if c.weight.is_finite() { c.weight } else { 0.0 });
        let edge = undirected(joint.parent, joint.child);
        match predicted.iter_mut().find(|(_, e)| *e == edge) {
            Some(entry) => entry.0 = entry.0.max(weight),
            None => predicted.push((weight, edge)),
        }
    }
    // Best first; ties broken by edge id so the ranking is deterministic.
    predicted.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let hits: Vec<bool> = predicted.iter().map(|(_, e)| truth_edges.contains(e)).collect();
    (average_precision(&hits, truth_edges.len()), predicted.len())
}

/// How one truth joint was reconstructed.
// A flat record of independent yes/no findings, read by people and scripts as JSON fields.
#[allow(clippy::struct_excessive_bools)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointRow {
    /// The truth joint's child part.
    pub child: PartId,
    pub truth_kind: JointKind,
    /// The type of the model's joint with this child; `None` when the part is missing from the
    /// model or is a root there.
    pub predicted_kind: Option<JointKind>,
    /// The child part is not in the model at all.
    pub part_missing: bool,
    pub type_correct: bool,
    /// The model joins the child to its truth parent's rigid body (either way round): to the
    /// truth parent itself or to a part the truth welds to it with fixed joints. A knob the truth
    /// hangs off an oven's body and the model off the hood welded to that body moves alike.
    #[serde(default)]
    pub parent_correct: bool,
    /// The model joins the same two parts as the truth (either way round): the strict reading
    /// of `parent_correct`.
    #[serde(default)]
    pub parent_same_part: bool,
    /// The model's confidence in its joint ([`crate::kinematics::JointEvidence`]), when it has one.
    #[serde(default)]
    pub confidence: Option<f32>,
    /// The model's confidence in how it placed the axis line (a hinge's edge; 1 where nothing
    /// was chosen), when it has evidence.
    #[serde(default)]
    pub axis_confidence: Option<f32>,
    /// Undirected angle between the axes, degrees: movable truth joints with the right type only.
    pub axis_error_deg: Option<f32>,
    /// Distance between the hinge lines, metres: revolute joints with the right type only.
    pub hinge_distance_m: Option<f32>,
    /// Prismatic origin distance, metres: prismatic joints with the right type only (see
    /// [`prismatic_origin_distance`]).
    #[serde(default)]
    pub prismatic_origin_distance_m: Option<f32>,
}

/// How far a predicted slide line runs from the part that slides: the distance from the
/// predicted joint origin to the truth child part's centre (the centre of its bounds), measured
/// perpendicular to the truth axis. A slide joint's origin is not a physical quantity — any point
/// moves the part the same way — and files put it anywhere (an MJCF slide sits at its body's
/// frame, which is often the parent's origin: LIBERO's three `wooden_cabinet` drawers and
/// `short_cabinet`'s all slide from the cabinet's base point), so the truth child's centre is the
/// reference; for the demo's generated truth it is the truth origin itself. The pipeline puts a
/// prismatic origin at the child's centre, so this measures where the sliding part was placed
/// across its direction of travel. `None` when the truth part has no geometry.
#[must_use]
pub fn prismatic_origin_distance(predicted_origin: Vec3, truth_axis: Vec3, truth_child_centre: Option<Vec3>) -> Option<f32> {
    let axis = truth_axis.try_normalize()?;
    let d = predicted_origin - truth_child_centre?;
    Some((d - axis * d.dot(axis)).length())
}

/// How far a predicted hinge line runs from the truth's where the part is: the distance from the
/// point of the truth line level with the truth child part's centre (its projection on the line;
/// the truth origin itself when the part has no geometry) to the predicted line. Two infinite
/// lines a fraction of a degree apart meet somewhere, metres away, so their closest approach
/// says nothing of the part; the hinge matters where the part turns.
#[must_use]
pub fn hinge_distance(
    predicted_origin: Vec3,
    predicted_axis: Vec3,
    truth_origin: Vec3,
    truth_axis: Vec3,
    truth_child_centre: Option<Vec3>,
) -> f32 {
    let t_axis = truth_axis.normalize_or_zero();
    let at = truth_child_centre.map_or(truth_origin, |c| truth_origin + t_axis * (c - truth_origin).dot(t_axis));
    let p_axis = predicted_axis.normalize_or_zero();
    let d = at - predicted_origin;
    (d - p_axis * d.dot(p_axis)).length()
}

/// Compares every truth joint of an object with the model's joint of the same child part.
pub(crate) fn joint_rows(model: &SceneModel, truth: &TruthObject) -> Vec<JointRow> {
    // A part the scan never saw (not in the model and not skipped by fitting) cannot be judged.
    let unobserved = |id: PartId| model.part(id).is_none() && model.skipped_parts.binary_search(&id).is_err();
    truth
        .joints
        .iter()
        .filter(|t| !unobserved(t.child) && !unobserved(t.parent))
        .map(|t| {
            let part_missing = model.part(t.child).is_none();
            // The model's joint between the same two parts, in either direction (a tree may hang
            // a bed's frame off its headboard: the same kinematic edge); else the child's joint.
            let same_pair =
                model.joints.iter().find(|j| (j.parent, j.child) == (t.parent, t.child) || (j.parent, j.child) == (t.child, t.parent));
            let predicted = if part_missing { None } else { same_pair.or_else(|| model.joint_of(t.child)) };
            let predicted_kind = predicted.map(|j| j.kind);
            // A URDF continuous joint is read as revolute without limits: both turn alike.
            let type_correct = predicted_kind.map(JointKind::motion_class) == Some(t.kind.motion_class());
            let (mut axis_error_deg, mut hinge_distance_m, mut prismatic_origin_distance_m) = (None, None, None);
            if let Some(p) = predicted.filter(|_| type_correct && t.kind.is_movable()) {
                axis_error_deg = Some(line_angle_deg(p.axis_world, t.axis_world));
                let centre = truth.parts.iter().find(|part| part.id == t.child).and_then(TruthPart::aabb).map(|(lo, hi)| 0.5 * (lo + hi));
                if t.kind.rotates() {
                    hinge_distance_m = Some(hinge_distance(p.origin_world, p.axis_world, t.origin_world, t.axis_world, centre));
                } else {
                    prismatic_origin_distance_m = prismatic_origin_distance(p.origin_world, t.axis_world, centre);
                }
            }
            let body = |id: PartId| rigid_body(truth, id);
            // Reversed (the truth parent hung off the child), only for the truth parent itself.
            let joined_to_parent_body = model
                .joints
                .iter()
                .any(|j| (j.child == t.child && body(j.parent) == body(t.parent)) || (j.parent == t.child && j.child == t.parent));
            let parent_correct = joined_to_parent_body && !part_missing;
            let parent_same_part = same_pair.is_some() && !part_missing;
            let evidence = predicted.and_then(|p| model.evidence.iter().find(|e| e.child == p.child));
            let (confidence, axis_confidence) = (evidence.map(|e| e.confidence), evidence.map(|e| e.axis_confidence));
            JointRow {
                child: t.child,
                truth_kind: t.kind,
                predicted_kind,
                part_missing,
                type_correct,
                parent_correct,
                parent_same_part,
                confidence,
                axis_confidence,
                axis_error_deg,
                hinge_distance_m,
                prismatic_origin_distance_m,
            }
        })
        .collect()
}

/// The rigid body a truth part belongs to, named by its topmost part: the part reached by
/// walking up the truth tree while the joints are fixed. A part the truth does not know is its own
/// body.
fn rigid_body(truth: &TruthObject, part: PartId) -> PartId {
    let mut id = part;
    // A tree has fewer joints than parts; the bound only guards a malformed truth with a cycle.
    for _ in 0..=truth.joints.len() {
        match truth.joints.iter().find(|j| j.child == id && j.kind == JointKind::Fixed) {
            Some(j) => id = j.parent,
            None => break,
        }
    }
    id
}

/// Truth parts of an object that the scan never saw: not in the model and not skipped by fitting.
pub(crate) fn unobserved_parts(model: &SceneModel, truth: &TruthObject) -> Vec<PartId> {
    truth.parts.iter().map(|p| p.id).filter(|&id| model.part(id).is_none() && model.skipped_parts.binary_search(&id).is_err()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prismatic_origin_distance_ignores_the_offset_along_the_axis() {
        // A drawer centred at (0, 0.3, 0.8) sliding along +y; a predicted origin 5 cm along the
        // axis and 3 cm to the side is 3 cm off, wherever the file put its own origin.
        let d = prismatic_origin_distance(Vec3::new(0.03, 0.35, 0.8), Vec3::new(0.0, -2.0, 0.0), Some(Vec3::new(0.0, 0.3, 0.8)));
        assert!((d.expect("distance") - 0.03).abs() < 1e-6, "{d:?}");
        assert_eq!(prismatic_origin_distance(Vec3::ZERO, Vec3::ZERO, Some(Vec3::ONE)), None);
        assert_eq!(prismatic_origin_distance(Vec3::ZERO, Vec3::Y, None), None);
    }

    #[test]
    fn a_hinge_a_tenth_of_a_degree_off_is_measured_where_the_part_turns_not_where_the_lines_meet() {
        // Regression: metaworld's lever, its hinge 6 cm from the truth's at the lever and skewed
        // by 0.06 degrees, scored 2 cm (the infinite lines' closest approach, far along them).
        let skew = Vec3::new(1.0, -0.001, 0.0);
        let got =
            hinge_distance(Vec3::new(0.06, 0.008, 0.272), skew, Vec3::new(0.07, 0.069, 0.25), Vec3::X, Some(Vec3::new(0.07, 0.0, 0.25)));
        assert!((got - 0.0648).abs() < 1e-3, "{got}");
        // Parallel lines: their distance, wherever the part is.
        let d = hinge_distance(Vec3::new(5.0, 0.03, 0.0), Vec3::X, Vec3::ZERO, Vec3::X, None);
        assert!((d - 0.03).abs() < 1e-6, "{d}");
    }

    #[test]
    fn ap_of_a_perfect_ranking_is_one() {
        assert_eq!(average_precision(&[true, true, true], 3), Some(1.0));
    }

    #[test]
    fn ap_of_a_mixed_ranking_matches_the_hand_computed_value() {
        // Truth {A, B, C}; ranking A ✓, X ✗, B ✓, Y ✗; C never predicted.
        // AP = 1/3 · 1/1 + 1/3 · 2/3 = 5/9.
        let ap = average_precision(&[true, false, true, false], 3).expect("ap");
        assert!((ap - 5.0 / 9.0).abs() < 1e-6, "{ap}");
        // False positives after the last hit do not matter; before the first they do.
        let ap = average_precision(&[false, true, true], 2).expect("ap");
        assert!((ap - (0.5 * 0.5 + 0.5 * 2.0 / 3.0)).abs() < 1e-6, "{ap}");
        assert_eq!(average_precision(&[], 2), Some(0.0));
        assert_eq!(average_precision(&[true], 0), None);
    }
}
