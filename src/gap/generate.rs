//! Recordings with concealed effects, for tests, benchmarks and demos. The physics here is
//! deliberately different code from the fitter's: fourth-order Runge–Kutta at 0.5 ms with event
//! location by bisection (velocity reversals under Coulomb friction with a stick/slip state
//! machine, impacts on stops), and gravity about a really tilted axis computed from the geometry
//! (the subtree's centre of mass rotated about the tilted axis), not the sin law the fitter uses.

use std::fmt::Write as _;

use glam::{DQuat, DVec3};
use rand::Rng;
use rand_distr::{Distribution, Normal};

use super::effects::Stop;
use super::error::GapError;
use super::model::{DofKind, GapModel};

/// An effect hidden in the generated recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrueEffect {
    /// −damping · v.
    ViscousDamping {
        /// N·m·s/rad or N·s/m.
        damping: f64,
    },
    /// Coulomb friction with sticking.
    CoulombFriction {
        /// N·m or N.
        friction: f64,
    },
    /// A spring.
    Spring {
        /// N·m/rad or N/m.
        stiffness: f64,
        /// rad or m.
        rest_position: f64,
    },
    /// The real axis is tilted by `tilt_deg` towards `azimuth_deg` (about the modelled axis,
    /// from an arbitrary perpendicular).
    AxisTilt {
        /// Degrees.
        tilt_deg: f64,
        /// Degrees.
        azimuth_deg: f64,
    },
    /// An extra hard stop.
    EndStop {
        /// rad or m.
        position: f64,
        /// In [0, 1].
        restitution: f64,
    },
    /// An extra compliant stop: a linear spring–damper that throws the joint back at
    /// `restitution` of its speed after `contact_time_s` (how a penalty limit behaves).
    CompliantStop {
        /// rad or m.
        position: f64,
        /// In (0, 1].
        restitution: f64,
        /// Seconds.
        contact_time_s: f64,
    },
    /// The moving part `scale` × as heavy: inertia and weight (spec `mass_scale`).
    ExtraInertia {
        /// Multiplier.
        scale: f64,
    },
    /// Damping between `engage_position` and the closed end.
    SoftClose {
        /// N·m·s/rad or N·s/m.
        damping: f64,
        /// rad or m.
        engage_position: f64,
    },
}

/// How to generate a recording.
#[derive(Debug, Clone)]
pub struct GenerateConfig {
    /// Length, s.
    pub duration_s: f64,
    /// Nominal sample rate, Hz.
    pub rate_hz: f64,
    /// Position noise σ (rad or m; for poses: rad of rotation, and this × 0.5 m of position).
    pub noise: f64,
    /// Share of samples dropped (plus one 0.2 s burst when > 0).
    pub dropout_fraction: f64,
    /// Jitter sample times by up to ±30 % of the period.
    pub irregular: bool,
    /// Write tracked child-link poses instead of `q` columns.
    pub pose_only: bool,
    /// Seed.
    pub seed: u64,
    /// Hidden effects: (joint name, effect).
    pub effects: Vec<(String, TrueEffect)>,
}

impl Default for GenerateConfig {
    fn default() -> Self {
        Self {
            duration_s: 10.0,
            rate_hz: 100.0,
            noise: 0.001,
            dropout_fraction: 0.0,
            irregular: false,
            pose_only: false,
            seed: 0,
            effects: Vec::new(),
        }
    }
}

/// Event code of a velocity reversal under Coulomb friction.
const REVERSAL: usize = usize::MAX;
/// Event code of a soft-close zone crossing.
const ZONE: usize = usize::MAX - 1;

struct TrueJoint {
    inertia: f64,
    mass: f64,
    com_offset: DVec3,
    axis: DVec3,
    tilted_axis: DVec3,
    gravity: DVec3,
    prismatic: bool,
    damping: f64,
    friction: f64,
    spring: (f64, f64),
    soft: Option<(f64, f64)>,
    closed_end: f64,
    stops: Vec<(f64, f64, bool)>,
    compliant: Vec<Stop>,
}

impl TrueJoint {
    /// Whether q lies in the soft-close zone.
    fn in_zone(&self, q: f64) -> bool {
        self.soft.is_some_and(|(_, e)| {
            (q - self.closed_end) * (e - self.closed_end) >= 0.0 && (q - self.closed_end).abs() <= (e - self.closed_end).abs()
        })
    }

    /// Everything but friction and impacts.
    fn smooth_force(&self, q: f64, v: f64, effort: f64) -> f64 {
        self.smooth_force_zone(q, v, effort, self.in_zone(q))
    }

