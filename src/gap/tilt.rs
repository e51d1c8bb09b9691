//! A chain's base tilted from the model's: the `gravity_tilt` of a chain's base joint.
//!
//! A robot on a table or a cart that is not quite level has its base joint's axis tilted, and
//! everything beyond it with it (the spec's `gravity_tilt`: "the true joint axis is tilted from
//! the modelled one"). A lone joint shows that as a sine of its own angle; in a chain the effort
//! depends on every joint's angle, and it loads every joint, not the base alone. To first order
//! in the tilt it is linear in two numbers, the horizontal components `w` of the true gravity
//! direction in the base's frame: the efforts of gravity are linear in the gravity vector, so
//! the tilt adds `|g| (w₁ G(q)·h₁ + w₂ G(q)·h₂)` where `G(q)·h` is the effort that holds the
//! tree still at q under a unit gravity along the horizontal direction h (one RNEA pass at rest).
//!
//! Only a base joint whose axis is near vertical gets the term (as a lone joint's tilt,
//! [`MAX_TILT_AXIS_FROM_VERTICAL_DEG`]): about a horizontal base axis one component
//! of a tilt is the base joint's angle read off by a constant, and the other only scales the
//! gravity effort the model already has, which its first-moment accuracy answers for.
//!
//! The term is fitted on every joint it loads and judged (its held-out cut, its replay) on the
//! base joint alone ([`super::effort`]'s `rows_of`): there a level model has no gravity effort and
//! no error of its first moments can make one, while on the joints beyond a tilt looks like those
//! errors. It may not enter where it raises the held-out error summed over every joint.
//!
//! The fitted model carries the tilt exactly: the tree's base turned ([`world_from_base`],
//! [`crate::dynamics::MultiBody::with_base_rotated`]) in the replays, and the fitted URDF's joints
//! on the root link placed by the same turn.

use glam::{DQuat, DVec3};

use super::accuracy::at_rest_series;
use super::model::{DofKind, GapModel};
use crate::dynamics::MultiBody;

/// Internal parameters of a base tilt: sin tilt, the base joint's equilibrium, and the lean w
/// (3 components, base frame; [`world_from_base`]).
pub const BASE_TILT_PARAMS: usize = 5;

/// Largest angle between a joint's axis and the vertical for which `gravity_tilt` is a candidate.
/// A tilt makes gravity act on a joint whose model says it does not (a door hinge); on a joint
/// far from vertical the model's gravity effort already dominates and a small tilt only scales
/// it by cos(tilt) — there the sin law would soak up other errors.
pub const MAX_TILT_AXIS_FROM_VERTICAL_DEG: f64 = 30.0;

/// Whether `gravity_tilt` applies to joint j (axis near vertical at the model's zero pose).
#[must_use]
pub fn tilt_applies(model: &GapModel, j: usize, gravity_dir: DVec3) -> bool {
    let zero = vec![0.0; model.joints.len()];
    let (_, axis) = model.joint_frame_world(j, &zero);
    gravity_dir != DVec3::ZERO && axis.normalize_or_zero().dot(gravity_dir).abs() >= MAX_TILT_AXIS_FROM_VERTICAL_DEG.to_radians().cos()
}

/// The base joint of a chain: the one movable joint that no movable joint carries, where the
/// model has exactly one (a single arm, not a tree with two movable roots) and it has a movable
/// joint beyond it.
#[must_use]
pub fn base_joint(model: &GapModel) -> Option<usize> {
    let movable = |k: usize| model.joints[k].kind != DofKind::Fixed;
    let carried = |j: usize| model.moving_joint_of(model.joints[j].parent).is_some();
    let mut roots = (0..model.joints.len()).filter(|&j| movable(j) && !carried(j));
    let (Some(j), None) = (roots.next(), roots.next()) else { return None };
    let chain = (0..model.joints.len()).any(|k| k != j && movable(k));
    chain.then_some(j)
}

/// Two horizontal unit directions for base joint j's tilt: h₁ its child frame's x axis (y where x
/// lies along the joint axis) at the model's zero pose, and h₂ = axis × h₁, both made
/// perpendicular to gravity. With the axis vertical, a tilt of components (w₁, w₂) pulls the part
/// along h₁ to rest at the joint angle atan2(w₂, w₁). None where the tilt does not apply (the
/// axis far from vertical, not a revolute joint).
#[must_use]
pub fn tilt_directions(model: &GapModel, j: usize, gravity_dir: DVec3) -> Option<[DVec3; 2]> {
    if !model.joints[j].kind.is_rotational() || !tilt_applies(model, j, gravity_dir) {
        return None;
    }
    let zero = vec![0.0; model.joints.len()];
    let (frame, axis) = model.joint_frame_world(j, &zero);
    let axis = axis.normalize_or_zero();
    let horizontal = |v: DVec3| (v - v.dot(gravity_dir) * gravity_dir).try_normalize();
    let x = frame.rotation * DVec3::X;
    let first = if x.dot(axis).abs() < 0.9 { x } else { frame.rotation * DVec3::Y };
    let h1 = horizontal(first)?;
    let h2 = horizontal(axis.cross(h1))?;
    Some([h1, h2])
}

