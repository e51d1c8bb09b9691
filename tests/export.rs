//! Export round trips: the URDF of an assembled scene parses back with urdf-rs to the same tree,
//! and loads into rapier3d as a multibody (feature `sim`); the MJCF reads back through our own
//! MJCF importer with the same joints, limits, geometry and fitted dynamics; the glTF reads back
//! through the `gltf` crate with one node per part along the tree and meshes at the primitives'
//! bounds.

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
        points_span: None,
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
            JointKind::Continuous => urdf_rs::JointType::Continuous,
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

/// A `scene.json` edited into a broken state is refused with the field and the part it names
/// (fuzzing found a support part that did not exist panicking the MJCF export).
#[test]
fn a_scene_json_with_a_dangling_reference_or_a_wild_value_is_refused_with_the_field_named() {
    fn check(edit: impl Fn(&mut serde_json::Value), expected: &str) {
        let mut v: serde_json::Value = serde_json::from_str(&scene_json(&scene())).expect("json");
        edit(&mut v);
        let err = scene_from_json(&v.to_string(), "room/scene.json").expect_err("a broken reference");
        assert_eq!(err.to_string(), expected);
    }
    check(|v| v["parts"][1]["id"] = 1.into(), "room/scene.json: parts: part id 1 appears more than once");
    check(|v| v["joints"][0]["child"] = 99.into(), "room/scene.json: joints[0].child: part 99 is not among the scene's parts");
    check(
        |v| v["joints"][0]["origin_world"][0] = 1e9.into(),
        "room/scene.json: joints[0]: expected a finite axis, limits and an origin within 10000 m of the origin",
    );
    check(
        |v| v["objects"][0]["supported_by_part"] = 77.into(),
        "room/scene.json: objects[0].supported_by_part: part 77 is not among the scene's parts",
    );
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

// ---------------------------------------------------------------------------------------------
// MJCF and glTF.

use partscene::export::{
    DynamicsTable, FittedEffect, dynamics_from_effects, fitted_effects_from_json, joint_name, scene_glb, scene_mjcf, write_scene_files,
};
use partscene::math::{Pose, Quat};
use partscene::primitive::PrimitiveKind;

/// The demo-like scene with every primitive kind and rotated primitives: cylinder legs, a capsule
/// handle lying along x, a sphere knob, a box turned about z.
fn mixed_scene() -> SceneModel {
    let mut s = scene();
    for p in &mut s.parts {
        let c = p.primitive.center();
        p.primitive = match (p.id, p.label.as_str()) {
            (_, "leg") => Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.05, 0.05, 0.71), Pose::from_translation(c)),
            (3, _) => Primitive::new(
                PrimitiveKind::Capsule,
                Vec3::new(0.03, 0.03, 0.2),
                Pose::from_parts(c, Quat::from_rotation_y(std::f32::consts::FRAC_PI_2)),
            ),
            (22, _) => Primitive::new(PrimitiveKind::Sphere, Vec3::splat(0.03), Pose::from_translation(c)),
            (20, _) => Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.5, 0.35, 0.3), Pose::from_parts(c, Quat::from_rotation_z(0.3))),
            _ => p.primitive,
        };
    }
    s
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