    /// As [`Self::smooth_force`] with the soft-close zone given (a step up to a zone crossing
    /// keeps the zone it started in, or RK4's last stage would straddle the switch).
    fn smooth_force_zone(&self, q: f64, v: f64, effort: f64, zone: bool) -> f64 {
        let g = if self.prismatic {
            self.mass * self.gravity.dot(self.axis)
        } else {
            let d = DQuat::from_axis_angle(self.tilted_axis, q) * self.com_offset;
            self.tilted_axis.dot(d.cross(self.gravity * self.mass))
        };
        let soft = match self.soft {
            Some((c, _)) if zone => c,
            _ => 0.0,
        };
        let contact: f64 = self
            .compliant
            .iter()
            .filter(|s| s.penetration(q) > 0.0)
            .map(|s| {
                let (stiffness, damping) = s.penalty(self.inertia);
                -stiffness * (q - s.position) - damping * v
            })
            .sum();
        effort + g - self.spring.0 * (q - self.spring.1) - (self.damping + soft) * v + contact
    }

    fn rk4(&self, q: f64, v: f64, effort: f64, slide: f64, h: f64) -> (f64, f64) {
        self.rk4_zone(q, v, effort, slide, h, None)
    }

    /// RK4 step; `zone` fixes the soft-close zone for every stage (None: from each stage's q).
    fn rk4_zone(&self, q: f64, v: f64, effort: f64, slide: f64, h: f64, zone: Option<bool>) -> (f64, f64) {
        let acc = |q: f64, v: f64| {
            (self.smooth_force_zone(q, v, effort, zone.unwrap_or_else(|| self.in_zone(q))) - self.friction * slide) / self.inertia
        };
        let (k1q, k1v) = (v, acc(q, v));
        let (k2q, k2v) = (v + 0.5 * h * k1v, acc(q + 0.5 * h * k1q, v + 0.5 * h * k1v));
        let (k3q, k3v) = (v + 0.5 * h * k2v, acc(q + 0.5 * h * k2q, v + 0.5 * h * k2v));
        let (k4q, k4v) = (v + h * k3v, acc(q + h * k3q, v + h * k3v));
        (q + h / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q), v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))
    }

    /// The first event in a step: velocity reversal while sliding ([`REVERSAL`]), crossing a
    /// stop (its index), or crossing the soft-close engage position ([`ZONE`]: the damping
    /// switches, which RK4 must not straddle).
    fn event(&self, q0: f64, q1: f64, v1: f64, slide: f64) -> Option<usize> {
        if slide != 0.0 && v1 * slide < 0.0 {
            return Some(REVERSAL);
        }
        if let Some(i) = self.stops.iter().position(|&(p, _, up)| if up { q1 > p && q0 <= p + 1e-12 } else { q1 < p && q0 >= p - 1e-12 }) {
            return Some(i);
        }
        self.soft.and_then(|(_, e)| ((q0 - e) * (q1 - e) < 0.0).then_some(ZONE))
    }

    /// Advances (q, v, slide direction) by `dt` under a constant effort.
    fn advance(&self, mut q: f64, mut v: f64, mut slide: f64, effort: f64, dt: f64) -> (f64, f64, f64) {
        const H: f64 = 0.0005;
        let mut left = dt;
        let mut guard = 0;
        while left > 1e-12 && guard < 100_000 {
            guard += 1;
            if v == 0.0 {
                // Resting against a stop and pushed into it: stays for the rest of the interval.
                let f = self.smooth_force(q, 0.0, effort);
                if self.stops.iter().any(|&(p, _, up)| (q - p).abs() < 1e-12 && if up { f >= 0.0 } else { f <= 0.0 }) {
                    return (q, 0.0, 0.0);
                }
            }
            if slide == 0.0 && self.friction > 0.0 && v == 0.0 {
                let f = self.smooth_force(q, 0.0, effort);
                if f.abs() <= self.friction {
                    // Stuck for the rest of this interval (the force only changes with the effort).
                    return (q, 0.0, 0.0);
                }
                slide = f.signum();
            }
            if self.friction > 0.0 && slide == 0.0 {
                slide = if v == 0.0 { 0.0 } else { v.signum() };
            }
            let h = left.min(H);
            let (q1, v1) = self.rk4(q, v, effort, slide, h);
            match self.event(q, q1, v1, slide) {
                None => {
                    (q, v) = (q1, v1);
                    left -= h;
                }
                Some(which) => {
                    // Bisection for the event time, in the zone the step starts in.
                    let zone = Some(self.in_zone(q));
                    let (mut a, mut b) = (0.0, h);
                    for _ in 0..40 {
                        let m = 0.5 * (a + b);
                        let (qm, vm) = self.rk4_zone(q, v, effort, slide, m, zone);
                        if self.event(q, qm, vm, slide).is_some() { b = m } else { a = m }
                    }
                    let (qe, ve) = self.rk4_zone(q, v, effort, slide, b, zone);
                    left -= b;
                    if which == REVERSAL {
                        (q, v, slide) = (qe, 0.0, 0.0);
                    } else if which == ZONE {
                        // Just past the engage position: the next step sees one damping only.
                        (q, v) = (qe, ve);
                    } else {
                        let (p, e, _) = self.stops[which];
                        q = p;
                        v = -e * ve;
                        if v.abs() < 1e-4 {
                            v = 0.0;
                        }
                        slide = if self.friction > 0.0 && v != 0.0 { v.signum() } else { 0.0 };
                    }
                }
            }
        }
        (q, v, slide)
    }
}

