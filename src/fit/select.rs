//! Candidate generation, scoring and selection for one part (see the module docs of
//! [`crate::fit`] for the score and why it differs from the paper's).

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use thiserror::Error;

use super::icp::{IcpConfig, icp_align};
use super::obb::{MIN_EXTENT_M, Obb, axes_angle_deg, min_volume_obb, pca_obb};
use super::{quantile_in_place, subsample_stride};
use crate::math::{Mat3, Pose, Quat, Vec3};
use crate::primitive::{Primitive, PrimitiveKind};

/// Settings of [`fit_part`].
#[derive(Clone, Debug, PartialEq)]
pub struct FitConfig {
    /// Parts with fewer points are not fitted ([`FitError::TooFewPoints`]); at least 4 is enforced.
    pub min_points: usize,
    /// The part is subsampled (by stride) to this many points for the outlier filter, the box and
    /// the final alignment.
    pub max_points_for_fit: usize,
    /// Candidates are aligned and scored on this many points (a stride subsample of the above).
    pub max_points_for_selection: usize,
    /// The kinds tried (cylinders and capsules along each of the three box axes).
    pub kinds: Vec<PrimitiveKind>,
    /// ICP settings (candidates and final alignment).
    pub icp: IcpConfig,
    /// ICP iterations every template gets before screening.
    pub screen_iterations: usize,
    /// After screening, at most this many candidates are aligned to convergence ...
    pub screen_keep_max: usize,
    /// ... those whose mean point→surface error is within this factor of the best one.
    pub screen_keep_ratio: f32,
    /// The best candidate of each kind is also aligned when its error is within this factor.
    pub screen_keep_ratio_per_kind: f32,
    /// Neighbours in the statistical outlier filter (0 disables the filter; the point spacing is
    /// still measured with one neighbour).
    pub outlier_neighbors: usize,
    /// A point is a stray when its mean neighbour distance exceeds this many times the median
    /// (and the median plus six robust standard deviations).
    pub outlier_factor: f32,
    /// Surface samples per candidate for the model→data (coverage) term.
    pub score_samples: usize,
    /// The coverage term averages over the best-covered share of the surface samples equal to
    /// the share the scan covers (measured on the candidate that explains the points best), but
    /// never less than this fraction.
    pub coverage_fraction: f32,
    /// Weight of the coverage term.
    pub coverage_weight: f32,
    /// Point→surface distances are capped at this in the score, metres.
    pub score_distance_cap_m: f32,
    /// Candidates within this relative score of the best count as a tie (the simpler kind wins).
    pub tie_tolerance: f32,
    /// A capsule must beat the other kinds by this relative margin: it has the most freedom and
    /// contains the sphere (length = diameter) and nearly the cylinder.
    pub capsule_penalty: f32,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            min_points: 10,
            max_points_for_fit: 1500,
            max_points_for_selection: 300,
            kinds: PrimitiveKind::ALL.to_vec(),
            icp: IcpConfig { refit_size: true, ..IcpConfig::default() },
            screen_iterations: 4,
            screen_keep_max: 2,
            screen_keep_ratio: 1.5,
            screen_keep_ratio_per_kind: 6.0,
            outlier_neighbors: 4,
            outlier_factor: 3.0,
            score_samples: 128,
            coverage_fraction: 0.5,
            coverage_weight: 0.5,
            score_distance_cap_m: 0.05,
            tie_tolerance: 0.03,
            capsule_penalty: 0.15,
        }
    }
}

/// One aligned candidate and its selection score (lower is better).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The aligned candidate primitive.
    pub primitive: Primitive,
    /// Selection score, metres (see [`crate::fit`]).
    pub score: f32,
}

/// The primitive chosen for a part.
#[derive(Clone, Debug, PartialEq)]
pub struct PartFit {
    /// The chosen primitive, after a final alignment on the larger subsample.
    pub primitive: Primitive,
    /// Mean point→surface distance over all the part's points, metres.
    pub fit_error: f32,
    /// Selection score of `primitive`, metres (same scale as the candidates').
    pub score: f32,
    /// Every aligned candidate (before the final alignment), in generation order: kinds in
    /// config order, cylinders and capsules along box axes x, y, z.
    pub candidates: Vec<Candidate>,
}

