//! From a recording to per-joint measured positions: `q` columns as they are, tracked link poses
//! through the model (walking up fixed joints to the joint that moves the link, ancestors at their
//! own measured positions), dropouts as NaN; plus gap filling and smoothed derivatives.

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};

use super::error::GapError;
use super::model::{DofKind, GapModel, Iso};
use super::recording::Recording;

/// Measured positions of every observed movable joint (NaN where missing), by joint index.
pub fn observed_positions(model: &GapModel, rec: &Recording) -> Result<BTreeMap<usize, Vec<f64>>, GapError> {
    let n = rec.time_s.len();
    let mut observed: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    let mut filled: Vec<Vec<f64>> = vec![vec![0.0; n]; model.joints.len()];
    for &j in &model.order {
        let joint = &model.joints[j];
        if joint.kind == DofKind::Fixed {
            continue;
        }
        let mut q = rec.joint_q.get(&joint.name).cloned().unwrap_or_else(|| vec![f64::NAN; n]);
        for (link_name, track) in &rec.links {
            let Some(link) = model.link_index(link_name) else { continue };
            let Some((moving, child_from_link)) = model.moving_joint_of(link) else { continue };
            if moving != j {
                continue;
            }
            let from_pose = pose_positions(model, j, &child_from_link, track, &filled, n)
                .map_err(|message| GapError::Analysis { file: rec.file.clone(), message: format!("link {link_name}: {message}") })?;
            for (qi, pi) in q.iter_mut().zip(from_pose) {
                if !qi.is_finite() {
                    *qi = pi;
                }
            }
        }
        if q.iter().any(|v| v.is_finite()) {
            filled[j] = fill_gaps(&q);
            observed.insert(j, q);
        }
    }
    Ok(observed)
}

/// Joint positions implied by a tracked link's poses (NaN where the pose is missing).
fn pose_positions(
    model: &GapModel,
    j: usize,
    child_from_link: &Iso,
    track: &super::recording::LinkTrack,
    filled: &[Vec<f64>],
    n: usize,
) -> Result<Vec<f64>, String> {
    let joint = &model.joints[j];
    let axis = joint.axis_joint;
    let link_from_child = child_from_link.inverse();
    let mut out = vec![f64::NAN; n];
    let mut config = vec![0.0; model.joints.len()];
    let mut previous: Option<f64> = None;
    let lever = child_from_link.translation - axis * child_from_link.translation.dot(axis);
    if track.quaternion.is_none() && joint.kind.is_rotational() && lever.length() < 1e-3 {
        return Err(format!(
            "only positions are tracked and the link origin lies on the axis of joint {}: its angle cannot be recovered",
            joint.name
        ));
    }
    for i in 0..n {
        for (c, series) in config.iter_mut().zip(filled) {
            *c = series[i];
        }
        let (frame, _) = model.joint_frame_world(j, &config);
        let rotation = track.quaternion.as_ref().map(|qt| DQuat::from_xyzw(qt[1][i], qt[2][i], qt[3][i], qt[0][i]));
        let position = track.position_m.as_ref().map(|p| DVec3::new(p[0][i], p[1][i], p[2][i]));
        let value = match (joint.kind, rotation, position) {
            (DofKind::Revolute | DofKind::Continuous, Some(r), _) if r.is_finite() && r.length() > 0.5 => {
                let world_from_child = r.normalize() * link_from_child.rotation;
                let rel = frame.rotation.inverse() * world_from_child;
                let rel = if rel.w < 0.0 { -rel } else { rel };
                let angle = 2.0 * DVec3::new(rel.x, rel.y, rel.z).dot(axis).atan2(rel.w);
                unwrap_near(angle, previous)
            }
            (DofKind::Revolute | DofKind::Continuous, _, Some(p)) if p.is_finite() => {
                let local = frame.rotation.inverse() * (p - frame.translation);
                let local_perp = local - axis * local.dot(axis);
                let angle = lever.cross(local_perp).dot(axis).atan2(lever.dot(local_perp));
                unwrap_near(angle, previous)
            }
            (DofKind::Prismatic, r, Some(p)) if p.is_finite() => {
                let world_from_link_rotation =
                    r.filter(|r| r.is_finite() && r.length() > 0.5).map_or(frame.rotation * child_from_link.rotation, DQuat::normalize);
                let origin_child = p + world_from_link_rotation * link_from_child.translation;
                (frame.rotation.inverse() * (origin_child - frame.translation)).dot(axis)
            }
            _ => f64::NAN,
        };
        if value.is_finite() {
            previous = Some(value);
        }
        out[i] = value;
    }
    Ok(out)
}

fn unwrap_near(angle: f64, previous: Option<f64>) -> f64 {
    let Some(p) = previous else { return angle };
    let tau = std::f64::consts::TAU;
    angle + ((p - angle) / tau).round() * tau
}

/// Linear interpolation over NaN gaps; ends held at the nearest sample; all-NaN gives zeros.
#[must_use]
pub fn fill_gaps(values: &[f64]) -> Vec<f64> {
    let known: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_finite()).collect();
    let (Some(&first), Some(&last)) = (known.first(), known.last()) else { return vec![0.0; values.len()] };
    let mut out = values.to_vec();
    for v in &mut out[..first] {
        *v = values[first];
    }
    for v in &mut out[last + 1..] {
        *v = values[last];
    }
    for w in known.windows(2) {
        let (a, b) = (w[0], w[1]);
        for (k, v) in out.iter_mut().enumerate().take(b).skip(a + 1) {
            let s = (k - a) as f64 / (b - a) as f64;
            *v = values[a] * (1.0 - s) + values[b] * s;
        }
    }
    out
}

/// Local quadratic fits over ±`half` valid neighbours: (position, velocity, acceleration) per
/// sample, NaN where too few neighbours.
#[must_use]
pub fn smoothed_derivatives(time_s: &[f64], y: &[f64], half: usize) -> Vec<[f64; 3]> {
    let valid: Vec<usize> = (0..y.len()).filter(|&i| y[i].is_finite()).collect();
    let mut out = vec![[f64::NAN; 3]; y.len()];
    if valid.len() < 2 * half + 1 {
        return out;
    }
    for (k, &i) in valid.iter().enumerate() {
        let lo = k.saturating_sub(half).min(valid.len() - (2 * half + 1));
        let window = &valid[lo..=lo + 2 * half];
        let t0 = time_s[i];
        // Normal equations of y = c0 + c1 dt + c2 dt²/2.
        let mut a = [[0.0f64; 3]; 3];
        let mut b = [0.0f64; 3];
        for &w in window {
            let dt = time_s[w] - t0;
            let phi = [1.0, dt, dt * dt / 2.0];
            for r in 0..3 {
                for c in 0..3 {
                    a[r][c] += phi[r] * phi[c];
                }
                b[r] += phi[r] * y[w];
            }
        }
        if let Some(x) = super::fit::solve_spd(&a.iter().flatten().copied().collect::<Vec<_>>(), &b, 3) {
            out[i] = [x[0], x[1], x[2]];
        }
    }
    out
}