#[test]
fn mjcf_reads_back_through_our_importer_with_the_same_joints_and_geometry() {
    for s in [scene(), mixed_scene()] {
        let text = scene_mjcf(&s, &UrdfConfig::default(), &DynamicsTable::new()).expect("mjcf");
        let doc = roxmltree::Document::parse(&text).expect("well-formed XML");
        assert_eq!(doc.root_element().tag_name().name(), "mujoco");
        let compiler = doc.descendants().find(|n| n.has_tag_name("compiler")).expect("compiler");
        assert_eq!(compiler.attribute("angle"), Some("radian"));
        assert_eq!(doc.descendants().filter(|n| n.has_tag_name("body")).count(), s.parts.len());
        let movable = s.joints.iter().filter(|j| j.kind.is_movable()).count();
        assert_eq!(doc.descendants().filter(|n| n.has_tag_name("joint")).count(), movable, "fixed joints are welds");

        let asset = partscene::assets::mjcf::parse_mjcf(&text, std::path::Path::new("scene.mjcf.xml")).expect("our importer reads it");
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
        assert_eq!(asset.links.len(), s.parts.len() + 1, "world + one body per part");
        for j in &s.joints {
            let child = link_name(&s, s.part(j.child).expect("child"));
            let parent = link_name(&s, s.part(j.parent).expect("parent"));
            let aj = asset.joints.iter().find(|a| a.child == child).expect("joint into the child body");
            assert_eq!(aj.parent, parent, "{child}");
            assert_eq!(aj.kind, j.kind, "{child}");
            if j.kind.is_movable() {
                assert_eq!(aj.name, joint_name(&s, s.part(j.child).expect("child")));
                assert!(aj.axis_world.dot(j.axis_world) > 0.9999, "{child}: axis {} vs {}", aj.axis_world, j.axis_world);
                assert!(close(aj.origin_world, j.origin_world, 1e-5), "{child}: origin {} vs {}", aj.origin_world, j.origin_world);
                assert!((aj.lower - j.lower).abs() < 1e-6 && (aj.upper - j.upper).abs() < 1e-6, "{child}: limits");
            }
        }
        // Object roots: on the world, or on the part that supports them.
        for obj in &s.objects {
            let root = link_name(&s, s.part(obj.root_part).expect("root"));
            let aj = asset.joints.iter().find(|a| a.child == root).expect("mount");
            assert_eq!(aj.kind, JointKind::Fixed);
            let want = obj.supported_by_part.map_or_else(|| "world".to_owned(), |p| link_name(&s, s.part(p).expect("support")));
            assert_eq!(aj.parent, want);
        }
        // Geometry: each body holds its primitive, same kind, size and placement.
        for part in &s.parts {
            let link = asset.link(&link_name(&s, part)).expect("body");
            assert_eq!(link.geoms.len(), 1);
            let partscene::assets::GeomShape::Primitive(prim) = &link.geoms[0].shape else { panic!("primitive geom") };
            assert_eq!(prim.kind, part.primitive.kind, "{}", link.name);
            assert!(close(prim.size, part.primitive.size, 1e-5), "{}: size {} vs {}", link.name, prim.size, part.primitive.size);
            assert!(close(prim.center(), part.primitive.center(), 1e-5), "{}: centre", link.name);
            for (a, b) in prim.axes_world().iter().zip(part.primitive.axes_world()) {
                assert!(a.dot(b).abs() > 0.9999, "{}: axes", link.name);
            }
        }
    }
}

