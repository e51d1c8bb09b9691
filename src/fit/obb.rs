//! Minimum-volume oriented bounding boxes (the paper scales its primitive templates by the
//! minimal box of the part, after Dimitrov et al. 2009).
//!
//! Exact minimum-volume boxes (O'Rourke's algorithm) are cubic in the hull size; we use the
//! standard near-optimal scheme instead: for every distinct face normal of the convex hull, the
//! hull is projected onto the face plane and the minimum-area rectangle is found by rotating
//! calipers (exact in 2D), so the box has one face flush with a hull face. The PCA box, and a box
//! flush with the floor (world +z, furniture stands upright) are candidates as well, and the best
//! box is polished by a deterministic local search over small rotations.

use super::subsample_stride;
use crate::math::{Mat3, Pose, Quat, Vec2, Vec3, principal_axes};
use crate::polygon::{convex_hull, min_area_rect_dir};

/// Smallest extent a box (and a fitted primitive) reports, metres: flat or collinear point sets
/// get this thickness instead of zero.
pub const MIN_EXTENT_M: f32 = 1e-3;

/// At most this many points go into the convex hull (a stride subsample; the final extents use
/// all points). Round parts put most of their points on the hull, and the cost grows with it.
const MAX_HULL_INPUT: usize = 800;
/// Hull faces whose normals differ by less than ~1.5° are one candidate direction.
const NORMAL_MERGE_COS: f32 = 0.999_66;
/// At most this many face directions (largest total area first) are tried.
const MAX_FACE_NORMALS: usize = 12;
/// Clustering stops opening new directions after this many (faces come largest first).
const MAX_CLUSTERS: usize = 64;
/// A box axis within ~30° of world +z makes the box "upright": that axis becomes its z.
const UPRIGHT_COS: f32 = 0.866;
/// Local search steps (degrees), coarse to fine.
const SEARCH_STEPS_DEG: [f32; 6] = [2.0, 1.0, 0.5, 0.25, 0.1, 0.05];

/// An oriented box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obb {
    /// Centre, world frame.
    pub center: Vec3,
    /// The box axes in world coordinates (columns; unit, right-handed).
    pub axes: Mat3,
    /// Full extents along `axes`, metres (each at least [`MIN_EXTENT_M`]).
    pub size: Vec3,
}

impl Obb {
    /// Volume, m³.
    #[must_use]
    pub fn volume(&self) -> f32 {
        self.size.x * self.size.y * self.size.z
    }

    /// The box frame: maps box coordinates (centred, along `axes`) to the world.
    #[must_use]
    pub fn world_from_box(&self) -> Pose {
        Pose::from_parts(self.center, Quat::from_mat3(&self.axes).normalize())
    }

    /// A world point in box coordinates.
    #[must_use]
    pub fn to_box(&self, world_point: Vec3) -> Vec3 {
        self.axes.transpose() * (world_point - self.center)
    }
}

/// A box orientation with its (clamped) volume on some vertex set.
#[derive(Clone, Copy)]
struct Oriented {
    axes: Mat3,
    volume: f32,
}

