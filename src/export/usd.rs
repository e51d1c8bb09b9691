//! `scene.usda`: the scene as text USD with the `UsdPhysics` schemas, for Isaac Sim and any other
//! `UsdPhysics` reader (Isaac's URDF importer drops `<dynamics damping friction>`, so the fitted
//! physics of `partscene gap` only reaches Isaac this way).
//!
//! Layout: `/partscene` (the default prim) holds a `PhysicsScene` and one `Xform` per object with
//! `PhysicsArticulationRootAPI` (a one-part object is a lone body fixed to the world); under it one `Xform` per part (a link, named as in `scene.urdf`),
//! flat, each with `PhysicsRigidBodyAPI` and `PhysicsMassAPI` (the URDF's mass, centre of mass and
//! principal inertia), placed at its URDF link origin (world-aligned, so the layout is the URDF's
//! frames), holding a `visual` primitive and a `collision` primitive (`PhysicsCollisionAPI`, purpose
//! `guide`; trimmed where parts touch, as the URDF's). Joints live in the object's `joints` scope:
//! `PhysicsRevoluteJoint` / `PhysicsPrismaticJoint` with axis X of a joint frame turned onto the
//! joint's axis (`localRot0` = `localRot1`), limits in degrees or metres (none for continuous
//! joints), `PhysicsFixedJoint` for rigid mounts, and the object's root fixed to the world. Objects
//! standing on others are separate articulations, fixed to the world where they stand. The
//! pairs `scene.srdf` disables, and those trimming could not separate, are filtered
//! (`PhysicsFilteredPairsAPI`), as MJCF's `<exclude>`.
//!
//! Fitted dynamics ([`super::DynamicsTable`], from `partscene gap`): viscous damping and springs
//! become a force drive (`PhysicsDriveAPI:angular|linear`: damping, stiffness, target position at
//! the spring's rest; rotational values per degree, as the schema stores them); Coulomb friction
//! and armature become `PhysxJointAxisAPI` (`staticFrictionEffort` = `dynamicFrictionEffort`,
//! `armature`), the `PhysX` schema Isaac Sim reads; an end stop narrows the limits.

use std::collections::{BTreeMap, BTreeSet};

use super::clearance::{CollisionSet, collision_set};
use super::mjcf::{DynamicsTable, JointDynamics, joint_name, num, num64, object_root, part_mass};
use super::tree::ExportTree;
use super::urdf::{UrdfConfig, label_color, object_name};
use crate::kinematics::{Joint, JointKind};
use crate::math::{Quat, Vec3};
use crate::model::{PartModel, SceneModel};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::{ObjectId, PartId};