#[test]
fn mjcf_inertia_matches_the_urdf_and_the_srdf_pairs_are_excluded() {
    let s = mixed_scene();
    let cfg = UrdfConfig::default();
    let text = scene_mjcf(&s, &cfg, &DynamicsTable::new()).expect("mjcf");
    let robot = urdf_rs::read_from_string(&scene_urdf(&s, &cfg).expect("urdf")).expect("urdf parses");
    let doc = roxmltree::Document::parse(&text).expect("xml");
    for body in doc.descendants().filter(|n| n.has_tag_name("body")) {
        let name = body.attribute("name").expect("name");
        let inertial = body.children().find(|n| n.has_tag_name("inertial")).expect("inertial");
        let mass: f64 = inertial.attribute("mass").expect("mass").parse().expect("number");
        let link = robot.links.iter().find(|l| l.name == name).expect("same link in the URDF");
        assert!((mass - link.inertial.mass.value).abs() < 1e-4 * mass.max(1.0), "{name}: {mass} vs {}", link.inertial.mass.value);
    }
    let excluded: Vec<(String, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("exclude"))
        .map(|n| (n.attribute("body1").unwrap_or("").to_owned(), n.attribute("body2").unwrap_or("").to_owned()))
        .collect();
    let name = |id| link_name(&s, s.part(id).expect("part"));
    let has = |a: i64, b: i64| excluded.iter().any(|(x, y)| (*x == name(a) && *y == name(b)) || (*x == name(b) && *y == name(a)));
    // Exactly the SRDF's pairs: a parent and child, or parts touching at rest.
    let collisions = partscene::export::collision_set(&s, cfg.collision_clearance_m);
    let mut srdf_pairs: Vec<(String, String)> = collisions.disabled.iter().map(|&(a, b, _)| (name(a), name(b))).collect();
    srdf_pairs.extend(collisions.unresolved.iter().map(|&(a, b, _)| (name(a), name(b))));
    for (a, b) in &srdf_pairs {
        assert!(excluded.iter().any(|(x, y)| (x == a && y == b) || (x == b && y == a)), "{a} {b} is in the SRDF, not excluded");
    }
    assert_eq!(
        excluded.len(),
        srdf_pairs.iter().map(|(a, b)| if a < b { (a, b) } else { (b, a) }).collect::<std::collections::BTreeSet<_>>().len()
    );
    assert!(has(1, 2), "a drawer and its carcass welded to the world (MuJoCo's parent filter skips those)");
    assert!(has(20, 21), "the microwave door and its body");
    assert!(!has(11, 12), "two legs apart keep their contacts");
    assert!(!has(2, 20), "different objects apart keep their contacts");
}

