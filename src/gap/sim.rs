//! The fitter's 1-DoF integrator: one joint at a time, the moving subtree rigid, the other joints
//! held at their recorded positions (their terms are evaluated per sample). Per joint rather than
//! the full chain because each effect lives on one joint and the recorded neighbours are better
//! known than simulated ones; it also keeps a fit to a few parameters and a few thousand steps.
//!
//! Velocity by the trapezoidal rule for viscous damping (position forces at the predicted midpoint)
//! with Coulomb friction as a clamped impulse
//! (so sticking is exact, no chattering), position by the trapezoidal rule; stops and the soft-close
//! zone boundary as events located within the step (impact with restitution, then the rest of the
//! step), position clamps as the fallback. A compliant stop is a spring–damper force instead, and
//! a step that reaches into one is cut into sub-steps of a [`CONTACT_SUBSTEPS`]th of its contact.

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

/// One integration step of length h from (q, v) under `effort`, with event handling: when the
/// step crosses a stop (model limit or extra stop) or the soft-close engage position, the step is
/// cut at the crossing (located by linear interpolation of the trapezoidal position), the impact
/// or zone change applied there, and the rest of the step integrated from it. Without this, a
/// restitution-0 stop hit mid-step loses the effort's pull for the rest of the step, and a
/// damping zone switches a whole step late: errors of O(h) that look like missing physics.
#[must_use]
pub fn step(p: &JointPhysics, terms: &JointTerms, effort: f64, q: f64, v: f64, h: f64) -> (f64, f64) {
    let whole = step_events(p, terms, effort, q, v, h, 0);
    let Some(contact_s) = p.shortest_contact_s() else { return whole };
    // Within reach of the stop at the start's speed, or past it at the end: a step may dip into a
    // stiff contact and out again, and its midpoint force would throw the joint back.
    let touches = p.stops.iter().any(|s| s.is_compliant() && (s.penetration(q) + v.abs() * h > 0.0 || s.penetration(whole.0) > 0.0));
    let n = (h * CONTACT_SUBSTEPS / contact_s).ceil();
    if !touches || n <= 1.0 {
        return whole;
    }
    let h_sub = h / n;
    (0..n as usize).fold((q, v), |(q, v), _| step_events(p, terms, effort, q, v, h_sub, 0))
}

/// Sub-steps per contact time inside a compliant stop: the spring's phase advances π/40 per
/// sub-step, so a bounce's restitution and duration come out within a percent.
pub const CONTACT_SUBSTEPS: f64 = 40.0;

/// Most events handled within one step before falling back to clamping.
const MAX_EVENTS: usize = 4;

/// What happens at a crossing.
#[derive(Debug, Clone, Copy)]
enum Event {
    /// A stop at `position`: (restitution, blocks upward).
    Stop(f64, f64, bool),
    /// The soft-close zone boundary at `position`.
    Zone(f64),
}

/// The joint's inertia under `p`: the modelled one scaled, plus armature.
fn inertia_of(p: &JointPhysics, terms: &JointTerms) -> f64 {
    p.inertia(terms.inertia)
}

/// The gravity effort under `p` (a heavier part weighs more).
fn gravity_of(p: &JointPhysics, terms: &JointTerms, q: f64) -> f64 {
    let g = if terms.gravity_cos == 0.0 && terms.gravity_sin == 0.0 { terms.gravity_const } else { terms.gravity(q) };
    g * p.mass_scale
}

fn free_step(p: &JointPhysics, terms: &JointTerms, effort: f64, q: f64, v: f64, h: f64) -> (f64, f64) {
    let inertia = inertia_of(p, terms);
    // Position forces at the predicted midpoint and trapezoidal damping: second order, so that a
    // stiff spring or a strong soft-close damper does not drift from the truth over seconds.
    let q_mid = q + 0.5 * h * v;
    let (contact, contact_damping) = p.compliant_contact(q_mid, inertia);
    let force = effort + p.effort_offset + terms.coupling + gravity_of(p, terms, q_mid) + p.position_effort(q_mid) + contact;
    // Damping of the zone the step moves into (a start exactly on the engage position counts
    // the side the joint is heading to).
    let k = 0.5 * h * (p.damping_at(q_mid) + contact_damping) / inertia;
    let free = v * (1.0 - k) + h * force / inertia;
    let v_new = if p.friction_shape.transition_speed > 0.0 {
        // Smooth friction, linearised about v and taken implicitly: stable for any step even
        // when the transition is much faster than the step.
        let s = p.friction_shape.transition_speed;
        let level = p.friction_level(v);
        let slope = level / s * (1.0 - (v / s).tanh().powi(2));
        let f0 = p.smooth_friction(v);
        (free + h * (f0 + slope * v) / inertia) / (1.0 + k + h * slope / inertia)
    } else {
        let direction = if free == 0.0 { v } else { free };
        let friction_dv = h * p.friction_level(direction) / inertia;
        if free.abs() <= friction_dv { 0.0 } else { (free - friction_dv * free.signum()) / (1.0 + k) }
    };
    // Trapezoidal position update: exact for piecewise-constant acceleration (the held effort).
    (q + 0.5 * h * (v + v_new), v_new)
}