/// Why the USD could not be written.
#[derive(Debug, thiserror::Error)]
pub enum UsdError {
    /// A part's geometry holds NaN or infinity (USD readers would reject the numbers).
    #[error("cannot write USD: part {part} ({link}) has a non-finite {what}")]
    NonFinite { part: PartId, link: String, what: &'static str },
}

/// The default prim of `scene.usda`.
pub const USD_ROOT: &str = "partscene";

/// `scene.usda` as text: the scene with the fitted `dynamics` (an empty table for none).
pub fn scene_usda(scene: &SceneModel, cfg: &UrdfConfig, dynamics: &DynamicsTable) -> Result<String, UsdError> {
    scene_usda_with(scene, cfg, dynamics, &collision_set(scene, cfg.collision_clearance_m))
}

/// [`scene_usda`] with the collision set already computed (`write_scene_files` shares one).
pub(crate) fn scene_usda_with(
    scene: &SceneModel,
    cfg: &UrdfConfig,
    dynamics: &DynamicsTable,
    collisions: &CollisionSet,
) -> Result<String, UsdError> {
    let tree = ExportTree::new(scene);
    if let Some((part, what)) = tree.first_non_finite(scene) {
        return Err(UsdError::NonFinite { part, link: tree.name[&part].clone(), what });
    }
    let mut w = UsdaWriter::default();
    w.line("#usda 1.0");
    w.line("(");
    w.line(&format!("    defaultPrim = \"{USD_ROOT}\""));
    w.line(&format!("    doc = \"partscene scene from {}; link and joint names match scene.urdf\"", escape(&scene.source)));
    w.line("    kilogramsPerUnit = 1");
    w.line("    metersPerUnit = 1");
    w.line("    upAxis = \"Z\"");
    w.line(")");
    w.line("");
    w.open(&format!("def Xform \"{USD_ROOT}\""), &[]);
    w.open("def PhysicsScene \"physics_scene\"", &[]);
    w.line("vector3f physics:gravityDirection = (0, 0, -1)");
    w.line("float physics:gravityMagnitude = 9.81");
    w.close();
    let filtered = filtered_pairs(collisions, &tree);
    for object in &scene.objects {
        let parts: Vec<&PartModel> = scene.parts.iter().filter(|p| p.object == object.id).collect();
        if parts.is_empty() {
            continue;
        }
        let ctx = ObjectCtx { scene, tree: &tree, cfg, dynamics, collisions, filtered: &filtered, object: object.id, parts };
        ctx.write(&mut w);
    }
    w.close();
    Ok(w.out)
}

/// Per part, the parts whose contacts with it are filtered (listed on the smaller id only).
fn filtered_pairs(collisions: &CollisionSet, tree: &ExportTree) -> BTreeMap<PartId, BTreeSet<PartId>> {
    let mut out: BTreeMap<PartId, BTreeSet<PartId>> = BTreeMap::new();
    let pairs = collisions.disabled.iter().map(|&(a, b, _)| (a, b)).chain(collisions.unresolved.iter().map(|&(a, b, _)| (a, b)));
    for (a, b) in pairs.filter(|(a, b)| a != b && tree.name.contains_key(a) && tree.name.contains_key(b)) {
        out.entry(a.min(b)).or_default().insert(a.max(b));
    }
    out
}

/// What writing one object needs.
struct ObjectCtx<'a, 's> {
    scene: &'s SceneModel,
    tree: &'a ExportTree<'s>,
    cfg: &'a UrdfConfig,
    dynamics: &'a DynamicsTable,
    collisions: &'a CollisionSet,
    filtered: &'a BTreeMap<PartId, BTreeSet<PartId>>,
    object: ObjectId,
    parts: Vec<&'s PartModel>,
}

/// How a part hangs in its object's articulation.
enum Mount<'s> {
    /// The object's root: fixed to the world.
    World,
    /// A joint of the scene from a part of the same object.
    Joint(PartId, &'s Joint),
    /// Welded to a part of the object (a stray part, or a fixed mount without a joint).
    Weld(PartId),
}

impl<'s> ObjectCtx<'_, 's> {
    fn in_object(&self, id: PartId) -> bool {
        self.parts.iter().any(|p| p.id == id)
    }

    fn path(&self, id: PartId) -> String {
        format!("/{USD_ROOT}/{}/{}", ident(&object_name(self.scene, self.object)), ident(&self.tree.name[&id]))
    }

    /// The object's root: the topmost of its parts above its root part in the export tree (as
    /// in its MJCF).
    fn root(&self) -> PartId {
        object_root(self.scene, self.tree, self.object, &|id| self.in_object(id)).map_or(self.parts[0].id, |p| p.id)
    }

