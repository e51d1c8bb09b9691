//! The per-object part-level parse tree (paper eq. 3): candidate edges from the contact test,
//! then Edmonds' maximum arborescence.
//!
//! A virtual root joins the graph with tiny-weight edges to every part, so the arborescence
//! always exists and Edmonds itself chooses the object's root (the part whose parenting costs
//! least). Two label priors, both configurable (0 turns them off):
//! - `root_prior`: the most base-like part (labelled body, base, frame or top; then the largest)
//!   gets a root edge of this weight, so a bed hangs off its frame rather than its headboard when
//!   the contact ratios alone are nearly symmetric;
//! - `label_prior`: a contact edge from a typical parent of the child's label
//!   ([`crate::kinematics::Vocabulary::is_typical_parent`]: a handle's door or drawer, a latch's door, a
//!   headboard's frame, a leg's top) gets this weight added. Contact weights are at most 1, so with the
//!   default 1 a typical parent in contact wins over any other part in contact, and the contact
//!   weights choose among typical parents. Contacts alone are ambiguous — a handle touches the body
//!   behind a 2 cm door too, a headboard touches both the frame and the mattress end, a latch reaches
//!   into the frame's strike by design and touches it more than its own door — but the part is
//!   mounted on its typical parent. The prior only chooses among real contacts; it never creates an
//!   edge.
//! - `grip_set_into_factor` divides the contact of a grip (handle, pull) with a part when the grip
//!   also touches a part set into that one (whose box lies inside its box): a drawer front flush
//!   with the cabinet's front lies inside the box fitted to the cabinet, so the handle's back touches
//!   both front faces, but it is mounted on the drawer — the part it moves. Two parts that each
//!   carry a grip (stacked drawers) touch, but each is moved by its own grip and neither is mounted
//!   on the other: their contact counts as none.
//!
//! A part with no contact at all is attached by a fallback edge far lighter than any contact, and
//! reported: to a typical parent of its label when the object has one (the headboard of a bed whose
//! frame was seen only over its foot half), else to its nearest part.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::arborescence::{WeightedEdge, max_arborescence};
use crate::contact::{ContactConfig, PairContact, contact, through_contact};
use crate::kinematics::Vocabulary;
use crate::model::ContactEdge;
use crate::primitive::Primitive;
use crate::report::Warning;
use crate::scan::PartId;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeConfig {
    pub contact: ContactConfig,
    /// Weight of the root edge of the most base-like part.
    pub root_prior: f32,
    /// Weight added to contact edges from a typical parent of the child's label (0: off).
    pub label_prior: f32,
    /// Divisor of a grip's contact with a part that has a part set into it which the grip touches.
    #[serde(default = "default_grip_set_into_factor")]
    pub grip_set_into_factor: f32,
    /// A part that touches only its peers hangs off a typical parent within this many contact
    /// distances (`contact.dist_max_m`) that it does not touch ([`uncontacted_weight`]).
    #[serde(default = "default_peer_mount_reach")]
    pub peer_mount_reach: f32,
}

fn default_grip_set_into_factor() -> f32 {
    1.5
}

fn default_peer_mount_reach() -> f32 {
    2.0
}

impl Default for TreeConfig {
    fn default() -> Self {
        Self {
            contact: ContactConfig::default(),
            root_prior: 1.0,
            label_prior: 1.0,
            grip_set_into_factor: default_grip_set_into_factor(),
            peer_mount_reach: default_peer_mount_reach(),
        }
    }
}

/// One object's tree.
#[derive(Clone, Debug, Default)]
pub struct PartTree {
    pub root: PartId,
    /// child → parent.
    pub parent: BTreeMap<PartId, PartId>,
    /// Candidate contact edges (the directed graph), sorted by (parent, child).
    pub edges: Vec<ContactEdge>,
    /// The contact behind each candidate edge, by (parent, child).
    pub contacts: BTreeMap<(PartId, PartId), PairContact>,
}

impl PartTree {
    /// Children of a part, sorted.
    #[must_use]
    pub fn children(&self, part: PartId) -> Vec<PartId> {
        self.parent.iter().filter(|(_, p)| **p == part).map(|(c, _)| *c).collect()
    }

    /// Parts top-down (breadth first from the root, children in id order).
    #[must_use]
    pub fn top_down(&self) -> Vec<PartId> {
        let mut order = vec![self.root];
        let mut i = 0;
        while i < order.len() {
            order.extend(self.children(order[i]));
            i += 1;
        }
        order
    }
}

