//! The fitter's 1-DoF integrator: one joint at a time, the moving subtree rigid, the other joints
//! held at their recorded positions (their terms are evaluated per sample). Per joint rather than
//! the full chain because each effect lives on one joint and the recorded neighbours are better
//! known than simulated ones; it also keeps a fit to a few parameters and a few thousand steps.
//!
//! Velocity by implicit Euler with implicit viscous damping and Coulomb friction as a clamped impulse
//! (so sticking is exact, no chattering), position by the trapezoidal rule, stops as position clamps with restitution.

use super::effects::JointPhysics;
use super::model::JointTerms;

/// Largest integration step, seconds.
pub const MAX_STEP_S: f64 = 0.002;

/// The recorded inputs of one joint, one entry per sample.
#[derive(Debug, Clone, Copy)]
pub struct SimInput<'a> {
    /// Sample times, s.
    pub time_s: &'a [f64],
    /// Applied effort, held until the next sample.
    pub effort: &'a [f64],
    /// Rigid-body terms per sample (other joints at their recorded positions).
    pub terms: &'a [JointTerms],
}

/// One integration step of length h from (q, v) under `effort`.
#[must_use]
pub fn step(p: &JointPhysics, terms: &JointTerms, effort: f64, q: f64, v: f64, h: f64) -> (f64, f64) {
    let inertia = (terms.inertia * p.mass_scale).max(1e-9);
    let gravity = if terms.gravity_cos == 0.0 && terms.gravity_sin == 0.0 { terms.gravity_const } else { terms.gravity(q) };
    let force = effort + gravity + p.position_effort(q);
    let free = v + h * force / inertia;
    let friction_dv = h * p.friction / inertia;
    let damping = p.damping_at(q);
    let mut v_new = if free.abs() <= friction_dv { 0.0 } else { (free - friction_dv * free.signum()) / (1.0 + h * damping / inertia) };
    // Trapezoidal position update: exact for piecewise-constant acceleration (the held effort).
    let mut q_new = q + 0.5 * h * (v + v_new);
    if let Some(lo) = p.lower
        && q_new < lo
    {
        q_new = lo;
        v_new = v_new.max(0.0);
    }
    if let Some(hi) = p.upper
        && q_new > hi
    {
        q_new = hi;
        v_new = v_new.min(0.0);
    }
    for s in &p.stops {
        if s.blocks_upward && q_new > s.position {
            q_new = s.position;
            if v_new > 0.0 {
                v_new *= -s.restitution;
            }
        } else if !s.blocks_upward && q_new < s.position {
            q_new = s.position;
            if v_new < 0.0 {
                v_new *= -s.restitution;
            }
        }
    }
    (q_new, v_new)
}

/// Simulates samples `i0..=i1` from state (q0, v0) at sample i0; writes positions into
/// `out[0..=i1-i0]` and returns the final velocity.
pub fn simulate(input: &SimInput<'_>, p: &JointPhysics, i0: usize, i1: usize, q0: f64, v0: f64, out: &mut [f64]) -> f64 {
    let (mut q, mut v) = (q0, v0);
    out[0] = q;
    for i in i0..i1 {
        let dt = input.time_s[i + 1] - input.time_s[i];
        let n = (dt / MAX_STEP_S).ceil().max(1.0) as usize;
        let h = dt / n as f64;
        let terms = &input.terms[i];
        let effort = input.effort[i];
        for _ in 0..n {
            (q, v) = step(p, terms, effort, q, v, h);
        }
        out[i + 1 - i0] = q;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::model::DofKind;

    fn free_joint() -> JointPhysics {
        JointPhysics {
            kind: DofKind::Continuous,
            damping: 0.0,
            friction: 0.0,
            stiffness: 0.0,
            rest_position: 0.0,
            tilt_amplitude: 0.0,
            tilt_equilibrium: 0.0,
            mass_scale: 1.0,
            stops: Vec::new(),
            soft_close: None,
            closed_end: 0.0,
            lower: None,
            upper: None,
        }
    }

    #[test]
    fn damped_spring_matches_the_closed_form() {
        let mut p = free_joint();
        (p.stiffness, p.damping) = (4.0, 0.4);
        let time: Vec<f64> = (0..=300).map(|i| f64::from(i) * 0.01).collect();
        let effort = vec![0.0; time.len()];
        let terms = vec![JointTerms { inertia: 1.0, ..JointTerms::default() }; time.len()];
        let mut out = vec![0.0; time.len()];
        simulate(&SimInput { time_s: &time, effort: &effort, terms: &terms }, &p, 0, 300, 1.0, 0.0, &mut out);
        // x'' + 0.4 x' + 4 x = 0: ζ = 0.1, ω = 2.
        let wd = 2.0 * (1.0f64 - 0.01).sqrt();
        let exact = |t: f64| (-0.2 * t).exp() * ((wd * t).cos() + 0.2 / wd * (wd * t).sin());
        for (i, t) in time.iter().enumerate() {
            assert!((out[i] - exact(*t)).abs() < 0.01, "t {t}: {} vs {}", out[i], exact(*t));
        }
    }

    #[test]
    fn coulomb_friction_holds_below_breakaway() {
        let mut p = free_joint();
        p.friction = 1.0;
        let terms = JointTerms { inertia: 1.0, ..JointTerms::default() };
        let (q, v) = step(&p, &terms, 0.9, 0.0, 0.0, 0.002);
        assert!(q == 0.0 && v == 0.0);
        let (_, v) = step(&p, &terms, 2.0, 0.0, 0.0, 0.002);
        assert!((v - 0.002).abs() < 1e-12);
    }
}
