//! Rigid ICP of a primitive onto a part's points, with optional size re-estimation.
//!
//! Scans are partial, so correspondences go data→model: every point is paired with its analytic
//! closest point on the primitive surface ([`Primitive::closest_surface_point_local`]); surface the
//! scanner never saw attracts nothing. Each iteration drops the worst `trim_fraction` of the
//! residuals (stray points, other parts; never those below 3× the median or below
//! `keep_within_rel` of the part's size, which on clean data are the informative ones), then
//! solves the best rigid update of the model onto the data:
//! - default (`point_to_plane`): one damped Gauss–Newton step on the point-to-plane distances
//!   `nᵢ·(R cᵢ + t − pᵢ)`. Point-to-point ICP converges linearly, moving each step only by the
//!   share of points whose normals see the error: a door board (96 % of its points on its two
//!   big faces) slides along its face by ~4 % of the offset per iteration;
//! - fallback, or with `point_to_plane = false`: Kabsch on the centred pairs
//!   ([`kabsch_rotation`]), the classic Besl–McKay update.
//!
//! Spheres only translate; the twist of cylinders and capsules about their own axis is dropped
//! (it moves no surface). The result is the best primitive seen (mean residual truncated at a
//! cap fixed on the first iteration); iteration stops on convergence or after three iterations
//! without improvement (discrete face assignments can make the resize cycle).
//!
//! With `refit_size`, the size is re-estimated along the primitive's own axes after each rigid
//! step, in the primitive frame. Points are assigned to the face, side or cap they are closest
//! to, measured against the data's own robust extent (2 %/98 % quantiles per axis), not against
//! the model, which a stray point may have inflated or shifted:
//! - a planar face pair (cuboid faces, cylinder caps): the median coordinate of the points on
//!   each face (unbiased under zero-mean noise, unlike extreme percentiles). A face counts as
//!   seen only with points in its central region (points overhanging from a neighbouring face
//!   hug its border); a face nobody saw is placed from the 0.5 %/99.5 % quantiles of the other
//!   points along that axis, corrected for their uniform spread (`lo = (p − 0.005·hi)/0.995`);
//!   with no evidence at all the extent is kept. Two "faces" closer than six times their spread
//!   are one flat surface split by a tilted model: the extent is kept and the model is turned
//!   onto the surface's plane instead (ICP alone stalls there, the points lying between the
//!   model's faces). These statistics use all points (robust ones), not the trimmed set, which
//!   would drop exactly the points overhanging a too-small model;
//! - round surfaces: up to three Gauss–Newton steps of a geometric circle fit (cylinder and
//!   capsule sides, in the cross-section) or sphere fit on the inliers, which recovers radius
//!   *and* axis from a half-seen side (arcs under ~60° are rejected: flat data has no radius);
//! - capsule caps: a Gauss–Newton fit of each seen hemisphere gives the end of the axis segment.
//!
//! The kind's constraints are then re-imposed by [`PrimitiveKind::normalize_size`]. Size steps are
//! limited to a factor of two per iteration and to 1.25× the data's diameter.

use super::obb::MIN_EXTENT_M;
use super::{quantile_in_place, solve_linear};
use crate::math::{DVec3, Pose, Quat, Vec2, Vec3, kabsch_rotation};
use crate::primitive::{Primitive, PrimitiveKind};

/// ICP settings.
#[derive(Clone, Debug, PartialEq)]
pub struct IcpConfig {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Fraction of the largest residuals ignored in each update, in [0, 0.9].
    pub trim_fraction: f32,
    /// Residuals below this fraction of the primitive's largest extent are never trimmed.
    pub keep_within_rel: f32,
    /// Re-estimate the size along the primitive's own axes (see the module docs).
    pub refit_size: bool,
    /// Rigid update by point-to-plane Gauss–Newton (default) instead of point-to-point Kabsch.
    pub point_to_plane: bool,
    /// Converged when an update rotates by less than this (radians) ...
    pub min_rotation_step_rad: f32,
    /// ... and moves (and resizes, with `refit_size`) by less than this (metres).
    pub min_translation_step_m: f32,
}

impl Default for IcpConfig {
    fn default() -> Self {
        Self {
            max_iterations: 20,
            trim_fraction: 0.1,
            keep_within_rel: 0.03,
            refit_size: false,
            point_to_plane: true,
            min_rotation_step_rad: 1e-4,
            min_translation_step_m: 1e-4,
        }
    }
}

/// The outcome of [`icp_align`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IcpResult {
    /// The aligned primitive.
    pub primitive: Primitive,
    /// Mean point→surface distance over all (finite) input points at the final pose, metres
    /// (0 for an empty input).
    pub mean_error: f32,
    /// Iterations run (each one a correspondence search plus an update).
    pub iterations: usize,
}

