//! The one place that picks the math types: glam (shared with parry3d through glamx) in `f32`,
//! `f64` for accumulations. Frames are named in variables: `world_from_part` maps part-frame
//! points to world-frame points.

pub use glam::{DMat3, DVec3, Mat3, Quat, Vec2, Vec3};
pub use glamx::{DSymmetricEigen3, SymmetricEigen3};

/// A rigid transform (rotation, then translation). Same type as parry3d's `Pose`.
pub type Pose = parry3d::math::Pose;

/// World up (+z), as the scan format says.
pub const UP: Vec3 = Vec3::Z;

/// The rotation `R` minimising `Σ wᵢ‖R·fromᵢ − toᵢ‖²` (Kabsch / Horn).
///
/// Written here (not a crate) because glam has no SVD and glamx's SVD goes through the
/// eigenvectors of `AᵀA` in closed form, which loses the rotation for the rank-deficient inputs
/// refinement feeds it (one or two normal pairs). Horn's quaternion form with a Jacobi
/// eigen-solver in `f64` is exact for every rank: with a single pair it returns the shortest arc.
#[must_use]
pub fn kabsch_rotation(from: &[Vec3], to: &[Vec3], weights: Option<&[f32]>) -> Quat {
    let n = from.len().min(to.len());
    if n == 0 {
        return Quat::IDENTITY;
    }
    if n == 1 {
        return Quat::from_rotation_arc(from[0].normalize_or_zero(), to[0].normalize_or_zero());
    }
    // Cross-covariance S = Σ w a bᵀ.
    let mut s = [[0.0_f64; 3]; 3];
    for i in 0..n {
        let w = weights.map_or(1.0, |w| f64::from(w[i]));
        let a = from[i].as_dvec3();
        let b = to[i].as_dvec3();
        let (a, b) = (a.to_array(), b.to_array());
        for (r, row) in s.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v += w * a[r] * b[c];
            }
        }
    }
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = s;
    let nmat = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (values, vectors) = jacobi_eigen4(nmat);
    let mut best = 0;
    for k in 1..4 {
        if values[k] > values[best] {
            best = k;
        }
    }
    let q = [vectors[0][best], vectors[1][best], vectors[2][best], vectors[3][best]];
    // Horn's quaternion is (w, x, y, z).
    let quat = Quat::from_xyzw(q[1] as f32, q[2] as f32, q[3] as f32, q[0] as f32);
    if quat.length_squared() < 1e-12 { Quat::IDENTITY } else { quat.normalize() }
}