    fn mount(&self, id: PartId, root: PartId) -> Mount<'s> {
        if id == root {
            return Mount::World;
        }
        match self.tree.parent.get(&id).copied().filter(|p| self.in_object(*p)) {
            Some(parent) => match self.tree.joint_into.get(&id) {
                Some(joint) if joint.kind.is_movable() => Mount::Joint(parent, joint),
                _ => Mount::Weld(parent),
            },
            None => Mount::Weld(root),
        }
    }

    fn write(&self, w: &mut UsdaWriter) {
        let name = ident(&object_name(self.scene, self.object));
        // One part is one rigid body fixed to the world: an articulation of a single body is
        // degenerate (the UsdPhysics parser gives it no bodies).
        let apis: &[&str] = if self.parts.len() > 1 { &["PhysicsArticulationRootAPI"] } else { &[] };
        w.open(&format!("def Xform \"{name}\""), apis);
        for part in &self.parts {
            self.write_link(w, part);
        }
        let root = self.root();
        w.open("def Scope \"joints\"", &[]);
        for part in &self.parts {
            self.write_joint(w, part, root);
        }
        w.close();
        w.close();
    }

    fn write_link(&self, w: &mut UsdaWriter, part: &PartModel) {
        let origin = self.tree.origin_world[&part.id];
        let filtered: Vec<String> = self.filtered.get(&part.id).into_iter().flatten().map(|&o| self.path_anywhere(o)).collect();
        let mut apis = vec!["PhysicsRigidBodyAPI", "PhysicsMassAPI"];
        if !filtered.is_empty() {
            apis.push("PhysicsFilteredPairsAPI");
        }
        w.open(&format!("def Xform \"{}\"", ident(&self.tree.name[&part.id])), &apis);
        w.line(&format!("double3 xformOp:translate = {}", tuple(origin)));
        w.line("uniform token[] xformOpOrder = [\"xformOp:translate\"]");
        let prim = &part.primitive;
        let mass = part_mass(prim, self.cfg);
        w.line(&format!("float physics:mass = {}", num(mass)));
        w.line(&format!("point3f physics:centerOfMass = {}", tuple(prim.center() - origin)));
        w.line(&format!("float3 physics:diagonalInertia = {}", tuple(prim.principal_inertia(mass).max(Vec3::splat(1e-6)))));
        w.line(&format!("quatf physics:principalAxes = {}", quat(prim.rotation())));
        if !filtered.is_empty() {
            w.line(&format!("rel physics:filteredPairs = [{}]", filtered.iter().map(|p| format!("<{p}>")).collect::<Vec<_>>().join(", ")));
        }
        write_shape(w, "visual", prim, origin, Some(label_color(&part.label)));
        let collision = self.collisions.primitives.get(&part.id).unwrap_or(prim);
        write_shape(w, "collision", collision, origin, None);
        w.close();
    }

    /// The path of any part of the scene (a filtered pair may cross objects).
    fn path_anywhere(&self, id: PartId) -> String {
        let object = self.scene.part(id).map_or(self.object, |p| p.object);
        format!("/{USD_ROOT}/{}/{}", ident(&object_name(self.scene, object)), ident(&self.tree.name[&id]))
    }

    fn write_joint(&self, w: &mut UsdaWriter, part: &PartModel, root: PartId) {
        let origin = self.tree.origin_world[&part.id];
        let (name, kind, body0, pos0, axis) = match self.mount(part.id, root) {
            Mount::World => (format!("{}_to_world", self.tree.name[&part.id]), "PhysicsFixedJoint", None, origin, None),
            Mount::Weld(parent) => (
                format!("{}_joint", self.tree.name[&part.id]),
                "PhysicsFixedJoint",
                Some(parent),
                origin - self.tree.origin_world[&parent],
                None,
            ),
            Mount::Joint(parent, joint) => {
                let kind = if joint.kind == JointKind::Prismatic { "PhysicsPrismaticJoint" } else { "PhysicsRevoluteJoint" };
                (joint_name(self.scene, part), kind, Some(parent), origin - self.tree.origin_world[&parent], Some(joint))
            }
        };
        let dynamics = self.dynamics.get(&name).copied().unwrap_or_default();
        let apis = axis.map(|j| joint_apis(j, &dynamics)).unwrap_or_default();
        w.open(&format!("def {kind} \"{}\"", ident(&name)), &apis.iter().map(String::as_str).collect::<Vec<_>>());
        if let Some(parent) = body0 {
            w.line(&format!("rel physics:body0 = <{}>", self.path(parent)));
        }
        w.line(&format!("rel physics:body1 = <{}>", self.path(part.id)));
        let frame = axis.map_or(Quat::IDENTITY, |j| rotation_from_x(j.axis_world.normalize_or(Vec3::X)));
        w.line(&format!("point3f physics:localPos0 = {}", tuple(pos0)));
        w.line(&format!("quatf physics:localRot0 = {}", quat(frame)));
        w.line("point3f physics:localPos1 = (0, 0, 0)");
        w.line(&format!("quatf physics:localRot1 = {}", quat(frame)));
        if let Some(joint) = axis {
            write_joint_physics(w, joint, &dynamics);
        }
        w.close();
    }
}

