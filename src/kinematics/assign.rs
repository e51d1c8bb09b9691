//! Joint templates fitted to the geometry (paper III-B: "matching the primitive parts to a
//! library of articulated templates"). Which template a part gets comes from its label's class
//! and the geometric tests ([`super::evidence`]); here each is fitted:
//!
//! | template | joint | axis | pivot / origin | limits |
//! | --- | --- | --- | --- | --- |
//! | fixed | fixed | — | child centre | 0 |
//! | drawer | prismatic | the parent's face normal the part sits on, outward | child centre | 0 .. `drawer_travel` × parent depth |
//! | `hinge`, `lid_hinge` | revolute | the door edge away from its handle (vertical for side doors without one, on the outer edge; a lid's longer edge towards the parent's centre; centred on the parent without a grip: either edge, [`HingeEdge::Undetermined`]) | on that edge, at the door's back face (where its points end, when they reach past its box); a door set into its parent's opening (half its thickness or more within the parent's depth): in the jamb beside the edge, at mid-thickness | 0 .. `revolute_upper_rad` |
//! | `sliding_panel` | prismatic | in the panel's plane, towards the parent's centre (where it has room) | child centre | 0 .. the gap |
//! | knob | revolute | the outward face normal (or the round axis a test found; touching nothing, a disc's thin axis) | knob centre | −π .. π |
//! | lever | revolute | the outward face normal | a bar (≥ `lever_min_elongation` × as long as wide across the axis): its end away from a grip on it, else the end nearer the parent's centre; otherwise, or through its mount, its centre | −π .. π |
//! | rocker | revolute | the part's in-plane axis along its shorter side (a lever: the test's pivot line) | part centre (a lever: where it leaves its mount) | ± `rocker_tilt_rad` |
//! | button | prismatic | into the parent (a round cap no taller than wide: along its own axis) | button centre | 0 .. `button_travel_m` |
//! | `lift_off` | prismatic | the round body's axis, outward | lid centre | 0 .. half the body's height |
//! | swing | revolute | the handle's long axis through its ends | on the body's axis | ± π/2 |
//! | spin, turn | continuous | the part's round axis (spin) or the mount normal (turn) | part centre | display range ± π |
//!
//! Axes are signed so that positive motion opens: a drawer slides out, a door swings away from
//! its parent.

use serde::{Deserialize, Serialize};

use super::joint::{Joint, JointKind};
use super::vocabulary::Template;
use crate::fit::PointSpan;
use crate::math::{UP, Vec3};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::PartId;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KinematicsConfig {
    /// Upper limit of doors and lids, radians.
    pub revolute_upper_rad: f32,
    /// A drawer slides out this fraction of its parent's depth.
    pub drawer_travel: f32,
    /// Travel of a button, metres.
    pub button_travel_m: f32,
    /// Tilt of a rocker switch either way, radians.
    pub rocker_tilt_rad: f32,
    /// How many times longer than wide (across its axis) a lever must be to turn about an end.
    #[serde(default = "default_lever_min_elongation")]
    pub lever_min_elongation: f32,
}

fn default_lever_min_elongation() -> f32 {
    2.0
}

impl Default for KinematicsConfig {
    fn default() -> Self {
        Self {
            revolute_upper_rad: std::f32::consts::FRAC_PI_2,
            drawer_travel: 0.85,
            button_travel_m: 0.005,
            rocker_tilt_rad: 0.26,
            lever_min_elongation: default_lever_min_elongation(),
        }
    }
}

/// The direction in which `child` sticks out of `parent`: one of the parent's six face normals,
/// the one the child lies farthest along (relative to the parent's half extent), with the
/// handle's offset as extra evidence (a handle sticks out of the front).
#[must_use]
pub fn outward_direction(parent: &Primitive, child: &Primitive, handle: Option<Vec3>) -> Vec3 {
    let axes = parent.axes_world();
    let half = parent.size * 0.5;
    let offset = child.center() - parent.center();
    let mut best = (f32::NEG_INFINITY, axes[0]);
    for (k, axis) in axes.iter().enumerate() {
        for side in [1.0_f32, -1.0] {
            let n = *axis * side;
            let mut score = offset.dot(n) / half[k].max(1e-3);
            if let Some(h) = handle {
                // A handle stands proud of the child's front face: its offset along n, measured
                // against the child's own half thickness along n (noise-sized offsets count little).
                let reach = 0.5 * child.extent_along(n) + 0.01;
                score += 0.5 * ((h - child.center()).dot(n) / reach).clamp(-1.0, 1.0);
            }
            if score > best.0 + 1e-6 {
                best = (score, n);
            }
        }
    }
    best.1
}

/// What [`fit_joint`] fits: the type, its template, and what the geometry already told.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointSpec {
    pub kind: JointKind,
    pub template: Template,
    /// Centre of a handle, knob or latch mounted on the child, if it has one ([`super::Vocabulary::marks_free_edge`]).
    pub handle: Option<Vec3>,
    /// The outward normal of the parent face the child is mounted on (paper eq. 1), when known.
    pub mount_normal: Option<Vec3>,
    /// An axis and a point on it fixed by a geometric test (swing handles, lift-off lids, discs).
    pub axis_line: Option<(Vec3, Vec3)>,
    /// The edge a person chose for a door's or lid's hinge: a world direction from the part's
    /// centre towards it ([`crate::edit::EditCommand::OtherHingeEdge`]).
    pub hinge_edge_world: Option<Vec3>,
    /// Where the child's points end along its primitive's axes (a door's back, which a box
    /// fitted to a door with its handle can stop short of).
    pub child_span: Option<PointSpan>,
}

/// How a hinge's edge was chosen ([`fit_joint`]); the evidence states it with a confidence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HingeEdge {
    /// The edge away from a handle, knob or latch on the part (the grip marks the free edge).
    AwayFromGrip,
    /// No grip, a side door off-centre on its parent: its outer edge (double doors hinge outside).
    OuterEdge,
    /// No grip, a lid off-centre on its parent: its long edge towards the parent's centre.
    TowardsParentCentre,
    /// No grip and centred on its parent (within [`CENTRED_ON_PARENT`] of its half-width):
    /// nothing in the geometry tells the two edges apart; one is taken.
    Undetermined,
    /// The edge a person chose.
    Pinned,
}

