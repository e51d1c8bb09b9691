//! The object-level baseline the paper compares with (Han et al. 2022, "Scene reconstruction with
//! functional objects for robot autonomy"): every object is replaced by one whole-object template
//! fitted to its points, ignoring the part segmentation.
//!
//! Templates are small built-in assemblies of cuboids in the unit box `[-0.5, 0.5]³` (z up, +y the
//! back). For each object: all its points (all parts merged, labels ignored) → an upright oriented
//! box (z = world up, footprint = the minimum-area rectangle of the points' xy hull by rotating
//! calipers) → every template scaled into that box in each of the 4 yaw quarter turns → the lowest
//! fit score wins. The score is two-sided so that neither a solid box (which covers everything) nor a
//! sparse frame (which lies on few points) wins by default:
//! `mean_p min_prim dist(p, prim surface)` + trimmed mean over template surface samples of the
//! distance to the nearest point (the worst `1 − TRIM_KEEP` are dropped: scans miss hidden faces).
//! The object's category is not used (the fit alone decides). Deterministic: no randomness, fixed
//! template order, ties keep the first.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::geometry::sample_shapes;
use crate::math::{Pose, Quat, Vec2, Vec3};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::{ObjectId, Scan};

/// At most this many object points are scored (an even stride over the object's points).
pub const MAX_SCORED_POINTS: usize = 2000;
/// Surface samples per template for the template → points term.
pub const TEMPLATE_SAMPLES: usize = 800;
/// Fraction of template samples kept (the nearest ones) in the template → points term.
pub const TRIM_KEEP: f32 = 0.75;

/// One cuboid of a template, in the unit box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateBox {
    pub center_unit: Vec3,
    pub size_unit: Vec3,
}

const fn cuboid(cx: f32, cy: f32, cz: f32, sx: f32, sy: f32, sz: f32) -> TemplateBox {
    TemplateBox { center_unit: Vec3::new(cx, cy, cz), size_unit: Vec3::new(sx, sy, sz) }
}

/// A whole-object template: cuboids filling the unit box `[-0.5, 0.5]³`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Template {
    pub name: &'static str,
    pub boxes: &'static [TemplateBox],
}

/// The built-in template library (order matters only for ties).
pub const TEMPLATES: &[Template] = &[
    // Cabinet, fridge, microwave, dresser: one solid block.
    Template { name: "box", boxes: &[cuboid(0.0, 0.0, 0.0, 1.0, 1.0, 1.0)] },
    Template {
        name: "table",
        boxes: &[
            cuboid(0.0, 0.0, 0.47, 1.0, 1.0, 0.06),
            cuboid(-0.46, -0.46, -0.03, 0.08, 0.08, 0.94),
            cuboid(0.46, -0.46, -0.03, 0.08, 0.08, 0.94),
            cuboid(-0.46, 0.46, -0.03, 0.08, 0.08, 0.94),
            cuboid(0.46, 0.46, -0.03, 0.08, 0.08, 0.94),
        ],
    },
    Template {
        name: "chair",
        boxes: &[
            cuboid(0.0, 0.0, -0.06, 1.0, 1.0, 0.08),
            cuboid(0.0, 0.45, 0.24, 1.0, 0.1, 0.52),
            cuboid(-0.45, -0.45, -0.3, 0.1, 0.1, 0.4),
            cuboid(0.45, -0.45, -0.3, 0.1, 0.1, 0.4),
            cuboid(-0.45, 0.45, -0.3, 0.1, 0.1, 0.4),
            cuboid(0.45, 0.45, -0.3, 0.1, 0.1, 0.4),
        ],
    },
    Template {
        name: "bed",
        boxes: &[cuboid(0.0, 0.0, -0.3, 1.0, 1.0, 0.4), cuboid(0.0, 0.04, 0.0, 1.0, 0.92, 0.2), cuboid(0.0, -0.46, 0.0, 1.0, 0.08, 1.0)],
    },
    Template {
        name: "desk",
        boxes: &[
            cuboid(0.0, 0.0, 0.47, 1.0, 1.0, 0.06),
            cuboid(-0.47, 0.0, -0.03, 0.06, 1.0, 0.94),
            cuboid(0.47, 0.0, -0.03, 0.06, 1.0, 0.94),
        ],
    },
    Template {
        name: "shelf",
        boxes: &[
            cuboid(-0.48, 0.0, 0.0, 0.04, 1.0, 1.0),
            cuboid(0.48, 0.0, 0.0, 0.04, 1.0, 1.0),
            cuboid(0.0, 0.0, 0.48, 0.92, 1.0, 0.04),
            cuboid(0.0, 0.0, -0.48, 0.92, 1.0, 0.04),
            cuboid(0.0, 0.48, 0.0, 0.92, 0.04, 0.92),
            cuboid(0.0, -0.02, -0.16, 0.92, 0.96, 0.04),
            cuboid(0.0, -0.02, 0.16, 0.92, 0.96, 0.04),
        ],
    },
];