#[test]
fn fitted_gap_effects_become_mjcf_joint_dynamics() {
    let s = scene();
    let cfg = UrdfConfig::default();
    let door = s.part(4).expect("door");
    let door_joint = joint_name(&s, door);
    let drawer_joint = joint_name(&s, s.part(2).expect("drawer"));
    let sidecar = serde_json::json!({
        "format": "partscene-gap-fitted/1",
        "model": "scene.urdf",
        "effects": [
            {"joint": door_joint, "kind": "viscous_damping", "params": {"damping": 0.4}, "confidence": 0.9},
            {"joint": door_joint, "kind": "viscous_damping", "params": {"damping": 0.1}},
            {"joint": door_joint, "kind": "coulomb_friction", "params": {"friction": 0.05}},
            {"joint": door_joint, "kind": "spring", "params": {"stiffness": 2.0, "rest_position": 0.3}},
            {"joint": door_joint, "kind": "end_stop", "params": {"position": 1.2, "restitution": 0.2}},
            {"joint": door_joint, "kind": "mass_scale", "params": {"scale": 1.5}},
            {"joint": drawer_joint, "kind": "end_stop", "params": {"position": 0.02, "restitution": 0.92, "contact_time": 0.063}},
            {"joint": drawer_joint, "kind": "soft_close", "params": {"damping": 3.0, "engage_position": 0.05}},
            {"joint": "no_such_joint", "kind": "viscous_damping", "params": {"damping": 1.0}},
        ],
    })
    .to_string();
    let effects: Vec<FittedEffect> = fitted_effects_from_json(&sidecar, "model.fitted.json").expect("sidecar");
    assert_eq!(effects.len(), 9);
    let (table, warnings) = dynamics_from_effects(&s, &cfg, &effects);
    assert_eq!(warnings.len(), 3, "soft close, the unknown joint and the compliant limit's two ends: {warnings:?}");
    assert!(warnings.iter().any(|w| w.message.contains("both limits")), "{warnings:?}");
    let d = table[&door_joint];
    assert!((d.damping - 0.5).abs() < 1e-12 && (d.frictionloss - 0.05).abs() < 1e-12);
    assert!((d.stiffness - 2.0).abs() < 1e-12 && (d.springref - 0.3).abs() < 1e-12);
    let door_j = s.joint_of(4).expect("door joint");
    assert_eq!(d.range, Some([f64::from(door_j.lower), 1.2]), "the stop near the open end narrows the upper limit");
    // Armature = 0.5 × inertia of door + handle about the hinge line (boxes at 600 kg/m³).
    let about_hinge: f32 = [4, 5]
        .iter()
        .map(|&id| {
            let p = s.part(id).expect("part").primitive;
            let m = p.size.x * p.size.y * p.size.z * 600.0;
            let r = (p.center() - door_j.origin_world).truncate().length();
            m * (p.size.x * p.size.x + p.size.y * p.size.y) / 12.0 + m * r * r
        })
        .sum();
    assert!((d.armature - 0.5 * f64::from(about_hinge)).abs() < 1e-4 * d.armature, "{} vs {}", d.armature, 0.5 * about_hinge);
    assert_eq!(table[&drawer_joint].range.map(|r| r[0]), Some(0.02), "the stop near the closed end narrows the lower limit");
    // The compliant drawer stop as MuJoCo's soft limit: the spring–damper with restitution 0.92
    // and 63 ms contacts, (time constant 1/(ζω_n), damping ratio ζ).
    let zeta = -0.92f64.ln() / (std::f64::consts::PI.powi(2) + 0.92f64.ln().powi(2)).sqrt();
    let omega_n = std::f64::consts::PI / 0.063 / (1.0 - zeta * zeta).sqrt();
    let [timeconst, dampratio] = table[&drawer_joint].solreflimit.expect("a compliant stop writes solreflimit");
    assert!((dampratio - zeta).abs() < 1e-12 && (timeconst - 1.0 / (zeta * omega_n)).abs() < 1e-9, "{timeconst} {dampratio}");
    assert_eq!(d.solreflimit, None, "a hard stop keeps MuJoCo's default soft limit");

    let text = scene_mjcf(&s, &cfg, &table).expect("mjcf");
    let doc = roxmltree::Document::parse(&text).expect("xml");
    let joint = doc.descendants().find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(door_joint.as_str())).expect("door");
    let attr = |k: &str| joint.attribute(k).and_then(|v| v.parse::<f64>().ok());
    assert_eq!(attr("damping"), Some(0.5));
    assert_eq!(attr("frictionloss"), Some(0.05));
    assert_eq!(attr("stiffness"), Some(2.0));
    assert_eq!(attr("springref"), Some(0.3));
    assert!(attr("armature").is_some_and(|a| (a - d.armature).abs() < 1e-9));
    let drawer = doc.descendants().find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(drawer_joint.as_str())).expect("drawer");
    let written: Vec<f64> = drawer.attribute("solreflimit").expect("solreflimit").split(' ').map(|v| v.parse().expect("number")).collect();
    assert!((written[0] - timeconst).abs() < 1e-6 * timeconst && (written[1] - dampratio).abs() < 1e-6);
    let asset = partscene::assets::mjcf::parse_mjcf(&text, std::path::Path::new("x.xml")).expect("reads back");
    let aj = asset.joints.iter().find(|j| j.name == door_joint).expect("door joint");
    assert!((aj.upper - 1.2).abs() < 1e-6);
    // Without effects nothing is written.
    let plain = scene_mjcf(&s, &cfg, &DynamicsTable::new()).expect("mjcf");
    assert!(!plain.contains("damping=") && !plain.contains("armature="));

    assert!(fitted_effects_from_json("{\"format\": \"other\", \"effects\": []}", "x.json").is_err());
    assert!(fitted_effects_from_json("not json", "x.json").is_err());
}

