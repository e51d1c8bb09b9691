//! Stops the model does not have, found in effort space. A stop's force acts only while the joint
//! is at it, so it has no regressor: the evidence is that at an extreme of the observed motion
//! that is not a modelled limit, the residual effort of the model as written pushes back from
//! the extreme, consistently and far beyond its level elsewhere — a free turning point of an
//! excitation trajectory shows no such push. The samples in contact are then left out of the
//! regression, and the restitution is read off the measured positions around each short impact.

use super::effects::{Effect, EffectKind};
use super::effort::{median, robust_scale};

/// What the evidence must show.
#[derive(Debug, Clone, Copy)]
pub struct StopRules {
    /// Contact band: this share of the observed travel (or four noise σ) from the extreme.
    pub band_share: f64,
    /// The mean residual in contact, over the residual's robust scale away from contact.
    pub min_push_sigmas: f64,
    /// The mean residual in contact, over the joint's RMS effort.
    pub min_push_share: f64,
    /// Fewest samples in contact.
    pub min_samples: usize,
}

impl Default for StopRules {
    fn default() -> Self {
        Self { band_share: 0.01, min_push_sigmas: 4.0, min_push_share: 0.1, min_samples: 3 }
    }
}

/// A stop found on one joint.
#[derive(Debug, Clone)]
pub struct FoundStop {
    /// The effect (`end_stop`: position, restitution; `blocks_upward`).
    pub effect: Effect,
    /// Samples in contact (the band around the stop).
    pub contact: Vec<bool>,
    /// Mean push of the stop in contact (effort units).
    pub push: f64,
    /// Robust scale of the residual away from contact (effort units).
    pub scale: f64,
    /// Confidence from how far the push stands out.
    pub confidence: f64,
}

impl FoundStop {
    /// Whether the push would still pass `rules` (against the residual's scale and the joint's
    /// RMS effort `effort_rms`) with `held` taken off it: what dry friction of static level
    /// `held` found on the joint could hold there by itself. A drawer that its friction holds
    /// where a hand's push gives out rests at an extreme of its motion under a push, as one held
    /// by a stop does (three engines' loaded drawers, each "stopped" at a different extreme).
    #[must_use]
    pub fn beyond(&self, held: f64, effort_rms: f64, rules: &StopRules) -> bool {
        let push = self.push - held.max(0.0);
        push >= rules.min_push_sigmas * self.scale && push >= rules.min_push_share * effort_rms
    }
}

/// Looks for an unmodelled stop at each extreme of `y` (raw positions) with the nominal residual
/// effort `residual` (NaN where unused), `effort_rms` the joint's RMS effort, `noise` the
/// position noise σ, `limits` the model's stops.
#[must_use]
pub fn find_stops(
    time_s: &[f64],
    y: &[f64],
    residual: &[f64],
    effort_rms: f64,
    noise: f64,
    limits: (Option<f64>, Option<f64>),
    rules: &StopRules,
) -> Vec<FoundStop> {
    let finite: Vec<f64> = y.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    let band = (rules.band_share * (hi - lo)).max(4.0 * noise);
    let mut out = Vec::new();
    for (extreme, upward, limit) in [(hi, true, limits.1), (lo, false, limits.0)] {
        // At or beyond a modelled limit (soft stops let the joint sink into it): the model's.
        let at_limit = limit.is_some_and(|l| if upward { extreme >= l - 2.0 * band } else { extreme <= l + 2.0 * band });
        if at_limit {
            continue;
        }
        let contact: Vec<bool> = y.iter().map(|&v| v.is_finite() && (v - extreme).abs() <= band).collect();
        let inside: Vec<f64> = (0..y.len()).filter(|&i| contact[i] && residual[i].is_finite()).map(|i| residual[i]).collect();
        if inside.len() < rules.min_samples {
            continue;
        }
        let outside: Vec<f64> = (0..y.len()).filter(|&i| !contact[i] && residual[i].is_finite()).map(|i| residual[i]).collect();
        let scale = robust_scale(&outside).max(1e-12);
        // An upper stop pushes down: the recorded effort exceeds what the free model needs, and
        // by more than it does elsewhere: a residual level everywhere (a sensor offset) is not a
        // stop. The push counts from zero or from that level, whichever leaves it smaller.
        let sign = if upward { 1.0 } else { -1.0 };
        let raw = inside.iter().sum::<f64>() / inside.len() as f64 * sign;
        let push = raw.min(raw - median(&outside) * sign);
        if push < rules.min_push_sigmas * scale || push < rules.min_push_share * effort_rms {
            continue;
        }
        let restitution = restitution(time_s, y, &contact);
        out.push(FoundStop {
            effect: Effect { kind: EffectKind::EndStop, params: vec![extreme, restitution], blocks_upward: upward },
            contact,
            push,
            scale,
            confidence: (1.0 - (-(push / scale) / (2.0 * rules.min_push_sigmas)).exp()).clamp(0.0, 1.0),
        });
    }
    out
}

