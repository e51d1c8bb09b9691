//! Collision geometry that does not start in contact, and the pairs a self-colliding simulator
//! should ignore.
//!
//! A reconstructed object is a set of touching primitives: drawers stacked in their carcass, a
//! handle flush with the drawer front and the body beside it, a microwave door on the table. A
//! simulator that collides a model with itself (`PyBullet`'s `URDF_USE_SELF_COLLISION`, `MuJoCo`,
//! SAPIEN, `MoveIt`) excludes only parent–child pairs; every other pair that touches at rest starts
//! in contact, and the contact solver pushes the parts apart before anyone touches them. `MuJoCo`
//! does not even filter parent–child pairs when the parent is welded to the world (a carcass and
//! its drawers, loaded from URDF).
//!
//! [`collision_set`] gives every part a *collision* primitive: its fitted primitive with the faces
//! that touch another part moved back until the two are `clearance_m` apart (visual geometry
//! keeps the fitted primitive). Of each touching pair the smaller part is trimmed (the larger where
//! the smaller would lose too much), along its own axis closest to the contact normal, never by
//! more than [`MAX_TRIM_SHARE`] of its size there nor more than [`MAX_TRIM_M`]. The clearance is
//! kept along the motion too: a touching pair is checked with each joint between the two parts
//! sampled over its range (a door whose fitted hinge is a little tilted sinks into the door below
//! it as it opens). It
//! also lists the pairs for an SRDF (`<disable_collisions>`, the `MoveIt`/SAPIEN convention):
//! adjacent links and links touching at rest, and reports pairs that trimming could not separate
//! (the smaller part of such a pair, unless parent and child, gets no URDF collision shape).

use std::collections::{BTreeMap, BTreeSet};

use crate::math::{Pose, Quat, Vec3};
use crate::model::SceneModel;
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::PartId;

use super::tree::ExportTree;

/// The most a collision primitive is trimmed along one axis, as a share of its size there. A
/// pair that would need more (one part sunk deep into another) is left as fitted and reported.
pub const MAX_TRIM_SHARE: f32 = 0.25;
/// The most a collision primitive is trimmed along one axis, metres: overlaps of fit noise (a few
/// millimetres) are trimmed; a deeper one is a part inside another, and moving a carcass's side
/// in by centimetres to free a handle would change what the robot collides with.
pub const MAX_TRIM_M: f32 = 0.01;

/// Passes over the touching pairs: a part trimmed against one neighbour may still touch another.
const PASSES: usize = 4;

/// Why a pair of links is listed in the SRDF.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DisableReason {
    /// Parent and child of a joint (or of an object mount).
    Adjacent,
    /// In contact (or closer than the clearance) in the rest pose, before trimming: the SRDF
    /// reason `MoveIt`'s setup assistant calls `Default`.
    Default,
}

impl DisableReason {
    /// The SRDF `reason` attribute.
    #[must_use]
    pub fn srdf_name(self) -> &'static str {
        match self {
            Self::Adjacent => "Adjacent",
            Self::Default => "Default",
        }
    }
}

/// Collision primitives per part and the pairs to exclude.
#[derive(Clone, Debug, Default)]
pub struct CollisionSet {
    /// The collision primitive of every part (the fitted one where nothing touches).
    pub primitives: BTreeMap<PartId, Primitive>,
    /// Pairs (smaller id first) to list in an SRDF, sorted.
    pub disabled: Vec<(PartId, PartId, DisableReason)>,
    /// Pairs still closer than the clearance after trimming, at rest or as a joint between them
    /// moves, with their closest signed distance (m), sorted by pair.
    pub unresolved: Vec<(PartId, PartId, f32)>,
    /// Parts whose collision shape a format without pair filters (URDF) leaves out: the smaller
    /// part of every unresolved pair that is not parent and child. A part sunk into another at
    /// rest (a latch through its door into the frame) would otherwise be thrown out of it by the
    /// first contact; formats with pair filters (SRDF, MJCF `<exclude>`) exclude the pair instead.
    pub without_collision: BTreeSet<PartId>,
}

