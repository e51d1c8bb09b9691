//! Which joint a part gets, and why: the label's class ([`super::Vocabulary`]) gives the allowed
//! types, a motion word or a geometric test chooses among them, and parts whose label names no
//! class are judged by geometry alone. Every decision keeps its evidence and a confidence, so the
//! editor can show them and sort the doubtful joints first.
//!
//! Geometric tests (all on the fitted primitives, in metres):
//! - **sliding panel**: a thin panel with another thin panel parallel to it (within 10°), in a
//!   second plane (offset along the normal between 0.4× their summed thickness and 3× that sum
//!   plus 3 cm) and overlapping it (projections overlap by ≥ 5 % of the smaller panel) slides: two
//!   tracks of a sliding wardrobe. Coplanar double doors hinge. Doors slide sideways, so the two
//!   panels must lie side by side across a horizontal in-plane axis: stacked doors meeting at an
//!   edge (a fridge's freezer door over its main door) hinge.
//! - **lift-off**: a round lid (cylinder or sphere) on a round body (cylinder or sphere), axes
//!   parallel within 18°, its centre within 30 % of the body's radius from the body's axis and
//!   beyond the body's centre along it, lifts along that axis (pots, kettles, bottles, cups).
//! - **swing handle**: a handle at least 0.8× as long as a round body is wide, its long axis
//!   across the body's axis (within 17° of perpendicular), centred over the axis (within 30 % of
//!   the radius) and at or above the body's centre, swings about its long axis through its ends.
//! - **toggle lever**: a switch whose reach beyond its mount's face (along the face normal it
//!   sticks out of) is at least its widest extent across that face is a lever and turns, about
//!   the in-face axis along its narrower side through the point where it leaves the face; a squat
//!   switch (a push switch, a slider lying inside its mount's bounds) keeps the class's default.
//! - **grip-mounted** (unknown labels, and labels of rigid parts): a grip at the part's front
//!   makes it a drawer or a door ([`super::joint_from_handle`]).
//! - **motion word** (unknown labels): a label that names a motion and no class (`slider`,
//!   `hinge_2`) moves so, fitted by the type's default template.
//! - **spinning disc** (unknown labels): a cylinder no taller than 0.7× its diameter whose axis
//!   is horizontal (within 17°) spins about that axis, as wheels do.
//!
//! Confidence is the product of a type confidence (how the type was chosen: the constants below),
//! a parent confidence (the margin of the chosen parent's contact weight over the next
//! candidate's, [`parent_confidence`]) and an axis confidence (a hinge's edge where nothing tells
//! it, [`hinge_edge_evidence`]; 1 elsewhere). `partscene bench` prints how often joints above 0.9 are
//! right.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::assign::{HingeEdge, joint_from_handle, outward_direction};
use super::joint::JointKind;
use super::vocabulary::{GeometryTest, LabelMatch, Role, Template, Vocabulary};
use crate::math::{UP, Vec3};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::PartId;

/// Type confidence when a person pinned the type.
pub const CONF_PINNED: f32 = 1.0;
/// A whole label word whose class allows one type, or a motion word the class allows.
pub const CONF_LABEL_ONLY_TYPE: f32 = 0.97;
/// A whole label word whose class allows several types, chosen by its geometric tests.
pub const CONF_LABEL_AND_GEOMETRY: f32 = 0.85;
/// Factor for a class found inside a compound word rather than as a whole word.
pub const CONF_COMPOUND_FACTOR: f32 = 0.85;
/// An unknown label, type from a grip mounted on the part.
pub const CONF_GRIP_GEOMETRY: f32 = 0.7;
/// A label naming a rigid part whose part carries a grip at its parent's front: geometry overrides.
pub const CONF_LABEL_OVERRIDDEN: f32 = 0.55;
/// An unknown label, a spinning disc.
pub const CONF_DISC_GEOMETRY: f32 = 0.55;
/// A label whose only reading is a motion word (`slider`): the type it names.
pub const CONF_MOTION_WORD_ONLY: f32 = 0.7;
/// An unknown label with no geometric evidence: kept rigid.
pub const CONF_UNKNOWN_RIGID: f32 = 0.6;
/// Parent confidence of a part touching nothing (hung off the nearest part).
pub const CONF_NO_CONTACT_PARENT: f32 = 0.4;
/// Axis confidence of a hinge whose side nothing tells (no grip, centred on its parent): one of
/// two edges, a coin flip.
pub const CONF_HINGE_EDGE_UNDETERMINED: f32 = 0.5;