/// Aligns `initial` to `points` (world frame) by trimmed point-to-surface ICP.
///
/// Never panics: non-finite points are ignored, an update that would make the pose or size
/// non-finite ends the iteration with the last good primitive.
#[must_use]
pub fn icp_align(initial: &Primitive, points: &[Vec3], cfg: &IcpConfig) -> IcpResult {
    let points: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let mut prim = *initial;
    prim.size = prim.kind.normalize_size(prim.size);
    if points.is_empty() {
        return IcpResult { primitive: prim, mean_error: 0.0, iterations: 0 };
    }
    let trim = cfg.trim_fraction.clamp(0.0, 0.9);
    let (lo, hi) = points.iter().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(l, h), p| (l.min(*p), h.max(*p)));
    let data_diameter = (hi - lo).length().max(MIN_EXTENT_M);
    let n = points.len();
    let mut local = vec![Vec3::ZERO; n];
    let mut closest = vec![Vec3::ZERO; n];
    let mut resid = vec![0.0_f32; n];
    let mut scratch = vec![0.0_f32; n];
    let mut from = Vec::new();
    let mut to = Vec::new();
    let mut moved: Vec<Vec3> = Vec::with_capacity(n);
    let mut inlier: Vec<bool> = Vec::with_capacity(n);
    let mut iterations = 0;
    // The best primitive seen: ICP is not monotone once sizes change.
    let mut best: Option<(f64, Primitive)> = None;
    let mut converged = false;
    let mut stalled = 0usize;
    let mut objective_cap: Option<f32> = None;

    loop {
        let pose = prim.world_from_primitive;
        for i in 0..n {
            local[i] = pose.inverse_transform_point(points[i]);
            closest[i] = prim.closest_surface_point_local(local[i]);
            resid[i] = (local[i] - closest[i]).length();
        }
        scratch.copy_from_slice(&resid);
        let q = quantile_in_place(&mut scratch, 1.0 - trim).unwrap_or(f32::INFINITY);
        let median = quantile_in_place(&mut scratch, 0.5).unwrap_or(0.0);
        // The objective tracked across iterations: the mean residual truncated at a cap fixed
        // on the first iteration (so every point counts, and strays count at most the cap).
        let cap = *objective_cap.get_or_insert((3.0 * median).max(cfg.keep_within_rel * prim.size.max_element()).max(1e-6));
        let objective = resid.iter().map(|r| f64::from(r.min(cap))).sum::<f64>() / n as f64;
        match &best {
            Some(b) if objective >= b.0 * (1.0 - 1e-3) => stalled += 1,
            _ => stalled = 0,
        }
        if best.as_ref().is_none_or(|b| objective < b.0) {
            best = Some((objective, prim));
        }
        // Stop when converged, or when the objective has not improved for a few iterations
        // (discrete face assignments can make the resize cycle between two states).
        if converged || stalled >= 3 || iterations >= cfg.max_iterations {
            break;
        }
        iterations += 1;
        // Trim the worst residuals, but never those below 3× the median or below a small
        // fraction of the part's size: on clean data the largest residuals are the informative
        // ones (the far ends of a rotation error, the edge faces of a board that slid).
        let threshold = if trim > 0.0 { q.max(3.0 * median).max(cfg.keep_within_rel * prim.size.max_element()) } else { f32::INFINITY };

        // Rigid update: model (closest points) onto data (points), both in the primitive frame.
        let update = if cfg.point_to_plane { point_to_plane_update(&prim, &local, &closest, &resid, threshold) } else { None };
        let Some((rot, trans)) = update.or_else(|| kabsch_update(prim.kind, &local, &closest, &resid, threshold, &mut from, &mut to))
        else {
            break;
        };
        // New world_from_primitive = old ∘ delta, delta mapping model onto data.
        let mut next = prim;
        next.world_from_primitive = Pose::from_parts(pose.transform_point(trans), (pose.rotation * rot).normalize());
        if !next.world_from_primitive.is_finite() {
            break;
        }
        if cfg.refit_size {
            moved.clear();
            inlier.clear();
            for i in 0..n {
                // The same point in the updated frame: delta⁻¹ · local.
                moved.push(rot.inverse() * (local[i] - trans));
                inlier.push(resid[i] <= threshold);
            }
            if let Some((size, shift, correction)) = refit_size(next.kind, next.size, &moved, &inlier) {
                // No extent beyond the data's own diameter (with a margin): a primitive that
                // swallows the points has no surface near them to pull it back.
                let size = next.kind.normalize_size(size.min(Vec3::splat(1.25 * data_diameter)));
                let center = next.world_from_primitive.transform_point(shift);
                if size.is_finite() && center.is_finite() {
                    next.size = size;
                    next.world_from_primitive.translation = center;
                    next.world_from_primitive.rotation = (next.world_from_primitive.rotation * correction).normalize();
                }
            }
        }
        // Converged when the whole iteration (rigid step and resize) barely changed anything.
        let rot_step = next.rotation().angle_between(prim.rotation());
        let move_step = (next.center() - prim.center()).length().max((next.size - prim.size).abs().max_element());
        converged = rot_step < cfg.min_rotation_step_rad && move_step < cfg.min_translation_step_m;
        prim = next;
    }

    let prim = best.map_or(prim, |b| b.1);
    let mean_error = points.iter().map(|p| f64::from(prim.surface_distance(*p))).sum::<f64>() / n as f64;
    IcpResult { primitive: prim, mean_error: mean_error as f32, iterations }
}