/// Eigen decomposition of a symmetric 4×4 matrix by cyclic Jacobi rotations.
/// Returns (eigenvalues, eigenvectors as columns).
#[allow(clippy::needless_range_loop)] // (p, q, k) index math reads like the textbook algorithm
fn jacobi_eigen4(mut a: [[f64; 4]; 4]) -> ([f64; 4], [[f64; 4]; 4]) {
    let mut v = [[0.0; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let mut off = 0.0;
        for p in 0..4 {
            for q in (p + 1)..4 {
                off += a[p][q] * a[p][q];
            }
        }
        if off < 1e-30 {
            break;
        }
        for p in 0..4 {
            for q in (p + 1)..4 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..4 {
                    let akp = a[k][p];
                    let akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..4 {
                    let apk = a[p][k];
                    let aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in &mut v {
                    let vkp = row[p];
                    let vkq = row[q];
                    row[p] = c * vkp - s * vkq;
                    row[q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2], a[3][3]], v)
}

/// Principal axes of a point set: (centroid, axes as columns sorted by decreasing variance).
#[must_use]
pub fn principal_axes(points: &[Vec3]) -> (Vec3, Mat3) {
    if points.is_empty() {
        return (Vec3::ZERO, Mat3::IDENTITY);
    }
    let n = points.len() as f64;
    let mean = points.iter().fold(DVec3::ZERO, |acc, p| acc + p.as_dvec3()) / n;
    let mut cov = DMat3::ZERO;
    for p in points {
        let d = p.as_dvec3() - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    cov *= 1.0 / n;
    let eig = DSymmetricEigen3::new(cov).reverse();
    let x = eig.eigenvectors.x_axis.normalize_or(DVec3::X);
    let mut y = eig.eigenvectors.y_axis;
    y = (y - x * x.dot(y)).normalize_or(x.any_orthonormal_vector());
    let z = x.cross(y);
    (mean.as_vec3(), Mat3::from_cols(x.as_vec3(), y.as_vec3(), z.as_vec3()))
}

/// Roll-pitch-yaw (URDF convention: R = Rz(yaw)·Ry(pitch)·Rx(roll)) of a rotation, from its
/// matrix in f64, exact at and near gimbal lock. (glam's `to_euler` turned a knob whose axis lies
/// along y, pitch ≈ −90°, by 90° about the wrong axis in `PyBullet`; found by
/// `scripts/check_sim_clients.py`.)
#[must_use]
pub fn quat_to_rpy(q: Quat) -> [f64; 3] {
    dquat_to_rpy(q.as_dquat())
}

/// [`quat_to_rpy`] of a double-precision rotation.
#[must_use]
pub fn dquat_to_rpy(q: glam::DQuat) -> [f64; 3] {
    let m = glam::DMat3::from_quat(q.normalize());
    // Row r, column c of the matrix is m.col(c)[r].
    let at = |r: usize, c: usize| m.col(c)[r];
    let cos_pitch = at(0, 0).hypot(at(1, 0));
    let pitch = (-at(2, 0)).atan2(cos_pitch);
    if cos_pitch > 1e-9 {
        [at(2, 1).atan2(at(2, 2)), pitch, at(1, 0).atan2(at(0, 0))]
    } else {
        // cos(pitch) = 0: only roll − yaw (or roll + yaw) is defined; put it all in roll.
        [(-at(1, 2)).atan2(at(1, 1)), pitch, 0.0]
    }
}

/// Inverse of [`quat_to_rpy`].
#[must_use]
pub fn rpy_to_quat(rpy: [f64; 3]) -> Quat {
    glam::DQuat::from_euler(glam::EulerRot::ZYX, rpy[2], rpy[1], rpy[0]).as_quat()
}

/// A deterministic random generator for a seed (`ChaCha8`: stable across platforms and versions).
#[must_use]
pub fn rng(seed: u64) -> rand_chacha::ChaCha8Rng {
    use rand::SeedableRng;
    rand_chacha::ChaCha8Rng::seed_from_u64(seed)
}

/// Angle between two lines (undirected), degrees, in [0, 90].
#[must_use]
pub fn line_angle_deg(a: Vec3, b: Vec3) -> f32 {
    let c = a.normalize_or_zero().dot(b.normalize_or_zero()).abs().min(1.0);
    c.acos().to_degrees()
}

/// Distance between two infinite lines given by point and direction.
#[must_use]
pub fn line_line_distance(p1: Vec3, d1: Vec3, p2: Vec3, d2: Vec3) -> f32 {
    let d1 = d1.normalize_or_zero();
    let d2 = d2.normalize_or_zero();
    let n = d1.cross(d2);
    let w = p2 - p1;
    if n.length() < 1e-4 {
        // Parallel: distance from p2 to line 1.
        (w - d1 * w.dot(d1)).length()
    } else {
        w.dot(n.normalize()).abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kabsch_recovers_a_known_rotation() {
        let r = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let from = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(1.0, 2.0, -0.5)];
        let to: Vec<Vec3> = from.iter().map(|v| r * *v).collect();
        let got = kabsch_rotation(&from, &to, None);
        assert!(got.angle_between(r) < 1e-4, "{got:?} vs {r:?}");
    }

    #[test]
    fn kabsch_with_two_pairs_is_exact() {
        let r = Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 0.05);
        let from = [Vec3::X, Vec3::Z];
        let to: Vec<Vec3> = from.iter().map(|v| r * *v).collect();
        let got = kabsch_rotation(&from, &to, None);
        assert!(got.angle_between(r) < 1e-4);
    }

    #[test]
    fn kabsch_single_pair_is_shortest_arc() {
        let got = kabsch_rotation(&[Vec3::X], &[Vec3::Y], None);
        assert!((got * Vec3::X - Vec3::Y).length() < 1e-5);
        assert!((got * Vec3::Z - Vec3::Z).length() < 1e-5);
    }

    #[test]
    fn rpy_round_trip() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.2, 0.4, -1.3);
        let back = rpy_to_quat(quat_to_rpy(q));
        assert!(back.angle_between(q) < 1e-5);
    }

    #[test]
    fn principal_axes_of_a_line() {
        let pts: Vec<Vec3> = (0..10).map(|i| Vec3::new(0.0, i as f32, 0.0)).collect();
        let (c, axes) = principal_axes(&pts);
        assert!((c.y - 4.5).abs() < 1e-5);
        assert!(axes.x_axis.dot(Vec3::Y).abs() > 0.999);
    }

    #[test]
    fn line_distance_of_parallel_and_skew_lines() {
        assert!((line_line_distance(Vec3::ZERO, Vec3::Z, Vec3::X, Vec3::Z) - 1.0).abs() < 1e-6);
        assert!((line_line_distance(Vec3::ZERO, Vec3::X, Vec3::Z * 2.0, Vec3::Y) - 2.0).abs() < 1e-6);
    }
}
