//! The scene-level contact graph (paper III-C, after Han et al.): the floor, object support
//! relations (floor → table → microwave) and proximity, and each object's pose refined by what
//! supports it (made upright, set down on the supporting surface).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::contact::surface_planes;
use crate::math::{Pose, Quat, UP, Vec2, Vec3};
use crate::model::{ObjectRelation, RelationKind};
use crate::polygon::{convex_hull, convex_intersection, polygon_area};
use crate::primitive::Primitive;
use crate::report::Warning;
use crate::scan::{ObjectId, PartId};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneConfig {
    /// How far an object's bottom may be from a supporting surface, metres.
    pub support_gap_m: f32,
    /// Minimum fraction of the object's footprint that must lie on the supporting surface.
    pub support_overlap: f32,
    /// Objects whose bounds come this close are proximal, metres.
    pub proximity_m: f32,
    /// Make supported objects upright when their up axis is within this angle, degrees.
    pub upright_max_deg: f32,
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self { support_gap_m: 0.06, support_overlap: 0.3, proximity_m: 0.15, upright_max_deg: 15.0 }
    }
}

/// One object as the scene stage sees it.
#[derive(Clone, Debug)]
pub struct SceneObject {
    pub id: ObjectId,
    pub root_part: PartId,
    pub parts: Vec<(PartId, Primitive)>,
}

/// The result of the scene stage.
#[derive(Clone, Debug, Default)]
pub struct SceneGraph {
    pub floor_z: f32,
    /// Object → supporting part (None = floor).
    pub support: BTreeMap<ObjectId, Option<PartId>>,
    pub relations: Vec<ObjectRelation>,
}

/// Floor height from background points: the densest 1 cm z-slab among the lowest points; falls
/// back to the lowest primitive bottom when there is no background.
#[must_use]
pub fn estimate_floor(background: &[Vec3], objects: &[SceneObject]) -> f32 {
    let lowest_part = objects.iter().flat_map(|o| o.parts.iter()).map(|(_, p)| p.aabb().0.z).fold(f32::INFINITY, f32::min);
    if background.len() < 50 {
        return if lowest_part.is_finite() { lowest_part } else { 0.0 };
    }
    // A stride subsample of at most 50k heights estimates a 1 cm slab as well as all of them.
    let step = (background.len() / 50_000).max(1);
    let mut zs: Vec<f32> = background.iter().step_by(step).map(|p| p.z).collect();
    zs.sort_by(f32::total_cmp);
    // The floor is the lowest dense horizontal slab: scan the lower quarter of heights.
    let lo = zs[zs.len() / 200];
    let bin = 0.01;
    let mut counts: BTreeMap<i64, usize> = BTreeMap::new();
    for z in &zs {
        if *z > lo + 0.5 {
            break;
        }
        *counts.entry(((z - lo) / bin).floor() as i64).or_default() += 1;
    }
    let best = counts.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0))).map_or(0, |(k, _)| *k);
    // Median of the points in the densest bin and its neighbours.
    let slab: Vec<f32> = zs
        .iter()
        .copied()
        .filter(|z| {
            let k = ((z - lo) / bin).floor() as i64;
            (k - best).abs() <= 1
        })
        .collect();
    slab.get(slab.len() / 2).copied().unwrap_or(lo)
}

/// The footprint (xy convex polygon) of an object's lowest faces and its bottom height.
fn footprint(obj: &SceneObject) -> (f32, Vec<Vec2>) {
    let bottom = obj.parts.iter().map(|(_, p)| p.aabb().0.z).fold(f32::INFINITY, f32::min);
    let mut pts = Vec::new();
    for (_, p) in &obj.parts {
        for c in p.box_corners() {
            if c.z <= bottom + 0.05 {
                pts.push(Vec2::new(c.x, c.y));
            }
        }
    }
    (bottom, convex_hull(pts))
}