/// Why a part could not be fitted.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FitError {
    /// Fewer points than `FitConfig::min_points` (at least 4).
    #[error("part has {got} points; fitting a primitive needs at least {min}")]
    TooFewPoints { got: usize, min: usize },
    /// A point with a NaN or infinite coordinate (index into the part's points).
    #[error("part point {index} is not finite: ({x}, {y}, {z})")]
    NonFinite { index: usize, x: f32, y: f32, z: f32 },
    /// Nothing to fit: all points (nearly) coincide, no kinds to try, or no candidate aligned.
    #[error("degenerate part: {reason}")]
    Degenerate { reason: String },
}

/// Fits the best primitive to one part's points (world frame).
///
/// With `forced_kind`, only candidates of that kind are tried (e.g. a label that implies a
/// shape); otherwise `cfg.kinds`. Deterministic; single-threaded.
pub fn fit_part(points: &[Vec3], cfg: &FitConfig, forced_kind: Option<PrimitiveKind>) -> Result<PartFit, FitError> {
    let min = cfg.min_points.max(4);
    if points.len() < min {
        return Err(FitError::TooFewPoints { got: points.len(), min });
    }
    if let Some((index, p)) = points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(FitError::NonFinite { index, x: p.x, y: p.y, z: p.z });
    }
    let fit_set = subsample_stride(points, cfg.max_points_for_fit.max(min));
    let coords: Vec<[f32; 3]> = fit_set.iter().map(Vec3::to_array).collect();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&coords)
        .map_err(|e| FitError::Degenerate { reason: format!("cannot index the part's points: {e:?}") })?;
    // Stray points are dropped from the selection subsample (neighbours looked up among the
    // denser fit set): the minimal box is built on it and would be inflated by them.
    let selection_raw = subsample_stride(&fit_set, cfg.max_points_for_selection.max(min));
    let (filtered, spacing) = drop_isolated(&selection_raw, &fit_set, &tree, cfg.outlier_neighbors.max(1), cfg.outlier_factor);
    let selection = if cfg.outlier_neighbors > 0 && filtered.len() >= min { filtered } else { selection_raw };

    let obb = min_volume_obb(&selection);
    if obb.size.max_element() < 2.0 * MIN_EXTENT_M {
        return Err(FitError::Degenerate {
            reason: format!("all {} points lie within {} mm of each other", points.len(), 2.0 * MIN_EXTENT_M * 1000.0),
        });
    }

    let kinds: Vec<PrimitiveKind> = if let Some(k) = forced_kind {
        vec![k]
    } else {
        let mut ks = Vec::new();
        for k in &cfg.kinds {
            if !ks.contains(k) {
                ks.push(*k);
            }
        }
        ks
    };
    if kinds.is_empty() {
        return Err(FitError::Degenerate { reason: "no primitive kinds to try (FitConfig::kinds is empty)".into() });
    }

    // Screening: a few ICP iterations per template; only the candidates whose mean point→surface
    // error is close to the best one are aligned to convergence (the others keep their
    // screening pose and are still scored and listed).
    let screen_icp = IcpConfig { max_iterations: cfg.screen_iterations.min(cfg.icp.max_iterations), ..cfg.icp.clone() };
    let mut screened: Vec<(Primitive, f32)> = Vec::new();
    let pca_box = pca_obb(&selection);
    let pca_box = (axes_angle_deg(&pca_box.axes, &obb.axes) > 1.0).then_some(&pca_box);
    for template in templates(&obb, pca_box, &kinds) {
        let res = icp_align(&template, &selection, &screen_icp);
        let p = res.primitive;
        if p.world_from_primitive.is_finite() && p.size.is_finite() && res.mean_error.is_finite() {
            screened.push((p, res.mean_error));
        }
    }
    let mut order: Vec<usize> = (0..screened.len()).collect();
    order.sort_by(|a, b| screened[*a].1.total_cmp(&screened[*b].1).then(a.cmp(b)));
    let best_error = order.first().map_or(f32::INFINITY, |i| screened[*i].1);
    let mut measured = Vec::with_capacity(screened.len());
    for (i, (p, error)) in screened.iter().enumerate() {
        let rank = order.iter().position(|o| *o == i).unwrap_or(usize::MAX);
        // The first of its kind in the ranking gets a second chance: a template whose box was
        // inflated by a near stray point converges more slowly than the others.
        let first_of_kind = order.iter().find(|o| screened[**o].0.kind == p.kind) == Some(&i);
        let promising = (rank < cfg.screen_keep_max.max(1) && *error <= best_error * cfg.screen_keep_ratio.max(1.0) + 1e-4)
            || (first_of_kind && *error <= best_error * cfg.screen_keep_ratio_per_kind.max(1.0) + 1e-4);
        let aligned = if promising { icp_align(p, &selection, &cfg.icp).primitive } else { *p };
        if aligned.world_from_primitive.is_finite() && aligned.size.is_finite() {
            measured.push(measure(&aligned, &selection, &tree, cfg));
        }
    }
    // The paper's own candidate, the minimal box aligned rigidly with its size kept: size
    // re-estimation can collapse a box whose points form a U (a bed frame seen along its sides
    // and foot, its head hidden behind the headboard), which the truncated score then tolerates.
    let rigid_icp = IcpConfig { refit_size: false, ..cfg.icp.clone() };
    let rigid_box = kinds.contains(&PrimitiveKind::Cuboid).then(|| {
        let template = Primitive::new(PrimitiveKind::Cuboid, obb.size, obb.world_from_box());
        icp_align(&template, &selection, &rigid_icp).primitive
    });
    if let Some(b) = rigid_box.filter(|b| b.world_from_primitive.is_finite() && b.size.is_finite()) {
        measured.push(measure(&b, &selection, &tree, cfg));
    }
    // The share of the surface the scanner saw, from the candidate that explains the points best
    // (lowest data→model distance): the coverage term averages over that share (at least
    // `coverage_fraction`) of every candidate's best-covered surface samples.
    let covered_within = (3.0 * spacing).max(2.0 * MIN_EXTENT_M);
    let fraction = measured
        .iter()
        .min_by(|a, b| a.data_to_model.total_cmp(&b.data_to_model))
        .map_or(1.0, |m| m.covered_fraction(covered_within))
        .clamp(cfg.coverage_fraction.clamp(0.0, 1.0), 1.0);
    let candidates: Vec<Candidate> = measured
        .iter()
        .map(|m| Candidate { primitive: m.primitive, score: m.score(fraction, cfg.coverage_weight) })
        .filter(|c| c.score.is_finite())
        .collect();
    let chosen = choose(&candidates, cfg.tie_tolerance, cfg.capsule_penalty)
        .ok_or_else(|| FitError::Degenerate { reason: "no candidate primitive could be aligned".into() })?;

    // Final alignment on the larger subsample, without the points far from the chosen primitive
    // (strays; the size statistics use all points given); kept unless it made things worse.
    let kept = near_points(&chosen.primitive, &fit_set);
    let chose_rigid = rigid_box.is_some_and(|b| b == chosen.primitive);
    let refined = icp_align(&chosen.primitive, &kept, if chose_rigid { &rigid_icp } else { &cfg.icp }).primitive;
    let refined_score = measure(&refined, &selection, &tree, cfg).score(fraction, cfg.coverage_weight);
    let (primitive, score) =
        if refined.world_from_primitive.is_finite() && refined_score.is_finite() && refined_score <= chosen.score * 1.1 + 1e-4 {
            (refined, refined_score)
        } else {
            (chosen.primitive, chosen.score)
        };
    let fit_error = (points.iter().map(|p| f64::from(primitive.surface_distance(*p))).sum::<f64>() / points.len() as f64) as f32;
    Ok(PartFit { primitive, fit_error, score, candidates })
}