/// Point-to-point update (Kabsch on the centred inlier pairs): the rotation and translation
/// taking the model points onto the data points.
fn kabsch_update(
    kind: PrimitiveKind,
    local: &[Vec3],
    closest: &[Vec3],
    resid: &[f32],
    threshold: f32,
    from: &mut Vec<Vec3>,
    to: &mut Vec<Vec3>,
) -> Option<(Quat, Vec3)> {
    let (mut c_from, mut c_to, mut count) = (DVec3::ZERO, DVec3::ZERO, 0usize);
    for i in 0..local.len() {
        if resid[i] <= threshold {
            c_from += closest[i].as_dvec3();
            c_to += local[i].as_dvec3();
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let c_from = (c_from / count as f64).as_vec3();
    let c_to = (c_to / count as f64).as_vec3();
    from.clear();
    to.clear();
    for i in 0..local.len() {
        if resid[i] <= threshold {
            from.push(closest[i] - c_from);
            to.push(local[i] - c_to);
        }
    }
    let rot = match kind {
        PrimitiveKind::Sphere => Quat::IDENTITY,
        PrimitiveKind::Cylinder | PrimitiveKind::Capsule => drop_twist_z(kabsch_rotation(from, to, None)),
        PrimitiveKind::Cuboid => kabsch_rotation(from, to, None),
    };
    Some((rot, c_to - rot * c_from))
}

/// Point-to-plane update: one damped Gauss–Newton step on `Σ (nᵢ·(R cᵢ + t − pᵢ))²` over the
/// inliers, `nᵢ` the surface normal at the closest point `cᵢ`. Converges in a few iterations
/// where the point-to-point update only moves by the share of points whose normals see the
/// error (a board slides along its face by the few percent of points on its edges).
/// `None` when the system is degenerate.
#[allow(clippy::needless_range_loop)] // (row, column) index pairs of a symmetric 6×6 system
fn point_to_plane_update(prim: &Primitive, local: &[Vec3], closest: &[Vec3], resid: &[f32], threshold: f32) -> Option<(Quat, Vec3)> {
    let mut a = [[0.0_f64; 6]; 6];
    let mut b = [0.0_f64; 6];
    let mut count = 0usize;
    for i in 0..local.len() {
        if resid[i] > threshold {
            continue;
        }
        let (p, c) = (local[i], closest[i]);
        let n = surface_normal_local(prim, c, p).as_dvec3();
        let cd = c.as_dvec3();
        let cn = cd.cross(n);
        let j = [cn.x, cn.y, cn.z, n.x, n.y, n.z];
        let e = n.dot(cd - p.as_dvec3());
        for (r, jr) in j.iter().enumerate() {
            for (cidx, jc) in j.iter().enumerate().skip(r) {
                a[r][cidx] += jr * jc;
            }
            b[r] -= jr * e;
        }
        count += 1;
    }
    if count < 3 {
        return None;
    }
    let trace: f64 = (0..6).map(|k| a[k][k]).sum();
    for r in 0..6 {
        for c in 0..r {
            a[r][c] = a[c][r];
        }
        // Marquardt damping plus a floor: directions the data cannot see (a body of
        // revolution's twist, a lone face's sliding) stay put instead of drifting.
        a[r][r] = a[r][r] * (1.0 + 1e-6) + 1e-9 * trace;
    }
    let x = solve_linear(a, b)?;
    let mut omega = Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
    let trans = Vec3::new(x[3] as f32, x[4] as f32, x[5] as f32);
    match prim.kind {
        PrimitiveKind::Sphere => omega = Vec3::ZERO,
        PrimitiveKind::Cylinder | PrimitiveKind::Capsule => omega.z = 0.0,
        PrimitiveKind::Cuboid => {}
    }
    // A linearised step: keep it small (the next iteration continues).
    let angle = omega.length();
    if angle > 0.2 {
        omega *= 0.2 / angle;
    }
    (omega.is_finite() && trans.is_finite()).then(|| (Quat::from_scaled_axis(omega), trans))
}

/// Unit normal for the point-to-plane residual at surface point `c` (primitive frame) for data
/// point `p`: the direction from `c` to `p` when they are apart (edges and corners included),
/// otherwise the analytic surface normal at `c`.
fn surface_normal_local(prim: &Primitive, c: Vec3, p: Vec3) -> Vec3 {
    let d = p - c;
    let scale = prim.size.max_element().max(MIN_EXTENT_M);
    if d.length() > 1e-4 * scale {
        return d.normalize_or(Vec3::Z);
    }
    let h = prim.size * 0.5;
    match prim.kind {
        PrimitiveKind::Cuboid => {
            let rel = c.abs() - h;
            if rel.x >= rel.y && rel.x >= rel.z {
                Vec3::X * c.x.signum()
            } else if rel.y >= rel.z {
                Vec3::Y * c.y.signum()
            } else {
                Vec3::Z * c.z.signum()
            }
        }
        PrimitiveKind::Cylinder => {
            let rho = Vec2::new(c.x, c.y).length();
            if h.z - c.z.abs() < h.x - rho { Vec3::Z * c.z.signum() } else { Vec3::new(c.x, c.y, 0.0).normalize_or(Vec3::X) }
        }
        PrimitiveKind::Sphere => c.normalize_or(Vec3::Z),
        PrimitiveKind::Capsule => {
            let a = (h.z - h.x).max(0.0);
            (c - Vec3::new(0.0, 0.0, c.z.clamp(-a, a))).normalize_or(Vec3::X)
        }
    }
}

/// The swing part of `q` (its twist about z removed): rotations of a body of revolution about
/// its own axis move no surface.
fn drop_twist_z(q: Quat) -> Quat {
    let twist = Quat::from_xyzw(0.0, 0.0, q.z, q.w);
    if twist.length_squared() < 1e-12 {
        return q; // a half-turn swing: no well-defined twist
    }
    (q * twist.normalize().inverse()).normalize()
}

/// Collects the coordinates of the points on the + and − face of one axis.
///
/// A face counts as seen only when some of its points lie in its central region: points of a
/// neighbouring face that overhang the box are assigned to this face too, but they hug its
/// border (and their mean would only creep outwards).
#[derive(Default)]
struct FacePair {
    coords: [Vec<f32>; 2],
    central: [usize; 2],
    /// The points themselves (both faces), for the plane of a [`Faces::OneSurface`].
    points: Vec<Vec3>,
}

/// What the points on a pair of opposite faces say.
enum Faces {
    /// Median position of the + and of the − face, where seen.
    Seen { plus: Option<f32>, minus: Option<f32> },
    /// The two "faces" are closer than six times their spread (median absolute deviation):
    /// one surface split in two (a thin box tilted against a flat scan).
    OneSurface,
}

impl FacePair {
    /// Adds a point on the − (`minus`) or + face.
    fn add(&mut self, point: Vec3, coord: f32, minus: bool, central: bool) {
        let s = usize::from(minus);
        self.coords[s].push(coord);
        self.central[s] += usize::from(central);
        self.points.push(point);
    }

    /// The rotation (primitive frame) turning `axis` onto the normal of the plane through the
    /// points (their least principal axis), at most 0.3 rad; `None` without enough points.
    fn plane_correction(&self, axis: Vec3, min_count: usize) -> Option<Quat> {
        if self.points.len() < min_count.max(3) {
            return None;
        }
        let (_, axes) = crate::math::principal_axes(&self.points);
        let n = axes.z_axis;
        let n = if n.dot(axis) < 0.0 { -n } else { n };
        let q = Quat::from_rotation_arc(axis, n.normalize_or(axis));
        let angle = q.angle_between(Quat::IDENTITY);
        if !angle.is_finite() {
            return None;
        }
        Some(if angle > 0.3 { Quat::IDENTITY.slerp(q, 0.3 / angle) } else { q })
    }

    /// Median positions (the median: stray points are not trimmed away here, see
    /// [`refit_size`]).
    fn positions(&mut self, min_count: usize) -> Faces {
        let mut at = |s: usize| {
            let count = self.coords[s].len();
            let seen = count >= min_count && self.central[s] >= (count / 10).max(2);
            if !seen {
                return None;
            }
            let median = quantile_in_place(&mut self.coords[s], 0.5)?;
            let mut dev: Vec<f32> = self.coords[s].iter().map(|c| (c - median).abs()).collect();
            Some((median, quantile_in_place(&mut dev, 0.5).unwrap_or(0.0)))
        };
        match (at(0), at(1)) {
            (Some((hi, mad_hi)), Some((lo, mad_lo))) if hi - lo <= 6.0 * mad_hi.max(mad_lo) => Faces::OneSurface,
            (plus, minus) => Faces::Seen { plus: plus.map(|p| p.0), minus: minus.map(|m| m.0) },
        }
    }
}

/// The 2 % and 98 % quantiles of `values` (the data's own robust extent, a little inside it,
/// never widened by a stray point or two), or `None`.
fn rough_interval(values: &mut [f32]) -> Option<(f32, f32)> {
    let lo = quantile_in_place(values, 0.02)?;
    let hi = quantile_in_place(values, 0.98)?;
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi.max(lo)))
}

