//! `scene.urdf`: one URDF with a `world` root; every object is a subtree hanging off the world or
//! off the part that supports it; every part is a link whose geometry is its primitive.
//!
//! Frames: every link frame keeps the world orientation and sits at its joint's origin (the hinge
//! point of a door, the centre of anything else), so joint origins are pure translations and joint
//! axes are the world axes. Geometry and inertia carry the primitive's rotation. Capsules are
//! written as a cylinder plus two spheres, which every URDF reader understands.
//!
//! Collision geometry is the fitted primitive trimmed where it touches a part that is not its
//! parent or child (`clearance.rs`), so simulators that collide a model with itself do not start in
//! contact. `objects/<name>.urdf` ([`object_urdf`]) holds one articulated object each, its root
//! part as the root link.

use std::collections::{BTreeMap, BTreeSet};

use super::clearance::{CollisionSet, collision_set};

use serde::{Deserialize, Serialize};
use urdf_rs as ur;

use crate::kinematics::{Joint, JointKind};
use crate::math::{Pose, Quat, Vec3};
use crate::model::{PartModel, SceneModel};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::{ObjectId, PartId};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UrdfConfig {
    /// Density used for masses, kg/m³ (the reality-gap spec's default).
    pub density_kg_m3: f32,
    /// Effort and velocity limits written on movable joints.
    pub effort: f64,
    pub velocity: f64,
    /// Gap left between the collision shapes of parts that touch at rest and are not parent and
    /// child, metres (`clearance::collision_set`); visual shapes are not changed.
    #[serde(default = "default_clearance_m")]
    pub collision_clearance_m: f32,
}

fn default_clearance_m() -> f32 {
    0.002
}

