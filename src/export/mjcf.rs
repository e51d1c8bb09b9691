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
//! `armature`, an end stop → a narrowed `range` (a compliant one also → `solreflimit`). Soft-close damping and a tilted gravity axis
//! have no MJCF joint attribute; [`dynamics_from_effects`] reports them instead.
//!
//! Contacts are excluded for exactly the pairs `scene.srdf` disables (parent and child, parts
//! touching at rest; see [`super::clearance`]) and the pairs clearance trimming could not
//! separate, so that an exported drawer slides instead of jamming on its own carcass (`MuJoCo`'s
//! parent filter skips a carcass welded to the world) while parts that do not touch at rest, and
//! different objects, still collide. [`object_mjcf`] writes one object alone (`objects/<name>.xml`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::clearance::{CollisionSet, collision_set};
use super::tree::ExportTree;
use super::urdf::{UrdfConfig, label_color, sanitize};
use super::xml::XmlWriter;
use crate::kinematics::JointKind;
use crate::math::{Quat, Vec3};
use crate::model::{PartModel, SceneModel};
use crate::primitive::PrimitiveKind;
use crate::report::Warning;
use crate::scan::{ObjectId, PartId};

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
    /// A compliant end stop's `solreflimit` (time constant s, damping ratio).
    pub solreflimit: Option<[f64; 2]>,
}

