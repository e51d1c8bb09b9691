//! What the 3D view draws, as plain data (no GPU): instanced primitives, scan points and lines,
//! built from a scene, its scan and the current joint positions. Shared by the editor's view and
//! `partscene render`.

use std::collections::BTreeMap;

use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Mat4, Vec3};

use crate::kinematics::{Joint, JointKind};
use crate::math::{Pose, Quat};
use crate::model::SceneModel;
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::{PartId, Scan};

/// One instance of a unit mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SolidInstance {
    /// Columns of `world_from_unit` (pose × scale).
    pub world_from_unit: [[f32; 4]; 4],
    /// Columns of the normal matrix (rotation × inverse scale), padded.
    pub normal_from_unit: [[f32; 4]; 3],
    /// sRGB colour and opacity.
    pub color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PointInstance {
    pub position_world: [f32; 3],
    /// sRGBA, 8 bits each.
    pub color: [u8; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LineVertex {
    pub position_world: [f32; 3],
    pub color: [u8; 4],
}

/// Instances per unit mesh.
#[derive(Clone, Debug, Default)]
pub struct SolidBatches {
    pub cubes: Vec<SolidInstance>,
    pub cylinders: Vec<SolidInstance>,
    pub spheres: Vec<SolidInstance>,
}

impl SolidBatches {
    #[must_use]
    pub fn len(&self) -> usize {
        self.cubes.len() + self.cylinders.len() + self.spheres.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Adds `prim` (capsules as a cylinder and two spheres).
    pub fn push_primitive(&mut self, prim: &Primitive, color: [f32; 4]) {
        let pose = prim.world_from_primitive;
        match prim.kind {
            PrimitiveKind::Cuboid => self.cubes.push(instance(pose, prim.size, color)),
            PrimitiveKind::Cylinder => self.cylinders.push(instance(pose, prim.size, color)),
            PrimitiveKind::Sphere => self.spheres.push(instance(pose, prim.size, color)),
            PrimitiveKind::Capsule => {
                let d = prim.size.x;
                let shaft = (prim.size.z - d).max(0.0);
                self.cylinders.push(instance(pose, Vec3::new(d, d, shaft), color));
                for sign in [-0.5f32, 0.5] {
                    let cap = pose * Pose::from_translation(Vec3::new(0.0, 0.0, sign * shaft));
                    self.spheres.push(instance(cap, Vec3::splat(d), color));
                }
            }
        }
    }

    /// A rod (thin cylinder) from `a` to `b`.
    pub fn push_rod(&mut self, a: Vec3, b: Vec3, diameter_m: f32, color: [f32; 4]) {
        let along = b - a;
        let Some(dir) = along.try_normalize() else { return };
        let pose = Pose::from_parts(0.5 * (a + b), Quat::from_rotation_arc(Vec3::Z, dir));
        self.cylinders.push(instance(pose, Vec3::new(diameter_m, diameter_m, along.length()), color));
    }

    pub fn push_ball(&mut self, centre: Vec3, diameter_m: f32, color: [f32; 4]) {
        self.spheres.push(instance(Pose::from_translation(centre), Vec3::splat(diameter_m), color));
    }
}

fn instance(pose: Pose, size: Vec3, color: [f32; 4]) -> SolidInstance {
    let size = size.max(Vec3::splat(1e-5));
    let world_from_unit = Mat4::from_scale_rotation_translation(size, pose.rotation, pose.translation);
    let normal = Mat3::from_quat(pose.rotation) * Mat3::from_diagonal(size.recip());
    SolidInstance {
        world_from_unit: world_from_unit.to_cols_array_2d(),
        normal_from_unit: [normal.x_axis.extend(0.0).into(), normal.y_axis.extend(0.0).into(), normal.z_axis.extend(0.0).into()],
        color,
    }
}

/// How scan points are coloured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PointColors {
    /// Each part its own colour (the segmentation).
    #[default]
    ByPart,
    /// Distance to the part's fitted primitive: blue 0 → red at [`FIT_ERROR_FULL_SCALE_M`] or more.
    ByFitError,
}

/// The fit-error colour scale's top, metres.
pub const FIT_ERROR_FULL_SCALE_M: f32 = 0.03;

/// What to draw.
// Independent display toggles, as in any viewer's View menu; an enum set would only obscure them.
#[allow(clippy::struct_excessive_bools)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawOptions {
    pub show_points: bool,
    pub show_primitives: bool,
    pub show_joints: bool,
    pub show_contacts: bool,
    pub show_floor: bool,
    pub point_colors: PointColors,
    /// Opacity of the primitives (below 1 they are drawn blended, so points show through).
    pub primitive_alpha: f32,
    /// At most this many scan points are drawn (evenly thinned).
    pub max_points: usize,
}

impl Default for DrawOptions {
    fn default() -> Self {
        Self {
            show_points: true,
            show_primitives: true,
            show_joints: true,
            show_contacts: false,
            show_floor: true,
            point_colors: PointColors::ByPart,
            primitive_alpha: 1.0,
            max_points: 400_000,
        }
    }
}

/// The scene to draw and its state.
pub struct SceneView<'a> {
    pub model: &'a SceneModel,
    pub scan: Option<&'a Scan>,
    /// Motion of each moved part (from [`crate::kinematics::part_motions`]); absent = at rest.
    pub motions: &'a BTreeMap<PartId, Pose>,
    pub selected: Option<PartId>,
    pub hovered: Option<PartId>,
}