/// Up-facing faces of a primitive: (height, xy outline).
fn top_faces(p: &Primitive) -> Vec<(f32, Vec<Vec2>)> {
    surface_planes(p)
        .into_iter()
        .filter(|pl| pl.normal.dot(UP) > 0.95)
        .map(|pl| (pl.center().z, pl.outline.iter().map(|u| Vec2::new(u.x, u.y)).collect()))
        .collect()
}

/// Finds support and proximity relations and refines object poses by their support: an object
/// nearly upright is made exactly upright (rotated about its root part's centre) and set down on
/// its support. `objects` are moved in place; objects are processed bottom-up so a microwave is
/// placed on the table after the table was placed on the floor.
pub fn build_scene(objects: &mut [SceneObject], floor_z: f32, cfg: &SceneConfig) -> (SceneGraph, Vec<Warning>) {
    let mut warnings = Vec::new();
    let mut graph = SceneGraph { floor_z, ..SceneGraph::default() };
    // Bottom-up order.
    let bottoms: Vec<f32> = objects.iter().map(|o| footprint(o).0).collect();
    let mut order: Vec<usize> = (0..objects.len()).collect();
    order.sort_by(|&a, &b| bottoms[a].total_cmp(&bottoms[b]).then(objects[a].id.cmp(&objects[b].id)));
    for &i in &order {
        make_upright(&mut objects[i], cfg);
        let (bottom, print) = footprint(&objects[i]);
        let print_area = polygon_area(&print).max(1e-9);
        // Candidate supports: the floor and every up-facing face of other objects below.
        let mut best: Option<(f32, Option<PartId>, Option<ObjectId>, f32)> = None; // (score, part, object, height)
        if (bottom - floor_z).abs() <= cfg.support_gap_m {
            best = Some((1.0 + 1.0 / (1.0 + (bottom - floor_z).abs()), None, None, floor_z));
        }
        for (j, other) in objects.iter().enumerate() {
            if j == i {
                continue;
            }
            for (pid, prim) in &other.parts {
                for (h, outline) in top_faces(prim) {
                    if (bottom - h).abs() > cfg.support_gap_m || h <= floor_z + cfg.support_gap_m {
                        continue;
                    }
                    let overlap = polygon_area(&convex_intersection(&print, &outline)) / print_area;
                    if overlap < cfg.support_overlap {
                        continue;
                    }
                    // Prefer real surfaces above the floor when both fit; then the closest and widest.
                    let score = 2.0 + overlap - (bottom - h).abs();
                    if best.is_none_or(|b| score > b.0) {
                        best = Some((score, Some(*pid), Some(other.id), h));
                    }
                }
            }
        }
        let id = objects[i].id;
        let (support_part, support_object, height) = if let Some((_, part, obj, h)) = best {
            (part, obj, h)
        } else {
            warnings.push(Warning::new(
                "scene",
                format!("object {id}"),
                format!("rests on nothing (bottom at {bottom:.3} m, floor at {floor_z:.3} m); placed on the floor"),
            ));
            (None, None, floor_z)
        };
        // Set the object down on its support.
        let dz = height - bottom;
        if dz.abs() <= cfg.support_gap_m {
            for (_, p) in &mut objects[i].parts {
                p.world_from_primitive.translation += Vec3::Z * dz;
            }
        }
        graph.support.insert(id, support_part);
        graph.relations.push(ObjectRelation { kind: RelationKind::Support, from: support_object, to: id });
    }
    // Proximity between objects not in a support relation.
    for a in 0..objects.len() {
        for b in (a + 1)..objects.len() {
            let (ia, ib) = (objects[a].id, objects[b].id);
            let supported = graph
                .relations
                .iter()
                .any(|r| r.kind == RelationKind::Support && ((r.from == Some(ia) && r.to == ib) || (r.from == Some(ib) && r.to == ia)));
            if supported {
                continue;
            }
            if bounds_gap(&objects[a], &objects[b]) <= cfg.proximity_m {
                let (from, to) = if ia < ib { (ia, ib) } else { (ib, ia) };
                graph.relations.push(ObjectRelation { kind: RelationKind::Proximity, from: Some(from), to });
            }
        }
    }
    graph.relations.sort();
    (graph, warnings)
}