/// A parry shape and its world pose for a primitive (parry's round axis is y, ours z).
fn parry_shape(p: &Primitive) -> (parry3d::shape::SharedShape, Pose) {
    use parry3d::shape::SharedShape;
    let h = p.size * 0.5;
    let y_to_z = Pose::from_parts(Vec3::ZERO, Quat::from_rotation_x(std::f32::consts::FRAC_PI_2));
    match p.kind {
        PrimitiveKind::Cuboid => (SharedShape::cuboid(h.x, h.y, h.z), p.world_from_primitive),
        PrimitiveKind::Sphere => (SharedShape::ball(h.x), p.world_from_primitive),
        PrimitiveKind::Cylinder => (SharedShape::cylinder(h.z, h.x), p.world_from_primitive * y_to_z),
        PrimitiveKind::Capsule => (SharedShape::capsule_y((h.z - h.x).max(0.0), h.x), p.world_from_primitive * y_to_z),
    }
}

/// Whether parry's contact query can take the primitive: every size between a micrometre and
/// ten kilometres, a finite pose.
fn measurable(p: &Primitive) -> bool {
    let sizes_ok = p.size.to_array().iter().all(|s| (1e-6..=1e4).contains(s));
    sizes_ok && p.center().is_finite() && p.rotation().is_finite()
}

/// Signed distance between two primitives within `prediction` (negative: penetration depth) and
/// the unit normal pointing from `a` towards `b`; `None` when farther apart.
fn separation(a: &Primitive, b: &Primitive, prediction: f32) -> Option<(f32, Vec3)> {
    // Shapes parry cannot measure (flat, huge or not finite; only an edited or hand-written
    // scene has them): no contact is computed and the part keeps its fitted primitive.
    if !(measurable(a) && measurable(b)) {
        return None;
    }
    let (sa, pa) = parry_shape(a);
    let (sb, pb) = parry_shape(b);
    let c = parry3d::query::contact(&pa, sa.as_ref(), &pb, sb.as_ref(), prediction).ok()??;
    let n = c.normal1;
    let normal = if n.is_finite() && n.length_squared() > 0.5 { n } else { (b.center() - a.center()).normalize_or(Vec3::Z) };
    Some((c.dist, normal))
}

/// `p` with the side facing `towards` (unit, world) moved back by `depth_m`; `None` when that
/// would cut more than [`MAX_TRIM_SHARE`] of its size or more than [`MAX_TRIM_M`]. Round kinds stay round: a radial cut
/// shrinks the diameter and moves the centre away, so the far side stays where it was.
fn trimmed(p: &Primitive, towards: Vec3, depth_m: f32) -> Option<Primitive> {
    let axes = p.axes_world();
    let k = (0..3).max_by(|&i, &j| axes[i].dot(towards).abs().total_cmp(&axes[j].dot(towards).abs())).unwrap_or(2);
    let radial = matches!(p.kind, PrimitiveKind::Cylinder | PrimitiveKind::Capsule) && k != 2;
    let sphere = p.kind == PrimitiveKind::Sphere;
    let mut size = p.size;
    let mut shrink = |i: usize| {
        size[i] -= depth_m;
        depth_m <= MAX_TRIM_SHARE * p.size[i] && depth_m <= MAX_TRIM_M
    };
    let ok = if sphere {
        (0..3).all(&mut shrink)
    } else if radial {
        shrink(0) & shrink(1)
    } else {
        shrink(k)
    };
    if !ok {
        return None;
    }
    // Move away from the neighbour: along the cut axis, or (round sides) straight away.
    let away = if radial || sphere {
        let along = if radial { towards - axes[2] * axes[2].dot(towards) } else { towards };
        -along.normalize_or(-axes[0])
    } else {
        -axes[k] * axes[k].dot(towards).signum()
    };
    let centre = p.center() + away * (0.5 * depth_m);
    Some(Primitive { kind: p.kind, size, world_from_primitive: Pose::from_parts(centre, p.rotation()) })
}

