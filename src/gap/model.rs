//! The URDF as the gap analysis needs it (spec §1): links with mass, centre of mass and inertia
//! (from `<inertial>`, else the link's primitives at 600 kg/m³), 1-DoF joints with axis, limits
//! and `<dynamics>`, forward kinematics, and per joint the inertia of the subtree it moves and the
//! gravity torque about it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DMat3, DQuat, DVec3, EulerRot};

use super::error::GapError;
use crate::dynamics::spatial::{ParentFromChild, RigidInertia};
use crate::dynamics::{Body, JointMotion, MultiBody};

/// Density given to a link without `<inertial>`, kg/m³ (spec §1).
pub const DEFAULT_DENSITY_KG_M3: f64 = 600.0;

/// A rigid transform in f64 (`parent_from_child` style).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iso {
    /// Rotation.
    pub rotation: DQuat,
    /// Translation, metres.
    pub translation: DVec3,
}

impl Iso {
    /// The identity.
    pub const IDENTITY: Self = Self { rotation: DQuat::IDENTITY, translation: DVec3::ZERO };

    /// From a URDF `<origin xyz rpy>`.
    #[must_use]
    pub fn from_urdf(pose: &urdf_rs::Pose) -> Self {
        let [x, y, z] = pose.xyz.0;
        let [roll, pitch, yaw] = pose.rpy.0;
        Self { rotation: DQuat::from_euler(EulerRot::ZYX, yaw, pitch, roll), translation: DVec3::new(x, y, z) }
    }

    /// `self ∘ other`.
    #[must_use]
    pub fn mul(&self, other: &Self) -> Self {
        Self { rotation: (self.rotation * other.rotation).normalize(), translation: self.translation + self.rotation * other.translation }
    }

    /// The inverse transform.
    #[must_use]
    pub fn inverse(&self) -> Self {
        let r = self.rotation.inverse();
        Self { rotation: r, translation: -(r * self.translation) }
    }

    /// Maps a point.
    #[must_use]
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.translation + self.rotation * p
    }
}

/// Joint types the analysis distinguishes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DofKind {
    /// Welded.
    Fixed,
    /// Rotation with stops.
    Revolute,
    /// Rotation without stops.
    Continuous,
    /// Translation with stops.
    Prismatic,
}

impl DofKind {
    /// Rotational (rad) rather than translational (m).
    #[must_use]
    pub fn is_rotational(self) -> bool {
        matches!(self, Self::Revolute | Self::Continuous)
    }
}

/// A link's mass properties in its own frame.
#[derive(Debug, Clone)]
pub struct GapLink {
    /// URDF name.
    pub name: String,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass in the link frame, m.
    pub com_link_m: DVec3,
    /// Inertia about the centre of mass, link-frame axes, kg·m².
    pub inertia_link: DMat3,
    /// True when the mass came from primitives at [`DEFAULT_DENSITY_KG_M3`].
    pub from_primitives: bool,
}

/// A joint of the model.
#[derive(Debug, Clone)]
pub struct GapJoint {
    /// URDF name.
    pub name: String,
    /// Type.
    pub kind: DofKind,
    /// Parent link index.
    pub parent: usize,
    /// Child link index.
    pub child: usize,
    /// `<origin>`: parent link frame ← joint frame (= child frame at q = 0).
    pub parent_from_joint: Iso,
    /// Unit axis in the joint frame.
    pub axis_joint: DVec3,
    /// Lower hard stop (revolute / prismatic).
    pub lower: Option<f64>,
    /// Upper hard stop.
    pub upper: Option<f64>,
    /// `<dynamics damping>` (N·m·s/rad or N·s/m).
    pub damping: f64,
    /// `<dynamics friction>` (N·m or N).
    pub friction: f64,
}

/// Per-joint rigid-body terms at a configuration: `inertia · a = effort + gravity(q) + …`,
/// gravity(q) = `gravity_const + gravity_cos·cos q + gravity_sin·sin q` (revolute; prismatic only
/// the constant).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointTerms {
    /// Inertia of the moving subtree along the joint (kg·m² or kg).
    pub inertia: f64,
    /// Constant part of the gravity effort.
    pub gravity_const: f64,
    /// Coefficient of cos q.
    pub gravity_cos: f64,
    /// Coefficient of sin q.
    pub gravity_sin: f64,
    /// Mass of the moving subtree, kg.
    pub subtree_mass_kg: f64,
    /// Distance of the subtree's centre of mass from the axis, m (0 for prismatic).
    pub com_radius_m: f64,
    /// Effort on this joint from the recorded motion of the other joints (their accelerations,
    /// Coriolis and centrifugal terms), which a 1-DoF replay would otherwise drop.
    pub coupling: f64,
}

