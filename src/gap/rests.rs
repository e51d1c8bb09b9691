//! Rests of joints that dry friction holds, left out of effort space.
//!
//! Stuck, a joint's dry friction is whatever holds it: any effort up to its static level, set by
//! what the drive, gravity and the rest of the tree push with while it rests, not the value a law
//! of the speed takes near zero. Those samples say only that the level is at least what they
//! show. Fitted through them (and through the filter's support around them, where every term is
//! a blend of the rest and the motion), the law is pulled towards whatever pushed while the joint
//! stuck: the Robotics Toolbox's PUMA 560 under a plain computed-torque drive (its friction not
//! fed forward), stuck 14–53 % of the time on its six joints, had 8 of its 18 joints over three
//! seeds read right, its viscous damping missed on up to five joints and its dry friction up to
//! 16 % high. Robot identification leaves samples near zero speed out of friction fits for this
//! reason.
//!
//! Only rests that are rests: a joint that turns round smoothly passes through zero speed as
//! quickly as it passes any other low speed, and those samples show the law's shape through zero
//! (its transition), which a smooth law needs and a rest does not have. A joint dwells where it
//! spends far longer below a small speed than between it and twice it
//! ([`SelectionRules::min_dwell_ratio`]); the real Panda, whose joints turn round smoothly,
//! spends about as long in each (ratio 0.8–1.5 on its seven joints), the stuck PUMA 1.6–15 times
//! as long.
//!
//! And only where the rests are mostly friction: where the joint carries a gravity effort far
//! above its friction's level ([`SelectionRules::min_held_friction_over_gravity`]), its rests
//! still weigh the links it carries (what the model's own first-moment error and a sensor's
//! offset are told apart by), and the friction's share of them is a small error on that.

use super::effort::{JointFinding, SelectionRules};

/// The samples where one joint rests held by the dry friction of its reading `finding` (not yet
/// widened by the filters' support), or None where its rests stay in effort space: no dry
/// friction of a single transition (`coulomb_friction`) in the reading, a friction small beside
/// the gravity effort the joint carries, or a joint that does not dwell at rest (see the module
/// documentation). `speed` is the joint's smoothed speed per sample; `used`, the samples its
/// effort row uses.
#[must_use]
pub fn held_rests(finding: &JointFinding, speed: &[f64], used: &[bool], rules: &SelectionRules) -> Option<Vec<bool>> {
    let (level, _) = finding.friction_at_rest()?;
    finding.effects.iter().find(|e| e.kind == super::effects::EffectKind::CoulombFriction)?;
    if !(level > 0.0 && level >= rules.min_held_friction_over_gravity * finding.gravity_rms) {
        return None;
    }
    let kept: Vec<f64> = speed.iter().zip(used).filter(|(v, u)| **u && v.is_finite()).map(|(v, _)| *v).collect();
    if kept.is_empty() {
        return None;
    }
    let v_rms = (kept.iter().map(|v| v * v).sum::<f64>() / kept.len() as f64).sqrt();
    let slow = rules.rest_speed_share * v_rms;
    let below = kept.iter().filter(|v| v.abs() < slow).count();
    let next = kept.iter().filter(|v| (slow..2.0 * slow).contains(&v.abs())).count();
    if below == 0 || below as f64 <= rules.min_dwell_ratio * next as f64 {
        return None;
    }
    Some(speed.iter().zip(used).map(|(v, u)| *u && v.abs() < slow).collect())
}

/// The transition speed of the dry friction in `finding` (`coulomb_friction`'s): what a reading
/// without the joint's rests keeps, since the samples that show a law's shape through zero speed
/// are the ones left out.
#[must_use]
pub fn transition_speed(finding: &JointFinding) -> Option<f64> {
    finding.effects.iter().find(|e| e.kind == super::effects::EffectKind::CoulombFriction).map(|e| e.params[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::effects::{Effect, EffectKind};

    /// A finding on one joint with Coulomb friction of `level` and the gravity effort `gravity_rms`.
    fn finding(level: f64, gravity_rms: f64) -> JointFinding {
        JointFinding {
            joint: 0,
            effects: vec![Effect { kind: EffectKind::CoulombFriction, params: vec![level, 0.01, f64::NAN], blocks_upward: false }],
            param_std: vec![vec![0.0; 3]],
            confidence: vec![1.0],
            effect_rms: vec![level],
            cv_rms_before: 1.0,
            cv_rms_after: 0.1,
            effort_rms: 1.0,
            gravity_rms,
            model_correlation: 1.0,
            residual_before: Vec::new(),
            residual_after: Vec::new(),
            rejected: Vec::new(),
            first_moments: Vec::new(),
            rests_left_out: None,
        }
    }

    /// A sine of speed (amplitude 1, 400 samples a period), held at 0 for `hold` samples at each
    /// of its zeros.
    fn speed(hold: usize) -> Vec<f64> {
        let mut out = Vec::new();
        for i in 0..1200 {
            let v = (std::f64::consts::TAU * f64::from(i) / 400.0).sin();
            out.push(v);
            if i % 200 == 0 {
                out.extend(std::iter::repeat_n(0.0, hold));
            }
        }
        out
    }

    /// Whether the rests of `speed` are left out for a finding of friction `level` beside the
    /// gravity effort `gravity_rms`, and how many samples.
    fn check((hold, level, gravity_rms): (usize, f64, f64), expected: Option<usize>) {
        let v = speed(hold);
        let used = vec![true; v.len()];
        let rests = held_rests(&finding(level, gravity_rms), &v, &used, &SelectionRules::default());
        assert_eq!(rests.map(|r| r.iter().filter(|&&x| x).count()), expected, "hold {hold}, level {level}, gravity {gravity_rms}");
    }

    #[test]
    fn a_joint_that_sticks_where_it_turns_has_its_rests_left_out() {
        // A smooth sine spends about as long below 5 % of its RMS speed as between 5 and 10 %.
        check((0, 1.0, 0.0), None);
        // Held for 40 samples at each of its 6 zeros: 240 rests, and the samples of the sine
        // itself below 5 % of its RMS speed (0.032): 5 about each zero, 3 after the first and 2
        // before the end.
        check((40, 1.0, 0.0), Some(240 + 30));
        // A joint whose friction is small beside the gravity effort it carries keeps them.
        check((40, 1.0, 10.0), None);
        check((40, 1.0, 3.0), Some(270));
    }
}
