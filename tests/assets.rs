//! Importing articulated assets (URDF, MJCF): hand-written snippets with known answers, and every
//! object of the shared benchmark (`/work/shared/data/objects`) against its `gt_kinematics.json`.

use std::f32::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

use partscene::assets::{AssetError, AssetGeom, GeomRole, GeomShape, load_asset};
use partscene::kinematics::JointKind;
use partscene::math::{Vec3, line_line_distance};
use partscene::primitive::PrimitiveKind;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).expect("create the test folder");
    }
    std::fs::write(&path, text).expect("write the test file");
    path
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).length() < tol
}

const CUBE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

#[test]
fn urdf_revolute_door_with_comma_vectors() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "meshes/panel.obj", CUBE_OBJ);
    let path = write(
        dir.path(),
        "door.urdf",
        r#"<?xml version="1.0"?>
<robot name="door">
  <link name="frame"/>
  <joint name="hinge" type="revolute">
    <origin xyz="1.0, 2.0, 0" rpy="0 0 1.5707963"/>
    <parent link="frame"/>
    <child link="panel"/>
    <axis xyz="0 0 1"/>
    <limit lower="0.0" upper="1.5" effort="1" velocity="1"/>
  </joint>
  <link name="panel">
    <visual>
      <origin xyz="0.5, 0, 0"/>
      <geometry><mesh filename="package://door_pkg/meshes/panel.obj" scale="2, 1, 1"/></geometry>
    </visual>
    <visual>
      <geometry><mesh filename="meshes/absent.stl"/></geometry>
    </visual>
    <collision>
      <origin xyz="0.5 0 0"/>
      <geometry><box size="1.0, 0.05, 2.0"/></geometry>
    </collision>
  </link>
  <joint name="knob_spin" type="continuous">
    <origin xyz="0.9 0 0"/>
    <parent link="panel"/>
    <child link="knob"/>
    <axis xyz="1 0 0"/>
  </joint>
  <link name="knob"><collision><geometry><cylinder radius="0.02" length="0.1"/></geometry></collision></link>
</robot>"#,
    );
    let asset = load_asset(&path).unwrap();
    assert_eq!(asset.name, "door");
    assert_eq!(asset.joints.len(), 2);
    let hinge = &asset.joints[0];
    assert_eq!((hinge.kind, hinge.parent.as_str(), hinge.child.as_str()), (JointKind::Revolute, "frame", "panel"));
    assert!(close(hinge.origin_world, Vec3::new(1.0, 2.0, 0.0), 1e-6), "{:?}", hinge.origin_world);
    assert!(close(hinge.axis_world, Vec3::Z, 1e-6));
    assert_eq!((hinge.lower, hinge.upper), (0.0, 1.5));
    // The knob sits 0.9 along the panel's x, which the hinge's yaw turned onto world +y.
    let knob = &asset.joints[1];
    assert_eq!(knob.kind, JointKind::Revolute);
    assert!(knob.lower.is_infinite() && knob.upper.is_infinite());
    assert!(close(knob.origin_world, Vec3::new(1.0, 2.9, 0.0), 1e-5), "{:?}", knob.origin_world);
    assert!(close(knob.axis_world, Vec3::Y, 1e-5), "{:?}", knob.axis_world);

    let panel = asset.link("panel").unwrap();
    assert_eq!(panel.geoms.len(), 2, "the missing mesh is skipped, the link kept");
    assert!(asset.warnings.iter().any(|w| w.message.contains("absent.stl")), "{:?}", asset.warnings);
    // Mesh: scale (2, 1, 1), then the geom origin, then the link pose (yaw 90° about (1, 2, 0)).
    let GeomShape::Mesh { vertices, triangles } = &panel.geoms[0].shape else { panic!("expected a mesh") };
    assert_eq!((vertices.len(), triangles.len()), (8, 12));
    assert!(close(vertices[1], Vec3::new(1.0, 2.0 + 2.5, 0.0), 1e-5), "{:?}", vertices[1]);
    // Collision box centre: 0.5 along panel x → world (1, 2.5, 0); its long side turned onto y.
    let GeomShape::Primitive(board) = &panel.geoms[1].shape else { panic!("expected a box") };
    assert_eq!(board.kind, PrimitiveKind::Cuboid);
    assert!(close(board.center(), Vec3::new(1.0, 2.5, 0.0), 1e-5));
    assert!(close(board.size, Vec3::new(1.0, 0.05, 2.0), 1e-6));
    assert!(close(board.axes_world()[0].abs(), Vec3::Y, 1e-5));
    assert_eq!(panel.preferred_geoms().len(), 1);
    assert_eq!(panel.preferred_geoms()[0].role, GeomRole::Collision);
    let GeomShape::Primitive(knob_cyl) = &asset.link("knob").unwrap().geoms[0].shape else { panic!() };
    assert!(close(knob_cyl.size, Vec3::new(0.04, 0.04, 0.1), 1e-6));
}

