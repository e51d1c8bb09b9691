//! One in-memory model for an articulated asset read from URDF or MJCF, at its rest pose (q = 0),
//! with every pose, axis and vertex in the model root frame ("world").

use crate::kinematics::JointKind;
use crate::math::{Pose, Vec3};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::report::Warning;

/// An articulated object made by another project: rigid links, the joints between them and the
/// problems met while reading it.
#[derive(Clone, Debug, Default)]
pub struct ArticulatedAsset {
    /// The model's own name (`<robot name>`, `<mujoco model>`), else the file stem.
    pub name: String,
    /// Links in file order (MJCF: depth-first body order, the world body first).
    pub links: Vec<AssetLink>,
    /// Joints in file order. Every non-root link has at least one parent joint (bodies welded to
    /// their parent in MJCF get a [`JointKind::Fixed`] joint), so links and joints form a tree.
    pub joints: Vec<AssetJoint>,
    /// Problems carried past: missing or unreadable meshes, unsupported geoms or joint types.
    pub warnings: Vec<Warning>,
}

/// A rigid link (URDF link, MJCF body) at rest.
#[derive(Clone, Debug)]
pub struct AssetLink {
    pub name: String,
    /// Whether the file gave the link its name. A name the reader made up for an unnamed body
    /// (MJCF `body7`) says nothing about what the part is, and is never read as a label.
    pub named: bool,
    /// The link frame in the model root frame at q = 0.
    pub world_from_link: Pose,
    /// Visual and collision geometry, in the model root frame.
    pub geoms: Vec<AssetGeom>,
}

/// Whether a geom is drawn or collides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum GeomRole {
    /// URDF `<visual>`; MJCF geom with `contype = conaffinity = 0` (it never collides).
    Visual,
    /// URDF `<collision>`; MJCF geom that can collide.
    Collision,
}

/// One piece of geometry of a link.
#[derive(Clone, Debug)]
pub struct AssetGeom {
    /// The geom's own frame in the model root frame (for primitives the same as the primitive's
    /// `world_from_primitive`; for meshes the frame the file's vertices were given in).
    pub world_from_geom: Pose,
    pub shape: GeomShape,
    pub role: GeomRole,
    /// Names the file gives the geom, as written: its own name, its mesh's name (MJCF) or mesh
    /// file stem (URDF), its material's name. Empty when the file names nothing. Read for
    /// semantic words (a mesh called `…_handle_vis` is a handle), never for joint types.
    pub names: Vec<String>,
}

/// The shape of a geom, already placed in the model root frame.
#[derive(Clone, Debug)]
pub enum GeomShape {
    /// Box, cylinder, sphere or capsule with full sizes (our convention, see [`Primitive`]).
    Primitive(Primitive),
    /// A triangle mesh, scale applied, vertices in the model root frame.
    Mesh { vertices: Vec<Vec3>, triangles: Vec<[u32; 3]> },
}

/// A joint at rest, in the model root frame.
#[derive(Clone, Debug, PartialEq)]
pub struct AssetJoint {
    pub name: String,
    /// URDF continuous joints are [`JointKind::Revolute`] with infinite limits.
    pub kind: JointKind,
    /// Parent link name.
    pub parent: String,
    /// Child link name.
    pub child: String,
    /// Unit axis in the model root frame, signed as in the file (+X for fixed joints).
    pub axis_world: Vec3,
    /// A point on the axis: the joint frame's origin at q = 0.
    pub origin_world: Vec3,
    /// Lower limit, radians (revolute) or metres (prismatic); `-inf` when the file sets none,
    /// 0 for fixed joints.
    pub lower: f32,
    /// Upper limit, as `lower`; `+inf` when the file sets none.
    pub upper: f32,
}

impl ArticulatedAsset {
    /// The link called `name`.
    #[must_use]
    pub fn link(&self, name: &str) -> Option<&AssetLink> {
        self.links.iter().find(|l| l.name == name)
    }

    /// Joints that move (prismatic and revolute), in file order.
    pub fn movable_joints(&self) -> impl Iterator<Item = &AssetJoint> {
        self.joints.iter().filter(|j| j.kind.is_movable())
    }

    /// Links that are no joint's child (the model root; several if the file has several trees).
    #[must_use]
    pub fn root_links(&self) -> Vec<&AssetLink> {
        self.links.iter().filter(|l| !self.joints.iter().any(|j| j.child == l.name)).collect()
    }

    /// Every primitive geom of the model with its link name and role.
    #[must_use]
    pub fn primitives(&self) -> Vec<(&str, GeomRole, &Primitive)> {
        self.links
            .iter()
            .flat_map(|l| {
                l.geoms.iter().filter_map(move |g| match &g.shape {
                    GeomShape::Primitive(p) => Some((l.name.as_str(), g.role, p)),
                    GeomShape::Mesh { .. } => None,
                })
            })
            .collect()
    }
}

impl AssetLink {
    /// The geometry that best describes the link's shape: its collision primitives when it has
    /// any (designed simplifications), else its visual meshes, else collision meshes, else visual
    /// primitives. Empty for links without geometry.
    #[must_use]
    pub fn preferred_geoms(&self) -> Vec<&AssetGeom> {
        let classes: [(GeomRole, bool); 4] =
            [(GeomRole::Collision, true), (GeomRole::Visual, false), (GeomRole::Collision, false), (GeomRole::Visual, true)];
        for (role, primitive) in classes {
            let found: Vec<&AssetGeom> = self.geoms.iter().filter(|g| g.role == role && g.is_primitive() == primitive).collect();
            if !found.is_empty() {
                return found;
            }
        }
        Vec::new()
    }
}

impl AssetGeom {
    /// True for box, cylinder, sphere and capsule geoms.
    #[must_use]
    pub fn is_primitive(&self) -> bool {
        matches!(self.shape, GeomShape::Primitive(_))
    }

    /// A primitive geom placed at `world_from_geom` with full extents `size` (see [`Primitive`]).
    #[must_use]
    pub fn primitive(kind: PrimitiveKind, size: Vec3, world_from_geom: Pose, role: GeomRole) -> Self {
        Self { world_from_geom, shape: GeomShape::Primitive(Primitive::new(kind, size, world_from_geom)), role, names: Vec::new() }
    }

    /// A mesh geom: `vertices_geom` (scale applied) are moved into the model root frame.
    #[must_use]
    pub fn mesh(vertices_geom: &[Vec3], triangles: Vec<[u32; 3]>, world_from_geom: Pose, role: GeomRole) -> Self {
        let vertices = vertices_geom.iter().map(|&v| world_from_geom.transform_point(v)).collect();
        Self { world_from_geom, shape: GeomShape::Mesh { vertices, triangles }, role, names: Vec::new() }
    }

    /// The geom with the names its file gives it (empty names are dropped).
    #[must_use]
    pub fn named<S: AsRef<str>>(mut self, names: impl IntoIterator<Item = S>) -> Self {
        self.names.extend(names.into_iter().map(|n| n.as_ref().trim().to_owned()).filter(|n| !n.is_empty()));
        self
    }

    /// Axis-aligned bounds in the model root frame.
    #[must_use]
    pub fn aabb(&self) -> Option<(Vec3, Vec3)> {
        match &self.shape {
            GeomShape::Primitive(p) => Some(p.aabb()),
            GeomShape::Mesh { vertices, .. } => {
                let first = *vertices.first()?;
                Some(vertices.iter().fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v))))
            }
        }
    }
}