impl JointTerms {
    /// Gravity effort at position q.
    #[must_use]
    pub fn gravity(&self, q: f64) -> f64 {
        self.gravity_const + self.gravity_cos * q.cos() + self.gravity_sin * q.sin()
    }
}

/// The model: links, joints, the tree.
#[derive(Debug, Clone)]
pub struct GapModel {
    /// Where it was read from.
    pub file: PathBuf,
    /// Links in URDF order.
    pub links: Vec<GapLink>,
    /// Joints in URDF order.
    pub joints: Vec<GapJoint>,
    /// The root link (fixed to the world at identity).
    pub root: usize,
    /// Joint indices, parents before children.
    pub order: Vec<usize>,
    /// For each link, the joint whose child it is.
    pub parent_joint: Vec<Option<usize>>,
    /// What the reader assumed (links massed from primitives, meshes without mass…).
    pub notes: Vec<String>,
    /// The parsed URDF, to write the fitted model from.
    pub robot: urdf_rs::Robot,
}

/// Reads a URDF model from disk.
pub fn load_model(path: &Path) -> Result<GapModel, GapError> {
    let bytes = crate::io::read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    parse_model(&text, path)
}

fn primitive_mass(geometry: &urdf_rs::Geometry) -> Option<(f64, DMat3)> {
    let rho = DEFAULT_DENSITY_KG_M3;
    match geometry {
        urdf_rs::Geometry::Box { size } => {
            let [a, b, c] = size.0;
            let m = rho * a * b * c;
            Some((m, DMat3::from_diagonal(DVec3::new(b * b + c * c, a * a + c * c, a * a + b * b) * (m / 12.0))))
        }
        urdf_rs::Geometry::Cylinder { radius, length } => {
            let m = rho * std::f64::consts::PI * radius * radius * length;
            let side = m * (3.0 * radius * radius + length * length) / 12.0;
            Some((m, DMat3::from_diagonal(DVec3::new(side, side, m * radius * radius / 2.0))))
        }
        urdf_rs::Geometry::Capsule { radius, length } => {
            let mc = rho * std::f64::consts::PI * radius * radius * length;
            let ms = rho * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
            let side = mc * (3.0 * radius * radius + length * length) / 12.0 + ms * (0.4 * radius * radius + length * length / 4.0);
            Some((mc + ms, DMat3::from_diagonal(DVec3::new(side, side, mc * radius * radius / 2.0 + 0.4 * ms * radius * radius))))
        }
        urdf_rs::Geometry::Sphere { radius } => {
            let m = rho * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
            Some((m, DMat3::from_diagonal(DVec3::splat(0.4 * m * radius * radius))))
        }
        urdf_rs::Geometry::Mesh { .. } => None,
    }
}

