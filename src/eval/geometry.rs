//! Geometric similarity (paper Table I): Chamfer distance between unit-box-normalised objects and
//! voxel `IoU` on a 32³ grid.
//!
//! Both metrics normalise by the *truth* object's axis-aligned bounding box: centre at the origin,
//! divided by its largest extent, so a prediction is scored in the truth's unit frame and a
//! prediction that is too large or misplaced is penalised rather than rescaled away.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::mesh::{self, WorldLattice};
use crate::math::Vec3;
use crate::primitive::Primitive;
use crate::scan::ObjectId;
use crate::truth::{GroundTruth, TruthMesh, TruthObject};

/// Surface samples per object (split over its primitives by area) for the Chamfer distance.
/// Point-to-sample distances put a floor under the Chamfer of two different samplings of the same
/// surface (up to about 0.015 in unit-box units at this count: a box shifted by 0.1 of its size scores
/// 0.078 instead of the continuous 0.067); more samples lower it at a cost of time.
pub const CHAMFER_SAMPLES: usize = 10_000;
/// Voxels along each side of the truth object's normalised bounding cube.
pub const VOXEL_RESOLUTION: usize = 32;
/// Margin added on each side of the truth object's normalised bounding cube, as a fraction of its
/// largest extent (the cube's side is `1 + 2 · VOXEL_MARGIN` in unit-box coordinates).
pub const VOXEL_MARGIN: f32 = 0.03;
/// The voxel lattice keeps the truth cube's pitch and extends over a prediction that reaches beyond
/// the cube, up to this half-width in unit-box coordinates; anything farther out is not counted.
pub const VOXEL_LATTICE_HALF_WIDTH: f32 = 2.0;

/// Geometric scores of one truth object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeometryScore {
    pub object: ObjectId,
    pub category: String,
    /// Chamfer distance in unit-box coordinates (lower is better); `None` when the prediction or
    /// the truth has no surface.
    pub chamfer: Option<f32>,
    /// Voxel `IoU` in [0, 1] (higher is better); `None` when the truth occupies no voxel.
    pub iou: Option<f32>,
}

/// Mean Chamfer and `IoU` over a set of geometry scores (objects without a value are skipped).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeometrySummary {
    pub objects: usize,
    pub mean_chamfer: Option<f32>,
    pub mean_iou: Option<f32>,
}

impl GeometrySummary {
    /// Summarises per-object scores.
    #[must_use]
    pub fn of(scores: &[GeometryScore]) -> Self {
        Self {
            objects: scores.len(),
            mean_chamfer: mean(scores.iter().filter_map(|s| s.chamfer)),
            mean_iou: mean(scores.iter().filter_map(|s| s.iou)),
        }
    }
}

/// Scores predicted objects against the truth, one row per truth object (in truth order).
///
/// `objects` holds each predicted object's primitives; several entries with the same id are merged,
/// a truth object with no entry is scored against an empty prediction (Chamfer `None`, `IoU` 0).
/// Usable for the part-level reconstruction and for the object-level baseline alike.
#[must_use]
pub fn evaluate_geometry(objects: &[(ObjectId, Vec<Primitive>)], truth: &GroundTruth) -> Vec<GeometryScore> {
    truth
        .objects
        .par_iter()
        .map(|t| {
            let predicted: Vec<Primitive> =
                objects.iter().filter(|(id, _)| *id == t.id).flat_map(|(_, prims)| prims.iter().copied()).collect();
            let (chamfer, iou) = object_geometry(&predicted, t);
            GeometryScore { object: t.id, category: t.category.clone(), chamfer, iou }
        })
        .collect()
}

/// Solid geometry to compare: primitives and closed or open triangle meshes (world frame).
#[derive(Clone, Debug, Default)]
pub struct Solids<'a> {
    pub primitives: Vec<Primitive>,
    /// Closed meshes count by their inside, open ones by the voxels their surface passes through.
    pub meshes: Vec<&'a TruthMesh>,
}