/// Everything the GPU draws for one view.
#[derive(Clone, Debug, Default)]
pub struct DrawData {
    pub opaque: SolidBatches,
    /// Blended primitives, drawn after everything opaque without writing depth.
    pub translucent: SolidBatches,
    pub points: Vec<PointInstance>,
    /// Line list (pairs of vertices).
    pub lines: Vec<LineVertex>,
    /// Bounds of what is drawn (for framing), or `None` when empty.
    pub bounds: Option<(Vec3, Vec3)>,
}

pub use crate::model::part_color;

/// Blue → cyan → green → yellow → red for `t` in 0..1.
#[must_use]
pub fn error_color(t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    let stops = [[0.15, 0.3, 0.95], [0.1, 0.8, 0.9], [0.2, 0.85, 0.3], [0.95, 0.85, 0.15], [0.9, 0.15, 0.1]];
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f32;
    let (a, b) = (stops[i], stops[i + 1]);
    [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f]
}

fn to_u8(c: [f32; 3], alpha: f32) -> [u8; 4] {
    let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    [q(c[0]), q(c[1]), q(c[2]), q(alpha)]
}

const SELECTED: [f32; 3] = [1.0, 0.55, 0.1];
const REVOLUTE: [f32; 3] = crate::model::joint_kind_color(JointKind::Revolute);
const PRISMATIC: [f32; 3] = crate::model::joint_kind_color(JointKind::Prismatic);

/// The primitive of a part where its joints put it.
#[must_use]
pub fn posed_primitive(prim: &Primitive, motion: Option<&Pose>) -> Primitive {
    match motion {
        Some(m) => Primitive { world_from_primitive: *m * prim.world_from_primitive, ..*prim },
        None => *prim,
    }
}

/// Builds the draw data of a view.
#[must_use]
pub fn scene_draw_data(view: &SceneView<'_>, options: &DrawOptions) -> DrawData {
    let mut out = scene_geometry(view, options);
    out.points = scene_points(view, options);
    out
}

/// The scan's points as drawn (by part, the selected part highlighted, or by fit error), moved
/// with their parts. Hover does not change them: the editor caches them apart from the rest.
#[must_use]
pub fn scene_points(view: &SceneView<'_>, options: &DrawOptions) -> Vec<PointInstance> {
    match view.scan {
        Some(scan) if options.show_points => points(scan, view, options),
        _ => Vec::new(),
    }
}

/// Everything but the scan points: primitives, joints, contact edges, floor, bounds.
#[must_use]
pub fn scene_geometry(view: &SceneView<'_>, options: &DrawOptions) -> DrawData {
    let mut out = DrawData::default();
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let model = view.model;
    let posed: BTreeMap<PartId, Primitive> =
        model.parts.iter().map(|p| (p.id, posed_primitive(&p.primitive, view.motions.get(&p.id)))).collect();
    for (id, prim) in &posed {
        let (a, b) = prim.aabb();
        lo = lo.min(a);
        hi = hi.max(b);
        if !options.show_primitives {
            continue;
        }
        let base = part_color(*id);
        let color = if view.selected == Some(*id) {
            SELECTED
        } else if view.hovered == Some(*id) {
            base.map(|c| (c * 1.2 + 0.1).min(1.0))
        } else {
            base
        };
        let alpha = if view.selected == Some(*id) { options.primitive_alpha.max(0.6) } else { options.primitive_alpha };
        let batch = if alpha < 0.999 { &mut out.translucent } else { &mut out.opaque };
        batch.push_primitive(prim, [color[0], color[1], color[2], alpha]);
    }
    if options.show_joints {
        for j in &model.joints {
            push_joint(&mut out, j, &posed, view);
        }
    }
    if options.show_contacts {
        for e in &model.contact_edges {
            let (Some(a), Some(b)) = (posed.get(&e.parent), posed.get(&e.child)) else { continue };
            let color = if e.in_tree { to_u8([1.0, 0.85, 0.2], 1.0) } else { to_u8([0.6, 0.6, 0.6], 1.0) };
            out.lines.push(LineVertex { position_world: a.center().into(), color });
            out.lines.push(LineVertex { position_world: b.center().into(), color });
        }
    }
    if lo.is_finite() && hi.is_finite() {
        if options.show_floor {
            push_floor(&mut out, lo, hi, model.floor_z);
        }
        out.bounds = Some((lo.min(Vec3::new(lo.x, lo.y, model.floor_z)), hi));
    }
    out
}