fn bounds(obj: &SceneObject) -> (Vec3, Vec3) {
    obj.parts.iter().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), (_, p)| {
        let (a, b) = p.aabb();
        (lo.min(a), hi.max(b))
    })
}

fn bounds_gap(a: &SceneObject, b: &SceneObject) -> f32 {
    let (alo, ahi) = bounds(a);
    let (blo, bhi) = bounds(b);
    (blo - ahi).max(alo - bhi).max(Vec3::ZERO).length()
}

/// Rotates the whole object so its root part's most vertical axis is exactly vertical.
fn make_upright(obj: &mut SceneObject, cfg: &SceneConfig) {
    let Some(root) = obj.parts.iter().find(|(id, _)| *id == obj.root_part).map(|(_, p)| *p) else { return };
    let Some(up_axis) = root.axes_world().into_iter().max_by(|a, b| a.dot(UP).abs().total_cmp(&b.dot(UP).abs())) else { return };
    let up_axis = up_axis * up_axis.dot(UP).signum();
    if crate::math::line_angle_deg(up_axis, UP) > cfg.upright_max_deg {
        return;
    }
    let rot = Quat::from_rotation_arc(up_axis, UP);
    let pivot = root.center();
    for (_, p) in &mut obj.parts {
        let c = pivot + rot * (p.center() - pivot);
        p.world_from_primitive = Pose::from_parts(c, (rot * p.rotation()).normalize());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn microwave_stands_on_the_table_which_stands_on_the_floor() {
        let table = SceneObject {
            id: 1,
            root_part: 10,
            parts: vec![
                (10, Primitive::cuboid_at(Vec3::new(0.0, 0.0, 0.73), Vec3::new(1.2, 0.8, 0.04))),
                (11, Primitive::cuboid_at(Vec3::new(0.5, 0.3, 0.355), Vec3::new(0.05, 0.05, 0.71))),
            ],
        };
        // The microwave floats 2 cm above the table top and is slightly tilted.
        let tilt = Quat::from_rotation_x(0.03);
        let mw = SceneObject {
            id: 2,
            root_part: 20,
            parts: vec![(
                20,
                Primitive::new(
                    crate::primitive::PrimitiveKind::Cuboid,
                    Vec3::new(0.5, 0.35, 0.3),
                    Pose::from_parts(Vec3::new(0.1, 0.0, 0.92), tilt),
                ),
            )],
        };
        let chair = SceneObject {
            id: 3,
            root_part: 30,
            parts: vec![(30, Primitive::cuboid_at(Vec3::new(0.0, 0.55, 0.22), Vec3::new(0.4, 0.2, 0.44)))],
        };
        let mut objects = vec![mw, table, chair];
        let (graph, warnings) = build_scene(&mut objects, 0.0, &SceneConfig::default());
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(graph.support[&1], None);
        assert_eq!(graph.support[&2], Some(10));
        let mw = objects.iter().find(|o| o.id == 2).expect("microwave");
        let bottom = mw.parts[0].1.aabb().0.z;
        assert!((bottom - 0.75).abs() < 1e-4, "bottom {bottom}");
        assert!(mw.parts[0].1.rotation().angle_between(Quat::IDENTITY) < 1e-4);
        assert!(graph.relations.contains(&ObjectRelation { kind: RelationKind::Proximity, from: Some(1), to: 3 }));
    }

    #[test]
    fn floor_comes_from_the_dense_low_slab() {
        let mut bg: Vec<Vec3> = (0..1000).map(|i| Vec3::new(i as f32 * 0.01, 0.0, 0.002 * ((i % 5) as f32 - 2.0))).collect();
        bg.extend((0..300).map(|i| Vec3::new(0.0, 3.0, 0.01 * i as f32))); // a wall
        bg.push(Vec3::new(0.0, 0.0, -0.4)); // a stray point below
        let z = estimate_floor(&bg, &[]);
        assert!(z.abs() < 0.005, "{z}");
    }
}