/// The paper's templates scaled by the minimal box: the box itself, cylinders and capsules along
/// each box axis (diameter = mean of the other two extents), a sphere of the mean extent; and
/// the principal-axes box as a second cuboid when its axes differ from the minimal box's.
fn templates(obb: &Obb, pca_box: Option<&Obb>, kinds: &[PrimitiveKind]) -> Vec<Primitive> {
    let axes = [obb.axes.x_axis, obb.axes.y_axis, obb.axes.z_axis];
    let s = obb.size.to_array();
    let pose_of = |m: Mat3| Pose::from_parts(obb.center, Quat::from_mat3(&m).normalize());
    let mut out = Vec::new();
    for kind in kinds {
        match kind {
            PrimitiveKind::Cuboid => {
                out.push(Primitive::new(*kind, obb.size, pose_of(obb.axes)));
                if let Some(b) = pca_box {
                    out.push(Primitive::new(*kind, b.size, Pose::from_parts(b.center, Quat::from_mat3(&b.axes).normalize())));
                }
            }
            PrimitiveKind::Sphere => out.push(Primitive::new(*kind, Vec3::splat(obb.size.element_sum() / 3.0), pose_of(obb.axes))),
            PrimitiveKind::Cylinder | PrimitiveKind::Capsule => {
                for k in 0..3 {
                    // Cyclic permutation keeps the frame right-handed; the axis becomes local z.
                    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                    let m = Mat3::from_cols(axes[i], axes[j], axes[k]);
                    out.push(Primitive::new(*kind, Vec3::new(s[i], s[j], s[k]), pose_of(m)));
                }
            }
        }
    }
    out
}