/// Per direction of `directions`, per dof and sample: the effort that holds the tree still at
/// the positions of `q_of` under gravity of `gravity`'s magnitude along that direction (NaN
/// where the motion is not finite).
#[must_use]
pub fn tilt_efforts(tree: &MultiBody, q_of: &[Vec<[f64; 3]>], gravity: DVec3, directions: [DVec3; 2]) -> [Vec<Vec<f64>>; 2] {
    let g = gravity.length();
    let mut series =
        at_rest_series(q_of, 2, |q| directions.iter().map(|&h| tree.inverse_dynamics(q, &[], &[], g * h)).collect()).into_iter();
    std::array::from_fn(|_| series.next().unwrap_or_default())
}

/// The turn of the base (world ← base) under which gravity, seen from the base, leans by `w`
/// (the horizontal part of the unit gravity direction in the base's frame, |w| = sin tilt, what
/// the two columns fit to first order): the base sees gravity along w + ĝ √(1 − |w|²).
#[must_use]
pub fn world_from_base(w: DVec3, gravity_dir: DVec3) -> DQuat {
    let seen = (w + gravity_dir * (1.0 - w.length_squared()).max(0.0).sqrt()).normalize_or_zero();
    if seen == DVec3::ZERO || gravity_dir == DVec3::ZERO {
        return DQuat::IDENTITY;
    }
    DQuat::from_rotation_arc(seen, gravity_dir)
}

/// The tilt of a base whose gravity leans by `w` ([`world_from_base`]), rad.
#[must_use]
pub fn tilt_rad(w: DVec3) -> f64 {
    w.length().min(1.0).asin()
}

/// The base tilt an effect's parameters describe, if it is one: `gravity_tilt` on a chain's
/// base joint carries (sin tilt, equilibrium, w) with w the lean of gravity in the base's frame.
#[must_use]
pub fn base_lean(effect: &super::effects::Effect) -> Option<DVec3> {
    (effect.kind == super::effects::EffectKind::GravityTilt && effect.params.len() == BASE_TILT_PARAMS)
        .then(|| DVec3::new(effect.params[2], effect.params[3], effect.params[4]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::model::parse_model;

    const ARM: &str = r#"<robot name="arm"><link name="base"/>
      <link name="turret"><inertial><origin xyz="0.05 0 0.1"/><mass value="2"/><inertia ixx="0.02" iyy="0.02" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="upper"><inertial><origin xyz="0.2 0 0"/><mass value="1.5"/><inertia ixx="0.005" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="yaw" type="revolute"><parent link="base"/><child link="turret"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="50" velocity="3"/></joint>
      <joint name="pitch" type="revolute"><parent link="turret"/><child link="upper"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="50" velocity="3"/></joint></robot>"#;

    #[test]
    fn the_tilt_columns_are_the_efforts_of_the_turned_base_to_first_order() {
        let model = parse_model(ARM, std::path::Path::new("arm.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let gravity = DVec3::new(0.0, 0.0, -9.81);
        let down = gravity.normalize();
        let j = base_joint(&model).expect("a base joint");
        assert_eq!(model.joints[j].name, "yaw");
        let dirs = tilt_directions(&model, j, down).expect("vertical axis");
        let w = 1e-4 * DVec3::new(0.3, -0.7, 0.0);
        let (a, b) = (w.dot(dirs[0]), w.dot(dirs[1]));
        let q_of: Vec<Vec<[f64; 3]>> = vec![vec![[0.7, 0.0, 0.0]], vec![[-0.4, 0.0, 0.0]]];
        let cols = tilt_efforts(&tree, &q_of, gravity, dirs);
        let turned = tree.with_base_rotated(world_from_base(w, down));
        let q = [0.7, -0.4];
        let level = tree.inverse_dynamics(&q, &[], &[], gravity);
        let tilted = turned.inverse_dynamics(&q, &[], &[], gravity);
        for d in 0..2 {
            let linear = a * cols[0][d][0] + b * cols[1][d][0];
            let exact = tilted[d] - level[d];
            assert!(linear.abs() > 1e-5, "dof {d}: the tilt loads it");
            assert!((linear - exact).abs() < 1e-3 * exact.abs(), "dof {d}: {linear} against {exact}");
        }
    }

    #[test]
    fn a_part_along_the_first_direction_rests_where_the_lean_points() {
        // The turret's centre of mass lies along its x axis; leaning gravity along h₂ (the
        // axis × h₁ side) pulls it to rest at +90°: the yaw effort there is nil, and a little
        // beyond it pushes back.
        let model = parse_model(ARM, std::path::Path::new("arm.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let gravity = DVec3::new(0.0, 0.0, -9.81);
        let dirs = tilt_directions(&model, 0, gravity.normalize()).expect("vertical axis");
        let turned = tree.with_base_rotated(world_from_base(0.01 * dirs[1], gravity.normalize()));
        // Upper arm pointing straight up, so that only the turret's offset pulls.
        let yaw_effort = |yaw: f64| turned.inverse_dynamics(&[yaw, -std::f64::consts::FRAC_PI_2], &[], &[], gravity)[0];
        let rest = std::f64::consts::FRAC_PI_2;
        assert!(yaw_effort(rest).abs() < 1e-9, "{}", yaw_effort(rest));
        // The effort that holds it past its rest is the pull back, negated.
        assert!(yaw_effort(rest + 0.1) > 0.0 && yaw_effort(rest - 0.1) < 0.0);
    }
}