/// Why a joint has its type, parent and axis, and how sure the tool is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointEvidence {
    /// The joint's child part.
    pub child: PartId,
    /// How the label was read (class, word, motion word) or that it names no class.
    pub label_rule: String,
    /// The geometric tests that were run and what they found.
    pub tests: Vec<String>,
    /// How the axis, pivot and limits are fitted.
    pub template: Template,
    /// Why this parent: its contact weight against the next candidate's.
    pub parent_rule: String,
    /// The second-best type, when another type was possible.
    pub runner_up: Option<JointKind>,
    /// Confidence in the type, in [0, 1].
    pub type_confidence: f32,
    /// Confidence in the parent, in [0, 1].
    pub parent_confidence: f32,
    /// How the axis line was placed where a rule chose between alternatives (a hinge's edge);
    /// empty where the template alone fixes it.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub axis_rule: String,
    /// Confidence in that choice, in [0, 1] (1 where nothing was chosen).
    #[serde(default = "one")]
    pub axis_confidence: f32,
    /// `type_confidence × parent_confidence × axis_confidence`.
    pub confidence: f32,
}

fn one() -> f32 {
    1.0
}

impl Default for JointEvidence {
    fn default() -> Self {
        Self {
            child: 0,
            label_rule: String::new(),
            tests: Vec::new(),
            template: Template::default(),
            parent_rule: String::new(),
            runner_up: None,
            type_confidence: 0.0,
            parent_confidence: 0.0,
            axis_rule: String::new(),
            axis_confidence: 1.0,
            confidence: 0.0,
        }
    }
}

/// Why a hinge stands on its edge, and the axis confidence ([`HingeEdge`]).
#[must_use]
pub fn hinge_edge_evidence(edge: HingeEdge) -> (String, f32) {
    match edge {
        HingeEdge::AwayFromGrip => ("hinge on the edge away from the grip mounted on the part".into(), 1.0),
        HingeEdge::OuterEdge => {
            ("no grip: hinge on the door's outer edge, away from its parent's centre (double doors hinge outside)".into(), 1.0)
        }
        HingeEdge::TowardsParentCentre => ("no grip off its centre: hinge on the lid's long edge towards its parent's centre".into(), 1.0),
        HingeEdge::Undetermined => (
            "no grip off its centre, and centred on its parent: nothing tells its two edges apart; one taken (runner-up: the other edge; \
             `Other edge` moves the hinge there)"
                .into(),
            CONF_HINGE_EDGE_UNDETERMINED,
        ),
        HingeEdge::Pinned => ("hinge on the edge a person chose".into(), CONF_PINNED),
    }
}

/// What [`decide`] needs to know about a part and its surroundings.
pub struct JointContext<'a> {
    pub label: &'a str,
    /// The object's category (`toilet`): some words name other classes in some objects.
    pub category: &'a str,
    pub parent: &'a Primitive,
    pub child: &'a Primitive,
    /// Centre of a grip mounted on the child, if any.
    pub grip: Option<Vec3>,
    /// The other parts of the object (not the parent, not the child) with their labels.
    pub others: Vec<(&'a Primitive, &'a str)>,
}

/// The chosen type, with the evidence (which holds the template).
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    pub kind: JointKind,
    /// A front normal found by a test, used as the mount normal.
    pub front: Option<Vec3>,
    /// Axis and a point on it, when a test fixes them (swing handles, lift-off lids).
    pub axis_line: Option<(Vec3, Vec3)>,
    pub evidence: JointEvidence,
}

/// Decides the joint type of the part in `ctx` (module docs).
#[must_use]
pub fn decide(vocab: &Vocabulary, ctx: &JointContext<'_>) -> Decision {
    match vocab.classify_in(ctx.label, ctx.category) {
        // A part named like the object's base that hangs off another part is not the base: its
        // name says nothing of how it moves (a window's second `body`, its sash).
        Some(m) if m.class.role == Role::Base => {
            let mut d = decide_by_geometry(vocab, ctx);
            d.evidence.label_rule = format!(
                "label `{}` names the object's base (class {}), but the part hangs off another: geometry alone",
                ctx.label, m.class.name
            );
            d
        }
        Some(m) => decide_by_class(vocab, &m, ctx),
        None => decide_by_geometry(vocab, ctx),
    }
}