fn step_events(p: &JointPhysics, terms: &JointTerms, effort: f64, q: f64, v: f64, h: f64, depth: usize) -> (f64, f64) {
    let (q1, v1) = free_step(p, terms, effort, q, v, h);
    if depth < MAX_EVENTS && h > 1e-9 {
        // The earliest crossing within the step: fraction s of h.
        let mut first: Option<(f64, Event)> = None;
        let mut consider = |position: f64, event: Event, upward: Option<bool>| {
            let crosses = match upward {
                Some(true) => q <= position && q1 > position,
                Some(false) => q >= position && q1 < position,
                None => (q - position) * (q1 - position) < 0.0,
            };
            if crosses {
                let s = ((position - q) / (q1 - q)).clamp(0.0, 1.0);
                if first.is_none_or(|(f, _)| s < f) {
                    first = Some((s, event));
                }
            }
        };
        if let Some(lo) = p.lower {
            consider(lo, Event::Stop(lo, p.limit_restitution, false), Some(false));
        }
        if let Some(hi) = p.upper {
            consider(hi, Event::Stop(hi, p.limit_restitution, true), Some(true));
        }
        for s in p.stops.iter().filter(|s| !s.is_compliant()) {
            consider(s.position, Event::Stop(s.position, s.restitution, s.blocks_upward), Some(s.blocks_upward));
        }
        if let Some((_, engage)) = p.soft_close {
            consider(engage, Event::Zone(engage), None);
        }
        if let Some((s, event)) = first {
            let at = s * h;
            // State at the crossing: the step redone up to it, so that the forces and the damping
            // zone of the side it starts on act (the full step may have used the other zone's).
            let ve = free_step(p, terms, effort, q, v, at).1;
            let (qe, ve) = match event {
                Event::Stop(position, restitution, up) => {
                    let into = if up { ve > 0.0 } else { ve < 0.0 };
                    let mut rebound = if into { -restitution * ve } else { ve };
                    // Pushed back into the stop, the bounces form a geometric series lasting
                    // 2|v|/(|a|(1 − e)): when that ends within this step the joint comes to rest.
                    let a = (effort + p.effort_offset + terms.coupling + gravity_of(p, terms, position) + p.position_effort(position))
                        / inertia_of(p, terms);
                    let pushed = if up { a > 0.0 } else { a < 0.0 };
                    if into && pushed && 2.0 * rebound.abs() <= a.abs() * (1.0 - restitution).max(1e-3) * (h - at) {
                        rebound = 0.0;
                    }
                    (position, rebound)
                }
                Event::Zone(position) => (position, ve),
            };
            // A crossing at the very start (resting on a stop, pushed into it) would repeat:
            // it is left to the clamps below.
            if at > 1e-12 || matches!(event, Event::Zone(_)) || (ve - v).abs() > 1e-12 {
                return step_events(p, terms, effort, qe, ve, h - at, depth + 1);
            }
        }
    }
    clamp(p, q1, v1)
}

/// Keeps the state inside the model limits and the extra stops.
fn clamp(p: &JointPhysics, mut q_new: f64, mut v_new: f64) -> (f64, f64) {
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
    // Only reached while resting on a stop (or after many events in one step): no bounce.
    for s in p.stops.iter().filter(|s| !s.is_compliant()) {
        if s.blocks_upward && q_new > s.position {
            q_new = s.position;
            v_new = v_new.min(0.0);
        } else if !s.blocks_upward && q_new < s.position {
            q_new = s.position;
            v_new = v_new.max(0.0);
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
    use crate::gap::effects::Stop;
    use crate::gap::model::DofKind;

    fn free_joint() -> JointPhysics {
        JointPhysics::free(DofKind::Continuous)
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
    fn a_compliant_stop_throws_the_joint_back_at_its_restitution_after_its_contact_time() {
        // A free 2 kg slide at 0.3 m/s into a compliant stop at 0.1 m: it leaves the stop at
        // restitution × its speed, having been inside for the contact time, as deep as the
        // spring–damper lets it go.
        for (restitution, contact_s) in [(0.9, 0.06), (0.5, 0.02), (0.1, 0.01)] {
            let mut p = JointPhysics::free(DofKind::Prismatic);
            let stop = Stop { position: 0.1, restitution, blocks_upward: true, contact_time_s: contact_s };
            p.stops.push(stop);
            let terms = JointTerms { inertia: 2.0, ..JointTerms::default() };
            let (mut q, mut v, mut t, mut inside_s) = (0.0, 0.3, 0.0, 0.0);
            while t < 1.5 {
                (q, v) = step(&p, &terms, 0.0, q, v, 0.002);
                t += 0.002;
                if q > 0.1 {
                    inside_s += 0.002;
                }
            }
            assert!((v + restitution * 0.3).abs() < 0.01 * 0.3, "e {restitution}: left at {v}");
            assert!((inside_s - contact_s).abs() <= 0.0021, "e {restitution}: inside {inside_s} s, not {contact_s}");
            assert!(q < 0.1, "e {restitution}: still inside at {q}");
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
