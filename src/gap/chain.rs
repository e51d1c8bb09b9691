//! Replaying a recording through the whole tree: every degree of freedom integrated together
//! under the recorded efforts (held between samples), with the multibody dynamics of the model
//! ([`crate::dynamics`]) and each joint's physics ([`JointPhysics`]: damping, friction of any
//! shape, springs, tilts, offsets, armature, a heavier part, stops). This is the position-space
//! check of a model found in effort space, and the replay that must be exact for a recording made
//! from the model's own equations.
//!
//! Semi-implicit Euler with sub-steps of at most [`MAX_STEP_S`]; friction as impulses solved by
//! projected Gauss–Seidel on the inverse mass matrix (exact sticking for ideal Coulomb, the
//! smooth law linearised and taken implicitly); hard stops clamp the position and reflect the
//! velocity with the stop's restitution, compliant ones push back as spring–dampers.

use glam::DVec3;

use super::effects::JointPhysics;
use super::sim::CONTACT_SUBSTEPS;
use crate::dynamics::MultiBody;
use crate::linalg::generalized_eigenvalues;

/// Largest integration step, s.
pub const MAX_STEP_S: f64 = 0.0005;

/// Gauss–Seidel sweeps for the friction impulses.
const SWEEPS: usize = 12;

/// One replay's inputs.
#[derive(Debug, Clone, Copy)]
pub struct ChainInput<'a> {
    /// Sample times, s.
    pub time_s: &'a [f64],
    /// Recorded effort per dof and sample (zeros where not recorded).
    pub effort: &'a [Vec<f64>],
    /// Gravity, m/s², world frame.
    pub gravity: DVec3,
}

/// Positions of every dof at every sample, from (q0, v0) at the first sample. `tree` must carry
/// any mass scaling already; `physics[d]` is dof d's physics.
#[must_use]
pub fn replay(tree: &MultiBody, physics: &[JointPhysics], input: &ChainInput<'_>, q0: &[f64], v0: &[f64]) -> Vec<Vec<f64>> {
    let n = input.time_s.len();
    let nd = tree.dof_count();
    let mut out = vec![vec![f64::NAN; n]; nd];
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    if n == 0 {
        return out;
    }
    for d in 0..nd {
        out[d][0] = q[d];
    }
    for i in 0..n - 1 {
        let dt = input.time_s[i + 1] - input.time_s[i];
        // A compliant stop's contact in at least `CONTACT_SUBSTEPS` steps, as in the 1-DoF
        // integrator (its spring–damper is explicit here).
        let contact_steps =
            physics.iter().filter_map(JointPhysics::shortest_contact_s).map(|t| (dt * CONTACT_SUBSTEPS / t).ceil()).fold(0.0, f64::max);
        let steps = (dt / MAX_STEP_S).ceil().max(contact_steps).max(1.0) as usize;
        let h = dt / steps as f64;
        let effort: Vec<f64> = (0..nd).map(|d| input.effort.get(d).and_then(|e| e.get(i)).copied().unwrap_or(0.0)).collect();
        for _ in 0..steps {
            if !step(tree, physics, &effort, input.gravity, &mut q, &mut v, h) {
                return out;
            }
        }
        for d in 0..nd {
            out[d][i + 1] = q[d];
        }
    }
    out
}

/// One step; false when the mass matrix is singular (the replay stops there).
fn step(tree: &MultiBody, physics: &[JointPhysics], effort: &[f64], gravity: DVec3, q: &mut [f64], v: &mut [f64], h: f64) -> bool {
    let nd = q.len();
    let (mut m, bias) = tree.mass_matrix_and_bias(q, v, gravity);
    for d in 0..nd {
        m[d * nd + d] += physics[d].armature;
    }
    let Some(w) = crate::linalg::inverse_spd(&m, nd) else { return false };
    let rhs: Vec<f64> = (0..nd)
        .map(|d| {
            let p = &physics[d];
            // A compliant stop's spring–damper at the joint's own diagonal inertia.
            let (contact, contact_damping) = p.compliant_contact(q[d], m[d * nd + d]);
            effort[d] + p.effort_offset + p.position_effort(q[d]) + contact - (p.damping_at(q[d]) + contact_damping) * v[d] - bias[d]
        })
        .collect();
    let v_free: Vec<f64> = (0..nd).map(|d| v[d] + h * (0..nd).map(|k| w[d * nd + k] * rhs[k]).sum::<f64>()).collect();
    let impulse = friction_impulses(physics, &w, &v_free, v, h);
    for d in 0..nd {
        v[d] = v_free[d] + (0..nd).map(|k| w[d * nd + k] * impulse[k]).sum::<f64>();
        q[d] += h * v[d];
        stop(&physics[d], &mut q[d], &mut v[d]);
    }
    q.iter().chain(v.iter()).all(|x| x.is_finite())
}