/// Median of |speed out| / |speed in| over short visits (impacts that bounce off); 0 when the
/// joint only ever comes to rest at the stop.
fn restitution(time_s: &[f64], y: &[f64], contact: &[bool]) -> f64 {
    let slope = |a: usize, b: usize| -> Option<f64> {
        let (ya, yb) = (y[a], y[b]);
        let dt = time_s[b] - time_s[a];
        (ya.is_finite() && yb.is_finite() && dt > 0.0).then(|| (yb - ya) / dt)
    };
    let mut ratios = Vec::new();
    let mut i = 0;
    while i < contact.len() {
        if !contact[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < contact.len() && contact[i] {
            i += 1;
        }
        let end = i - 1;
        if start >= 3
            && end + 3 < y.len()
            && end - start <= 3
            && let (Some(v_in), Some(v_out)) = (slope(start - 3, start - 1), slope(end + 1, end + 3))
            && v_in.abs() > 1e-9
        {
            ratios.push((v_out / v_in).abs().min(1.0));
        }
    }
    if ratios.is_empty() {
        return 0.0;
    }
    ratios.sort_by(f64::total_cmp);
    ratios[ratios.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A joint swinging between 0.1 and 0.9 (turning points at both), its nominal residual
    /// `level` everywhere plus `push` at the upper extreme; how many stops are found.
    fn check(level: f64, push_at_top: f64, expected_stops: usize) {
        check_held(level, push_at_top, 0.0, expected_stops);
    }

    /// As [`check`], with dry friction of static level `held` on the joint.
    fn check_held(level: f64, push_at_top: f64, held: f64, expected_stops: usize) {
        let time_s: Vec<f64> = (0..2000).map(|i| f64::from(i) * 0.005).collect();
        let y: Vec<f64> = time_s.iter().map(|t| 0.5 + 0.4 * (t * 2.0).sin()).collect();
        let residual: Vec<f64> = y
            .iter()
            .enumerate()
            .map(|(i, &q)| level + 1e-3 * ((i * 7919) % 13) as f64 / 13.0 + if q > 0.9 - 0.004 { push_at_top } else { 0.0 })
            .collect();
        let rules = StopRules::default();
        let mut found = find_stops(&time_s, &y, &residual, 1.0, 1e-4, (Some(0.0), Some(2.0)), &rules);
        found.retain(|s| s.beyond(held, 1.0, &rules));
        assert_eq!(
            found.len(),
            expected_stops,
            "level {level}, push {push_at_top}, friction {held}: {:?}",
            found.iter().map(|s| &s.effect).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_sensor_offset_at_a_turning_point_is_not_a_stop() {
        // Regression (MuJoCo drawer whose effort reads 2 N low): the offset, the same everywhere,
        // was taken for a stop at the lowest point of the motion.
        check(-2.0, 0.0, 0);
        check(2.0, 0.0, 0);
        check(0.0, 0.0, 0);
    }

    #[test]
    fn a_stop_that_pushes_beyond_an_offset_is_still_found() {
        check(0.0, 1.0, 1);
        check(0.3, 1.0, 1);
        check(-0.3, 1.0, 1);
    }

    #[test]
    fn a_push_its_friction_could_hold_is_no_stop() {
        // Regression (loaded drawers with 6 N of dry friction in DART, Klamp't and JaxSim): a
        // hand's push that gave out at an extreme of the motion left the drawer resting there
        // under it, and a stop was named at that extreme.
        check_held(0.0, 1.0, 1.0, 0);
        check_held(0.0, 1.0, 2.0, 0);
        check_held(0.0, 1.0, 0.5, 1);
        check_held(0.0, 3.0, 1.0, 1);
    }
}