/// The two halves of a candidate's score.
struct Measured {
    primitive: Primitive,
    /// Mean point→surface distance, each capped, metres.
    data_to_model: f32,
    /// Distance from each surface sample to the nearest point, capped, ascending.
    sample_distances: Vec<f32>,
}

impl Measured {
    /// Share of the surface samples within `within` of a point.
    fn covered_fraction(&self, within: f32) -> f32 {
        if self.sample_distances.is_empty() {
            return 1.0;
        }
        self.sample_distances.partition_point(|d| *d <= within) as f32 / self.sample_distances.len() as f32
    }

    /// Data→model mean plus `weight` × the mean over the best-covered `fraction` of the samples.
    fn score(&self, fraction: f32, weight: f32) -> f32 {
        let n = self.sample_distances.len();
        let coverage = if n == 0 || weight <= 0.0 {
            0.0
        } else {
            let keep = ((n as f32 * fraction.clamp(0.0, 1.0)).ceil() as usize).clamp(1, n);
            self.sample_distances[..keep].iter().map(|d| f64::from(*d)).sum::<f64>() / keep as f64
        };
        (f64::from(self.data_to_model) + f64::from(weight.max(0.0)) * coverage) as f32
    }
}

/// Measures a candidate against the points (data→model) and the indexed part (model→data).
fn measure(prim: &Primitive, points: &[Vec3], tree: &ImmutableKdTree<f32, 3>, cfg: &FitConfig) -> Measured {
    let cap = cfg.score_distance_cap_m.max(MIN_EXTENT_M);
    let data_to_model = if points.is_empty() {
        f32::INFINITY
    } else {
        (points.iter().map(|p| f64::from(prim.surface_distance(*p).min(cap))).sum::<f64>() / points.len() as f64) as f32
    };
    let mut sample_distances: Vec<f32> = prim
        .sample_surface(cfg.score_samples.max(1))
        .iter()
        .map(|s| {
            // Bounded search: far samples count as `cap` (and an unbounded search from far
            // away visits much of the tree).
            tree.query(&s.to_array())
                .nearest_n::<SquaredEuclidean<f32>>(NonZero::<usize>::MIN)
                .within(cap * cap)
                .execute()
                .first()
                .map_or(cap, |r| r.distance.sqrt().min(cap))
        })
        .collect();
    sample_distances.sort_by(f32::total_cmp);
    Measured { primitive: *prim, data_to_model, sample_distances }
}

/// The best candidate by score (a capsule's score raised by `capsule_penalty`); among those
/// within `tie_tolerance` of the best, the simplest kind (declaration order of
/// [`PrimitiveKind`]), then the lower score, then the earlier one.
fn choose(candidates: &[Candidate], tie_tolerance: f32, capsule_penalty: f32) -> Option<Candidate> {
    let effective = |c: &Candidate| {
        if c.primitive.kind == PrimitiveKind::Capsule { c.score * (1.0 + capsule_penalty.max(0.0)) } else { c.score }
    };
    let best = candidates.iter().map(effective).fold(f32::INFINITY, f32::min);
    if !best.is_finite() {
        return None;
    }
    let bar = best * (1.0 + tie_tolerance.max(0.0)) + 1e-5;
    candidates
        .iter()
        .filter(|c| effective(c) <= bar)
        .min_by(|a, b| a.primitive.kind.cmp(&b.primitive.kind).then(effective(a).total_cmp(&effective(b))))
        .copied()
}

/// The points within `max(8 × median, 5 % of the largest extent, 5 mm)` of the primitive's
/// surface (all of them when that would leave fewer than half).
fn near_points(prim: &Primitive, points: &[Vec3]) -> Vec<Vec3> {
    let dist: Vec<f32> = points.iter().map(|p| prim.surface_distance(*p)).collect();
    let mut scratch = dist.clone();
    let median = quantile_in_place(&mut scratch, 0.5).unwrap_or(0.0);
    let limit = (8.0 * median).max(0.05 * prim.size.max_element()).max(0.005);
    let kept: Vec<Vec3> = points.iter().zip(&dist).filter(|(_, d)| **d <= limit).map(|(p, _)| *p).collect();
    if kept.len() * 2 < points.len() { points.to_vec() } else { kept }
}

