//! The library of candidate physics terms (spec §3 effect kinds) and the per-joint dynamics they
//! add up to.

use serde::Serialize;

use super::model::{DofKind, GapJoint};

/// A kind of physics the model may have left out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// force = −damping · v.
    ViscousDamping,
    /// force = −friction · sign(v); sticks while the other forces are below it.
    CoulombFriction,
    /// force = −stiffness · (q − `rest_position`).
    Spring,
    /// The true axis is tilted: gravity pulls a revolute joint towards an equilibrium, ∝ sin.
    GravityTilt,
    /// A stop at `position` not in the model: hard, or compliant with a contact time.
    EndStop,
    /// True inertia = scale × modelled.
    MassScale,
    /// Viscous damping only between `engage_position` and the closed end.
    SoftClose,
    /// Friction that takes more force to start than to keep moving:
    /// −(friction + (breakaway − friction)·exp(−(v/`stribeck_speed`)²))·sign(v).
    StribeckFriction,
    /// A constant effort added to the recorded one (sensor bias, gravity compensation).
    EffortOffset,
    /// Reflected rotor inertia added to the joint's own diagonal inertia (no weight).
    Armature,
    /// Structure in the residual that no known kind explains.
    Unknown,
}

impl EffectKind {
    /// Whether the effort of this kind depends on the joint's position alone (an offset, a
    /// spring, gravity along a tilted axis): the shape an error of the model's weights and centres
    /// of mass takes.
    #[must_use]
    pub fn depends_on_position_alone(self) -> bool {
        matches!(self, Self::EffortOffset | Self::Spring | Self::GravityTilt)
    }

    /// Whether this kind adds inertia to the joint (a rotor's, or a heavier part's with its
    /// weight): the shape an error of the model's masses and inertias takes.
    #[must_use]
    pub fn adds_inertia(self) -> bool {
        matches!(self, Self::Armature | Self::MassScale)
    }

    /// Every fittable kind, in a fixed order (ties in selection go to the earlier one).
    pub const FITTABLE: [Self; 7] =
        [Self::ViscousDamping, Self::CoulombFriction, Self::Spring, Self::GravityTilt, Self::EndStop, Self::MassScale, Self::SoftClose];

    /// The spec's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::ViscousDamping => "viscous_damping",
            Self::CoulombFriction => "coulomb_friction",
            Self::Spring => "spring",
            Self::GravityTilt => "gravity_tilt",
            Self::EndStop => "end_stop",
            Self::MassScale => "mass_scale",
            Self::SoftClose => "soft_close",
            Self::StribeckFriction => "stribeck_friction",
            Self::EffortOffset => "effort_offset",
            Self::Armature => "armature",
            Self::Unknown => "unknown",
        }
    }

    /// Names of the internal parameters, in order.
    #[must_use]
    pub fn internal_params(self) -> &'static [&'static str] {
        match self {
            Self::ViscousDamping => &["damping"],
            Self::SoftClose => &["damping", "engage_position"],
            Self::CoulombFriction => &["friction"],
            Self::Spring => &["stiffness", "rest_position"],
            Self::GravityTilt => &["torque_amplitude", "equilibrium_position"],
            Self::EndStop => &["position", "restitution"],
            Self::MassScale => &["scale"],
            Self::StribeckFriction => &["friction", "breakaway", "stribeck_speed"],
            Self::EffortOffset => &["offset"],
            Self::Armature => &["armature"],
            Self::Unknown => &[],
        }
    }

    /// Number of internal parameters.
    #[must_use]
    pub fn param_count(self) -> usize {
        match self {
            Self::ViscousDamping | Self::CoulombFriction | Self::MassScale | Self::EffortOffset | Self::Armature => 1,
            Self::Spring | Self::GravityTilt | Self::EndStop | Self::SoftClose => 2,
            Self::StribeckFriction => 3,
            Self::Unknown => 0,
        }
    }

    /// Whether the kind makes sense on a joint of this type.
    #[must_use]
    pub fn applies_to(self, kind: DofKind) -> bool {
        match self {
            Self::GravityTilt => kind.is_rotational(),
            Self::Unknown => false,
            _ => kind != DofKind::Fixed,
        }
    }

    /// Parses the spec's name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Every kind, `unknown` last.
    pub const ALL: [Self; 11] = [
        Self::ViscousDamping,
        Self::CoulombFriction,
        Self::Spring,
        Self::GravityTilt,
        Self::EndStop,
        Self::MassScale,
        Self::SoftClose,
        Self::StribeckFriction,
        Self::EffortOffset,
        Self::Armature,
        Self::Unknown,
    ];
}