fn points(scan: &Scan, view: &SceneView<'_>, options: &DrawOptions) -> Vec<PointInstance> {
    let mut out = Vec::new();
    let total = scan.point_count().max(1);
    let stride = total.div_ceil(options.max_points.max(1)).max(1);
    for part in &scan.parts {
        let motion = view.motions.get(&part.id);
        let prim = view.model.part(part.id).map(|p| p.primitive);
        let base = if view.selected == Some(part.id) { SELECTED } else { part_color(part.id) };
        let dim = |c: [f32; 3]| c.map(|x| x * 0.6);
        for p in part.points.iter().step_by(stride) {
            let color = match (options.point_colors, prim) {
                (PointColors::ByFitError, Some(prim)) => error_color(prim.surface_distance(*p) / FIT_ERROR_FULL_SCALE_M),
                (PointColors::ByFitError, None) => [0.5, 0.5, 0.5],
                (PointColors::ByPart, _) => dim(base),
            };
            let world = motion.map_or(*p, |m| m.transform_point(*p));
            out.push(PointInstance { position_world: world.into(), color: to_u8(color, 1.0) });
        }
    }
    out
}

/// Axis rods, pivot balls and the range of motion.
fn push_joint(out: &mut DrawData, j: &Joint, posed: &BTreeMap<PartId, Primitive>, view: &SceneView<'_>) {
    if j.kind == JointKind::Fixed {
        return;
    }
    let Some(child) = posed.get(&j.child) else { return };
    // The joint frame moves with the parent's motion.
    let parent_motion = view.motions.get(&j.parent).copied().unwrap_or(Pose::IDENTITY);
    let axis = parent_motion.rotation * j.axis_world.normalize_or(Vec3::Z);
    let origin = parent_motion.transform_point(j.origin_world);
    let extent = child.size.max_element().clamp(0.05, 2.0);
    let emphasis = if view.selected == Some(j.child) { 1.8 } else { 1.0 };
    let rod = (0.012 * extent).clamp(0.004, 0.015) * emphasis;
    match j.kind {
        JointKind::Revolute | JointKind::Continuous => {
            // The hinge line through the pivot, as long as the part along it, and a ball at the pivot.
            let centre_on_axis = origin + axis * (child.center() - origin).dot(axis);
            let half = 0.5 * child.extent_along(axis).max(0.05) + 0.03;
            let c = [REVOLUTE[0], REVOLUTE[1], REVOLUTE[2], 1.0];
            out.opaque.push_rod(centre_on_axis - axis * half, centre_on_axis + axis * half, rod, c);
            out.opaque.push_ball(centre_on_axis, rod * 2.5, c);
            // The swing: an arc of the child's far point from lower to upper.
            let rest_child = view.model.part(j.child).map_or(child.center(), |p| p.primitive.center());
            let far = parent_motion.transform_point(rest_child);
            let radial = far - centre_on_axis - axis * (far - centre_on_axis).dot(axis);
            let steps = 24;
            let color = to_u8(REVOLUTE, 1.0);
            let point_at = |t: f32| centre_on_axis + Quat::from_axis_angle(axis, t) * radial;
            for k in 0..steps {
                let (a, b) = (k as f32 / steps as f32, (k + 1) as f32 / steps as f32);
                let (qa, qb) = (j.lower + (j.upper - j.lower) * a, j.lower + (j.upper - j.lower) * b);
                out.lines.push(LineVertex { position_world: point_at(qa).into(), color });
                out.lines.push(LineVertex { position_world: point_at(qb).into(), color });
            }
            for q in [j.lower, j.upper] {
                out.lines.push(LineVertex { position_world: centre_on_axis.into(), color });
                out.lines.push(LineVertex { position_world: point_at(q).into(), color });
            }
        }
        JointKind::Prismatic => {
            // An arrow along the axis from the child's rest centre over the travel, ticks at the limits.
            let rest_child = view.model.part(j.child).map_or(child.center(), |p| p.primitive.center());
            let start = parent_motion.transform_point(rest_child);
            let travel = (j.upper - j.lower).abs().max(0.05);
            let c = [PRISMATIC[0], PRISMATIC[1], PRISMATIC[2], 1.0];
            let (a, b) = (start + axis * j.lower, start + axis * (j.lower + travel));
            out.opaque.push_rod(a, b, rod, c);
            out.opaque.push_ball(b, rod * 3.0, c);
            let color = to_u8(PRISMATIC, 1.0);
            let side = axis.any_orthonormal_vector() * 0.04;
            for q in [j.lower, j.upper] {
                let p = start + axis * q;
                out.lines.push(LineVertex { position_world: (p - side).into(), color });
                out.lines.push(LineVertex { position_world: (p + side).into(), color });
            }
        }
        JointKind::Fixed => {}
    }
}

