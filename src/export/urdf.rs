//! `scene.urdf`: one URDF with a `world` root; every object is a subtree hanging off the world or
//! off the part that supports it; every part is a link whose geometry is its primitive.
//!
//! Frames: every link frame keeps the world orientation and sits at its joint's origin (the hinge
//! point of a door, the centre of anything else), so joint origins are pure translations and joint
//! axes are the world axes. Geometry and inertia carry the primitive's rotation. Capsules are
//! written as a cylinder plus two spheres, which every URDF reader understands.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use urdf_rs as ur;

use crate::kinematics::JointKind;
use crate::math::{Pose, Quat, Vec3};
use crate::model::{PartModel, SceneModel};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::PartId;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UrdfConfig {
    /// Density used for masses, kg/m³ (the reality-gap spec's default).
    pub density_kg_m3: f32,
    /// Effort and velocity limits written on movable joints.
    pub effort: f64,
    pub velocity: f64,
}

impl Default for UrdfConfig {
    fn default() -> Self {
        Self { density_kg_m3: 600.0, effort: 100.0, velocity: 1.0 }
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

/// Builds the URDF robot of a scene.
#[must_use]
pub fn scene_urdf_robot(scene: &SceneModel, cfg: &UrdfConfig) -> ur::Robot {
    let names: BTreeMap<PartId, String> = scene.parts.iter().map(|p| (p.id, link_name(scene, p))).collect();
    let origins: BTreeMap<PartId, Vec3> = scene.parts.iter().map(|p| (p.id, super::tree::link_origin(scene, p))).collect();
    let mut links = vec![ur::Link { name: "world".to_owned(), inertial: ur::Inertial::default(), visual: vec![], collision: vec![] }];
    let mut joints = Vec::new();
    let mut materials = Vec::new();
    for part in &scene.parts {
        let origin = origins[&part.id];
        let prim = &part.primitive;
        let local = Pose::from_parts(prim.center() - origin, prim.rotation());
        let mut visual = Vec::new();
        let mut collision = Vec::new();
        for (k, (dz, geom)) in geometry(prim).into_iter().enumerate() {
            let at = local.transform_point(Vec3::Z * dz);
            let o = pose(at, prim.rotation());
            let material_name = format!("mat_{}", sanitize(&part.label));
            visual.push(ur::Visual {
                name: Some(format!("{}_v{k}", names[&part.id])),
                origin: o.clone(),
                geometry: geom.clone(),
                material: Some(ur::Material { name: material_name.clone(), color: None, texture: None }),
            });
            collision.push(ur::Collision { name: Some(format!("{}_c{k}", names[&part.id])), origin: o, geometry: geom });
            if !materials.iter().any(|m: &ur::Material| m.name == material_name) {
                let rgba = label_color(&part.label);
                materials.push(ur::Material { name: material_name, color: Some(ur::Color { rgba: ur::Vec4(rgba) }), texture: None });
            }
        }
        let mass = (prim.volume() * cfg.density_kg_m3).max(1e-3);
        let inertia = prim.principal_inertia(mass).max(Vec3::splat(1e-6));
        links.push(ur::Link {
            name: names[&part.id].clone(),
            inertial: ur::Inertial {
                origin: pose(local.translation, prim.rotation()),
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
        });
    }
    // Part joints.
    for j in &scene.joints {
        let (Some(pn), Some(cn)) = (names.get(&j.parent), names.get(&j.child)) else { continue };
        let joint_type = match j.kind {
            JointKind::Fixed => ur::JointType::Fixed,
            JointKind::Prismatic => ur::JointType::Prismatic,
            JointKind::Revolute => ur::JointType::Revolute,
            JointKind::Continuous => ur::JointType::Continuous,
        };
        let movable = j.kind.is_movable();
        // A continuous joint has no position limits (URDF ignores them; written as 0).
        let limited = movable && j.kind != JointKind::Continuous;
        joints.push(ur::Joint {
            name: format!("{cn}_joint"),
            joint_type,
            origin: pose(origins[&j.child] - origins[&j.parent], crate::math::Quat::IDENTITY),
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
        });
    }
    // Object roots: to the world, or to the part that supports them.
    for obj in &scene.objects {
        let Some(cn) = names.get(&obj.root_part) else { continue };
        let (parent_name, parent_origin) = match obj.supported_by_part.and_then(|p| names.get(&p).map(|n| (n.clone(), origins[&p]))) {
            Some(x) => x,
            None => ("world".to_owned(), Vec3::ZERO),
        };
        joints.push(ur::Joint {
            name: format!("{cn}_mount"),
            joint_type: ur::JointType::Fixed,
            origin: pose(origins[&obj.root_part] - parent_origin, crate::math::Quat::IDENTITY),
            parent: ur::LinkName { link: parent_name },
            child: ur::LinkName { link: cn.clone() },
            axis: ur::Axis { xyz: v3(Vec3::X) },
            limit: ur::JointLimit::default(),
            calibration: None,
            dynamics: None,
            mimic: None,
            safety_controller: None,
        });
    }
    ur::Robot { name: "partscene".to_owned(), links, joints, materials }
}

/// `scene.urdf` as text.
pub fn scene_urdf(scene: &SceneModel, cfg: &UrdfConfig) -> Result<String, UrdfError> {
    ur::write_to_string(&scene_urdf_robot(scene, cfg)).map_err(|e| UrdfError::Write(e.to_string()))
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