/// One effect with its internal parameters (see [`EffectKind::internal_params`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Effect {
    /// Kind.
    pub kind: EffectKind,
    /// Internal parameters.
    pub params: Vec<f64>,
    /// For `end_stop`: true when the stop blocks motion upwards (q may not exceed `position`).
    pub blocks_upward: bool,
}

/// The shape of a joint's friction beyond its level (effort space fits it; the position-space
/// fitter keeps the ideal law).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrictionShape {
    /// Speed of the smooth transition through zero, tanh(v / `transition_speed`); 0 = ideal sign
    /// with exact sticking.
    pub transition_speed: f64,
    /// Level for v < 0 when it differs from the level for v > 0.
    pub friction_reverse: Option<f64>,
    /// Stribeck: (breakaway level, Stribeck speed); `friction` is then the sliding level.
    pub stribeck: Option<(f64, f64)>,
}

/// An extra stop: hard (impacts are instant) or compliant (a linear spring–damper the joint
/// sinks into, as an engine's penalty limit or a rubber bumper).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stop {
    /// Position of the stop (where contact begins).
    pub position: f64,
    /// Coefficient of restitution in [0, 1].
    pub restitution: f64,
    /// True: q ≤ position; false: q ≥ position.
    pub blocks_upward: bool,
    /// How long an impact keeps the joint past `position`, s; 0 for a hard stop.
    pub contact_time_s: f64,
}

/// Shortest and longest contact of a compliant stop, s (the fitter's bounds): below a
/// millisecond no recording tells a compliant stop from a hard one, and a joint held half a
/// second is resting on it, not bouncing.
pub const CONTACT_TIME_RANGE_S: (f64, f64) = (1e-3, 0.5);

/// Least restitution a compliant stop is given: 0 would need a critically damped contact, which
/// never ends (the joint creeps back out).
const MIN_COMPLIANT_RESTITUTION: f64 = 0.01;

impl Stop {
    /// Whether impacts take time (a compliant stop).
    #[must_use]
    pub fn is_compliant(&self) -> bool {
        self.contact_time_s > 0.0
    }

    /// How far `q` lies past the stop (positive inside it).
    #[must_use]
    pub fn penetration(&self, q: f64) -> f64 {
        if self.blocks_upward { q - self.position } else { self.position - q }
    }

    /// Stiffness and damping of the linear spring–damper (Kelvin–Voigt) contact that throws a
    /// joint of `inertia` back at `restitution` of its speed after `contact_time_s`: damping
    /// ratio ζ from e = exp(−πζ/√(1−ζ²)), the contact lasting the damped half-period `π/ω_d`.
    /// This is how a penalty limit (Newton's `limit_ke`/`limit_kd`, `MuJoCo`'s soft limits) and a
    /// bumper behave; the pair is fitted as (restitution, contact time), which a recording shows
    /// directly and which do not depend on each other.
    #[must_use]
    pub fn penalty(&self, inertia: f64) -> (f64, f64) {
        let (omega_n, zeta) = contact_oscillator(self.restitution, self.contact_time_s);
        (inertia * omega_n * omega_n, 2.0 * zeta * inertia * omega_n)
    }
}

/// The linear spring–damper contact, as natural frequency `ω_n` (rad/s) and damping ratio ζ, that
/// throws a body back at `restitution` of its speed after `contact_time_s`, whatever its mass:
/// e = exp(−πζ/√(1−ζ²)), the contact the damped half-period `π/ω_d`. Restitution is kept within
/// [0.01, 1] (0 would need a critically damped contact that never ends).
#[must_use]
pub fn contact_oscillator(restitution: f64, contact_time_s: f64) -> (f64, f64) {
    let log_e = -restitution.clamp(MIN_COMPLIANT_RESTITUTION, 1.0).ln();
    let zeta = log_e / (std::f64::consts::PI.powi(2) + log_e * log_e).sqrt();
    let omega_d = std::f64::consts::PI / contact_time_s.max(CONTACT_TIME_RANGE_S.0);
    (omega_d / (1.0 - zeta * zeta).sqrt(), zeta)
}