/// Friction impulses by projected Gauss–Seidel on `w` = M⁻¹.
fn friction_impulses(physics: &[JointPhysics], w: &[f64], v_free: &[f64], v_old: &[f64], h: f64) -> Vec<f64> {
    let nd = v_free.len();
    let mut p = vec![0.0; nd];
    if physics.iter().all(|x| x.friction == 0.0 && x.friction_shape.friction_reverse.is_none_or(|r| r == 0.0)) {
        return p;
    }
    // A smooth law linearised about the step's start velocity, implicit in the new one: its
    // force there and its slope, the same in every sweep.
    let smooth: Vec<Option<(f64, f64)>> = physics
        .iter()
        .zip(v_old)
        .map(|(phys, &v)| {
            let s = phys.friction_shape.transition_speed;
            (s > 0.0).then(|| {
                // [`JointPhysics::smooth_friction`]'s force, its tanh taken once.
                let (level, tanh) = (phys.friction_level(v), (v / s).tanh());
                let slope = level / s * (1.0 - tanh.powi(2));
                ((-level * tanh).abs() * v.signum(), slope)
            })
        })
        .collect();
    for _ in 0..SWEEPS {
        let mut moved = false;
        for d in 0..nd {
            let wdd = w[d * nd + d].max(1e-12);
            let c = v_free[d] + (0..nd).filter(|&k| k != d).map(|k| w[d * nd + k] * p[k]).sum::<f64>();
            let next = if let Some((force, slope)) = smooth[d] {
                -h * (force + slope * (c - v_old[d])) / (1.0 + h * slope * wdd)
            } else {
                // Ideal Coulomb: the impulse that stops the joint, within the friction cone.
                let level = h * physics[d].friction_level(if c == 0.0 { v_old[d] } else { c });
                (-c / wdd).clamp(-level, level)
            };
            moved |= next.to_bits() != p[d].to_bits();
            p[d] = next;
        }
        // A sweep that changed no impulse to the bit is a fixed point: every later sweep would
        // compute the same numbers again.
        if !moved {
            break;
        }
    }
    p
}

/// Model limits (inelastic) and extra stops (with restitution).
fn stop(p: &JointPhysics, q: &mut f64, v: &mut f64) {
    if let Some(lo) = p.lower
        && *q < lo
    {
        *q = lo;
        *v = v.max(0.0);
    }
    if let Some(hi) = p.upper
        && *q > hi
    {
        *q = hi;
        *v = v.min(0.0);
    }
    for s in p.stops.iter().filter(|s| !s.is_compliant()) {
        let beyond = if s.blocks_upward { *q > s.position } else { *q < s.position };
        if beyond {
            *q = s.position;
            let into = if s.blocks_upward { *v > 0.0 } else { *v < 0.0 };
            if into {
                *v *= -s.restitution;
            }
        }
    }
}

