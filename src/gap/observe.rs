//! From a recording to per-joint measured positions: `q` columns as they are, tracked link poses
//! through the model (walking up fixed joints to the joint that moves the link, ancestors at their
//! own measured positions), dropouts as NaN; plus gap filling and smoothed derivatives.

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};

use super::error::GapError;
use super::model::{DofKind, GapModel, Iso};
use super::recording::Recording;

/// What the recording measures of the joints.
pub struct Observed {
    /// Measured positions of every observed movable joint (NaN where missing), by joint index.
    pub positions: BTreeMap<usize, Vec<f64>>,
    /// What was read as missing though the recording holds a value ([`drop_stale_readings`]).
    pub notes: Vec<String>,
}

/// The measured positions of the model's joints, from `q` columns and tracked poses.
pub fn observed_positions(model: &GapModel, rec: &Recording) -> Result<Observed, GapError> {
    let n = rec.time_s.len();
    let mut observed: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    let mut notes = Vec::new();
    let mut filled: Vec<Vec<f64>> = vec![vec![0.0; n]; model.joints.len()];
    for &j in &model.order {
        let joint = &model.joints[j];
        if joint.kind == DofKind::Fixed {
            continue;
        }
        let mut q = rec.joint_q.get(&joint.name).cloned().unwrap_or_else(|| vec![f64::NAN; n]);
        if joint.kind.is_rotational() {
            let turns = unwrap_turns(&mut q);
            if turns > 0 {
                notes.push(format!(
                    "{}.q: the reading jumps by more than π between samples {turns} times: read as the same angle wrapped \
                     round a full turn (a logger that keeps angles within one turn) and unwrapped",
                    joint.name
                ));
            }
        }
        let stale = drop_stale_readings(&mut q);
        if stale > 0 {
            notes.push(format!(
                "{}.q: {stale} samples repeat the reading before them exactly while the joint moves on by three \
                 steps of its resolution or more: read as missing (a log that holds a slower signal between its updates)",
                joint.name
            ));
        }
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
    Ok(Observed { positions: observed, notes })
}

/// Unwraps an angle logged within one turn (ROS drivers and encoders that report a continuous
/// joint in (−π, π] or [0, 2π)): each finite reading is taken at the turn nearest the one before
/// it ([`unwrap_near`], as tracked poses are), so wherever the reading jumps by more than π the
/// rest of the record moves by whole turns (`numpy.unwrap`'s rule). No joint turns by half a turn
/// between two samples of a recording that resolves its motion, so such a jump is a wrap, not
/// motion. Returns how many jumps were unwrapped.
fn unwrap_turns(q: &mut [f64]) -> usize {
    // The reading before, as logged and as unwrapped.
    let (mut previous, mut count) = (None::<(f64, f64)>, 0);
    for v in q.iter_mut().filter(|v| v.is_finite()) {
        let raw = *v;
        let unwrapped = unwrap_near(raw, previous.map(|(_, u)| u));
        if previous.is_some_and(|(p, _)| (raw - p).abs() > std::f64::consts::PI) {
            count += 1;
        }
        previous = Some((raw, unwrapped));
        // Untouched where no turn is added, to the bit (−0 + 0 would be +0): an exact test.
        #[allow(clippy::float_cmp)]
        if unwrapped != raw {
            *v = unwrapped;
        }
    }
    count
}

/// Steps of a position's resolution (its smallest change between samples) beyond which the
/// joint must move on after a run of exact repeats for the repeats to be stale: three steps or
/// more (a quantised encoder leaving a turning point moves on by one or two; 2.5, not 2, so that
/// two steps summed in floating point do not count as more than two).
const STALE_JUMP_RESOLUTIONS: f64 = 2.5;

/// Share of a position's magnitude within which two readings differ only by rounding (doubles
/// carry 16 digits; no encoder resolves 12).
const ROUNDING_SHARE: f64 = 1e-12;

/// Marks as missing (NaN) the readings of `q` that repeat the one before them exactly while the
/// joint then moves on by three steps of its resolution or more ([`STALE_JUMP_RESOLUTIONS`]; the
/// resolution: the smallest change between consecutive readings beyond rounding,
/// [`ROUNDING_SHARE`]) and by more than twice what it moves next, the run, its jump and the next
/// reading all consecutive rows (a gap of missing rows says nothing of when the joint moved). A
/// log written faster than the signal it holds (a 1 kHz log of a 200 Hz encoder, topics merged at
/// different rates) repeats the last value until the next update, and that staircase would read
/// as a joint that stops and jumps every few samples. A real encoder repeats too, at rest or
/// moving slower than a step per sample, but then moves on by a step or two (a real double
/// pendulum's 14-bit encoders, DFKI: none marked). The first reading of a run stays (it is the
/// update). Returns how many were marked.
fn drop_stale_readings(q: &mut [f64]) -> usize {
    let finite: Vec<usize> = (0..q.len()).filter(|&i| q[i].is_finite()).collect();
    // Changes within rounding of the last digits (a CSV round trip) are no steps: one of them
    // would make every encoder step a jump.
    let scale = finite.iter().map(|&i| q[i].abs()).fold(1.0, f64::max);
    let resolution =
        finite.windows(2).map(|w| (q[w[1]] - q[w[0]]).abs()).filter(|&d| d > ROUNDING_SHARE * scale).fold(f64::INFINITY, f64::min);
    if !resolution.is_finite() {
        return 0;
    }
    let mut stale = Vec::new();
    let mut k = 0;
    while k < finite.len() {
        // The run of readings equal to finite[k].
        let mut end = k + 1;
        // Exactly the same reading: a repeat, not a small change (both finite).
        #[allow(clippy::float_cmp)]
        while end < finite.len() && finite[end] == finite[end - 1] + 1 && q[finite[end]] == q[finite[k]] {
            end += 1;
        }
        // Stale where the jump after the run carries the motion held back through it: beyond the
        // resolution, and more than twice the change that follows (another run, or the joint
        // moving on at its speed). A joint that breaks away from rest moves off slowly and
        // speeds up (stuck by friction in a noise-free recording, where its rests repeat
        // exactly): its first step is the smaller. Nothing to judge at the end of the record or
        // across a gap.
        let stale_run = match (finite.get(end), finite.get(end + 1)) {
            (Some(&next), Some(&then)) if next == finite[end - 1] + 1 && then == next + 1 => {
                let jump = (q[next] - q[finite[k]]).abs();
                jump > STALE_JUMP_RESOLUTIONS * resolution && (q[then] - q[next]).abs() <= 0.5 * jump
            }
            _ => false,
        };
        if stale_run {
            stale.extend(finite[k + 1..end].iter().copied());
        }
        k = end;
    }
    for &i in &stale {
        q[i] = f64::NAN;
    }
    stale.len()
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

/// A position read at every `step`-th sample of a faster log ([`super::Recording::every`]): the
/// mean of the finite readings within ±`step`/2 samples of it (a moving average centred on the
/// sample, so that it lags nothing, and averages the readings the working rate leaves out); NaN
/// where none is finite.
#[must_use]
pub fn centred_means(values: &[f64], step: usize) -> Vec<f64> {
    let (step, n) = (step.max(1), values.len());
    (0..n)
        .step_by(step)
        .map(|i| {
            let window = &values[i.saturating_sub(step / 2)..(i + step / 2 + 1).min(n)];
            let (sum, count) = window.iter().filter(|v| v.is_finite()).fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
            if count > 0 { sum / count as f64 } else { f64::NAN }
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// [`drop_stale_readings`] on `q`: the indices it marks missing.
    fn check(q: &[f64], expected: &[usize]) {
        let mut v = q.to_vec();
        let count = drop_stale_readings(&mut v);
        let got: Vec<usize> = (0..v.len()).filter(|&i| v[i].is_nan() && q[i].is_finite()).collect();
        assert_eq!((got.as_slice(), count), (expected, expected.len()), "{q:?}");
    }

    #[test]
    fn a_position_read_at_a_working_rate_is_the_mean_around_its_sample() {
        let q = [0.0, 1.0, 2.0, 3.0, f64::NAN, 5.0, 6.0, 7.0, f64::NAN, f64::NAN, f64::NAN];
        let got = centred_means(&q, 4);
        // Samples 0, 4 and 8: means over 0..=2, 2..=6 (the missing one skipped) and 6..=10.
        let want = [1.0, 4.0, 6.5];
        assert!(got.len() == want.len() && got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-12), "{got:?}");
        assert!(centred_means(&[f64::NAN; 3], 2).iter().all(|v| v.is_nan()));
    }

    #[test]
    fn an_angle_logged_within_one_turn_is_unwrapped_and_a_real_swing_is_not() {
        // A joint turning steadily through 7 rad, logged in (−π, π] and in [0, 2π), with a dropout
        // across one wrap: both read back as the turn, to rounding.
        let tau = std::f64::consts::TAU;
        let turn: Vec<f64> = (0..50).map(|i| -3.0 + 0.14 * f64::from(i)).collect();
        for wrapped in [
            turn.iter().map(|x| (x + std::f64::consts::PI).rem_euclid(tau) - std::f64::consts::PI).collect::<Vec<_>>(),
            turn.iter().map(|x| x.rem_euclid(tau)).collect(),
        ] {
            let mut q = wrapped.clone();
            q[22] = f64::NAN;
            let count = unwrap_turns(&mut q);
            assert!(count >= 1, "{wrapped:?}");
            let offset = q[0] - turn[0];
            assert!((offset / tau - (offset / tau).round()).abs() < 1e-9, "a whole number of turns: {offset}");
            for (i, (&got, &want)) in q.iter().zip(&turn).enumerate().filter(|(i, _)| *i != 22) {
                assert!((got - offset - want).abs() < 1e-9, "sample {i}: {got} against {want}");
            }
            assert!(q[22].is_nan());
        }
        // A swing that stays within half a turn per sample is left as it is, bit for bit.
        let swing: Vec<f64> = (0..200).map(|i| 3.0 * (0.05 * f64::from(i)).sin()).collect();
        let mut q = swing.clone();
        assert_eq!(unwrap_turns(&mut q), 0);
        assert_eq!(q.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), swing.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
    }

    #[test]
    fn a_log_that_holds_a_slower_signal_loses_its_repeats_and_an_encoder_keeps_its_own() {
        // A slower signal logged three rows per update, speeding up and then turning round (the
        // turn shows the resolution). A staircase at one constant speed could as well be an
        // encoder of that step moving a step every three rows: it is not told apart.
        check(&[0.0, 0.0, 0.0, 0.1, 0.1, 0.1, 0.4, 0.4, 0.4, 0.8, 0.82], &[1, 2, 4, 5, 7, 8]);
        // A quantised encoder (step 0.5) at a turning point: repeats, then one or two steps on.
        check(&[2.0, 2.5, 3.0, 3.0, 3.0, 3.5, 3.5, 3.0, 2.0], &[]);
        // A joint held by its friction, noise-free, breaking away: its first step is the smallest
        // of its departure, whatever the resolution elsewhere (here a turn of 0.0001).
        check(&[0.5, 0.5001, 0.5001, 0.5001, 0.5, 0.5, 0.5, 0.502, 0.508, 0.518], &[]);
        // At rest to the end, and a dropout inside a run: nothing moves on, nothing is stale.
        check(&[1.0, 1.0, f64::NAN, 1.0, 1.0], &[]);
        // A run ends at a dropout: the joint may have moved during it, nothing is stale.
        check(&[0.0, 0.01, 0.01, f64::NAN, 0.5, 0.5, 0.9], &[]);
        // A rounding of the last digit does not make every encoder step a jump.
        let mut steps = vec![2.0, 2.0 + 1e-15];
        steps.extend((0..60).map(|i| 2.5 + 0.5 * f64::from(i / 3)));
        check(&steps, &[]);
        check(&[], &[]);
    }
}