/// Everything the 1-DoF integrator needs about one joint beyond the rigid-body terms.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPhysics {
    /// Rotational or translational.
    pub kind: DofKind,
    /// Total viscous damping.
    pub damping: f64,
    /// Total Coulomb friction (the level for v > 0).
    pub friction: f64,
    /// Smooth, direction-dependent or Stribeck friction.
    pub friction_shape: FrictionShape,
    /// Constant effort added to the recorded one.
    pub effort_offset: f64,
    /// Reflected inertia added to the joint's own.
    pub armature: f64,
    /// Spring stiffness.
    pub stiffness: f64,
    /// Spring rest position.
    pub rest_position: f64,
    /// Amplitude of the tilt gravity effort (−amplitude · sin(q − equilibrium)).
    pub tilt_amplitude: f64,
    /// Equilibrium of the tilt term.
    pub tilt_equilibrium: f64,
    /// Inertia multiplier.
    pub mass_scale: f64,
    /// Extra stops.
    pub stops: Vec<Stop>,
    /// Soft-close damping and the position where it engages.
    pub soft_close: Option<(f64, f64)>,
    /// Closed end of travel (the model's lower limit, else 0).
    pub closed_end: f64,
    /// Model limits.
    pub lower: Option<f64>,
    /// Model limits.
    pub upper: Option<f64>,
    /// Coefficient of restitution of the model's own limits (0: they stop the joint dead). Not an
    /// effect: how the modelled stops bounce, which no URDF says; fitted where a recording hits
    /// them ([`crate::gap`]'s held-out replays).
    pub limit_restitution: f64,
}

impl JointPhysics {
    /// The model joint as written (its `<dynamics>` and limits), no extra effects.
    #[must_use]
    pub fn nominal(joint: &GapJoint) -> Self {
        Self {
            damping: joint.damping,
            friction: joint.friction,
            closed_end: joint.lower.unwrap_or(0.0),
            lower: joint.lower,
            upper: joint.upper,
            ..Self::free(joint.kind)
        }
    }

    /// A joint of `kind` with nothing on it: no damping, friction or limits.
    #[must_use]
    pub fn free(kind: DofKind) -> Self {
        Self {
            kind,
            damping: 0.0,
            friction: 0.0,
            friction_shape: FrictionShape::default(),
            effort_offset: 0.0,
            armature: 0.0,
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
            limit_restitution: 0.0,
        }
    }

    /// The model joint with `effects` added.
    #[must_use]
    pub fn with_effects(joint: &GapJoint, effects: &[Effect]) -> Self {
        let mut p = Self::nominal(joint);
        for e in effects {
            let x = &e.params;
            match e.kind {
                EffectKind::ViscousDamping => p.damping += x[0],
                EffectKind::CoulombFriction => {
                    p.friction += x[0];
                    if let Some(&speed) = x.get(1) {
                        p.friction_shape.transition_speed = speed.max(0.0);
                    }
                    if let Some(&reverse) = x.get(2).filter(|r| r.is_finite()) {
                        p.friction_shape.friction_reverse = Some(reverse);
                    }
                }
                EffectKind::StribeckFriction => {
                    p.friction += x[0];
                    p.friction_shape.stribeck = Some((x[1], x[2].max(1e-6)));
                }
                EffectKind::EffortOffset => p.effort_offset += x[0],
                EffectKind::Armature => p.armature += x[0],
                EffectKind::Spring => (p.stiffness, p.rest_position) = (x[0], x[1]),
                // A chain's base tilt turns the whole tree (`super::tilt`), not this joint alone.
                EffectKind::GravityTilt if super::tilt::base_lean(e).is_some() => {}
                EffectKind::GravityTilt => (p.tilt_amplitude, p.tilt_equilibrium) = (x[0], x[1]),
                EffectKind::EndStop => p.stops.push(Stop {
                    position: x[0],
                    restitution: x[1],
                    blocks_upward: e.blocks_upward,
                    contact_time_s: x
                        .get(2)
                        .copied()
                        .filter(|t| t.is_finite() && *t > 0.0)
                        .map_or(0.0, |t| t.clamp(CONTACT_TIME_RANGE_S.0, CONTACT_TIME_RANGE_S.1)),
                }),
                EffectKind::MassScale => p.mass_scale = x[0],
                EffectKind::SoftClose => p.soft_close = Some((x[0], x[1])),
                EffectKind::Unknown => {}
            }
        }
        p
    }