#[test]
fn urdf_errors_name_file_and_problem() {
    let dir = tempfile::tempdir().unwrap();
    let broken = write(dir.path(), "broken.urdf", "<robot name='x'><link name='a'></robot>");
    let err = load_asset(&broken).unwrap_err();
    assert!(matches!(err, AssetError::Xml { .. }), "{err}");
    assert!(err.to_string().contains("broken.urdf"));
    let dangling = write(
        dir.path(),
        "dangling.urdf",
        r#"<robot name="x"><link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="ghost"/></joint></robot>"#,
    );
    let err = load_asset(&dangling).unwrap_err().to_string();
    assert!(err.contains("dangling.urdf") && err.contains("ghost"), "{err}");
    let unknown = write(dir.path(), "thing.dae", "");
    assert!(matches!(load_asset(&unknown), Err(AssetError::UnknownFormat { .. })));
}

#[test]
fn mjcf_degrees_radians_slide_nesting_include_and_classes() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "parts/cube.obj", CUBE_OBJ);
    write(
        dir.path(),
        "parts/defaults.xml",
        r#"<mujocoinclude>
  <asset><mesh name="cube" file="cube.obj" scale="0.1 0.1 0.1"/></asset>
  <default>
    <default class="cab">
      <joint axis="0 1 0" range="0 90"/>
      <geom contype="0" conaffinity="0" type="box" size="0.1 0.1 0.1"/>
      <default class="cab_col"><geom contype="1" conaffinity="1"/></default>
    </default>
  </default>
</mujocoinclude>"#,
    );
    let path = write(
        dir.path(),
        "cabinet.xml",
        r#"<mujoco model="cabinet">
  <compiler angle="degree"/>
  <include file="parts/defaults.xml"/>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body pos="0 0 1">
      <body name="case" childclass="cab" pos="1 0 0" euler="0 0 90">
        <geom/>
        <geom class="cab_col" pos="0.5 0 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.02"/>
        <geom type="cylinder" size="0.05 0.2" quat="0.7071068 0.7071068 0 0"/>
        <geom type="mesh" mesh="cube" pos="0 0 -1"/>
        <body name="door" pos="0.5 0 0">
          <joint name="door_hinge" type="hinge" pos="0 0.2 0"/>
        </body>
        <body name="drawer" pos="0 0.5 0" axisangle="0 0 1 -90">
          <joint name="drawer_slide" type="slide" axis="1 0 0" range="0 0.3"/>
          <frame pos="0 0 0.1"><body name="handle"/></frame>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>"#,
    );
    let asset = load_asset(&path).unwrap();
    assert_eq!(asset.name, "cabinet");
    let names: Vec<&str> = asset.links.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["world", "body1", "case", "door", "drawer", "handle"]);
    let case = asset.link("case").unwrap();
    assert!(close(case.world_from_link.translation, Vec3::new(1.0, 0.0, 1.0), 1e-6));

    let movable: Vec<_> = asset.movable_joints().collect();
    assert_eq!(movable.len(), 2);
    let hinge = movable[0];
    assert_eq!(
        (hinge.name.as_str(), hinge.kind, hinge.parent.as_str(), hinge.child.as_str()),
        ("door_hinge", JointKind::Revolute, "case", "door")
    );
    // Class axis (0 1 0) turned by the case's yaw of 90° → world −x; range "0 90" in degrees.
    assert!(close(hinge.axis_world, Vec3::NEG_X, 1e-5), "{:?}", hinge.axis_world);
    assert!((hinge.upper - FRAC_PI_2).abs() < 1e-6 && hinge.lower == 0.0);
    // Door at case + R(90°)·(0.5, 0, 0) = (1, 0.5, 1); joint pos (0, 0.2, 0) → (0.8, 0.5, 1).
    assert!(close(hinge.origin_world, Vec3::new(0.8, 0.5, 1.0), 1e-5), "{:?}", hinge.origin_world);
    let slide = movable[1];
    assert_eq!(slide.kind, JointKind::Prismatic);
    // Drawer yaw: 90° − 90° = 0, so its x axis is world x; slide range stays in metres.
    assert!(close(slide.axis_world, Vec3::X, 1e-5), "{:?}", slide.axis_world);
    assert_eq!((slide.lower, slide.upper), (0.0, 0.3));
    assert!(close(asset.link("handle").unwrap().world_from_link.translation, Vec3::new(0.5, 0.0, 1.1), 1e-5));
    // Welded bodies get fixed joints; the tree is complete.
    assert_eq!(asset.joints.iter().filter(|j| j.kind == JointKind::Fixed).count(), 3);
    assert_eq!(asset.root_links().len(), 1);

    let geoms = &case.geoms;
    assert_eq!(geoms.len(), 5);
    // Default class geom: a visual box with the class size (half 0.1 → full 0.2).
    let GeomShape::Primitive(b) = &geoms[0].shape else { panic!() };
    assert_eq!((b.kind, geoms[0].role), (PrimitiveKind::Cuboid, GeomRole::Visual));
    assert!(close(b.size, Vec3::splat(0.2), 1e-6));
    // Nested class inherits type and size, overrides the collision flags.
    let GeomShape::Primitive(c) = &geoms[1].shape else { panic!() };
    assert_eq!(geoms[1].role, GeomRole::Collision);
    assert!(close(c.center(), Vec3::new(1.0, 0.5, 1.0), 1e-5));
    // fromto capsule: radius 0.02, straight part 0.4 → total length 0.44, centred at z + 0.2.
    let GeomShape::Primitive(cap) = &geoms[2].shape else { panic!() };
    assert_eq!(cap.kind, PrimitiveKind::Capsule);
    assert!(close(cap.size, Vec3::new(0.04, 0.04, 0.44), 1e-5), "{:?}", cap.size);
    assert!(close(cap.center(), Vec3::new(1.0, 0.0, 1.2), 1e-5));
    // Cylinder half-height 0.2 → full 0.4; quat turns its axis onto the case's −y = world +x.
    let GeomShape::Primitive(cyl) = &geoms[3].shape else { panic!() };
    assert!(close(cyl.size, Vec3::new(0.1, 0.1, 0.4), 1e-5));
    assert!(cyl.axes_world()[2].abs().abs_diff_eq(Vec3::X, 1e-5), "{:?}", cyl.axes_world()[2]);
    // Mesh from the included asset, relative to the including file, scaled by 0.1.
    let GeomShape::Mesh { vertices, .. } = &geoms[4].shape else { panic!() };
    assert_eq!(vertices.len(), 8);
    let (lo, hi) = geoms[4].aabb().unwrap();
    assert!(close(hi - lo, Vec3::splat(0.1), 1e-5), "{lo:?} {hi:?}");
    // Names the file gives a geom (mesh name here) are kept for semantic words; unnamed: none.
    assert_eq!(geoms[4].names, ["cube"]);
    assert!(geoms[0].names.is_empty());
    // The world plane is reported and skipped.
    assert!(asset.warnings.iter().any(|w| w.message.contains("plane")), "{:?}", asset.warnings);
}