fn ordered(a: PartId, b: PartId) -> (PartId, PartId) {
    if a <= b { (a, b) } else { (b, a) }
}

/// Joint positions sampled over a joint's range when a touching pair is checked along its motion.
const SWEEP_SAMPLES: usize = 9;

/// A world motion that moves one part of a pair: a joint between the two at some position.
#[derive(Clone, Copy)]
struct Motion {
    /// Which part of the pair moves (0: the first, 1: the second).
    moving: usize,
    world_from_world: Pose,
}

/// The motion of `joint` at position `q` (radians or metres) as a world transform.
fn joint_motion(joint: &crate::kinematics::Joint, q: f32) -> Pose {
    let axis = joint.axis_world.normalize_or(Vec3::Z);
    if joint.kind == crate::kinematics::JointKind::Prismatic {
        return Pose::from_translation(axis * q);
    }
    let rotation = Quat::from_axis_angle(axis, q);
    // About the hinge line: x ↦ o + R (x − o).
    Pose::from_parts(joint.origin_world - rotation * joint.origin_world, rotation)
}

/// The motions that move `a` and `b` relative to each other: every movable joint on the tree
/// path between them, sampled over its range while the others stay at rest (the rest pose
/// included), so that parts touching at rest stay apart as any one joint moves.
fn relative_motions(a: PartId, b: PartId, tree: &ExportTree) -> Vec<Motion> {
    let chain = |mut at: PartId| {
        let mut out = vec![at];
        while let Some(&up) = tree.parent.get(&at) {
            if out.contains(&up) {
                break;
            }
            out.push(up);
            at = up;
        }
        out
    };
    let (up_a, up_b) = (chain(a), chain(b));
    let mut out = vec![Motion { moving: 0, world_from_world: Pose::IDENTITY }];
    for (moving, own, other) in [(0, &up_a, &up_b), (1, &up_b, &up_a)] {
        // Joints into the parts of this side's chain below the common ancestor.
        for &node in own.iter().take_while(|n| !other.contains(n)) {
            let Some(joint) = tree.movable_joint(node) else { continue };
            let (lo, hi) = if joint.kind == crate::kinematics::JointKind::Continuous {
                (0.0, std::f32::consts::TAU * (1.0 - 1.0 / SWEEP_SAMPLES as f32))
            } else {
                (joint.lower.min(joint.upper), joint.upper.max(joint.lower))
            };
            if !(hi - lo).is_finite() || hi - lo <= 0.0 {
                continue;
            }
            for k in 0..SWEEP_SAMPLES {
                let q = lo + (hi - lo) * k as f32 / (SWEEP_SAMPLES - 1) as f32;
                out.push(Motion { moving, world_from_world: joint_motion(joint, q) });
            }
        }
    }
    out
}

/// `p` moved by `motion`.
fn moved(p: &Primitive, motion: Pose) -> Primitive {
    Primitive { kind: p.kind, size: p.size, world_from_primitive: motion * p.world_from_primitive }
}

/// The closest the two primitives come over `motions` within `prediction`: the signed distance,
/// the unit normal from `a` towards `b` in each part's rest frame (the normal as the moving part
/// sees it, rotated back by its motion).
fn closest_over(a: &Primitive, b: &Primitive, motions: &[Motion], prediction: f32) -> Option<(f32, Vec3, Vec3)> {
    let mut best: Option<(f32, Vec3, Vec3)> = None;
    for m in motions {
        let (pa, pb) = if m.moving == 0 { (moved(a, m.world_from_world), *b) } else { (*a, moved(b, m.world_from_world)) };
        let Some((dist, normal_ab)) = separation(&pa, &pb, prediction) else { continue };
        if best.is_none_or(|(d, _, _)| dist < d) {
            let back = m.world_from_world.rotation.inverse();
            let (na, nb) = if m.moving == 0 { (back * normal_ab, normal_ab) } else { (normal_ab, back * normal_ab) };
            best = Some((dist, na, nb));
        }
    }
    best
}

