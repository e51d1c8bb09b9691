//! `scene.mjcf.xml`: the scene for `MuJoCo` (MJCF), beside the URDF and with the same names and
//! frames. Bodies nest along the kinematic tree (an object hangs off the world or off the part
//! that supports it, as in the URDF); every body frame keeps the world orientation and sits at its
//! joint origin, so joint axes are the world axes. A movable joint is a `hinge` or `slide` with
//! its limits as `range`; a fixed joint is no joint (the body is welded to its parent), so the
//! static scene is welded to the world. Geoms are the primitives themselves (box, cylinder,
//! sphere, capsule); `<inertial>` gives the same mass and inertia as the URDF (uniform density).
//!
//! Fitted dynamics from the reality-gap analysis (`partscene gap`, its `model.fitted.json`) go
//! onto the joints through a [`DynamicsTable`]: viscous damping → `damping`, Coulomb friction →
//! `frictionloss`, a spring → `stiffness` + `springref`, a heavier-than-modelled joint →
//! `armature`, an end stop → a narrowed `range`. Soft-close damping and a tilted gravity axis
//! have no MJCF joint attribute; [`dynamics_from_effects`] reports them instead.
//!
//! Contacts between parts of one object that the fit leaves touching (a drawer in its body, a
//! door beside a drawer, also a drawer and its own static carcass, which `MuJoCo`'s parent filter
//! leaves in because the carcass is welded to the world) are excluded where one of them can move, and so are those between a
//! standing object's moving parts and the part it stands on, so that an exported drawer slides
//! instead of jamming on its own carcass; contacts between objects stay.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::tree::ExportTree;
use super::urdf::{UrdfConfig, label_color, sanitize};
use super::xml::XmlWriter;
use crate::kinematics::JointKind;
use crate::math::{Quat, Vec3};
use crate::model::{PartModel, SceneModel};
use crate::primitive::PrimitiveKind;
use crate::report::Warning;
use crate::scan::PartId;

/// Why the MJCF could not be written, or fitted effects not read.
#[derive(Debug, thiserror::Error)]
pub enum MjcfError {
    /// A part's geometry holds NaN or infinity (MJCF would not compile).
    #[error("cannot write MJCF: part {part} ({link}) has a non-finite {what}")]
    NonFinite { part: PartId, link: String, what: &'static str },
    /// The fitted-effects file is not what `partscene gap` writes.
    #[error("{path}: not a partscene gap report or model.fitted.json: {message}")]
    Effects { path: String, message: String },
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
}

/// Dynamics written on one MJCF joint, in SI units (rad-based for hinges, m-based for slides).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointDynamics {
    /// Viscous damping, N·m·s/rad or N·s/m.
    pub damping: f64,
    /// Coulomb (dry) friction, N·m or N.
    pub frictionloss: f64,
    /// Spring stiffness, N·m/rad or N/m.
    pub stiffness: f64,
    /// Spring rest position, rad or m.
    pub springref: f64,
    /// Added inertia along the joint, kg·m² or kg.
    pub armature: f64,
    /// Limits replacing the scene's (end stops), rad or m.
    pub range: Option<[f64; 2]>,
}

/// Dynamics per joint name (the URDF joint names, `<child link>_joint`).
pub type DynamicsTable = BTreeMap<String, JointDynamics>;

/// One fitted effect as `partscene gap` reports it (an entry of `effects` in `report.json` or
/// `model.fitted.json`): spec §3 kind names and parameter names.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FittedEffect {
    /// Joint name.
    pub joint: String,
    /// `viscous_damping`, `coulomb_friction`, `spring`, `end_stop`, `mass_scale`, ...
    pub kind: String,
    /// Parameters in SI units.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
}

#[derive(Deserialize)]
struct EffectsFile {
    format: String,
    effects: Vec<FittedEffect>,
}

/// Parses the fitted effects out of `partscene gap`'s `model.fitted.json` (or `report.json`);
/// `path` names the file in errors.
pub fn fitted_effects_from_json(text: &str, path: &str) -> Result<Vec<FittedEffect>, MjcfError> {
    let bad = |message: String| MjcfError::Effects { path: path.to_owned(), message };
    let doc: EffectsFile = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    if doc.format != "partscene-gap-fitted/1" && doc.format != "partscene-gap-report/1" {
        return Err(bad(format!("format is {:?}, expected \"partscene-gap-fitted/1\" or \"partscene-gap-report/1\"", doc.format)));
    }
    Ok(doc.effects)
}

