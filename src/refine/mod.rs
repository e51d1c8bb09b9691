//! Spatial refinement among parts (paper Algorithm 1): top-down over the part tree, each child's
//! box normals that roughly align with its parent's are snapped onto them by the Kabsch rotation
//! (about the child's centre; its subtree moves with it). Then, beyond the paper's rotation-only
//! step, the child is slid along the contact plane's normal so the touching faces meet exactly,
//! which removes the penetration and gaps left by noisy fits.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::contact::{ContactConfig, contact, surface_planes};
use crate::math::{Pose, Quat, Vec3, kabsch_rotation};
use crate::primitive::Primitive;
use crate::scan::PartId;
use crate::tree::PartTree;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefineConfig {
    /// Normals with |cos| at least this are treated as "roughly aligned" (authors: 0.975).
    pub align_min: f32,
    /// Also remove gaps and penetration along the contact normal.
    pub snap_contacts: bool,
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self { align_min: 0.975, snap_contacts: true }
    }
}

/// What refinement changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RefineStats {
    pub parts_rotated: usize,
    pub max_rotation_deg: f32,
    pub parts_moved: usize,
    pub max_translation_m: f32,
}

impl RefineStats {
    pub fn merge(&mut self, other: RefineStats) {
        self.parts_rotated += other.parts_rotated;
        self.parts_moved += other.parts_moved;
        self.max_rotation_deg = self.max_rotation_deg.max(other.max_rotation_deg);
        self.max_translation_m = self.max_translation_m.max(other.max_translation_m);
    }
}

/// The rotation that snaps `child`'s roughly aligned box normals onto `parent`'s
/// (`getAlignedPlanes` + `refineTF`).
#[must_use]
pub fn aligning_rotation(parent: &Primitive, child: &Primitive, align_min: f32) -> Option<Quat> {
    let pa = parent.axes_world();
    let ca = child.axes_world();
    let mut xc = Vec::with_capacity(3);
    let mut xp = Vec::with_capacity(3);
    for c in ca {
        // The best-aligned parent axis for this child axis.
        let (cos, p) = pa.iter().map(|p| (c.dot(*p), *p)).max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()))?;
        if cos.abs() >= align_min {
            xc.push(c);
            xp.push(p * cos.signum());
        }
    }
    if xc.is_empty() {
        return None;
    }
    Some(kabsch_rotation(&xc, &xp, None))
}

/// Applies a rigid motion (rotation about `pivot`, then translation) to a part and its subtree.
fn move_subtree(prims: &mut BTreeMap<PartId, Primitive>, tree: &PartTree, part: PartId, pivot: Vec3, rot: Quat, shift: Vec3) {
    let mut stack = vec![part];
    while let Some(p) = stack.pop() {
        if let Some(prim) = prims.get_mut(&p) {
            let c = pivot + rot * (prim.center() - pivot) + shift;
            prim.world_from_primitive = Pose::from_parts(c, (rot * prim.rotation()).normalize());
        }
        stack.extend(tree.children(p));
    }
}

/// Refines one object's primitives in place, top-down along `tree`.
pub fn refine_object(
    prims: &mut BTreeMap<PartId, Primitive>,
    tree: &PartTree,
    cfg: &RefineConfig,
    contact_cfg: &ContactConfig,
) -> RefineStats {
    refine_object_observed(prims, tree, cfg, contact_cfg, &mut |_, _| {})
}

/// [`refine_object`], calling `on_step(child, primitives)` after each child is refined.
pub fn refine_object_observed(
    prims: &mut BTreeMap<PartId, Primitive>,
    tree: &PartTree,
    cfg: &RefineConfig,
    contact_cfg: &ContactConfig,
    on_step: &mut dyn FnMut(PartId, &BTreeMap<PartId, Primitive>),
) -> RefineStats {
    let mut stats = RefineStats::default();
    for child in tree.top_down().into_iter().skip(1) {
        refine_child(prims, tree, *cfg, contact_cfg, child, &mut stats);
        on_step(child, prims);
    }
    stats
}