/// World (scene, z-up) transform of every node of a glTF document, by node index.
fn gltf_world(doc: &gltf::Document) -> BTreeMap<usize, glam::Mat4> {
    let mut out = BTreeMap::new();
    let mut stack: Vec<(gltf::Node, glam::Mat4)> = doc.default_scene().expect("scene").nodes().map(|n| (n, glam::Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let m = parent * glam::Mat4::from_cols_array_2d(&node.transform().matrix());
        out.insert(node.index(), m);
        stack.extend(node.children().map(|c| (c, m)));
    }
    out
}

#[test]
fn glb_reads_back_with_one_node_per_part_along_the_tree_and_meshes_at_the_primitive_bounds() {
    let s = mixed_scene();
    let bytes = scene_glb(&s).expect("glb");
    let gltf::Gltf { document: doc, blob } = gltf::Gltf::from_slice(&bytes).expect("the gltf crate reads it");
    let blob = blob.expect("binary chunk");
    // The crate is built without its `names`/`extras` features: read those from the JSON chunk.
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).expect("JSON chunk");
    let node_name = |n: &gltf::Node| json["nodes"][n.index()]["name"].as_str().expect("named node").to_owned();
    assert_eq!(doc.nodes().count(), s.parts.len() + 1, "a y-up root plus one node per part");
    let root = doc.default_scene().expect("scene").nodes().next().expect("root");
    assert_eq!(node_name(&root), "partscene");
    // The root turns z-up into y-up: scene +z becomes glTF +y.
    let world = gltf_world(&doc);
    let up = world[&root.index()].transform_vector3(glam::Vec3::Z);
    assert!(up.abs_diff_eq(glam::Vec3::Y, 1e-6), "{up}");
    let scene_from_gltf = world[&root.index()].inverse();
    let mut parent_of: BTreeMap<String, String> = BTreeMap::new();
    for node in doc.nodes() {
        for c in node.children() {
            parent_of.insert(node_name(&c), node_name(&node));
        }
    }
    for j in &s.joints {
        let child = link_name(&s, s.part(j.child).expect("child"));
        assert_eq!(parent_of.get(&child), Some(&link_name(&s, s.part(j.parent).expect("parent"))), "{child}");
    }
    let mw_root = link_name(&s, s.part(20).expect("microwave"));
    assert_eq!(parent_of.get(&mw_root), Some(&link_name(&s, s.part(10).expect("top"))));
    let cabinet_root = link_name(&s, s.part(1).expect("cabinet"));
    assert_eq!(parent_of.get(&cabinet_root).map(String::as_str), Some("partscene"));
    // Meshes: in each primitive's own frame the mesh spans exactly ± half its size.
    for node in doc.nodes().filter(|n| n.index() != root.index()) {
        let name = node_name(&node);
        let part = s.parts.iter().find(|p| link_name(&s, p) == name).expect("node named after a part");
        let mesh = node.mesh().expect("mesh");
        let prim_gltf = mesh.primitives().next().expect("one primitive");
        assert!(prim_gltf.material().index().is_some());
        let reader = prim_gltf.reader(|_| Some(&blob));
        let m = scene_from_gltf * world[&node.index()];
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        let mut count = 0;
        for p in reader.read_positions().expect("positions") {
            let w = m.transform_point3(glam::Vec3::from_array(p));
            let local = part.primitive.world_from_primitive.inverse_transform_point(Vec3::new(w.x, w.y, w.z));
            lo = lo.min(local);
            hi = hi.max(local);
            count += 1;
        }
        assert!(count >= 24);
        let h = part.primitive.size * 0.5;
        assert!(close(hi, h, 1e-5) && close(lo, -h, 1e-5), "{name} ({:?}): [{lo}, {hi}] vs ±{h}", part.primitive.kind);
        let tri = reader.read_indices().expect("indices").into_u32().count();
        assert_eq!(tri % 3, 0);
        assert_eq!(json["nodes"][node.index()]["extras"]["part"], part.id);
    }
}

