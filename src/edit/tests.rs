use std::sync::OnceLock;

use super::*;
use crate::pipeline::Quiet;

/// The demo room (seed 0), fitted once for all tests.
fn demo() -> Document {
    static DOC: OnceLock<Document> = OnceLock::new();
    DOC.get_or_init(|| {
        Document::open(SceneSource::Demo { seed: 0, clean: false }, PipelineConfig::default(), PinnedEdits::default(), &Quiet).unwrap()
    })
    .clone()
}

fn label(doc: &Document, id: PartId) -> &str {
    &doc.model().part(id).unwrap().label
}

/// A movable joint whose child carries a handle: (door or drawer, its parent, the handle).
fn door_with_handle(doc: &Document) -> (PartId, PartId, PartId) {
    doc.model()
        .joints
        .iter()
        .filter(|j| j.kind.is_movable())
        .find_map(|j| {
            let handle = doc.model().joints.iter().find(|h| h.parent == j.child && label(doc, h.child).contains("handle"))?;
            Some((j.child, j.parent, handle.child))
        })
        .unwrap()
}

/// A door or lid of the demo hinged by the `hinge` or `lid_hinge` template.
fn hinged_door(doc: &Document) -> PartId {
    doc.model().evidence.iter().find(|e| e.template.is_hinge()).unwrap().child
}

/// Applies `cmd` to the demo and checks the outcome: `Ok(check)` runs `check` on the edited
/// document, `Err(text)` expects a refusal whose message contains `text` and an unchanged scene.
/// Checks run on (before, after) an edit that succeeded.
type Outcome<'a> = Result<&'a dyn Fn(&Document, &Document), &'a str>;

fn check(cmd: impl FnOnce(&Document) -> EditCommand, expected: Outcome<'_>) {
    let mut doc = demo();
    let before = doc.clone();
    let cmd = cmd(&doc);
    match (doc.apply(cmd), expected) {
        (Ok(()), Ok(check)) => check(&before, &doc),
        (Err(e), Err(text)) => {
            assert!(e.to_string().contains(text), "{e}");
            assert_eq!(doc.pins(), before.pins());
            assert_eq!(doc.model().joints, before.model().joints);
            assert!(doc.undo_label().is_none());
        }
        (got, want) => panic!("{cmd:?}: got {got:?}, expected {}", if want.is_ok() { "success" } else { "a refusal" }),
    }
}