/// A 0.5 m grid on the floor under the scene.
fn push_floor(out: &mut DrawData, lo: Vec3, hi: Vec3, floor_z: f32) {
    // Counted lines (at most 400 each way): a float loop never ends where x + step == x.
    let step = 0.5f32;
    let (x0, x1) = ((lo.x / step).floor() * step - step, (hi.x / step).ceil() * step + step);
    let (y0, y1) = ((lo.y / step).floor() * step - step, (hi.y / step).ceil() * step + step);
    let color = [110, 110, 118, 255];
    let nx = (((x1 - x0) / step).round() as usize).min(400);
    let ny = (((y1 - y0) / step).round() as usize).min(400);
    for i in 0..=nx {
        let x = x0 + i as f32 * step;
        out.lines.push(LineVertex { position_world: [x, y0, floor_z], color });
        out.lines.push(LineVertex { position_world: [x, y1, floor_z], color });
    }
    for i in 0..=ny {
        let y = y0 + i as f32 * step;
        out.lines.push(LineVertex { position_world: [x0, y, floor_z], color });
        out.lines.push(LineVertex { position_world: [x1, y, floor_z], color });
    }
}

/// The part hit first by a world ray, with the distance along it, under the given motions.
#[must_use]
pub fn pick_part(model: &SceneModel, motions: &BTreeMap<PartId, Pose>, origin: Vec3, dir: Vec3) -> Option<(PartId, f32)> {
    model
        .parts
        .iter()
        .filter_map(|p| {
            let prim = posed_primitive(&p.primitive, motions.get(&p.id));
            prim.ray_cast(origin, dir, 1e4).map(|(t, _)| (p.id, t))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::PartModel;

    fn model() -> SceneModel {
        let part = |id, center: Vec3, size: Vec3| PartModel {
            id,
            object: 1,
            label: "x".into(),
            primitive: Primitive::cuboid_at(center, size),
            fit_error: 0.0,
            point_count: 0,
            points_span: None,
        };
        SceneModel {
            parts: vec![part(1, Vec3::new(0.0, 0.0, 0.5), Vec3::ONE), part(2, Vec3::new(0.0, -0.51, 0.5), Vec3::new(0.8, 0.02, 0.8))],
            joints: vec![Joint {
                parent: 1,
                child: 2,
                kind: JointKind::Revolute,
                axis_world: Vec3::Z,
                origin_world: Vec3::new(0.4, -0.52, 0.0),
                lower: 0.0,
                upper: 1.5,
            }],
            ..SceneModel::default()
        }
    }

    #[test]
    fn picking_finds_the_front_part_and_follows_the_door_when_it_opens() {
        let m = model();
        let at_rest = BTreeMap::new();
        assert_eq!(pick_part(&m, &at_rest, Vec3::new(0.0, -3.0, 0.5), Vec3::Y).map(|h| h.0), Some(2));
        // Open the door 90°: it swings out of the way and the ray hits the cabinet.
        let open = crate::kinematics::part_motions(&m.joints, &BTreeMap::from([(2, std::f32::consts::FRAC_PI_2)]));
        assert_eq!(pick_part(&m, &open, Vec3::new(0.0, -3.0, 0.5), Vec3::Y).map(|h| h.0), Some(1));
        assert_eq!(pick_part(&m, &at_rest, Vec3::new(5.0, -3.0, 0.5), Vec3::Y), None);
    }

    #[test]
    fn draw_data_has_every_primitive_and_the_joint_and_bounds_the_scene() {
        let m = model();
        let motions = BTreeMap::new();
        let view = SceneView { model: &m, scan: None, motions: &motions, selected: Some(2), hovered: None };
        let d = scene_draw_data(&view, &DrawOptions::default());
        assert_eq!(d.opaque.cubes.len(), 2);
        assert_eq!(d.opaque.cylinders.len(), 1, "one hinge rod");
        assert!(!d.lines.is_empty() && d.lines.len().is_multiple_of(2));
        let (lo, hi) = d.bounds.unwrap();
        assert!(lo.z <= 0.0 && hi.z >= 1.0);
        let hidden = scene_draw_data(
            &view,
            &DrawOptions { show_primitives: false, show_joints: false, show_floor: false, ..DrawOptions::default() },
        );
        assert!(hidden.opaque.is_empty() && hidden.lines.is_empty());
        let glass = scene_draw_data(&view, &DrawOptions { primitive_alpha: 0.3, ..DrawOptions::default() });
        assert_eq!(glass.translucent.cubes.len(), 2);
    }
}