/// New (size, centre shift in the primitive frame, rotation correction in the primitive frame)
/// from the points in the primitive frame.
///
/// Points are assigned to faces against the data's own robust extent along each axis (not the
/// current model, which may be inflated by a stray point or offset). Extents use *all* points
/// with robust statistics (face medians, percentiles): the trimmed set would lose exactly the
/// points that overhang a too-small model, which is the evidence that it must grow. Radii use
/// the trimmed `inlier` points (least-squares fits).
fn refit_size(kind: PrimitiveKind, size: Vec3, pts: &[Vec3], inlier: &[bool]) -> Option<(Vec3, Vec3, Quat)> {
    let min_count = (pts.len() / 100).max(5);
    if pts.len() < min_count || inlier.len() != pts.len() {
        return None;
    }
    let mut correction = Quat::IDENTITY;
    let h = size * 0.5;
    let mut buf: Vec<f32> = Vec::with_capacity(pts.len());
    let (new_size, shift) = match kind {
        PrimitiveKind::Cuboid => {
            let mut rough = [(0.0_f32, 0.0_f32); 3];
            for (k, r) in rough.iter_mut().enumerate() {
                buf.clear();
                buf.extend(pts.iter().map(|p| p[k]));
                *r = rough_interval(&mut buf)?;
            }
            let rc = Vec3::new(rough[0].0 + rough[0].1, rough[1].0 + rough[1].1, rough[2].0 + rough[2].1) * 0.5;
            let rh = (Vec3::new(rough[0].1 - rough[0].0, rough[1].1 - rough[1].0, rough[2].1 - rough[2].0) * 0.5)
                .max(Vec3::splat(0.5 * MIN_EXTENT_M));
            let mut faces: [FacePair; 3] = Default::default();
            let mut assigned: Vec<(usize, usize)> = Vec::with_capacity(pts.len()); // (axis, side)
            for p in pts {
                let d = *p - rc;
                let excess = d.abs() - rh;
                let k = if excess.x >= excess.y && excess.x >= excess.z {
                    0
                } else if excess.y >= excess.z {
                    1
                } else {
                    2
                };
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                let central = d[i].abs() < 0.5 * rh[i] && d[j].abs() < 0.5 * rh[j];
                faces[k].add(*p, p[k], d[k] < 0.0, central);
                assigned.push((k, usize::from(d[k] < 0.0)));
            }
            let mut size_new = size;
            let mut shift = Vec3::ZERO;
            let mut tilt_support = 0usize;
            for (k, face) in faces.iter_mut().enumerate() {
                let (lo, hi) = match face.positions(min_count) {
                    Faces::Seen { plus, minus } => {
                        let seen = [plus.is_some(), minus.is_some()];
                        // Every point not on a seen face of this axis spreads over the axis'
                        // interval (points overhanging a too-small model included).
                        buf.clear();
                        buf.extend(pts.iter().zip(&assigned).filter(|(_, (a, s))| *a != k || !seen[*s]).map(|(p, _)| p[k]));
                        interval(plus, minus, &mut buf, rough[k], size[k], min_count)
                    }
                    // Not observable while the box is tilted against the surface: keep the
                    // extent (growing it to the data's spread feeds the tilt) and turn the box
                    // onto the surface's plane instead (ICP alone stalls there: the points lie
                    // inside the box, between its faces).
                    Faces::OneSurface => {
                        if face.points.len() > tilt_support
                            && let Some(q) = face.plane_correction(Vec3::AXES[k], min_count)
                        {
                            tilt_support = face.points.len();
                            correction = q;
                        }
                        (-h[k], h[k])
                    }
                };
                size_new[k] = hi - lo;
                shift[k] = 0.5 * (lo + hi);
            }
            (size_new, shift)
        }
        PrimitiveKind::Cylinder => {
            let r = h.x;
            buf.clear();
            buf.extend(pts.iter().map(|p| p.z));
            let rough = rough_interval(&mut buf)?;
            let (rcz, rhz) = (0.5 * (rough.0 + rough.1), (0.5 * (rough.1 - rough.0)).max(0.5 * MIN_EXTENT_M));
            let mut caps = FacePair::default();
            let mut side_xy = Vec::new();
            let mut lateral = Vec::new();
            let mut cap_xy = Vec::new();
            for (p, ok) in pts.iter().zip(inlier) {
                let rho = Vec2::new(p.x, p.y).length();
                if rho - r > (p.z - rcz).abs() - rhz {
                    if *ok {
                        side_xy.push(Vec2::new(p.x, p.y));
                    }
                    lateral.push(p.z);
                } else {
                    caps.add(*p, p.z, p.z < rcz, rho < 0.5 * r);
                    if *ok {
                        cap_xy.push(Vec2::new(p.x, p.y));
                    }
                }
            }
            let (centre, radius) = round_cross_section(&side_xy, &mut cap_xy, r, min_count);
            let (lo, hi) = match caps.positions(min_count) {
                Faces::Seen { plus, minus } => {
                    for (s, seen) in [plus.is_some(), minus.is_some()].into_iter().enumerate() {
                        if !seen {
                            lateral.extend_from_slice(&caps.coords[s]);
                        }
                    }
                    interval(plus, minus, &mut lateral, rough, size.z, min_count)
                }
                Faces::OneSurface => {
                    if let Some(q) = caps.plane_correction(Vec3::Z, min_count) {
                        correction = q;
                    }
                    (-h.z, h.z)
                }
            };
            (Vec3::new(2.0 * radius, 2.0 * radius, hi - lo), Vec3::new(centre.x, centre.y, 0.5 * (lo + hi)))
        }
        PrimitiveKind::Sphere => {
            let kept: Vec<Vec3> = pts.iter().zip(inlier).filter(|(_, ok)| **ok).map(|(p, _)| *p).collect();
            let (centre, radius) = sphere_fit_gn(&kept, h.x)?;
            (Vec3::splat(2.0 * radius), centre)
        }
        PrimitiveKind::Capsule => {
            let r = h.x;
            let a = (h.z - r).max(0.0);
            let mut ends = FacePair::default();
            let mut side_xy = Vec::new();
            let mut lateral = Vec::new();
            let (mut radial_sum, mut radial_count) = (0.0_f64, 0usize);
            for (p, ok) in pts.iter().zip(inlier) {
                if *ok {
                    let on_axis = Vec3::new(0.0, 0.0, p.z.clamp(-a, a));
                    radial_sum += f64::from((*p - on_axis).length());
                    radial_count += 1;
                }
                if p.z.abs() <= a {
                    if *ok {
                        side_xy.push(Vec2::new(p.x, p.y));
                    }
                    lateral.push(p.z);
                } else {
                    // This cap point's vote for the end of the axis segment.
                    let rho2 = p.x * p.x + p.y * p.y;
                    let lift = (r * r - rho2).max(0.0).sqrt();
                    ends.add(*p, p.z - lift * p.z.signum(), p.z < 0.0, rho2 < 0.25 * r * r);
                }
            }
            let fit = if side_xy.len() >= min_count { circle_fit_gn(&side_xy, r) } else { None };
            let mean_radial = if radial_count > 0 { (radial_sum / radial_count as f64) as f32 } else { r };
            let (centre, radius) = fit.unwrap_or((Vec2::ZERO, mean_radial));
            let (lo, hi) = match ends.positions(min_count) {
                Faces::Seen { plus, minus } => {
                    for (s, seen) in [plus.is_some(), minus.is_some()].into_iter().enumerate() {
                        if !seen {
                            lateral.extend_from_slice(&ends.coords[s]);
                        }
                    }
                    // The median vote is a start; a geometric fit of the hemisphere (all its
                    // points, the rim weighted down) finds the end (votes of rim points are
                    // biased by noise).
                    let axis = Vec3::new(centre.x, centre.y, 0.0);
                    let refine = |start: f32, sign: f32| {
                        let cap: Vec<Vec3> = ends.points.iter().filter(|p| p.z * sign > 0.0).map(|p| *p - axis).collect();
                        cap_end_fit(&cap, start, radius)
                    };
                    let plus = plus.map(|e| refine(e, 1.0));
                    let minus = minus.map(|e| refine(e, -1.0));
                    interval(plus, minus, &mut lateral, (-a, a), 2.0 * a, min_count)
                }
                Faces::OneSurface => (-a, a),
            };
            let length = (hi - lo).max(0.0) + 2.0 * radius;
            (Vec3::new(2.0 * radius, 2.0 * radius, length), Vec3::new(centre.x, centre.y, 0.5 * (lo + hi)))
        }
    };
    // At most a factor of two per step; never below the minimum extent.
    let new_size = new_size.clamp(size * 0.5, size * 2.0).max(Vec3::splat(MIN_EXTENT_M));
    (new_size.is_finite() && shift.is_finite() && correction.is_finite()).then_some((new_size, shift, correction))
}