/// Generates a recording (CSV text in the spec's form) of `model` with `cfg.effects` hidden.
pub fn generate_recording(model: &GapModel, cfg: &GenerateConfig) -> Result<String, GapError> {
    let gravity = DVec3::new(0.0, 0.0, -9.81);
    let dofs = model.dofs();
    for (name, _) in &cfg.effects {
        if !dofs.iter().any(|&j| model.joints[j].name == *name) {
            return Err(GapError::Model {
                file: model.file.clone(),
                field: format!("joint {name}"),
                message: "not a movable joint".into(),
            });
        }
    }
    let mut rng = crate::math::rng(cfg.seed);
    let n = (cfg.duration_s * cfg.rate_hz).round() as usize + 1;
    let period = 1.0 / cfg.rate_hz;
    let time: Vec<f64> =
        (0..n).map(|i| i as f64 * period + if cfg.irregular && i > 0 { rng.random_range(-0.3..0.3) * period } else { 0.0 }).collect();
    let zero = vec![0.0; model.joints.len()];
    let mut q_all: Vec<Vec<f64>> = vec![vec![0.0; n]; model.joints.len()];
    let mut effort_all: Vec<Vec<f64>> = vec![vec![0.0; n]; model.joints.len()];
    for &j in &dofs {
        let joint = &model.joints[j];
        let (frame, axis) = model.joint_frame_world(j, &zero);
        let (mass, com, _) = model.subtree_mass_world(j, &zero);
        let terms = model.joint_terms(j, &zero, gravity);
        let mut tj = TrueJoint {
            inertia: terms.inertia.max(1e-9),
            mass,
            com_offset: com - frame.translation,
            axis,
            tilted_axis: axis,
            gravity,
            prismatic: joint.kind == DofKind::Prismatic,
            damping: joint.damping,
            friction: joint.friction,
            spring: (0.0, 0.0),
            soft: None,
            closed_end: joint.lower.unwrap_or(0.0),
            stops: Vec::new(),
            compliant: Vec::new(),
        };
        if let Some(l) = joint.lower {
            tj.stops.push((l, 0.0, false));
        }
        if let Some(u) = joint.upper {
            tj.stops.push((u, 0.0, true));
        }
        let (lo, hi) = match (joint.lower, joint.upper) {
            (Some(l), Some(u)) => (l, u),
            _ if tj.prismatic => (-0.3, 0.3),
            _ => (-1.5, 1.5),
        };
        let q_start = lo + 0.3 * (hi - lo);
        let mut reach = (lo, hi);
        for (name, effect) in cfg.effects.iter().filter(|(name, _)| *name == joint.name) {
            let _ = name;
            match *effect {
                TrueEffect::ViscousDamping { damping } => tj.damping += damping,
                TrueEffect::CoulombFriction { friction } => tj.friction += friction,
                TrueEffect::Spring { stiffness, rest_position } => tj.spring = (stiffness, rest_position),
                TrueEffect::AxisTilt { tilt_deg, azimuth_deg } => {
                    let e1 = axis.any_orthonormal_vector();
                    let e2 = axis.cross(e1);
                    let az = azimuth_deg.to_radians();
                    let n = e1 * az.cos() + e2 * az.sin();
                    tj.tilted_axis = DQuat::from_axis_angle(n, tilt_deg.to_radians()) * axis;
                }
                TrueEffect::EndStop { position, restitution } => {
                    let up = position > q_start;
                    tj.stops.push((position, restitution, up));
                    // Let the hand push past it so that the stop is hit.
                    if up { reach.1 = reach.1.max(position) } else { reach.0 = reach.0.min(position) }
                }
                TrueEffect::CompliantStop { position, restitution, contact_time_s } => {
                    let up = position > q_start;
                    tj.compliant.push(Stop { position, restitution, blocks_upward: up, contact_time_s });
                    if up { reach.1 = reach.1.max(position) } else { reach.0 = reach.0.min(position) }
                }
                TrueEffect::ExtraInertia { scale } => {
                    tj.inertia *= scale;
                    tj.mass *= scale;
                }
                TrueEffect::SoftClose { damping, engage_position } => tj.soft = Some((damping, engage_position)),
            }
        }
        // A hand: pushes towards a random target (saturated PD) for 0.4–0.9 s, then lets go for
        // 0.6–1.4 s, often while the joint still moves; targets reach a little past the stops.
        let nominal_inertia = terms.inertia.max(1e-9);
        let omega = 4.0;
        let (kp, kd) = (nominal_inertia * omega * omega, nominal_inertia * omega);
        let limit = nominal_inertia * 10.0 + terms.gravity_cos.hypot(terms.gravity_sin).abs() * 1.2 + (mass * 9.81 * 0.0);
        let (mut q, mut v, mut slide) = (q_start, 0.0, 0.0);
        let mut target = q_start;
        let mut pushing = false;
        let mut phase_end = 0.0;
        for i in 0..n {
            let t = time[i];
            if t >= phase_end {
                pushing = !pushing;
                phase_end = t + if pushing { rng.random_range(0.4..0.9) } else { rng.random_range(0.6..1.4) };
                target = reach.0 + rng.random_range(-0.1..1.1) * (reach.1 - reach.0);
            }
            let effort = if pushing { (kp * (target - q) - kd * v).clamp(-limit, limit) } else { 0.0 };
            q_all[j][i] = q;
            effort_all[j][i] = effort;
            if i + 1 < n {
                (q, v, slide) = tj.advance(q, v, slide, effort, time[i + 1] - time[i]);
            }
        }
    }
    write_csv(model, cfg, &time, &q_all, &effort_all, &mut rng)
}