#[test]
fn edits_are_pinned_and_refusals_change_nothing() {
    // Re-parent a handle onto the door's parent.
    check(
        |d| {
            let (_, parent, handle) = door_with_handle(d);
            EditCommand::SetParent { child: handle, parent }
        },
        Ok(&|before, after| {
            let (_, parent, handle) = door_with_handle(before);
            assert_eq!(after.model().joint_of(handle).unwrap().parent, parent);
            assert_eq!(after.pins().parent.get(&handle), Some(&parent));
        }),
    );
    // A door under its own handle would be a cycle.
    check(
        |d| {
            let (door, _, handle) = door_with_handle(d);
            EditCommand::SetParent { child: door, parent: handle }
        },
        Err("cycle"),
    );
    check(
        |d| {
            let (door, ..) = door_with_handle(d);
            EditCommand::SetParent { child: door, parent: door }
        },
        Err("own parent"),
    );
    // Parts of two objects.
    check(
        |d| {
            let (door, ..) = door_with_handle(d);
            let object = d.model().part(door).unwrap().object;
            let other = d.model().parts.iter().find(|p| p.object != object).unwrap().id;
            EditCommand::SetParent { child: door, parent: other }
        },
        Err("different objects"),
    );
    // A root has no joint to edit.
    check(|d| EditCommand::SetJointKind { child: d.model().objects[0].root_part, kind: JointKind::Revolute }, Err("has no joint"));
    check(
        |d| {
            let (door, ..) = door_with_handle(d);
            EditCommand::SetLimits { child: door, lower: 1.0, upper: 0.0 }
        },
        Err("lower <= upper"),
    );
    check(|_| EditCommand::SetJointKind { child: 999_999, kind: JointKind::Fixed }, Err("not in the scene"));
    // Flipping an axis reverses it and mirrors the limits: the same motion range.
    check(
        |d| EditCommand::FlipAxis { child: door_with_handle(d).0 },
        Ok(&|before, after| {
            let door = door_with_handle(before).0;
            let (a, b) = (before.model().joint_of(door).unwrap(), after.model().joint_of(door).unwrap());
            assert!((a.axis_world + b.axis_world).length() < 1e-5);
            assert_eq!((b.lower, b.upper), (-a.upper, -a.lower));
        }),
    );
    // A hinge moved to its door's other edge: the pivot mirrors through the door's centre, the
    // evidence says a person chose it, and the axis still opens the door outward.
    check(
        |d| EditCommand::OtherHingeEdge { child: hinged_door(d) },
        Ok(&|before, after| {
            let door = hinged_door(before);
            let (a, b) = (before.model().joint_of(door).unwrap(), after.model().joint_of(door).unwrap());
            // The pivot moves across the door, at least its width, to the other side of its centre.
            let primitive = &before.model().part(door).unwrap().primitive;
            let moved = b.origin_world - a.origin_world;
            let across = moved.normalize();
            assert!(across.dot(a.axis_world).abs() < 1e-3, "{a:?} -> {b:?}");
            assert!(moved.length() >= primitive.extent_along(across) - 1e-3, "{a:?} -> {b:?}");
            let centre = primitive.center();
            assert!((a.origin_world - centre).dot(across) < 0.0 && (b.origin_world - centre).dot(across) > 0.0);
            // Both open the door the same way.
            let step = |j: &crate::kinematics::Joint| j.axis_world.cross(centre - j.origin_world);
            let normal = a.axis_world.cross(across);
            assert!(step(a).dot(normal) * step(b).dot(normal) > 0.0, "both open outward: {a:?} {b:?}");
            let e = after.model().evidence.iter().find(|e| e.child == door).unwrap();
            assert!(e.axis_rule.contains("a person chose") && (e.axis_confidence - 1.0).abs() < 1e-6, "{e:?}");
            assert!(after.pins().hinge_edge.contains_key(&door) && is_pinned(after.pins(), door));
        }),
    );
    // A handle has no hinge edge to move.
    check(|d| EditCommand::OtherHingeEdge { child: door_with_handle(d).2 }, Err("no other edge"));
    // Confirming a joint pins its parent and type as they are; the scene does not change.
    check(
        |d| EditCommand::Confirm { child: door_with_handle(d).0 },
        Ok(&|before, after| {
            let (door, parent, _) = door_with_handle(before);
            assert_eq!(after.pins().parent.get(&door), Some(&parent));
            assert_eq!(after.pins().joint_kind.get(&door), Some(&before.model().joint_of(door).unwrap().kind));
            assert_eq!(after.model().joints, before.model().joints);
        }),
    );
    check(|d| EditCommand::Confirm { child: d.model().objects[0].root_part }, Err("has no joint"));
    // A new primitive kind re-fits the part.
    check(
        |d| EditCommand::SetPrimitiveKind { part: door_with_handle(d).2, kind: PrimitiveKind::Sphere },
        Ok(&|before, after| {
            let handle = door_with_handle(before).2;
            assert_eq!(after.model().part(handle).unwrap().primitive.kind, PrimitiveKind::Sphere);
        }),
    );
}

#[test]
fn undo_and_redo_give_back_exactly_the_scene_before_and_after() {
    let mut doc = demo();
    let original = doc.model().clone();
    let (door, ..) = door_with_handle(&doc);
    doc.apply(EditCommand::SetJointKind { child: door, kind: JointKind::Fixed }).unwrap();
    doc.apply(EditCommand::SetPrimitiveKind { part: door, kind: PrimitiveKind::Cylinder }).unwrap();
    let edited = doc.model().clone();
    assert_eq!(edited.joint_of(door).unwrap().kind, JointKind::Fixed);
    assert_eq!(doc.undo_label(), Some(format!("part {door}: primitive -> cylinder").as_str()));
    assert!(doc.undo().is_some() && doc.undo().is_some());
    assert!(doc.undo().is_none(), "only two edits to take back");
    assert_eq!(doc.model().joints, original.joints);
    assert_eq!(doc.model().part(door).unwrap().primitive, original.part(door).unwrap().primitive);
    assert!(doc.redo().is_some() && doc.redo().is_some());
    assert_eq!(doc.model().joints, edited.joints);
    assert_eq!(doc.model().part(door).unwrap().primitive, edited.part(door).unwrap().primitive);
    // A new edit after an undo drops the redo history.
    doc.undo();
    doc.apply(EditCommand::FlipAxis { child: door }).unwrap();
    assert!(doc.redo_label().is_none());
}