/// One part as the tree builder sees it.
#[derive(Clone, Copy, Debug)]
pub struct TreePart<'a> {
    pub id: PartId,
    pub label: &'a str,
    pub primitive: &'a Primitive,
}

/// How base-like a part is (larger is more): parts labelled as a base (body, base, frame, top)
/// first, then larger parts. The tree's root prior and the pipeline's co-alignment reference both
/// use it.
#[must_use]
pub fn root_preference(vocab: &Vocabulary, label: &str, primitive: &Primitive) -> (bool, f32) {
    (vocab.is_base(label), primitive.volume())
}

const ROOT_WEIGHT: f64 = 1e-6;
const FALLBACK_WEIGHT: f64 = 1e-4;
const FORCED_WEIGHT: f64 = 1e3;

/// Builds the tree of one object's parts (`parts` sorted by id). `forced_parent` pins
/// child → parent edges (editor corrections); a pin naming a part outside `parts` is ignored
/// with a warning.
#[must_use]
pub fn build_part_tree(
    parts: &[TreePart<'_>],
    cfg: &TreeConfig,
    vocab: &Vocabulary,
    forced_parent: &BTreeMap<PartId, PartId>,
) -> (PartTree, Vec<Warning>) {
    let mut warnings = Vec::new();
    let n = parts.len();
    if n == 0 {
        return (PartTree::default(), warnings);
    }
    let index: BTreeMap<PartId, usize> = parts.iter().enumerate().map(|(i, p)| (p.id, i)).collect();
    // Contacts for every ordered pair.
    let mut contacts = BTreeMap::new();
    for p in parts {
        for c in parts {
            if p.id == c.id {
                continue;
            }
            // Face contact (the paper's test), else a child passing through the parent.
            if let Some(pc) =
                contact(p.primitive, c.primitive, &cfg.contact).or_else(|| through_contact(p.primitive, c.primitive, &cfg.contact))
            {
                contacts.insert((p.id, c.id), pc);
            }
        }
    }
    // Root preference: base labels first, then volume (rank keeps weights tiny and ordered).
    let mut by_pref: Vec<usize> = (0..n).collect();
    by_pref.sort_by(|&a, &b| {
        let ka = root_preference(vocab, parts[a].label, parts[a].primitive);
        let kb = root_preference(vocab, parts[b].label, parts[b].primitive);
        ka.partial_cmp(&kb).unwrap_or(std::cmp::Ordering::Equal).then(parts[b].id.cmp(&parts[a].id))
    });
    let mut edges = Vec::new();
    let mut edge_pairs = Vec::new();
    for (rank, &i) in by_pref.iter().enumerate() {
        let weight = if rank + 1 == n { f64::from(cfg.root_prior).max(ROOT_WEIGHT) } else { ROOT_WEIGHT * (1.0 + rank as f64) / n as f64 };
        edges.push(WeightedEdge { from: 0, to: i + 1, weight });
        edge_pairs.push(None);
    }
    // Parts whose every contact is with a part of their own class (a door meeting a door).
    let only_peers: std::collections::BTreeSet<PartId> = parts
        .iter()
        .filter(|c| {
            let class = vocab.class_name(c.label);
            let mut touching = parts.iter().filter(|q| q.id != c.id && contacts.contains_key(&(q.id, c.id))).peekable();
            class.is_some() && touching.peek().is_some() && touching.all(|q| vocab.class_name(q.label) == class)
        })
        .map(|c| c.id)
        .collect();
    let carriers = grip_carriers(parts, &contacts, vocab, cfg);
    let mut forced: BTreeMap<usize, usize> = BTreeMap::new();
    for (child, parent) in forced_parent {
        match (index.get(child), index.get(parent)) {
            (Some(&c), Some(&p)) if c != p => {
                forced.insert(c, p);
            }
            (Some(_), _) => warnings.push(Warning::new(
                "tree",
                format!("part {child}"),
                format!("pinned parent {parent} is not a part of the same object; pin ignored"),
            )),
            _ => {}
        }
    }
    for (ci, c) in parts.iter().enumerate() {
        if let Some(&pi) = forced.get(&ci) {
            edges.push(WeightedEdge { from: pi + 1, to: ci + 1, weight: FORCED_WEIGHT });
            edge_pairs.push(Some((parts[pi].id, c.id)));
            continue;
        }
        for (pi, p) in parts.iter().enumerate() {
            if pi == ci {
                continue;
            }
            let weight = match contacts.get(&(p.id, c.id)) {
                Some(pc) if vocab.is_typical_parent(c.label, p.label) => f64::from(pc.weight + cfg.label_prior.max(0.0)),
                Some(pc) if vocab.is_grip(c.label) && grip_touches_a_part_set_into(c, p, parts, &contacts, cfg.contact.dist_max_m) => {
                    f64::from(pc.weight / cfg.grip_set_into_factor.max(1.0))
                }
                // Two parts each moved by its own grip (stacked drawers) touch, but neither is
                // mounted on the other: their contact counts as none.
                Some(_) if carriers.contains(&p.id) && carriers.contains(&c.id) => {
                    uncontacted_weight(p, c, only_peers.contains(&c.id), vocab, cfg)
                }
                Some(pc) => f64::from(pc.weight),
                None => uncontacted_weight(p, c, only_peers.contains(&c.id), vocab, cfg),
            };
            edges.push(WeightedEdge { from: pi + 1, to: ci + 1, weight });
            edge_pairs.push(Some((p.id, c.id)));
        }
    }
    let Some(chosen) = max_arborescence(n + 1, 0, &edges) else {
        // Cannot happen: the virtual root reaches every node. Keep a flat tree anyway.
        warnings.push(Warning::new("tree", "object", "no spanning tree; parts left flat"));
        return (PartTree { root: parts[0].id, ..PartTree::default() }, warnings);
    };
    let mut parent = BTreeMap::new();
    let mut roots = Vec::new();
    for k in chosen {
        match edge_pairs[k] {
            Some((p, c)) => {
                if !contacts.contains_key(&(p, c)) && !forced_parent.contains_key(&c) {
                    let message = if only_peers.contains(&c) {
                        format!("touches only parts of its own class; hung off part {p} nearby, which it does not touch")
                    } else {
                        format!("touches no other part; attached to the nearest part {p} by a fixed joint")
                    };
                    warnings.push(Warning::new("tree", format!("part {c}"), message));
                }
                parent.insert(c, p);
            }
            None => roots.push(parts[edges[k].to - 1].id),
        }
    }
    // Several roots happen only when the pins disconnect the graph: hang the others off the first.
    roots.sort_unstable();
    let root = roots.first().copied().unwrap_or(parts[0].id);
    for r in roots.iter().skip(1) {
        warnings.push(Warning::new("tree", format!("part {r}"), format!("separate component; attached to root {root}")));
        parent.insert(*r, root);
    }
    let tree_edges: Vec<ContactEdge> = contacts
        .iter()
        .map(|(&(p, c), pc)| ContactEdge { parent: p, child: c, weight: pc.weight, in_tree: parent.get(&c) == Some(&p) })
        .collect();
    (PartTree { root, parent, edges: tree_edges, contacts }, warnings)
}

/// The weight of a candidate edge `p → c` without contact. A typical parent of the child's label
/// beats any other part, the nearest within each group (weights in (1, 2] and (0, 1] ×
/// `FALLBACK_WEIGHT`). But a part that touches only its peers (parts of its own class: a fridge's
/// lower door meeting its upper door edge to edge: `touches_only_peers`) is not mounted on them: a
/// typical parent within `peer_mount_reach` × the contact distance weighs as one barely touched
/// (`label_prior`, the nearest first), so it wins over the peers (a scan may leave a seal's gap
/// between a door and its body). With the label prior off (0) the rule is off too.
fn uncontacted_weight(p: &TreePart<'_>, c: &TreePart<'_>, touches_only_peers: bool, vocab: &Vocabulary, cfg: &TreeConfig) -> f64 {
    let gap = primitive_gap(p.primitive, c.primitive);
    let typical = vocab.is_typical_parent(c.label, p.label);
    let nearness = 1.0 / (1.0 + f64::from(gap));
    if cfg.label_prior > 0.0 && typical && touches_only_peers && gap <= cfg.peer_mount_reach * cfg.contact.dist_max_m {
        return f64::from(cfg.label_prior) + FALLBACK_WEIGHT * nearness;
    }
    FALLBACK_WEIGHT * (f64::from(u8::from(typical)) + nearness)
}

/// The parts that carry a grip: for each grip-labelled part, the part it touches most, a part
/// with a part set into it that the grip also touches counting `grip_set_into_factor` less (as in
/// the tree's weights); ties to the smaller id.
fn grip_carriers(
    parts: &[TreePart<'_>],
    contacts: &BTreeMap<(PartId, PartId), PairContact>,
    vocab: &Vocabulary,
    cfg: &TreeConfig,
) -> std::collections::BTreeSet<PartId> {
    parts
        .iter()
        .filter(|g| vocab.is_grip(g.label))
        .filter_map(|g| {
            parts
                .iter()
                .filter(|q| q.id != g.id && !vocab.is_grip(q.label))
                .filter_map(|q| {
                    let w = contacts.get(&(q.id, g.id))?.weight;
                    let set_into = grip_touches_a_part_set_into(g, q, parts, contacts, cfg.contact.dist_max_m);
                    Some((if set_into { w / cfg.grip_set_into_factor.max(1.0) } else { w }, q.id))
                })
                .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)))
                .map(|(_, id)| id)
        })
        .collect()
}