/// Reads [`fitted_effects_from_json`] from a file.
pub fn read_fitted_effects(path: &Path) -> Result<Vec<FittedEffect>, MjcfError> {
    let text = std::fs::read_to_string(path).map_err(|source| crate::io::IoError { path: path.to_path_buf(), action: "read", source })?;
    fitted_effects_from_json(&text, &path.display().to_string())
}

/// The MJCF/URDF joint name of the joint into `child`.
#[must_use]
pub fn joint_name(scene: &SceneModel, child: &PartModel) -> String {
    format!("{}_joint", super::link_name(scene, child))
}

/// Turns fitted effects into per-joint MJCF dynamics for `scene`. Effects on one joint add up
/// (two damping terms sum); `armature` is the same `MuJoCo` attribute; Coulomb and Stribeck friction become
/// `frictionloss` (the sliding level); `mass_scale` becomes `armature = (scale − 1) ×` the modelled inertia
/// of the joint's subtree about (or along) the axis at rest, with masses from `cfg`. Effects MJCF
/// cannot express on a joint (soft-close, gravity tilt, unknown, a lighter-than-modelled mass
/// scale) and effects on joints the scene does not have come back as warnings.
#[must_use]
pub fn dynamics_from_effects(scene: &SceneModel, cfg: &UrdfConfig, effects: &[FittedEffect]) -> (DynamicsTable, Vec<Warning>) {
    let tree = ExportTree::new(scene);
    let by_name: BTreeMap<String, PartId> =
        scene.parts.iter().filter(|p| tree.movable_joint(p.id).is_some()).map(|p| (joint_name(scene, p), p.id)).collect();
    let mut table = DynamicsTable::new();
    let mut warnings = Vec::new();
    for e in effects {
        let Some(&child) = by_name.get(&e.joint) else {
            warnings.push(Warning::new(
                "export",
                format!("joint {}", e.joint),
                format!("{} effect on a joint the scene has no movable joint for; not written", e.kind),
            ));
            continue;
        };
        let Some(joint) = tree.movable_joint(child) else { continue };
        let p = |name: &str| e.params.get(name).copied().filter(|v| v.is_finite()).unwrap_or(0.0);
        let d = table.entry(e.joint.clone()).or_default();
        match e.kind.as_str() {
            "viscous_damping" => d.damping += p("damping").max(0.0),
            // MuJoCo's frictionloss is one symmetric level, regularised by the solver: a smooth
            // transition is what it does anyway; a direction-dependent level takes the mean.
            "coulomb_friction" => {
                let forward = p("friction").max(0.0);
                let reverse = e.params.get("friction_reverse").copied().filter(|v| v.is_finite()).map_or(forward, |r| r.max(0.0));
                d.frictionloss += 0.5 * (forward + reverse);
            }
            // The sliding level; the breakaway excess has no MJCF attribute.
            "stribeck_friction" => d.frictionloss += p("friction").max(0.0),
            "armature" => d.armature += p("armature").max(0.0),
            "spring" => {
                d.stiffness += p("stiffness");
                d.springref = p("rest_position");
            }
            "end_stop" => {
                let [lo, hi] = d.range.unwrap_or([f64::from(joint.lower.min(joint.upper)), f64::from(joint.upper.max(joint.lower))]);
                let at = p("position");
                if at > lo && at < hi {
                    d.range = Some(if at - lo < hi - at { [at, hi] } else { [lo, at] });
                }
            }
            "mass_scale" => {
                let scale = e.params.get("scale").copied().unwrap_or(1.0);
                if scale >= 1.0 {
                    d.armature += (scale - 1.0) * f64::from(inertia_along_joint(scene, &tree, child, cfg));
                } else {
                    warnings.push(Warning::new(
                        "export",
                        format!("joint {}", e.joint),
                        format!("mass scale {scale:.3} < 1 cannot be written as armature; the modelled inertia is kept"),
                    ));
                }
            }
            other => warnings.push(Warning::new(
                "export",
                format!("joint {}", e.joint),
                format!("{other} has no MJCF joint attribute; kept only in the gap report"),
            )),
        }
    }
    (table, warnings)
}