impl<'a> Solids<'a> {
    /// Primitives only.
    #[must_use]
    pub fn of_primitives(primitives: &[Primitive]) -> Self {
        Self { primitives: primitives.to_vec(), meshes: Vec::new() }
    }

    /// Every primitive and mesh of every part of a truth object.
    #[must_use]
    pub fn of_truth(object: &'a TruthObject) -> Self {
        Self {
            primitives: object.parts.iter().flat_map(|p| p.shapes.iter().copied()).collect(),
            meshes: object.parts.iter().flat_map(|p| p.meshes.iter()).collect(),
        }
    }

    fn aabb(&self) -> Option<(Vec3, Vec3)> {
        crate::truth::bounds(&self.primitives, self.meshes.iter().copied())
    }

    /// About `n_total` surface samples split by surface area over primitives and meshes
    /// (deterministic).
    #[must_use]
    pub fn sample(&self, n_total: usize) -> Vec<Vec3> {
        let prim_areas: Vec<f32> = self.primitives.iter().map(|s| s.surface_area().max(0.0)).collect();
        let mesh_areas: Vec<f32> = self.meshes.iter().map(|m| mesh::mesh_area(m)).collect();
        let total: f32 = prim_areas.iter().chain(&mesh_areas).filter(|a| a.is_finite()).sum();
        if total <= 0.0 || !total.is_finite() {
            return Vec::new();
        }
        let share = |area: f32| ((n_total as f32 * area / total).round() as usize).max(1);
        let mut out = Vec::with_capacity(n_total + self.primitives.len() + self.meshes.len());
        for (shape, area) in self.primitives.iter().zip(&prim_areas) {
            out.extend(shape.sample_surface(share(*area)));
        }
        for (m, area) in self.meshes.iter().zip(&mesh_areas) {
            if area.is_finite() && *area > 0.0 {
                out.extend(mesh::sample_mesh(m, share(*area)));
            }
        }
        out
    }
}

/// (Chamfer, `IoU`) of a prediction against a truth object (primitives and meshes), with the
/// default sample count and grid.
pub(crate) fn object_geometry(predicted: &[Primitive], truth: &TruthObject) -> (Option<f32>, Option<f32>) {
    let pred = Solids::of_primitives(predicted);
    let truth = Solids::of_truth(truth);
    (chamfer_between(&pred, &truth, CHAMFER_SAMPLES), iou_between(&pred, &truth, VOXEL_RESOLUTION))
}

/// The truth object's unit box: its AABB centre and largest extent (metres).
#[derive(Clone, Copy, Debug)]
struct UnitBox {
    center_world: Vec3,
    largest_extent_m: f32,
}

impl UnitBox {
    fn of(solids: &Solids) -> Option<Self> {
        let (lo, hi) = solids.aabb()?;
        let largest_extent_m = (hi - lo).max_element();
        (largest_extent_m.is_finite() && largest_extent_m > 1e-9).then_some(Self { center_world: 0.5 * (lo + hi), largest_extent_m })
    }

    fn to_unit(self, world: Vec3) -> Vec3 {
        (world - self.center_world) / self.largest_extent_m
    }

    fn to_world(self, unit: Vec3) -> Vec3 {
        self.center_world + unit * self.largest_extent_m
    }
}

/// About `n_total` surface samples over several primitives, split by surface area (deterministic).
#[must_use]
pub fn sample_shapes(shapes: &[Primitive], n_total: usize) -> Vec<Vec3> {
    Solids::of_primitives(shapes).sample(n_total)
}