/// Where a hinge stands and why ([`fit_joint`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HingePlacement {
    /// How its edge was chosen.
    pub edge: HingeEdge,
    /// How far behind the back face of the part's box its pin stands because the part's points
    /// reach past that face (a box fitted to a door with its handle), metres; 0 otherwise.
    pub past_box_m: f32,
}

/// A door or lid whose centre lies within this fraction of its half-width (across the hinge)
/// of its parent's centre is centred on it: its offset says nothing of its hinge side.
pub const CENTRED_ON_PARENT: f32 = 0.1;

/// Estimates the joint between `parent` and `child` ([`JointSpec`]; templates in the module
/// docs). The mount normal is the direction a drawer slides, a door opens towards, a knob turns
/// about. A vertical mount normal for a side-opening template (drawer, door hinge, sliding panel;
/// found resting on a shelf rather than hung in the front) is not trusted; then, and without a
/// contact, [`outward_direction`] decides from the geometry. Where a hinge stands and how its
/// edge was chosen is returned beside the joint (`None` for other templates).
#[must_use]
pub fn fit_joint(
    parent_id: PartId,
    parent: &Primitive,
    child_id: PartId,
    child: &Primitive,
    spec: &JointSpec,
    cfg: &KinematicsConfig,
) -> (Joint, Option<HingePlacement>) {
    let side_opening = matches!(spec.template, Template::SlidingPanel | Template::Drawer | Template::Hinge);
    let out = match spec.mount_normal {
        Some(n) if !(side_opening && n.dot(UP).abs() > 0.7) => n.normalize_or(Vec3::Z),
        _ => outward_direction(parent, child, spec.handle),
    };
    let kind = spec.kind;
    let mut joint =
        Joint { parent: parent_id, child: child_id, kind, axis_world: out, origin_world: child.center(), lower: 0.0, upper: 0.0 };
    if kind == JointKind::Fixed {
        return (joint, None);
    }
    let mut hinge_edge = None;
    match spec.template {
        Template::Fixed => {}
        Template::SlidingPanel => (joint.axis_world, joint.upper) = slide_in_plane(parent, child, out),
        Template::Button => {
            // A round cap is pressed along its own axis, into the parent; else into the face.
            joint.axis_world = match child.kind {
                PrimitiveKind::Cylinder if child.size.z <= child.size.x.max(child.size.y) => {
                    let a = child.axes_world()[2];
                    if a.dot(parent.center() - child.center()) < 0.0 { -a } else { a }
                }
                _ => -out,
            };
            joint.upper = cfg.button_travel_m;
        }
        Template::Drawer => {
            joint.upper = cfg.drawer_travel * parent.extent_along(out);
        }
        Template::Knob | Template::Lever => {
            if let Some((axis, origin)) = spec.axis_line {
                joint.axis_world = axis;
                joint.origin_world = origin;
            } else if spec.template == Template::Knob
                && spec.mount_normal.is_none()
                && let Some(axis) = disc_axis(child)
            {
                // Touching nothing, it shows no face it is mounted on: a dial turns about its
                // own thin axis (pointing away from the parent's centre).
                joint.axis_world = if axis.dot(child.center() - parent.center()) < 0.0 { -axis } else { axis };
            }
            if spec.axis_line.is_none() && spec.template == Template::Lever {
                joint.origin_world = lever_pivot(parent, child, out, spec.handle, cfg.lever_min_elongation);
            }
            joint.lower = -std::f32::consts::PI;
            joint.upper = std::f32::consts::PI;
        }
        Template::Rocker => {
            joint.lower = -cfg.rocker_tilt_rad;
            joint.upper = cfg.rocker_tilt_rad;
            if let Some((axis, pivot)) = spec.axis_line {
                // A lever's pivot line, found by its test.
                joint.axis_world = axis;
                joint.origin_world = pivot;
                return (joint, None);
            }
            // About the in-plane box axis along the shorter side, through the centre.
            let axes = child.axes_world();
            let axis = (0..3)
                .filter(|&a| axes[a].dot(out).abs() < 0.5)
                .min_by(|&a, &b| child.size[a].total_cmp(&child.size[b]).then(a.cmp(&b)))
                .map_or(axes[0], |a| axes[a]);
            joint.axis_world = axis;
        }
        Template::Hinge | Template::LidHinge => {
            let (axis, pivot, placement) = hinge(parent, child, out, spec);
            joint.axis_world = axis;
            joint.origin_world = pivot;
            hinge_edge = Some(placement);
            joint.upper = cfg.revolute_upper_rad;
        }
        Template::LiftOff => {
            let axis = spec.axis_line.map_or(out, |(a, _)| a);
            joint.axis_world = axis;
            joint.upper = 0.5 * parent.extent_along(axis);
        }
        Template::Swing => {
            if let Some((axis, origin)) = spec.axis_line {
                joint.axis_world = axis;
                joint.origin_world = origin;
            }
            joint.lower = -std::f32::consts::FRAC_PI_2;
            joint.upper = std::f32::consts::FRAC_PI_2;
        }
        Template::Spin | Template::Turn => {
            joint.axis_world = match (spec.template, spec.axis_line) {
                (Template::Spin, Some((a, _))) => a,
                (Template::Spin, None) => round_axis(child),
                _ => out,
            };
            joint.lower = -std::f32::consts::PI;
            joint.upper = std::f32::consts::PI;
        }
    }
    (joint, hinge_edge)
}

/// Axis and travel of a sliding panel: in its own plane, along the panel's box axis that points
/// towards the parent's centre: that is where the panel has room to go (a sliding door over half
/// a front, a sash over the lower half of its frame); travel up to that gap. The plane is the
/// panel's own (its thinnest axis is its normal) where it is a panel: a sash touching no frame
/// face has no mount normal to go by. A panel standing out of the face it is mounted on (a
/// desk's sliding cover on its top) runs along that face: the in-plane axis across the mount
/// normal `out`.
fn slide_in_plane(parent: &Primitive, child: &Primitive, out: Vec3) -> (Vec3, f32) {
    let normal = panel_normal(child).unwrap_or(out);
    let towards = parent.center() - child.center();
    let in_plane = towards - normal * towards.dot(normal);
    let axes = child.axes_world();
    let stands_out = child.center().dot(out) + 0.5 * child.extent_along(out) > parent.center().dot(out) + 0.5 * parent.extent_along(out);
    let along_mount = (stands_out && normal.dot(out).abs() < 0.5).then(|| normal.cross(out).normalize_or_zero());
    let axis = along_mount.filter(|a| *a != Vec3::ZERO).unwrap_or_else(|| {
        axes.iter()
            .filter(|a| a.dot(normal).abs() < 0.5)
            .max_by(|a, b| a.dot(in_plane).abs().total_cmp(&b.dot(in_plane).abs()))
            .copied()
            .unwrap_or(axes[0])
    });
    let axis = if axis.dot(in_plane) < 0.0 { -axis } else { axis };
    (axis, (2.0 * in_plane.dot(axis)).max(0.0).min(parent.extent_along(axis)))
}

