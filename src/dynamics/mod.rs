//! Rigid multibody dynamics of a kinematic tree (fixed base): inverse dynamics by the recursive
//! Newton–Euler algorithm, the joint-space mass matrix by the composite-rigid-body algorithm, and
//! forward dynamics from the two (Featherstone, *Rigid Body Dynamics Algorithms*, ch. 5–6).
//!
//! Convention: `τ = M(q) q̈ + b(q, q̇)`, where `b` holds Coriolis, centrifugal and gravity
//! efforts — the convention of Pinocchio's `rnea`/`crba` and `MuJoCo`'s `qfrc_bias`/`mj_fullM`
//! (checked against both by `scripts/check_dynamics.py`). The reality gap uses it for coupled
//! replays and effort-space identification; anything that simulates a tree can.
//!
//! Written here rather than taken from a crate: the Rust robotics crates either do kinematics
//! only (`k`) or keep their multibody dynamics internal to a simulator (rapier), and none gives
//! RNEA/CRBA with per-body inertia access, which identification needs (the effort of one body's
//! inertia is a regressor). The algorithms are short; `spatial` holds the 6D algebra.

pub mod spatial;

use glam::{DQuat, DVec3};

use spatial::{Force, Motion, ParentFromChild, RigidInertia};

/// How a body moves relative to its parent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointMotion {
    /// Welded.
    Fixed,
    /// Rotation about a unit axis of the joint frame, q in rad.
    Revolute(DVec3),
    /// Translation along a unit axis of the joint frame, q in m.
    Prismatic(DVec3),
}

impl JointMotion {
    /// The joint's motion subspace in the child frame (unit speed).
    #[must_use]
    pub fn subspace(&self) -> Motion {
        match *self {
            Self::Fixed => Motion::default(),
            Self::Revolute(axis) => Motion { angular: axis, linear: DVec3::ZERO },
            Self::Prismatic(axis) => Motion { angular: DVec3::ZERO, linear: axis },
        }
    }

    /// Joint frame ← child frame at position q.
    #[must_use]
    pub fn transform(&self, q: f64) -> ParentFromChild {
        match *self {
            Self::Fixed => ParentFromChild::new(DQuat::IDENTITY, DVec3::ZERO),
            Self::Revolute(axis) => ParentFromChild::new(DQuat::from_axis_angle(axis, q), DVec3::ZERO),
            Self::Prismatic(axis) => ParentFromChild::new(DQuat::IDENTITY, axis * q),
        }
    }
}

/// One body (a link other than the fixed root) and the joint that carries it.
#[derive(Debug, Clone)]
pub struct Body {
    /// The link's name.
    pub name: String,
    /// Parent body (an earlier index); None for the fixed root.
    pub parent: Option<usize>,
    /// Parent frame ← joint frame (the child frame at q = 0).
    pub parent_from_joint: ParentFromChild,
    /// The joint.
    pub joint: JointMotion,
    /// Index of the joint's coordinate in q (None for fixed joints).
    pub dof: Option<usize>,
    /// Inertia in the body frame.
    pub inertia: RigidInertia,
}

/// A tree that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DynamicsError {
    /// Bodies out of order or coordinates missing.
    #[error("multibody: {0}")]
    Invalid(String),
}

/// A kinematic tree with a fixed root, bodies ordered parents first.
#[derive(Debug, Clone)]
pub struct MultiBody {
    bodies: Vec<Body>,
    dof_count: usize,
}

/// Per-body kinematics at one state: placements, velocities, accelerations (bias included).
#[derive(Debug, Clone)]
pub struct Kinematics {
    /// Parent frame ← body frame at q.
    pub parent_from_body: Vec<ParentFromChild>,
    /// Spatial velocity of each body, body frame.
    pub velocity: Vec<Motion>,
    /// Spatial acceleration of each body (gravity as an upward base acceleration), body frame.
    pub acceleration: Vec<Motion>,
}