/// The (near-)minimum-volume oriented box of `points`.
///
/// Non-finite points are ignored; an empty input gives a minimal box at the origin. Flat or
/// collinear sets get [`MIN_EXTENT_M`] in the degenerate directions. The axes are canonical:
/// when one axis is within ~30° of world +z it becomes the box's z (pointing up) and x is the
/// longer of the two others; otherwise x, y, z go by decreasing extent. Each axis is signed so
/// its largest component is positive (z upright: pointing up), and the frame is right-handed.
#[must_use]
pub fn min_volume_obb(points: &[Vec3]) -> Obb {
    let finite: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    if finite.is_empty() {
        return Obb { center: Vec3::ZERO, axes: Mat3::IDENTITY, size: Vec3::splat(MIN_EXTENT_M) };
    }
    let sample = subsample_stride(&finite, MAX_HULL_INPUT);
    let (centroid, pca) = principal_axes(&sample);
    // Work relative to the centroid: better conditioned hulls and projections.
    let rel: Vec<Vec3> = sample.iter().map(|p| *p - centroid).collect();
    let (verts, mut normals) = hull_directions(&rel).unwrap_or_else(|| (rel.clone(), Vec::new()));
    normals.extend([pca.x_axis, pca.y_axis, pca.z_axis, Vec3::Z]);

    let mut best = Oriented { axes: pca, volume: clamped_volume(&verts, &pca) };
    for n in normals {
        if let Some(cand) = box_flush_with(&verts, n)
            && cand.volume < best.volume * (1.0 - 1e-6)
        {
            best = cand;
        }
    }
    let axes = local_search(&verts, best);
    let obb = box_with_axes(&finite, centroid, axes);
    canonicalize(obb)
}

/// The box along the principal axes of `points` (non-finite points ignored), canonicalised
/// like [`min_volume_obb`]. For a partial scan dominated by one face (a board seen from the
/// front and along two edges) the principal frame is the face's, where the minimal box is
/// ambiguous (the hull of an L-shaped section fits equally well in tilted boxes).
#[must_use]
pub fn pca_obb(points: &[Vec3]) -> Obb {
    let finite: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    if finite.is_empty() {
        return Obb { center: Vec3::ZERO, axes: Mat3::IDENTITY, size: Vec3::splat(MIN_EXTENT_M) };
    }
    let (centroid, axes) = principal_axes(&finite);
    canonicalize(box_with_axes(&finite, centroid, axes))
}

/// Largest angle (degrees) between an axis of `a` and the closest axis of `b` (as lines).
#[must_use]
pub fn axes_angle_deg(a: &Mat3, b: &Mat3) -> f32 {
    let bs = [b.x_axis, b.y_axis, b.z_axis];
    [a.x_axis, a.y_axis, a.z_axis]
        .iter()
        .map(|u| bs.iter().map(|v| crate::math::line_angle_deg(*u, *v)).fold(f32::INFINITY, f32::min))
        .fold(0.0, f32::max)
}

/// Clamped volume of the box with the given axes around `verts`.
fn clamped_volume(verts: &[Vec3], axes: &Mat3) -> f32 {
    let (lo, hi) = extents(verts, axes);
    (hi - lo).max(Vec3::splat(MIN_EXTENT_M)).element_product()
}

/// Min and max coordinates of `verts` along the columns of `axes`.
fn extents(verts: &[Vec3], axes: &Mat3) -> (Vec3, Vec3) {
    let t = axes.transpose();
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in verts {
        let q = t * *p;
        lo = lo.min(q);
        hi = hi.max(q);
    }
    (lo, hi)
}