/// Where a lever turning about `axis` is pivoted: a bar (its longest extent across the axis at
/// least `min_elongation` × the other) turns about one end, the one away from a grip
/// mounted on it, else the one nearer `parent`'s centre (the end its mount supports; the other
/// reaches out); anything squarer turns about its centre, and so does a bar that passes through
/// its mount to stand out of both faces (handles on both sides of a door, one spindle between).
fn lever_pivot(parent: &Primitive, lever: &Primitive, axis: Vec3, grip: Option<Vec3>, min_elongation: f32) -> Vec3 {
    let c = lever.center();
    let (pc, reach) = (parent.center().dot(axis), 0.5 * parent.extent_along(axis));
    let (lc, half) = (c.dot(axis), 0.5 * lever.extent_along(axis));
    if lc - half < pc - reach && lc + half > pc + reach {
        return c;
    }
    let axes = lever.axes_world();
    let mut across: Vec<(f32, Vec3)> = (0..3).filter(|&k| axes[k].dot(axis).abs() < 0.5).map(|k| (lever.size[k], axes[k])).collect();
    across.sort_by(|a, b| b.0.total_cmp(&a.0));
    let [(long, dir), (wide, _)] = across[..] else { return c };
    if long < min_elongation * wide {
        return c;
    }
    let ends = [c + dir * (0.5 * long), c - dir * (0.5 * long)];
    let away_from = |p: Vec3| if (ends[0] - p).length() >= (ends[1] - p).length() { ends[0] } else { ends[1] };
    let nearer_to = |p: Vec3| if (ends[0] - p).length() <= (ends[1] - p).length() { ends[0] } else { ends[1] };
    grip.map_or_else(|| nearer_to(parent.center()), away_from)
}

/// The normal of a panel: its thinnest box axis, where that extent is at most half the next.
fn panel_normal(p: &Primitive) -> Option<Vec3> {
    let axes = p.axes_world();
    let mut order = [0_usize, 1, 2];
    order.sort_by(|&a, &b| p.size[a].total_cmp(&p.size[b]));
    (p.size[order[0]] <= 0.5 * p.size[order[1]]).then_some(axes[order[0]])
}

/// The thin axis of a disc-shaped part: its smallest box extent at most 0.6× the next, and its
/// face no more than twice as long as wide (a dial, not a bar).
fn disc_axis(p: &Primitive) -> Option<Vec3> {
    let axes = p.axes_world();
    let mut order = [0_usize, 1, 2];
    order.sort_by(|&a, &b| p.size[a].total_cmp(&p.size[b]));
    let [thin, mid, long] = order.map(|k| p.size[k]);
    (thin <= 0.6 * mid && long <= 2.0 * mid).then_some(axes[order[0]])
}

/// The axis a round part turns about: a cylinder's or capsule's own axis, else the box axis of
/// its smallest extent (a disc's thickness).
fn round_axis(p: &Primitive) -> Vec3 {
    let axes = p.axes_world();
    match p.kind {
        PrimitiveKind::Cylinder | PrimitiveKind::Capsule => axes[2],
        _ => (0..3).min_by(|&a, &b| p.size[a].total_cmp(&p.size[b])).map_or(axes[2], |a| axes[a]),
    }
}

/// A handle whose offset from the panel's centre is below this fraction of the panel's half
/// extent, along both in-plane axes, is centred: the panel is pulled straight out.
const CENTRED_HANDLE: f32 = 0.35;

/// The joint template a part calls for from its geometry when its label names no joint but a
/// handle is mounted on it (labels + geometry): the handle marks the part's front, the side
/// it is pulled from. With `n` the parent's face normal nearest that front, the part must sit at
/// the parent's front (its front face within `max(3 cm, 10 %` of the parent's depth) of the
/// parent's face along `n`, `n` horizontal, its centre inside the parent's face outline); then
/// - a handle centred on the front → a drawer: prismatic out of the front (a drawer front is
///   pulled straight out; a closed drawer shows only its front, so its depth cannot decide);
/// - a handle off centre on a thin panel (thickness at most half its smaller side) → a door:
///   revolute, hinged on the edge away from the handle (the handle sits where the lever is).
///
/// Returns the kind and the outward front normal (the mount normal for [`fit_joint`]);
/// `None` keeps the part rigid (no front found, not at the parent's front, a lid-like top face,
/// a thick block with an off-centre handle).
#[must_use]
pub fn joint_from_handle(parent: &Primitive, child: &Primitive, handle: Vec3) -> Option<(JointKind, Vec3)> {
    let axes = child.axes_world();
    let half = child.size * 0.5;
    let d = handle - child.center();
    // The front: the child axis along which the handle stands farthest beyond the child's box.
    let front = (0..3).max_by(|&a, &b| (d.dot(axes[a]).abs() - half[a]).total_cmp(&(d.dot(axes[b]).abs() - half[b])))?;
    let along = d.dot(axes[front]);
    if along.abs() < 0.5 * half[front] {
        return None; // the handle is not on a face of the part
    }
    let front_dir = axes[front] * along.signum();
    // Snap to the parent's nearest face normal.
    let paxes = parent.axes_world();
    let k = (0..3).max_by(|&a, &b| paxes[a].dot(front_dir).abs().total_cmp(&paxes[b].dot(front_dir).abs()))?;
    let cos = paxes[k].dot(front_dir);
    if cos.abs() < 0.87 {
        return None;
    }
    let n = paxes[k] * cos.signum();
    if n.dot(UP).abs() > 0.7 {
        return None; // a top face: a lid or a tray, not decided here
    }
    let parent_half = parent.size * 0.5;
    let parent_front = parent.center().dot(n) + parent_half[k];
    let child_front = child.center().dot(n) + 0.5 * child.extent_along(n);
    if (child_front - parent_front).abs() > (0.1 * parent.size[k]).max(0.03) {
        return None;
    }
    let offset = child.center() - parent.center();
    let inside_outline = (0..3).filter(|&a| a != k).all(|a| offset.dot(paxes[a]).abs() <= parent_half[a]);
    if !inside_outline {
        return None;
    }
    let in_plane: Vec<usize> = (0..3).filter(|&a| a != front).collect();
    let centred = in_plane.iter().all(|&a| d.dot(axes[a]).abs() < CENTRED_HANDLE * half[a].max(1e-4));
    if centred {
        return Some((JointKind::Prismatic, n));
    }
    let thin = child.size[front] <= 0.5 * in_plane.iter().map(|&a| child.size[a]).fold(f32::INFINITY, f32::min);
    thin.then_some((JointKind::Revolute, n))
}

