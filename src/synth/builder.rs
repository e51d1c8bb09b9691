//! Objects in their own frame and how they are placed in the world.
//!
//! The object frame: x to the right when facing the object's front, y = the outward front normal,
//! z up, the floor (or the supporting surface) at z = 0. Generators build parts and joints there;
//! [`Furniture::place`] turns them into a [`TruthObject`] in the world.

use crate::kinematics::{Joint, JointKind};
use crate::math::{Pose, Quat, Vec2, Vec3};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::{ObjectId, PartId};
use crate::truth::{TruthObject, TruthPart};

/// A part in the object frame.
#[derive(Clone, Debug)]
pub struct LocalPart {
    /// Semantic label from the scan-format vocabulary (`body`, `door`, `drawer`, ...).
    pub label: &'static str,
    /// Geometry in the object frame.
    pub shapes: Vec<Primitive>,
}

/// A joint between two parts (indices into [`Furniture::parts`]), in the object frame.
#[derive(Clone, Copy, Debug)]
pub struct LocalJoint {
    /// Index of the parent part.
    pub parent: usize,
    /// Index of the child part.
    pub child: usize,
    /// Fixed, prismatic or revolute.
    pub kind: JointKind,
    /// Unit axis in the object frame; positive motion opens.
    pub axis_object: Vec3,
    /// A point on the axis, object frame.
    pub origin_object: Vec3,
    /// Lower limit (metres or radians; 0 for fixed joints).
    pub lower: f32,
    /// Upper limit (metres or radians; 0 for fixed joints).
    pub upper: f32,
}

/// A procedurally generated object in its own frame, with its kinematic tree.
#[derive(Clone, Debug)]
pub struct Furniture {
    /// Category word (`cabinet`, `microwave`, `table`, ...).
    pub category: &'static str,
    /// Parts; index 0 is the root of the kinematic tree.
    pub parts: Vec<LocalPart>,
    /// One joint per non-root part.
    pub joints: Vec<LocalJoint>,
}

impl Furniture {
    /// An empty object of a category.
    #[must_use]
    pub fn new(category: &'static str) -> Self {
        Self { category, parts: Vec::new(), joints: Vec::new() }
    }

    /// Adds a part made of one primitive; returns its index.
    pub fn add_part(&mut self, label: &'static str, shape: Primitive) -> usize {
        self.parts.push(LocalPart { label, shapes: vec![shape] });
        self.parts.len() - 1
    }

    /// Adds a part fixed to `parent` (origin at the child's centre, axis +z, limits 0).
    pub fn add_fixed(&mut self, parent: usize, label: &'static str, shape: Primitive) -> usize {
        let child = self.add_part(label, shape);
        self.joints.push(LocalJoint {
            parent,
            child,
            kind: JointKind::Fixed,
            axis_object: Vec3::Z,
            origin_object: shape.center(),
            lower: 0.0,
            upper: 0.0,
        });
        child
    }

    /// Adds a part sliding along `axis_object` from 0 to `upper_m`, origin at its centre.
    pub fn add_prismatic(&mut self, parent: usize, label: &'static str, shape: Primitive, axis_object: Vec3, upper_m: f32) -> usize {
        let child = self.add_part(label, shape);
        self.joints.push(LocalJoint {
            parent,
            child,
            kind: JointKind::Prismatic,
            axis_object: axis_object.normalize_or(Vec3::Y),
            origin_object: shape.center(),
            lower: 0.0,
            upper: upper_m,
        });
        child
    }

    /// Adds a part turning about the line (`origin_object`, `axis_object`) from 0 to `upper_rad`.
    pub fn add_revolute(
        &mut self,
        parent: usize,
        label: &'static str,
        shape: Primitive,
        axis_object: Vec3,
        origin_object: Vec3,
        upper_rad: f32,
    ) -> usize {
        let child = self.add_part(label, shape);
        self.joints.push(LocalJoint {
            parent,
            child,
            kind: JointKind::Revolute,
            axis_object: axis_object.normalize_or(Vec3::Z),
            origin_object,
            lower: 0.0,
            upper: upper_rad,
        });
        child
    }

    /// Footprint of the object in its own frame: (min, max) over x, y of every shape's bounds.
    #[must_use]
    pub fn footprint(&self) -> (Vec2, Vec2) {
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        for shape in self.parts.iter().flat_map(|p| p.shapes.iter()) {
            let (a, b) = shape.aabb();
            lo = lo.min(a.truncate());
            hi = hi.max(b.truncate());
        }
        if lo.x > hi.x {
            return (Vec2::ZERO, Vec2::ZERO);
        }
        (lo, hi)
    }