/// An upright oriented box: yaw about world z, full extents along its own x, y and world z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UprightBox {
    pub center_world: Vec3,
    pub size_m: Vec3,
    pub yaw_rad: f32,
}

/// The chosen template of one object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TemplateFit {
    pub template: String,
    /// Quarter turns (0–3) of the template about z inside the fitted box.
    pub quarter_turns: u8,
    /// The fit score (metres, lower is better).
    pub score_m: f32,
    /// The placed template.
    pub primitives: Vec<Primitive>,
}

/// The baseline reconstruction of a scan: one fitted template per object, sorted by object id.
/// Objects without points get an empty primitive list.
#[must_use]
pub fn object_level_baseline(scan: &Scan) -> Vec<(ObjectId, Vec<Primitive>)> {
    let mut by_object: std::collections::BTreeMap<ObjectId, Vec<Vec3>> = scan.objects.keys().map(|id| (*id, Vec::new())).collect();
    for part in &scan.parts {
        by_object.entry(part.object).or_default().extend_from_slice(&part.points);
    }
    let objects: Vec<(ObjectId, Vec<Vec3>)> = by_object.into_iter().collect();
    objects.par_iter().map(|(id, points)| (*id, fit_template(points).map(|f| f.primitives).unwrap_or_default())).collect()
}

/// Fits every template in every quarter turn to an object's points; the best fit, or `None` when
/// there are no finite points.
#[must_use]
pub fn fit_template(points: &[Vec3]) -> Option<TemplateFit> {
    let points: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let bounds = upright_box(&points)?;
    let stride = points.len().div_ceil(MAX_SCORED_POINTS).max(1);
    let scored: Vec<Vec3> = points.iter().step_by(stride).copied().collect();
    let scored_arrays: Vec<[f32; 3]> = scored.iter().map(Vec3::to_array).collect();
    let tree = kiddo::ImmutableKdTree::<f32, 3>::new_from_slice(&scored_arrays).ok()?;
    let mut best: Option<TemplateFit> = None;
    for template in TEMPLATES {
        for quarter_turns in 0..4_u8 {
            let primitives = place_template(template, &bounds, quarter_turns);
            let score_m = fit_score(&scored, &tree, &primitives);
            if best.as_ref().is_none_or(|b| score_m < b.score_m) {
                best = Some(TemplateFit { template: template.name.to_owned(), quarter_turns, score_m, primitives });
            }
        }
    }
    best
}

/// Two-sided fit score of placed template primitives against object points (see the module doc).
fn fit_score(points: &[Vec3], tree: &kiddo::ImmutableKdTree<f32, 3>, primitives: &[Primitive]) -> f32 {
    let to_template: f64 = points
        .iter()
        .map(|p| f64::from(primitives.iter().map(|prim| prim.surface_distance(*p)).fold(f32::INFINITY, f32::min)))
        .sum::<f64>()
        / points.len().max(1) as f64;
    let mut to_points: Vec<f32> = sample_shapes(primitives, TEMPLATE_SAMPLES)
        .iter()
        .map(|s| tree.query(&s.to_array()).nearest_one::<kiddo::SquaredEuclidean<f32>>().execute().distance.sqrt())
        .collect();
    to_points.sort_by(f32::total_cmp);
    let keep = ((to_points.len() as f32 * TRIM_KEEP).ceil() as usize).clamp(1, to_points.len().max(1));
    let kept = &to_points[..keep.min(to_points.len())];
    let trimmed = kept.iter().map(|d| f64::from(*d)).sum::<f64>() / kept.len().max(1) as f64;
    (to_template + trimmed) as f32
}

