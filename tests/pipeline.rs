//! The whole pipeline on the built-in demo room: the targets on the default seed,
//! reported skips instead of failures, pinned edits, determinism.

use partscene::eval::{evaluate, evaluate_baseline};
use partscene::export::scene_json;
use partscene::kinematics::JointKind;
use partscene::pipeline::{PinnedEdits, PipelineConfig, Quiet, reconstruct};
use partscene::scan::Scan;

fn run(scan: &Scan, edits: &PinnedEdits) -> partscene::model::SceneModel {
    reconstruct(scan, &PipelineConfig::default(), edits, &Quiet)
}

#[test]
fn demo_room_meets_the_accuracy_targets() {
    let (truth, scan) = partscene::synth::demo(0);
    let scene = run(&scan, &PinnedEdits::default());
    let m = evaluate(&scene, &truth);
    let b = evaluate_baseline(&scan, &truth);
    let s = &m.summary;
    eprintln!("{m}\nbaseline: {b}");
    assert_eq!(scene.parts.len(), scan.parts.len(), "every scanned part is fitted: {:?}", scene.warnings);
    assert!(s.joint_type_accuracy.unwrap_or(0.0) >= 0.95, "joint type accuracy {:?}", s.joint_type_accuracy);
    assert!(s.movable_type_accuracy.unwrap_or(0.0) >= 0.95, "movable type accuracy {:?}", s.movable_type_accuracy);
    assert!(s.median_axis_error_deg.unwrap_or(90.0) <= 3.0, "median axis error {:?}", s.median_axis_error_deg);
    assert!(s.map.unwrap_or(0.0) >= 0.95, "kinematic-edge mAP {:?}", s.map);
    let (pc, oc) = (s.mean_chamfer.unwrap_or(9.0), b.summary.mean_chamfer.unwrap_or(0.0));
    let (pi, oi) = (s.mean_iou.unwrap_or(0.0), b.summary.mean_iou.unwrap_or(1.0));
    assert!(pc < oc, "part-level Chamfer {pc} must beat object-level {oc}");
    assert!(pi > oi, "part-level IoU {pi} must beat object-level {oi}");
    // The microwave stands on the table, not on the floor.
    let table = truth.objects.iter().find(|o| o.category == "table").expect("table");
    let microwave = truth.objects.iter().find(|o| o.category == "microwave").expect("microwave");
    let mw = scene.objects.iter().find(|o| o.id == microwave.id).expect("microwave reconstructed");
    let support = mw.supported_by_part.and_then(|p| scene.part(p)).map(|p| p.object);
    assert_eq!(support, Some(table.id), "the microwave's support");
}

#[test]
fn a_part_with_three_points_is_reported_and_the_rest_is_reconstructed() {
    let (_, mut scan) = partscene::synth::demo(0);
    let victim = scan.parts[3].id;
    scan.parts[3].points.truncate(3);
    let scene = run(&scan, &PinnedEdits::default());
    assert!(scene.part(victim).is_none());
    assert!(scene.warnings.iter().any(|w| w.subject == format!("part {victim}") && w.message.contains("point")), "{:?}", scene.warnings);
    assert_eq!(scene.parts.len(), scan.parts.len() - 1);
}

#[test]
fn an_unknown_label_is_a_rigid_part() {
    let (_, mut scan) = partscene::synth::demo(0);
    let drawer = scan.parts.iter_mut().find(|p| p.label == "drawer").expect("a drawer");
    drawer.label = "glorp".to_owned();
    let (id, object) = (drawer.id, drawer.object);
    // With its handle, geometry says what the unnamed part is: a handle centred on a box sunk in
    // the cabinet's front is a drawer.
    let scene = run(&scan, &PinnedEdits::default());
    assert_eq!(scene.joint_of(id).map(|j| j.kind), Some(JointKind::Prismatic));
    // Without any handle nothing says it moves: rigid.
    scan.parts.retain(|p| !(p.object == object && p.label == "handle"));
    let scene = run(&scan, &PinnedEdits::default());
    assert_eq!(scene.joint_of(id).map(|j| j.kind), Some(JointKind::Fixed));
    assert_eq!(scene.part(id).map(|p| p.label.as_str()), Some("glorp"));
}

#[test]
fn pinned_edits_are_kept_by_a_rerun() {
    let (_, scan) = partscene::synth::demo(0);
    let scene = run(&scan, &PinnedEdits::default());
    // Re-parent a handle onto its object's root, and make a drawer revolute.
    let handle = scene.parts.iter().find(|p| p.label == "handle").expect("handle");
    let root = scene.objects.iter().find(|o| o.id == handle.object).expect("object").root_part;
    let drawer = scene.parts.iter().find(|p| p.label == "drawer").expect("drawer").id;
    let mut edits = PinnedEdits::default();
    edits.parent.insert(handle.id, root);
    edits.joint_kind.insert(drawer, JointKind::Revolute);
    let again = run(&scan, &edits);
    assert_eq!(again.joint_of(handle.id).map(|j| j.parent), Some(root));
    assert_eq!(again.joint_of(drawer).map(|j| j.kind), Some(JointKind::Revolute));
}

#[test]
fn reconstruction_is_deterministic() {
    let (_, scan) = partscene::synth::demo(3);
    let a = scene_json(&run(&scan, &PinnedEdits::default()));
    let b = scene_json(&run(&scan, &PinnedEdits::default()));
    assert_eq!(a, b);
}
