//! `partscene eval`: scores a reconstruction ([`SceneModel`]) against ground truth
//! ([`GroundTruth`]) with the paper's metrics (§IV): Chamfer distance and 32³ voxel `IoU` per object
//! (Table I), kinematic-edge mAP (Table II), plus joint type accuracy and axis errors; and the
//! object-level baseline the paper compares with ([`baseline`]).
//!
//! Part ids in the model are the scan's part ids, which are the truth's part ids; objects are
//! matched by id. Every truth object gets one row; model objects the truth does not know are listed
//! in the summary.

mod aggregate;
pub mod baseline;
pub mod geometry;
pub mod kinematics;
pub mod mesh;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::{self, Write as _};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use aggregate::{Aggregate, BaselineMetrics, aggregate, evaluate_baseline};
pub use baseline::object_level_baseline;
pub use geometry::{
    GeometryScore, GeometrySummary, Solids, chamfer_between, chamfer_distance, evaluate_geometry, iou_between, sample_shapes, voxel_iou,
};
pub use kinematics::{JointRow, average_precision};

use crate::model::SceneModel;
use crate::primitive::Primitive;
use crate::scan::{ObjectId, PartId};
use crate::truth::GroundTruth;

/// Scores of one truth object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectRow {
    pub id: ObjectId,
    pub category: String,
    pub truth_parts: usize,
    /// Model parts carrying this object id.
    pub predicted_parts: usize,
    /// Chamfer distance on the truth's unit box (lower is better); `None` without a prediction.
    pub chamfer: Option<f32>,
    /// 32³ voxel `IoU` (higher is better).
    pub iou: Option<f32>,
    /// Kinematic-edge AP; `None` when the truth has no contact edge.
    pub ap: Option<f32>,
    pub truth_edges: usize,
    pub predicted_edges: usize,
    /// One row per truth joint.
    pub joints: Vec<JointRow>,
    pub correct_types: usize,
    pub movable_joints: usize,
    pub movable_correct_types: usize,
    /// Truth parts that the scan has but the model lost (their joints count as wrong types).
    pub missing_parts: Vec<PartId>,
    /// Truth parts the scan never saw: their joints and contact edges are not scored.
    #[serde(default)]
    pub unobserved_parts: Vec<PartId>,
}

impl ObjectRow {
    /// Axis errors (degrees) of this object's movable joints with the right type.
    pub fn axis_errors_deg(&self) -> impl Iterator<Item = f32> + '_ {
        self.joints.iter().filter_map(|j| j.axis_error_deg)
    }
}

/// Scene-level summary of the metrics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub objects: usize,
    /// Mean Chamfer over objects that have one.
    pub mean_chamfer: Option<f32>,
    pub mean_iou: Option<f32>,
    /// Mean kinematic-edge AP over objects with at least one truth contact edge.
    pub map: Option<f32>,
    pub map_by_category: BTreeMap<String, f32>,
    pub objects_with_edges: usize,
    pub joints: usize,
    pub correct_types: usize,
    /// Correct joint types over all truth joints.
    pub joint_type_accuracy: Option<f32>,
    pub movable_joints: usize,
    pub movable_correct_types: usize,
    /// Correct joint types over movable (prismatic, revolute) truth joints.
    pub movable_type_accuracy: Option<f32>,
    /// Movable joints with the right type, whose axis error was measured.
    pub axes_measured: usize,
    pub mean_axis_error_deg: Option<f32>,
    pub median_axis_error_deg: Option<f32>,
    pub hinges_measured: usize,
    pub median_hinge_distance_m: Option<f32>,
    /// Prismatic joints with the right type whose origin distance was measured.
    #[serde(default)]
    pub prismatic_origins_measured: usize,
    /// Median prismatic origin distance ([`kinematics::prismatic_origin_distance`]), metres.
    #[serde(default)]
    pub median_prismatic_origin_distance_m: Option<f32>,
    pub missing_parts: usize,
    /// Truth parts the scan never saw (not scored for joints and edges).
    #[serde(default)]
    pub unobserved_parts: usize,
    /// Model objects with no truth object of the same id.
    pub unmatched_model_objects: Vec<ObjectId>,
}