#[test]
fn mjcf_angles_default_to_degrees() {
    let dir = tempfile::tempdir().unwrap();
    let body = r#"<worldbody><body name="b" euler="90 0 0"><joint name="j" range="-45 45"/></body></worldbody>"#;
    let deg = load_asset(&write(dir.path(), "deg.xml", &format!("<mujoco>{body}</mujoco>"))).unwrap();
    let j = deg.movable_joints().next().unwrap();
    assert!((j.upper - PI / 4.0).abs() < 1e-6 && (j.lower + PI / 4.0).abs() < 1e-6);
    assert!(close(j.axis_world, Vec3::NEG_Y, 1e-5), "Rx(90°)·z = −y, got {:?}", j.axis_world);
    let rad = load_asset(&write(dir.path(), "rad.xml", &format!(r#"<mujoco><compiler angle="radian"/>{body}</mujoco>"#))).unwrap();
    let j = rad.movable_joints().next().unwrap();
    assert_eq!((j.lower, j.upper), (-45.0, 45.0));
    let expected = Vec3::new(0.0, -(90.0f32).sin(), (90.0f32).cos());
    assert!(close(j.axis_world, expected, 1e-4), "{:?}", j.axis_world);
}

#[test]
fn mjcf_errors_name_file_element_and_attribute() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "bad.xml", "<mujoco>\n<worldbody>\n<body pos=\"0 zero 0\"/>\n</worldbody>\n</mujoco>");
    let err = load_asset(&path).unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(&err, AssetError::BadAttribute { line: 3, element, attribute, .. } if element == "body" && attribute == "pos"),
        "{text}"
    );
    assert!(text.contains("bad.xml"), "{text}");
    let count = write(dir.path(), "count.xml", r#"<mujoco><worldbody><body><joint range="1"/></body></worldbody></mujoco>"#);
    let text = load_asset(&count).unwrap_err().to_string();
    assert!(text.contains("range") && text.contains("2 numbers"), "{text}");
    let missing = write(dir.path(), "missing.xml", r#"<mujoco><include file="nowhere.xml"/></mujoco>"#);
    assert!(load_asset(&missing).unwrap_err().to_string().contains("nowhere.xml"));
    let looped = write(dir.path(), "loop.xml", r#"<mujoco><include file="loop.xml"/></mujoco>"#);
    assert!(load_asset(&looped).unwrap_err().to_string().contains("loop"));
}

// ---------------------------------------------------------------------------------------------
// The shared benchmark: every object's movable joints against its own annotation.

const OBJECTS: &str = "/work/shared/data/objects";

#[derive(serde::Deserialize)]
struct TruthFile {
    links: Vec<String>,
    joints: Vec<TruthJoint>,
    #[serde(default)]
    primitive_geoms: Vec<TruthGeom>,
}

#[derive(serde::Deserialize)]
struct TruthJoint {
    name: String,
    #[serde(rename = "type")]
    kind: String,
    child: String,
    axis_world: [f32; 3],
    origin_world: [f32; 3],
}

#[derive(serde::Deserialize)]
struct TruthGeom {
    body: String,
    #[serde(rename = "type")]
    kind: String,
    /// `MuJoCo` sizes: half extents (box), radius and half length (capsule, cylinder).
    size: Vec<f32>,
    pos_world: [f32; 3],
    /// Row-major rotation matrix (`MuJoCo` `xmat`).
    rot_world: [f32; 9],
}

/// The file to import from an object folder: `*_obj.urdf` (OBJ conversions) over `*.urdf`,
/// `*_standalone.xml` over `<id>.xml`; URDFs may sit in a `urdf/` subfolder.
fn asset_file(dir: &Path, object_id: &str, format: &str) -> Option<PathBuf> {
    let list = |d: &Path| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d).map(|r| r.filter_map(|e| e.ok().map(|e| e.path())).collect()).unwrap_or_default();
        v.sort();
        v
    };
    let name = |p: &PathBuf| p.file_name().and_then(|n| n.to_str()).unwrap_or("").to_owned();
    if format.starts_with("urdf") {
        let mut files = list(dir);
        files.extend(list(&dir.join("urdf")));
        let urdfs: Vec<PathBuf> = files.into_iter().filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf"))).collect();
        urdfs.iter().find(|p| name(p).ends_with("_obj.urdf")).or_else(|| urdfs.first()).cloned()
    } else {
        let files = list(dir);
        files
            .iter()
            .find(|p| name(p).ends_with("_standalone.xml"))
            .or_else(|| files.iter().find(|p| name(p) == format!("{object_id}.xml")))
            .cloned()
    }
}

/// Problems with one object, empty when its joints match the annotation.
fn check_object(dir: &Path, object_id: &str, format: &str) -> Vec<String> {
    let Some(file) = asset_file(dir, object_id, format) else { return vec!["no URDF/MJCF file found".into()] };
    let asset = match load_asset(&file) {
        Ok(a) => a,
        Err(e) => return vec![format!("import failed: {e}")],
    };
    let truth: TruthFile =
        serde_json::from_str(&std::fs::read_to_string(dir.join("gt_kinematics.json")).expect("gt_kinematics.json readable"))
            .expect("gt_kinematics.json parses");
    let mut problems = Vec::new();
    for w in &asset.warnings {
        eprintln!("    warning {object_id}: {w}");
    }
    if asset.warnings.iter().any(|w| w.message.contains("not found") || w.message.contains("cannot read mesh")) {
        problems.push(format!("meshes missing: {:?}", asset.warnings));
    }
    for name in &truth.links {
        if asset.link(name).is_none() {
            problems.push(format!("annotated link {name:?} not imported"));
        }
    }
    // Visual meshes and collision primitives of a link must describe the same body (mesh
    // frames, scales and units right): their bounding boxes' centres agree within a quarter of
    // the collision box diagonal.
    for link in &asset.links {
        let bounds = |role: GeomRole, primitive: bool| {
            link.geoms
                .iter()
                .filter(|g| g.role == role && g.is_primitive() == primitive)
                .filter_map(AssetGeom::aabb)
                .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
        };
        if let (Some(mesh), Some(prim)) = (bounds(GeomRole::Visual, false), bounds(GeomRole::Collision, true)) {
            let offset = (0.5 * (mesh.0 + mesh.1) - 0.5 * (prim.0 + prim.1)).length();
            if offset > 0.25 * (prim.1 - prim.0).length() {
                problems.push(format!("link {}: visual meshes {mesh:?} and collision primitives {prim:?} disagree", link.name));
            }
        }
    }
    let movable: Vec<_> = asset.movable_joints().collect();
    for kind in ["revolute", "prismatic"] {
        let want = truth.joints.iter().filter(|j| j.kind == kind).count();
        let got = movable.iter().filter(|j| j.kind.name() == kind).count();
        if want != got {
            problems.push(format!("{kind}: {got} imported, {want} annotated"));
        }
    }
    for t in truth.joints.iter().filter(|j| j.kind != "fixed") {
        let origin = Vec3::from(t.origin_world);
        let axis = Vec3::from(t.axis_world).normalize();
        let by_name = movable.iter().find(|j| j.child == t.child);
        let nearest = || movable.iter().min_by(|a, b| (a.origin_world - origin).length().total_cmp(&(b.origin_world - origin).length()));
        let Some(j) = by_name.or_else(nearest) else {
            problems.push(format!("joint {} unmatched", t.name));
            continue;
        };
        let angle_deg = j.axis_world.dot(axis).clamp(-1.0, 1.0).acos().to_degrees();
        if j.kind.name() != t.kind {
            problems.push(format!("joint {}: type {} vs {}", t.name, j.kind.name(), t.kind));
        }
        if angle_deg >= 1.0 {
            problems.push(format!("joint {}: axis {:?} vs {:?} ({angle_deg:.2}°)", t.name, j.axis_world, axis));
        }
        if t.kind == "revolute" {
            let d = line_line_distance(j.origin_world, j.axis_world, origin, axis);
            if d >= 0.01 {
                problems.push(format!("joint {}: hinge line {:.4} m away ({:?} vs {:?})", t.name, d, j.origin_world, origin));
            }
        }
    }
    // MJCF annotations list the box/capsule/cylinder geoms in world frame: each must be imported
    // on the same body with the same placement and full size (ours) = 2 × half size (MuJoCo's).
    let prims = asset.primitives();
    for g in &truth.primitive_geoms {
        let (kind, want_size) = match (g.kind.as_str(), g.size.as_slice()) {
            ("box", [x, y, z, ..]) => (PrimitiveKind::Cuboid, Vec3::new(2.0 * x, 2.0 * y, 2.0 * z)),
            ("cylinder", [r, h, ..]) => (PrimitiveKind::Cylinder, Vec3::new(2.0 * r, 2.0 * r, 2.0 * h)),
            ("capsule", [r, h, ..]) => (PrimitiveKind::Capsule, Vec3::new(2.0 * r, 2.0 * r, 2.0 * h + 2.0 * r)),
            _ => {
                problems.push(format!("annotation geom {} with size {:?} not understood by the test", g.kind, g.size));
                continue;
            }
        };
        let at = Vec3::from(g.pos_world);
        let r = &g.rot_world;
        let truth_axes = [Vec3::new(r[0], r[3], r[6]), Vec3::new(r[1], r[4], r[7]), Vec3::new(r[2], r[5], r[8])];
        let same = |p: &partscene::primitive::Primitive| {
            let axes = p.axes_world();
            let axes_ok = match kind {
                // Box: the same three signed-free axes with the same extents along them.
                PrimitiveKind::Cuboid => (0..3).all(|k| axes[k].dot(truth_axes[k]).abs() > 0.9998),
                // Round shapes: only the z axis is defined.
                _ => axes[2].dot(truth_axes[2]).abs() > 0.9998,
            };
            p.kind == kind && close(p.center(), at, 1e-4) && close(p.size, want_size, 1e-4) && axes_ok
        };
        if !prims.iter().any(|(link, _, p)| *link == g.body && same(p)) {
            problems.push(format!("primitive {} {:?} at {at:?} on {} not imported", g.kind, g.size, g.body));
        }
    }
    if !truth.primitive_geoms.is_empty() {
        let ours = prims.iter().filter(|(_, _, p)| p.kind != PrimitiveKind::Sphere).count();
        if ours != truth.primitive_geoms.len() {
            problems.push(format!("{ours} box/capsule/cylinder geoms imported, {} annotated", truth.primitive_geoms.len()));
        }
    }
    problems
}

/// Per link: the bounds of its visual meshes.
fn visual_mesh_bounds(asset: &partscene::assets::ArticulatedAsset) -> Vec<(String, Option<(Vec3, Vec3)>)> {
    asset
        .links
        .iter()
        .map(|l| {
            let b = l.geoms.iter().filter(|g| g.role == GeomRole::Visual && !g.is_primitive()).filter_map(AssetGeom::aabb);
            (l.name.clone(), b.reduce(|a, b| (a.0.min(b.0), a.1.max(b.1))))
        })
        .collect()
}

/// The habitat URDFs reference GLB meshes, their `*_obj.urdf` twins OBJ conversions of them:
/// both must give the same visual geometry.
#[test]
fn habitat_glb_meshes_match_their_obj_conversions() {
    let root = Path::new(OBJECTS).join("habitat_replicacad");
    if !root.is_dir() {
        eprintln!("!!!!! SKIPPED: {} is absent; GLB import was not checked !!!!!", root.display());
        return;
    }
    let mut compared = 0;
    for object in ["door1", "door2", "fridge", "kitchen_counter"] {
        let glb = load_asset(&root.join(object).join(format!("{object}.urdf"))).unwrap();
        let obj = load_asset(&root.join(object).join(format!("{object}_obj.urdf"))).unwrap();
        assert!(glb.warnings.iter().all(|w| !w.message.contains("mesh")), "{object}: {:?}", glb.warnings);
        for ((name, a), (_, b)) in visual_mesh_bounds(&glb).into_iter().zip(visual_mesh_bounds(&obj)) {
            match (a, b) {
                (Some(a), Some(b)) => {
                    assert!(close(a.0, b.0, 0.01) && close(a.1, b.1, 0.01), "{object}/{name}: GLB {a:?} vs OBJ {b:?}");
                    compared += 1;
                }
                (None, None) => {}
                other => panic!("{object}/{name}: visual meshes differ: {other:?}"),
            }
        }
    }
    assert!(compared >= 10, "only {compared} links compared");
}

#[test]
fn shared_objects_match_their_annotations() {
    let root = Path::new(OBJECTS);
    let Ok(manifest) = std::fs::read_to_string(root.join("MANIFEST.tsv")) else {
        eprintln!("!!!!! SKIPPED: {OBJECTS}/MANIFEST.tsv is absent; the benchmark objects were not checked !!!!!");
        return;
    };
    let mut lines = manifest.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (id_col, format_col, dir_col) = (col("object_id"), col("format"), col("local_dir"));
    let mut failures = Vec::new();
    let mut checked = 0;
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split('\t').collect();
        let dir = root.join(cells[dir_col]);
        let problems = check_object(&dir, cells[id_col], cells[format_col]);
        checked += 1;
        if problems.is_empty() {
            eprintln!("ok   {}", cells[dir_col]);
        } else {
            eprintln!("FAIL {}: {}", cells[dir_col], problems.join("; "));
            failures.push(format!("{}: {}", cells[dir_col], problems.join("; ")));
        }
    }
    assert!(checked >= 15, "only {checked} objects in the manifest");
    assert!(failures.is_empty(), "{} of {checked} objects do not match:\n{}", failures.len(), failures.join("\n"));
}