/// Symmetric Chamfer distance between a prediction and the truth, both normalised by the truth's
/// unit box: mean over predicted samples of the distance to the nearest truth sample, plus the mean
/// over truth samples of the distance to the nearest predicted sample. Distances are Euclidean,
/// not squared (the paper does not say; plain distances keep the unit of "fraction of the object's
/// size"). `n_samples` samples are drawn on each side. `None` when either side has no surface.
#[must_use]
pub fn chamfer_distance(predicted: &[Primitive], truth: &[Primitive], n_samples: usize) -> Option<f32> {
    chamfer_between(&Solids::of_primitives(predicted), &Solids::of_primitives(truth), n_samples)
}

/// [`chamfer_distance`] between any solids (meshes sampled by area like primitives).
#[must_use]
pub fn chamfer_between(predicted: &Solids, truth: &Solids, n_samples: usize) -> Option<f32> {
    let unit = UnitBox::of(truth)?;
    let to_unit = |pts: Vec<Vec3>| -> Vec<[f32; 3]> { pts.into_iter().map(|p| unit.to_unit(p).to_array()).collect() };
    let pred = to_unit(predicted.sample(n_samples));
    let gt = to_unit(truth.sample(n_samples));
    Some(mean_nearest_distance(&pred, &gt)? + mean_nearest_distance(&gt, &pred)?)
}

/// Mean over `queries` of the Euclidean distance to the nearest point of `targets`.
/// `None` when either set is empty (or the tree cannot be built).
///
/// Identical targets are merged first: they change no nearest distance, but a k-d tree cannot split
/// a bucket of equal points, so a degenerate solid (zero size, or coordinates so far out that `f32`
/// rounds its samples together) made every query a linear scan — found by fuzzing `scene.json` and
/// `gt.json`, like the axis-aligned faces below.
pub(crate) fn mean_nearest_distance(queries: &[[f32; 3]], targets: &[[f32; 3]]) -> Option<f32> {
    if queries.is_empty() || targets.is_empty() {
        return None;
    }
    // Both sets turned by one fixed, generic rotation (distances are unchanged): samples on the
    // face of an axis-aligned box share a coordinate, and a k-d tree that splits on that axis
    // cannot divide them, so its buckets grew to whole faces and each query scanned one.
    let turn = glam::Mat3::from_euler(glam::EulerRot::ZYX, 0.61, 0.37, 0.23);
    let turned = |p: &[f32; 3]| (turn * glam::Vec3::from_array(*p)).to_array();
    let mut distinct: Vec<[f32; 3]> = targets.iter().map(turned).collect();
    distinct.sort_unstable_by_key(|p| p.map(f32::to_bits));
    distinct.dedup_by_key(|p| p.map(f32::to_bits));
    let tree = kiddo::ImmutableKdTree::<f32, 3>::new_from_slice(&distinct).ok()?;
    let sum: f64 = queries
        .iter()
        .map(|q| f64::from(tree.query(&turned(q)).nearest_one::<kiddo::SquaredEuclidean<f32>>().execute().distance.sqrt()))
        .sum();
    Some((sum / queries.len() as f64) as f32)
}

/// Voxel `IoU` of a prediction against the truth: a `resolution`³ lattice spans the truth's normalised
/// bounding cube (side `1 + 2·VOXEL_MARGIN`), extended at the same pitch over any part of the
/// prediction outside it (up to `VOXEL_LATTICE_HALF_WIDTH`); a voxel is occupied when its centre
/// lies inside any solid primitive. `None` when the truth has no extent or occupies no voxel.
#[must_use]
pub fn voxel_iou(predicted: &[Primitive], truth: &[Primitive], resolution: usize) -> Option<f32> {
    iou_between(&Solids::of_primitives(predicted), &Solids::of_primitives(truth), resolution)
}