/// The box with `axes` around `points` (world), `offset` being any nearby point (precision).
fn box_with_axes(points: &[Vec3], offset: Vec3, axes: Mat3) -> Obb {
    let t = axes.transpose();
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in points {
        let q = t * (*p - offset);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let mid = 0.5 * (lo + hi);
    Obb { center: offset + axes * mid, axes, size: (hi - lo).max(Vec3::splat(MIN_EXTENT_M)) }
}

/// Hull vertices and the distinct face directions of the hull (largest area first), or `None`
/// when the hull is degenerate (flat, collinear, fewer than four points).
fn hull_directions(rel: &[Vec3]) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
    if rel.len() < 4 {
        return None;
    }
    let (verts, tris) = parry3d::transformation::try_convex_hull(rel).ok()?;
    if verts.len() < 4 || tris.len() < 4 || verts.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // Faces by decreasing area (index as tie-break: deterministic).
    let mut faces: Vec<(f32, Vec3)> = Vec::with_capacity(tris.len());
    for t in &tris {
        let (Some(a), Some(b), Some(c)) = (verts.get(t[0] as usize), verts.get(t[1] as usize), verts.get(t[2] as usize)) else {
            continue;
        };
        let n = (*b - *a).cross(*c - *a);
        let len = n.length();
        if len > 1e-12 && len.is_finite() {
            faces.push((len, canonical_sign(n / len)));
        }
    }
    if faces.is_empty() {
        return None;
    }
    faces.sort_by(|x, y| y.0.total_cmp(&x.0));
    // Greedy clustering of near-parallel normals; a cluster is represented by its first (largest)
    // face and averages the members weighted by area.
    let mut clusters: Vec<(Vec3, Vec3, f32)> = Vec::new(); // (representative, weighted sum, area)
    for (area, n) in faces {
        if let Some(c) = clusters.iter_mut().find(|c| c.0.dot(n).abs() >= NORMAL_MERGE_COS) {
            c.1 += n * area * c.0.dot(n).signum();
            c.2 += area;
        } else if clusters.len() < MAX_CLUSTERS {
            clusters.push((n, n * area, area));
        }
    }
    clusters.sort_by(|x, y| y.2.total_cmp(&x.2));
    let normals = clusters.iter().take(MAX_FACE_NORMALS).map(|c| c.1.try_normalize().unwrap_or(c.0)).collect();
    Some((verts, normals))
}

/// `v` or `-v`, whichever has its largest-magnitude component positive (first one on ties).
fn canonical_sign(v: Vec3) -> Vec3 {
    let a = v.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        v.x
    } else if a.y >= a.z {
        v.y
    } else {
        v.z
    };
    if k < 0.0 { -v } else { v }
}

/// The smallest box with one face perpendicular to `normal`: min-area rectangle of the
/// projection (rotating calipers) times the extent along `normal`.
fn box_flush_with(verts: &[Vec3], normal: Vec3) -> Option<Oriented> {
    let n = normal.try_normalize()?;
    let u = n.any_orthonormal_vector();
    let v = n.cross(u); // (u, v, n) right-handed
    let mut flat = Vec::with_capacity(verts.len());
    for p in verts {
        flat.push(Vec2::new(p.dot(u), p.dot(v)));
    }
    let hull = convex_hull(flat);
    let dir = min_area_rect_dir(&hull, MIN_EXTENT_M);
    let a1 = u * dir.x + v * dir.y;
    let a2 = u * -dir.y + v * dir.x;
    let axes = Mat3::from_cols(a1, a2, n);
    Some(Oriented { axes, volume: clamped_volume(verts, &axes) })
}

/// Deterministic coordinate descent over small rotations about the box's own axes.
fn local_search(verts: &[Vec3], start: Oriented) -> Mat3 {
    let mut rot = Quat::from_mat3(&start.axes).normalize();
    let mut best = start.volume;
    for step_deg in SEARCH_STEPS_DEG {
        let step = step_deg.to_radians();
        for _ in 0..8 {
            let mut improved: Option<(Quat, f32)> = None;
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                for sign in [1.0, -1.0] {
                    let cand = (rot * Quat::from_axis_angle(axis, sign * step)).normalize();
                    let vol = clamped_volume(verts, &Mat3::from_quat(cand));
                    let bar = improved.map_or(best, |b| b.1);
                    if vol < bar * (1.0 - 1e-6) {
                        improved = Some((cand, vol));
                    }
                }
            }
            match improved {
                Some((q, v)) => {
                    rot = q;
                    best = v;
                }
                None => break,
            }
        }
    }
    let m = Mat3::from_quat(rot);
    // Re-orthonormalise (accumulated float error).
    let x = m.x_axis.normalize_or(Vec3::X);
    let y = (m.y_axis - x * x.dot(m.y_axis)).normalize_or(x.any_orthonormal_vector());
    Mat3::from_cols(x, y, x.cross(y))
}