/// The result of `partscene eval`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// The model's source (scan path or demo seed).
    pub source: String,
    /// One row per truth object, in truth order.
    pub objects: Vec<ObjectRow>,
    pub summary: Summary,
}

/// Scores a reconstruction against ground truth (objects in parallel, results in truth order).
#[must_use]
pub fn evaluate(model: &SceneModel, truth: &GroundTruth) -> Metrics {
    let objects: Vec<ObjectRow> = truth
        .objects
        .par_iter()
        .map(|t| {
            let predicted: Vec<Primitive> = model.parts_of(t.id).map(|p| p.primitive).collect();
            let model_parts: BTreeSet<PartId> = model.parts_of(t.id).map(|p| p.id).collect();
            let (chamfer, iou) = geometry::object_geometry(&predicted, t);
            let (ap, predicted_edges) = kinematics::edge_ap(model, t, &model_parts);
            let unobserved_parts = kinematics::unobserved_parts(model, t);
            let truth_edges: BTreeSet<[PartId; 2]> = t
                .contact_edges
                .iter()
                .filter(|e| !unobserved_parts.contains(&e[0]) && !unobserved_parts.contains(&e[1]))
                .map(|e| [e[0].min(e[1]), e[0].max(e[1])])
                .collect();
            let joints = kinematics::joint_rows(model, t);
            let movable = joints.iter().filter(|j| j.truth_kind.is_movable());
            ObjectRow {
                id: t.id,
                category: t.category.clone(),
                truth_parts: t.parts.len(),
                predicted_parts: predicted.len(),
                chamfer,
                iou,
                ap,
                truth_edges: truth_edges.len(),
                predicted_edges,
                correct_types: joints.iter().filter(|j| j.type_correct).count(),
                movable_joints: movable.clone().count(),
                movable_correct_types: movable.filter(|j| j.type_correct).count(),
                missing_parts: t
                    .parts
                    .iter()
                    .map(|p| p.id)
                    .filter(|id| model.part(*id).is_none() && !unobserved_parts.contains(id))
                    .collect(),
                unobserved_parts,
                joints,
            }
        })
        .collect();
    let truth_ids: BTreeSet<ObjectId> = truth.objects.iter().map(|o| o.id).collect();
    let model_ids: BTreeSet<ObjectId> = model.objects.iter().map(|o| o.id).chain(model.parts.iter().map(|p| p.object)).collect();
    let unmatched = model_ids.difference(&truth_ids).copied().collect();
    let summary = summarise(&objects, unmatched);
    Metrics { source: model.source.clone(), objects, summary }
}