/// Combines bodies `(mass, com, inertia about com, all in one frame)` by the parallel-axis theorem.
fn combine(bodies: &[(f64, DVec3, DMat3)]) -> (f64, DVec3, DMat3) {
    let mass: f64 = bodies.iter().map(|b| b.0).sum();
    if mass <= 0.0 {
        return (0.0, DVec3::ZERO, DMat3::ZERO);
    }
    let com = bodies.iter().map(|b| b.1 * b.0).sum::<DVec3>() / mass;
    let mut inertia = DMat3::ZERO;
    for &(m, c, i) in bodies {
        let d = c - com;
        inertia += i + (DMat3::IDENTITY * d.length_squared() - outer(d, d)) * m;
    }
    (mass, com, inertia)
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Names of the links that have an `<inertial>` element (urdf-rs reads a missing one as zeros).
fn links_with_inertial(text: &str) -> std::collections::BTreeSet<String> {
    let Ok(doc) = roxmltree::Document::parse(text) else { return std::collections::BTreeSet::new() };
    doc.root_element()
        .children()
        .filter(|n| n.has_tag_name("link") && n.children().any(|c| c.has_tag_name("inertial")))
        .filter_map(|n| n.attribute("name").map(str::to_owned))
        .collect()
}

/// Parses URDF text; `file` names it in messages.
pub fn parse_model(text: &str, file: &Path) -> Result<GapModel, GapError> {
    // Vectors written with commas (`xyz="0, 0, 1"`, found in published URDFs) are read as the
    // asset importer reads them, and noted.
    let (normalised, commas) = crate::assets::urdf::normalise_vector_commas(text, file)
        .map_err(|e| GapError::Urdf { file: file.to_path_buf(), message: e.to_string() })?;
    let text = normalised.as_str();
    let robot = urdf_rs::read_from_string(text).map_err(|e| GapError::Urdf { file: file.to_path_buf(), message: e.to_string() })?;
    let model_error = |field: String, message: String| GapError::Model { file: file.to_path_buf(), field, message };
    let mut notes = Vec::new();
    if commas > 0 {
        notes.push(format!("{commas} vector attribute(s) written with commas were read as space-separated"));
    }
    let with_inertial = links_with_inertial(text);
    let mut index_of: BTreeMap<&str, usize> = BTreeMap::new();
    let mut links = Vec::with_capacity(robot.links.len());
    for (i, link) in robot.links.iter().enumerate() {
        if index_of.insert(link.name.as_str(), i).is_some() {
            return Err(model_error(format!("link {}", link.name), "defined twice".into()));
        }
        let inertial = &link.inertial;
        let i3 = &inertial.inertia;
        // An `<inertial>` written with mass 0 is a massless link, as every other URDF reader
        // takes it; only a link without the element gets its primitives' mass (spec §1).
        let declared =
            with_inertial.contains(link.name.as_str()) || inertial.mass.value > 0.0 || [i3.ixx, i3.iyy, i3.izz].iter().any(|v| *v > 0.0);
        if declared {
            let origin = Iso::from_urdf(&inertial.origin);
            let r = DMat3::from_quat(origin.rotation);
            let local = DMat3::from_cols(
                DVec3::new(i3.ixx, i3.ixy, i3.ixz),
                DVec3::new(i3.ixy, i3.iyy, i3.iyz),
                DVec3::new(i3.ixz, i3.iyz, i3.izz),
            );
            links.push(GapLink {
                name: link.name.clone(),
                mass_kg: inertial.mass.value,
                com_link_m: origin.translation,
                inertia_link: r * local * r.transpose(),
                from_primitives: false,
            });
            continue;
        }
        let geoms: Vec<(&urdf_rs::Pose, &urdf_rs::Geometry)> = if link.collision.is_empty() {
            link.visual.iter().map(|v| (&v.origin, &v.geometry)).collect()
        } else {
            link.collision.iter().map(|c| (&c.origin, &c.geometry)).collect()
        };
        let mut bodies = Vec::new();
        for (origin, geometry) in geoms {
            if let Some((m, inertia)) = primitive_mass(geometry) {
                let pose = Iso::from_urdf(origin);
                let r = DMat3::from_quat(pose.rotation);
                bodies.push((m, pose.translation, r * inertia * r.transpose()));
            } else {
                notes.push(format!("link {}: mesh geometry has no mass here (no <inertial>)", link.name));
            }
        }
        let (mass, com, inertia) = combine(&bodies);
        if !bodies.is_empty() {
            notes.push(format!(
                "link {} has no <inertial>: mass {mass:.3} kg from its primitives at {DEFAULT_DENSITY_KG_M3} kg/m^3",
                link.name
            ));
        }
        links.push(GapLink { name: link.name.clone(), mass_kg: mass, com_link_m: com, inertia_link: inertia, from_primitives: true });
    }

    let mut joints = Vec::with_capacity(robot.joints.len());
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        let field = format!("joint {}", joint.name);
        let kind = match joint.joint_type {
            urdf_rs::JointType::Fixed => DofKind::Fixed,
            urdf_rs::JointType::Revolute => DofKind::Revolute,
            urdf_rs::JointType::Continuous => DofKind::Continuous,
            urdf_rs::JointType::Prismatic => DofKind::Prismatic,
            ref other => {
                return Err(model_error(field, format!("type {other:?} is not supported (revolute, continuous, prismatic, fixed)")));
            }
        };
        let find = |name: &str| index_of.get(name).copied().ok_or_else(|| model_error(field.clone(), format!("unknown link {name:?}")));
        let parent = find(&joint.parent.link)?;
        let child = find(&joint.child.link)?;
        if parent_joint[child].replace(j).is_some() {
            return Err(model_error(field, format!("link {} has two parent joints", joint.child.link)));
        }
        let axis = DVec3::from_array(joint.axis.xyz.0);
        let axis_joint = if kind == DofKind::Fixed {
            DVec3::X
        } else {
            axis.try_normalize().ok_or_else(|| model_error(field.clone(), "axis has zero length".into()))?
        };
        let limited = matches!(kind, DofKind::Revolute | DofKind::Prismatic) && joint.limit.lower < joint.limit.upper;
        let dynamics = joint.dynamics.as_ref();
        joints.push(GapJoint {
            name: joint.name.clone(),
            kind,
            parent,
            child,
            parent_from_joint: Iso::from_urdf(&joint.origin),
            axis_joint,
            lower: limited.then_some(joint.limit.lower),
            upper: limited.then_some(joint.limit.upper),
            damping: dynamics.map_or(0.0, |d| d.damping.max(0.0)),
            friction: dynamics.map_or(0.0, |d| d.friction.max(0.0)),
        });
    }
    let roots: Vec<usize> = (0..links.len()).filter(|&l| parent_joint[l].is_none()).collect();
    let [root] = roots[..] else {
        return Err(model_error("links".into(), format!("expected exactly one root link, found {}", roots.len())));
    };
    // Parents before children; a cycle leaves joints unordered.
    let mut order = Vec::with_capacity(joints.len());
    let mut frontier = vec![root];
    while let Some(link) = frontier.pop() {
        for (j, joint) in joints.iter().enumerate() {
            if joint.parent == link {
                order.push(j);
                frontier.push(joint.child);
            }
        }
    }
    if order.len() != joints.len() {
        return Err(model_error("joints".into(), "the joints do not form a tree".into()));
    }
    Ok(GapModel { file: file.to_path_buf(), links, joints, root, order, parent_joint, notes, robot })
}