fn label_rule(m: &LabelMatch<'_>, label: &str) -> String {
    let joints: Vec<&str> = m.class.joints.iter().map(|k| k.name()).collect();
    let how = if m.whole_token { "word" } else { "inside the compound" };
    let mut rule = format!("label `{label}`: class {} ({how} `{}`), allows {}", m.class.name, m.word, joints.join(", "));
    if let Some((word, kind)) = &m.motion {
        let used = if m.class.allows(*kind) { "used" } else { "not allowed, ignored" };
        let _ = write!(rule, "; motion word `{word}` → {} ({used})", kind.name());
    }
    rule
}

fn decide_by_class(vocab: &Vocabulary, m: &LabelMatch<'_>, ctx: &JointContext<'_>) -> Decision {
    let class = m.class;
    let compound = if m.whole_token { 1.0 } else { CONF_COMPOUND_FACTOR };
    let mut rule = label_rule(m, ctx.label);
    if vocab.classify(ctx.label).is_none_or(|plain| plain.class.name != m.class.name) {
        let _ = write!(rule, " (so in a {})", ctx.category);
    }
    let mut evidence = JointEvidence { label_rule: rule, ..JointEvidence::default() };
    let mut kind = class.default_joint();
    let mut type_conf = CONF_LABEL_ONLY_TYPE;
    let mut axis_line = None;
    if let Some(k) = m.allowed_motion() {
        kind = k;
    } else if class.joints.len() > 1 {
        type_conf = CONF_LABEL_AND_GEOMETRY;
        for test in &class.tests {
            let (found, note) = run_test(*test, vocab, ctx);
            evidence.tests.push(note);
            if let Some((k, line)) = found.filter(|(k, _)| class.allows(*k)) {
                kind = k;
                axis_line = line;
                break;
            }
        }
    }
    evidence.runner_up = class.joints.iter().copied().find(|k| *k != kind);
    evidence.type_confidence = type_conf * compound;
    // A part its label calls rigid that carries a grip at the parent's front is moved by it (a
    // drawer named by its position, `cabinet_top`): the geometry overrides the word, doubtfully.
    if kind == JointKind::Fixed
        && class.role != Role::Grip
        && m.allowed_motion().is_none()
        && let Some(d) = moved_by_grip(ctx, &mut evidence, CONF_LABEL_OVERRIDDEN, ", though the label names a rigid part")
    {
        return d;
    }
    evidence.template = class.template(kind);
    Decision { kind, front: None, axis_line, evidence }
}

/// A grip at the child's front (a drawer or a door, [`joint_from_handle`]): the decision, with
/// the test noted in `evidence` and `confidence` as its type confidence; `None` when there is no
/// grip or it is not at the parent's front.
fn moved_by_grip(ctx: &JointContext<'_>, evidence: &mut JointEvidence, confidence: f32, note: &str) -> Option<Decision> {
    let (kind, front) = joint_from_handle(ctx.parent, ctx.child, ctx.grip?)?;
    let (template, noun) = if kind == JointKind::Prismatic { (Template::Drawer, "drawer") } else { (Template::Hinge, "door") };
    evidence.tests.push(format!("grip-mounted: a grip at its front moves it as a {noun}{note}"));
    evidence.runner_up = Some(JointKind::Fixed);
    evidence.type_confidence = confidence;
    evidence.template = template;
    Some(Decision { kind, front: Some(front), axis_line: None, evidence: std::mem::take(evidence) })
}