impl MultiBody {
    /// Checks the order (parents first) and that the coordinates are `0..n`, each used once.
    pub fn new(bodies: Vec<Body>) -> Result<Self, DynamicsError> {
        let mut seen = Vec::new();
        for (i, b) in bodies.iter().enumerate() {
            if b.parent.is_some_and(|p| p >= i) {
                return Err(DynamicsError::Invalid(format!("body {} comes before its parent", b.name)));
            }
            if (b.dof.is_some()) == (b.joint == JointMotion::Fixed) {
                return Err(DynamicsError::Invalid(format!("body {}: a coordinate exactly when the joint moves", b.name)));
            }
            seen.extend(b.dof);
        }
        seen.sort_unstable();
        if seen.iter().enumerate().any(|(i, d)| i != *d) {
            return Err(DynamicsError::Invalid("coordinates are not 0..n, each once".into()));
        }
        Ok(Self { dof_count: seen.len(), bodies })
    }

    /// Number of coordinates.
    #[must_use]
    pub fn dof_count(&self) -> usize {
        self.dof_count
    }

    /// The same tree with body `body`'s inertia scaled by `s` (a heavier part).
    #[must_use]
    pub fn with_body_scaled(&self, body: usize, s: f64) -> Self {
        let mut out = self.clone();
        if let Some(b) = out.bodies.get_mut(body) {
            b.inertia = b.inertia.scaled(s);
        }
        out
    }

    /// The same tree with `first_moment` (kg·m, body frame) added to body `body`'s mass × centre
    /// of mass, its mass and rotational inertia about its origin left as they are (a centre of
    /// mass a little off).
    #[must_use]
    pub fn with_first_moment_added(&self, body: usize, first_moment: DVec3) -> Self {
        let mut out = self.clone();
        if let Some(b) = out.bodies.get_mut(body) {
            b.inertia.first_moment += first_moment;
        }
        out
    }

    /// The same tree on a base turned by `world_from_base` about the root frame's origin: every
    /// body carried by the fixed root is placed by it (a robot mounted on a tilted table). Under
    /// the same gravity this is the tree as it was with gravity turned by the inverse rotation.
    #[must_use]
    pub fn with_base_rotated(&self, world_from_base: DQuat) -> Self {
        let turn = ParentFromChild::new(world_from_base, DVec3::ZERO);
        let mut out = self.clone();
        for b in out.bodies.iter_mut().filter(|b| b.parent.is_none()) {
            b.parent_from_joint = turn.then(&b.parent_from_joint);
        }
        out
    }

    /// The bodies, parents first.
    #[must_use]
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    fn coordinate(v: &[f64], b: &Body) -> f64 {
        b.dof.map_or(0.0, |d| v.get(d).copied().unwrap_or(0.0))
    }

    /// Each body's placement in its parent's frame at q.
    #[must_use]
    pub fn placements(&self, q: &[f64]) -> Vec<ParentFromChild> {
        self.bodies.iter().map(|b| b.parent_from_joint.then(&b.joint.transform(Self::coordinate(q, b)))).collect()
    }

    /// The forward pass of RNEA: placements, velocities and accelerations of every body.
    #[must_use]
    pub fn kinematics(&self, q: &[f64], qd: &[f64], qdd: &[f64], gravity: DVec3) -> Kinematics {
        self.kinematics_at(self.placements(q), qd, qdd, gravity)
    }

    /// [`Self::kinematics`] from the placements at q ([`Self::placements`]).
    fn kinematics_at(&self, parent_from_body: Vec<ParentFromChild>, qd: &[f64], qdd: &[f64], gravity: DVec3) -> Kinematics {
        let n = self.bodies.len();
        let mut k = Kinematics { parent_from_body, velocity: Vec::with_capacity(n), acceleration: Vec::with_capacity(n) };
        let base_acceleration = Motion { angular: DVec3::ZERO, linear: -gravity };
        for (b, x) in self.bodies.iter().zip(&k.parent_from_body) {
            let (v_parent, a_parent) = b.parent.map_or((Motion::default(), base_acceleration), |p| (k.velocity[p], k.acceleration[p]));
            let s = b.joint.subspace();
            let vj = s * Self::coordinate(qd, b);
            let v = x.motion_to_child(&v_parent) + vj;
            let a = x.motion_to_child(&a_parent) + s * Self::coordinate(qdd, b) + v.cross_motion(&vj);
            k.velocity.push(v);
            k.acceleration.push(a);
        }
        k
    }