/// `objects/<name>.urdf`, `.srdf` and `.xml` per object, indexed by `scene_objects.json`: each
/// holds that object's parts and joints only, its root first, and reads back.
#[test]
fn every_object_gets_its_own_urdf_srdf_and_mjcf_that_read_back() {
    let s = mixed_scene();
    let dir = tempfile::tempdir().expect("tmp");
    write_scene_files(dir.path(), &s, &UrdfConfig::default()).expect("written");
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scene_objects.json")).expect("index")).expect("json");
    assert_eq!(index["format"], "partscene-scene-objects/1");
    let entries = index["objects"].as_array().expect("objects");
    assert_eq!(entries.len(), s.objects.len());
    for entry in entries {
        let id = entry["id"].as_i64().expect("id");
        let parts: Vec<&PartModel> = s.parts.iter().filter(|p| p.object == id).collect();
        let names: Vec<String> = parts.iter().map(|p| link_name(&s, p)).collect();
        let movable = s.joints.iter().filter(|j| j.kind.is_movable() && parts.iter().any(|p| p.id == j.child)).count();
        let read = |key: &str| std::fs::read_to_string(dir.path().join(entry[key].as_str().expect("path"))).expect("file");

        let robot = urdf_rs::read_from_string(&read("urdf")).expect("the object's URDF parses");
        assert_eq!(robot.links.len(), parts.len(), "object {id}");
        assert_eq!(robot.links[0].name, entry["root_link"].as_str().expect("root"), "root link first");
        assert!(robot.links.iter().all(|l| names.contains(&l.name)), "object {id}: only its own links");
        assert_eq!(robot.joints.iter().filter(|j| !matches!(j.joint_type, urdf_rs::JointType::Fixed)).count(), movable);

        let asset = partscene::assets::mjcf::parse_mjcf(&read("mjcf"), std::path::Path::new("object.xml")).expect("the object's MJCF");
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
        assert_eq!(asset.links.len(), parts.len() + 1, "object {id}: world + one body per part");
        assert_eq!(asset.joints.iter().filter(|j| j.kind.is_movable()).count(), movable, "object {id}");
        let root = asset.link(entry["root_link"].as_str().expect("root")).expect("root body");
        assert!(close(root.world_from_link.translation, Vec3::ZERO, 1e-6), "object {id}: root body at the origin");

        let srdf = read("srdf");
        let doc = roxmltree::Document::parse(&srdf).expect("SRDF is XML");
        for pair in doc.descendants().filter(|n| n.has_tag_name("disable_collisions")) {
            for key in ["link1", "link2"] {
                let link = pair.attribute(key).expect("link");
                assert!(names.iter().any(|n| n == link), "object {id}: SRDF names {link} of another object");
            }
        }
    }
}

/// A part sunk deep into a part it is not joined to (a latch through its door into the frame)
/// cannot be trimmed free: the URDF, which has no pair filter, gives it no collision shape, the SRDF
/// says so, and the MJCF excludes the pair. Regression: a reconstructed door with such a latch
/// swung open by 69 degrees at rest in `PyBullet` with self-collision on.
#[test]
fn a_part_sunk_into_a_part_it_is_not_joined_to_loses_its_urdf_collision_shape() {
    let mut s = scene();
    // The door's handle pushed 25 cm into the carcass, through the door.
    let handle = s.parts.iter_mut().find(|p| p.id == 5).expect("handle");
    handle.primitive = Primitive::cuboid_at(Vec3::new(0.3, 0.15, 0.35), Vec3::new(0.02, 0.3, 0.15));
    let cfg = UrdfConfig::default();
    let collisions = partscene::export::collision_set(&s, cfg.collision_clearance_m);
    assert!(collisions.unresolved.iter().any(|&(a, b, _)| (a, b) == (1, 5)), "{:?}", collisions.unresolved);
    assert_eq!(collisions.without_collision.iter().copied().collect::<Vec<_>>(), vec![5]);
    let robot = urdf_rs::read_from_string(&scene_urdf(&s, &cfg).expect("urdf")).expect("parses");
    let link = |id: i64| robot.links.iter().find(|l| l.name == link_name(&s, s.part(id).expect("part"))).expect("link");
    assert!(link(5).collision.is_empty() && !link(5).visual.is_empty(), "no collision shape, the visual stays");
    assert!(!link(4).collision.is_empty(), "the door keeps its own");
    let srdf = partscene::export::srdf(&s, "partscene", &collisions, |_, _| true);
    assert!(srdf.contains(&format!("the URDF gives {} no collision shape", link(5).name)), "{srdf}");
    let mjcf = scene_mjcf(&s, &cfg, &DynamicsTable::new()).expect("mjcf");
    let (body, handle) = (link_name(&s, s.part(1).expect("body")), link(5).name.clone());
    assert!(mjcf.contains(&format!("<exclude body1=\"{body}\" body2=\"{handle}\"/>")), "{mjcf}");
}

