//! The model's own rigid-body accuracy, fitted beside the effects in effort space.
//!
//! A published or identified arm model's centres of mass are a few percent off its real links
//! (an identification's own error, a cable, a bolt). In effort space that error is an effort
//! that depends on the configuration through gravity, and it takes the shapes of the
//! terms the effects are named from: a constant on a joint whose outer links barely turn
//! (a false `effort_offset`), a share of an acceleration (a false `armature`), or it hides a
//! real sensor bias that is smaller than itself. Robot identification fits the inertial
//! parameters together with friction and offsets for that reason (Khalil & Dombre; Gautier's
//! IDIM): here each outer link's first moment (mass × centre of mass, 3 numbers in its own frame)
//! is a nuisance regressor of every joint it loads, fitted but never named.
//!
//! The nuisance columns join every fit of the effort problem (each held-out fold's too), one set
//! per link shared by all the joints it loads, so that a link's error must explain all of them at
//! once (what a single joint's constant cannot do); a ridge prior keeps them to the model's
//! accuracy: a first-moment error beyond a tolerance of the link's own
//! (`SelectionRules::first_moment_tolerance`, 5 %) is unlikely, so a heavier payload or a sensor
//! bias still shows as one. The prior is weighed against one piece of evidence per filter width,
//! not per sample: the filtered efforts are correlated over that width, and counted sample by
//! sample any recording would swamp it.
//!
//! The fitted error is part of the fitted model: the held-out replays that judge the named
//! effects replay it, and the fitted URDF carries it as moved centres of mass (the report's
//! `com_shift_m`), so that what was validated is what is delivered. Only joints in a serial chain get it: a
//! lone door or lid has its own kinds for a wrong weight or a tilted axis (`mass_scale`,
//! `gravity_tilt`) and one joint cannot tell them from a first-moment error.
//!
//! The regressor of a unit first moment is exact: the joint efforts are linear in each body's
//! (mass, first moment, rotational inertia) ([`crate::dynamics::RigidInertia`]), so one RNEA
//! backward pass at rest with only that moment set gives its gravity column.

use std::collections::BTreeMap;

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use crate::dynamics::MultiBody;
use crate::dynamics::spatial::RigidInertia;

/// Per body (of `bodies`), per axis of its frame, per dof and sample: the effort that holds a
/// unit first moment (1 kg·m along that axis, no mass, no rotational inertia) still against
/// `gravity` at the positions of `q_of` (NaN where the motion is not finite). Gravity's part
/// only: what a first-moment error does through the motion is an inertia a few percent off,
/// which [`super::effort::SelectionRules::min_inertial_load_share`] already answers for, and
/// fitted here it would take a real rotor's inertia on a joint gravity does not load.
#[must_use]
pub fn first_moment_efforts(
    tree: &MultiBody,
    q_of: &[Vec<[f64; 3]>],
    gravity: DVec3,
    bodies: &[usize],
) -> BTreeMap<usize, [Vec<Vec<f64>>; 3]> {
    let unit = |axis: DVec3| RigidInertia { mass_kg: 0.0, first_moment: axis, about_origin: DMat3::ZERO };
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut series = at_rest_series(q_of, 3 * bodies.len(), |q| {
        let k = tree.kinematics(q, &[], &[], gravity);
        bodies.iter().flat_map(|&b| axes.map(|a| tree.efforts_with(&k, |x| (x == b).then(|| unit(a))))).collect()
    })
    .into_iter();
    bodies.iter().map(|&b| (b, std::array::from_fn(|_| series.next().unwrap_or_default()))).collect()
}

/// `count` series of efforts over a recorded motion (`q_of`: per dof and sample, position first),
/// each per dof and sample: `at(q)` gives, at each sample's positions, every series' efforts on
/// every dof; NaN where the motion is not finite. The samples are evaluated in parallel.
#[must_use]
pub fn at_rest_series(q_of: &[Vec<[f64; 3]>], count: usize, at: impl Fn(&[f64]) -> Vec<Vec<f64>> + Sync) -> Vec<Vec<Vec<f64>>> {
    let nd = q_of.len();
    let n = q_of.first().map_or(0, Vec::len);
    let per_sample: Vec<Option<Vec<Vec<f64>>>> = (0..n)
        .into_par_iter()
        .map(|i| {
            if !q_of.iter().all(|d| d[i].iter().all(|v| v.is_finite())) {
                return None;
            }
            let q: Vec<f64> = q_of.iter().map(|d| d[i][0]).collect();
            Some(at(&q))
        })
        .collect();
    (0..count).map(|k| (0..nd).map(|d| per_sample.iter().map(|s| s.as_ref().map_or(f64::NAN, |e| e[k][d])).collect()).collect()).collect()
}

