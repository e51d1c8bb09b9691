//! Rests of joints that dry friction holds, left out of effort space.
//!
//! Stuck, a joint's dry friction is whatever holds it: any effort up to its static level, set by
//! what the drive, gravity and the rest of the tree push with while it rests, not the value a law
//! of the speed takes near zero. Those samples say only that the level is at least what they
//! show. Fitted through them (and through the filter's support around them, where every term is
//! a blend of the rest and the motion), the law is pulled towards whatever pushed while the joint
//! stuck: the Robotics Toolbox's PUMA 560 under a plain computed-torque drive (its friction not
//! fed forward), stuck 14–53 % of the time on its six joints, had 8 of its 18 joints over three
//! seeds read right, its viscous damping missed on up to four joints a seed and two false
//! positives. Robot identification leaves samples near zero speed out of friction fits for this
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
//!
//! The rests are left out with the filters' support around them, where a third of the usable
//! samples stay (`effort_mode::without_rests`: the recording and its training part both read
//! without the rests the whole recording's reading finds), and the readings are made again. The
//! joint's Coulomb candidates then keep the transition read with the rests, and no Stribeck law
//! is tried: its break-away, like the transition, lives in the samples left out.
//!
//! The rests can also be what keeps a reading from naming the friction that holds them, or from
//! explaining the joint at all: stuck, the residual is whatever holds the joint. So a joint that
//! dwells at rest ([`dwelling_rests`]) and whose reading leaves a material share of its effort
//! unexplained is read again without its rests, down to a twentieth of its samples, and that
//! reading is kept only where it names Coulomb friction that could hold them, as [`held_rests`]
//! judges it (`effort_mode::without_unexplained_rests`): a reading consistent with its own
//! exclusions.

use super::effects::EffectKind;
use super::effort::{JointFinding, SelectionRules, dry_friction_at_rest, rms};

/// One joint's rests that its dry friction holds ([`held_rests`]).
#[derive(Debug, Clone, PartialEq)]
pub struct HeldRests {
    /// Per sample: a rest (not yet widened by the filters' support).
    pub rests: Vec<bool>,
    /// The transition speed of the joint's dry friction, read with the rests (rad/s or m/s): what
    /// a reading without them keeps, since the samples that show a law's shape through zero speed
    /// are the ones left out.
    pub transition_speed: f64,
}

/// Where one joint rests held by the dry friction of its reading `finding`, or None where its
/// rests stay in effort space: no dry friction of a single transition (`coulomb_friction`) in the
/// reading, a friction small beside the gravity effort the joint carries, or a joint that does not
/// dwell at rest (see the module documentation). `speed` is the joint's smoothed speed per sample;
/// `used`, the samples its effort row may use (usable, not left out already). A joint's sizes
/// (its effort, gravity and inertial RMS, against which every term is judged) are then measured
/// over the samples it keeps.
#[must_use]
pub fn held_rests(finding: &JointFinding, speed: &[f64], used: &[bool], rules: &SelectionRules) -> Option<HeldRests> {
    let (level, transition_speed) = coulomb_at_rest(finding)?;
    if level < rules.min_held_friction_over_gravity * finding.gravity_rms {
        return None;
    }
    Some(HeldRests { rests: dwelling_rests(speed, used, rules)?.rests, transition_speed })
}

/// The static level and the transition speed of the Coulomb friction (`coulomb_friction`) of the
/// reading `finding`, where it names one with a positive level and a finite positive transition;
/// None otherwise.
#[must_use]
pub fn coulomb_at_rest(finding: &JointFinding) -> Option<(f64, f64)> {
    let law = finding.effects.iter().find(|e| e.kind == EffectKind::CoulombFriction)?;
    let (level, transition_speed) = dry_friction_at_rest(law)?;
    (level > 0.0 && transition_speed.is_finite() && transition_speed > 0.0).then_some((level, transition_speed))
}

/// Where a joint dwells at rest ([`dwelling_rests`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Dwelling {
    /// Per sample: a rest.
    pub rests: Vec<bool>,
    /// The speed below which the joint counts as at rest (rad/s or m/s).
    pub rest_speed: f64,
}

/// Where the joint rests, if it dwells at rest (see the module documentation); None where it
/// does not. `speed` and `used` as for [`held_rests`].
#[must_use]
pub fn dwelling_rests(speed: &[f64], used: &[bool], rules: &SelectionRules) -> Option<Dwelling> {
    let kept: Vec<f64> = speed.iter().zip(used).filter(|(v, u)| **u && v.is_finite()).map(|(v, _)| *v).collect();
    if kept.is_empty() {
        return None;
    }
    let v_rms = rms(kept.iter().copied());
    let slow = rules.rest_speed_share * v_rms;
    let below = kept.iter().filter(|v| v.abs() < slow).count();
    let next = kept.iter().filter(|v| (slow..2.0 * slow).contains(&v.abs())).count();
    if below == 0 || below as f64 <= rules.min_dwell_ratio * next as f64 {
        return None;
    }
    Some(Dwelling { rests: speed.iter().zip(used).map(|(v, u)| *u && v.abs() < slow).collect(), rest_speed: slow })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::effects::Effect;

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
        let held = held_rests(&finding(level, gravity_rms), &v, &used, &SelectionRules::default());
        assert!(held.as_ref().is_none_or(|h| (h.transition_speed - 0.01).abs() < 1e-15), "the reading's transition is kept");
        assert_eq!(held.map(|h| h.rests.iter().filter(|&&x| x).count()), expected, "hold {hold}, level {level}, gravity {gravity_rms}");
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
