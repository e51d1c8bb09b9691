//! The report (spec §3, `partscene-gap-report/1`), the fitted URDF (`<dynamics>` and stops where
//! URDF can say it) and the sidecar with every fitted effect.

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};
use serde::Serialize;

use super::effects::EffectKind;
use super::model::{GapModel, Iso};

/// The report's `format` value.
pub const REPORT_FORMAT: &str = "partscene-gap-report/1";

/// Conditions during a mismatch.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Conditions {
    /// Lowest measured position in the span.
    pub position_min: f64,
    /// Highest measured position in the span.
    pub position_max: f64,
    /// "increasing", "decreasing", "both" or "at rest" (direction of measured motion).
    pub direction: String,
    /// "lower limit", "upper limit" or null: whether the joint is near a modelled stop.
    pub near_stop: Option<String>,
}

/// Where simulation and recording disagree beyond the noise.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Mismatch {
    /// Joint name.
    pub joint: String,
    /// Start, s.
    pub t_start: f64,
    /// End, s.
    pub t_end: f64,
    /// RMSE of the residual in the span (rad or m).
    pub rmse: f64,
    /// In words.
    pub description: String,
    /// Position range, direction, stops.
    pub conditions: Conditions,
}

/// A found effect (spec §3 kinds and parameter names).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EffectReport {
    /// Joint name.
    pub joint: String,
    /// Spec kind name.
    pub kind: String,
    /// Parameters in SI units (spec names).
    pub params: BTreeMap<String, f64>,
    /// One standard deviation of each parameter (from the LM covariance).
    pub uncertainty: BTreeMap<String, f64>,
    /// Probability-like weight of this term against dropping or swapping it (BIC weights).
    pub confidence: f64,
    /// In words.
    pub description: String,
}

/// RMSE of open-loop simulation against the recording, before and after the fit.
#[derive(Debug, Clone, Copy, Serialize, PartialEq, Default)]
pub struct RmsePair {
    /// The model as written.
    pub rmse_before: f64,
    /// The fitted model.
    pub rmse_after: f64,
}

/// The `fit` section.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct FitSummary {
    /// Over every observed sample of every joint.
    pub rmse_before: f64,
    /// Over every observed sample of every joint.
    pub rmse_after: f64,
    /// Per joint.
    pub per_joint: BTreeMap<String, RmsePair>,
}

/// Held-out validation: parameters fitted on the first part of the recording, open-loop RMSE on
/// the rest.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct HeldOut {
    /// Held-out samples start here, s.
    pub t_start: f64,
    /// Per joint.
    pub per_joint: BTreeMap<String, RmsePair>,
}

/// The time series behind the plots (for the CLI's images and the editor's live plots).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointSeries {
    /// Joint name.
    pub joint: String,
    /// "rad" or "m".
    pub unit: &'static str,
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// Measured positions (NaN = dropout).
    pub measured: Vec<f64>,
    /// Open-loop simulation of the model as written.
    pub simulated_before: Vec<f64>,
    /// Open-loop simulation of the fitted model.
    pub simulated_after: Vec<f64>,
    /// Measured − simulated, before (NaN where not measured).
    pub residual_before: Vec<f64>,
    /// Measured − simulated, after.
    pub residual_after: Vec<f64>,
    /// Estimated measurement noise σ.
    pub noise_sigma: f64,
}

/// How one joint was analysed, and what was weighed and left out.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct JointAnalysis {
    /// "effort" (inverse dynamics of the whole tree, residual effort regressed on the effects'
    /// features) or "position" (simulation of the joint, multiple shooting).
    pub mode: String,
    /// Why this mode.
    pub why: String,
    /// RMS of the joint's own effort over the analysed samples (N·m or N; effort mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effort_rms: Option<f64>,
    /// Held-out RMS residual effort of the model as written and of the fitted one (effort mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effort_residual: Option<RmsePair>,
    /// Terms considered and not reported, each with the reason.
    pub rejected: Vec<String>,
}