impl GapModel {
    /// The model as a multibody tree: one body per link below the root, coordinates in the order
    /// of [`GapModel::dofs`]; `bodies_of_link[l]` is link `l`'s body (None for the root).
    pub fn multibody(&self) -> Result<(MultiBody, Vec<Option<usize>>), GapError> {
        let dofs = self.dofs();
        let mut body_of_link: Vec<Option<usize>> = vec![None; self.links.len()];
        let mut bodies = Vec::with_capacity(self.joints.len());
        for &j in &self.order {
            let joint = &self.joints[j];
            let link = &self.links[joint.child];
            let motion = match joint.kind {
                DofKind::Fixed => JointMotion::Fixed,
                DofKind::Revolute | DofKind::Continuous => JointMotion::Revolute(joint.axis_joint),
                DofKind::Prismatic => JointMotion::Prismatic(joint.axis_joint),
            };
            body_of_link[joint.child] = Some(bodies.len());
            bodies.push(Body {
                name: link.name.clone(),
                parent: body_of_link[joint.parent],
                parent_from_joint: ParentFromChild::new(joint.parent_from_joint.rotation, joint.parent_from_joint.translation),
                joint: motion,
                dof: dofs.iter().position(|&d| d == j),
                inertia: RigidInertia::from_com(link.mass_kg, link.com_link_m, link.inertia_link),
            });
        }
        let tree = MultiBody::new(bodies).map_err(|e| GapError::Model {
            file: self.file.clone(),
            field: "joints".into(),
            message: e.to_string(),
        })?;
        Ok((tree, body_of_link))
    }