/// The bodies beyond body `child` (it included): those whose chain of parents reaches it.
#[must_use]
pub fn bodies_beyond(tree: &MultiBody, child: usize) -> Vec<usize> {
    (0..tree.bodies().len())
        .filter(|&b| {
            let mut x = Some(b);
            while let Some(i) = x {
                if i == child {
                    return true;
                }
                x = tree.bodies()[i].parent;
            }
            false
        })
        .collect()
}

/// The prior standard deviation of body b's first-moment error, kg·m: `tolerance` × its first
/// moment, or × its mass times `min_lever_m` where that is larger.
#[must_use]
pub fn first_moment_prior(tree: &MultiBody, b: usize, tolerance: f64, min_lever_m: f64) -> f64 {
    let inertia = &tree.bodies()[b].inertia;
    tolerance * inertia.first_moment.length().max(inertia.mass_kg * min_lever_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An arm of three links (the last welded to the second), its joints' axes crossed so that
    /// gravity loads every axis of some link's first moment.
    const ARM: &str = r#"<robot name="arm"><link name="base"/>
      <link name="a"><inertial><origin xyz="0.02 0 -0.15"/><mass value="1.2"/><inertia ixx="0.01" iyy="0.01" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="b"><inertial><origin xyz="0 0.01 -0.12"/><mass value="0.7"/><inertia ixx="0.005" iyy="0.005" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="tool"><inertial><origin xyz="0.03 0 0"/><mass value="0.2"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
      <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 -0.3"/><axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
      <joint name="weld" type="fixed"><parent link="b"/><child link="tool"/><origin xyz="0 0 -0.25"/></joint>
    </robot>"#;

    fn check(q: [f64; 2]) {
        let model = crate::gap::model::parse_model(ARM, std::path::Path::new("arm.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let gravity = DVec3::new(0.0, 0.0, -9.81);
        let q_of: Vec<Vec<[f64; 3]>> = q.iter().map(|&x| vec![[x, 0.3, -1.0]]).collect();
        let bodies: Vec<usize> = (0..tree.bodies().len()).collect();
        let columns = first_moment_efforts(&tree, &q_of, gravity, &bodies);
        let at_rest = |t: &MultiBody| t.inverse_dynamics(&q, &[], &[], gravity);
        let nominal = at_rest(&tree);
        for &b in &bodies {
            for (axis, unit) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
                let moved = at_rest(&tree.with_first_moment_added(b, 1e-3 * unit));
                for d in 0..2 {
                    let want = (moved[d] - nominal[d]) / 1e-3;
                    let got = columns[&b][axis][d][0];
                    assert!((got - want).abs() < 1e-9 * (1.0 + want.abs()), "body {b} axis {axis} dof {d}: {got} against {want}");
                }
            }
        }
    }

    #[test]
    fn a_unit_first_moments_column_is_the_holding_effort_it_adds() {
        check([0.0, 0.0]);
        check([0.4, -1.1]);
        check([-2.0, 2.5]);
    }

    #[test]
    fn the_bodies_beyond_a_joint_include_what_is_welded_to_them() {
        let model = crate::gap::model::parse_model(ARM, std::path::Path::new("arm.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let index = |name: &str| tree.bodies().iter().position(|b| b.name == name).expect("body");
        let names = |v: Vec<usize>| v.into_iter().map(|b| tree.bodies()[b].name.clone()).collect::<Vec<String>>();
        assert_eq!(names(bodies_beyond(&tree, index("a"))), ["a", "b", "tool"]);
        assert_eq!(names(bodies_beyond(&tree, index("b"))), ["b", "tool"]);
        // A light body whose centre of mass is near its origin: its mass × the least lever.
        assert!((first_moment_prior(&tree, index("tool"), 0.1, 0.05) - 0.1 * 0.2 * 0.05).abs() < 1e-12);
    }
}