/// How fast gravity drives the tree away from configuration `q`, 1/s: linearised at rest,
/// `M δq̈ = −K δq` with `K = ∂G/∂q` (the gravity efforts' stiffness, by finite differences), so
/// errors grow as e^{λt} with λ² the largest eigenvalue of `−K` against `M`; 0 where every
/// direction is stable (a hanging chain) or the mass matrix is singular. An arm held up by its
/// controller against gravity diverges within a few tenths of a second when replayed open loop
/// under its recorded efforts, whatever the model: a replay longer than that measures the
/// divergence, not the model.
#[must_use]
pub fn instability_rate(tree: &MultiBody, q: &[f64], gravity: DVec3) -> f64 {
    let n = q.len();
    let zero = vec![0.0; n];
    let at = |q: &[f64]| tree.inverse_dynamics(q, &zero, &zero, gravity);
    let g0 = at(q);
    let h = 1e-6;
    let mut k = vec![0.0; n * n];
    for j in 0..n {
        let mut qj = q.to_vec();
        qj[j] += h;
        for (i, g) in at(&qj).into_iter().enumerate() {
            k[i * n + j] = -(g - g0[i]) / h;
        }
    }
    // −K is symmetric (the Hessian of the potential energy, negated) up to the differences'
    // rounding.
    let minus_k: Vec<f64> = (0..n * n).map(|i| 0.5 * (k[i] + k[(i % n) * n + i / n])).collect();
    generalized_eigenvalues(&minus_k, &tree.mass_matrix(q), n)
        .and_then(|mu| mu.last().copied())
        .map_or(0.0, |mu| if mu.is_finite() { mu.max(0.0).sqrt() } else { 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::effects::Stop;
    use crate::gap::model::parse_model;

    #[test]
    fn a_compliant_stop_in_a_chain_throws_the_joint_back_at_its_restitution_after_its_contact_time() {
        // A 2 kg slide at 0.3 m/s into a compliant stop at 0.1 m, gravity off: it comes back at
        // restitution × its speed after the contact time, as in the 1-DoF integrator.
        let urdf = r#"<robot name="slide"><link name="base"/>
          <link name="drawer"><inertial><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <joint name="slide" type="prismatic"><parent link="base"/><child link="drawer"/><axis xyz="1 0 0"/>
            <limit lower="-1" upper="1" effort="10" velocity="1"/></joint></robot>"#;
        let model = parse_model(urdf, std::path::Path::new("slide.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let mut physics = JointPhysics::nominal(&model.joints[model.dofs()[0]]);
        physics.stops.push(Stop { position: 0.1, restitution: 0.6, blocks_upward: true, contact_time_s: 0.04 });
        let time_s: Vec<f64> = (0..=1000).map(|i| f64::from(i) * 0.001).collect();
        let effort = vec![vec![0.0; time_s.len()]];
        let q = replay(&tree, &[physics], &ChainInput { time_s: &time_s, effort: &effort, gravity: DVec3::ZERO }, &[0.0], &[0.3]);
        let inside_s = q[0].iter().filter(|&&x| x > 0.1).count() as f64 * 0.001;
        let speed = (q[0][1000] - q[0][900]) / 0.1;
        assert!((inside_s - 0.04).abs() <= 0.002, "inside {inside_s} s");
        assert!((speed + 0.6 * 0.3).abs() < 0.02 * 0.3, "left at {speed}");
    }

    #[test]
    fn a_chain_held_up_diverges_at_its_pendulum_rate_and_a_hanging_one_does_not() {
        // Two links on parallel axes, each 1 kg at 0.5 m down its 1 m link (point masses and a
        // little inertia). Upright, the lower link straight above the upper: δq̈ = M⁻¹(−K)δq with
        // M = [[2.5, 0.75], [0.75, 0.25]] + 0.01·[[2, 1], [1, 1]] and −K = g·[[2, 0.5], [0.5, 0.5]]
        // (the potential's Hessian); hanging, −K is negated and nothing diverges.
        let urdf = r#"<robot name="arm"><link name="base"/>
          <link name="a"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <link name="b"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <joint name="shoulder" type="continuous"><parent link="base"/><child link="a"/><axis xyz="0 1 0"/></joint>
          <joint name="elbow" type="continuous"><parent link="a"/><child link="b"/><origin xyz="0 0 -1"/><axis xyz="0 1 0"/></joint></robot>"#;
        let model = parse_model(urdf, std::path::Path::new("arm.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let g = 9.81;
        let gravity = DVec3::new(0.0, 0.0, -g);
        let m = [2.5 + 0.02, 0.75 + 0.01, 0.75 + 0.01, 0.25 + 0.01];
        let minus_k = [2.0 * g, 0.5 * g, 0.5 * g, 0.5 * g];
        let want = generalized_eigenvalues(&minus_k, &m, 2).expect("positive definite").last().copied().expect("two").sqrt();
        let upright = instability_rate(&tree, &[std::f64::consts::PI, 0.0], gravity);
        assert!((upright - want).abs() < 1e-4 * want, "{upright} against {want}");
        assert!(instability_rate(&tree, &[0.0, 0.0], gravity) < 1e-3, "hanging");
    }
}