/// The end `e` of a capsule's axis segment (on z) whose hemisphere of radius `r` best fits the
/// cap points: Gauss–Newton on `|p − (0, 0, e)| − r`, from `start`.
fn cap_end_fit(cap: &[Vec3], start: f32, r: f32) -> f32 {
    let mut e = f64::from(start);
    let r = f64::from(r);
    for _ in 0..3 {
        let (mut num, mut den) = (0.0_f64, 0.0_f64);
        for p in cap {
            let d = Vec3::new(p.x, p.y, p.z - e as f32).as_dvec3();
            let len = d.length();
            if len < 1e-9 {
                continue;
            }
            let j = -d.z / len;
            num += (len - r) * j;
            den += j * j;
        }
        if den <= 1e-12 {
            break;
        }
        let step = -num / den;
        e += step.clamp(-r, r);
        if step.abs() < 1e-7 {
            break;
        }
    }
    if e.is_finite() { e as f32 } else { start }
}

/// Centre (cross-section) and radius of a round surface: a circle fit on the side points, or
/// from the spread of the cap points when the side was not seen, else unchanged.
fn round_cross_section(side_xy: &[Vec2], cap_xy: &mut [Vec2], r: f32, min_count: usize) -> (Vec2, f32) {
    if side_xy.len() >= min_count
        && let Some(fit) = circle_fit_gn(side_xy, r)
    {
        return fit;
    }
    if cap_xy.len() >= min_count {
        // Cap points are area-uniform on a disk: ρ² is uniform on [0, r²].
        let n = cap_xy.len() as f32;
        let centre = cap_xy.iter().fold(Vec2::ZERO, |s, p| s + *p) / n;
        let mut rho2: Vec<f32> = cap_xy.iter().map(|p| (*p - centre).length_squared()).collect();
        if let Some(q) = quantile_in_place(&mut rho2, 0.98) {
            let radius = (q / 0.98).sqrt();
            if radius.is_finite() && radius > 0.0 {
                return (centre, radius);
            }
        }
    }
    (Vec2::ZERO, r)
}