/// Inertia of the subtree under `child` about its hinge axis (kg·m²), or its mass for a slide
/// (kg), at rest, with masses at `cfg.density_kg_m3` as in the URDF.
fn inertia_along_joint(scene: &SceneModel, tree: &ExportTree, child: PartId, cfg: &UrdfConfig) -> f32 {
    let Some(joint) = tree.movable_joint(child) else { return 0.0 };
    let axis = joint.axis_world.normalize_or(Vec3::X);
    tree.subtree(child)
        .into_iter()
        .filter_map(|id| scene.part(id))
        .map(|part| {
            let prim = &part.primitive;
            let mass = part_mass(prim, cfg);
            if joint.kind == JointKind::Prismatic {
                return mass;
            }
            let local_axis = prim.rotation().inverse() * axis;
            let principal = prim.principal_inertia(mass);
            let about_centre = (local_axis * local_axis).dot(principal);
            let d = prim.center() - joint.origin_world;
            let off_axis = d - axis * d.dot(axis);
            about_centre + mass * off_axis.length_squared()
        })
        .sum()
}

fn part_mass(prim: &crate::primitive::Primitive, cfg: &UrdfConfig) -> f32 {
    (prim.volume() * cfg.density_kg_m3).max(1e-3)
}

fn num(x: f32) -> String {
    // `{}` prints the shortest text that reads back to the same f32; no "-0".
    if x == 0.0 { "0".to_owned() } else { format!("{x}") }
}

fn num64(x: f64) -> String {
    if x == 0.0 { "0".to_owned() } else { format!("{x}") }
}

fn vec3(v: Vec3) -> String {
    format!("{} {} {}", num(v.x), num(v.y), num(v.z))
}

/// `MuJoCo` quaternions are w x y z.
fn quat(q: Quat) -> String {
    let q = q.normalize();
    format!("{} {} {} {}", num(q.w), num(q.x), num(q.y), num(q.z))
}

fn is_identity(q: Quat) -> bool {
    q.normalize().w.abs() > 1.0 - 1e-7
}

fn material_name(label: &str) -> String {
    format!("mat_{}", sanitize(label))
}

/// `scene.mjcf.xml` as text: the scene with the fitted `dynamics` (pass an empty table for none).
pub fn scene_mjcf(scene: &SceneModel, cfg: &UrdfConfig, dynamics: &DynamicsTable) -> Result<String, MjcfError> {
    let tree = ExportTree::new(scene);
    if let Some((part, what)) = tree.first_non_finite(scene) {
        return Err(MjcfError::NonFinite { part, link: tree.name[&part].clone(), what });
    }
    let mut w = XmlWriter::new();
    w.open("mujoco", &[("model", "partscene".to_owned())]);
    w.comment(&format!("partscene scene from {}; body and joint names match scene.urdf", scene.source));
    w.empty("compiler", &[("angle", "radian".to_owned()), ("balanceinertia", "true".to_owned())]);
    w.empty("option", &[("gravity", "0 0 -9.81".to_owned()), ("integrator", "implicitfast".to_owned())]);
    w.open("asset", &[]);
    let mut materials = BTreeSet::new();
    for part in &scene.parts {
        let name = material_name(&part.label);
        if materials.insert(name.clone()) {
            let c = label_color(&part.label);
            w.empty("material", &[("name", name), ("rgba", format!("{} {} {} {}", num64(c[0]), num64(c[1]), num64(c[2]), num64(c[3])))]);
        }
    }
    w.close();
    w.open("worldbody", &[]);
    for root in &tree.roots {
        write_body(&mut w, scene, &tree, root, Vec3::ZERO, cfg, dynamics);
    }
    w.close();
    let excludes = contact_excludes(scene, &tree);
    if !excludes.is_empty() {
        w.open("contact", &[]);
        for (a, b) in excludes {
            w.empty("exclude", &[("body1", tree.name[&a].clone()), ("body2", tree.name[&b].clone())]);
        }
        w.close();
    }
    Ok(w.finish())
}

