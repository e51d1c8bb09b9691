use glam::{DMat3, DQuat, DVec3};

use super::spatial::{ParentFromChild, RigidInertia};
use super::{Body, JointMotion, MultiBody};

const G: DVec3 = DVec3::new(0.0, 0.0, -9.81);

/// A planar double pendulum about +y, links of length l hanging along −z at q = 0, point masses.
fn double_pendulum(m1: f64, m2: f64, l1: f64, l2: f64) -> MultiBody {
    let point = |m: f64, l: f64| RigidInertia::from_com(m, DVec3::new(0.0, 0.0, -l), DMat3::ZERO);
    MultiBody::new(vec![
        Body {
            name: "upper".into(),
            parent: None,
            parent_from_joint: ParentFromChild::new(DQuat::IDENTITY, DVec3::ZERO),
            joint: JointMotion::Revolute(DVec3::Y),
            dof: Some(0),
            inertia: point(m1, l1),
        },
        Body {
            name: "lower".into(),
            parent: Some(0),
            parent_from_joint: ParentFromChild::new(DQuat::IDENTITY, DVec3::new(0.0, 0.0, -l1)),
            joint: JointMotion::Revolute(DVec3::Y),
            dof: Some(1),
            inertia: point(m2, l2),
        },
    ])
    .expect("valid tree")
}

/// The textbook equations of the double pendulum with point masses (angles from the downward
/// vertical, positive about +y, so a positive angle swings the mass towards −x… sign-free here:
/// both sides use the same convention through sin/cos of the relative angle).
fn textbook(m1: f64, m2: f64, l1: f64, l2: f64, q: [f64; 2], qd: [f64; 2], qdd: [f64; 2]) -> [f64; 2] {
    let g = 9.81;
    let c2 = q[1].cos();
    let s2 = q[1].sin();
    let m11 = (m1 + m2) * l1 * l1 + m2 * l2 * l2 + 2.0 * m2 * l1 * l2 * c2;
    let m12 = m2 * l2 * l2 + m2 * l1 * l2 * c2;
    let m22 = m2 * l2 * l2;
    let h = m2 * l1 * l2 * s2;
    let c1 = -h * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]);
    let c2t = h * qd[0] * qd[0];
    let g1 = (m1 + m2) * g * l1 * q[0].sin() + m2 * g * l2 * (q[0] + q[1]).sin();
    let g2 = m2 * g * l2 * (q[0] + q[1]).sin();
    [m11 * qdd[0] + m12 * qdd[1] + c1 + g1, m12 * qdd[0] + m22 * qdd[1] + c2t + g2]
}

#[test]
fn double_pendulum_matches_the_textbook_equations() {
    let (m1, m2, l1, l2) = (1.3, 0.7, 0.4, 0.3);
    let mb = double_pendulum(m1, m2, l1, l2);
    for (q, qd, qdd) in [([0.3, -0.8], [1.2, -0.4], [0.5, 2.0]), ([2.5, 1.0], [-3.0, 2.0], [-1.0, 0.1]), ([0.0; 2], [0.0; 2], [0.0; 2])] {
        let got = mb.inverse_dynamics(&q, &qd, &qdd, G);
        let want = textbook(m1, m2, l1, l2, q, qd, qdd);
        for i in 0..2 {
            assert!((got[i] - want[i]).abs() < 1e-12, "q {q:?}: joint {i}: {} vs {}", got[i], want[i]);
        }
    }
}

/// A branched tree with a prismatic joint, a fixed joint and tilted frames.
fn branched() -> MultiBody {
    let body =
        |m: f64, c: [f64; 3], d: [f64; 3]| RigidInertia::from_com(m, DVec3::from_array(c), DMat3::from_diagonal(DVec3::from_array(d)));
    let at = |rpy: [f64; 3], t: [f64; 3]| {
        ParentFromChild::new(DQuat::from_euler(glam::EulerRot::ZYX, rpy[2], rpy[1], rpy[0]), DVec3::from_array(t))
    };
    MultiBody::new(vec![
        Body {
            name: "a".into(),
            parent: None,
            parent_from_joint: at([0.1, 0.2, 0.3], [0.0, 0.1, 0.5]),
            joint: JointMotion::Revolute(DVec3::new(0.0, 0.6, 0.8)),
            dof: Some(0),
            inertia: body(2.0, [0.1, 0.0, 0.2], [0.02, 0.03, 0.04]),
        },
        Body {
            name: "b".into(),
            parent: Some(0),
            parent_from_joint: at([0.0, -0.4, 0.0], [0.3, 0.0, 0.1]),
            joint: JointMotion::Prismatic(DVec3::X),
            dof: Some(2),
            inertia: body(0.5, [0.0, 0.05, 0.0], [0.001, 0.002, 0.001]),
        },
        Body {
            name: "c".into(),
            parent: Some(0),
            parent_from_joint: at([0.5, 0.0, -0.2], [-0.2, 0.1, 0.0]),
            joint: JointMotion::Fixed,
            dof: None,
            inertia: body(0.3, [0.0, 0.0, 0.1], [0.001, 0.001, 0.002]),
        },
        Body {
            name: "d".into(),
            parent: Some(2),
            parent_from_joint: at([0.0, 0.0, 0.7], [0.0, 0.0, 0.2]),
            joint: JointMotion::Revolute(DVec3::Z),
            dof: Some(1),
            inertia: body(0.8, [0.1, 0.1, 0.0], [0.004, 0.005, 0.006]),
        },
    ])
    .expect("valid tree")
}