fn summarise(objects: &[ObjectRow], unmatched_model_objects: Vec<ObjectId>) -> Summary {
    let mean = |it: &mut dyn Iterator<Item = f32>| geometry::mean(it);
    let ratio = |a: usize, b: usize| (b > 0).then(|| a as f32 / b as f32);
    let mut by_category: BTreeMap<String, Vec<f32>> = BTreeMap::new();
    for o in objects {
        if let Some(ap) = o.ap {
            by_category.entry(o.category.clone()).or_default().push(ap);
        }
    }
    let axis_errors: Vec<f32> = objects.iter().flat_map(ObjectRow::axis_errors_deg).collect();
    let hinges: Vec<f32> = objects.iter().flat_map(|o| o.joints.iter().filter_map(|j| j.hinge_distance_m)).collect();
    let slides: Vec<f32> = objects.iter().flat_map(|o| o.joints.iter().filter_map(|j| j.prismatic_origin_distance_m)).collect();
    let joints = objects.iter().map(|o| o.joints.len()).sum();
    let correct_types = objects.iter().map(|o| o.correct_types).sum();
    let movable_joints = objects.iter().map(|o| o.movable_joints).sum();
    let movable_correct_types = objects.iter().map(|o| o.movable_correct_types).sum();
    Summary {
        objects: objects.len(),
        mean_chamfer: mean(&mut objects.iter().filter_map(|o| o.chamfer)),
        mean_iou: mean(&mut objects.iter().filter_map(|o| o.iou)),
        map: mean(&mut objects.iter().filter_map(|o| o.ap)),
        map_by_category: by_category.into_iter().filter_map(|(c, aps)| geometry::mean(aps.into_iter()).map(|m| (c, m))).collect(),
        objects_with_edges: objects.iter().filter(|o| o.ap.is_some()).count(),
        joints,
        correct_types,
        joint_type_accuracy: ratio(correct_types, joints),
        movable_joints,
        movable_correct_types,
        movable_type_accuracy: ratio(movable_correct_types, movable_joints),
        axes_measured: axis_errors.len(),
        mean_axis_error_deg: mean(&mut axis_errors.iter().copied()),
        median_axis_error_deg: median(&axis_errors),
        hinges_measured: hinges.len(),
        median_hinge_distance_m: median(&hinges),
        prismatic_origins_measured: slides.len(),
        median_prismatic_origin_distance_m: median(&slides),
        missing_parts: objects.iter().map(|o| o.missing_parts.len()).sum(),
        unobserved_parts: objects.iter().map(|o| o.unobserved_parts.len()).sum(),
        unmatched_model_objects,
    }
}

/// Median of the finite values (mean of the middle two for an even count); `None` if empty.
pub(crate) fn median(values: &[f32]) -> Option<f32> {
    let mut v: Vec<f32> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f32::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

/// A number with `digits` decimals, or "-" for a missing value.
fn opt(value: Option<f32>, digits: usize) -> String {
    value.map_or_else(|| "-".to_owned(), |v| format!("{v:.digits$}"))
}

fn percent(value: Option<f32>) -> String {
    value.map_or_else(|| "-".to_owned(), |v| format!("{:.1}%", 100.0 * v))
}

impl Metrics {
    /// Markdown: a per-object table and a summary table (for reports and the README).
    #[must_use]
    pub fn markdown_table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "| object | category | parts (truth/model) | Chamfer ↓ | IoU ↑ | AP ↑ | joint types | mean axis err (°) |");
        let _ = writeln!(s, "|---:|---|---:|---:|---:|---:|---:|---:|");
        for o in &self.objects {
            let _ = writeln!(
                s,
                "| {} | {} | {}/{} | {} | {} | {} | {}/{} | {} |",
                o.id,
                o.category,
                o.truth_parts,
                o.predicted_parts,
                opt(o.chamfer, 3),
                opt(o.iou, 3),
                opt(o.ap, 3),
                o.correct_types,
                o.joints.len(),
                opt(geometry::mean(o.axis_errors_deg()), 2),
            );
        }
        let m = &self.summary;
        let _ = writeln!(s);
        let _ = writeln!(s, "| metric | value |");
        let _ = writeln!(s, "|---|---:|");
        let _ = writeln!(s, "| objects | {} |", m.objects);
        let _ = writeln!(s, "| mean Chamfer (unit box) ↓ | {} |", opt(m.mean_chamfer, 3));
        let _ = writeln!(s, "| mean IoU (32³) ↑ | {} |", opt(m.mean_iou, 3));
        let _ = writeln!(s, "| kinematic-edge mAP ↑ ({} objects) | {} |", m.objects_with_edges, opt(m.map, 3));
        for (category, map) in &m.map_by_category {
            let _ = writeln!(s, "| mAP, {category} | {map:.3} |");
        }
        let _ = writeln!(s, "| joint type accuracy ({}/{}) | {} |", m.correct_types, m.joints, percent(m.joint_type_accuracy));
        let _ = writeln!(
            s,
            "| movable joint type accuracy ({}/{}) | {} |",
            m.movable_correct_types,
            m.movable_joints,
            percent(m.movable_type_accuracy)
        );
        let _ = writeln!(
            s,
            "| axis error, median / mean (°, {} joints) | {} / {} |",
            m.axes_measured,
            opt(m.median_axis_error_deg, 2),
            opt(m.mean_axis_error_deg, 2)
        );
        let _ = writeln!(s, "| hinge line distance, median (m, {} joints) | {} |", m.hinges_measured, opt(m.median_hinge_distance_m, 3));
        let _ = writeln!(
            s,
            "| prismatic origin distance, median (m, {} joints) | {} |",
            m.prismatic_origins_measured,
            opt(m.median_prismatic_origin_distance_m, 3)
        );
        let _ = writeln!(s, "| truth parts missing from the model | {} |", m.missing_parts);
        let _ = writeln!(s, "| truth parts the scan never saw (not scored) | {} |", m.unobserved_parts);
        s
    }
}