/// Canonical axis order and signs (see [`min_volume_obb`]).
fn canonicalize(obb: Obb) -> Obb {
    let axes = [obb.axes.x_axis, obb.axes.y_axis, obb.axes.z_axis];
    let size = obb.size.to_array();
    let mut up = 0;
    for k in 1..3 {
        if axes[k].z.abs() > axes[up].z.abs() {
            up = k;
        }
    }
    let (x, sx, y, sy, z, sz);
    if axes[up].z.abs() >= UPRIGHT_COS {
        z = axes[up] * axes[up].z.signum();
        sz = size[up];
        let (o0, o1) = ((up + 1) % 3, (up + 2) % 3);
        let (o0, o1) = if o0 < o1 { (o0, o1) } else { (o1, o0) };
        let (xi, yi) = if size[o1] > size[o0] { (o1, o0) } else { (o0, o1) };
        x = horizontal_sign(axes[xi]);
        sx = size[xi];
        y = z.cross(x);
        sy = size[yi];
    } else {
        let mut order = [0usize, 1, 2];
        order.sort_by(|a, b| size[*b].total_cmp(&size[*a]));
        x = canonical_sign(axes[order[0]]);
        sx = size[order[0]];
        y = canonical_sign(axes[order[1]]);
        sy = size[order[1]];
        z = x.cross(y);
        sz = size[order[2]];
    }
    Obb { center: obb.center, axes: Mat3::from_cols(x, y, z), size: Vec3::new(sx, sy, sz) }
}