fn decide_by_geometry(vocab: &Vocabulary, ctx: &JointContext<'_>) -> Decision {
    let mut evidence =
        JointEvidence { label_rule: format!("label `{}` names no class: geometry alone", ctx.label), ..JointEvidence::default() };
    if let Some((word, kind)) = vocab.motion_without_class(ctx.label) {
        evidence.label_rule = format!("label `{}` names no class; motion word `{word}` → {}", ctx.label, kind.name());
        evidence.type_confidence = CONF_MOTION_WORD_ONLY;
        evidence.runner_up = Some(JointKind::Fixed);
        evidence.template = Template::default_for(kind);
        return Decision { kind, front: None, axis_line: None, evidence };
    }
    if let Some(d) = moved_by_grip(ctx, &mut evidence, CONF_GRIP_GEOMETRY, "") {
        return d;
    }
    if ctx.grip.is_some() {
        evidence.tests.push("grip-mounted: a grip, but not at the parent's front".into());
    }
    if let Some(axis) = spinning_disc_axis(ctx.child) {
        evidence.tests.push("spinning disc: a round disc on a horizontal axis".into());
        evidence.type_confidence = CONF_DISC_GEOMETRY;
        evidence.runner_up = Some(JointKind::Fixed);
        evidence.template = Template::Spin;
        return Decision { kind: JointKind::Continuous, front: None, axis_line: Some((axis, ctx.child.center())), evidence };
    }
    evidence.tests.push("no grip, not a disc: rigid".into());
    evidence.type_confidence = CONF_UNKNOWN_RIGID;
    evidence.template = Template::Fixed;
    Decision { kind: JointKind::Fixed, front: None, axis_line: None, evidence }
}

/// Runs one geometric test: the type it supports (with an axis line when it fixes one) and a note.
type TestOutcome = (Option<(JointKind, Option<(Vec3, Vec3)>)>, String);

fn run_test(test: GeometryTest, vocab: &Vocabulary, ctx: &JointContext<'_>) -> TestOutcome {
    match test {
        GeometryTest::SlidingPanel => {
            let panels: Vec<&Primitive> = ctx.others.iter().filter(|(_, label)| !vocab.is_base(label)).map(|(p, _)| *p).collect();
            match overlapping_parallel_panel(ctx.child, &panels) {
                Some(offset) => (
                    Some((JointKind::Prismatic, None)),
                    format!("sliding panel: a parallel panel overlaps it {:.0} mm behind or in front: slides", offset * 1e3),
                ),
                None => (None, "sliding panel: no overlapping parallel panel in a second plane".into()),
            }
        }
        GeometryTest::LiftOff => match lift_axis(ctx.parent, ctx.child) {
            Some(axis) => (
                Some((JointKind::Prismatic, Some((axis, ctx.child.center())))),
                "lift-off: a round lid centred on a round body: lifts along the body's axis".into(),
            ),
            None => (None, "lift-off: not a round lid centred on a round body".into()),
        },
        GeometryTest::SwingHandle => match swing_line(ctx.parent, ctx.child) {
            Some(line) => {
                (Some((JointKind::Revolute, Some(line))), "swing handle: spans the round body across its axis: swings on its ends".into())
            }
            None => (None, "swing handle: does not span a round body".into()),
        },
        GeometryTest::ToggleLever => match toggle_line(ctx.parent, ctx.child) {
            Some((line, reach, width)) => (
                Some((JointKind::Revolute, Some(line))),
                format!("toggle lever: stands {:.0} mm out of its mount, {:.0} mm wide: turns", reach * 1e3, width * 1e3),
            ),
            None => (None, "toggle lever: no farther out of its mount than it is wide".into()),
        },
    }
}

/// When `switch` stands out of `mount`'s face at least as far as it is wide across that face
/// (module docs): its pivot line (axis, point), how far it stands out and its width, metres.
fn toggle_line(mount: &Primitive, switch: &Primitive) -> Option<((Vec3, Vec3), f32, f32)> {
    let out = outward_direction(mount, switch, None);
    let face = mount.center().dot(out) + 0.5 * mount.extent_along(out);
    let reach = switch.center().dot(out) + 0.5 * switch.extent_along(out) - face;
    let across: Vec<(f32, Vec3)> =
        mount.axes_world().into_iter().filter(|a| a.dot(out).abs() < 0.5).map(|a| (switch.extent_along(a), a)).collect();
    let width = across.iter().map(|(e, _)| *e).fold(0.0_f32, f32::max);
    if width <= 0.0 || reach < width {
        return None;
    }
    let (_, axis) = across.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0))?;
    let c = switch.center();
    let pivot = c - out * (c.dot(out) - face);
    Some(((axis, pivot), reach, width))
}

fn is_round(p: &Primitive) -> bool {
    matches!(p.kind, PrimitiveKind::Cylinder | PrimitiveKind::Sphere)
}