/// [`voxel_iou`] between any solids: a closed mesh occupies the voxels whose centres it encloses
/// (vertical ray parity), an open mesh the voxels its surface passes through.
#[must_use]
pub fn iou_between(predicted: &Solids, truth: &Solids, resolution: usize) -> Option<f32> {
    let unit = UnitBox::of(truth)?;
    let resolution = resolution.max(1);
    let half_side = 0.5 + VOXEL_MARGIN;
    let pitch = 2.0 * half_side / resolution as f32;
    // Voxel i along an axis has its centre at -half_side + (i + 0.5)·pitch; i may be negative.
    let index_range = |lo: f32, hi: f32| -> (i64, i64) {
        let lo = lo.max(-VOXEL_LATTICE_HALF_WIDTH);
        let hi = hi.min(VOXEL_LATTICE_HALF_WIDTH);
        (((lo + half_side) / pitch - 0.5).ceil() as i64, ((hi + half_side) / pitch - 0.5).floor() as i64)
    };
    // Lattice bounds: the truth cube plus the predicted primitives' boxes.
    let mut lat_lo = [0_i64; 3];
    let mut lat_hi = [resolution as i64 - 1; 3];
    for (lo, hi) in predicted.primitives.iter().map(Primitive::aabb).chain(predicted.meshes.iter().filter_map(|m| m.aabb())) {
        let (lo, hi) = (unit.to_unit(lo), unit.to_unit(hi));
        for axis in 0..3 {
            let (a, b) = index_range(lo[axis], hi[axis]);
            if a <= b {
                lat_lo[axis] = lat_lo[axis].min(a);
                lat_hi[axis] = lat_hi[axis].max(b);
            }
        }
    }
    let dims = [0, 1, 2].map(|a| (lat_hi[a] - lat_lo[a] + 1) as usize);
    let lattice = WorldLattice {
        origin_world: unit.to_world(Vec3::new(lat_lo[0] as f32, lat_lo[1] as f32, lat_lo[2] as f32) * pitch - Vec3::splat(half_side)),
        pitch_m: pitch * unit.largest_extent_m,
        dims,
    };
    let rasterise = |solids: &Solids| -> Vec<bool> {
        let mut grid = vec![false; dims[0] * dims[1] * dims[2]];
        for m in &solids.meshes {
            mesh::rasterise_mesh(m, &lattice, &mut grid);
        }
        for s in &solids.primitives {
            let (lo, hi) = s.aabb();
            let (lo, hi) = (unit.to_unit(lo), unit.to_unit(hi));
            let ranges = [0, 1, 2].map(|a| {
                let (x, y) = index_range(lo[a], hi[a]);
                (x.max(lat_lo[a]), y.min(lat_hi[a]))
            });
            for i in ranges[0].0..=ranges[0].1 {
                for j in ranges[1].0..=ranges[1].1 {
                    for k in ranges[2].0..=ranges[2].1 {
                        let idx = ((i - lat_lo[0]) as usize * dims[1] + (j - lat_lo[1]) as usize) * dims[2] + (k - lat_lo[2]) as usize;
                        if grid[idx] {
                            continue;
                        }
                        let centre_unit = Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * pitch - Vec3::splat(half_side);
                        if s.contains(unit.to_world(centre_unit)) {
                            grid[idx] = true;
                        }
                    }
                }
            }
        }
        grid
    };
    let a = rasterise(predicted);
    let b = rasterise(truth);
    let (mut inter, mut union) = (0_usize, 0_usize);
    for (x, y) in a.iter().zip(&b) {
        inter += usize::from(*x && *y);
        union += usize::from(*x || *y);
    }
    let truth_voxels = b.iter().filter(|v| **v).count();
    (truth_voxels > 0 && union > 0).then(|| inter as f32 / union as f32)
}