/// Writes a part's body (and, recursively, its children's) whose parent frame is at `parent_origin`.
fn write_body(
    w: &mut XmlWriter,
    scene: &SceneModel,
    tree: &ExportTree,
    part: &PartModel,
    parent_origin: Vec3,
    cfg: &UrdfConfig,
    dynamics: &DynamicsTable,
) {
    let name = tree.name[&part.id].clone();
    let origin = tree.origin_world[&part.id];
    w.open("body", &[("name", name.clone()), ("pos", vec3(origin - parent_origin))]);
    if let Some(j) = tree.movable_joint(part.id) {
        let jname = joint_name(scene, part);
        let d = dynamics.get(&jname).copied().unwrap_or_default();
        let [lo, hi] = d.range.unwrap_or([f64::from(j.lower.min(j.upper)), f64::from(j.upper.max(j.lower))]);
        let kind = if j.kind == JointKind::Prismatic { "slide" } else { "hinge" };
        let mut attrs = vec![("name", jname), ("type", kind.to_owned()), ("axis", vec3(j.axis_world.normalize_or(Vec3::X)))];
        if j.kind == JointKind::Continuous && d.range.is_none() {
            attrs.push(("limited", "false".to_owned())); // wheels and turntables turn without end
        } else {
            attrs.push(("limited", "true".to_owned()));
            attrs.push(("range", format!("{} {}", num64(lo), num64(hi))));
        }
        let mut put = |key: &'static str, v: f64| {
            if v != 0.0 && v.is_finite() {
                attrs.push((key, num64(v)));
            }
        };
        put("damping", d.damping);
        put("frictionloss", d.frictionloss);
        put("stiffness", d.stiffness);
        put("springref", d.springref);
        put("armature", d.armature);
        w.empty("joint", &attrs);
    }
    let prim = &part.primitive;
    let local_centre = prim.center() - origin;
    let rot = prim.rotation();
    let mass = part_mass(prim, cfg);
    let inertia = prim.principal_inertia(mass).max(Vec3::splat(1e-6));
    let mut inertial = vec![("pos", vec3(local_centre))];
    if !is_identity(rot) {
        inertial.push(("quat", quat(rot)));
    }
    inertial.push(("mass", num(mass)));
    inertial.push(("diaginertia", vec3(inertia)));
    w.empty("inertial", &inertial);
    let h = prim.size * 0.5;
    let (kind, size) = match prim.kind {
        PrimitiveKind::Cuboid => ("box", vec3(h)),
        PrimitiveKind::Cylinder => ("cylinder", format!("{} {}", num(h.x), num(h.z))),
        // MuJoCo: radius and half-length of the straight part; a capsule with none is a sphere.
        PrimitiveKind::Capsule if h.z - h.x > 1e-6 => ("capsule", format!("{} {}", num(h.x), num(h.z - h.x))),
        PrimitiveKind::Sphere | PrimitiveKind::Capsule => ("sphere", num(h.x)),
    };
    let mut geom = vec![("name", format!("{name}_geom")), ("type", kind.to_owned()), ("size", size), ("pos", vec3(local_centre))];
    if !is_identity(rot) {
        geom.push(("quat", quat(rot)));
    }
    geom.push(("material", material_name(&part.label)));
    w.empty("geom", &geom);
    for child in tree.children_of(part.id) {
        write_body(w, scene, tree, child, origin, cfg, dynamics);
    }
    w.close();
}

/// Body pairs whose contacts are excluded (see the module docs), each as (smaller id, larger id).
/// Parent and child are listed too: `MuJoCo`'s parent filter does not apply when the parent is
/// welded to the world, which is exactly a drawer in a standing cabinet.
fn contact_excludes(scene: &SceneModel, tree: &ExportTree) -> Vec<(PartId, PartId)> {
    // Parts that move: everything under a movable joint.
    let mut moving = BTreeSet::new();
    for part in &scene.parts {
        if tree.movable_joint(part.id).is_some() {
            moving.extend(tree.subtree(part.id));
        }
    }
    let mut out = BTreeSet::new();
    let mut add = |a: PartId, b: PartId| {
        if a != b && (moving.contains(&a) || moving.contains(&b)) {
            out.insert((a.min(b), a.max(b)));
        }
    };
    for obj in &scene.objects {
        let ids: Vec<PartId> = scene.parts_of(obj.id).map(|p| p.id).collect();
        for (i, &a) in ids.iter().enumerate() {
            for &b in &ids[i + 1..] {
                add(a, b);
            }
        }
        // A support the scene does not hold (an edited or hand-written scene) has no body.
        if let Some(support) = obj.supported_by_part.filter(|s| tree.name.contains_key(s)) {
            for &a in &ids {
                add(a, support);
            }
        }
    }
    out.into_iter().collect()
}