/// Index of a primitive's thinnest box axis and whether it is a thin panel (thickness at most a
/// quarter of its smaller in-plane side).
fn thin_axis(p: &Primitive) -> Option<usize> {
    let s = p.size;
    let k = (0..3).min_by(|&a, &b| s[a].total_cmp(&s[b]))?;
    let in_plane = (0..3).filter(|&a| a != k).map(|a| s[a]).fold(f32::INFINITY, f32::min);
    (s[k] <= 0.25 * in_plane).then_some(k)
}

/// The normal offset to another thin panel parallel to `panel` in a second plane that overlaps
/// it (module docs), if there is one.
fn overlapping_parallel_panel(panel: &Primitive, others: &[&Primitive]) -> Option<f32> {
    let k = thin_axis(panel)?;
    let axes = panel.axes_world();
    let n = axes[k];
    let c = panel.center();
    let in_plane: Vec<usize> = (0..3).filter(|&a| a != k).collect();
    let area = panel.size[in_plane[0]] * panel.size[in_plane[1]];
    others
        .iter()
        .filter_map(|o| {
            let ko = thin_axis(o)?;
            if o.axes_world()[ko].dot(n).abs() < 0.985 {
                return None;
            }
            let thick = panel.size[k] + o.size[ko];
            let offset = (o.center() - c).dot(n).abs();
            // Side by side, not stacked: the in-plane axis along which the centres lie farther
            // apart (the way one would slide over the other) is horizontal.
            let apart = in_plane
                .iter()
                .map(|&a| axes[a])
                .max_by(|a, b| (o.center() - c).dot(*a).abs().total_cmp(&(o.center() - c).dot(*b).abs()))?;
            if apart.dot(UP).abs() > 0.5 {
                return None;
            }
            if offset < 0.4 * thick || offset > 3.0 * thick + 0.03 {
                return None;
            }
            // Overlap of the projections on the panel's two in-plane axes.
            let overlap: f32 = in_plane
                .iter()
                .map(|&a| {
                    let d = (o.center() - c).dot(axes[a]).abs();
                    (0.5 * (panel.size[a] + o.extent_along(axes[a])) - d).max(0.0).min(panel.size[a])
                })
                .product();
            let other_area = o.size.element_product() / o.size[ko].max(1e-6);
            (overlap >= 0.05 * area.min(other_area)).then_some(offset)
        })
        .min_by(f32::total_cmp)
}

/// The outward axis of a round body when `lid` is a round lid centred on it (module docs).
fn lift_axis(body: &Primitive, lid: &Primitive) -> Option<Vec3> {
    if !is_round(body) || !is_round(lid) {
        return None;
    }
    let a = if body.kind == PrimitiveKind::Sphere { UP } else { body.axes_world()[2] };
    if lid.kind == PrimitiveKind::Cylinder && lid.axes_world()[2].dot(a).abs() < 0.95 {
        return None;
    }
    let d = lid.center() - body.center();
    let along = d.dot(a);
    let radius = 0.5 * body.size.x.max(body.size.y);
    let off_axis = (d - a * along).length();
    if off_axis > 0.3 * radius || along.abs() < 1e-4 {
        return None;
    }
    Some(a * along.signum())
}

/// The swing axis and a point on it when `handle` spans the round `body` across its axis.
fn swing_line(body: &Primitive, handle: &Primitive) -> Option<(Vec3, Vec3)> {
    if !is_round(body) {
        return None;
    }
    let a = if body.kind == PrimitiveKind::Sphere { UP } else { body.axes_world()[2] };
    let a = if a.dot(UP) < 0.0 { -a } else { a };
    let axes = handle.axes_world();
    let long = (0..3).max_by(|&x, &y| handle.size[x].total_cmp(&handle.size[y]))?;
    let l = axes[long];
    if l.dot(a).abs() > 0.3 {
        return None;
    }
    let diameter = body.size.x.max(body.size.y);
    if handle.size[long] < 0.8 * diameter {
        return None;
    }
    let d = handle.center() - body.center();
    let along = d.dot(a);
    if (d - a * along).length() > 0.3 * 0.5 * diameter || along < 0.0 {
        return None;
    }
    // The ends: the handle's lowest reach along the body's axis.
    let ends = handle.center() - a * (0.5 * handle.extent_along(a));
    let on_axis = body.center() + a * (ends - body.center()).dot(a);
    Some((l, on_axis))
}