/// Hinge line of a door or lid: direction (signed so a positive angle opens outward), a pivot
/// point, and how its edge was chosen. The spec's `hinge_edge_world` (a person's choice: a world
/// direction from the part's centre towards the edge) overrides the rules.
fn hinge(parent: &Primitive, door: &Primitive, out: Vec3, spec: &JointSpec) -> (Vec3, Vec3, HingePlacement) {
    let axes = door.axes_world();
    let half = door.size * 0.5;
    let thick = (0..3).max_by(|&a, &b| axes[a].dot(out).abs().total_cmp(&axes[b].dot(out).abs())).unwrap_or(2);
    let in_plane = ((thick + 1) % 3, (thick + 2) % 3);
    let c = door.center();
    let pinned = spec.hinge_edge_world.and_then(|dir| {
        // The in-plane axis the chosen edge lies across, and its side.
        let (i1, i2) = in_plane;
        let (h, a) = if axes[i1].dot(dir).abs() >= axes[i2].dot(dir).abs() { (i2, i1) } else { (i1, i2) };
        let along = axes[a].dot(dir);
        (along.abs() > 1e-3).then(|| (h, a, along.signum(), HingeEdge::Pinned))
    });
    let (hinge_axis, across, side, edge) =
        pinned.or_else(|| edge_from_grip(door, spec.handle, in_plane)).unwrap_or_else(|| edge_without_grip(parent, door, out, in_plane));
    let (pivot, past_box_m) = if let Some(past_edge) = inset_pin_offset(parent, door, axes[across] * side, out, half[across]) {
        // An inset door: its pin stands in the jamb beside its edge, at mid-thickness.
        (c + axes[across] * (side * (half[across] + past_edge)), 0.0)
    } else {
        // An overlay door or lid swings about its back edge, against the parent's face: where
        // its points end behind it when they reach past its box.
        let facing = axes[thick].dot(out);
        let behind = spec.child_span.and_then(|span| span.reach_behind(thick, facing)).map_or(half[thick], |r| r.max(half[thick]));
        (c + axes[across] * (side * half[across]) - out * (facing.abs() * behind), behind - half[thick])
    };
    let mut axis = axes[hinge_axis];
    if axis.cross(c - pivot).dot(out) < 0.0 {
        axis = -axis;
    }
    (axis, pivot, HingePlacement { edge, past_box_m })
}

/// A hinge's (axis index, across index, side along the across axis, how chosen) from a grip
/// mounted off the door's centre: the hinge runs along the other in-plane axis, on the edge away
/// from the grip. `None` for a grip near the centre (within a tenth of the half-size): no cue.
fn edge_from_grip(door: &Primitive, handle: Option<Vec3>, (i1, i2): (usize, usize)) -> Option<(usize, usize, f32, HingeEdge)> {
    let axes = door.axes_world();
    let half = door.size * 0.5;
    let d = handle? - door.center();
    let r1 = d.dot(axes[i1]) / half[i1].max(1e-3);
    let r2 = d.dot(axes[i2]) / half[i2].max(1e-3);
    if r1.abs().max(r2.abs()) < 0.1 {
        return None;
    }
    Some(if r1.abs() >= r2.abs() {
        (i2, i1, -r1.signum(), HingeEdge::AwayFromGrip)
    } else {
        (i1, i2, -r2.signum(), HingeEdge::AwayFromGrip)
    })
}

/// The hinge of a door or lid with no grip off its centre: (hinge axis index, across axis
/// index, side along the across axis, how chosen). A side door hinges about its vertical
/// in-plane axis, on the outer edge, away from its parent's centre (double doors hinge outside);
/// a lid along its longer side, on the edge towards its parent's centre. A part centred on its
/// parent shows no side: the rule still gives one (deterministically), marked
/// [`HingeEdge::Undetermined`].
fn edge_without_grip(parent: &Primitive, door: &Primitive, out: Vec3, (i1, i2): (usize, usize)) -> (usize, usize, f32, HingeEdge) {
    let axes = door.axes_world();
    let half = door.size * 0.5;
    let vertical_out = out.dot(UP).abs() > 0.7;
    let (h, a) = if vertical_out {
        // A lid: hinge along its longer side.
        if half[i1] >= half[i2] { (i1, i2) } else { (i2, i1) }
    } else if axes[i1].dot(UP).abs() >= axes[i2].dot(UP).abs() {
        (i1, i2) // a side door: vertical hinge
    } else {
        (i2, i1)
    };
    let towards_parent = (parent.center() - door.center()).dot(axes[a]);
    let side = if vertical_out {
        if towards_parent >= 0.0 { 1.0 } else { -1.0 }
    } else if towards_parent > 0.0 {
        -1.0
    } else {
        1.0
    };
    let edge = if towards_parent.abs() < CENTRED_ON_PARENT * half[a] {
        HingeEdge::Undetermined
    } else if vertical_out {
        HingeEdge::TowardsParentCentre
    } else {
        HingeEdge::OuterEdge
    };
    (h, a, side, edge)
}

/// Least share of a door's thickness that must lie within the parent's depth for the door to be
/// inset (set into the parent's opening rather than laid over its face).
const INSET_DEPTH_SHARE: f32 = 0.5;