    /// Index of the joint named `name`.
    #[must_use]
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Index of the link named `name`.
    #[must_use]
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// The movable joints none of whose descendants is in `observed` (model joint indices,
    /// sorted): a subtree nothing measures, such as a gripper's fingers on an arm whose joints
    /// alone are logged.
    #[must_use]
    pub fn unobserved_subtrees(&self, observed: &[usize]) -> Vec<usize> {
        let mut seen_below = vec![false; self.joints.len()];
        for &k in observed {
            // Mark k and every joint above it.
            let mut at = Some(k);
            while let Some(j) = at {
                if seen_below[j] {
                    break;
                }
                seen_below[j] = true;
                at = self.parent_joint[self.joints[j].parent];
            }
        }
        self.dofs().into_iter().filter(|&j| !seen_below[j]).collect()
    }

    /// The model with `joints` welded at position 0 (their frame at q = 0, as the URDF places
    /// the child): what an analysis that holds an unobserved joint at 0 sees. Joint indices
    /// and names are unchanged; the parsed URDF is kept as read.
    #[must_use]
    pub fn with_welded(&self, joints: &[usize]) -> Self {
        let mut welded = self.clone();
        for &j in joints {
            welded.joints[j].kind = DofKind::Fixed;
        }
        welded
    }

    /// Movable joints (degrees of freedom), URDF order.
    #[must_use]
    pub fn dofs(&self) -> Vec<usize> {
        (0..self.joints.len()).filter(|&j| self.joints[j].kind != DofKind::Fixed).collect()
    }

    /// The joint's motion at position q: joint frame ← child frame.
    #[must_use]
    pub fn joint_motion(&self, j: usize, q: f64) -> Iso {
        let joint = &self.joints[j];
        match joint.kind {
            DofKind::Fixed => Iso::IDENTITY,
            DofKind::Revolute | DofKind::Continuous => {
                Iso { rotation: DQuat::from_axis_angle(joint.axis_joint, q), translation: DVec3::ZERO }
            }
            DofKind::Prismatic => Iso { rotation: DQuat::IDENTITY, translation: joint.axis_joint * q },
        }
    }

    /// World pose of every link for joint positions `q` (indexed by joint; fixed joints ignored).
    #[must_use]
    pub fn world_from_links(&self, q: &[f64]) -> Vec<Iso> {
        let mut poses = vec![Iso::IDENTITY; self.links.len()];
        for &j in &self.order {
            let joint = &self.joints[j];
            let qj = q.get(j).copied().filter(|v| v.is_finite()).unwrap_or(0.0);
            poses[joint.child] = poses[joint.parent].mul(&joint.parent_from_joint).mul(&self.joint_motion(j, qj));
        }
        poses
    }

    /// Links moved by joint `j` (its child and everything below).
    #[must_use]
    pub fn subtree(&self, j: usize) -> Vec<usize> {
        let mut out = vec![self.joints[j].child];
        let mut k = 0;
        while k < out.len() {
            let link = out[k];
            out.extend(self.joints.iter().filter(|jt| jt.parent == link).map(|jt| jt.child));
            k += 1;
        }
        out
    }

    /// World frame of joint `j` at its zero position, the others at `q`; and the world axis.
    #[must_use]
    pub fn joint_frame_world(&self, j: usize, q: &[f64]) -> (Iso, DVec3) {
        let poses = self.world_from_links(q);
        let joint = &self.joints[j];
        let frame = poses[joint.parent].mul(&joint.parent_from_joint);
        (frame, frame.rotation * joint.axis_joint)
    }

    /// Mass, centre of mass (world) and inertia about it (world axes) of the links moved by `j`,
    /// with `j` at zero and the other joints at `q`.
    #[must_use]
    pub fn subtree_mass_world(&self, j: usize, q: &[f64]) -> (f64, DVec3, DMat3) {
        let mut q0 = q.to_vec();
        if let Some(v) = q0.get_mut(j) {
            *v = 0.0;
        }
        let poses = self.world_from_links(&q0);
        let bodies: Vec<(f64, DVec3, DMat3)> = self
            .subtree(j)
            .into_iter()
            .map(|l| {
                let link = &self.links[l];
                let r = DMat3::from_quat(poses[l].rotation);
                (link.mass_kg, poses[l].transform_point(link.com_link_m), r * link.inertia_link * r.transpose())
            })
            .collect();
        combine(&bodies)
    }