/// Points whose mean distance to their `k` nearest neighbours (in `tree`) is not an outlier
/// (statistical filter with a robust threshold), and the median of that distance (the point
/// spacing). Filters nothing when it would drop more than a quarter of the points (then the
/// "outliers" are structure, not strays).
fn drop_isolated(points: &[Vec3], fit_set: &[Vec3], tree: &ImmutableKdTree<f32, 3>, k: usize, factor: f32) -> (Vec<Vec3>, f32) {
    let Some(qty) = NonZero::new(k + 1) else {
        return (points.to_vec(), 0.0);
    };
    if points.len() <= k + 1 {
        return (points.to_vec(), 0.0);
    }
    // Mean distance to the k nearest neighbours in the denser fit set, and those neighbours.
    let knn = |p: [f32; 3]| -> (f32, Vec<u32>) {
        let found = tree.query(&p).nearest_n::<SquaredEuclidean<f32>>(qty).execute();
        // The first hit is the point itself (or a duplicate at distance 0).
        let others = found.len().saturating_sub(1).max(1);
        let mean = found.iter().skip(1).map(|r| r.distance.sqrt()).sum::<f32>() / others as f32;
        (mean, found.iter().skip(1).map(|r| r.item).collect())
    };
    let local: Vec<(f32, f32)> = points
        .iter()
        .map(|p| {
            let (d, neighbours) = knn(p.to_array());
            // The neighbours' own spacing: scan density varies several-fold between the near and
            // the far side of a part, so a point is a stray only relative to its surroundings
            // (a lightweight local outlier factor), not to the part's global median.
            let mut around: Vec<f32> = neighbours.iter().filter_map(|&i| fit_set.get(i as usize)).map(|q| knn(q.to_array()).0).collect();
            let typical = quantile_in_place(&mut around, 0.5).unwrap_or(d);
            (d, typical)
        })
        .collect();
    let mut scratch: Vec<f32> = local.iter().map(|(d, _)| *d).collect();
    let Some(median) = quantile_in_place(&mut scratch, 0.5) else {
        return (points.to_vec(), 0.0);
    };
    let kept: Vec<Vec3> =
        points.iter().zip(&local).filter(|(_, (d, typical))| *d <= median || *d <= factor * typical.max(1e-6)).map(|(p, _)| *p).collect();
    if kept.len() * 4 < points.len() * 3 { (points.to_vec(), median) } else { (kept, median) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{line_angle_deg, rng};
    use rand::Rng;
    use rand_distr::{Distribution, Normal};

    /// Surface samples with σ = 2 mm noise and 1 % outliers in the surrounding box.
    fn noisy(prim: &Primitive, n: usize, seed: u64) -> Vec<Vec3> {
        let mut r = rng(seed);
        let noise = Normal::new(0.0_f32, 0.002).expect("valid sigma");
        let mut pts: Vec<Vec3> = prim
            .sample_surface(n)
            .into_iter()
            .map(|p| p + Vec3::new(noise.sample(&mut r), noise.sample(&mut r), noise.sample(&mut r)))
            .collect();
        let (lo, hi) = prim.aabb();
        let (lo, hi) = (lo - Vec3::splat(0.2), hi + Vec3::splat(0.2));
        for _ in 0..n / 100 {
            let t = Vec3::new(r.random(), r.random(), r.random());
            let idx = r.random_range(0..pts.len());
            pts.insert(idx, lo + (hi - lo) * t);
        }
        pts
    }

    fn pose(center: Vec3, rx: f32, ry: f32, rz: f32) -> Pose {
        Pose::from_parts(center, Quat::from_euler(glam::EulerRot::XYZ, rx, ry, rz))
    }

    #[test]
    fn picks_a_cuboid_for_box_points() {
        let truth = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.5, 0.4, 0.9), pose(Vec3::new(1.0, 0.0, 0.45), 0.0, 0.0, 0.4));
        let fit = fit_part(&noisy(&truth, 3000, 1), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Cuboid);
        assert!((fit.primitive.center() - truth.center()).length() < 0.005);
        let mut got = fit.primitive.size.to_array();
        let mut want = truth.size.to_array();
        got.sort_by(f32::total_cmp);
        want.sort_by(f32::total_cmp);
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 0.006, "{got:?} vs {want:?}");
        }
        // 8 templates, the rigidly aligned minimal box, and the principal-axes box when it
        // differs from the minimal box.
        assert!((9..=10).contains(&fit.candidates.len()), "{}", fit.candidates.len());
        assert!(fit.fit_error < 0.01, "{}", fit.fit_error);
    }

    #[test]
    fn picks_a_cylinder_with_the_right_axis() {
        let truth = Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.3, 0.3, 0.7), pose(Vec3::new(0.0, 2.0, 0.5), 0.5, 0.2, 0.0));
        let fit = fit_part(&noisy(&truth, 3000, 2), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Cylinder, "{:?}", fit.candidates);
        let axis_err = line_angle_deg(fit.primitive.axes_world()[2], truth.axes_world()[2]);
        assert!(axis_err < 1.0, "{axis_err}°");
        assert!((fit.primitive.size.x - 0.3).abs() < 0.006 && (fit.primitive.size.z - 0.7).abs() < 0.008, "{}", fit.primitive.size);
    }

    #[test]
    fn picks_a_sphere_for_sphere_points() {
        let truth = Primitive::new(PrimitiveKind::Sphere, Vec3::splat(0.35), pose(Vec3::new(-1.0, 0.5, 1.0), 0.0, 0.0, 0.0));
        let fit = fit_part(&noisy(&truth, 3000, 3), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Sphere, "{:?}", fit.candidates);
        assert!((fit.primitive.size.x - 0.35).abs() < 0.005, "{}", fit.primitive.size);
        assert!((fit.primitive.center() - truth.center()).length() < 0.003);
    }

    #[test]
    fn picks_a_capsule_for_capsule_points() {
        let truth = Primitive::new(PrimitiveKind::Capsule, Vec3::new(0.2, 0.2, 0.8), pose(Vec3::new(0.5, 0.5, 1.0), 1.2, 0.3, 0.0));
        let fit = fit_part(&noisy(&truth, 3000, 5), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Capsule, "{:?}", fit.candidates);
        assert!(line_angle_deg(fit.primitive.axes_world()[2], truth.axes_world()[2]) < 1.0);
        assert!((fit.primitive.size - truth.size).abs().max_element() < 0.008, "{}", fit.primitive.size);
    }

    #[test]
    fn thin_board_is_a_cuboid_with_the_right_thickness() {
        let truth = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.6, 0.02, 0.8), pose(Vec3::new(0.3, 0.8, 0.5), 0.0, 0.0, 1.1));
        let fit = fit_part(&noisy(&truth, 3000, 4), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Cuboid, "{:?}", fit.candidates);
        let thickness = fit.primitive.size.min_element();
        assert!((thickness - 0.02).abs() < 0.005, "{}", fit.primitive.size);
        // The thin axis is the board's normal.
        let [x, y, z] = fit.primitive.axes_world();
        let thin = [x, y, z][fit.primitive.size.to_array().iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |m| m.0)];
        assert!(line_angle_deg(thin, truth.axes_world()[1]) < 1.0);
    }

    /// Adds σ = 2 mm noise and 1 % outliers to `pts`.
    fn noisy_points(pts: &[Vec3], seed: u64) -> Vec<Vec3> {
        let mut r = rng(seed);
        let noise = Normal::new(0.0_f32, 0.002).expect("valid sigma");
        let mut out: Vec<Vec3> =
            pts.iter().map(|p| *p + Vec3::new(noise.sample(&mut r), noise.sample(&mut r), noise.sample(&mut r))).collect();
        let (lo, hi) = pts.iter().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(l, h), p| (l.min(*p), h.max(*p)));
        for _ in 0..pts.len() / 100 {
            let t = Vec3::new(r.random(), r.random(), r.random());
            let idx = r.random_range(0..out.len());
            out.insert(idx, lo - 0.2 + (hi - lo + 0.4) * t);
        }
        out
    }

    #[test]
    fn partial_scan_of_a_cabinet_is_a_cuboid_of_the_right_size() {
        // Seen from one corner: only the +x, +y and +z faces.
        let truth = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.5, 0.4, 0.9), pose(Vec3::new(1.0, 0.0, 0.45), 0.0, 0.0, 0.4));
        let h = truth.size * 0.5;
        let visible: Vec<Vec3> = truth
            .sample_surface(5000)
            .into_iter()
            .filter(|p| {
                let q = truth.world_from_primitive.inverse_transform_point(*p);
                (q - h).abs().min_element() < 1e-5
            })
            .collect();
        let fit = fit_part(&noisy_points(&visible, 11), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Cuboid, "{:?}", fit.candidates);
        assert!((fit.primitive.center() - truth.center()).length() < 0.01, "{}", fit.primitive.center());
        let mut got = fit.primitive.size.to_array();
        let mut want = truth.size.to_array();
        got.sort_by(f32::total_cmp);
        want.sort_by(f32::total_cmp);
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 0.01, "{got:?} vs {want:?}");
        }
    }

    #[test]
    fn partial_scan_of_a_cylinder_is_a_cylinder() {
        // Seen from the side and above: the half side facing +x and the top cap.
        let truth = Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.3, 0.3, 0.7), pose(Vec3::new(0.0, 2.0, 0.35), 0.0, 0.0, 0.0));
        let visible: Vec<Vec3> = truth
            .sample_surface(5000)
            .into_iter()
            .filter(|p| {
                let q = truth.world_from_primitive.inverse_transform_point(*p);
                q.x > 0.0 || q.z > 0.35 - 1e-5
            })
            .collect();
        let fit = fit_part(&noisy_points(&visible, 12), &FitConfig::default(), None).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Cylinder, "{:?}", fit.candidates);
        assert!(line_angle_deg(fit.primitive.axes_world()[2], Vec3::Z) < 2.0);
        assert!((fit.primitive.size.x - 0.3).abs() < 0.01 && (fit.primitive.size.z - 0.7).abs() < 0.01, "{}", fit.primitive.size);
    }

    #[test]
    fn forced_kind_is_respected() {
        let truth = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.5, 0.4, 0.3), pose(Vec3::ZERO, 0.0, 0.0, 0.0));
        let fit = fit_part(&truth.sample_surface(800), &FitConfig::default(), Some(PrimitiveKind::Sphere)).expect("fits");
        assert_eq!(fit.primitive.kind, PrimitiveKind::Sphere);
        assert!(fit.candidates.iter().all(|c| c.primitive.kind == PrimitiveKind::Sphere));
    }

    #[test]
    fn bad_inputs_are_errors() {
        let three = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert_eq!(fit_part(&three, &FitConfig::default(), None), Err(FitError::TooFewPoints { got: 3, min: 10 }));
        let msg = FitError::TooFewPoints { got: 3, min: 10 }.to_string();
        assert!(msg.contains('3') && msg.contains("10"), "{msg}");
        let mut pts = Primitive::cuboid_at(Vec3::ZERO, Vec3::ONE).sample_surface(100);
        pts[7] = Vec3::new(0.0, f32::NAN, 0.0);
        assert!(matches!(fit_part(&pts, &FitConfig::default(), None), Err(FitError::NonFinite { index: 7, .. })));
        let same = vec![Vec3::ONE; 50];
        assert!(matches!(fit_part(&same, &FitConfig::default(), None), Err(FitError::Degenerate { .. })));
    }

    #[test]
    fn planar_patch_fits_without_panicking() {
        let pts: Vec<Vec3> = (0..400).map(|i| Vec3::new((i % 20) as f32 * 0.02, (i / 20) as f32 * 0.03, 0.7)).collect();
        let fit = fit_part(&pts, &FitConfig::default(), None).expect("fits");
        assert!(fit.fit_error < 0.003, "{}", fit.fit_error);
    }

    /// Timing check, run by hand in release:
    /// `cargo test --release --no-default-features --lib fit::select::tests::timing -- --ignored --nocapture`
    #[test]
    #[ignore = "timing; run in release by hand"]
    fn timing_per_part() {
        let parts = [
            Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.5, 0.4, 0.9), pose(Vec3::ZERO, 0.0, 0.0, 0.4)),
            Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.6, 0.02, 0.8), pose(Vec3::ZERO, 0.0, 0.0, 1.1)),
            Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.3, 0.3, 0.7), pose(Vec3::ZERO, 0.5, 0.2, 0.0)),
            Primitive::new(PrimitiveKind::Sphere, Vec3::splat(0.35), pose(Vec3::ZERO, 0.0, 0.0, 0.0)),
        ];
        let clouds: Vec<Vec<Vec3>> = parts.iter().enumerate().map(|(i, p)| noisy(p, 3000, i as u64)).collect();
        let cfg = FitConfig::default();
        for (cloud, part) in clouds.iter().zip(&parts) {
            let reps = 50;
            let t0 = std::time::Instant::now();
            let mut kind = None;
            for _ in 0..reps {
                kind = Some(fit_part(cloud, &cfg, None).expect("fits").primitive.kind);
            }
            let per = t0.elapsed().as_secs_f64() * 1000.0 / f64::from(reps);
            eprintln!("{:?} ({} points) -> {kind:?}: {per:.3} ms/part", part.kind, cloud.len());
            let t0 = std::time::Instant::now();
            for _ in 0..reps {
                let _ = min_volume_obb(cloud);
            }
            eprintln!("  obb alone: {:.3} ms", t0.elapsed().as_secs_f64() * 1000.0 / f64::from(reps));
        }
    }

    /// Random cuboids, cylinders and spheres (1.5–80 cm extents, any pose), every other one seen
    /// from a single random viewpoint (visible surface only), σ = 2 mm noise and 1 % outliers:
    /// the kind must be right and every extent and the centre within 1 cm, in all but 1 % of the
    /// cases. Slow in a debug build:
    /// `cargo test --release --no-default-features --lib fit::select::tests::robustness -- --ignored`
    #[test]
    #[ignore = "slow; run in release by hand"]
    fn robustness_sweep() {
        let mut r = rng(77);
        let mut failures = Vec::new();
        for trial in 0..100u64 {
            for kind in [PrimitiveKind::Cuboid, PrimitiveKind::Cylinder, PrimitiveKind::Sphere] {
                let size = Vec3::new(r.random_range(0.015..0.8), r.random_range(0.015..0.8), r.random_range(0.015..0.8));
                let centre = Vec3::new(r.random_range(-2.0..2.0), r.random_range(-2.0..2.0), r.random_range(0.0..2.0));
                let truth = Primitive::new(
                    kind,
                    size,
                    pose(centre, r.random_range(-3.0..3.0), r.random_range(-3.0..3.0), r.random_range(-3.0..3.0)),
                );
                let partial = trial % 2 == 1;
                let view = Vec3::new(r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(0.2..1.0)).normalize();
                // Visible: the first hit of a ray from the viewer's side is the point itself.
                let visible = |q: &Vec3| truth.ray_cast(*q + view * 5.0, -view, 10.0).is_some_and(|hit| (hit.0 - 5.0).abs() < 1e-3);
                let pts: Vec<Vec3> = truth.sample_surface(3000).into_iter().filter(|q| !partial || visible(q)).collect();
                if pts.len() < 50 {
                    continue;
                }
                let pts = noisy_points(&pts, trial);
                let fit = fit_part(&pts, &FitConfig::default(), None).expect("fits");
                let mut got = fit.primitive.size.to_array();
                let mut want = truth.size.to_array();
                got.sort_by(f32::total_cmp);
                want.sort_by(f32::total_cmp);
                let size_err = got.iter().zip(want).map(|(g, w)| (g - w).abs()).fold(0.0, f32::max);
                let centre_err = (fit.primitive.center() - truth.center()).length();
                if fit.primitive.kind != kind || size_err > 0.01 || centre_err > 0.01 {
                    failures.push(format!(
                        "trial {trial} (partial {partial}) {kind:?} {} -> {:?} {} (size error {size_err:.3}, centre error {centre_err:.3})",
                        truth.size, fit.primitive.kind, fit.primitive.size
                    ));
                }
            }
        }
        // Known misses: small round parts seen from one side (a 5 cm cylinder's half side is
        // within noise of a box's two faces; ties go to the cuboid).
        assert!(failures.len() <= 3, "{} of 300 off: {failures:#?}", failures.len());
    }

    #[test]
    fn is_deterministic() {
        let truth = Primitive::new(PrimitiveKind::Cuboid, Vec3::new(0.5, 0.4, 0.9), pose(Vec3::ZERO, 0.1, 0.0, 0.4));
        let pts = noisy(&truth, 2000, 9);
        let a = fit_part(&pts, &FitConfig::default(), None).expect("fits");
        let b = fit_part(&pts, &FitConfig::default(), None).expect("fits");
        assert_eq!(a, b);
    }
}