/// Least damping ratio written for a compliant limit (a restitution of 1 would make the time
/// constant infinite).
const MIN_LIMIT_DAMPRATIO: f64 = 1e-3;

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
                let narrows = at > lo && at < hi;
                if narrows {
                    d.range = Some(if at - lo < hi - at { [at, hi] } else { [lo, at] });
                }
                if let Some(contact_s) = e.params.get("contact_time").copied().filter(|t| t.is_finite() && *t > 0.0) {
                    compliant_limit(d, &e.joint, p("restitution"), contact_s, narrows, &mut warnings);
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

/// The shortest time constant `MuJoCo` keeps for a soft limit at the exported (default) 2 ms
/// step: with `refsafe`, on by default, it raises shorter ones to twice the step.
const MUJOCO_MIN_TIMECONST_S: f64 = 0.004;

/// A compliant end stop as `MuJoCo`'s soft limit: the same spring–damper, mass-free in its (time
/// constant, damping ratio) form, `ω_n = 1/(τζ)` and `2ζω_n = 2/τ` at constant impedance. In
/// `MuJoCo` 3 a slide at 0.3 m/s into (restitution 0.92, 63 ms) came back at 0.921 after 63 ms;
/// below a restitution of about 0.5 it bounces a little more (0.55 for 0.5, 0.32 for 0.2), as a
/// limit there cannot pull. Written only where the stop is the joint's limit (it narrowed the
/// range); `solreflimit` softens both ends of the joint, which the warnings say.
fn compliant_limit(d: &mut JointDynamics, joint: &str, restitution: f64, contact_s: f64, narrows: bool, warnings: &mut Vec<Warning>) {
    let at = format!("joint {joint}");
    if !narrows {
        warnings.push(Warning::new("export", at, "a compliant end stop outside the joint's range: its compliance is not written"));
        return;
    }
    let (omega_n, zeta) = crate::gap::effects::contact_oscillator(restitution, contact_s);
    let zeta = zeta.max(MIN_LIMIT_DAMPRATIO);
    let timeconst = 1.0 / (zeta * omega_n);
    d.solreflimit = Some([timeconst, zeta]);
    warnings.push(Warning::new(
        "export",
        at.clone(),
        "a compliant end stop → solreflimit, which MJCF applies to both limits of the joint: the other end is as soft",
    ));
    if timeconst < MUJOCO_MIN_TIMECONST_S {
        warnings.push(Warning::new(
            "export",
            at,
            format!(
                "solreflimit time constant {:.1} ms: MuJoCo raises it to {:.0} ms (twice its step), so the stop comes out softer than fitted",
                1e3 * timeconst,
                1e3 * MUJOCO_MIN_TIMECONST_S
            ),
        ));
    }
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

pub(super) fn part_mass(prim: &crate::primitive::Primitive, cfg: &UrdfConfig) -> f32 {
    (prim.volume() * cfg.density_kg_m3).max(1e-3)
}

pub(super) fn num(x: f32) -> String {
    // `{}` prints the shortest text that reads back to the same f32; no "-0".
    if x == 0.0 { "0".to_owned() } else { format!("{x}") }
}

pub(super) fn num64(x: f64) -> String {
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
    scene_mjcf_with(scene, cfg, dynamics, &collision_set(scene, cfg.collision_clearance_m))
}

/// [`scene_mjcf`] with the scene's collision set already computed (`write_scene_files` shares
/// one among all its formats).
pub(crate) fn scene_mjcf_with(
    scene: &SceneModel,
    cfg: &UrdfConfig,
    dynamics: &DynamicsTable,
    collisions: &CollisionSet,
) -> Result<String, MjcfError> {
    mjcf_document(scene, cfg, dynamics, collisions, "partscene", None)
}

/// One object's own MJCF (`objects/<name>.xml`, model named [`super::object_name`]): its root body at
/// the origin, as in its URDF (`scene_objects.json` gives the pose in the room), the object's parts
/// only (objects standing on it are left out), with the fitted `dynamics` and the pairs of
/// `collisions` inside the object excluded. `None` for an unknown object or one without parts.
pub fn object_mjcf(
    scene: &SceneModel,
    object: ObjectId,
    cfg: &UrdfConfig,
    dynamics: &DynamicsTable,
    collisions: &CollisionSet,
) -> Result<Option<String>, MjcfError> {
    if !scene.parts.iter().any(|p| p.object == object) || !scene.objects.iter().any(|o| o.id == object) {
        return Ok(None);
    }
    mjcf_document(scene, cfg, dynamics, collisions, &super::object_name(scene, object), Some(object)).map(Some)
}

/// The MJCF of the whole scene (`only` = `None`) or of one object.
fn mjcf_document(
    scene: &SceneModel,
    cfg: &UrdfConfig,
    dynamics: &DynamicsTable,
    collisions: &CollisionSet,
    model_name: &str,
    only: Option<ObjectId>,
) -> Result<String, MjcfError> {
    let tree = ExportTree::new(scene);
    if let Some((part, what)) = tree.first_non_finite(scene) {
        return Err(MjcfError::NonFinite { part, link: tree.name[&part].clone(), what });
    }
    let keep = |id: PartId| only.is_none_or(|o| scene.part(id).is_some_and(|p| p.object == o));
    let mut w = XmlWriter::new();
    w.open("mujoco", &[("model", model_name.to_owned())]);
    w.comment(&format!("partscene scene from {}; body and joint names match scene.urdf", scene.source));
    w.empty("compiler", &[("angle", "radian".to_owned()), ("balanceinertia", "true".to_owned())]);
    w.empty("option", &[("gravity", "0 0 -9.81".to_owned()), ("integrator", "implicitfast".to_owned())]);
    w.open("asset", &[]);
    let mut materials = BTreeSet::new();
    for part in scene.parts.iter().filter(|p| keep(p.id)) {
        let name = material_name(&part.label);
        if materials.insert(name.clone()) {
            let c = label_color(&part.label);
            w.empty("material", &[("name", name), ("rgba", format!("{} {} {} {}", num64(c[0]), num64(c[1]), num64(c[2]), num64(c[3])))]);
        }
    }
    w.close();
    w.open("worldbody", &[]);
    let bodies = Bodies { scene, tree: &tree, cfg, dynamics, keep: &keep };
    match only {
        None => {
            for root in &tree.roots {
                bodies.write(&mut w, root, Vec3::ZERO, &[]);
            }
        }
        Some(object) => {
            // The object's root at the origin; its parts the tree puts elsewhere (an edited
            // scene's stray part) are welded to it, as in its URDF.
            let root = object_root(scene, &tree, object, &keep);
            let strays: Vec<&PartModel> = scene
                .parts
                .iter()
                .filter(|p| keep(p.id) && Some(p.id) != root.map(|r| r.id) && !tree.parent.get(&p.id).is_some_and(|up| keep(*up)))
                .collect();
            if let Some(root) = root {
                bodies.write(&mut w, root, tree.origin_world[&root.id], &strays);
            }
        }
    }
    w.close();
    let excludes = contact_excludes(collisions, &tree, &keep);
    if !excludes.is_empty() {
        w.open("contact", &[]);
        for (a, b) in excludes {
            w.empty("exclude", &[("body1", tree.name[&a].clone()), ("body2", tree.name[&b].clone())]);
        }
        w.close();
    }
    Ok(w.finish())
}

/// The root body of an object's own MJCF: the topmost of the object's parts above its root part
/// (else its first part) in the export tree.
pub(super) fn object_root<'s>(
    scene: &'s SceneModel,
    tree: &ExportTree<'s>,
    object: ObjectId,
    keep: &dyn Fn(PartId) -> bool,
) -> Option<&'s PartModel> {
    let obj = scene.objects.iter().find(|o| o.id == object)?;
    let start = scene.part(obj.root_part).filter(|p| p.object == object).or_else(|| scene.parts.iter().find(|p| p.object == object))?;
    let mut at = start.id;
    // The tree has no cycles; the bound only guards against a malformed one.
    for _ in 0..scene.parts.len() {
        match tree.parent.get(&at).copied().filter(|p| keep(*p)) {
            Some(up) => at = up,
            None => break,
        }
    }
    scene.part(at)
}