fn refine_child(
    prims: &mut BTreeMap<PartId, Primitive>,
    tree: &PartTree,
    cfg: RefineConfig,
    contact_cfg: &ContactConfig,
    child: PartId,
    stats: &mut RefineStats,
) {
    {
        let Some(&parent) = tree.parent.get(&child) else { return };
        let (Some(p), Some(c)) = (prims.get(&parent).copied(), prims.get(&child).copied()) else { return };
        if let Some(rot) = aligning_rotation(&p, &c, cfg.align_min) {
            let angle = rot.angle_between(Quat::IDENTITY).to_degrees();
            if angle > 1e-4 {
                move_subtree(prims, tree, child, c.center(), rot, Vec3::ZERO);
                stats.parts_rotated += 1;
                stats.max_rotation_deg = stats.max_rotation_deg.max(angle);
            }
        }
        if !cfg.snap_contacts {
            return;
        }
        let Some(c) = prims.get(&child).copied() else { return };
        // Use a looser alignment for finding the touching faces: they are aligned now.
        let Some(pc) = contact(&p, &c, contact_cfg) else { return };
        let pp = &surface_planes(&p)[pc.parent_face];
        let cp = &surface_planes(&c)[pc.child_face];
        if pp.normal.dot(cp.normal).abs() < cfg.align_min {
            return;
        }
        let s = pp.signed_distance(cp.center());
        if s.abs() > 1e-6 && s.abs() <= contact_cfg.dist_max_m {
            move_subtree(prims, tree, child, c.center(), Quat::IDENTITY, -pp.normal * s);
            stats.parts_moved += 1;
            stats.max_translation_m = stats.max_translation_m.max(s.abs());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitive::PrimitiveKind;

    #[test]
    fn tilted_leg_is_snapped_upright_and_onto_the_top() {
        let top = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.73), Vec3::new(1.2, 0.8, 0.04));
        let tilt = Quat::from_rotation_x(0.06);
        // Leg slightly tilted and 1 cm into the top.
        let leg =
            Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.05, 0.05, 0.72), Pose::from_parts(Vec3::new(0.5, 0.3, 0.36 + 0.01), tilt));
        let mut prims = BTreeMap::from([(1, top), (2, leg)]);
        let tree = PartTree { root: 1, parent: BTreeMap::from([(2, 1)]), ..PartTree::default() };
        let stats = refine_object(&mut prims, &tree, &RefineConfig::default(), &ContactConfig::default());
        let leg = prims[&2];
        assert!(leg.rotation().angle_between(Quat::IDENTITY) < 1e-4, "{:?}", leg.rotation());
        let leg_top = leg.center().z + 0.36;
        assert!((leg_top - 0.71).abs() < 1e-4, "leg top at {leg_top}");
        assert_eq!(stats.parts_rotated, 1);
        assert_eq!(stats.parts_moved, 1);
    }

    #[test]
    fn subtree_moves_with_its_root() {
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.5, 1.0));
        let rot = Quat::from_rotation_z(0.05);
        let door = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.7, 0.02, 0.9), Pose::from_parts(Vec3::new(0.0, 0.26, 0.5), rot));
        let handle = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.02, 0.03, 0.15), Pose::from_parts(Vec3::new(0.3, 0.285, 0.5), rot));
        let mut prims = BTreeMap::from([(1, body), (2, door), (3, handle)]);
        let tree = PartTree { root: 1, parent: BTreeMap::from([(2, 1), (3, 2)]), ..PartTree::default() };
        refine_object(&mut prims, &tree, &RefineConfig::default(), &ContactConfig::default());
        for id in [2, 3] {
            assert!(prims[&id].rotation().angle_between(Quat::IDENTITY) < 1e-4, "part {id}");
        }
    }
}