/// Clearance holds along the motion, not only at rest: a door whose fitted hinge leans half a
/// degree lifts its far edge into the deep drawer above it as it opens, so the door's collision
/// shape is trimmed by what the swing needs. Regression: a demo refrigerator's door stopped at
/// 0.38 rad of 1.57 in `PyBullet` with self-collision on, blocked by the part above it.
#[test]
fn a_door_with_a_leaning_hinge_is_kept_clear_of_the_drawer_above_over_its_swing() {
    let mut s = scene();
    // A deep drawer right on top of the door (door top at z = 0.65), reaching over its swing.
    let drawer = s.parts.iter_mut().find(|p| p.id == 2).expect("drawer");
    drawer.primitive = Primitive::cuboid_at(Vec3::new(0.0, 0.3, 0.75), Vec3::new(0.8, 1.1, 0.2));
    let lean = 0.5_f32.to_radians();
    let door = s.joints.iter_mut().find(|j| j.child == 4).expect("door joint");
    door.axis_world = Vec3::new(lean.sin(), 0.0, lean.cos()) * door.axis_world.z.signum();
    let cfg = UrdfConfig::default();
    let collisions = partscene::export::collision_set(&s, cfg.collision_clearance_m);
    assert!(!collisions.unresolved.iter().any(|&(a, b, _)| (a, b) == (2, 4)), "{:?}", collisions.unresolved);
    let lowered = 0.65 - collisions.primitives[&4].aabb().1.z;
    // At rest 2 mm would do; the far edge of a 0.7 m door leaning 0.5° rises about 6 mm.
    assert!(lowered > 0.006 && lowered <= partscene::export::MAX_TRIM_M + 1e-6, "door top lowered by {lowered} m");
}

#[test]
fn scene_files_are_all_written_and_a_broken_scene_writes_none() {
    let dir = tempfile::tempdir().expect("tmp");
    let files = write_scene_files(dir.path(), &scene(), &UrdfConfig::default()).expect("written");
    for p in files.all() {
        assert!(std::fs::metadata(p).expect("exists").len() > 0, "{}", p.display());
    }
    assert_eq!(files.mjcf.file_name().and_then(|f| f.to_str()), Some("scene.mjcf.xml"));
    assert_eq!(files.glb.file_name().and_then(|f| f.to_str()), Some("scene.glb"));
    let mut broken = scene();
    broken.parts[3].primitive.size.x = f32::NAN;
    let other = dir.path().join("broken");
    let err = write_scene_files(&other, &broken, &UrdfConfig::default()).expect_err("NaN size");
    assert!(err.to_string().contains("non-finite size"), "{err}");
    assert!(!other.join("scene.urdf").exists() && !other.join("scene.glb").exists());
    // An empty scene still gives valid files.
    let empty = SceneModel::default();
    let bytes = scene_glb(&empty).expect("glb");
    assert_eq!(gltf::Gltf::from_slice(&bytes).expect("valid").document.nodes().count(), 1);
    roxmltree::Document::parse(&scene_mjcf(&empty, &UrdfConfig::default(), &DynamicsTable::new()).expect("mjcf")).expect("xml");
}

/// The attribute lines (`type name = value` → name → value) directly inside the prim whose
/// definition line ends with `"name"`, in a `.usda` text.
fn usd_prim_attrs(text: &str, name: &str) -> BTreeMap<String, String> {
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().position(|l| l.trim_start().starts_with("def ") && l.contains(&format!("\"{name}\""))).expect("prim");
    let mut out = BTreeMap::new();
    let mut depth = 0;
    for line in &lines[start + 1..] {
        let t = line.trim();
        match t {
            "{" => depth += 1,
            "}" => {
                depth -= 1;
                if depth == 0 {
                    break;
                }
            }
            _ if depth == 1 => {
                if let Some((lhs, value)) = t.split_once(" = ") {
                    let key = lhs.split_whitespace().last().expect("name");
                    out.insert(key.to_owned(), value.to_owned());
                }
            }
            _ => {}
        }
    }
    out
}