#[test]
fn moving_a_hinge_to_the_other_edge_twice_puts_it_back() {
    let mut doc = demo();
    let door = hinged_door(&doc);
    let original = doc.model().joint_of(door).copied().unwrap();
    doc.apply(EditCommand::OtherHingeEdge { child: door }).unwrap();
    assert_ne!(doc.model().joint_of(door).unwrap().origin_world, original.origin_world);
    doc.apply(EditCommand::OtherHingeEdge { child: door }).unwrap();
    let back = doc.model().joint_of(door).copied().unwrap();
    assert!((back.origin_world - original.origin_world).length() < 1e-5 && back.axis_world.dot(original.axis_world) > 0.9999);
}

#[test]
fn a_flipped_axis_still_opens_the_door_outward_after_its_hinge_moves_to_the_other_edge() {
    // Regression: moving the edge dropped the pinned (flipped) axis and kept the mirrored
    // limits, so the door swung into its cabinet.
    let mut doc = demo();
    let door = hinged_door(&doc);
    let centre = doc.model().part(door).unwrap().primitive.center();
    // Where the door's centre goes at the far end of its range.
    let open_centre = |d: &Document| {
        let j = d.model().joint_of(door).copied().unwrap();
        let q = if j.upper.abs() >= j.lower.abs() { j.upper } else { j.lower };
        j.origin_world + crate::math::Quat::from_axis_angle(j.axis_world, q) * (centre - j.origin_world)
    };
    let outward = open_centre(&doc) - centre;
    doc.apply(EditCommand::FlipAxis { child: door }).unwrap();
    assert!((open_centre(&doc) - centre).dot(outward) > 0.0);
    doc.apply(EditCommand::OtherHingeEdge { child: door }).unwrap();
    let j = doc.model().joint_of(door).copied().unwrap();
    // The door's outward normal: across the axis and the door, on the side it first opened to.
    let normal = j.axis_world.cross(centre - j.origin_world).normalize();
    let normal = if normal.dot(outward) < 0.0 { -normal } else { normal };
    assert!(outward.dot(normal) > 0.05);
    assert!((open_centre(&doc) - centre).dot(normal) > 0.05, "opens into its parent: {j:?}");
}

#[test]
fn confirming_a_door_pins_its_hinge_edge() {
    let mut doc = demo();
    let door = hinged_door(&doc);
    doc.apply(EditCommand::Confirm { child: door }).unwrap();
    assert!(doc.pins().hinge_edge.contains_key(&door));
    assert_eq!(doc.model().evidence.iter().find(|e| e.child == door).unwrap().axis_rule, "hinge on the edge a person chose");
}

#[test]
fn a_saved_session_reopens_to_the_same_scene_and_exports_the_edit() {
    let mut doc = demo();
    let (door, parent, handle) = door_with_handle(&doc);
    doc.apply(EditCommand::SetJointKind { child: door, kind: JointKind::Prismatic }).unwrap();
    doc.apply(EditCommand::SetParent { child: handle, parent }).unwrap();
    let dir = tempfile::tempdir().unwrap();
    doc.session().save(&dir.path().join("session.json")).unwrap();
    let reopened = Document::open_session(&dir.path().join("session.json"), PipelineConfig::default(), &Quiet).unwrap();
    assert_eq!(reopened.model().joints, doc.model().joints);
    let files = reopened.export(&dir.path().join("out")).unwrap();
    let (urdf_path, json_path) = (files.urdf, files.json);
    let robot = urdf_rs::read_file(&urdf_path).unwrap();
    let door_link = crate::export::link_name(reopened.model(), reopened.model().part(door).unwrap());
    let joint = robot.joints.iter().find(|j| j.child.link == door_link).unwrap();
    assert!(matches!(joint.joint_type, urdf_rs::JointType::Prismatic), "{:?}", joint.joint_type);
    let scene = crate::export::read_scene_json(&json_path).unwrap();
    assert_eq!(scene.joint_of(handle).unwrap().parent, parent);
}

#[test]
fn descendants_follow_the_tree() {
    let doc = demo();
    let (door, parent, handle) = door_with_handle(&doc);
    assert!(doc.descendants(door).contains(&handle));
    assert!(doc.descendants(parent).contains(&door) && doc.descendants(parent).contains(&handle));
    assert!(doc.descendants(handle).is_empty());
}