/// The axis of a cylinder that is a disc on a horizontal axis (module docs).
fn spinning_disc_axis(p: &Primitive) -> Option<Vec3> {
    if p.kind != PrimitiveKind::Cylinder {
        return None;
    }
    let diameter = p.size.x.max(p.size.y);
    let axis = p.axes_world()[2];
    (p.size.z <= 0.7 * diameter && axis.dot(UP).abs() < 0.3).then_some(axis)
}

/// Contact weight from which a parent's contact counts as a full attachment (weights are in
/// [0, 1]); below it the part barely touches its parent, and the parent it is mounted on may be one
/// it does not touch in the scan (a latch whose door face was not seen).
pub const FULL_SUPPORT_WEIGHT: f32 = 0.3;

/// Parent confidence: 1 for a pinned parent, [`CONF_NO_CONTACT_PARENT`] for a part touching
/// nothing, else `0.5 + 0.5 × margin × support`, the margin being `(w − w₂) / w` of the chosen
/// parent's contact weight `w` over the best other candidate's `w₂` (1 when there is none), the
/// support `min(1, w / FULL_SUPPORT_WEIGHT)`: being the only part touched is little evidence
/// when the touch is slight.
#[must_use]
pub fn parent_confidence(chosen_weight: Option<f32>, runner_up_weight: Option<f32>, pinned: bool) -> f32 {
    if pinned {
        return CONF_PINNED;
    }
    let Some(w) = chosen_weight.filter(|w| *w > 0.0) else { return CONF_NO_CONTACT_PARENT };
    let margin = runner_up_weight.map_or(1.0, |w2| ((w - w2) / w).clamp(0.0, 1.0));
    let support = (w / FULL_SUPPORT_WEIGHT).min(1.0);
    0.5 + 0.5 * margin * support
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Pose, Quat};

    fn cylinder(center: Vec3, diameter: f32, height: f32, rotation: Quat) -> Primitive {
        Primitive::new(PrimitiveKind::Cylinder, Vec3::new(diameter, diameter, height), Pose::from_parts(center, rotation))
    }

    fn ctx<'a>(label: &'a str, parent: &'a Primitive, child: &'a Primitive, others: Vec<(&'a Primitive, &'a str)>) -> JointContext<'a> {
        JointContext { label, category: "object", parent, child, grip: None, others }
    }

    /// The type and template a part gets.
    fn check(c: &JointContext<'_>, expected: (JointKind, Template)) {
        let d = decide(&Vocabulary::builtin(), c);
        assert_eq!((d.kind, d.evidence.template), expected, "{:?}", d.evidence);
    }

    #[test]
    fn a_round_lid_on_a_round_pot_lifts_and_a_flat_lid_on_a_box_hinges() {
        let pot = cylinder(Vec3::new(0.0, 0.0, 0.1), 0.25, 0.2, Quat::IDENTITY);
        let lid = cylinder(Vec3::new(0.0, 0.0, 0.21), 0.26, 0.02, Quat::IDENTITY);
        check(&ctx("lid", &pot, &lid, vec![]), (JointKind::Prismatic, Template::LiftOff));
        let d = decide(&Vocabulary::builtin(), &ctx("lid", &pot, &lid, vec![]));
        assert!(d.axis_line.is_some_and(|(a, _)| a.dot(Vec3::Z) > 0.99), "{d:?}");
        let chest = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.2), Vec3::new(0.8, 0.4, 0.4));
        let flat = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.41), Vec3::new(0.8, 0.4, 0.02));
        check(&ctx("lid", &chest, &flat, vec![]), (JointKind::Revolute, Template::LidHinge));
        // GAPartNet's own word wins over geometry.
        check(&ctx("hinge_lid", &pot, &lid, vec![]), (JointKind::Revolute, Template::LidHinge));
    }

    #[test]
    fn overlapping_parallel_doors_slide_and_coplanar_double_doors_hinge() {
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.2, 0.6, 2.0));
        let front = Primitive::cuboid_at(Vec3::new(-0.28, 0.31, 1.0), Vec3::new(0.62, 0.02, 1.9));
        let back = Primitive::cuboid_at(Vec3::new(0.28, 0.28, 1.0), Vec3::new(0.62, 0.02, 1.9));
        check(&ctx("door", &body, &front, vec![(&back, "door")]), (JointKind::Prismatic, Template::SlidingPanel));
        let left = Primitive::cuboid_at(Vec3::new(-0.3, 0.31, 1.0), Vec3::new(0.6, 0.02, 1.9));
        let right = Primitive::cuboid_at(Vec3::new(0.3, 0.31, 1.0), Vec3::new(0.6, 0.02, 1.9));
        check(&ctx("door", &body, &left, vec![(&right, "door")]), (JointKind::Revolute, Template::Hinge));
        // The carcass's own back panel, far behind, is no second track.
        let back_panel = Primitive::cuboid_at(Vec3::new(0.0, -0.29, 1.0), Vec3::new(1.2, 0.02, 2.0));
        check(&ctx("door", &body, &left, vec![(&back_panel, "panel")]), (JointKind::Revolute, Template::Hinge));
    }

    #[test]
    fn a_fridge_door_stacked_under_its_freezer_door_hinges_though_their_edges_overlap() {
        // Demo seed 19: the main door 3 cm in front of the freezer door's plane, their edges
        // overlapping by 1.3 cm in height; they do not slide over each other.
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.9), Vec3::new(0.78, 0.7, 1.18));
        let main = Primitive::cuboid_at(Vec3::new(0.0, -0.36, 0.633), Vec3::new(0.76, 0.026, 1.144));
        let freezer = Primitive::cuboid_at(Vec3::new(0.0, -0.388, 1.307), Vec3::new(0.78, 0.029, 0.23));
        check(&ctx("door", &body, &main, vec![(&freezer, "door")]), (JointKind::Revolute, Template::Hinge));
        check(&ctx("door", &body, &freezer, vec![(&main, "door")]), (JointKind::Revolute, Template::Hinge));
    }

    #[test]
    fn a_bucket_handle_swings_and_a_wheel_spins_and_an_unknown_disc_spins_too() {
        let bucket = cylinder(Vec3::new(0.0, 0.0, 0.15), 0.3, 0.3, Quat::IDENTITY);
        let bail = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.35), Vec3::new(0.31, 0.01, 0.12));
        check(&ctx("handle", &bucket, &bail, vec![]), (JointKind::Revolute, Template::Swing));
        let cabinet = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.5, 1.0));
        let bar = Primitive::cuboid_at(Vec3::new(0.0, 0.27, 0.8), Vec3::new(0.3, 0.03, 0.02));
        check(&ctx("handle", &cabinet, &bar, vec![]), (JointKind::Fixed, Template::Fixed));
        let leg = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.3), Vec3::new(0.05, 0.05, 0.5));
        let wheel = cylinder(Vec3::new(0.0, 0.0, 0.04), 0.08, 0.03, Quat::from_rotation_x(std::f32::consts::FRAC_PI_2));
        check(&ctx("caster", &leg, &wheel, vec![]), (JointKind::Continuous, Template::Spin));
        check(&ctx("part_7", &leg, &wheel, vec![]), (JointKind::Continuous, Template::Spin));
        check(&ctx("part_7", &cabinet, &bar, vec![]), (JointKind::Fixed, Template::Fixed));
    }

    #[test]
    fn a_switch_standing_out_of_its_plate_turns_and_a_flush_or_inset_one_is_pressed() {
        // A wall plate facing -y; a toggle lever standing 7 cm out of it, 5 cm wide and 3 cm tall,
        // turns about the vertical (its narrower side) where it leaves the plate.
        let plate = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 1.2), Vec3::new(0.08, 0.01, 0.12));
        let lever = Primitive::cuboid_at(Vec3::new(0.0, -0.04, 1.2), Vec3::new(0.05, 0.07, 0.03));
        let d = decide(&Vocabulary::builtin(), &ctx("switch", &plate, &lever, vec![]));
        assert_eq!((d.kind, d.evidence.template), (JointKind::Revolute, Template::Rocker), "{:?}", d.evidence);
        let (axis, pivot) = d.axis_line.expect("a pivot line");
        assert!(axis.dot(Vec3::Z).abs() > 0.99, "{axis}");
        assert!((pivot.y + 0.005).abs() < 1e-4, "the pivot lies on the plate's face: {pivot}");
        // A push switch, wider than it stands out, keeps the class default: pressed.
        let push = Primitive::cuboid_at(Vec3::new(0.0, -0.015, 1.2), Vec3::new(0.05, 0.02, 0.03));
        check(&ctx("switch", &plate, &push, vec![]), (JointKind::Prismatic, Template::Button));
        // A slider lying inside its desk's bounds stands out of nothing.
        let desk = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.4), Vec3::new(1.0, 0.4, 0.8));
        let slider = Primitive::cuboid_at(Vec3::new(0.35, 0.1, 0.65), Vec3::new(0.15, 0.08, 0.07));
        check(&ctx("switch", &desk, &slider, vec![]), (JointKind::Prismatic, Template::Button));
    }

    #[test]
    fn a_toilet_seat_hinges_and_says_the_category_decided() {
        let bowl = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.2), Vec3::new(0.4, 0.5, 0.4));
        let seat = Primitive::cuboid_at(Vec3::new(0.0, -0.02, 0.41), Vec3::new(0.38, 0.45, 0.02));
        let in_toilet = JointContext { category: "Toilet", ..ctx("seat", &bowl, &seat, vec![]) };
        let d = decide(&Vocabulary::builtin(), &in_toilet);
        assert_eq!((d.kind, d.evidence.template), (JointKind::Revolute, Template::LidHinge), "{:?}", d.evidence);
        assert!(d.evidence.label_rule.contains("in a Toilet"), "{}", d.evidence.label_rule);
        check(&ctx("seat", &bowl, &seat, vec![]), (JointKind::Fixed, Template::Fixed));
    }

    #[test]
    fn a_label_that_names_only_a_motion_moves_so_and_says_it_is_unsure() {
        let body = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.5, 1.0));
        let part = Primitive::cuboid_at(Vec3::new(0.0, -0.26, 0.8), Vec3::new(0.7, 0.02, 0.3));
        check(&ctx("slider", &body, &part, vec![]), (JointKind::Prismatic, Template::Drawer));
        let d = decide(&Vocabulary::builtin(), &ctx("hinge_2", &body, &part, vec![]));
        assert_eq!((d.kind, d.evidence.template), (JointKind::Revolute, Template::Hinge));
        assert!(d.evidence.type_confidence < CONF_LABEL_AND_GEOMETRY, "{:?}", d.evidence);
        // A static part stays rigid, whatever its shape or what is mounted on it.
        let disc = Primitive::new(
            PrimitiveKind::Cylinder,
            Vec3::new(0.3, 0.3, 0.05),
            Pose::from_parts(Vec3::ZERO, Quat::from_rotation_x(std::f32::consts::FRAC_PI_2)),
        );
        check(&ctx("static_3", &body, &disc, vec![]), (JointKind::Fixed, Template::Fixed));
        let gripped = JointContext { grip: Some(Vec3::new(0.0, -0.3, 0.8)), ..ctx("static_3", &body, &part, vec![]) };
        check(&gripped, (JointKind::Fixed, Template::Fixed));
    }

    #[test]
    fn a_second_part_named_like_the_base_is_judged_by_its_geometry() {
        // A window's frame and its sash, both named `body`: the sash is not the base.
        let frame = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.8, 0.05, 1.0));
        let sash = Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.3), Vec3::new(0.7, 0.03, 0.45));
        let d = decide(&Vocabulary::builtin(), &ctx("body", &frame, &sash, vec![]));
        assert_eq!(d.kind, JointKind::Fixed, "{:?}", d.evidence);
        assert!(d.evidence.label_rule.contains("names the object's base"), "{}", d.evidence.label_rule);
        assert!(d.evidence.type_confidence < 0.9, "a guess from geometry alone is not confident");
    }

    #[test]
    fn parent_confidence_follows_the_margin_over_the_next_candidate() {
        assert!((parent_confidence(Some(1.0), None, false) - 1.0).abs() < 1e-6);
        assert!((parent_confidence(Some(1.0), Some(0.5), false) - 0.75).abs() < 1e-6);
        assert!((parent_confidence(None, None, false) - CONF_NO_CONTACT_PARENT).abs() < 1e-6);
        assert!((parent_confidence(Some(0.2), Some(0.9), true) - 1.0).abs() < 1e-6);
        // The only part touched, but barely: half-way to the full support.
        assert!((parent_confidence(Some(0.5 * FULL_SUPPORT_WEIGHT), None, false) - 0.75).abs() < 1e-6);
    }
}
