//! The object-level baseline scored like a reconstruction, and totals over several runs (the
//! demo's `--count`, the asset benchmark).

use std::fmt;

use serde::{Deserialize, Serialize};

use super::geometry::{GeometryScore, GeometrySummary, evaluate_geometry, mean};
use super::median;
use super::{Metrics, object_level_baseline};
use crate::scan::Scan;
use crate::truth::GroundTruth;

/// Geometry scores of the object-level baseline on one scan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BaselineMetrics {
    pub objects: Vec<GeometryScore>,
    pub summary: GeometrySummary,
}

/// Runs the object-level baseline on a scan and scores it against the truth.
#[must_use]
pub fn evaluate_baseline(scan: &Scan, truth: &GroundTruth) -> BaselineMetrics {
    let objects = evaluate_geometry(&object_level_baseline(scan), truth);
    let summary = GeometrySummary::of(&objects);
    BaselineMetrics { objects, summary }
}

impl fmt::Display for BaselineMetrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let show = |v: Option<f32>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.3}"));
        write!(
            f,
            "mean Chamfer {}, mean IoU {} over {} objects",
            show(self.summary.mean_chamfer),
            show(self.summary.mean_iou),
            self.summary.objects
        )
    }
}

/// Totals over runs: joint counts summed, axis errors pooled, per-run means averaged.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Aggregate {
    pub runs: usize,
    pub joints: usize,
    pub correct_types: usize,
    pub joint_type_accuracy: Option<f32>,
    pub movable_joints: usize,
    pub movable_correct_types: usize,
    pub movable_type_accuracy: Option<f32>,
    pub axes_measured: usize,
    pub median_axis_error_deg: Option<f32>,
    pub max_axis_error_deg: Option<f32>,
    pub median_hinge_distance_m: Option<f32>,
    /// Median prismatic origin distance over runs, metres.
    #[serde(default)]
    pub median_prismatic_origin_distance_m: Option<f32>,
    /// Mean over runs of each run's mAP.
    pub map: Option<f32>,
    pub min_run_map: Option<f32>,
    pub part_level_chamfer: Option<f32>,
    pub object_level_chamfer: Option<f32>,
    pub part_level_iou: Option<f32>,
    pub object_level_iou: Option<f32>,
    /// Runs in which part-level beats object-level on both Chamfer and `IoU`.
    pub runs_part_level_wins_both: usize,
}

/// Totals over (part-level metrics, baseline metrics) pairs.
pub fn aggregate<'a>(runs: impl Iterator<Item = (&'a Metrics, &'a BaselineMetrics)>) -> Aggregate {
    let mut a = Aggregate::default();
    let mut axes = Vec::new();
    let mut hinges = Vec::new();
    let mut slides = Vec::new();
    let (mut maps, mut pc, mut oc, mut pi, mut oi) = (vec![], vec![], vec![], vec![], vec![]);
    for (m, b) in runs {
        a.runs += 1;
        let s = &m.summary;
        a.joints += s.joints;
        a.correct_types += s.correct_types;
        a.movable_joints += s.movable_joints;
        a.movable_correct_types += s.movable_correct_types;
        for o in &m.objects {
            axes.extend(o.joints.iter().filter_map(|j| j.axis_error_deg));
            hinges.extend(o.joints.iter().filter_map(|j| j.hinge_distance_m));
            slides.extend(o.joints.iter().filter_map(|j| j.prismatic_origin_distance_m));
        }
        maps.extend(s.map);
        pc.extend(s.mean_chamfer);
        pi.extend(s.mean_iou);
        oc.extend(b.summary.mean_chamfer);
        oi.extend(b.summary.mean_iou);
        let wins = matches!((s.mean_chamfer, b.summary.mean_chamfer), (Some(p), Some(o)) if p < o)
            && matches!((s.mean_iou, b.summary.mean_iou), (Some(p), Some(o)) if p > o);
        a.runs_part_level_wins_both += usize::from(wins);
    }
    let ratio = |n: usize, d: usize| (d > 0).then(|| n as f32 / d as f32);
    a.joint_type_accuracy = ratio(a.correct_types, a.joints);
    a.movable_type_accuracy = ratio(a.movable_correct_types, a.movable_joints);
    a.axes_measured = axes.len();
    a.max_axis_error_deg = axes.iter().copied().reduce(f32::max);
    a.median_axis_error_deg = median(&axes);
    a.median_hinge_distance_m = median(&hinges);
    a.median_prismatic_origin_distance_m = median(&slides);
    a.min_run_map = maps.iter().copied().reduce(f32::min);
    a.map = mean(maps.into_iter());
    a.part_level_chamfer = mean(pc.into_iter());
    a.object_level_chamfer = mean(oc.into_iter());
    a.part_level_iou = mean(pi.into_iter());
    a.object_level_iou = mean(oi.into_iter());
    a
}

impl fmt::Display for Aggregate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let show = |v: Option<f32>, d: usize| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.d$}"));
        let pct = |v: Option<f32>| v.map_or_else(|| "-".to_owned(), |v| format!("{:.1}%", 100.0 * v));
        writeln!(
            f,
            "joint type accuracy: {} ({}/{}); movable: {} ({}/{})",
            pct(self.joint_type_accuracy),
            self.correct_types,
            self.joints,
            pct(self.movable_type_accuracy),
            self.movable_correct_types,
            self.movable_joints
        )?;
        writeln!(
            f,
            "axis error: median {}°, max {}° over {} joints; hinge line distance median {} m; prismatic origin distance median {} m",
            show(self.median_axis_error_deg, 2),
            show(self.max_axis_error_deg, 2),
            self.axes_measured,
            show(self.median_hinge_distance_m, 3),
            show(self.median_prismatic_origin_distance_m, 3)
        )?;
        writeln!(f, "kinematic-edge mAP: mean {} (lowest run {})", show(self.map, 3), show(self.min_run_map, 3))?;
        writeln!(
            f,
            "Chamfer (lower is better): part-level {} vs object-level {}",
            show(self.part_level_chamfer, 3),
            show(self.object_level_chamfer, 3)
        )?;
        writeln!(
            f,
            "IoU (higher is better):    part-level {} vs object-level {}",
            show(self.part_level_iou, 3),
            show(self.object_level_iou, 3)
        )?;
        write!(f, "part-level beats object-level on both in {}/{} runs", self.runs_part_level_wins_both, self.runs)
    }
}