    /// Highest point of the object above its base, metres.
    #[must_use]
    pub fn height_m(&self) -> f32 {
        self.parts.iter().flat_map(|p| p.shapes.iter()).map(|s| s.aabb().1.z).fold(0.0, f32::max)
    }

    /// Moves every shape and joint so that the footprint is centred on the origin (x, y).
    #[must_use]
    pub fn centred(mut self) -> Self {
        let (lo, hi) = self.footprint();
        let c = 0.5 * (lo + hi);
        let shift = Vec3::new(-c.x, -c.y, 0.0);
        for shape in self.parts.iter_mut().flat_map(|p| p.shapes.iter_mut()) {
            shape.world_from_primitive.translation += shift;
        }
        for j in &mut self.joints {
            j.origin_object += shift;
        }
        self
    }

    /// The object placed in the world with `world_from_object`, with ids assigned: the object gets
    /// `object_id`, its parts `first_part_id`, `first_part_id + 1`, ... in part order.
    #[must_use]
    pub fn place(
        &self,
        world_from_object: Pose,
        object_id: ObjectId,
        first_part_id: PartId,
        supported_by: Option<ObjectId>,
    ) -> TruthObject {
        let part_id = |i: usize| first_part_id + i as PartId;
        let parts = self
            .parts
            .iter()
            .enumerate()
            .map(|(i, p)| TruthPart {
                id: part_id(i),
                label: p.label.to_string(),
                shapes: p.shapes.iter().map(|s| Primitive::new(s.kind, s.size, world_from_object * s.world_from_primitive)).collect(),
                meshes: Vec::new(),
            })
            .collect();
        let joints = self
            .joints
            .iter()
            .map(|j| Joint {
                parent: part_id(j.parent),
                child: part_id(j.child),
                kind: j.kind,
                axis_world: world_from_object.transform_vector(j.axis_object).normalize_or(Vec3::Z),
                origin_world: world_from_object.transform_point(j.origin_object),
                lower: j.lower,
                upper: j.upper,
            })
            .collect::<Vec<_>>();
        let contact_edges = joints.iter().map(|j| if j.parent < j.child { [j.parent, j.child] } else { [j.child, j.parent] }).collect();
        TruthObject { id: object_id, category: self.category.to_string(), supported_by, parts, joints, contact_edges }
    }
}

/// An axis-aligned box in the object frame from its min and max corners.
#[must_use]
pub fn box_between(min: Vec3, max: Vec3) -> Primitive {
    Primitive::cuboid_at(0.5 * (min + max), (max - min).abs())
}

/// A cylinder with its axis along the object frame's `axis` (x, y or z), centred at `center`.
#[must_use]
pub fn cylinder_along(axis: Vec3, center: Vec3, diameter_m: f32, length_m: f32) -> Primitive {
    let rotation = Quat::from_rotation_arc(Vec3::Z, axis.normalize_or(Vec3::Z));
    Primitive::new(PrimitiveKind::Cylinder, Vec3::new(diameter_m, diameter_m, length_m), Pose::from_parts(center, rotation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placing_moves_shapes_and_joints_together() {
        let mut f = Furniture::new("thing");
        let body = f.add_part("body", box_between(Vec3::new(-0.5, -0.25, 0.0), Vec3::new(0.5, 0.25, 1.0)));
        let front = Vec3::new(0.0, 0.25, 0.5);
        let board = box_between(Vec3::new(-0.4, 0.25, 0.1), Vec3::new(0.4, 0.27, 0.9));
        f.add_prismatic(body, "drawer", board, Vec3::Y, 0.4);
        let yaw = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let pose = Pose::from_parts(Vec3::new(3.0, 1.0, 0.0), yaw);
        let obj = f.place(pose, 7, 20, None);
        assert_eq!(obj.parts[1].id, 21);
        assert_eq!(obj.joints[0].parent, 20);
        assert_eq!(obj.joints[0].child, 21);
        assert_eq!(obj.contact_edges, vec![[20, 21]]);
        // +y turned by +90° about z is -x.
        assert!((obj.joints[0].axis_world - Vec3::NEG_X).length() < 1e-6);
        let want = pose.transform_point(front + Vec3::Y * 0.01);
        assert!((obj.parts[1].shapes[0].center() - want).length() < 1e-5);
    }

    #[test]
    fn cylinder_along_x_spans_x() {
        let c = cylinder_along(Vec3::X, Vec3::ZERO, 0.02, 0.3);
        let (lo, hi) = c.aabb();
        assert!((hi.x - lo.x - 0.3).abs() < 1e-5);
        assert!((hi.z - lo.z - 0.02).abs() < 1e-5);
    }
}