/// Collision primitives `clearance_m` apart wherever non-adjacent parts touch, and the SRDF pairs.
#[must_use]
pub fn collision_set(scene: &SceneModel, clearance_m: f32) -> CollisionSet {
    let tree = ExportTree::new(scene);
    let clearance_m = clearance_m.max(0.0);
    let mut adjacent: BTreeSet<(PartId, PartId)> = BTreeSet::new();
    for (parent, children) in &tree.children {
        for c in children {
            adjacent.insert(ordered(*parent, c.id));
        }
    }
    let mut prims: BTreeMap<PartId, Primitive> = scene.parts.iter().map(|p| (p.id, p.primitive)).collect();
    let volume: BTreeMap<PartId, f32> = scene.parts.iter().map(|p| (p.id, p.primitive.volume())).collect();
    // Candidate pairs: bounding boxes within the clearance (adjacent ones too: see the module
    // docs); sorted by construction.
    let ids: Vec<PartId> = prims.keys().copied().collect();
    let bounds: Vec<(Vec3, Vec3)> = ids.iter().map(|id| prims[id].aabb()).collect();
    let mut pairs = Vec::new();
    for i in 0..ids.len() {
        for j in i + 1..ids.len() {
            let ((alo, ahi), (blo, bhi)) = (bounds[i], bounds[j]);
            let gap = (blo - ahi).max(alo - bhi).max(Vec3::ZERO).length();
            if gap <= clearance_m {
                pairs.push((ids[i], ids[j]));
            }
        }
    }
    let mut disabled: Vec<(PartId, PartId, DisableReason)> = adjacent.iter().map(|&(a, b)| (a, b, DisableReason::Adjacent)).collect();
    let mut touching = Vec::new();
    for &(a, b) in &pairs {
        if separation(&prims[&a], &prims[&b], clearance_m).is_some_and(|(d, _)| d < clearance_m) {
            touching.push((a, b));
            if !adjacent.contains(&(a, b)) {
                disabled.push((a, b, DisableReason::Default));
            }
        }
    }
    disabled.sort_unstable();
    let motions: BTreeMap<(PartId, PartId), Vec<Motion>> = touching.iter().map(|&(a, b)| ((a, b), relative_motions(a, b, &tree))).collect();
    let mut unresolved = BTreeMap::new();
    for _ in 0..PASSES {
        let mut changed = false;
        for &(a, b) in &touching {
            let Some((dist, normal_a, normal_b)) = closest_over(&prims[&a], &prims[&b], &motions[&(a, b)], clearance_m) else {
                unresolved.remove(&(a, b));
                continue;
            };
            if dist >= clearance_m - 1e-5 {
                unresolved.remove(&(a, b));
                continue;
            }
            // Trim the smaller part (ties: the larger id) on its side facing the other; where
            // that would cut too deep (a handle through its drawer into the body), the larger.
            let smaller_first =
                if (volume[&b], b) <= (volume[&a], a) { [(b, -normal_b), (a, normal_a)] } else { [(a, normal_a), (b, -normal_b)] };
            match smaller_first.iter().find_map(|&(cut, towards)| trimmed(&prims[&cut], towards, clearance_m - dist).map(|t| (cut, t))) {
                Some((cut, t)) => {
                    prims.insert(cut, t);
                    changed = true;
                }
                None => {
                    unresolved.insert((a, b), dist);
                }
            }
        }
        if !changed {
            break;
        }
    }
    // What is still too close after the last pass, at rest or along a joint's motion.
    for &(a, b) in &touching {
        if let Some((d, _, _)) =
            closest_over(&prims[&a], &prims[&b], &motions[&(a, b)], clearance_m).filter(|(d, _, _)| *d < clearance_m - 1e-4)
        {
            unresolved.insert((a, b), d);
        } else {
            unresolved.remove(&(a, b));
        }
    }
    let smaller = |a: PartId, b: PartId| if (volume[&b], b) <= (volume[&a], a) { b } else { a };
    let without_collision = unresolved.keys().filter(|pair| !adjacent.contains(pair)).map(|&(a, b)| smaller(a, b)).collect();
    CollisionSet {
        primitives: prims,
        disabled,
        unresolved: unresolved.into_iter().map(|((a, b), d)| (a, b, d)).collect(),
        without_collision,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cuboid(center: [f32; 3], size: [f32; 3]) -> Primitive {
        Primitive::cuboid_at(Vec3::from(center), Vec3::from(size))
    }

    #[test]
    fn trimming_moves_only_the_touching_face() {
        let p = cuboid([0.0, 0.0, 0.0], [0.4, 0.2, 0.1]);
        let t = trimmed(&p, Vec3::X, 0.01).expect("small cut");
        assert!((t.size.x - 0.39).abs() < 1e-6 && (t.size.y - 0.2).abs() < 1e-6 && (t.size.z - 0.1).abs() < 1e-6, "{t:?}");
        // The face at x = −0.2 stays; the one at +0.2 moves to +0.19.
        assert!((t.aabb().0.x + 0.2).abs() < 1e-6 && (t.aabb().1.x - 0.19).abs() < 1e-6, "{:?}", t.aabb());
        assert!(trimmed(&p, Vec3::Z, 0.03).is_none(), "a third of the height is too much");
    }

    #[test]
    fn a_round_part_trimmed_sideways_stays_round() {
        let p = Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.1, 0.1, 0.3), Pose::IDENTITY);
        let t = trimmed(&p, Vec3::Y, 0.01).expect("radial cut");
        assert!((t.size.x - 0.09).abs() < 1e-6 && (t.size.y - 0.09).abs() < 1e-6 && (t.size.z - 0.3).abs() < 1e-6, "{t:?}");
        assert!((t.center().y + 0.005).abs() < 1e-6, "moved away from +y: {:?}", t.center());
    }

    /// Regression (fuzzing): a flat capsule against a box of 3e38 m panicked inside parry's EPA.
    #[test]
    fn shapes_parry_cannot_measure_get_no_contact() {
        let flat = Primitive {
            kind: PrimitiveKind::Capsule,
            size: Vec3::new(0.0, 0.0, 1e-45),
            world_from_primitive: Pose::from_translation(Vec3::new(0.31, 0.0, 0.5)),
        };
        let huge = cuboid([3e38, -3e38, 0.0], [3e38, 3e38, 3e38]);
        let unit = cuboid([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        assert!(separation(&flat, &unit, 0.1).is_none());
        assert!(separation(&huge, &unit, 0.1).is_none());
        assert!(separation(&unit, &cuboid([0.0, 0.0, 1.0], [1.0, 1.0, 1.0]), 0.1).is_some());
    }

    #[test]
    fn separation_measures_gaps_and_penetration() {
        let a = cuboid([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        let near = cuboid([0.0, 0.0, 0.7], [0.2, 0.2, 0.2]);
        let (d, n) = separation(&a, &near, 0.5).expect("within prediction");
        assert!((d - 0.1).abs() < 1e-5 && n.z > 0.99, "{d} {n}");
        let sunk = cuboid([0.0, 0.0, 0.55], [0.2, 0.2, 0.2]);
        let (d, _) = separation(&a, &sunk, 0.0).expect("penetrating");
        assert!((d + 0.05).abs() < 1e-5, "{d}");
        let cyl = Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.2, 0.2, 1.0), Pose::from_translation(Vec3::new(0.0, 0.0, 1.0)));
        let (d, _) = separation(&a, &cyl, 0.1).expect("the cylinder's axis is z: its end sits on the box");
        assert!(d.abs() < 1e-4, "{d}");
    }
}