/// The shortest rotation taking +X onto the unit vector `axis`, exact also for nearly parallel
/// vectors (glam's `from_rotation_arc` returns the identity within about 1e-3 rad of +X, which
/// would tilt a joint axis by as much).
fn rotation_from_x(axis: Vec3) -> Quat {
    // From `from` (a unit vector within 90° of `axis`): the half-way quaternion (1 + from·axis, from × axis).
    let arc = |from: Vec3| {
        let c = from.cross(axis);
        Quat::from_xyzw(c.x, c.y, c.z, 1.0 + from.dot(axis)).normalize()
    };
    if Vec3::X.dot(axis) >= 0.0 {
        arc(Vec3::X)
    } else {
        // Half a turn about z first (+X onto −X), then the short arc from −X.
        arc(-Vec3::X) * Quat::from_rotation_z(std::f32::consts::PI)
    }
}

/// The API schemas of a movable joint with `dynamics`.
fn joint_apis(joint: &Joint, d: &JointDynamics) -> Vec<String> {
    let instance = if joint.kind == JointKind::Prismatic { "linear" } else { "angular" };
    let mut apis = Vec::new();
    if d.damping > 0.0 || d.stiffness != 0.0 {
        apis.push(format!("PhysicsDriveAPI:{instance}"));
    }
    if d.frictionloss > 0.0 || d.armature > 0.0 {
        apis.push(format!("PhysxJointAxisAPI:{instance}"));
    }
    apis
}

/// Axis, limits and fitted dynamics of a movable joint. Rotational quantities go in degrees (limits,
/// targets) and per degree (stiffness, damping), as `UsdPhysics` stores them.
fn write_joint_physics(w: &mut UsdaWriter, joint: &Joint, d: &JointDynamics) {
    w.line("uniform token physics:axis = \"X\"");
    let rotational = joint.kind != JointKind::Prismatic;
    let (instance, per_unit) = if rotational { ("angular", 1.0_f64.to_radians()) } else { ("linear", 1.0) };
    let unit = |v: f64| if rotational { v.to_degrees() } else { v };
    let limits = d.range.or_else(|| {
        (joint.kind != JointKind::Continuous).then(|| [f64::from(joint.lower.min(joint.upper)), f64::from(joint.upper.max(joint.lower))])
    });
    if let Some([lo, hi]) = limits {
        w.line(&format!("float physics:lowerLimit = {}", num64(unit(lo))));
        w.line(&format!("float physics:upperLimit = {}", num64(unit(hi))));
    }
    if d.damping > 0.0 || d.stiffness != 0.0 {
        w.line(&format!("uniform token drive:{instance}:physics:type = \"force\""));
        w.line(&format!("float drive:{instance}:physics:damping = {}", num64(d.damping.max(0.0) * per_unit)));
        w.line(&format!("float drive:{instance}:physics:stiffness = {}", num64(d.stiffness * per_unit)));
        w.line(&format!("float drive:{instance}:physics:targetPosition = {}", num64(unit(d.springref))));
        w.line(&format!("float drive:{instance}:physics:targetVelocity = 0"));
    }
    if d.frictionloss > 0.0 || d.armature > 0.0 {
        w.line(&format!("float physxJointAxis:{instance}:staticFrictionEffort = {}", num64(d.frictionloss.max(0.0))));
        w.line(&format!("float physxJointAxis:{instance}:dynamicFrictionEffort = {}", num64(d.frictionloss.max(0.0))));
        w.line(&format!("float physxJointAxis:{instance}:armature = {}", num64(d.armature.max(0.0))));
    }
}