#[test]
fn usd_has_an_articulation_per_object_joints_in_degrees_and_the_fitted_dynamics_in_usd_units() {
    use partscene::export::{DynamicsTable, dynamics_from_effects, fitted_effects_from_json, joint_name, scene_usda};
    let s = scene();
    let cfg = UrdfConfig::default();
    let plain = scene_usda(&s, &cfg, &DynamicsTable::new()).expect("usd");
    assert!(plain.starts_with("#usda 1.0"));
    // The cabinet, the table and the microwave: three articulations, one rigid body per part.
    assert_eq!(plain.matches("\"PhysicsArticulationRootAPI\"").count(), 3);
    assert_eq!(plain.matches("\"PhysicsRigidBodyAPI\", \"PhysicsMassAPI\"").count(), s.parts.len());
    assert_eq!(plain.matches("_to_world\"").count(), 3, "each object's root fixed to the world");
    let door_joint = joint_name(&s, s.part(4).expect("door"));
    let drawer_joint = joint_name(&s, s.part(2).expect("drawer"));
    let door = usd_prim_attrs(&plain, &door_joint);
    let door_j = s.joint_of(4).expect("door joint");
    let value = |m: &BTreeMap<String, String>, k: &str| m.get(k).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN);
    assert!((value(&door, "physics:upperLimit") - f64::from(door_j.upper).to_degrees()).abs() < 1e-3, "{door:?}");
    assert_eq!(door.get("physics:axis").map(String::as_str), Some("\"X\""));
    let drawer = usd_prim_attrs(&plain, &drawer_joint);
    assert!((value(&drawer, "physics:upperLimit") - f64::from(s.joint_of(2).expect("drawer").upper)).abs() < 1e-6, "metres");
    assert!(!plain.contains("drive:") && !plain.contains("physxJointAxis:"), "no fitted dynamics, none written");

    let sidecar = serde_json::json!({"format": "partscene-gap-fitted/1", "effects": [
        {"joint": door_joint, "kind": "viscous_damping", "params": {"damping": 0.5}},
        {"joint": door_joint, "kind": "coulomb_friction", "params": {"friction": 0.05}},
        {"joint": door_joint, "kind": "spring", "params": {"stiffness": 2.0, "rest_position": 0.3}},
        {"joint": drawer_joint, "kind": "viscous_damping", "params": {"damping": 4.0}},
        {"joint": drawer_joint, "kind": "armature", "params": {"armature": 0.2}},
    ]})
    .to_string();
    let (table, _) = dynamics_from_effects(&s, &cfg, &fitted_effects_from_json(&sidecar, "x.json").expect("sidecar"));
    let fitted = scene_usda(&s, &cfg, &table).expect("usd");
    let door = usd_prim_attrs(&fitted, &door_joint);
    // Rotational drives are per degree, targets in degrees.
    assert!((value(&door, "drive:angular:physics:damping") - 0.5_f64.to_radians()).abs() < 1e-9, "{door:?}");
    assert!((value(&door, "drive:angular:physics:stiffness") - 2.0_f64.to_radians()).abs() < 1e-9);
    assert!((value(&door, "drive:angular:physics:targetPosition") - 0.3_f64.to_degrees()).abs() < 1e-9);
    assert!((value(&door, "physxJointAxis:angular:staticFrictionEffort") - 0.05).abs() < 1e-12);
    let drawer = usd_prim_attrs(&fitted, &drawer_joint);
    assert!((value(&drawer, "drive:linear:physics:damping") - 4.0).abs() < 1e-12, "per metre, no degree conversion");
    assert!((value(&drawer, "physxJointAxis:linear:armature") - 0.2).abs() < 1e-12);
}