/// Mean of the finite values of an iterator; `None` when there are none.
pub(crate) fn mean(values: impl Iterator<Item = f32>) -> Option<f32> {
    let (sum, n) = values.filter(|v| v.is_finite()).fold((0.0_f64, 0_usize), |(s, n), v| (s + f64::from(v), n + 1));
    (n > 0).then(|| (sum / n as f64) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Pose, Quat};
    use crate::primitive::PrimitiveKind;

    fn unit_cube(center: Vec3) -> Primitive {
        Primitive::cuboid_at(center, Vec3::ONE)
    }

    #[test]
    fn nearest_distance_to_many_identical_targets_is_the_distance_to_one() {
        // Regression (fuzz, scene_json/gt_json/multiscan): 10 000 equal targets made a k-d tree bucket
        // that could not split, and every query scanned all of it.
        let targets = vec![[1.0_f32, 2.0, 3.0]; 10_000];
        let queries = [[1.0_f32, 2.0, 7.0], [4.0, 6.0, 3.0]];
        let near = |d: Option<f32>, want: f32| d.is_some_and(|d| (d - want).abs() < 1e-5);
        assert!(near(mean_nearest_distance(&queries, &targets), 4.5));
        let mixed: Vec<[f32; 3]> = targets.iter().copied().chain([[1.0, 2.0, 6.0]]).collect();
        assert!(near(mean_nearest_distance(&queries, &mixed), 3.0));
    }

    #[test]
    fn chamfer_of_identical_shapes_is_zero() {
        let pose = Pose::from_parts(Vec3::new(2.0, 1.0, 0.4), Quat::from_rotation_z(0.4));
        let shapes = [
            Primitive::new(PrimitiveKind::Cuboid, Vec3::new(1.2, 0.6, 0.8), pose),
            Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.1, 0.1, 0.7), Pose::from_translation(Vec3::Z)),
        ];
        let c = chamfer_distance(&shapes, &shapes, CHAMFER_SAMPLES).expect("chamfer");
        assert!(c.abs() < 1e-5, "{c}");
    }

    #[test]
    fn chamfer_of_a_box_shifted_by_a_tenth_matches_the_analytic_value() {
        // Unit cube vs the same cube shifted by 0.1 along x. Continuous surface distances:
        // +x face: 0.1; -x face (inside the truth): E[min(0.1, u, v)] with u, v ~ U(0, 0.5)
        // = ∫₀^0.1 (1 − 2t)² dt = (1 − 0.8³)/6; the four side faces: 0.1 of their length sticks
        // out, mean 0.005. Mean over the 6 faces, times 2 (the case is symmetric).
        let minus_x = (1.0 - 0.8_f32.powi(3)) / 6.0;
        let expected = 2.0 * (0.1 + minus_x + 4.0 * 0.005) / 6.0;
        let truth = [unit_cube(Vec3::new(3.0, -1.0, 0.5))];
        let pred = [unit_cube(Vec3::new(3.1, -1.0, 0.5))];
        // A sample's nearest sample is never nearer than the surface, so the sampled value sits a
        // little above the continuous one (the sampling floor), less so the denser the sampling.
        let dense = chamfer_distance(&pred, &truth, 40_000).expect("chamfer");
        assert!(dense > expected - 0.001 && dense < expected + 0.008, "{dense} vs {expected}");
        let c = chamfer_distance(&pred, &truth, CHAMFER_SAMPLES).expect("chamfer");
        assert!(c > dense - 0.001 && c < expected + 0.02, "{c} vs {expected}");
        // Scale invariance: a 3× larger scene gives the same normalised value.
        let big = |p: Primitive| Primitive::cuboid_at(p.center() * 3.0, p.size * 3.0);
        let c3 = chamfer_distance(&[big(pred[0])], &[big(truth[0])], CHAMFER_SAMPLES).expect("chamfer");
        assert!((c3 - c).abs() < 1e-3, "{c3} vs {c}");
    }

    #[test]
    fn chamfer_of_an_empty_prediction_is_none() {
        assert_eq!(chamfer_distance(&[], &[unit_cube(Vec3::ZERO)], 100), None);
    }

    #[test]
    fn iou_of_identical_shapes_is_one() {
        let shapes = [
            Primitive::new(PrimitiveKind::Cuboid, Vec3::new(1.0, 0.5, 0.3), Pose::from_parts(Vec3::ZERO, Quat::from_rotation_z(0.7))),
            Primitive::new(PrimitiveKind::Sphere, Vec3::splat(0.4), Pose::from_translation(Vec3::Z * 0.3)),
        ];
        let iou = voxel_iou(&shapes, &shapes, VOXEL_RESOLUTION).expect("iou");
        assert!((iou - 1.0).abs() < 1e-6, "{iou}");
    }

    #[test]
    fn iou_of_half_overlapping_boxes_is_a_third() {
        let truth = [unit_cube(Vec3::ZERO)];
        let pred = [unit_cube(Vec3::new(0.5, 0.0, 0.0))];
        let iou = voxel_iou(&pred, &truth, VOXEL_RESOLUTION).expect("iou");
        assert!((iou - 1.0 / 3.0).abs() < 0.02, "{iou}");
        // No overlap at all: 0; an empty prediction: 0.
        let far = [unit_cube(Vec3::new(1.5, 0.0, 0.0))];
        assert_eq!(voxel_iou(&far, &truth, VOXEL_RESOLUTION), Some(0.0));
        assert_eq!(voxel_iou(&[], &truth, VOXEL_RESOLUTION), Some(0.0));
    }

    #[test]
    fn a_mesh_box_scores_like_the_primitive_box() {
        let lo = Vec3::new(1.0, -0.5, 0.0);
        let hi = Vec3::new(1.8, 0.1, 1.2);
        let mesh = crate::eval::mesh::box_mesh(lo, hi);
        let prim = [Primitive::cuboid_at(0.5 * (lo + hi), hi - lo)];
        let truth = Solids { primitives: vec![], meshes: vec![&mesh] };
        let pred = Solids::of_primitives(&prim);
        let c = chamfer_between(&pred, &truth, CHAMFER_SAMPLES).expect("chamfer");
        assert!(c < 0.03, "{c}");
        let iou = iou_between(&pred, &truth, VOXEL_RESOLUTION).expect("iou");
        assert!(iou > 0.97, "{iou}");
        // The upper half of the truth box: IoU one half.
        let half = [Primitive::cuboid_at(Vec3::new(1.4, -0.2, 0.9), Vec3::new(0.8, 0.6, 0.6))];
        let iou = iou_between(&Solids::of_primitives(&half), &truth, VOXEL_RESOLUTION).expect("iou");
        assert!((iou - 0.5).abs() < 0.03, "{iou}");
    }

    #[test]
    fn evaluate_geometry_scores_every_truth_object_in_order() {
        use crate::truth::{TruthObject, TruthPart};
        let object = |id: ObjectId, center: Vec3| TruthObject {
            id,
            category: "cabinet".into(),
            supported_by: None,
            parts: vec![TruthPart { id: id * 10, label: "body".into(), shapes: vec![unit_cube(center)], meshes: vec![] }],
            joints: vec![],
            contact_edges: vec![],
        };
        let truth = GroundTruth {
            format: crate::truth::TRUTH_FORMAT.into(),
            objects: vec![object(2, Vec3::ZERO), object(1, Vec3::X * 5.0)],
            floor_z: 0.0,
        };
        let predicted = vec![(1, vec![unit_cube(Vec3::X * 5.0)])];
        let scores = evaluate_geometry(&predicted, &truth);
        assert_eq!(scores.len(), 2);
        assert_eq!(scores[0].object, 2);
        assert_eq!(scores[0].chamfer, None);
        assert_eq!(scores[0].iou, Some(0.0));
        assert_eq!(scores[1].object, 1);
        assert!(scores[1].chamfer.expect("chamfer") < 1e-5);
        assert_eq!(scores[1].iou, Some(1.0));
        let summary = GeometrySummary::of(&scores);
        assert_eq!(summary.mean_iou, Some(0.5));
    }
}
