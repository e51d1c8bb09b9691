//! The kinematic forest every nesting format (MJCF bodies, glTF nodes) writes: each part's parent
//! (its joint's parent part, the part supporting its object, or the world), children in id order,
//! and the link frames the URDF uses (world-aligned, at the joint origin of movable parts, else at
//! the primitive centre).

use std::collections::{BTreeMap, BTreeSet};

use crate::kinematics::Joint;
use crate::math::Vec3;
use crate::model::{PartModel, SceneModel};
use crate::scan::PartId;

/// Where a part's link frame sits in the world: the joint origin of movable parts, else the
/// primitive centre (the same frame `scene.urdf` uses).
#[must_use]
pub(crate) fn link_origin(scene: &SceneModel, part: &PartModel) -> Vec3 {
    match scene.joint_of(part.id) {
        Some(j) if j.kind.is_movable() => j.origin_world,
        _ => part.primitive.center(),
    }
}

/// The scene as a forest under the world.
pub(crate) struct ExportTree<'s> {
    /// Parts with no parent part (hang off the world), in id order.
    pub roots: Vec<&'s PartModel>,
    /// Children of each part, in id order.
    pub children: BTreeMap<PartId, Vec<&'s PartModel>>,
    /// The part each part hangs under (the inverse of `children`).
    pub parent: BTreeMap<PartId, PartId>,
    /// The joint into each part from its parent part (absent for world-mounted and object-mounted roots).
    pub joint_into: BTreeMap<PartId, &'s Joint>,
    /// World position of each part's link frame.
    pub origin_world: BTreeMap<PartId, Vec3>,
    /// Link name of each part.
    pub name: BTreeMap<PartId, String>,
}

impl<'s> ExportTree<'s> {
    /// Builds the forest. Parts that no joint or object mount reaches from the world (or that a
    /// malformed scene puts on a cycle) hang off the world, so every part is written exactly once.
    pub fn new(scene: &'s SceneModel) -> Self {
        let mut parent: BTreeMap<PartId, PartId> = BTreeMap::new();
        let mut joint_into = BTreeMap::new();
        for j in &scene.joints {
            if scene.part(j.parent).is_some() && scene.part(j.child).is_some() && j.parent != j.child {
                parent.entry(j.child).or_insert(j.parent);
                joint_into.entry(j.child).or_insert(j);
            }
        }
        for obj in &scene.objects {
            if let Some(support) = obj.supported_by_part.filter(|s| scene.part(*s).is_some() && *s != obj.root_part)
                && scene.part(obj.root_part).is_some()
                && !parent.contains_key(&obj.root_part)
            {
                parent.insert(obj.root_part, support);
            }
        }
        // Break cycles: walk up from every part; a part whose walk revisits itself loses its parent.
        for part in &scene.parts {
            let mut seen = BTreeSet::from([part.id]);
            let mut at = part.id;
            while let Some(&up) = parent.get(&at) {
                if !seen.insert(up) {
                    parent.remove(&at);
                    joint_into.remove(&at);
                    break;
                }
                at = up;
            }
        }
        let mut roots = Vec::new();
        let mut children: BTreeMap<PartId, Vec<&PartModel>> = BTreeMap::new();
        for part in &scene.parts {
            match parent.get(&part.id) {
                Some(p) => children.entry(*p).or_default().push(part),
                None => roots.push(part),
            }
        }
        let origin_world = scene.parts.iter().map(|p| (p.id, link_origin(scene, p))).collect();
        let name = scene.parts.iter().map(|p| (p.id, super::link_name(scene, p))).collect();
        Self { roots, children, parent, joint_into, origin_world, name }
    }

    /// Children of a part (empty when none).
    pub fn children_of(&self, id: PartId) -> &[&'s PartModel] {
        self.children.get(&id).map_or(&[], Vec::as_slice)
    }

    /// The movable joint into a part, if any.
    pub fn movable_joint(&self, id: PartId) -> Option<&'s Joint> {
        self.joint_into.get(&id).copied().filter(|j| j.kind.is_movable())
    }

    /// All parts of the subtree under `id` (itself included), depth first.
    pub fn subtree(&self, id: PartId) -> Vec<PartId> {
        let mut out = Vec::new();
        let mut stack = vec![id];
        while let Some(at) = stack.pop() {
            out.push(at);
            stack.extend(self.children_of(at).iter().rev().map(|c| c.id));
        }
        out
    }

    /// The first part (in id order) whose primitive or joint holds NaN or infinity, and what.
    pub fn first_non_finite(&self, scene: &SceneModel) -> Option<(PartId, &'static str)> {
        scene.parts.iter().find_map(|part| {
            let prim = &part.primitive;
            let what =
                if !prim.size.is_finite() {
                    "size"
                } else if !prim.center().is_finite() || !prim.rotation().is_finite() {
                    "pose"
                } else if self.joint_into.get(&part.id).is_some_and(|j| {
                    !j.axis_world.is_finite() || !j.origin_world.is_finite() || !j.lower.is_finite() || !j.upper.is_finite()
                }) {
                    "joint"
                } else {
                    return None;
                };
            Some((part.id, what))
        })
    }
}