fn write_csv(
    model: &GapModel,
    cfg: &GenerateConfig,
    time: &[f64],
    q_all: &[Vec<f64>],
    effort_all: &[Vec<f64>],
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Result<String, GapError> {
    let dofs = model.dofs();
    let noise = Normal::new(0.0, cfg.noise.max(0.0)).map_err(|e| GapError::Model {
        file: model.file.clone(),
        field: "noise".into(),
        message: e.to_string(),
    })?;
    let n = time.len();
    let mut drop = vec![false; n];
    if cfg.dropout_fraction > 0.0 {
        for d in &mut drop[1..] {
            *d = rng.random_bool(cfg.dropout_fraction.clamp(0.0, 1.0));
        }
        let burst = (0.2 * cfg.rate_hz) as usize;
        let at = n / 2;
        for d in drop.iter_mut().skip(at).take(burst) {
            *d = true;
        }
    }
    let mut header = vec!["time".to_owned()];
    for &j in &dofs {
        let name = &model.joints[j].name;
        if cfg.pose_only {
            let link = &model.links[model.joints[j].child].name;
            header.extend(["pos.x", "pos.y", "pos.z", "quat.w", "quat.x", "quat.y", "quat.z"].iter().map(|c| format!("{link}.{c}")));
        } else {
            header.push(format!("{name}.q"));
        }
        header.push(format!("{name}.effort"));
    }
    let mut out = String::new();
    let _ = writeln!(out, "# description: generated by partscene gap::generate (seed {}), hidden effects: {:?}", cfg.seed, cfg.effects);
    let _ = writeln!(out, "# gravity: 0 0 -9.81");
    let _ = writeln!(out, "{}", header.join(","));
    let mut config = vec![0.0; model.joints.len()];
    for i in 0..n {
        let _ = write!(out, "{:.6}", time[i]);
        for (c, q) in config.iter_mut().zip(q_all) {
            *c = q[i];
        }
        let poses = if cfg.pose_only { model.world_from_links(&config) } else { Vec::new() };
        for &j in &dofs {
            if cfg.pose_only {
                let pose = poses[model.joints[j].child];
                if drop[i] {
                    out.push_str(",,,,,,,");
                } else {
                    let axis = DVec3::new(noise.sample(rng), noise.sample(rng), noise.sample(rng));
                    let r = (DQuat::from_scaled_axis(axis) * pose.rotation).normalize();
                    let p = pose.translation + DVec3::new(noise.sample(rng), noise.sample(rng), noise.sample(rng)) * 0.5;
                    let _ = write!(out, ",{:.7},{:.7},{:.7},{:.8},{:.8},{:.8},{:.8}", p.x, p.y, p.z, r.w, r.x, r.y, r.z);
                }
            } else if drop[i] {
                out.push(',');
            } else {
                let _ = write!(out, ",{:.7}", q_all[j][i] + noise.sample(rng));
            }
            // Shortest exact decimal: a fixed number of decimals would round a light part's
            // efforts (a knob's are ~1e-5 N·m) by whole percent, a real effort-gain error.
            let _ = write!(out, ",{}", effort_all[j][i]);
        }
        out.push('\n');
    }
    Ok(out)
}