/// Geometric circle fit (centre, radius) by Gauss–Newton from centre 0 and radius `r0`.
fn circle_fit_gn(pts: &[Vec2], r0: f32) -> Option<(Vec2, f32)> {
    let (mut cx, mut cy, mut r) = (0.0_f64, 0.0_f64, f64::from(r0));
    for _ in 0..3 {
        let mut a = [[0.0_f64; 3]; 3];
        let mut b = [0.0_f64; 3];
        for p in pts {
            let (dx, dy) = (f64::from(p.x) - cx, f64::from(p.y) - cy);
            let dist = (dx * dx + dy * dy).sqrt();
            if dist < 1e-9 {
                continue;
            }
            let j = [-dx / dist, -dy / dist, -1.0];
            let e = dist - r;
            for (row, jr) in a.iter_mut().zip(j) {
                for (v, jc) in row.iter_mut().zip(j) {
                    *v += jr * jc;
                }
            }
            for (v, jr) in b.iter_mut().zip(j) {
                *v -= jr * e;
            }
        }
        let step = solve_linear(a, b)?;
        cx += step[0];
        cy += step[1];
        r += step[2];
        if step.iter().map(|v| v.abs()).fold(0.0, f64::max) < 1e-7 {
            break;
        }
    }
    // An arc narrower than ~60° (mean resultant length of the directions > 0.95) pins neither
    // the radius nor the centre: flat data would send the radius to infinity.
    let c = Vec2::new(cx as f32, cy as f32);
    let resultant = pts.iter().fold(Vec2::ZERO, |s, p| s + (*p - c).normalize_or_zero()).length() / pts.len().max(1) as f32;
    (r.is_finite() && r > 0.0 && resultant < 0.95).then_some((c, r as f32))
}

/// Geometric sphere fit (centre, radius) by Gauss–Newton from centre 0 and radius `r0`.
fn sphere_fit_gn(pts: &[Vec3], r0: f32) -> Option<(Vec3, f32)> {
    let mut c = DVec3::ZERO;
    let mut r = f64::from(r0);
    for _ in 0..3 {
        let mut a = [[0.0_f64; 4]; 4];
        let mut b = [0.0_f64; 4];
        for p in pts {
            let d = p.as_dvec3() - c;
            let dist = d.length();
            if dist < 1e-9 {
                continue;
            }
            let u = d / dist;
            let j = [-u.x, -u.y, -u.z, -1.0];
            let e = dist - r;
            for (row, jr) in a.iter_mut().zip(j) {
                for (v, jc) in row.iter_mut().zip(j) {
                    *v += jr * jc;
                }
            }
            for (v, jr) in b.iter_mut().zip(j) {
                *v -= jr * e;
            }
        }
        let step = solve_linear(a, b)?;
        c += DVec3::new(step[0], step[1], step[2]);
        r += step[3];
        if step.iter().map(|v| v.abs()).fold(0.0, f64::max) < 1e-7 {
            break;
        }
    }
    // A cap narrower than ~25° half-angle pins neither the radius nor the centre.
    let cf = c.as_vec3();
    let resultant = pts.iter().fold(Vec3::ZERO, |s, p| s + (*p - cf).normalize_or_zero()).length() / pts.len().max(1) as f32;
    (r.is_finite() && r > 0.0 && c.is_finite() && resultant < 0.95).then_some((cf, r as f32))
}