/// Markdown comparing the part-level reconstruction with the object-level baseline per object
/// (the paper's Table I layout): Chamfer and `IoU` side by side, plus the means.
#[must_use]
pub fn comparison_markdown(part_level: &Metrics, baseline: &[GeometryScore]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| object | category | Chamfer ↓ object-level | Chamfer ↓ part-level | IoU ↑ object-level | IoU ↑ part-level |");
    let _ = writeln!(s, "|---:|---|---:|---:|---:|---:|");
    for o in &part_level.objects {
        let b = baseline.iter().find(|b| b.object == o.id);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            o.id,
            o.category,
            opt(b.and_then(|b| b.chamfer), 3),
            opt(o.chamfer, 3),
            opt(b.and_then(|b| b.iou), 3),
            opt(o.iou, 3),
        );
    }
    let b = GeometrySummary::of(baseline);
    let m = &part_level.summary;
    let _ = writeln!(
        s,
        "| **mean** | | {} | {} | {} | {} |",
        opt(b.mean_chamfer, 3),
        opt(m.mean_chamfer, 3),
        opt(b.mean_iou, 3),
        opt(m.mean_iou, 3)
    );
    s
}

impl fmt::Display for Metrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "partscene eval: {}", self.source)?;
        writeln!(
            f,
            "{:>6}  {:<12} {:>9} {:>8} {:>6} {:>6} {:>7} {:>9}",
            "object", "category", "parts t/m", "chamfer", "iou", "ap", "types", "axis(deg)"
        )?;
        for o in &self.objects {
            writeln!(
                f,
                "{:>6}  {:<12} {:>9} {:>8} {:>6} {:>6} {:>7} {:>9}",
                o.id,
                o.category,
                format!("{}/{}", o.truth_parts, o.predicted_parts),
                opt(o.chamfer, 3),
                opt(o.iou, 3),
                opt(o.ap, 3),
                format!("{}/{}", o.correct_types, o.joints.len()),
                opt(geometry::mean(o.axis_errors_deg()), 2),
            )?;
        }
        let m = &self.summary;
        writeln!(f, "mean Chamfer (unit box, lower is better): {}", opt(m.mean_chamfer, 3))?;
        writeln!(f, "mean IoU (32^3, higher is better):        {}", opt(m.mean_iou, 3))?;
        write!(f, "kinematic-edge mAP ({} objects):          {}", m.objects_with_edges, opt(m.map, 3))?;
        if !m.map_by_category.is_empty() {
            let parts: Vec<String> = m.map_by_category.iter().map(|(c, v)| format!("{c} {v:.3}")).collect();
            write!(f, "  ({})", parts.join(", "))?;
        }
        writeln!(f)?;
        writeln!(
            f,
            "joint type accuracy: {} ({}/{}), movable {} ({}/{})",
            percent(m.joint_type_accuracy),
            m.correct_types,
            m.joints,
            percent(m.movable_type_accuracy),
            m.movable_correct_types,
            m.movable_joints
        )?;
        writeln!(
            f,
            "axis error (deg, {} joints): median {}, mean {}; hinge distance (m, {} joints): median {}; prismatic origin distance (m, {} joints): median {}",
            m.axes_measured,
            opt(m.median_axis_error_deg, 2),
            opt(m.mean_axis_error_deg, 2),
            m.hinges_measured,
            opt(m.median_hinge_distance_m, 3),
            m.prismatic_origins_measured,
            opt(m.median_prismatic_origin_distance_m, 3)
        )?;
        if m.missing_parts > 0 {
            let missing: Vec<String> = self.objects.iter().flat_map(|o| o.missing_parts.iter().map(ToString::to_string)).collect();
            writeln!(f, "truth parts missing from the model: {}", missing.join(", "))?;
        }
        if !m.unmatched_model_objects.is_empty() {
            let ids: Vec<String> = m.unmatched_model_objects.iter().map(ToString::to_string).collect();
            writeln!(f, "model objects not in the truth: {}", ids.join(", "))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{Joint, JointKind};
    use crate::math::Vec3;
    use crate::model::{ContactEdge, ObjectModel, PartModel};
    use crate::truth::{TRUTH_FORMAT, TruthObject, TruthPart};

    fn cuboid(center: Vec3, size: Vec3) -> Primitive {
        Primitive::cuboid_at(center, size)
    }

    fn joint(parent: PartId, child: PartId, kind: JointKind, axis: Vec3, origin: Vec3) -> Joint {
        Joint { parent, child, kind, axis_world: axis, origin_world: origin, lower: 0.0, upper: 1.0 }
    }

    /// A cabinet: body 1, door 2 (revolute about z at x = 0.3, y = -0.2), drawer 3 (prismatic
    /// along -y), handle 4 (fixed to the door), top 5 (fixed).
    fn cabinet_truth() -> GroundTruth {
        let body = cuboid(Vec3::new(0.0, 0.0, 0.4), Vec3::new(0.6, 0.4, 0.8));
        let part = |id: PartId, label: &str, shape: Primitive| TruthPart { id, label: label.into(), shapes: vec![shape], meshes: vec![] };
        let truth_object = TruthObject {
            id: 7,
            category: "cabinet".into(),
            supported_by: None,
            parts: vec![
                part(1, "body", body),
                part(2, "door", cuboid(Vec3::new(0.0, -0.21, 0.6), Vec3::new(0.6, 0.02, 0.4))),
                part(3, "drawer", cuboid(Vec3::new(0.0, -0.05, 0.2), Vec3::new(0.56, 0.3, 0.3))),
                part(4, "handle", cuboid(Vec3::new(-0.2, -0.24, 0.6), Vec3::new(0.02, 0.04, 0.1))),
                part(5, "top", cuboid(Vec3::new(0.0, 0.0, 0.81), Vec3::new(0.6, 0.4, 0.02))),
            ],
            joints: vec![
                joint(1, 2, JointKind::Revolute, Vec3::Z, Vec3::new(0.3, -0.2, 0.6)),
                joint(1, 3, JointKind::Prismatic, -Vec3::Y, Vec3::new(0.0, -0.2, 0.2)),
                joint(2, 4, JointKind::Fixed, Vec3::Z, Vec3::ZERO),
                joint(1, 5, JointKind::Fixed, Vec3::Z, Vec3::ZERO),
            ],
            contact_edges: vec![[1, 2], [1, 3], [2, 4], [1, 5]],
        };
        GroundTruth { format: TRUTH_FORMAT.into(), objects: vec![truth_object], floor_z: 0.0 }
    }

    fn model_from_truth(truth: &GroundTruth) -> SceneModel {
        let object = &truth.objects[0];
        let parts = object
            .parts
            .iter()
            .map(|p| PartModel {
                id: p.id,
                object: object.id,
                label: p.label.clone(),
                primitive: p.shapes[0],
                fit_error: 0.0,
                point_count: 100,
                points_span: None,
            })
            .collect();
        let contact_edges =
            object.joints.iter().map(|j| ContactEdge { parent: j.parent, child: j.child, weight: 0.9, in_tree: true }).collect();
        SceneModel {
            source: "test".into(),
            parts,
            joints: object.joints.clone(),
            contact_edges,
            objects: vec![ObjectModel { id: object.id, category: object.category.clone(), root_part: 1, supported_by_part: None }],
            ..SceneModel::default()
        }
    }

    #[test]
    fn a_perfect_reconstruction_scores_perfectly() {
        let truth = cabinet_truth();
        let model = model_from_truth(&truth);
        let m = evaluate(&model, &truth);
        let o = &m.objects[0];
        assert!(o.chamfer.expect("chamfer") < 1e-5);
        assert_eq!(o.iou, Some(1.0));
        assert_eq!(o.ap, Some(1.0));
        assert_eq!(m.summary.map, Some(1.0));
        assert_eq!(m.summary.map_by_category.get("cabinet"), Some(&1.0));
        assert_eq!(m.summary.joint_type_accuracy, Some(1.0));
        assert_eq!(m.summary.movable_type_accuracy, Some(1.0));
        assert_eq!(m.summary.axes_measured, 2);
        assert_eq!(m.summary.hinges_measured, 1);
        assert!(m.summary.median_axis_error_deg.expect("axis") < 1e-3);
        assert!(m.summary.median_hinge_distance_m.expect("hinge") < 1e-6);
        assert!(m.summary.unmatched_model_objects.is_empty());
    }

    #[test]
    fn a_part_the_scan_never_saw_is_not_scored_but_reported() {
        let truth = cabinet_truth();
        let mut model = model_from_truth(&truth);
        model.parts.retain(|p| p.id != 5);
        model.joints.retain(|j| j.child != 5);
        let m = evaluate(&model, &truth);
        let o = &m.objects[0];
        assert_eq!(o.unobserved_parts, vec![5]);
        assert!(o.missing_parts.is_empty());
        assert_eq!(m.summary.joint_type_accuracy, Some(1.0));
        assert_eq!(m.summary.unobserved_parts, 1);
    }

    #[test]
    fn a_reversed_edge_is_scored_as_the_same_joint() {
        let truth = cabinet_truth();
        let mut model = model_from_truth(&truth);
        let fixed = model.joints.iter_mut().find(|j| j.kind == JointKind::Fixed).expect("a fixed joint");
        std::mem::swap(&mut fixed.parent, &mut fixed.child);
        let m = evaluate(&model, &truth);
        assert_eq!(m.summary.joint_type_accuracy, Some(1.0));
    }

    #[test]
    fn a_knob_hung_off_a_part_welded_to_its_truth_parent_has_its_parent_right_but_not_the_same_part() {
        // The truth hangs a knob 6 off the body 1 and welds the top 5 to the body; a model that
        // hangs the knob off the top moves it alike (one rigid body). Off the door 2, it does not.
        let mut truth = cabinet_truth();
        let knob = cuboid(Vec3::new(0.2, 0.0, 0.83), Vec3::new(0.04, 0.04, 0.03));
        truth.objects[0].parts.push(TruthPart { id: 6, label: "knob".into(), shapes: vec![knob], meshes: vec![] });
        truth.objects[0].joints.push(joint(1, 6, JointKind::Revolute, Vec3::Z, Vec3::new(0.2, 0.0, 0.83)));
        let row_of_knob = |parent: PartId| {
            let mut model = model_from_truth(&truth);
            model.joints.last_mut().expect("the knob's joint").parent = parent;
            let m = evaluate(&model, &truth);
            let row = m.objects[0].joints.iter().find(|j| j.child == 6).cloned().expect("the knob's row");
            (row.parent_correct, row.parent_same_part)
        };
        assert_eq!(row_of_knob(1), (true, true));
        assert_eq!(row_of_knob(5), (true, false));
        assert_eq!(row_of_knob(2), (false, false));
    }

    #[test]
    fn joint_errors_and_wrong_types_are_measured() {
        let truth = cabinet_truth();
        let mut model = model_from_truth(&truth);
        // Door axis tilted 3° about x and hinge moved 5 cm sideways; drawer predicted revolute
        // (wrong type); handle predicted revolute (wrong type); top part missing from the model.
        let tilt = crate::math::Quat::from_rotation_x(3.0_f32.to_radians());
        model.joints[0].axis_world = tilt * Vec3::Z;
        model.joints[0].origin_world += Vec3::new(0.05, 0.0, 0.0);
        model.joints[1].kind = JointKind::Revolute;
        model.joints[2].kind = JointKind::Revolute;
        model.parts.retain(|p| p.id != 5);
        model.joints.retain(|j| j.child != 5);
        model.skipped_parts = vec![5]; // in the scan, lost by fitting
        let m = evaluate(&model, &truth);
        let o = &m.objects[0];
        assert_eq!(o.missing_parts, vec![5]);
        assert_eq!(o.correct_types, 1); // only the door
        assert_eq!(o.movable_joints, 2);
        assert_eq!(o.movable_correct_types, 1);
        assert_eq!(m.summary.joint_type_accuracy, Some(0.25));
        assert_eq!(m.summary.movable_type_accuracy, Some(0.5));
        let axis = m.summary.median_axis_error_deg.expect("axis");
        assert!((axis - 3.0).abs() < 0.01, "{axis}");
        // Hinge: the line through (0.35, -0.2, 0.6) tilted about x vs the vertical line through
        // (0.3, -0.2, 0.6): their common normal is x, the offset along it 0.05 m.
        let hinge = m.summary.median_hinge_distance_m.expect("hinge");
        assert!((hinge - 0.05).abs() < 1e-4, "{hinge}");
        let top = o.joints.iter().find(|j| j.child == 5).expect("top row");
        assert!(top.part_missing && !top.type_correct && top.predicted_kind.is_none());
        // Edges: 3 predicted, all true, 4 truth edges → AP = 3/4.
        assert_eq!(o.predicted_edges, 3);
        assert!((o.ap.expect("ap") - 0.75).abs() < 1e-6);
        // The summary mentions the missing part.
        let text = m.to_string();
        assert!(text.contains("missing from the model: 5"), "{text}");
        assert!(m.markdown_table().contains("| 7 | cabinet | 5/4 |"));
    }

    #[test]
    fn edges_are_ranked_by_contact_weight() {
        let truth = cabinet_truth();
        let mut model = model_from_truth(&truth);
        // Replace the handle's parent by the body (a wrong edge 1-4) and give it the top weight:
        // ranking 1-4 ✗ (0.95), then 1-2, 1-3, 1-5 ✓ (0.9, ties by id), truth edge 2-4 missed.
        model.joints[2].parent = 1;
        model.contact_edges.push(ContactEdge { parent: 1, child: 4, weight: 0.95, in_tree: true });
        model.contact_edges.sort_by_key(|c| (c.parent, c.child));
        let m = evaluate(&model, &truth);
        // AP = 1/4 · (1/2 + 2/3 + 3/4).
        let expected = 0.25 * (0.5 + 2.0 / 3.0 + 0.75);
        let ap = m.objects[0].ap.expect("ap");
        assert!((ap - expected).abs() < 1e-6, "{ap} vs {expected}");
    }

    #[test]
    fn metrics_round_trip_through_json() {
        let truth = cabinet_truth();
        let m = evaluate(&model_from_truth(&truth), &truth);
        let json = serde_json::to_string(&m).expect("serialise");
        let back: Metrics = serde_json::from_str(&json).expect("deserialise");
        assert_eq!(back, m);
    }

    #[test]
    fn median_of_even_and_odd_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
    }
}
