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