#[test]
fn mass_matrix_is_the_acceleration_part_of_inverse_dynamics() {
    let mb = branched();
    let q = [0.4, -1.1, 0.07];
    let qd = [0.9, -2.0, 0.3];
    let m = mb.mass_matrix(&q);
    let bias = mb.bias(&q, &qd, G);
    for c in 0..3 {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        let tau = mb.inverse_dynamics(&q, &qd, &e, G);
        for r in 0..3 {
            assert!((tau[r] - bias[r] - m[r * 3 + c]).abs() < 1e-12, "M[{r}][{c}]");
            assert!((m[r * 3 + c] - m[c * 3 + r]).abs() < 1e-15);
        }
    }
    let qdd = [1.5, -0.3, 2.0];
    let tau = mb.inverse_dynamics(&q, &qd, &qdd, G);
    let back = mb.forward_dynamics(&q, &qd, &tau, G).expect("M positive definite");
    for i in 0..3 {
        assert!((back[i] - qdd[i]).abs() < 1e-10);
    }
}

/// A tree on a turned base under gravity is the tree as it was under gravity turned back.
#[test]
fn a_turned_base_is_gravity_turned_the_other_way() {
    let mb = branched();
    let world_from_base = DQuat::from_axis_angle(DVec3::new(0.6, -0.8, 0.0), 0.05);
    let turned = mb.with_base_rotated(world_from_base);
    let (q, qd, qdd) = ([0.4, -1.1, 0.07], [0.9, -2.0, 0.3], [1.5, -0.3, 2.0]);
    let want = mb.inverse_dynamics(&q, &qd, &qdd, world_from_base.inverse() * G);
    let got = turned.inverse_dynamics(&q, &qd, &qdd, G);
    let level = mb.inverse_dynamics(&q, &qd, &qdd, G);
    for d in 0..3 {
        assert!((got[d] - want[d]).abs() < 1e-12 * (1.0 + want[d].abs()), "dof {d}: {} against {}", got[d], want[d]);
    }
    assert!((0..3).any(|d| (got[d] - level[d]).abs() > 1e-2), "the turn changes nothing: {got:?} against {level:?}");
}

/// A replay step asks for both from one set of placements: the same numbers, bit for bit.
#[test]
fn mass_matrix_and_bias_together_are_each_alone_bit_for_bit() {
    let mb = branched();
    for (q, qd) in [([0.4, -1.1, 0.07], [0.9, -2.0, 0.3]), ([-2.5, 0.3, -0.2], [0.0, 4.0, -1.5])] {
        let (m, bias) = mb.mass_matrix_and_bias(&q, &qd, G);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&m), bits(&mb.mass_matrix(&q)));
        assert_eq!(bits(&bias), bits(&mb.bias(&q, &qd, G)));
    }
}

/// Energy balance: d/dt (kinetic + potential) = q̇ · τ, checked by finite differences along a
/// trajectory with q̈ from forward dynamics (no friction anywhere).
#[test]
fn power_balance_holds_along_a_motion() {
    let mb = branched();
    let energy = |q: &[f64], qd: &[f64]| {
        let m = mb.mass_matrix(q);
        let kinetic: f64 = (0..3).map(|r| (0..3).map(|c| 0.5 * qd[r] * m[r * 3 + c] * qd[c]).sum::<f64>()).sum();
        // Potential: −Σ m g·p over bodies, from the placements.
        let k = mb.kinematics(q, &[0.0; 3], &[0.0; 3], G);
        let mut world: Vec<ParentFromChild> = Vec::new();
        let mut potential = 0.0;
        for (i, b) in mb.bodies().iter().enumerate() {
            let x = b.parent.map_or(k.parent_from_body[i], |p: usize| world[p].then(&k.parent_from_body[i]));
            world.push(x);
            potential -= b.inertia.mass_kg * G.dot(x.rotation * b.inertia.com() + x.translation);
        }
        kinetic + potential
    };
    let q = [0.4, -1.1, 0.07];
    let qd = [0.9, -2.0, 0.3];
    let tau = [0.3, -0.2, 1.0];
    let qdd = mb.forward_dynamics(&q, &qd, &tau, G).expect("M positive definite");
    let h = 1e-6;
    let step = |s: f64| -> ([f64; 3], [f64; 3]) {
        let mut a = [0.0; 3];
        let mut b = [0.0; 3];
        for i in 0..3 {
            a[i] = q[i] + s * qd[i] + 0.5 * s * s * qdd[i];
            b[i] = qd[i] + s * qdd[i];
        }
        (a, b)
    };
    let (qp, qdp) = step(h);
    let (qm, qdm) = step(-h);
    let de = (energy(&qp, &qdp) - energy(&qm, &qdm)) / (2.0 * h);
    let power: f64 = (0..3).map(|i| qd[i] * tau[i]).sum();
    assert!((de - power).abs() < 1e-5, "dE/dt {de} vs power {power}");
}