/// Sign of a (roughly horizontal) axis: its largest horizontal component positive.
fn horizontal_sign(v: Vec3) -> Vec3 {
    let k = if v.x.abs() >= v.y.abs() { v.x } else { v.y };
    if k < 0.0 { -v } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{line_angle_deg, rng};
    use crate::primitive::{Primitive, PrimitiveKind};
    use rand::Rng;

    fn pca_box_volume(points: &[Vec3]) -> f32 {
        let (c, axes) = principal_axes(points);
        box_with_axes(points, c, axes).volume()
    }

    #[test]
    fn recovers_a_rotated_box() {
        let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.3, 0.9);
        let size = Vec3::new(0.8, 0.5, 0.3);
        let prim = Primitive::new(PrimitiveKind::Cuboid, size, Pose::from_parts(Vec3::new(1.0, 2.0, 0.5), rot));
        let pts = prim.sample_surface(3000);
        let obb = min_volume_obb(&pts);
        let truth = prim.axes_world();
        let got = [obb.axes.x_axis, obb.axes.y_axis, obb.axes.z_axis];
        let got_size = obb.size.to_array();
        for (k, t) in truth.iter().enumerate() {
            // The box axis most parallel to the true axis k.
            let (best, angle) = (0..3).map(|g| (g, line_angle_deg(got[g], *t))).min_by(|a, b| a.1.total_cmp(&b.1)).expect("three axes");
            assert!(angle < 1.0, "axis {k}: {angle}°");
            let rel = (got_size[best] / size[k] - 1.0).abs();
            assert!(rel < 0.02, "size {k}: {} vs {}", got_size[best], size[k]);
        }
        assert!((obb.center - prim.center()).length() < 0.01);
        assert!(obb.volume() <= pca_box_volume(&pts) * 1.0001, "{} vs PCA {}", obb.volume(), pca_box_volume(&pts));
        // Right-handed unit frame.
        assert!((obb.axes.determinant() - 1.0).abs() < 1e-4);
        // Every point inside (up to float error).
        for p in &pts {
            let q = obb.to_box(*p).abs();
            assert!(q.cmple(obb.size * 0.5 + 1e-4).all());
        }
    }

    #[test]
    fn beats_pca_on_a_skewed_cloud() {
        // Dense points on one side of a box skew PCA; the minimal box does not care.
        let prim =
            Primitive::new(PrimitiveKind::Cuboid, Vec3::new(1.0, 1.0, 0.2), Pose::from_parts(Vec3::ZERO, Quat::from_rotation_z(0.3)));
        let mut pts = prim.sample_surface(1000);
        let extra: Vec<Vec3> =
            prim.sample_surface(4000).into_iter().filter(|p| prim.world_from_primitive.inverse_transform_point(*p).x > 0.3).collect();
        pts.extend(extra);
        let obb = min_volume_obb(&pts);
        assert!(obb.volume() < pca_box_volume(&pts) * 0.99 || (pca_box_volume(&pts) - 0.2).abs() < 0.004);
        assert!((obb.volume() - 0.2).abs() < 0.004, "{}", obb.volume());
    }

    #[test]
    fn upright_boxes_get_z_up() {
        let prim = Primitive::new(
            PrimitiveKind::Cuboid,
            Vec3::new(0.3, 0.9, 0.6),
            Pose::from_parts(Vec3::new(0.0, 0.0, 0.3), Quat::from_rotation_z(0.5)),
        );
        let obb = min_volume_obb(&prim.sample_surface(2000));
        assert!(obb.axes.z_axis.dot(Vec3::Z) > 0.9999);
        assert!((obb.size.z - 0.6).abs() < 0.01, "{}", obb.size);
        assert!((obb.size.x - 0.9).abs() < 0.01, "{}", obb.size);
        assert!((obb.axes.determinant() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn noisy_box_stays_close() {
        let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.1, 0.2, -0.6);
        let size = Vec3::new(0.6, 0.4, 0.5);
        let prim = Primitive::new(PrimitiveKind::Cuboid, size, Pose::from_parts(Vec3::ZERO, rot));
        let mut r = rng(3);
        let pts: Vec<Vec3> = prim
            .sample_surface(3000)
            .into_iter()
            .map(|p| p + Vec3::new(r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)) * 0.002)
            .collect();
        let obb = min_volume_obb(&pts);
        for t in prim.axes_world() {
            let angle =
                [obb.axes.x_axis, obb.axes.y_axis, obb.axes.z_axis].iter().map(|g| line_angle_deg(*g, t)).fold(f32::INFINITY, f32::min);
            assert!(angle < 2.0, "{angle}");
        }
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        // Planar: a rotated square patch.
        let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.7, 0.1, 0.3);
        let planar: Vec<Vec3> = (0..400).map(|i| rot * Vec3::new((i % 20) as f32 * 0.05, (i / 20) as f32 * 0.03, 0.0)).collect();
        let obb = min_volume_obb(&planar);
        let mut s = obb.size.to_array();
        s.sort_by(f32::total_cmp);
        assert!((s[0] - MIN_EXTENT_M).abs() < 1e-4, "{s:?}");
        assert!((s[1] - 0.57).abs() < 1e-3 && (s[2] - 0.95).abs() < 1e-3, "{s:?}");
        // Collinear.
        let line: Vec<Vec3> = (0..50).map(|i| Vec3::new(1.0, 2.0, 3.0) * (i as f32 * 0.01)).collect();
        let obb = min_volume_obb(&line);
        assert!((obb.size.max_element() - 0.49 * Vec3::new(1.0, 2.0, 3.0).length()).abs() < 1e-3, "{}", obb.size);
        // Few points, duplicates, non-finite, empty.
        for pts in [
            vec![],
            vec![Vec3::ONE],
            vec![Vec3::ONE, Vec3::ONE, Vec3::ONE, Vec3::ONE, Vec3::ONE],
            vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            vec![Vec3::ZERO, Vec3::X, Vec3::NAN, Vec3::Y, Vec3::Z, Vec3::INFINITY],
        ] {
            let obb = min_volume_obb(&pts);
            assert!(obb.center.is_finite() && obb.size.is_finite() && obb.size.min_element() >= MIN_EXTENT_M, "{obb:?}");
            assert!((obb.axes.determinant() - 1.0).abs() < 1e-4);
        }
    }
}