/// The interval [lo, hi] of one axis from the positions of its two faces (when seen) and the
/// coordinates of the points on the other faces (`lateral`, uniform over the interval).
/// `rough` (the data's own extent) stands in when there is no evidence at all; `span` (the
/// current extent) when one face is seen and nothing else.
fn interval(plus: Option<f32>, minus: Option<f32>, lateral: &mut [f32], rough: (f32, f32), span: f32, min_count: usize) -> (f32, f32) {
    const Q: f32 = 0.005;
    let lat = if lateral.len() >= min_count { quantile_in_place(lateral, Q).zip(quantile_in_place(lateral, 1.0 - Q)) } else { None };
    let (lo, hi) = match (minus, plus) {
        (Some(lo), Some(hi)) => (lo, hi),
        (None, Some(hi)) => (lat.map_or(hi - span, |(pl, _)| (pl - Q * hi) / (1.0 - Q)), hi),
        (Some(lo), None) => (lo, lat.map_or(lo + span, |(_, ph)| (ph - Q * lo) / (1.0 - Q))),
        (None, None) => lat.map_or(rough, |(pl, ph)| {
            let half = 0.5 * (ph - pl) / (1.0 - 2.0 * Q);
            let mid = 0.5 * (pl + ph);
            (mid - half, mid + half)
        }),
    };
    if !(lo.is_finite() && hi.is_finite()) {
        return rough;
    }
    if hi - lo < MIN_EXTENT_M {
        let mid = 0.5 * (lo + hi);
        return (mid - 0.5 * MIN_EXTENT_M, mid + 0.5 * MIN_EXTENT_M);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng;
    use rand::Rng;
    use rand_distr::{Distribution, Normal};

    fn true_box() -> Primitive {
        Primitive::new(
            PrimitiveKind::Cuboid,
            Vec3::new(0.6, 0.4, 0.8),
            Pose::from_parts(Vec3::new(1.0, -0.5, 0.4), Quat::from_euler(glam::EulerRot::XYZ, 0.1, -0.2, 0.7)),
        )
    }

    /// The true primitive displaced by a small known offset (3 cm, 4°).
    fn perturbed(p: &Primitive) -> Primitive {
        let mut q = *p;
        let delta = Quat::from_axis_angle(Vec3::new(0.3, -0.5, 0.8).normalize(), 4f32.to_radians());
        q.world_from_primitive = Pose::from_parts(p.center() + Vec3::new(0.02, -0.015, 0.01), delta * p.rotation());
        q
    }

    fn assert_pose_close(got: &Primitive, want: &Primitive) {
        let dt = (got.center() - want.center()).length();
        let da = got.rotation().angle_between(want.rotation()).to_degrees();
        assert!(dt < 0.001, "translation off by {dt} m");
        assert!(da < 0.5, "rotation off by {da}°");
    }

    #[test]
    fn recovers_a_cuboid_pose_from_its_full_surface() {
        let truth = true_box();
        let pts = truth.sample_surface(2000);
        for point_to_plane in [true, false] {
            let cfg = IcpConfig { point_to_plane, max_iterations: 30, ..IcpConfig::default() };
            let res = icp_align(&perturbed(&truth), &pts, &cfg);
            assert_pose_close(&res.primitive, &truth);
            assert!(res.mean_error < 1e-3, "{}", res.mean_error);
        }
    }

    #[test]
    fn recovers_a_cuboid_pose_from_three_visible_faces() {
        let truth = true_box();
        // Keep only the +x, +y and +z faces (as seen from one corner).
        let pts: Vec<Vec3> = truth
            .sample_surface(3000)
            .into_iter()
            .filter(|p| {
                let q = truth.world_from_primitive.inverse_transform_point(*p);
                let h = truth.size * 0.5;
                (q.x - h.x).abs() < 1e-5 || (q.y - h.y).abs() < 1e-5 || (q.z - h.z).abs() < 1e-5
            })
            .collect();
        assert!(pts.len() > 1000 && pts.len() < 2000);
        let res = icp_align(&perturbed(&truth), &pts, &IcpConfig::default());
        assert_pose_close(&res.primitive, &truth);
        assert!(res.iterations < 20, "point-to-plane took {} iterations", res.iterations);
        // The point-to-point (Kabsch) update gets there too, more slowly.
        let cfg = IcpConfig { max_iterations: 40, point_to_plane: false, ..IcpConfig::default() };
        let res = icp_align(&perturbed(&truth), &pts, &cfg);
        assert_pose_close(&res.primitive, &truth);
        // With size re-estimation from a wrong initial size.
        let mut start = perturbed(&truth);
        start.size = truth.size * Vec3::new(1.1, 0.92, 1.05);
        let cfg = IcpConfig { refit_size: true, ..IcpConfig::default() };
        let res = icp_align(&start, &pts, &cfg);
        assert_pose_close(&res.primitive, &truth);
        assert!((res.primitive.size - truth.size).abs().max_element() < 0.005, "{}", res.primitive.size);
    }

    #[test]
    fn slides_a_thin_board_along_its_face() {
        let truth = Primitive::new(
            PrimitiveKind::Cuboid,
            Vec3::new(0.6, 0.02, 0.8),
            Pose::from_parts(Vec3::new(0.3, 0.8, 0.5), Quat::from_rotation_z(1.1)),
        );
        let pts = truth.sample_surface(3000);
        let mut start = truth;
        // 1.5 cm along the face, 3° about the face normal: only the edge points see this.
        start.world_from_primitive = Pose::from_parts(
            truth.center() + truth.axes_world()[0] * 0.015 - truth.axes_world()[2] * 0.01,
            truth.rotation() * Quat::from_rotation_y(3f32.to_radians()),
        );
        let res = icp_align(&start, &pts, &IcpConfig::default());
        assert_pose_close(&res.primitive, &truth);
    }

    #[test]
    fn refits_the_thickness_of_a_board_seen_from_the_front_and_two_edges() {
        let truth = Primitive::new(
            PrimitiveKind::Cuboid,
            Vec3::new(0.3, 0.6, 0.028),
            Pose::from_parts(Vec3::new(0.3, 0.8, 0.5), Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 1.1)),
        );
        let h = truth.size * 0.5;
        let pts: Vec<Vec3> = truth
            .sample_surface(3000)
            .into_iter()
            .filter(|p| {
                let q = truth.world_from_primitive.inverse_transform_point(*p);
                (q.z - h.z).abs() < 1e-5 || (q.x + h.x).abs() < 1e-5 || (q.y - h.y).abs() < 1e-5
            })
            .collect();
        let mut r = rng(8);
        let noise = Normal::new(0.0_f32, 0.002).expect("valid sigma");
        let pts: Vec<Vec3> =
            pts.iter().step_by(6).map(|p| *p + Vec3::new(noise.sample(&mut r), noise.sample(&mut r), noise.sample(&mut r))).collect();
        for tilt_deg in [0.0_f32, 4.0] {
            // Thin start; tilted about the long axis (the minimal box of an L-shaped section is
            // ambiguous by up to atan(thickness / width)).
            let mut start = truth;
            start.size.z = 0.015;
            start.world_from_primitive.rotation = truth.rotation() * Quat::from_rotation_y(tilt_deg.to_radians());
            let res = icp_align(&start, &pts, &IcpConfig { refit_size: true, ..IcpConfig::default() });
            // Noise biases the extents of the unseen faces outwards by ~2σ (extreme percentiles).
            assert!((res.primitive.size - truth.size).abs().max_element() < 0.008, "tilt {tilt_deg}: {}", res.primitive.size);
            assert!((res.primitive.center() - truth.center()).length() < 0.005, "tilt {tilt_deg}");
            assert!(res.primitive.rotation().angle_between(truth.rotation()).to_degrees() < 0.5, "tilt {tilt_deg}");
        }
    }

    #[test]
    fn refits_a_cylinder_from_a_noisy_half_side() {
        let truth = Primitive::new(
            PrimitiveKind::Cylinder,
            Vec3::new(0.3, 0.3, 0.7),
            Pose::from_parts(Vec3::new(0.2, 0.1, 0.35), Quat::from_rotation_x(0.3)),
        );
        let mut r = rng(5);
        let noise = Normal::new(0.0_f32, 0.002).expect("valid sigma");
        // Seen from +x: the half side facing +x and the top cap.
        let pts: Vec<Vec3> = truth
            .sample_surface(4000)
            .into_iter()
            .filter(|p| truth.world_from_primitive.inverse_transform_point(*p).x > 0.0)
            .map(|p| p + Vec3::new(noise.sample(&mut r), noise.sample(&mut r), noise.sample(&mut r)))
            .collect();
        let mut start = truth;
        start.size = Vec3::new(0.36, 0.36, 0.75);
        start.world_from_primitive.translation += Vec3::new(0.02, 0.0, -0.01);
        let cfg = IcpConfig { refit_size: true, max_iterations: 30, ..IcpConfig::default() };
        let res = icp_align(&start, &pts, &cfg);
        let got = res.primitive;
        assert!((got.size.x - 0.3).abs() < 0.006, "diameter {}", got.size.x);
        assert!((got.size.z - 0.7).abs() < 0.01, "height {}", got.size.z);
        let axis_err = crate::math::line_angle_deg(got.axes_world()[2], truth.axes_world()[2]);
        assert!(axis_err < 1.0, "{axis_err}°");
        assert!(crate::math::line_line_distance(got.center(), got.axes_world()[2], truth.center(), truth.axes_world()[2]) < 0.003);
    }

    #[test]
    fn refits_a_sphere_from_a_hemisphere() {
        let truth = Primitive::new(PrimitiveKind::Sphere, Vec3::splat(0.25), Pose::from_translation(Vec3::new(0.0, 1.0, 2.0)));
        let pts: Vec<Vec3> = truth.sample_surface(2000).into_iter().filter(|p| p.z > 2.0).collect();
        let mut start = truth;
        start.size = Vec3::splat(0.3);
        start.world_from_primitive.translation += Vec3::new(0.01, -0.02, 0.03);
        let res = icp_align(&start, &pts, &IcpConfig { refit_size: true, ..IcpConfig::default() });
        assert!((res.primitive.size.x - 0.25).abs() < 0.002, "{}", res.primitive.size);
        assert!((res.primitive.center() - truth.center()).length() < 0.002);
    }

    #[test]
    fn handles_empty_and_non_finite_input() {
        let truth = true_box();
        let res = icp_align(&truth, &[], &IcpConfig::default());
        assert_eq!(res.iterations, 0);
        assert_eq!(res.primitive, truth);
        let mut pts = truth.sample_surface(200);
        pts.push(Vec3::NAN);
        let mut r = rng(1);
        pts.push(Vec3::new(r.random(), f32::INFINITY, 0.0));
        let res = icp_align(&truth, &pts, &IcpConfig { refit_size: true, ..IcpConfig::default() });
        assert!(res.primitive.world_from_primitive.is_finite() && res.mean_error < 1e-3);
    }
}