impl Default for UrdfConfig {
    fn default() -> Self {
        Self { density_kg_m3: 600.0, effort: 100.0, velocity: 1.0, collision_clearance_m: default_clearance_m() }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    #[error("cannot write URDF: {0}")]
    Write(String),
}

pub(crate) fn sanitize(s: &str) -> String {
    let out: String = s.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect();
    if out.is_empty() { "part".to_owned() } else { out }
}

/// The URDF link name of a part, e.g. `cabinet3_drawer17`.
#[must_use]
pub fn link_name(scene: &SceneModel, part: &PartModel) -> String {
    let category = scene.objects.iter().find(|o| o.id == part.object).map_or("object", |o| o.category.as_str());
    format!("{}{}_{}{}", sanitize(category), part.object, sanitize(&part.label), part.id)
}

fn v3(v: Vec3) -> ur::Vec3 {
    ur::Vec3([f64::from(v.x), f64::from(v.y), f64::from(v.z)])
}

/// A unit vector normalised in f64, so readers that check unit length (`PyBullet`) see 1 exactly
/// enough; +x for a zero vector.
fn unit_f64(v: Vec3) -> ur::Vec3 {
    let [x, y, z] = v3(v).0;
    let n = (x * x + y * y + z * z).sqrt();
    if n > 1e-12 && n.is_finite() { ur::Vec3([x / n, y / n, z / n]) } else { ur::Vec3([1.0, 0.0, 0.0]) }
}

/// Roll-pitch-yaw of a rotation (one place for it: [`crate::math::quat_to_rpy`]).
pub(crate) fn rpy_of(q: Quat) -> [f64; 3] {
    crate::math::quat_to_rpy(q)
}

fn pose(xyz: Vec3, rot: crate::math::Quat) -> ur::Pose {
    ur::Pose { xyz: v3(xyz), rpy: ur::Vec3(rpy_of(rot)) }
}

/// Geometry pieces of a primitive in its own frame: (offset along z, geometry).
fn geometry(p: &Primitive) -> Vec<(f32, ur::Geometry)> {
    let s = p.size;
    match p.kind {
        PrimitiveKind::Cuboid => vec![(0.0, ur::Geometry::Box { size: v3(s) })],
        PrimitiveKind::Cylinder => vec![(0.0, ur::Geometry::Cylinder { radius: f64::from(s.x * 0.5), length: f64::from(s.z) })],
        PrimitiveKind::Sphere => vec![(0.0, ur::Geometry::Sphere { radius: f64::from(s.x * 0.5) })],
        PrimitiveKind::Capsule => {
            let r = s.x * 0.5;
            let straight = (s.z - s.x).max(0.0);
            let mut out = vec![
                (0.5 * straight, ur::Geometry::Sphere { radius: f64::from(r) }),
                (-0.5 * straight, ur::Geometry::Sphere { radius: f64::from(r) }),
            ];
            if straight > 1e-6 {
                out.insert(0, (0.0, ur::Geometry::Cylinder { radius: f64::from(r), length: f64::from(straight) }));
            }
            out
        }
    }
}

/// The robot name and file stem of an object's own URDF, e.g. `cabinet3`.
#[must_use]
pub fn object_name(scene: &SceneModel, object: ObjectId) -> String {
    let category = scene.objects.iter().find(|o| o.id == object).map_or("object", |o| o.category.as_str());
    format!("{}{object}", sanitize(category))
}

/// What the URDF links are made of: names, frames and collision primitives of every part.
struct LinkFrames {
    names: BTreeMap<PartId, String>,
    origins: BTreeMap<PartId, Vec3>,
    collision: BTreeMap<PartId, Primitive>,
    /// Parts written without collision geometry (`CollisionSet::without_collision`).
    without_collision: BTreeSet<PartId>,
}

impl LinkFrames {
    fn new(scene: &SceneModel, collisions: &CollisionSet) -> Self {
        Self {
            names: scene.parts.iter().map(|p| (p.id, link_name(scene, p))).collect(),
            origins: scene.parts.iter().map(|p| (p.id, super::tree::link_origin(scene, p))).collect(),
            collision: collisions.primitives.clone(),
            without_collision: collisions.without_collision.clone(),
        }
    }
}

/// Geometry elements of a primitive in a link frame at `origin`: (origin, geometry) per piece.
fn placed_geometry(prim: &Primitive, origin: Vec3) -> Vec<(ur::Pose, ur::Geometry)> {
    let local = Pose::from_parts(prim.center() - origin, prim.rotation());
    geometry(prim).into_iter().map(|(dz, geom)| (pose(local.transform_point(Vec3::Z * dz), prim.rotation()), geom)).collect()
}

/// A part's link: visual geometry from the fitted primitive, collision geometry from its
/// collision primitive (trimmed where it touches a non-adjacent part), inertia from the fitted
/// primitive at the configured density. New materials are added to `materials`.
fn part_link(part: &PartModel, frames: &LinkFrames, cfg: &UrdfConfig, materials: &mut Vec<ur::Material>) -> ur::Link {
    let name = &frames.names[&part.id];
    let origin = frames.origins[&part.id];
    let prim = &part.primitive;
    let material_name = format!("mat_{}", sanitize(&part.label));
    if !materials.iter().any(|m| m.name == material_name) {
        let rgba = label_color(&part.label);
        materials.push(ur::Material { name: material_name.clone(), color: Some(ur::Color { rgba: ur::Vec4(rgba) }), texture: None });
    }
    let visual = placed_geometry(prim, origin)
        .into_iter()
        .enumerate()
        .map(|(k, (o, geometry))| ur::Visual {
            name: Some(format!("{name}_v{k}")),
            origin: o,
            geometry,
            material: Some(ur::Material { name: material_name.clone(), color: None, texture: None }),
        })
        .collect();
    let collision_prim = frames.collision.get(&part.id).unwrap_or(prim);
    let pieces = if frames.without_collision.contains(&part.id) { Vec::new() } else { placed_geometry(collision_prim, origin) };
    let collision = pieces
        .into_iter()
        .enumerate()
        .map(|(k, (o, geometry))| ur::Collision { name: Some(format!("{name}_c{k}")), origin: o, geometry })
        .collect();
    let mass = (prim.volume() * cfg.density_kg_m3).max(1e-3);
    let inertia = prim.principal_inertia(mass).max(Vec3::splat(1e-6));
    ur::Link {
        name: name.clone(),
        inertial: ur::Inertial {
            origin: pose(prim.center() - origin, prim.rotation()),
            mass: ur::Mass { value: f64::from(mass) },
            inertia: ur::Inertia {
                ixx: f64::from(inertia.x),
                ixy: 0.0,
                ixz: 0.0,
                iyy: f64::from(inertia.y),
                iyz: 0.0,
                izz: f64::from(inertia.z),
            },
        },
        visual,
        collision,
    }
}

/// The URDF joint of a part joint.
fn part_joint(j: &Joint, frames: &LinkFrames, cfg: &UrdfConfig) -> Option<ur::Joint> {
    let (pn, cn) = (frames.names.get(&j.parent)?, frames.names.get(&j.child)?);
    let joint_type = match j.kind {
        JointKind::Fixed => ur::JointType::Fixed,
        JointKind::Prismatic => ur::JointType::Prismatic,
        JointKind::Revolute => ur::JointType::Revolute,
        JointKind::Continuous => ur::JointType::Continuous,
    };
    let movable = j.kind.is_movable();
    // A continuous joint has no position limits (URDF ignores them; written as 0).
    let limited = movable && j.kind != JointKind::Continuous;
    Some(ur::Joint {
        name: format!("{cn}_joint"),
        joint_type,
        origin: pose(frames.origins[&j.child] - frames.origins[&j.parent], Quat::IDENTITY),
        parent: ur::LinkName { link: pn.clone() },
        child: ur::LinkName { link: cn.clone() },
        axis: ur::Axis { xyz: unit_f64(if movable { j.axis_world } else { Vec3::X }) },
        limit: ur::JointLimit {
            lower: if limited { f64::from(j.lower) } else { 0.0 },
            upper: if limited { f64::from(j.upper) } else { 0.0 },
            effort: if movable { cfg.effort } else { 0.0 },
            velocity: if movable { cfg.velocity } else { 0.0 },
        },
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    })
}

/// A fixed joint that places `child` on `parent` (object mounts; `parent_origin` is the parent's
/// link frame in the world).
fn mount_joint(child_name: &str, child_origin: Vec3, parent_name: &str, parent_origin: Vec3) -> ur::Joint {
    ur::Joint {
        name: format!("{child_name}_mount"),
        joint_type: ur::JointType::Fixed,
        origin: pose(child_origin - parent_origin, Quat::IDENTITY),
        parent: ur::LinkName { link: parent_name.to_owned() },
        child: ur::LinkName { link: child_name.to_owned() },
        axis: ur::Axis { xyz: v3(Vec3::X) },
        limit: ur::JointLimit::default(),
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    }
}

/// Builds the URDF robot of a scene: every part a link, the `world` link first (it has no
/// inertia; [`scene_urdf`] writes it without an `<inertial>` element).
#[must_use]
pub fn scene_urdf_robot(scene: &SceneModel, cfg: &UrdfConfig) -> ur::Robot {
    scene_urdf_robot_with(scene, cfg, &collision_set(scene, cfg.collision_clearance_m))
}

fn scene_urdf_robot_with(scene: &SceneModel, cfg: &UrdfConfig, collisions: &CollisionSet) -> ur::Robot {
    let frames = LinkFrames::new(scene, collisions);
    let mut materials = Vec::new();
    let mut links = vec![ur::Link { name: WORLD.to_owned(), inertial: ur::Inertial::default(), visual: vec![], collision: vec![] }];
    links.extend(scene.parts.iter().map(|part| part_link(part, &frames, cfg, &mut materials)));
    let mut joints: Vec<ur::Joint> = scene.joints.iter().filter_map(|j| part_joint(j, &frames, cfg)).collect();
    // Object roots: to the world, or to the part that supports them.
    for obj in &scene.objects {
        let Some(cn) = frames.names.get(&obj.root_part) else { continue };
        let (parent_name, parent_origin) =
            match obj.supported_by_part.and_then(|p| frames.names.get(&p).map(|n| (n.as_str(), frames.origins[&p]))) {
                Some(x) => x,
                None => (WORLD, Vec3::ZERO),
            };
        joints.push(mount_joint(cn, frames.origins[&obj.root_part], parent_name, parent_origin));
    }
    ur::Robot { name: "partscene".to_owned(), links, joints, materials }
}

/// The root link of every scene URDF.
const WORLD: &str = "world";

/// One articulated object as its own URDF robot (named [`object_name`]): its root part is the
/// root link, link frames as in `scene.urdf` (so the object's world pose is the root link's
/// origin, world-aligned; `scene_objects.json` lists it). Parts the object's joints do not reach
/// from its root are fixed to the root. `None` for an unknown object or one without parts.
#[must_use]
pub fn object_urdf_robot(scene: &SceneModel, object: ObjectId, cfg: &UrdfConfig) -> Option<ur::Robot> {
    object_urdf_robot_with(scene, object, cfg, &collision_set(scene, cfg.collision_clearance_m))
}

fn object_urdf_robot_with(scene: &SceneModel, object: ObjectId, cfg: &UrdfConfig, collisions: &CollisionSet) -> Option<ur::Robot> {
    let obj = scene.objects.iter().find(|o| o.id == object)?;
    let frames = LinkFrames::new(scene, collisions);
    let parts: Vec<&PartModel> = scene.parts.iter().filter(|p| p.object == object).collect();
    let root = parts.iter().find(|p| p.id == obj.root_part).or(parts.first())?.id;
    let mut materials = Vec::new();
    let mut links = vec![];
    // The root link first: readers take the first link without a parent as the root.
    for part in parts.iter().filter(|p| p.id == root).chain(parts.iter().filter(|p| p.id != root)) {
        links.push(part_link(part, &frames, cfg, &mut materials));
    }
    let in_object = |id: PartId| parts.iter().any(|p| p.id == id);
    let mut joints: Vec<ur::Joint> = scene
        .joints
        .iter()
        .filter(|j| in_object(j.parent) && in_object(j.child) && j.child != root)
        .filter_map(|j| part_joint(j, &frames, cfg))
        .collect();
    let reached: BTreeSet<PartId> = joints_reaching(scene, root, &parts);
    for part in parts.iter().filter(|p| p.id != root && !reached.contains(&p.id)) {
        joints.retain(|j| j.child.link != frames.names[&part.id]);
        joints.push(mount_joint(&frames.names[&part.id], frames.origins[&part.id], &frames.names[&root], frames.origins[&root]));
    }
    Some(ur::Robot { name: object_name(scene, object), links, joints, materials })
}

/// Parts of `parts` reached from `root` through joints inside the object.
fn joints_reaching(scene: &SceneModel, root: PartId, parts: &[&PartModel]) -> BTreeSet<PartId> {
    let mut reached = BTreeSet::from([root]);
    loop {
        let before = reached.len();
        for j in &scene.joints {
            if reached.contains(&j.parent) && parts.iter().any(|p| p.id == j.child) {
                reached.insert(j.child);
            }
        }
        if reached.len() == before {
            return reached;
        }
    }
}

/// A robot as URDF text; a link named `world` is written without `<inertial>` (ROS tools warn
/// about inertia on the root, and a zero mass means nothing).
pub fn robot_to_string(robot: &ur::Robot) -> Result<String, UrdfError> {
    let has_world = robot.links.iter().any(|l| l.name == WORLD);
    let mut stripped = robot.clone();
    stripped.links.retain(|l| l.name != WORLD);
    let text = ur::write_to_string(&stripped).map_err(|e| UrdfError::Write(e.to_string()))?;
    let open = text.find("<robot").and_then(|at| text[at..].find('>').map(|end| at + end + 1));
    let Some(open) = open else { return Err(UrdfError::Write("no <robot> element in the written URDF".to_owned())) };
    let world = if has_world { format!("\n  <link name=\"{WORLD}\"/>") } else { String::new() };
    Ok(format!("{}{MUJOCO_EXTENSION}{world}{}", &text[..open], &text[open..]))
}

/// `MuJoCo`'s URDF extension (other readers skip unknown elements): keep links without a joint
/// as bodies of their own. By default `MuJoCo` fuses them into their parent, the root into the
/// world, and contacts with the world body are never filtered as parent–child: every drawer
/// would start in contact with its carcass.
const MUJOCO_EXTENSION: &str = "\n  <mujoco>\n    <compiler fusestatic=\"false\" discardvisual=\"false\"/>\n  </mujoco>";

/// `scene.urdf` as text.
pub fn scene_urdf(scene: &SceneModel, cfg: &UrdfConfig) -> Result<String, UrdfError> {
    robot_to_string(&scene_urdf_robot(scene, cfg))
}

/// [`scene_urdf`] with the scene's collision set already computed.
pub(crate) fn scene_urdf_with(scene: &SceneModel, cfg: &UrdfConfig, collisions: &CollisionSet) -> Result<String, UrdfError> {
    robot_to_string(&scene_urdf_robot_with(scene, cfg, collisions))
}

/// An object's own URDF as text ([`object_urdf_robot`]); `None` for an unknown object.
pub fn object_urdf(scene: &SceneModel, object: ObjectId, cfg: &UrdfConfig) -> Result<Option<String>, UrdfError> {
    object_urdf_with(scene, object, cfg, &collision_set(scene, cfg.collision_clearance_m))
}

/// [`object_urdf`] with the scene's collision set already computed.
pub(crate) fn object_urdf_with(
    scene: &SceneModel,
    object: ObjectId,
    cfg: &UrdfConfig,
    collisions: &CollisionSet,
) -> Result<Option<String>, UrdfError> {
    object_urdf_robot_with(scene, object, cfg, collisions).map(|r| robot_to_string(&r)).transpose()
}

/// A stable colour per label word (for viewers that show URDF materials).
#[must_use]
pub fn label_color(label: &str) -> [f64; 4] {
    let h = label.bytes().fold(2_166_136_261_u32, |h, b| (h ^ u32::from(b)).wrapping_mul(16_777_619));
    let f = |shift: u32| 0.35 + 0.55 * f64::from((h >> shift) & 0xff) / 255.0;
    [f(0), f(8), f(16), 1.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R = Rz(yaw)·Ry(pitch)·Rx(roll), written out, to check [`rpy_of`] without glam's Euler code.
    fn matrix_of_rpy([r, p, y]: [f64; 3]) -> glam::DMat3 {
        let rx = glam::DMat3::from_cols_array(&[1.0, 0.0, 0.0, 0.0, r.cos(), r.sin(), 0.0, -r.sin(), r.cos()]);
        let ry = glam::DMat3::from_cols_array(&[p.cos(), 0.0, -p.sin(), 0.0, 1.0, 0.0, p.sin(), 0.0, p.cos()]);
        let rz = glam::DMat3::from_cols_array(&[y.cos(), y.sin(), 0.0, -y.sin(), y.cos(), 0.0, 0.0, 0.0, 1.0]);
        rz * ry * rx
    }

    #[test]
    fn rpy_reproduces_the_rotation_also_at_gimbal_lock() {
        use rand::Rng;
        let mut rng = crate::math::rng(7);
        let mut cases = vec![
            // The demo knob that glam's to_euler got wrong (axis along −y, pitch ≈ −90°).
            Quat::from_xyzw(-0.501_262_66, -0.498_734_15, -0.501_262_66, 0.498_734_15),
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            Quat::from_rotation_y(-std::f32::consts::FRAC_PI_2) * Quat::from_rotation_x(0.7),
            Quat::from_rotation_z(0.3) * Quat::from_rotation_y(std::f32::consts::FRAC_PI_2 - 1e-4),
            Quat::IDENTITY,
        ];
        for _ in 0..200 {
            cases.push(
                Quat::from_xyzw(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize(),
            );
        }
        for q in cases {
            let want = glam::DMat3::from_quat(q.as_dquat().normalize());
            let got = matrix_of_rpy(rpy_of(q));
            let err = (want - got).to_cols_array().iter().fold(0.0_f64, |a, b| a.max(b.abs()));
            assert!(err < 1e-6, "{q}: rpy {:?} off by {err}", rpy_of(q));
        }
    }
}