/// What writing bodies needs, for the whole scene or one object (`keep`).
struct Bodies<'a, 's> {
    scene: &'s SceneModel,
    tree: &'a ExportTree<'s>,
    cfg: &'a UrdfConfig,
    dynamics: &'a DynamicsTable,
    keep: &'a dyn Fn(PartId) -> bool,
}

impl Bodies<'_, '_> {
    /// Writes `part`'s body, its kept children's and (welded, no joint) `welded` extra bodies.
    fn write(&self, w: &mut XmlWriter, part: &PartModel, parent_origin: Vec3, welded: &[&PartModel]) {
        let origin = self.tree.origin_world[&part.id];
        write_body_head(w, self.scene, self.tree, part, parent_origin, self.cfg, self.dynamics);
        for child in self.tree.children_of(part.id).iter().filter(|c| (self.keep)(c.id)) {
            self.write(w, child, origin, &[]);
        }
        for extra in welded {
            let origin_extra = self.tree.origin_world[&extra.id];
            w.open("body", &[("name", self.tree.name[&extra.id].clone()), ("pos", vec3(origin_extra - origin))]);
            write_inertial_and_geom(w, self.tree, extra, origin_extra, self.cfg);
            for child in self.tree.children_of(extra.id).iter().filter(|c| (self.keep)(c.id)) {
                self.write(w, child, origin_extra, &[]);
            }
            w.close();
        }
        w.close();
    }
}

/// Opens a part's body whose parent frame is at `parent_origin` and writes its joint, inertial
/// and geom (the caller writes the children and closes it).
fn write_body_head(
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
        if let Some([timeconst, dampratio]) = d.solreflimit {
            attrs.push(("solreflimit", format!("{} {}", num64(timeconst), num64(dampratio))));
        }
        w.empty("joint", &attrs);
    }
    write_inertial_and_geom(w, tree, part, origin, cfg);
}

/// A body's `<inertial>` and its geom: the fitted primitive.
fn write_inertial_and_geom(w: &mut XmlWriter, tree: &ExportTree, part: &PartModel, origin: Vec3, cfg: &UrdfConfig) {
    let name = &tree.name[&part.id];
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
}

/// Body pairs whose contacts are excluded, each as (smaller id, larger id): the pairs the SRDF
/// disables (parent and child, and parts touching at rest; `MuJoCo`'s own parent filter does not
/// apply when the parent is welded to the world, which is exactly a drawer in a standing cabinet)
/// and the pairs clearance trimming could not separate, among the parts `keep` keeps.
fn contact_excludes(collisions: &CollisionSet, tree: &ExportTree, keep: &dyn Fn(PartId) -> bool) -> Vec<(PartId, PartId)> {
    let pairs = collisions.disabled.iter().map(|&(a, b, _)| (a, b)).chain(collisions.unresolved.iter().map(|&(a, b, _)| (a, b)));
    let known = |id: &PartId| tree.name.contains_key(id) && keep(*id);
    let out: BTreeSet<(PartId, PartId)> =
        pairs.filter(|(a, b)| a != b && known(a) && known(b)).map(|(a, b)| (a.min(b), a.max(b))).collect();
    out.into_iter().collect()
}