impl JointSeries {
    /// The series of one joint: measurement, both replays, and their residuals.
    #[must_use]
    pub fn new(
        joint: &str,
        unit: &'static str,
        time_s: &[f64],
        measured: &[f64],
        before: Vec<f64>,
        after: Vec<f64>,
        noise_sigma: f64,
    ) -> Self {
        let residual_of = |sim: &[f64]| measured.iter().zip(sim).map(|(a, b)| a - b).collect::<Vec<f64>>();
        Self {
            joint: joint.to_owned(),
            unit,
            time_s: time_s.to_vec(),
            measured: measured.to_vec(),
            residual_before: residual_of(&before),
            residual_after: residual_of(&after),
            simulated_before: before,
            simulated_after: after,
            noise_sigma,
        }
    }
}

/// The whole report. Serializes to `report.json`; `series` and `fitted` stay in memory.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GapReport {
    /// Always [`REPORT_FORMAT`].
    pub format: &'static str,
    /// Worst first.
    pub mismatches: Vec<Mismatch>,
    /// What the model left out.
    pub effects: Vec<EffectReport>,
    /// RMSE before/after over all samples.
    pub fit: FitSummary,
    /// File name of the fitted URDF (relative to the report).
    pub fitted_model: String,
    /// Held-out validation.
    pub held_out: HeldOut,
    /// Estimated noise σ per joint.
    pub noise_sigma: BTreeMap<String, f64>,
    /// Assumptions (primitive masses, skipped joints…).
    pub notes: Vec<String>,
    /// Per joint: the way in (effort or position space) and what was rejected.
    pub joints: BTreeMap<String, JointAnalysis>,
    /// Per link: how far effort space moved its centre of mass (m, link frame) as the model's own
    /// accuracy, fitted beside the effects and not an effect itself (`gap::accuracy`); written
    /// into the fitted URDF's `<inertial><origin>`. Empty (and absent) without a chain in effort
    /// space.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub com_shift_m: BTreeMap<String, [f64; 3]>,
    /// Plot series, one per analysed joint.
    #[serde(skip)]
    pub series: Vec<JointSeries>,
}

/// The fitted URDF: the model's text with `<dynamics damping friction>` raised by the found
/// viscous damping and Coulomb friction, `<limit>` narrowed by found end stops, centres of mass
/// moved by `com_shift_m` (link name → shift in the link frame, m) and the joints on the root
/// link turned by a chain's base tilt (the root link's own geometry stays as it was).
pub fn fitted_urdf(
    model: &GapModel,
    effects: &[EffectReport],
    com_shift_m: &BTreeMap<String, [f64; 3]>,
) -> Result<String, super::error::GapError> {
    let mut robot = model.robot.clone();
    // Links massed from their primitives get that mass written out: a URDF writer emits an
    // `<inertial>` for every link, and one of mass 0 would read back as a massless link.
    for (link, mass) in robot.links.iter_mut().zip(&model.links) {
        if mass.from_primitives {
            let i = mass.inertia_link;
            link.inertial = urdf_rs::Inertial {
                origin: urdf_rs::Pose { xyz: urdf_rs::Vec3(mass.com_link_m.to_array()), rpy: urdf_rs::Vec3([0.0; 3]) },
                mass: urdf_rs::Mass { value: mass.mass_kg },
                inertia: urdf_rs::Inertia {
                    ixx: i.x_axis.x,
                    ixy: i.y_axis.x,
                    ixz: i.z_axis.x,
                    iyy: i.y_axis.y,
                    iyz: i.z_axis.y,
                    izz: i.z_axis.z,
                },
            };
        }
    }
    for link in &mut robot.links {
        if let Some(shift) = com_shift_m.get(&link.name) {
            // The inertial frame's origin is the centre of mass, in the link frame.
            for (x, d) in link.inertial.origin.xyz.0.iter_mut().zip(shift) {
                *x += d;
            }
        }
    }
    turn_tilted_base(model, effects, &mut robot);
    for joint in &mut robot.joints {
        for e in effects.iter().filter(|e| e.joint == joint.name) {
            let kind = EffectKind::from_name(&e.kind);
            let p = |name: &str| e.params.get(name).copied().unwrap_or(0.0);
            match kind {
                Some(EffectKind::ViscousDamping) => {
                    joint.dynamics.get_or_insert_with(urdf_rs::Dynamics::default).damping += p("damping");
                }
                // URDF's friction is one symmetric level: a direction-dependent one writes the mean,
                // a Stribeck law its sliding level (the rest is in the sidecar).
                Some(EffectKind::CoulombFriction) => {
                    let reverse = e.params.get("friction_reverse").copied().unwrap_or(p("friction"));
                    joint.dynamics.get_or_insert_with(urdf_rs::Dynamics::default).friction += 0.5 * (p("friction") + reverse);
                }
                Some(EffectKind::StribeckFriction) => {
                    joint.dynamics.get_or_insert_with(urdf_rs::Dynamics::default).friction += p("friction");
                }
                Some(EffectKind::EndStop)
                    if joint.joint_type == urdf_rs::JointType::Revolute || joint.joint_type == urdf_rs::JointType::Prismatic =>
                {
                    let position = p("position");
                    let (lo, hi) = (joint.limit.lower, joint.limit.upper);
                    if position > lo && position < hi {
                        if (position - lo).abs() < (hi - position).abs() {
                            joint.limit.lower = position;
                        } else {
                            joint.limit.upper = position;
                        }
                    }
                }
                _ => {}
            }
        }
    }
    urdf_rs::write_to_string(&robot).map_err(|e| super::error::GapError::Urdf { file: model.file.clone(), message: e.to_string() })
}