    /// Rigid-body terms of joint `j` with the other joints at `q` (moving subtree held rigid).
    #[must_use]
    pub fn joint_terms(&self, j: usize, q: &[f64], gravity: DVec3) -> JointTerms {
        let (frame, axis) = self.joint_frame_world(j, q);
        let (mass, com, inertia_com) = self.subtree_mass_world(j, q);
        let d = com - frame.translation;
        let d_perp = d - axis * d.dot(axis);
        match self.joints[j].kind {
            DofKind::Prismatic => {
                JointTerms { inertia: mass, gravity_const: mass * gravity.dot(axis), subtree_mass_kg: mass, ..JointTerms::default() }
            }
            DofKind::Fixed => JointTerms::default(),
            DofKind::Revolute | DofKind::Continuous => JointTerms {
                inertia: axis.dot(inertia_com * axis) + mass * d_perp.length_squared(),
                gravity_const: 0.0,
                gravity_cos: mass * axis.dot(d_perp.cross(gravity)),
                gravity_sin: mass * axis.dot(axis.cross(d_perp).cross(gravity)),
                subtree_mass_kg: mass,
                com_radius_m: d_perp.length(),
                coupling: 0.0,
            },
        }
    }

    /// The movable joint that moves `link` and the pose of the link in that joint's child frame
    /// (walking up through fixed joints).
    #[must_use]
    pub fn moving_joint_of(&self, link: usize) -> Option<(usize, Iso)> {
        let mut child_from_link = Iso::IDENTITY;
        let mut current = link;
        loop {
            let j = self.parent_joint[current]?;
            let joint = &self.joints[j];
            if joint.kind != DofKind::Fixed {
                return Some((j, child_from_link));
            }
            child_from_link = joint.parent_from_joint.mul(&child_from_link);
            current = joint.parent;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOOR: &str = r#"<robot name="c">
      <link name="body"><inertial><mass value="10"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="door"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.02 0.8"/></geometry></collision></link>
      <joint name="hinge" type="revolute"><parent link="body"/><child link="door"/><origin xyz="1 0 0"/><axis xyz="0 1 0"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    </robot>"#;

    #[test]
    fn primitives_give_mass_and_inertia_about_the_hinge() {
        let m = parse_model(DOOR, Path::new("door.urdf")).expect("model");
        let door = &m.links[1];
        let mass = 600.0 * 0.6 * 0.02 * 0.8;
        assert!((door.mass_kg - mass).abs() < 1e-9 && door.from_primitives);
        let t = m.joint_terms(0, &[0.0], DVec3::new(0.0, 0.0, -9.81));
        // Box about its edge, axis y: m (a² + c²)/12 + m (a/2)².
        let expected = mass * (0.36 + 0.64) / 12.0 + mass * 0.09;
        assert!((t.inertia - expected).abs() < 1e-9, "{}", t.inertia);
        // Horizontal door on a horizontal hinge: gravity pulls down with m g r at q = 0.
        assert!((t.gravity(0.0).abs() - mass * 9.81 * 0.3).abs() < 1e-9);
        // At q = π/2 (rotation about +y takes +x to -z) the door hangs: no torque.
        assert!(t.gravity(std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!(m.notes.iter().any(|n| n.contains("600")));
    }

    /// Published URDFs (Habitat's `ReplicaCAD`) write some vectors with commas; urdf-rs alone refused
    /// them, so `partscene gap` could not read those models.
    #[test]
    fn vectors_written_with_commas_read_as_with_spaces() {
        let commas = DOOR.replace(r#"<origin xyz="1 0 0"/><axis xyz="0 1 0"/>"#, r#"<origin xyz="1, 0, 0"/><axis xyz="0,1,0"/>"#);
        assert_ne!(commas, DOOR);
        let (a, b) =
            (parse_model(DOOR, Path::new("door.urdf")).expect("spaces"), parse_model(&commas, Path::new("door.urdf")).expect("commas"));
        let q = [0.3];
        let g = DVec3::new(0.0, 0.0, -9.81);
        assert!((a.joint_terms(0, &q, g).inertia - b.joint_terms(0, &q, g).inertia).abs() < 1e-12);
        assert!((a.joint_terms(0, &q, g).gravity(0.3) - b.joint_terms(0, &q, g).gravity(0.3)).abs() < 1e-12);
        assert!(b.notes.iter().any(|n| n.contains("2 vector attribute(s) written with commas")), "{:?}", b.notes);
    }
}