/// A template scaled into an upright box and turned by `quarter_turns` · 90° about z.
#[must_use]
pub fn place_template(template: &Template, bounds: &UprightBox, quarter_turns: u8) -> Vec<Primitive> {
    let turn = f32::from(quarter_turns % 4) * std::f32::consts::FRAC_PI_2;
    let world_from_template = Quat::from_rotation_z(bounds.yaw_rad + turn);
    // An odd turn puts the template's x along the box's y: scale it by the box's y extent.
    let scale = if quarter_turns.is_multiple_of(2) { bounds.size_m } else { Vec3::new(bounds.size_m.y, bounds.size_m.x, bounds.size_m.z) };
    template
        .boxes
        .iter()
        .map(|b| {
            let center = bounds.center_world + world_from_template * (b.center_unit * scale);
            Primitive::new(PrimitiveKind::Cuboid, b.size_unit * scale, Pose::from_parts(center, world_from_template))
        })
        .collect()
}

/// The upright box of a point set: the footprint is the minimum-area rectangle around the xy convex
/// hull (rotating calipers over the hull edges), the height spans the points' z range. `None` for an
/// empty set; a degenerate footprint falls back to the axis-aligned one.
#[must_use]
pub fn upright_box(points: &[Vec3]) -> Option<UprightBox> {
    let (first, _) = points.split_first()?;
    let (mut z_lo, mut z_hi) = (first.z, first.z);
    for p in points {
        z_lo = z_lo.min(p.z);
        z_hi = z_hi.max(p.z);
    }
    let hull = crate::polygon::convex_hull(points.iter().map(|p| p.truncate()).collect());
    // The minimum-area rectangle has a side on a hull edge (rotating calipers).
    let u = crate::polygon::min_area_rect_dir(&hull, 0.0);
    let v = u.perp();
    let mut lo = Vec2::splat(f32::INFINITY);
    let mut hi = Vec2::splat(f32::NEG_INFINITY);
    for p in &hull {
        let q = Vec2::new(p.dot(u), p.dot(v));
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let mid = 0.5 * (lo + hi);
    let center_xy = u * mid.x + u.perp() * mid.y;
    Some(UprightBox {
        center_world: Vec3::new(center_xy.x, center_xy.y, 0.5 * (z_lo + z_hi)),
        size_m: Vec3::new(hi.x - lo.x, hi.y - lo.y, z_hi - z_lo),
        yaw_rad: u.y.atan2(u.x),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::{ScanObject, ScanPart};

    /// Surface samples of cuboids (centre, size) in an object frame, placed at `center` with `yaw`.
    fn object_points(boxes: &[(Vec3, Vec3)], center: Vec3, yaw: f32, n: usize) -> Vec<Vec3> {
        let r = Quat::from_rotation_z(yaw);
        let prims: Vec<Primitive> =
            boxes.iter().map(|(c, s)| Primitive::new(PrimitiveKind::Cuboid, *s, Pose::from_parts(center + r * *c, r))).collect();
        sample_shapes(&prims, n)
    }

    fn table_boxes() -> Vec<(Vec3, Vec3)> {
        // 1.2 × 0.8 × 0.75 m, 4 cm top, 5 cm legs; origin at the centre of the bounding box.
        let mut boxes = vec![(Vec3::new(0.0, 0.0, 0.355), Vec3::new(1.2, 0.8, 0.04))];
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            boxes.push((Vec3::new(sx * 0.56, sy * 0.36, -0.02), Vec3::new(0.05, 0.05, 0.71)));
        }
        boxes
    }

    fn chair_boxes() -> Vec<(Vec3, Vec3)> {
        // 0.5 × 0.5 × 0.9 m: legs to 0.45 m, seat 0.45–0.5 m, back on -x side up to 0.9 m.
        let mut boxes =
            vec![(Vec3::new(0.0, 0.0, 0.025), Vec3::new(0.5, 0.5, 0.05)), (Vec3::new(-0.23, 0.0, 0.25), Vec3::new(0.04, 0.5, 0.4))];
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            boxes.push((Vec3::new(sx * 0.23, sy * 0.23, -0.225), Vec3::new(0.04, 0.04, 0.45)));
        }
        boxes
    }

    #[test]
    fn upright_box_recovers_a_rotated_box() {
        let points = object_points(&[(Vec3::ZERO, Vec3::new(0.6, 0.4, 0.9))], Vec3::new(1.0, 2.0, 0.45), 0.3, 3000);
        let b = upright_box(&points).expect("box");
        let (long, short) = (b.size_m.x.max(b.size_m.y), b.size_m.x.min(b.size_m.y));
        assert!((long - 0.6).abs() < 1e-3 && (short - 0.4).abs() < 1e-3, "{:?}", b.size_m);
        assert!((b.size_m.z - 0.9).abs() < 1e-3);
        assert!((b.center_world - Vec3::new(1.0, 2.0, 0.45)).length() < 1e-3, "{:?}", b.center_world);
        // The yaw is the box's up to quarter turns.
        let quarter = std::f32::consts::FRAC_PI_2;
        let off = (b.yaw_rad - 0.3).rem_euclid(quarter);
        assert!(off.min(quarter - off) < 1e-3, "{}", b.yaw_rad);
    }

    #[test]
    fn a_box_gets_the_box_template() {
        let points = object_points(&[(Vec3::ZERO, Vec3::new(0.6, 0.5, 0.9))], Vec3::new(-1.0, 0.5, 0.45), -0.3, 3000);
        let fit = fit_template(&points).expect("fit");
        assert_eq!(fit.template, "box", "score {}", fit.score_m);
        assert!(fit.score_m < 0.01, "{}", fit.score_m);
    }

    #[test]
    fn table_points_get_the_table_template() {
        let points = object_points(&table_boxes(), Vec3::new(2.0, 1.0, 0.375), 0.5, 4000);
        let fit = fit_template(&points).expect("fit");
        assert_eq!(fit.template, "table", "score {}", fit.score_m);
    }

    #[test]
    fn chair_points_get_the_chair_template_facing_the_right_way() {
        let yaw = 1.1;
        let center = Vec3::new(0.0, -1.0, 0.45);
        let points = object_points(&chair_boxes(), center, yaw, 4000);
        let fit = fit_template(&points).expect("fit");
        assert_eq!(fit.template, "chair", "score {}", fit.score_m);
        // The template's back (its tallest box) sits on the chair's back side (object -x).
        let back = fit.primitives.iter().max_by(|a, b| a.center().z.total_cmp(&b.center().z)).expect("back");
        let back_dir = Quat::from_rotation_z(yaw) * -Vec3::X;
        assert!((back.center() - center).truncate().normalize().dot(back_dir.truncate()) > 0.9);
    }

    #[test]
    fn baseline_replaces_each_object_of_a_scan() {
        let part = |id, object, points| ScanPart { id, object, label: "x".into(), points, normals: None };
        let table = object_points(&table_boxes(), Vec3::new(2.0, 1.0, 0.375), 0.5, 4000);
        let cabinet = object_points(&[(Vec3::ZERO, Vec3::new(0.6, 0.5, 0.9))], Vec3::new(-1.0, 0.5, 0.45), 0.0, 3000);
        let (top, legs) = table.split_at(1500);
        let scan = Scan {
            source: "test".into(),
            parts: vec![part(1, 4, top.to_vec()), part(2, 4, legs.to_vec()), part(3, 9, cabinet)],
            objects: [(4, "table"), (9, "cabinet"), (11, "lamp")]
                .into_iter()
                .map(|(id, c)| (id, ScanObject { id, category: c.into() }))
                .collect(),
            background: vec![],
        };
        let out = object_level_baseline(&scan);
        let ids: Vec<ObjectId> = out.iter().map(|(id, _)| *id).collect();
        assert_eq!(ids, vec![4, 9, 11]);
        assert_eq!(out[0].1.len(), 5); // table: top + 4 legs
        assert_eq!(out[1].1.len(), 1); // cabinet: one box
        assert!(out[2].1.is_empty()); // no points
        // The cabinet box matches the truth box.
        let truth = [Primitive::cuboid_at(Vec3::new(-1.0, 0.5, 0.45), Vec3::new(0.6, 0.5, 0.9))];
        let iou = super::super::voxel_iou(&out[1].1, &truth, 32).expect("iou");
        assert!(iou > 0.95, "{iou}");
    }

    #[test]
    fn fitting_is_deterministic() {
        let points = object_points(&table_boxes(), Vec3::new(0.0, 0.0, 0.375), 0.2, 3000);
        assert_eq!(fit_template(&points), fit_template(&points));
        assert_eq!(fit_template(&[]), None);
    }
}