/// A chain's base tilt ([`super::tilt`]; a `gravity_tilt` with its turn's axis) places every
/// joint on the root link by the turn: the fitted URDF stands as tilted as the recording showed.
fn turn_tilted_base(model: &GapModel, effects: &[EffectReport], robot: &mut urdf_rs::Robot) {
    for e in effects.iter().filter(|e| e.kind == EffectKind::GravityTilt.name()) {
        let p = |name: &str| e.params.get(name).copied();
        let (Some(x), Some(y), Some(z), Some(tilt_deg)) = (p("tilt_axis_x"), p("tilt_axis_y"), p("tilt_axis_z"), p("tilt_deg")) else {
            continue;
        };
        let Some(axis) = DVec3::new(x, y, z).try_normalize() else { continue };
        let turn = DQuat::from_axis_angle(axis, tilt_deg.to_radians());
        let root = &model.links[model.root].name;
        for joint in robot.joints.iter_mut().filter(|j| &j.parent.link == root) {
            let origin = Iso::from_urdf(&joint.origin);
            joint.origin = urdf_rs::Pose {
                xyz: urdf_rs::Vec3((turn * origin.translation).to_array()),
                rpy: urdf_rs::Vec3(crate::math::dquat_to_rpy(turn * origin.rotation)),
            };
        }
    }
}

/// The sidecar JSON: every effect (including those URDF cannot express), machine-readable.
#[must_use]
pub fn sidecar_json(report: &GapReport, model_file: &str) -> String {
    let value = serde_json::json!({
        "format": "partscene-gap-fitted/1",
        "model": model_file,
        "urdf": report.fitted_model,
        "effects": report.effects,
        "in_urdf": [
            "viscous_damping -> <dynamics damping>",
            "coulomb_friction -> <dynamics friction> (the mean of both directions; transition_speed and friction_reverse only here)",
            "stribeck_friction -> <dynamics friction> (the sliding level; breakaway and stribeck_speed only here)",
            "end_stop -> <limit> (restitution, and a compliant stop's contact_time, stiffness and damping, only here; MJCF: range, solreflimit)",
            "gravity_tilt of a chain's base joint -> the <origin> of every joint on the root link, turned by tilt_deg about tilt_axis",
            "armature, effort_offset, mass_scale, spring, gravity_tilt of a lone joint, soft_close -> only here (MJCF: armature, stiffness/springref)"
        ],
    });
    serde_json::to_string_pretty(&value).unwrap_or_default()
}
