//! Export round trips: the URDF of an assembled scene parses back with urdf-rs to the same tree,
//! and loads into rapier3d as a multibody (feature `sim`).

use std::collections::BTreeMap;

use partscene::export::{UrdfConfig, link_name, scene_from_json, scene_json, scene_urdf};
use partscene::kinematics::JointKind;
use partscene::math::Vec3;
use partscene::model::{PartModel, SceneModel};
use partscene::pipeline::{FittedParts, FloorHint, PinnedEdits, PipelineConfig, assemble};
use partscene::primitive::Primitive;

fn part(id: i64, object: i64, label: &str, center: [f32; 3], size: [f32; 3]) -> PartModel {
    PartModel {
        id,
        object,
        label: label.to_owned(),
        primitive: Primitive::cuboid_at(Vec3::from_array(center), Vec3::from_array(size)),
        fit_error: 0.001,
        point_count: 100,
    }
}

/// A cabinet (drawer + door with handles), a table and a microwave standing on it.
fn fitted() -> (FittedParts, BTreeMap<i64, String>) {
    let parts = vec![
        part(1, 1, "body", [0.0, 0.0, 0.5], [0.8, 0.5, 1.0]),
        part(2, 1, "drawer", [0.0, 0.26, 0.85], [0.7, 0.02, 0.2]),
        part(3, 1, "handle", [0.0, 0.285, 0.85], [0.2, 0.03, 0.02]),
        part(4, 1, "door", [0.0, 0.26, 0.35], [0.7, 0.02, 0.6]),
        part(5, 1, "handle", [0.3, 0.285, 0.35], [0.02, 0.03, 0.15]),
        part(10, 2, "top", [2.0, 0.0, 0.73], [1.2, 0.8, 0.04]),
        part(11, 2, "leg", [1.45, -0.35, 0.355], [0.05, 0.05, 0.71]),
        part(12, 2, "leg", [2.55, -0.35, 0.355], [0.05, 0.05, 0.71]),
        part(13, 2, "leg", [1.45, 0.35, 0.355], [0.05, 0.05, 0.71]),
        part(14, 2, "leg", [2.55, 0.35, 0.355], [0.05, 0.05, 0.71]),
        part(20, 3, "body", [2.0, 0.0, 0.91], [0.5, 0.35, 0.3]),
        part(21, 3, "door", [1.95, 0.185, 0.91], [0.38, 0.02, 0.26]),
        part(22, 3, "handle", [2.11, 0.21, 0.91], [0.02, 0.03, 0.2]),
    ];
    let categories = BTreeMap::from([(1, "cabinet".to_owned()), (2, "table".to_owned()), (3, "microwave".to_owned())]);
    (FittedParts { parts, skipped: vec![], warnings: vec![] }, categories)
}

fn scene() -> SceneModel {
    let (fitted, categories) = fitted();
    assemble(&fitted, &categories, FloorHint::Height(0.0), &PipelineConfig::default(), &PinnedEdits::default()).0
}

#[test]
fn assembled_scene_has_the_expected_tree_and_joints() {
    let s = scene();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let parent_of = |c: i64| s.joint_of(c).map(|j| (j.parent, j.kind));
    assert_eq!(parent_of(2), Some((1, JointKind::Prismatic)));
    assert_eq!(parent_of(3), Some((2, JointKind::Fixed)));
    assert_eq!(parent_of(4), Some((1, JointKind::Revolute)));
    assert_eq!(parent_of(5), Some((4, JointKind::Fixed)));
    for leg in 11..=14 {
        assert_eq!(parent_of(leg), Some((10, JointKind::Fixed)));
    }
    assert_eq!(parent_of(21), Some((20, JointKind::Revolute)));
    let door = s.joint_of(4).expect("door joint");
    assert!(door.axis_world.z.abs() > 0.999 && door.origin_world.x < -0.3, "hinge on the edge away from the handle: {door:?}");
    let microwave = s.objects.iter().find(|o| o.id == 3).expect("microwave");
    assert_eq!(microwave.supported_by_part, Some(10), "the microwave stands on the table top");
}

