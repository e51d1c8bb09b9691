//! Spatial (6D) algebra in a body's own frame, Featherstone's notation: a motion is (ω, v) with
//! v the velocity of the point at the frame origin, a force is (n, f) with n the moment about the
//! origin. Rigid-body inertias stay rigid-body inertias under sums and changes of frame, so they
//! are kept as (m, h = m·c, I about the origin) instead of 6×6 matrices.

use glam::{DMat3, DQuat, DVec3};

/// A spatial motion vector (angular, linear at the frame origin).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Angular velocity (or acceleration), rad/s.
    pub angular: DVec3,
    /// Linear velocity of the point at the frame origin, m/s.
    pub linear: DVec3,
}

/// A spatial force vector (moment about the frame origin, force).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Force {
    /// Moment about the frame origin, N·m.
    pub moment: DVec3,
    /// Force, N.
    pub force: DVec3,
}

impl Motion {
    /// `self × m` (motion cross product, `crm`).
    #[must_use]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion { angular: self.angular.cross(m.angular), linear: self.angular.cross(m.linear) + self.linear.cross(m.angular) }
    }

    /// `self ×* f` (force cross product, `crf`).
    #[must_use]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force { moment: self.angular.cross(f.moment) + self.linear.cross(f.force), force: self.angular.cross(f.force) }
    }

    /// `selfᵀ f`: power of a force along this motion.
    #[must_use]
    pub fn dot(&self, f: &Force) -> f64 {
        self.angular.dot(f.moment) + self.linear.dot(f.force)
    }
}

impl std::ops::Add for Motion {
    type Output = Motion;
    fn add(self, o: Motion) -> Motion {
        Motion { angular: self.angular + o.angular, linear: self.linear + o.linear }
    }
}

impl std::ops::Mul<f64> for Motion {
    type Output = Motion;
    fn mul(self, s: f64) -> Motion {
        Motion { angular: self.angular * s, linear: self.linear * s }
    }
}

impl std::ops::Add for Force {
    type Output = Force;
    fn add(self, o: Force) -> Force {
        Force { moment: self.moment + o.moment, force: self.force + o.force }
    }
}

impl std::ops::AddAssign for Force {
    fn add_assign(&mut self, o: Force) {
        self.moment += o.moment;
        self.force += o.force;
    }
}

/// The placement of a child frame in its parent: `p_parent = rotation · p_child + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParentFromChild {
    /// Rotation, child axes to parent axes.
    pub rotation: DMat3,
    /// The child origin in the parent frame, m.
    pub translation: DVec3,
}

impl ParentFromChild {
    /// From a quaternion and a translation.
    #[must_use]
    pub fn new(rotation: DQuat, translation: DVec3) -> Self {
        Self { rotation: DMat3::from_quat(rotation), translation }
    }

    /// `self ∘ other` (other is the child's child).
    #[must_use]
    pub fn then(&self, other: &Self) -> Self {
        Self { rotation: self.rotation * other.rotation, translation: self.translation + self.rotation * other.translation }
    }

    /// A parent-frame motion expressed in the child frame.
    #[must_use]
    pub fn motion_to_child(&self, m: &Motion) -> Motion {
        let rt = self.rotation.transpose();
        Motion { angular: rt * m.angular, linear: rt * (m.linear - self.translation.cross(m.angular)) }
    }

    /// A child-frame force expressed in the parent frame.
    #[must_use]
    pub fn force_to_parent(&self, f: &Force) -> Force {
        let force = self.rotation * f.force;
        Force { moment: self.rotation * f.moment + self.translation.cross(force), force }
    }
}

/// A rigid-body inertia about a frame's origin.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RigidInertia {
    /// Mass, kg.
    pub mass_kg: f64,
    /// First moment m·c (c the centre of mass), kg·m.
    pub first_moment: DVec3,
    /// Rotational inertia about the frame origin, kg·m².
    pub about_origin: DMat3,
}

/// `[c]×`, the cross-product matrix.
fn skew(c: DVec3) -> DMat3 {
    DMat3::from_cols(DVec3::new(0.0, c.z, -c.y), DVec3::new(-c.z, 0.0, c.x), DVec3::new(c.y, -c.x, 0.0))
}

impl RigidInertia {
    /// From mass, centre of mass and the inertia about the centre of mass (same frame).
    #[must_use]
    pub fn from_com(mass_kg: f64, com: DVec3, inertia_com: DMat3) -> Self {
        let s = skew(com);
        Self { mass_kg, first_moment: com * mass_kg, about_origin: inertia_com - s * s * mass_kg }
    }

    /// The centre of mass (the origin for a massless body).
    #[must_use]
    pub fn com(&self) -> DVec3 {
        if self.mass_kg > 0.0 { self.first_moment / self.mass_kg } else { DVec3::ZERO }
    }

    /// The inertia about the centre of mass.
    #[must_use]
    pub fn about_com(&self) -> DMat3 {
        let s = skew(self.com());
        self.about_origin + s * s * self.mass_kg
    }

    /// `I · m`: the momentum (or inertial force) of a motion.
    #[must_use]
    pub fn apply(&self, m: &Motion) -> Force {
        Force {
            moment: self.about_origin * m.angular + self.first_moment.cross(m.linear),
            force: m.linear * self.mass_kg - self.first_moment.cross(m.angular),
        }
    }

    /// The same body seen from the parent frame.
    #[must_use]
    pub fn to_parent(&self, x: &ParentFromChild) -> Self {
        let com = x.rotation * self.com() + x.translation;
        let inertia_com = x.rotation * self.about_com() * x.rotation.transpose();
        Self::from_com(self.mass_kg, com, inertia_com)
    }

    /// The inertia scaled by `s` (a body `s` times as heavy, same shape).
    #[must_use]
    pub fn scaled(&self, s: f64) -> Self {
        Self { mass_kg: self.mass_kg * s, first_moment: self.first_moment * s, about_origin: self.about_origin * s }
    }
}

impl std::ops::Add for RigidInertia {
    type Output = RigidInertia;
    fn add(self, o: RigidInertia) -> RigidInertia {
        RigidInertia {
            mass_kg: self.mass_kg + o.mass_kg,
            first_moment: self.first_moment + o.first_moment,
            about_origin: self.about_origin + o.about_origin,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_changes_preserve_power_and_inertia() {
        let x = ParentFromChild::new(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1), DVec3::new(0.2, -0.5, 0.9));
        let m = Motion { angular: DVec3::new(0.1, 2.0, -0.3), linear: DVec3::new(-1.0, 0.4, 0.7) };
        let f = Force { moment: DVec3::new(0.5, -0.2, 0.3), force: DVec3::new(2.0, 1.0, -4.0) };
        // Power is frame-independent: (X m)·f_child = m·(X* f_child) with m in the parent frame.
        let p_child = x.motion_to_child(&m).dot(&f);
        let p_parent = m.dot(&x.force_to_parent(&f));
        assert!((p_child - p_parent).abs() < 1e-12);
        // Kinetic energy of a body is frame-independent too.
        let body = RigidInertia::from_com(2.5, DVec3::new(0.1, 0.2, -0.3), DMat3::from_diagonal(DVec3::new(0.1, 0.2, 0.3)));
        let mc = x.motion_to_child(&m);
        let e_child = mc.dot(&body.apply(&mc));
        let e_parent = m.dot(&body.to_parent(&x).apply(&m));
        assert!((e_child - e_parent).abs() < 1e-12, "{e_child} vs {e_parent}");
    }
}