    /// The backward pass of RNEA with the bodies' inertias given by `inertia` (None: massless):
    /// the joint efforts those inertias need for the motion in `k`.
    #[must_use]
    pub fn efforts_with(&self, k: &Kinematics, inertia: impl Fn(usize) -> Option<RigidInertia>) -> Vec<f64> {
        let mut forces: Vec<Force> = (0..self.bodies.len())
            .map(|i| {
                inertia(i).map_or_else(Force::default, |body| {
                    let v = k.velocity[i];
                    body.apply(&k.acceleration[i]) + v.cross_force(&body.apply(&v))
                })
            })
            .collect();
        let mut tau = vec![0.0; self.dof_count];
        for i in (0..self.bodies.len()).rev() {
            let b = &self.bodies[i];
            if let Some(d) = b.dof {
                tau[d] = b.joint.subspace().dot(&forces[i]);
            }
            if let Some(p) = b.parent {
                let f = k.parent_from_body[i].force_to_parent(&forces[i]);
                forces[p] += f;
            }
        }
        tau
    }

    /// Inverse dynamics (RNEA): the efforts that produce q̈ at (q, q̇) under `gravity`.
    #[must_use]
    pub fn inverse_dynamics(&self, q: &[f64], qd: &[f64], qdd: &[f64], gravity: DVec3) -> Vec<f64> {
        let k = self.kinematics(q, qd, qdd, gravity);
        self.efforts_with(&k, |i| Some(self.bodies[i].inertia))
    }

    /// Coriolis, centrifugal and gravity efforts: RNEA with q̈ = 0.
    #[must_use]
    pub fn bias(&self, q: &[f64], qd: &[f64], gravity: DVec3) -> Vec<f64> {
        self.inverse_dynamics(q, qd, &[], gravity)
    }

    /// The joint-space mass matrix (CRBA), row-major n×n.
    #[must_use]
    pub fn mass_matrix(&self, q: &[f64]) -> Vec<f64> {
        self.mass_matrix_at(&self.placements(q))
    }

    /// The mass matrix at q and the bias efforts at (q, q̇) ([`Self::mass_matrix`],
    /// [`Self::bias`]: the same numbers) from one set of placements, as a forward-dynamics step
    /// needs both.
    #[must_use]
    pub fn mass_matrix_and_bias(&self, q: &[f64], qd: &[f64], gravity: DVec3) -> (Vec<f64>, Vec<f64>) {
        let placements = self.placements(q);
        let m = self.mass_matrix_at(&placements);
        let k = self.kinematics_at(placements, qd, &[], gravity);
        (m, self.efforts_with(&k, |i| Some(self.bodies[i].inertia)))
    }

    /// [`Self::mass_matrix`] from the placements at q.
    fn mass_matrix_at(&self, placements: &[ParentFromChild]) -> Vec<f64> {
        let n = self.dof_count;
        let mut composite: Vec<RigidInertia> = self.bodies.iter().map(|b| b.inertia).collect();
        for i in (0..self.bodies.len()).rev() {
            if let Some(p) = self.bodies[i].parent {
                let c = composite[i].to_parent(&placements[i]);
                composite[p] = composite[p] + c;
            }
        }
        let mut m = vec![0.0; n * n];
        for (i, b) in self.bodies.iter().enumerate() {
            let Some(di) = b.dof else { continue };
            let mut f = composite[i].apply(&b.joint.subspace());
            m[di * n + di] = b.joint.subspace().dot(&f);
            let mut j = i;
            while let Some(p) = self.bodies[j].parent {
                f = placements[j].force_to_parent(&f);
                j = p;
                if let Some(dj) = self.bodies[j].dof {
                    let v = self.bodies[j].joint.subspace().dot(&f);
                    m[di * n + dj] = v;
                    m[dj * n + di] = v;
                }
            }
        }
        m
    }

    /// Forward dynamics: q̈ = M⁻¹ (τ − b). None when the mass matrix is singular (a coordinate
    /// that moves no mass).
    #[must_use]
    pub fn forward_dynamics(&self, q: &[f64], qd: &[f64], tau: &[f64], gravity: DVec3) -> Option<Vec<f64>> {
        let n = self.dof_count;
        let bias = self.bias(q, qd, gravity);
        let rhs: Vec<f64> = (0..n).map(|i| tau.get(i).copied().unwrap_or(0.0) - bias[i]).collect();
        crate::linalg::solve_spd(&self.mass_matrix(q), &rhs, n)
    }
}

#[cfg(test)]
mod tests;