#[test]
fn urdf_parses_back_to_the_same_tree() {
    let s = scene();
    let text = scene_urdf(&s, &UrdfConfig::default()).expect("urdf");
    let robot = urdf_rs::read_from_string(&text).expect("urdf-rs parses our URDF");
    assert_eq!(robot.links.len(), s.parts.len() + 1);
    assert_eq!(robot.joints.len(), s.parts.len(), "one joint into every part link");
    for j in &s.joints {
        let child = link_name(&s, s.part(j.child).expect("child"));
        let parent = link_name(&s, s.part(j.parent).expect("parent"));
        let uj = robot.joints.iter().find(|u| u.child.link == child).expect("joint for child");
        assert_eq!(uj.parent.link, parent);
        let want = match j.kind {
            JointKind::Fixed => urdf_rs::JointType::Fixed,
            JointKind::Prismatic => urdf_rs::JointType::Prismatic,
            JointKind::Revolute => urdf_rs::JointType::Revolute,
        };
        assert_eq!(uj.joint_type, want);
        if j.kind.is_movable() {
            let axis = Vec3::new(uj.axis.xyz[0] as f32, uj.axis.xyz[1] as f32, uj.axis.xyz[2] as f32);
            assert!(axis.dot(j.axis_world) > 0.9999);
            assert!((uj.limit.upper - f64::from(j.upper)).abs() < 1e-6);
        }
    }
    // The microwave's root hangs off the table top, the others off the world.
    let mw_root = link_name(&s, s.part(20).expect("microwave body"));
    let mount = robot.joints.iter().find(|u| u.child.link == mw_root).expect("mount");
    assert_eq!(mount.parent.link, link_name(&s, s.part(10).expect("top")));
}

#[test]
fn scene_json_round_trips() {
    let s = scene();
    let text = scene_json(&s);
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    assert_eq!(v["format"], "partscene-scene/1");
    assert_eq!(v["parts"][0]["primitive"]["kind"], "cuboid");
    assert!(v["joints"][0]["type"].is_string());
    let back = scene_from_json(&text, "scene.json").expect("parse back");
    assert_eq!(back.parts.len(), s.parts.len());
    assert_eq!(back.joints, s.joints);
    assert!(scene_from_json("{\"format\": \"x\"}", "bad.json").is_err());
}

#[cfg(feature = "sim")]
#[test]
fn urdf_loads_into_rapier_as_a_multibody() {
    use rapier3d::prelude::*;
    use rapier3d_urdf::{UrdfLoaderOptions, UrdfMultibodyOptions, UrdfRobot};
    let s = scene();
    let text = scene_urdf(&s, &UrdfConfig::default()).expect("urdf");
    let options = UrdfLoaderOptions { make_roots_fixed: true, ..UrdfLoaderOptions::default() };
    let (robot, parsed) = UrdfRobot::from_str(&text, options, std::path::Path::new(".")).expect("rapier3d-urdf loads it");
    // Joint types survive: count the locked-axis masks.
    let count = |mask: JointAxesMask| robot.joints.iter().filter(|j| j.joint.locked_axes == mask).count();
    let movable = |k: JointKind| s.joints.iter().filter(|j| j.kind == k).count();
    assert_eq!(count(JointAxesMask::LOCKED_PRISMATIC_AXES), movable(JointKind::Prismatic));
    assert_eq!(count(JointAxesMask::LOCKED_REVOLUTE_AXES), movable(JointKind::Revolute));
    assert_eq!(parsed.joints.len(), s.parts.len());
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, 0.0, -9.81);
    let handles = robot.insert_using_multibody_joints(
        &mut world.bodies,
        &mut world.colliders,
        &mut world.multibody_joints,
        UrdfMultibodyOptions::DISABLE_SELF_CONTACTS,
    );
    assert!(handles.joints.iter().filter(|j| j.joint.is_some()).count() >= s.joints.len());
    // A few physics steps stay finite.
    for _ in 0..20 {
        world.step();
    }
    for (_, b) in world.bodies.iter() {
        assert!(b.translation().is_finite());
    }
}