/// How far past its hinge edge (along `towards_edge`, unit, from the door's centre) an inset
/// door's pin stands, or None for a door laid over its parent's face (less than
/// [`INSET_DEPTH_SHARE`] of its thickness within the parent's depth along `out`). A door set
/// into its parent's opening cannot swing about its back edge, which lies inside the opening:
/// its pin stands in the jamb beside it, at mid-thickness, half way to the parent's outer side
/// there, and no further from the edge than the door is thick (a pin further out would open a
/// gap as the door turns). Doors on other projects' assets: a frame post's axis 3.5–6 cm past
/// the door's edge (robosuite, Adroit), a pin in the 0.8 cm gap (Meta-World's door lock).
fn inset_pin_offset(parent: &Primitive, door: &Primitive, towards_edge: Vec3, out: Vec3, half_across: f32) -> Option<f32> {
    let along = |p: &Primitive, dir: Vec3| {
        let (c, h) = (p.center().dot(dir), 0.5 * p.extent_along(dir));
        (c - h, c + h)
    };
    let (door_back, door_front) = along(door, out);
    let (parent_back, parent_front) = along(parent, out);
    let thickness = door_front - door_back;
    let within = door_front.min(parent_front) - door_back.max(parent_back);
    if thickness <= 0.0 || within < INSET_DEPTH_SHARE * thickness {
        return None;
    }
    let edge = door.center().dot(towards_edge) + half_across;
    let parent_side = along(parent, towards_edge).1;
    Some((0.5 * (parent_side - edge)).clamp(0.0, thickness))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(kind: JointKind, template: Template, handle: Option<Vec3>, mount_normal: Option<Vec3>) -> JointSpec {
        JointSpec { kind, template, handle, mount_normal, axis_line: None, hinge_edge_world: None, child_span: None }
    }

    /// What [`joint_from_handle`] makes of `child` on `parent` with a handle at `handle`.
    fn check_handle(parent: &Primitive, child: &Primitive, handle: Vec3, expected: Option<(JointKind, Vec3)>) {
        let got = joint_from_handle(parent, child, handle);
        match (got, expected) {
            (Some((kind, front)), Some((want, want_front))) => {
                assert_eq!(kind, want, "{child:?} handle {handle}");
                assert!(front.dot(want_front) > 0.999, "front {front} for {child:?}");
            }
            (None, None) => {}
            _ => panic!("{got:?}, expected {expected:?} for {child:?} with handle {handle}"),
        }
    }

    #[test]
    fn a_sash_touching_no_frame_face_slides_in_its_own_plane() {
        // Meta-World's window (regression: slid out of its plane, 90 degrees off): the sash in
        // the lower half of a deep frame, touching none of its faces; it slides up.
        let frame = Primitive::cuboid_at(Vec3::new(-0.002, -0.0135, 0.2405), Vec3::new(0.376, 0.121, 0.481));
        let sash = Primitive::cuboid_at(Vec3::new(-0.004, 0.0085, 0.151), Vec3::new(0.29, 0.017, 0.2));
        let cfg = KinematicsConfig::default();
        let j = fit_joint(1, &frame, 2, &sash, &spec(JointKind::Prismatic, Template::SlidingPanel, None, None), &cfg).0;
        assert!(j.axis_world.dot(Vec3::Z) > 0.99, "{}", j.axis_world);
        assert!(j.upper > 0.15, "{}", j.upper);
        // CALVIN's desk: a sliding cover standing on the desk's top runs along the top.
        let desk = Primitive::cuboid_at(Vec3::new(0.001, 0.04, 0.402), Vec3::new(1.058, 0.413, 0.804));
        let cover = Primitive::cuboid_at(Vec3::new(0.05, 0.084, 0.69), Vec3::new(0.355, 0.074, 0.278));
        let j = fit_joint(1, &desk, 2, &cover, &spec(JointKind::Prismatic, Template::SlidingPanel, None, None), &cfg).0;
        assert!(j.axis_world.dot(Vec3::X).abs() > 0.99, "{}", j.axis_world);
    }

    #[test]
    fn a_dial_touching_nothing_turns_about_its_own_thin_axis_not_towards_the_nearest_part() {
        // The franka oven's first knob (regression: 90 degrees off): seen apart from the hood it
        // sits on, hung off a small plate beside it; the plate's side is no mount face.
        let plate = Primitive::cuboid_at(Vec3::new(-0.4, -0.035, 2.27), Vec3::new(0.078, 0.012, 0.054));
        let dial = Primitive::cuboid_at(Vec3::new(-0.125, -0.065, 2.22), Vec3::new(0.09, 0.023, 0.08));
        let cfg = KinematicsConfig::default();
        let j = fit_joint(1, &plate, 2, &dial, &spec(JointKind::Revolute, Template::Knob, None, None), &cfg).0;
        assert!(j.axis_world.dot(Vec3::NEG_Y) > 0.99, "{}", j.axis_world);
        // Mounted on a face it touches, that face decides.
        let j = fit_joint(1, &plate, 2, &dial, &spec(JointKind::Revolute, Template::Knob, None, Some(Vec3::X)), &cfg).0;
        assert!(j.axis_world.dot(Vec3::X) > 0.99, "{}", j.axis_world);
    }

    #[test]
    fn a_lever_turns_about_the_end_away_from_its_grip_else_the_end_its_mount_supports() {
        // Meta-World's lever: a bar 20 cm long on the side of a base, a ball grip at its far end;
        // and a lock bar on a door without a grip. Regression: both turned about their centres.
        let base = Primitive::cuboid_at(Vec3::new(-0.05, 0.07, 0.2), Vec3::new(0.08, 0.17, 0.33));
        let bar = Primitive::cuboid_at(Vec3::new(0.06, 0.01, 0.27), Vec3::new(0.04, 0.2, 0.025));
        let cfg = KinematicsConfig::default();
        let lever = |grip: Option<Vec3>| {
            fit_joint(1, &base, 2, &bar, &spec(JointKind::Revolute, Template::Lever, grip, Some(Vec3::X)), &cfg).0.origin_world
        };
        assert!((lever(Some(Vec3::new(0.07, -0.13, 0.25))) - Vec3::new(0.06, 0.11, 0.27)).length() < 1e-5);
        // A grip at the end its mount supports: the grip decides.
        assert!((lever(Some(Vec3::new(0.07, 0.13, 0.25))) - Vec3::new(0.06, -0.09, 0.27)).length() < 1e-5);
        assert!((lever(None) - Vec3::new(0.06, 0.11, 0.27)).length() < 1e-5, "the end nearer the base's centre");
        // A square latch plate turns about its centre, and so does a bar through a door (ADROIT's
        // latch: a handle on each face).
        let plate = Primitive::cuboid_at(Vec3::new(0.06, 0.01, 0.27), Vec3::new(0.02, 0.06, 0.05));
        let j = fit_joint(1, &base, 2, &plate, &spec(JointKind::Revolute, Template::Lever, None, Some(Vec3::X)), &cfg).0;
        assert!((j.origin_world - plate.center()).length() < 1e-6);
        let door = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.1, 0.5, 1.0));
        let through = Primitive::cuboid_at(Vec3::new(0.0, 0.1, 1.0), Vec3::new(0.28, 0.44, 0.07));
        let j = fit_joint(1, &door, 2, &through, &spec(JointKind::Revolute, Template::Lever, None, Some(Vec3::X)), &cfg).0;
        assert!((j.origin_world - through.center()).length() < 1e-6);
    }

    #[test]
    fn a_round_button_on_a_desk_top_is_pressed_along_its_own_axis_not_towards_the_desk_front() {
        // CALVIN's button: a cap 8 cm across, 3 cm tall, near the front edge of a desk's top
        // (the desk's box is deep, so its front face is the nearest); it is pressed down.
        let desk = Primitive::cuboid_at(Vec3::new(0.0, 0.04, 0.4), Vec3::new(1.05, 0.41, 0.8));
        let cap = Primitive::new(
            crate::primitive::PrimitiveKind::Cylinder,
            Vec3::new(0.08, 0.08, 0.03),
            crate::math::Pose::from_parts(Vec3::new(-0.35, -0.12, 0.58), crate::math::Quat::IDENTITY),
        );
        let j = fit_joint(1, &desk, 2, &cap, &spec(JointKind::Prismatic, Template::Button, None, None), &KinematicsConfig::default()).0;
        assert!(j.axis_world.dot(Vec3::NEG_Z) > 0.999, "{}", j.axis_world);
        // A square key is pressed into the face it sits on.
        let key = Primitive::cuboid_at(Vec3::new(-0.35, -0.175, 0.58), Vec3::new(0.03, 0.02, 0.03));
        let j = fit_joint(1, &desk, 2, &key, &spec(JointKind::Prismatic, Template::Button, None, None), &KinematicsConfig::default()).0;
        assert!(j.axis_world.dot(Vec3::Y) > 0.999, "{}", j.axis_world);
    }

    #[test]
    fn drawer_named_by_position_with_a_handle_slides() {
        // LIBERO's wooden cabinet: drawer bodies `cabinet_top/middle/bottom` (labels "top",
        // "part"); a closed drawer shows only its front, flush with the body's front (y = −0.25).
        let body = cabinet_body();
        let front = Primitive::cuboid_at(Vec3::new(0.0, -0.248, 0.8), Vec3::new(0.7, 0.004, 0.2));
        let deep = Primitive::cuboid_at(Vec3::new(0.0, -0.05, 0.8), Vec3::new(0.7, 0.4, 0.2));
        let handle = Vec3::new(0.01, -0.265, 0.8);
        check_handle(&body, &front, handle, Some((JointKind::Prismatic, Vec3::NEG_Y)));
        check_handle(&body, &deep, handle, Some((JointKind::Prismatic, Vec3::NEG_Y)));
        // Through the pipeline's estimate: slides out of the front by most of the body's depth.
        let j = fit_joint(
            1,
            &body,
            2,
            &front,
            &spec(JointKind::Prismatic, Template::Drawer, Some(handle), Some(Vec3::NEG_Y)),
            &KinematicsConfig::default(),
        )
        .0;
        assert!(j.axis_world.dot(Vec3::NEG_Y) > 0.999 && (j.upper - 0.85 * 0.5).abs() < 1e-5, "{j:?}");
    }

    #[test]
    fn unnamed_panel_with_an_off_centre_handle_swings_and_other_parts_stay_rigid() {
        let body = cabinet_body();
        let door = Primitive::cuboid_at(Vec3::new(0.2, 0.26, 0.5), Vec3::new(0.4, 0.02, 0.9));
        // Handle near the door's +x edge: a door, front +y.
        check_handle(&body, &door, Vec3::new(0.36, 0.29, 0.5), Some((JointKind::Revolute, Vec3::Y)));
        // The same panel, handle on top (a lid-like top face): not decided here.
        let lid = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 1.01), Vec3::new(0.8, 0.5, 0.02));
        check_handle(&body, &lid, Vec3::new(0.0, 0.0, 1.04), None);
        // A thick block with an off-centre handle is no door.
        let block = Primitive::cuboid_at(Vec3::new(0.2, 0.1, 0.5), Vec3::new(0.4, 0.3, 0.3));
        check_handle(&body, &block, Vec3::new(0.36, 0.27, 0.5), None);
        // A panel standing 20 cm in front of the body is not at its front.
        let away = Primitive::cuboid_at(Vec3::new(0.0, 0.46, 0.8), Vec3::new(0.7, 0.004, 0.2));
        check_handle(&body, &away, Vec3::new(0.0, 0.48, 0.8), None);
        // A handle inside the part's box marks no face.
        check_handle(&body, &block, Vec3::new(0.2, 0.1, 0.5), None);
    }

    fn cabinet_body() -> Primitive {
        Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.5, 1.0))
    }

    #[test]
    fn drawer_slides_out_of_the_front_about_its_depth() {
        let drawer = Primitive::cuboid_at(Vec3::new(0.0, 0.26, 0.8), Vec3::new(0.6, 0.02, 0.2));
        let j = fit_joint(
            1,
            &cabinet_body(),
            2,
            &drawer,
            &spec(JointKind::Prismatic, Template::Drawer, None, None),
            &KinematicsConfig::default(),
        )
        .0;
        assert!(j.axis_world.dot(Vec3::Y) > 0.999, "{j:?}");
        assert!((j.upper - 0.85 * 0.5).abs() < 1e-5);
    }

    #[test]
    fn door_hinges_on_the_edge_away_from_its_handle_and_opens_outward() {
        let door = Primitive::cuboid_at(Vec3::new(0.2, 0.26, 0.5), Vec3::new(0.4, 0.02, 0.9));
        let handle = Vec3::new(0.36, 0.29, 0.5); // near the door's +x edge
        let j = fit_joint(
            1,
            &cabinet_body(),
            2,
            &door,
            &spec(JointKind::Revolute, Template::Hinge, Some(handle), None),
            &KinematicsConfig::default(),
        )
        .0;
        assert!(j.axis_world.dot(Vec3::Z).abs() > 0.999, "vertical hinge: {j:?}");
        assert!((j.origin_world.x - 0.0).abs() < 1e-5, "hinge on the -x edge: {j:?}");
        assert!((j.origin_world.y - 0.25).abs() < 1e-5, "at the back face: {j:?}");
        // Opening by a small angle moves the door centre outward (+y).
        let q = crate::math::Quat::from_axis_angle(j.axis_world, 0.3);
        let moved = j.origin_world + q * (door.center() - j.origin_world);
        assert!(moved.y > door.center().y);
    }

    /// How [`fit_joint`] chooses the edge of `door` (hinge template, on the cabinet body) and
    /// where its pivot lands; any edge opens outward, away from the body, for a positive angle.
    fn check_edge(door: &Primitive, handle: Option<Vec3>, pinned: Option<Vec3>, expected: (HingeEdge, Vec3)) {
        let lid = door.center().z > 1.0;
        let template = if lid { Template::LidHinge } else { Template::Hinge };
        let out = if lid { Vec3::Z } else { Vec3::Y };
        let spec = JointSpec { hinge_edge_world: pinned, ..spec(JointKind::Revolute, template, handle, Some(out)) };
        let (j, placement) = fit_joint(1, &cabinet_body(), 2, door, &spec, &KinematicsConfig::default());
        let edge = placement.map(|h| h.edge);
        assert!(
            edge == Some(expected.0) && (j.origin_world - expected.1).length() < 1e-5,
            "{door:?}, handle {handle:?}, pinned {pinned:?}: {edge:?} at {}, expected {expected:?}",
            j.origin_world
        );
        let q = crate::math::Quat::from_axis_angle(j.axis_world, 0.3);
        assert!((j.origin_world + q * (door.center() - j.origin_world)).dot(out) > door.center().dot(out), "{j:?}");
    }

    #[test]
    fn a_hinge_edge_comes_from_a_grip_or_the_offset_is_undetermined_on_a_centred_part_and_a_person_can_choose_it() {
        let door = |x: f32| Primitive::cuboid_at(Vec3::new(x, 0.26, 0.5), Vec3::new(0.4, 0.02, 0.9));
        let at = |x: f32| Vec3::new(x, 0.25, 0.5);
        // A handle decides.
        check_edge(&door(0.0), Some(Vec3::new(0.16, 0.29, 0.5)), None, (HingeEdge::AwayFromGrip, at(-0.2)));
        // Double doors, no handles: the outer edges.
        check_edge(&door(0.2), None, None, (HingeEdge::OuterEdge, at(0.4)));
        check_edge(&door(-0.2), None, None, (HingeEdge::OuterEdge, at(-0.4)));
        // Just off centre (beyond a tenth of its half-width) the offset counts; within, it does not.
        check_edge(&door(0.021), None, None, (HingeEdge::OuterEdge, at(0.221)));
        check_edge(&door(0.019), None, None, (HingeEdge::Undetermined, at(0.219)));
        check_edge(&door(0.0), None, None, (HingeEdge::Undetermined, at(0.2)));
        // A grip at the door's centre is no cue.
        check_edge(&door(0.0), Some(Vec3::new(0.01, 0.29, 0.5)), None, (HingeEdge::Undetermined, at(0.2)));
        // A person's choice wins, whatever the rules say, and keeps the door opening outward.
        check_edge(&door(0.0), None, Some(Vec3::NEG_X), (HingeEdge::Pinned, at(-0.2)));
        check_edge(&door(0.2), None, Some(Vec3::new(-1.0, 0.1, 0.0)), (HingeEdge::Pinned, at(0.0)));
        check_edge(&door(0.0), Some(Vec3::new(0.16, 0.29, 0.5)), Some(Vec3::X), (HingeEdge::Pinned, at(0.2)));
        // An edge along the other in-plane axis: a door hinged at its bottom like an oven's.
        check_edge(&door(0.0), None, Some(Vec3::NEG_Z), (HingeEdge::Pinned, Vec3::new(0.0, 0.25, 0.05)));
        // A lid: its long edge towards the body's centre; centred, undetermined; chosen, pinned.
        let lid = |y: f32| Primitive::cuboid_at(Vec3::new(0.0, y, 1.01), Vec3::new(0.8, 0.4, 0.02));
        check_edge(&lid(0.05), None, None, (HingeEdge::TowardsParentCentre, Vec3::new(0.0, -0.15, 1.0)));
        check_edge(&lid(0.0), None, None, (HingeEdge::Undetermined, Vec3::new(0.0, 0.2, 1.0)));
        check_edge(&lid(0.0), None, Some(Vec3::NEG_Y), (HingeEdge::Pinned, Vec3::new(0.0, -0.2, 1.0)));
    }

    #[test]
    fn an_inset_door_turns_about_a_pin_in_the_jamb_beside_it_at_mid_thickness() {
        // A door set into a frame's opening (its 4 cm thickness inside the frame's depth), the
        // frame's side 10 cm past the door's -x edge: the pin stands half way to it, capped at
        // the door's thickness, at the door's mid-thickness.
        let frame = Primitive::cuboid_at(Vec3::new(0.2, 0.0, 1.0), Vec3::new(1.0, 0.1, 2.0));
        let door = Primitive::cuboid_at(Vec3::new(0.2, 0.0, 1.0), Vec3::new(0.8, 0.04, 1.9));
        let handle = Vec3::new(0.5, 0.04, 1.0);
        let j =
            fit_joint(1, &frame, 2, &door, &spec(JointKind::Revolute, Template::Hinge, Some(handle), None), &KinematicsConfig::default()).0;
        assert!(j.axis_world.dot(Vec3::Z).abs() > 0.999, "{j:?}");
        assert!((j.origin_world.x - (-0.2 - 0.04)).abs() < 1e-5, "a door's thickness past the -x edge: {j:?}");
        assert!(j.origin_world.y.abs() < 1e-5, "at mid-thickness: {j:?}");
        // The same door laid over the frame's front face hinges on its back edge.
        let overlay = Primitive::cuboid_at(Vec3::new(0.2, 0.07, 1.0), Vec3::new(0.8, 0.04, 1.9));
        let handle = Vec3::new(0.5, 0.11, 1.0);
        let j = fit_joint(
            1,
            &frame,
            2,
            &overlay,
            &spec(JointKind::Revolute, Template::Hinge, Some(handle), None),
            &KinematicsConfig::default(),
        )
        .0;
        assert!((j.origin_world.x + 0.2).abs() < 1e-5 && (j.origin_world.y - 0.05).abs() < 1e-5, "{j:?}");
    }

    #[test]
    fn a_door_whose_box_stops_short_of_its_points_turns_at_their_back() {
        // Regression (a microwave whose door mesh carries its handle): the box fitted to the
        // door ran from the panel's front face to the handle's, and the hinge stood on that box's
        // back face, 4.4 cm in front of the pin; the panel's sides reach back to the body.
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.04, 0.19), Vec3::new(0.69, 0.44, 0.37));
        let front_box = Primitive::cuboid_at(Vec3::new(-0.11, -0.217, 0.2), Vec3::new(0.47, 0.071, 0.35));
        // The points end 8 cm behind the box's centre (at y = -0.137), 4.4 cm behind its back face.
        let span = PointSpan {
            min_local: Vec3::new(-0.235, -0.046, -0.175),
            max_local: Vec3::new(0.283, 0.08, 0.175),
            share_past_min: Vec3::ZERO,
            share_past_max: Vec3::new(0.0, 0.2, 0.0),
        };
        let handle = Vec3::new(0.13, -0.243, 0.19);
        let door_spec = |child_span| JointSpec { child_span, ..spec(JointKind::Revolute, Template::Hinge, Some(handle), None) };
        let cfg = KinematicsConfig::default();
        let (with_points, placement) = fit_joint(1, &body, 2, &front_box, &door_spec(Some(span)), &cfg);
        assert!((with_points.origin_world.y + 0.137).abs() < 1e-4, "at the points' back: {with_points:?}");
        assert!(placement.is_some_and(|h| (h.past_box_m - 0.0445).abs() < 1e-4), "{placement:?}");
        assert!((with_points.origin_world.x + 0.345).abs() < 1e-4, "on the edge away from the handle: {with_points:?}");
        let (box_only, placement) = fit_joint(1, &body, 2, &front_box, &door_spec(None), &cfg);
        assert!(placement.is_some_and(|h| h.past_box_m == 0.0), "{placement:?}");
        assert!((box_only.origin_world.y + 0.1815).abs() < 1e-4, "at the box's back: {box_only:?}");
        // Too few points past the box (noise, a neighbour's points at the border) leave it as it is.
        let inside = PointSpan { max_local: Vec3::new(0.283, 0.08, 0.175), share_past_max: Vec3::new(0.0, 0.05, 0.0), ..span };
        let j = fit_joint(1, &body, 2, &front_box, &door_spec(Some(inside)), &cfg).0;
        assert!((j.origin_world - box_only.origin_world).length() < 1e-6, "{j:?}");
    }

    #[test]
    fn oven_door_with_handle_on_top_hinges_at_the_bottom() {
        let door = Primitive::cuboid_at(Vec3::new(0.0, 0.26, 0.4), Vec3::new(0.7, 0.02, 0.5));
        let handle = Vec3::new(0.0, 0.29, 0.6);
        let j = fit_joint(
            1,
            &cabinet_body(),
            2,
            &door,
            &spec(JointKind::Revolute, Template::Hinge, Some(handle), None),
            &KinematicsConfig::default(),
        )
        .0;
        assert!(j.axis_world.dot(Vec3::X).abs() > 0.999, "{j:?}");
        assert!((j.origin_world.z - 0.15).abs() < 1e-5, "{j:?}");
    }

    #[test]
    fn a_knob_near_the_side_edge_turns_about_the_face_it_is_mounted_on() {
        // A knob on the front face at the body's +x edge, fitted 2 cm past it (a few points): by
        // position alone it lies farther out along +x than along the front normal (+y); the
        // contact face decides, and without one its own thin axis does (a dial).
        let body = cabinet_body();
        let knob = Primitive::cuboid_at(Vec3::new(0.42, 0.2575, 0.9), Vec3::new(0.04, 0.015, 0.04));
        let cfg = KinematicsConfig::default();
        let guessed = fit_joint(1, &body, 2, &knob, &spec(JointKind::Revolute, Template::Knob, None, None), &cfg).0;
        let mounted = fit_joint(1, &body, 2, &knob, &spec(JointKind::Revolute, Template::Knob, None, Some(Vec3::Y)), &cfg).0;
        assert!(guessed.axis_world.dot(Vec3::Y) > 0.99, "the dial's own axis, not the side: {guessed:?}");
        assert!(mounted.axis_world.dot(Vec3::Y) > 0.999, "{mounted:?}");
        // A vertical mount normal does not turn a door into a lid.
        let door = Primitive::cuboid_at(Vec3::new(0.2, 0.26, 0.5), Vec3::new(0.4, 0.02, 0.9));
        let j = fit_joint(
            1,
            &body,
            2,
            &door,
            &spec(JointKind::Revolute, Template::Hinge, Some(Vec3::new(0.36, 0.29, 0.5)), Some(Vec3::Z)),
            &cfg,
        )
        .0;
        assert!(j.axis_world.dot(Vec3::Z).abs() > 0.999, "{j:?}");
    }

    #[test]
    fn a_sliding_panel_slides_in_its_plane_towards_the_open_side() {
        let body = cabinet_body(); // front face at y = 0.25, x in [-0.4, 0.4]
        let panel = Primitive::cuboid_at(Vec3::new(-0.2, 0.26, 0.5), Vec3::new(0.4, 0.02, 0.9));
        let j = fit_joint(
            1,
            &body,
            2,
            &panel,
            &spec(JointKind::Prismatic, Template::SlidingPanel, None, Some(Vec3::Y)),
            &KinematicsConfig::default(),
        )
        .0;
        assert!(j.axis_world.dot(Vec3::X) > 0.999, "{j:?}");
        assert!((j.upper - 0.4).abs() < 1e-4, "{j:?}");
    }
}