/// Whether `grip` (a grip-labelled part) also touches another part whose box lies inside
/// `outer`'s box: then it is mounted on that inner part rather than on `outer` (module docs).
fn grip_touches_a_part_set_into(
    grip: &TreePart<'_>,
    outer: &TreePart<'_>,
    parts: &[TreePart<'_>],
    contacts: &BTreeMap<(PartId, PartId), PairContact>,
    margin_m: f32,
) -> bool {
    parts.iter().any(|q| {
        q.id != grip.id
            && q.id != outer.id
            && contacts.contains_key(&(q.id, grip.id))
            && lies_within(q.primitive, outer.primitive, margin_m)
    })
}

/// Whether every corner of `inner`'s box lies inside `outer`'s box grown by `margin_m`.
fn lies_within(inner: &Primitive, outer: &Primitive, margin_m: f32) -> bool {
    let half_outer = outer.size * 0.5 + crate::math::Vec3::splat(margin_m);
    inner.box_corners().iter().all(|corner_world| {
        let local = outer.world_from_primitive.inverse_transform_point(*corner_world);
        local.abs().cmple(half_outer).all()
    })
}

/// Distance between the bounding boxes of two primitives (0 when they overlap).
fn primitive_gap(a: &Primitive, b: &Primitive) -> f32 {
    let (alo, ahi) = a.aabb();
    let (blo, bhi) = b.aabb();
    (blo - ahi).max(alo - bhi).max(crate::math::Vec3::ZERO).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn table() -> Vec<(PartId, &'static str, Primitive)> {
        let mut parts = vec![(1, "top", Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.73), Vec3::new(1.2, 0.8, 0.04)))];
        for (k, (x, y)) in [(-0.55, -0.35), (0.55, -0.35), (-0.55, 0.35), (0.55, 0.35)].into_iter().enumerate() {
            parts.push((2 + k as PartId, "leg", Primitive::cuboid_at(Vec3::new(x, y, 0.355), Vec3::new(0.05, 0.05, 0.71))));
        }
        parts
    }

    #[test]
    fn table_legs_hang_off_the_top() {
        let parts = table();
        let view: Vec<TreePart> = parts.iter().map(|(id, l, p)| TreePart { id: *id, label: l, primitive: p }).collect();
        let (tree, warnings) = build_part_tree(&view, &TreeConfig::default(), &Vocabulary::builtin(), &BTreeMap::new());
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(tree.root, 1);
        for leg in 2..=5 {
            assert_eq!(tree.parent.get(&leg), Some(&1));
        }
        assert_eq!(tree.top_down(), vec![1, 2, 3, 4, 5]);
    }

    #[test]
    fn pinned_parent_wins_and_isolated_part_is_reported() {
        let mut parts = table();
        parts.push((9, "handle", Primitive::cuboid_at(Vec3::new(3.0, 0.0, 0.5), Vec3::splat(0.05))));
        let view: Vec<TreePart> = parts.iter().map(|(id, l, p)| TreePart { id: *id, label: l, primitive: p }).collect();
        let pins = BTreeMap::from([(3, 2)]);
        let (tree, warnings) = build_part_tree(&view, &TreeConfig::default(), &Vocabulary::builtin(), &pins);
        assert_eq!(tree.parent.get(&3), Some(&2));
        assert!(tree.parent.contains_key(&9));
        assert!(warnings.iter().any(|w| w.subject == "part 9"), "{warnings:?}");
    }

    #[test]
    fn handle_on_a_drawer_flush_with_the_body_front_hangs_off_the_drawer() {
        // The body's box covers the drawer front (flush at y = −0.25): the handle's back face
        // touches both front faces equally, yet it is mounted on the drawer. Neither label is a
        // typical parent of a handle (the drawer is named by position).
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.5, 1.0));
        let drawer = Primitive::cuboid_at(Vec3::new(0.0, -0.248, 0.8), Vec3::new(0.7, 0.004, 0.2));
        let handle = Primitive::cuboid_at(Vec3::new(0.0, -0.265, 0.8), Vec3::new(0.1, 0.03, 0.02));
        let view = [
            TreePart { id: 1, label: "base", primitive: &body },
            TreePart { id: 2, label: "top", primitive: &drawer },
            TreePart { id: 3, label: "handle", primitive: &handle },
        ];
        let (tree, _) = build_part_tree(&view, &TreeConfig::default(), &Vocabulary::builtin(), &BTreeMap::new());
        assert_eq!(tree.parent.get(&3), Some(&2), "{:?}", tree.parent);
        assert_eq!(tree.parent.get(&2), Some(&1), "{:?}", tree.parent);
        // A part that is not a grip keeps its contact weights (the drawer itself, under the body).
        assert!(lies_within(&drawer, &body, 0.0) && !lies_within(&body, &drawer, 0.03));
    }

    #[test]
    fn a_drawer_stacked_under_another_hangs_off_the_cabinet_not_the_drawer_above() {
        // LIBERO's wooden cabinet, partial scan (regression: the middle drawer hung off the top
        // one, which it touches more than the cabinet's box, so its grip was not at its parent's
        // front and it was made fixed). Drawers named by position, each with its handle.
        let bounds = |lo: [f32; 3], hi: [f32; 3]| {
            let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
            Primitive::cuboid_at(0.5 * (lo + hi), hi - lo)
        };
        let prims = [
            bounds([-0.121, -0.082, 0.0], [0.12, 0.111, 0.22]),
            bounds([-0.122, -0.079, 0.129], [0.122, 0.111, 0.22]),
            bounds([-0.055, -0.106, 0.172], [0.036, -0.079, 0.189]),
            bounds([-0.122, -0.079, 0.046], [0.12, 0.097, 0.129]),
            bounds([-0.052, -0.112, 0.083], [0.039, -0.079, 0.1]),
            bounds([-0.122, -0.079, 0.0], [0.12, 0.073, 0.076]),
            bounds([-0.044, -0.109, 0.027], [0.041, -0.079, 0.045]),
        ];
        let labels = ["base", "top", "handle", "cabinet", "handle", "cabinet", "handle"];
        let view: Vec<TreePart<'_>> =
            prims.iter().zip(labels).zip(1..).map(|((primitive, label), id)| TreePart { id, label, primitive }).collect();
        let (tree, _) = build_part_tree(&view, &TreeConfig::default(), &Vocabulary::builtin(), &BTreeMap::new());
        let parents: Vec<Option<&PartId>> = (2..=7).map(|c| tree.parent.get(&c)).collect();
        assert_eq!(parents, [Some(&1), Some(&2), Some(&1), Some(&4), Some(&1), Some(&6)], "{:?}", tree.parent);
    }

    #[test]
    fn a_latch_touching_the_frame_more_than_its_door_hangs_on_the_door() {
        // A door closed in its frame; the latch sits at the door's free edge, its back face half on
        // the door's front face and half on the frame post beside it — or, as in robosuite's door
        // (regression: parent wrong there), three quarters on the frame.
        for latch_x in [0.04, 0.02] {
            let frame = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.1, 0.1, 1.0));
            let door = Primitive::cuboid_at(Vec3::new(0.45, -0.03, 0.5), Vec3::new(0.8, 0.04, 1.0));
            let latch = Primitive::cuboid_at(Vec3::new(latch_x, -0.07, 0.5), Vec3::new(0.12, 0.04, 0.04));
            let view = [
                TreePart { id: 1, label: "frame", primitive: &frame },
                TreePart { id: 2, label: "door", primitive: &door },
                TreePart { id: 3, label: "latch", primitive: &latch },
            ];
            let cfg = TreeConfig::default();
            let from_frame = crate::contact::contact(&frame, &latch, &cfg.contact).expect("frame contact").weight;
            let from_door = crate::contact::contact(&door, &latch, &cfg.contact).expect("door contact").weight;
            assert!(from_frame > from_door, "the frame must touch more: {from_frame} vs {from_door}");
            let (tree, _) = build_part_tree(&view, &cfg, &Vocabulary::builtin(), &BTreeMap::new());
            assert_eq!(tree.parent.get(&3), Some(&2), "latch at x = {latch_x}: {:?}", tree.parent);
        }
    }

    #[test]
    fn a_fridge_door_touching_only_the_door_above_hangs_off_the_body_behind_it() {
        // ReplicaCAD's fridge (regression: the lower door hung off the upper one and turned about
        // their shared edge): the lower door stands 3.3 cm proud of the body, and its top edge
        // meets the upper door's bottom edge.
        let body = Primitive::cuboid_at(Vec3::new(-0.052, 0.0, 0.953), Vec3::new(0.618, 0.698, 1.882));
        let upper = Primitive::cuboid_at(Vec3::new(0.3055, 0.0, 1.326), Vec3::new(0.097, 0.712, 1.082));
        let lower = Primitive::cuboid_at(Vec3::new(0.323, 0.0, 0.3925), Vec3::new(0.066, 0.686, 0.785));
        let view = [
            TreePart { id: 1, label: "body", primitive: &body },
            TreePart { id: 2, label: "door", primitive: &upper },
            TreePart { id: 3, label: "door", primitive: &lower },
        ];
        let cfg = TreeConfig::default();
        assert!(crate::contact::contact(&upper, &lower, &cfg.contact).is_some(), "the doors meet");
        assert!(crate::contact::contact(&body, &lower, &cfg.contact).is_none(), "the body is not touched");
        let (tree, warnings) = build_part_tree(&view, &cfg, &Vocabulary::builtin(), &BTreeMap::new());
        assert_eq!((tree.parent.get(&2), tree.parent.get(&3)), (Some(&1), Some(&1)), "{:?}", tree.parent);
        assert!(warnings.iter().any(|w| w.subject == "part 3" && w.message.contains("own class")), "{warnings:?}");
        // Beyond twice the contact distance the body is no mount: the door stays on its peer.
        let far = Primitive::cuboid_at(Vec3::new(0.39, 0.0, 0.3925), Vec3::new(0.066, 0.686, 0.785));
        let upper_deep = Primitive::cuboid_at(Vec3::new(0.339, 0.0, 1.326), Vec3::new(0.164, 0.712, 1.082));
        let view = [
            TreePart { id: 1, label: "body", primitive: &body },
            TreePart { id: 2, label: "door", primitive: &upper_deep },
            TreePart { id: 3, label: "door", primitive: &far },
        ];
        let (tree, _) = build_part_tree(&view, &cfg, &Vocabulary::builtin(), &BTreeMap::new());
        assert_eq!(tree.parent.get(&3), Some(&2), "{:?}", tree.parent);
    }

    #[test]
    fn a_part_touching_nothing_goes_to_its_typical_parent_before_the_nearest_part() {
        // A bed whose frame was seen only over its foot half: the headboard (x ≈ 0) touches
        // nothing; the mattress is 8 cm away, the frame 80 cm.
        let frame = Primitive::cuboid_at(Vec3::new(1.6, 0.0, 0.2), Vec3::new(0.85, 1.3, 0.4));
        let mattress = Primitive::cuboid_at(Vec3::new(1.07, 0.0, 0.52), Vec3::new(1.92, 1.24, 0.24));
        let headboard = Primitive::cuboid_at(Vec3::new(0.02, 0.0, 0.57), Vec3::new(0.05, 1.37, 0.9));
        let view = [
            TreePart { id: 1, label: "frame", primitive: &frame },
            TreePart { id: 2, label: "mattress", primitive: &mattress },
            TreePart { id: 3, label: "headboard", primitive: &headboard },
        ];
        let (tree, warnings) = build_part_tree(&view, &TreeConfig::default(), &Vocabulary::builtin(), &BTreeMap::new());
        assert_eq!(tree.parent.get(&3), Some(&1), "{:?}", tree.parent);
        assert!(warnings.iter().any(|w| w.subject == "part 3"), "reported: {warnings:?}");
    }
}