    /// The joint's inertia along itself under these physics, from the `modelled` one: scaled by
    /// a heavier part, plus armature.
    #[must_use]
    pub fn inertia(&self, modelled: f64) -> f64 {
        (modelled * self.mass_scale + self.armature).max(1e-9)
    }

    /// Conservative efforts (spring, tilt) at position q.
    #[must_use]
    pub fn position_effort(&self, q: f64) -> f64 {
        let tilt = if self.tilt_amplitude == 0.0 { 0.0 } else { self.tilt_amplitude * (q - self.tilt_equilibrium).sin() };
        -self.stiffness * (q - self.rest_position) - tilt
    }

    /// The friction level opposing motion at velocity v (direction by the sign of v; at v = 0 the
    /// level to break away).
    #[must_use]
    pub fn friction_level(&self, v: f64) -> f64 {
        let base = match self.friction_shape.friction_reverse {
            Some(reverse) if v < 0.0 => reverse,
            _ => self.friction,
        };
        match self.friction_shape.stribeck {
            Some((breakaway, speed)) => base + (breakaway - base) * (-(v / speed).powi(2)).exp(),
            None => base,
        }
    }

    /// The friction force at velocity v for the smooth law (`transition_speed` > 0).
    #[must_use]
    pub fn smooth_friction(&self, v: f64) -> f64 {
        let s = self.friction_shape.transition_speed.max(1e-12);
        -self.friction_level(v) * (v / s).tanh()
    }

    /// The compliant stops' contact at position q of a joint of `inertia`: the spring effort and
    /// the damping coefficient of those q lies inside (the damping is left to the integrator: the
    /// 1-DoF one takes it implicitly, the chain replay in sub-steps of a fortieth of the contact).
    #[must_use]
    pub fn compliant_contact(&self, q: f64, inertia: f64) -> (f64, f64) {
        self.stops.iter().filter(|s| s.is_compliant() && s.penetration(q) > 0.0).fold((0.0, 0.0), |(f, c), s| {
            let (stiffness, damping) = s.penalty(inertia);
            (f - stiffness * (q - s.position), c + damping)
        })
    }

    /// The shortest contact time of the compliant stops, if any.
    #[must_use]
    pub fn shortest_contact_s(&self) -> Option<f64> {
        self.stops.iter().filter(|s| s.is_compliant()).map(|s| s.contact_time_s).reduce(f64::min)
    }

    /// Total viscous damping at position q (soft close included).
    #[must_use]
    pub fn damping_at(&self, q: f64) -> f64 {
        let soft = match self.soft_close {
            Some((c, engage))
                if (q - self.closed_end) * (engage - self.closed_end) >= 0.0
                    && (q - self.closed_end).abs() <= (engage - self.closed_end).abs() =>
            {
                c
            }
            _ => 0.0,
        };
        self.damping + soft
    }
}

/// Keeps parameters physical: non-negative coefficients, restitution in [0, 1], a compliant
/// stop's contact time within [`CONTACT_TIME_RANGE_S`], scale ≥ 0.05.
pub fn clamp_params(kind: EffectKind, x: &mut [f64]) {
    match kind {
        EffectKind::ViscousDamping | EffectKind::CoulombFriction | EffectKind::Spring | EffectKind::GravityTilt | EffectKind::SoftClose => {
            x[0] = x[0].max(0.0);
        }
        EffectKind::EndStop => {
            let compliant = x.get(2).is_some_and(|t| t.is_finite());
            x[1] = x[1].clamp(if compliant { MIN_COMPLIANT_RESTITUTION } else { 0.0 }, 1.0);
            if let Some(t) = x.get_mut(2).filter(|t| t.is_finite()) {
                *t = t.clamp(CONTACT_TIME_RANGE_S.0, CONTACT_TIME_RANGE_S.1);
            }
        }
        EffectKind::MassScale => x[0] = x[0].max(0.05),
        EffectKind::StribeckFriction | EffectKind::Armature => x.iter_mut().for_each(|v| *v = v.max(0.0)),
        EffectKind::EffortOffset | EffectKind::Unknown => {}
    }
}