/// One primitive as a USD geometry prim in its link's frame (`link_origin`): the visual one with a
/// colour, the collision one (`color` `None`) with `PhysicsCollisionAPI`, not rendered.
fn write_shape(w: &mut UsdaWriter, name: &str, prim: &Primitive, link_origin: Vec3, color: Option<[f64; 4]>) {
    let h = prim.size * 0.5;
    let (kind, attrs, scale) = match prim.kind {
        // A cube of size 1 scaled to the box: USD's Cube has no per-axis size.
        PrimitiveKind::Cuboid => ("Cube", vec!["double size = 1".to_owned()], Some(prim.size)),
        PrimitiveKind::Cylinder => {
            ("Cylinder", vec![format!("double radius = {}", num(h.x)), format!("double height = {}", num(prim.size.z)), axis_z()], None)
        }
        // USD's capsule height is the straight part, without the caps.
        PrimitiveKind::Capsule if prim.size.z > prim.size.x => (
            "Capsule",
            vec![format!("double radius = {}", num(h.x)), format!("double height = {}", num(prim.size.z - prim.size.x)), axis_z()],
            None,
        ),
        PrimitiveKind::Sphere | PrimitiveKind::Capsule => ("Sphere", vec![format!("double radius = {}", num(h.x))], None),
    };
    let apis: &[&str] = if color.is_some() { &[] } else { &["PhysicsCollisionAPI"] };
    w.open(&format!("def {kind} \"{name}\""), apis);
    for a in attrs {
        w.line(&a);
    }
    match color {
        Some(c) => w.line(&format!("color3f[] primvars:displayColor = [({}, {}, {})]", num64(c[0]), num64(c[1]), num64(c[2]))),
        None => w.line("uniform token purpose = \"guide\""),
    }
    w.line(&format!("double3 xformOp:translate = {}", tuple(prim.center() - link_origin)));
    w.line(&format!("quatf xformOp:orient = {}", quat(prim.rotation())));
    let mut order = vec!["\"xformOp:translate\"", "\"xformOp:orient\""];
    if let Some(s) = scale {
        w.line(&format!("float3 xformOp:scale = {}", tuple(s)));
        order.push("\"xformOp:scale\"");
    }
    w.line(&format!("uniform token[] xformOpOrder = [{}]", order.join(", ")));
    w.close();
}

fn axis_z() -> String {
    "uniform token axis = \"Z\"".to_owned()
}

/// A USD prim name: letters, digits and `_`, not starting with a digit.
fn ident(s: &str) -> String {
    let mut out: String = s.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// Escapes text for a double-quoted USD string.
fn escape(s: &str) -> String {
    s.chars()
        .flat_map(|c| match c {
            '"' => vec!['\\', '"'],
            '\\' => vec!['\\', '\\'],
            '\n' | '\r' | '\t' => vec![' '],
            c => vec![c],
        })
        .collect()
}

fn tuple(v: Vec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

/// USD quaternions are written (w, x, y, z).
fn quat(q: Quat) -> String {
    let q = q.normalize();
    format!("({}, {}, {}, {})", num(q.w), num(q.x), num(q.y), num(q.z))
}

/// Text of a `.usda` layer being written, four-space indent.
#[derive(Default)]
struct UsdaWriter {
    out: String,
    depth: usize,
}

impl UsdaWriter {
    fn line(&mut self, text: &str) {
        if !text.is_empty() {
            for _ in 0..self.depth {
                self.out.push_str("    ");
            }
        }
        self.out.push_str(text);
        self.out.push('\n');
    }

    /// `head` (e.g. `def Xform "name"`) with its API schemas, then `{`.
    fn open(&mut self, head: &str, apis: &[&str]) {
        if apis.is_empty() {
            self.line(head);
        } else {
            let list: Vec<String> = apis.iter().map(|a| format!("\"{a}\"")).collect();
            self.line(&format!("{head} ("));
            self.depth += 1;
            self.line(&format!("prepend apiSchemas = [{}]", list.join(", ")));
            self.depth -= 1;
            self.line(")");
        }
        self.line("{");
        self.depth += 1;
    }

    fn close(&mut self) {
        self.depth = self.depth.saturating_sub(1);
        self.line("}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_joint_frame_turns_x_onto_the_axis_also_when_nearly_parallel() {
        // Regression: an oven knob's axis (1, 1.06e-4, 0) came out as +X exactly.
        for axis in [
            Vec3::new(1.0, 1.06e-4, 0.0),
            Vec3::Y,
            -Vec3::X,
            Vec3::new(-1.0, 1e-4, 2e-4),
            Vec3::new(-0.999_999_8, 6.8e-4, 1.4e-4),
            Vec3::new(0.3, -0.5, 0.8),
            Vec3::new(-0.3, 0.5, -0.8),
        ] {
            let axis = axis.normalize();
            let turned = rotation_from_x(axis) * Vec3::X;
            assert!((turned - axis).length() < 1e-6, "{axis} → {turned}");
        }
    }

    #[test]
    fn prim_names_are_usd_identifiers() {
        assert_eq!(ident("cabinet3_door17"), "cabinet3_door17");
        assert_eq!(ident("3d-part"), "_3d_part");
        assert_eq!(ident(""), "_");
    }
}
