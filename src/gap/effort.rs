//! Effort-space identification ("IDIM", Khalil & Dombre; Gautier): for joints whose effort is
//! recorded while every joint of the model has its position recorded, the residual effort
//! `r = τ_measured − τ_model(q, q̇, q̈)` (inverse dynamics of the whole tree, [`crate::dynamics`])
//! is regressed on the effects' features. Most joint physics is linear in its parameters there
//! (viscous, Coulomb at a given transition speed, offset, armature, a heavier part, a spring, a
//! tilt, soft close at a given engage position), so every candidate model is one small weighted
//! least-squares solve over precomputed Gram matrices, and the choice between them is made on
//! data not used to fit them: contiguous time blocks, each held out in turn.
//!
//! A term is kept only when it lowers the held-out error of its joint by [`SelectionRules`]'s
//! margin in most folds *and* its effort matters next to the joint's own efforts over the motion;
//! everything else (engine regularisation, integrator differences, the published model's own
//! error) stays unnamed. What remains material after the best model is reported once per joint
//! as `unknown`, with its size in effort units.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::sync::{Arc, Mutex};

use glam::DVec3;
use rayon::prelude::*;

use super::accuracy::{bodies_beyond, first_moment_efforts, first_moment_prior};
use super::effects::{Effect, EffectKind};
use super::model::{DofKind, GapModel};
use super::smooth::{GAUSS_HALF_GAIN_F_SIGMA, GAUSS_SUPPORT_SIGMAS, Smoother, local_cubic};
use super::tilt::{BASE_TILT_PARAMS, base_joint, base_lean, tilt_applies, tilt_directions, tilt_efforts};
use crate::dynamics::MultiBody;
use crate::linalg::{back_substitute, cholesky, forward_substitute, solve_spd};

/// The thresholds of selection in effort space, in one place.
#[derive(Debug, Clone)]
pub struct SelectionRules {
    /// Contiguous time blocks for cross-validation and the jackknife.
    pub folds: usize,
    /// Relative cut of the joint's held-out squared error a new term must bring.
    pub min_cv_gain: f64,
    /// Share of the folds in which the term must lower the held-out error.
    pub min_fold_share: f64,
    /// RMS effort of a term over the motion, as a share of the joint's own dynamic RMS effort
    /// (beyond holding it still against gravity), below which it is "physically nothing" and
    /// not reported.
    pub min_effort_share: f64,
    /// How well a model's inertias are known, as a share of the effort it needs (the twin of
    /// [`Self::min_static_load_share`] for the motion): masses, centres of mass and inertia
    /// tensors a few percent off act on a joint through its whole row of the mass matrix, the
    /// velocity products and gravity. An armature (inertia along the joint, no weight) smaller
    /// than this share of the joint's RMS inertial effort (the model's effort beyond holding the
    /// tree against gravity), or a heavier part whose added effort is smaller than this share of
    /// the joint's whole RMS model effort, cannot be told from that error, and is not reported:
    /// a small link 1.6× as heavy as modelled can be 4 % of what the arm above it needs.
    pub min_inertial_load_share: f64,
    /// Residual RMS (share of the joint's own RMS effort) left after the best model above which
    /// `unknown` is reported.
    pub unknown_share: f64,
    /// How well a model's rigid bodies are known, as a share of the gravity effort it needs: a
    /// published model's masses and centres of mass are rarely better than 5 % (an identified
    /// robot model included), and their error acts on the joint as an effort that depends on the
    /// position alone. A term of that shape (an offset, a spring, a tilted axis) smaller than this
    /// share of the joint's RMS gravity effort cannot be told from that error, and is not
    /// reported; residual effort within it is the model's accuracy, not `unknown`.
    pub min_static_load_share: f64,
    /// Least cut of a chain's held-out replay error (the mean over its joints of each one's
    /// squared error relative to the model as written) for which the other reading of a joint's
    /// friction (dry friction for viscous damping, or the reverse) replaces the one effort space
    /// chose: a clear improvement of the predicted motion, not a tie broken by noise; it is tried
    /// only where effort space cannot tell the two apart (the other law's held-out effort error
    /// within 1 / (1 − this) of its reading's, the same margin the other way). Also the
    /// least cut of a lone joint's squared replay error for which an output-error refinement the
    /// efforts contradict replaces their reading ([`crate::gap`]'s `refine_given`).
    pub min_replay_gain: f64,
    /// Smallest change of a part's weight worth reporting (documented masses are rarely better
    /// than this): a 4 % heavier part is the model's accuracy, not missing physics.
    pub min_mass_change: f64,
    /// Plausible range of `mass_scale`: a documented part that weighs less than the lower or more
    /// than the upper bound times its model is a wrong model, not a missing effect; such a fit is
    /// not reported as a heavier part.
    pub mass_scale_range: (f64, f64),
    /// Largest break-away level of a Stribeck law, as a multiple of its sliding level. Static
    /// friction of real contacts exceeds sliding friction by tens of percent, rarely more than
    /// twice (Armstrong-Hélouvry's survey of friction in machines); a fitted "break-away" of ten
    /// times the sliding level is a speed-shaped bump standing in for something else.
    pub max_breakaway_ratio: f64,
    /// Widest transition through zero speed a smooth Coulomb law may have: (rad/s for a revolute
    /// joint, m/s for a prismatic one). Real joints' dry friction is smooth over 0.05-0.4 rad/s
    /// (the real Panda's published law: 0.12-0.39 rad/s; robot identification's usual range:
    /// 0.05-0.2) and 1-10 mm/s on linear guides; a "friction" smooth over more is a damping-shaped
    /// law, not dry friction (the real double pendulum's elbow, at 6 rad/s RMS, was read as one
    /// over 5.9 rad/s and replayed worse; a damped door tracked by its pose as one over 0.7 rad/s).
    pub max_transition_speed: (f64, f64),
    /// Prior standard deviation of a chain link's first-moment error (mass × centre of mass),
    /// as a share of its own first moment or of its mass × [`Self::first_moment_min_lever_m`],
    /// whichever is larger ([`super::accuracy`]): the accuracy [`Self::min_static_load_share`]
    /// grants a published model's masses and centres of mass, 5 %. Twice that let the real
    /// double pendulum's links wander by 3-5 cm and its held-out replay get 2-10× worse. 0 fits
    /// no such error.
    pub first_moment_tolerance: f64,
    /// Least lever of a link's first-moment prior, m: a link whose centre of mass sits on its
    /// joint's origin is still not known to better than a centimetre or so times its mass.
    pub first_moment_min_lever_m: f64,
    /// A fitted first-moment error whose length is beyond this many of its prior's standard
    /// deviations per axis ([`Self::first_moment_tolerance`]) is no model's accuracy: the report
    /// says the model's rigid bodies do not describe the recording. Ten: half a link's first
    /// moment (or of its mass × [`Self::first_moment_min_lever_m`]) at 5 %. The arms of three
    /// engines against models 5 % off, with sensor biases the first moments take in, reach 4 σ,
    /// the real Panda and double pendulum 2; the efforts of a discrete PD loop too stiff for its
    /// sampling moved centres of mass by a metre and more, silently.
    pub first_moment_implausible_sigmas: f64,
    /// Largest tilt of a chain's base, degrees ([`super::tilt`]): a robot stands within a few
    /// degrees of level; a steeper "tilt" is the fit taking in something else (the first
    /// recordings of a real arm showed 11° tilts standing in for friction).
    pub max_base_tilt_deg: f64,
    /// Least distance of a fitted level from none, in jackknife standard deviations over the
    /// folds left out, for the recording to resolve it (about the two-sided 95 % level): a term
    /// whose level the final reading fits closer to none is reported only where the joint's
    /// held-out replay shows it ([`EffortProblem::unresolved_terms`]), and a refinement whose
    /// departure from its base law lies closer is its base law.
    pub min_resolved_sigmas: f64,
    /// Half-width of the first, wide smoothing pass that measures the motion's frequency, s (the
    /// window used is then chosen from it, [`bandwidth`]).
    pub smoothing_half_width_s: f64,
    /// Speed below which a joint counts as at rest, as a share of its RMS smoothed speed over the
    /// samples its effort row uses ([`super::rests`]).
    pub rest_speed_share: f64,
    /// A joint dwells at rest (dry friction holds it, [`super::rests`]) where it spends more than
    /// this many times as many samples below [`Self::rest_speed_share`] of its RMS speed as
    /// between that and twice it: a smooth pass through zero speed spends about as long in each
    /// (the real Panda's joints 0.8–1.5; the Robotics Toolbox's PUMA under a plain drive 1.6–15).
    pub min_dwell_ratio: f64,
    /// Least level of a joint's dry friction, as a share of the RMS gravity effort it carries, for
    /// its rests to be left out of effort space ([`super::rests`]): below, the rests still weigh
    /// the links it carries and the friction is a small error on that (a quarter: `MuJoCo`'s
    /// Panda against a model 5 % off, friction 2–9 % of the gravity effort of its joints 2, 4 and
    /// 6, lost its joint 2's sensor offset when they were left out; the stuck PUMA's joints are
    /// at 85 % and more).
    pub min_held_friction_over_gravity: f64,
    /// Least share of the recording's usable samples a joint's row keeps once its rests are left
    /// out ([`super::rests`]); with less, they stay. The held-out blocks that judge every term see
    /// too little of the joint otherwise: the plain-drive PUMA's wrist, left with 23 % of its
    /// training part, had its armature and offset better in only 4 of 6 blocks there, and the
    /// training reading without them replayed the wrist's held-out motion at 1.4 rad RMS against
    /// 0.005 with the rests kept (a fifth let that reading through, and a false base tilt on
    /// another recording; a third neither).
    pub min_kept_without_rests: f64,
    /// The same least share where the reading without a joint's rests must name dry friction that
    /// holds them to be kept ([`super::rests`]): where its reading with them leaves a material
    /// share of its effort unexplained, or where that reading's friction holds them but leaving
    /// them out kept under [`Self::min_kept_without_rests`] (then the training part's reading must
    /// hold them too, since that floor guards it). That check, not the share, stands guard there.
    /// Our own heavier lid held near upright by its dry hinge (40 seeds) keeps 8–17 % of its
    /// samples once its rests and the filters' support about them are out; from a tenth, 29 of
    /// them are read right, from a twentieth 32 (15 with the rests kept; 34 with rests its reading
    /// held read without too).
    pub min_kept_without_unexplained_rests: f64,
}

impl SelectionRules {
    /// Whether a Stribeck law's break-away level lies beyond [`Self::max_breakaway_ratio`] × its
    /// sliding level.
    #[must_use]
    pub fn breakaway_beyond_ratio(&self, sliding: f64, breakaway: f64) -> bool {
        breakaway > self.max_breakaway_ratio * sliding
    }
}

impl Default for SelectionRules {
    fn default() -> Self {
        Self {
            folds: 8,
            min_cv_gain: 0.02,
            min_fold_share: 0.75,
            min_effort_share: 0.03,
            unknown_share: 0.2,
            min_static_load_share: 0.05,
            min_inertial_load_share: 0.05,
            smoothing_half_width_s: 0.1,
            mass_scale_range: (0.5, 3.0),
            min_mass_change: 0.1,
            max_breakaway_ratio: 3.0,
            max_transition_speed: (0.5, 0.1),
            min_replay_gain: 0.25,
            first_moment_tolerance: 0.05,
            first_moment_min_lever_m: 0.05,
            first_moment_implausible_sigmas: 10.0,
            max_base_tilt_deg: 10.0,
            min_resolved_sigmas: 2.0,
            rest_speed_share: 0.05,
            min_dwell_ratio: 2.0,
            min_held_friction_over_gravity: 0.25,
            min_kept_without_rests: 1.0 / 3.0,
            min_kept_without_unexplained_rests: 0.05,
        }
    }
}

/// Smoothed signals of the whole model, one entry per degree of freedom (model dof order).
#[derive(Debug, Clone)]
pub struct Signals {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// Position, velocity, acceleration per dof and sample, smoothed (the motion's description).
    pub q: Vec<Vec<[f64; 3]>>,
    /// Position, velocity, acceleration per dof and sample, differentiated by a narrow window
    /// only (the terms of the equation of motion are evaluated on these, then filtered).
    pub raw: Vec<Vec<[f64; 3]>>,
    /// The wide filter applied to every term and to the efforts.
    pub filter: Smoother,
    /// Measured effort per dof smoothed like `q`, for judging sizes (None without a column).
    pub effort_size: Vec<Option<Vec<f64>>>,
    /// Filtered measured effort per dof (None without an effort column).
    pub effort: Vec<Option<Vec<f64>>>,
    /// Whether sample i can be used: every signal finite, not within a window of either end.
    pub usable: Vec<bool>,
    /// The bandwidths used.
    pub band: Bandwidth,
}

/// Widest smoothing half-width, s.
const MAX_HALF_WIDTH_S: f64 = 0.15;

/// Cut-off of the description smoothing (the local cubic of the positions) as a multiple of the
/// motion's dominant frequency.
const CUTOFF_OVER_MOTION: f64 = 5.0;

/// Widest Gaussian σ of the parallel filter, s.
const MAX_SIGMA_S: f64 = 0.1;

/// The bandwidths chosen for a recording, from the motion they describe.
#[derive(Debug, Clone, Copy)]
pub struct Bandwidth {
    /// Dominant frequency of the fastest joint's motion, Hz (0 when it does not move).
    pub motion_hz: f64,
    /// Half-width of the local cubic that smooths the positions for their description, s.
    pub half_width_s: f64,
    /// σ of the Gaussian parallel filter of the equation of motion, s.
    pub sigma_s: f64,
    /// Half-width of the differentiator of the raw positions, s.
    pub narrow_s: f64,
}

/// Shortest and longest piece of a held-out replay, s ([`Bandwidth::held_out_horizon_s`]).
pub const HELD_OUT_HORIZON_S: (f64, f64) = (0.25, 2.0);

impl Bandwidth {
    /// Length of each piece of a chain's held-out replay: one period of the motion's dominant
    /// frequency, within [`HELD_OUT_HORIZON_S`]. Each piece starts from the measured state: over
    /// seconds a chain's open-loop replay drifts from any model (a double pendulum is chaotic, an
    /// arm driven by torques falls away under gravity), and a long tail would measure that drift,
    /// not the fitted physics. (A joint alone on its body is stable: its held-out part stays one
    /// open-loop replay, where a small damping adds up over seconds and shows.)
    #[must_use]
    pub fn held_out_horizon_s(&self) -> f64 {
        let (lo, hi) = HELD_OUT_HORIZON_S;
        if self.motion_hz > 0.0 { (1.0 / self.motion_hz).clamp(lo, hi) } else { hi }
    }

    /// Time on either side of a sample that its filtered terms draw on.
    #[must_use]
    pub fn support_s(&self) -> f64 {
        (GAUSS_SUPPORT_SIGMAS * self.sigma_s).max(self.half_width_s) + self.narrow_s
    }
}

/// The bandwidths for these positions: the motion's dominant frequency (RMS speed over RMS
/// excursion, and RMS acceleration over RMS speed, from a first wide pass of `first_pass_s`;
/// the larger, the fastest joint), then the description smoothing at [`CUTOFF_OVER_MOTION`] ×
/// that frequency (Schafer's rule for Savitzky–Golay filters, `f_c / f_Nyquist ≈ (order + 1) /
/// (3.2 M − 4.6)`, M the half-width in samples; between 3 samples and [`MAX_HALF_WIDTH_S`]) and
/// the parallel filter's half-gain at `cutoff_over_motion` × it (σ between 1.5 samples and
/// [`MAX_SIGMA_S`]). Attenuating the motion band costs nothing (both sides of the equation pass
/// the filter); what lies well above the motion is where a real mechanism may stop being the
/// model.
#[must_use]
pub fn bandwidth(time_s: &[f64], positions: &[Vec<f64>], first_pass_s: f64, cutoff_over_motion: f64) -> Bandwidth {
    let n = time_s.len();
    let dt = if n > 1 { ((time_s[n - 1] - time_s[0]) / (n - 1) as f64).max(1e-9) } else { 0.01 };
    let narrow = |sigma_s: f64| (DIFFERENTIATOR_SAMPLES * dt).max(DIFFERENTIATOR_OVER_SIGMA * sigma_s);
    let mut f_motion: f64 = 0.0;
    if n >= 3 {
        for y in positions {
            let s = local_cubic(time_s, y, first_pass_s);
            let q: Vec<f64> = s.iter().map(|x| x[0]).filter(|v| v.is_finite()).collect();
            let mean = q.iter().sum::<f64>() / q.len().max(1) as f64;
            let q_rms = rms(q.iter().map(|v| v - mean));
            let v_rms = rms(s.iter().map(|x| x[1]));
            let a_rms = rms(s.iter().map(|x| x[2]));
            // Two estimates of the angular frequency; the larger keeps fast swings of a motion
            // with a large excursion (a swing-up) unattenuated.
            if q_rms > 1e-9 {
                f_motion = f_motion.max(v_rms / (std::f64::consts::TAU * q_rms));
            }
            if v_rms > 1e-9 {
                f_motion = f_motion.max(a_rms / (std::f64::consts::TAU * v_rms));
            }
        }
    }
    if f_motion <= 0.0 {
        let sigma_s = (first_pass_s / 2.0).max(1.5 * dt);
        return Bandwidth { motion_hz: 0.0, half_width_s: first_pass_s, sigma_s, narrow_s: narrow(sigma_s) };
    }
    let f_nyquist = 0.5 / dt;
    let f_cut = (CUTOFF_OVER_MOTION * f_motion).min(0.5 * f_nyquist);
    let half_samples = (4.0 * f_nyquist / f_cut + 4.6) / 3.2;
    let half_width_s = (half_samples * dt).clamp(3.0 * dt, MAX_HALF_WIDTH_S.max(3.0 * dt));
    let f_equation = (cutoff_over_motion * f_motion).min(0.5 * f_nyquist);
    let sigma_s = (GAUSS_HALF_GAIN_F_SIGMA / f_equation).clamp(1.5 * dt, MAX_SIGMA_S.max(1.5 * dt));
    Bandwidth { motion_hz: f_motion, half_width_s, sigma_s, narrow_s: narrow(sigma_s) }
}

/// Least half-width of the differentiator of the raw positions, in samples.
const DIFFERENTIATOR_SAMPLES: f64 = 3.0;

/// Samples the differentiator's half-width keeps where a fast log is read at a working rate
/// ([`working_step`]): a local cubic (four coefficients) over eleven samples or more.
const WORKING_SAMPLES_PER_HALF_WIDTH: f64 = 5.0;

/// The step at which a recording of these positions is read ([`super::Recording::every`]): 1,
/// or, for a log sampled far faster than its motion, the largest step that leaves
/// [`WORKING_SAMPLES_PER_HALF_WIDTH`] samples within the narrowest band's differentiator.
/// Beyond that, samples only repeat what the filters average: a real Panda's 21 s at 1 kHz took
/// 19.7 s to analyse, its 200 Hz rows 1.6 s, for the same findings (the parallel filter's cost
/// grows with the samples per σ, and each of a few hundred candidate columns passes it).
#[must_use]
pub fn working_step(time_s: &[f64], positions: &[Vec<f64>], first_pass_s: f64, cutoff_over_motion: f64) -> usize {
    let band = bandwidth(time_s, positions, first_pass_s, cutoff_over_motion);
    let dt = median_step_s(time_s);
    if dt <= 0.0 {
        return 1;
    }
    let step = (band.narrow_s / (WORKING_SAMPLES_PER_HALF_WIDTH * dt)).floor();
    if step.is_finite() && step >= 2.0 { step as usize } else { 1 }
}

/// Least half-width of the differentiator of the raw positions, as a share of the parallel
/// filter's σ. A local cubic of half-width h passes up to about 0.6/h Hz; at σ/4 that is 13× the
/// filter's half-gain frequency (0.19/σ), so the differentiator leaves the band the filter
/// passes as it is, and removes only noise the filter would remove anyway, but for the terms
/// nonlinear in the motion: friction's sign of the speed and the velocity products rectify a
/// differentiator's noise into effort the filter cannot take out. Three samples of a 1 kHz log
/// are 3 ms: a real Panda's 1 kHz log (positions to 10⁻⁴ rad) read that way had `unknown` of
/// 0.8-1 N·m on its three proximal joints and no friction there, where the same log at 200 Hz
/// (three samples: 15 ms) named friction on all seven.
const DIFFERENTIATOR_OVER_SIGMA: f64 = 0.25;

/// The signals of the equation of motion, filtered in parallel (Gautier's IDIM practice): the
/// positions are differentiated by a narrow local cubic, every term of the equation (the model's
/// effort, each effect's regressor column) is evaluated sample by sample from those, and then
/// each term and the measured effort pass the same wide linear filter ([`Signals::filter`]).
/// Filtering the terms instead of the positions keeps the two sides consistent where the terms
/// are nonlinear in the motion: a Coulomb step at a reversal, `M(q) q̈` of a chain whose inertia
/// changes with its shape, `sin q` of gravity over a large swing. (Smoothing q first and then
/// evaluating the terms makes `K∗sign(q̇)` ≠ `sign(K∗q̇)`: on a real double pendulum the difference
/// was a third of its efforts.) For the linear terms both orders give the same result.
///
/// `q` keeps the widely smoothed positions and their derivatives, for what describes the motion
/// (its speed, its range, where it rests). Efforts hold until the next sample (spec §2), so an
/// effort sample counts at the middle of its hold.
#[must_use]
pub fn signals(time_s: &[f64], positions: &[Vec<f64>], efforts: &[Option<Vec<f64>>], band: &Bandwidth) -> Signals {
    let n = time_s.len();
    let (half_width_s, narrow) = (band.half_width_s, band.narrow_s);
    // Each dof's signals are its own: in parallel, collected in dof order.
    let raw: Vec<Vec<[f64; 3]>> = positions.par_iter().map(|y| local_cubic(time_s, y, narrow)).collect();
    let valid: Vec<bool> = (0..n).map(|i| raw.iter().all(|d| d[i].iter().all(|v| v.is_finite()))).collect();
    let filter = Smoother::new(time_s, &valid, time_s, band.sigma_s);
    let q: Vec<Vec<[f64; 3]>> = positions
        .par_iter()
        .map(|y| {
            let values: Vec<f64> = local_cubic(time_s, y, half_width_s).into_iter().map(|x| x[0]).collect();
            local_cubic(time_s, &values, narrow)
        })
        .collect();
    let mid: Vec<f64> = (0..n).map(|i| if i + 1 < n { 0.5 * (time_s[i] + time_s[i + 1]) } else { time_s[i] }).collect();
    let effort: Vec<Option<Vec<f64>>> = efforts
        .par_iter()
        .map(|e| {
            e.as_ref().map(|e| {
                let finite: Vec<bool> = e.iter().map(|v| v.is_finite()).collect();
                Smoother::new(&mid, &finite, time_s, band.sigma_s).apply(e)
            })
        })
        .collect();
    let effort_size: Vec<Option<Vec<f64>>> =
        efforts.par_iter().map(|e| e.as_ref().map(|e| local_cubic(time_s, e, half_width_s).into_iter().map(|x| x[0]).collect())).collect();
    let (t0, t1) = (time_s.first().copied().unwrap_or(0.0), time_s.last().copied().unwrap_or(0.0));
    let edge = band.support_s();
    let usable = (0..n)
        .map(|i| {
            time_s[i] - t0 >= edge
                && t1 - time_s[i] >= edge
                && q.iter().all(|d| d[i].iter().all(|v| v.is_finite()))
                && effort.iter().flatten().all(|e| e[i].is_finite())
        })
        .collect();
    Signals { time_s: time_s.to_vec(), q, raw, filter, effort_size, effort, usable, band: *band }
}

impl Signals {
    /// Dof `d`'s smoothed speed per sample (rad/s or m/s): the speed the friction laws, the
    /// reversals and the rests are judged on.
    #[must_use]
    pub fn speed(&self, d: usize) -> Vec<f64> {
        self.q[d].iter().map(|x| x[1]).collect()
    }

    /// A term of the equation of motion evaluated at every sample from the narrowly
    /// differentiated positions of dof `d`, then filtered like the efforts; NaN outside `keep`.
    fn term(&self, d: usize, keep: &[bool], f: &dyn Fn([f64; 3]) -> f64) -> Vec<f64> {
        self.filtered(&self.raw[d], keep, f)
    }

    /// A term evaluated on dof `d`'s smoothed motion (`q`) instead, then filtered like the
    /// efforts; NaN outside `keep`. Dry friction is read both ways ([`EffortProblem`]'s friction
    /// candidates).
    fn motion_term(&self, d: usize, keep: &[bool], f: &dyn Fn([f64; 3]) -> f64) -> Vec<f64> {
        self.filtered(&self.q[d], keep, f)
    }

    /// Each series (one per dof) parallel-filtered like the efforts, NaN outside the usable samples.
    fn filtered_usable(&self, series: &[Vec<f64>]) -> Vec<Vec<f64>> {
        series
            .iter()
            .map(|x| self.filter.apply(x).into_iter().enumerate().map(|(i, y)| if self.usable[i] { y } else { f64::NAN }).collect())
            .collect()
    }

    /// `f` of each sample of `motion`, filtered like the efforts; NaN outside `keep`.
    fn filtered(&self, motion: &[[f64; 3]], keep: &[bool], f: &dyn Fn([f64; 3]) -> f64) -> Vec<f64> {
        let values: Vec<f64> = motion.iter().map(|&x| if x.iter().all(|v| v.is_finite()) { f(x) } else { f64::NAN }).collect();
        self.filter.apply(&values).into_iter().zip(keep).map(|(v, &k)| if k { v } else { f64::NAN }).collect()
    }
}

/// Hyper-parameters of a base-tilt candidate: its two horizontal directions (world frame).
const BASE_TILT_HYPER: usize = 6;

/// One candidate term on one joint: its kind, its hyper-parameters, its regressor columns.
#[derive(Debug, Clone)]
struct Candidate {
    /// Effort row (index into the identified joints).
    row: usize,
    kind: EffectKind,
    /// Fixed nonlinear parameters: transition speed, Stribeck speed, engage position…
    hyper: Vec<f64>,
    /// Asymmetric Coulomb (two levels).
    asymmetric: bool,
    /// Columns (indices into the column store).
    columns: Vec<usize>,
    /// Candidates of one family replace each other (one friction law per joint…).
    family: Family,
    /// Why the recording cannot tell this law from another, when it cannot (then it is never
    /// reported): a Stribeck law whose speeds the joint only passes through where it turns.
    unresolved: Option<String>,
}

impl Candidate {
    /// A chain's base tilt ([`super::tilt`]): its hyper-parameters are its two directions.
    fn is_base_tilt(&self) -> bool {
        self.kind == EffectKind::GravityTilt && self.hyper.len() == BASE_TILT_HYPER
    }

    /// A law that extends its family's base law with more parameters (Stribeck's break-away
    /// over Coulomb friction, a second Coulomb level for the reverse direction).
    fn is_refinement(&self) -> bool {
        self.kind == EffectKind::StribeckFriction || (self.kind == EffectKind::CoulombFriction && self.asymmetric)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Family {
    Friction,
    Viscous,
    /// Constant efforts: an offset and a spring's rest position share the constant column.
    Constant,
    Inertia,
    Mass,
    Tilt,
    SoftClose,
}

impl Family {
    /// Whether its effort follows the joint's own motion (speed or acceleration) and vanishes
    /// where the joint rests: such a law says nothing where it does not move.
    fn follows_motion(self) -> bool {
        matches!(self, Self::Friction | Self::Viscous | Self::Inertia | Self::SoftClose)
    }

    /// Whether its effort has a shape the model's own rigid-body error takes: an inertia or a
    /// weight a few percent off acts on the joint through its acceleration (armature, a heavier
    /// part) or its position (an offset, a spring, a tilted axis). Friction and damping follow
    /// the speed, which no rigid-body term does alone.
    fn mimics_rigid_body_error(self) -> bool {
        matches!(self, Self::Constant | Self::Inertia | Self::Mass | Self::Tilt)
    }
}

/// A regressor column: its values on each effort row it touches (NaN = not used).
#[derive(Debug, Clone)]
struct Column {
    rows: BTreeMap<usize, Vec<f64>>,
    /// Its values on its candidate's own row in the motion's description (the smoothed
    /// positions, no parallel filter): the size of a term is judged there, since the filter
    /// attenuates fast terms (inertia) more than slow ones (gravity) and would bias the shares.
    size: Vec<f64>,
    /// Precision of its parameter's prior (a ridge on the diagonal of the normal equations): 0
    /// for a candidate's column, 1 / σ² for the model's own first-moment error ([`super::accuracy`]).
    precision: f64,
}

/// Per row and fold: the Gram matrix of the columns touching the row, their products with the
/// residual and the residual's square, all weighted.
#[derive(Debug, Clone)]
struct RowGram {
    /// Column ids touching this row.
    columns: Vec<usize>,
    /// Per fold: gram (len² row-major), c·r, r·r, sample count.
    folds: Vec<(Vec<f64>, Vec<f64>, f64, usize)>,
}

/// The normal equations of every pair of columns, summed over the effort rows and over the
/// folds other than each one in turn (and over all of them): what [`EffortProblem::solve`]
/// picks its matrix from, instead of adding up the rows' Gram matrices afresh for every
/// candidate set and fold (most of forward selection's time on a chain, whose every fit holds
/// the model's own accuracy). Each sum adds the same numbers in the same order as that assembly
/// did (rows ascending, then folds ascending), so the fits are its bit for bit (test
/// `blocks_solved_apart_give_the_joint_solve_and_a_heavier_part_couples_its_joints`).
///
/// Most columns live on one row (a joint's own terms): their pairs are that row's Gram summed
/// over folds. A column on several rows (the model's accuracy, a heavier part) keeps its sums
/// with every column. Memory: (folds + 1) · (Σ rows' columns² + multi-row columns · columns).
#[derive(Debug, Clone, Default)]
struct NormalSums {
    /// Per column: the rows it is on, ascending, with its index among each row's Gram columns.
    rows_of: Vec<Vec<(usize, usize)>>,
    /// Per column: where its sums are.
    place: Vec<SumPlace>,
    /// Per row, per fold left out (then none: index `folds`): its Gram matrix summed over the
    /// other folds (the row's columns², row-major).
    row_grams: Vec<(usize, Vec<Vec<f64>>)>,
    /// Per column on several rows, per fold left out (then none): its sums with every column.
    multi: Vec<Vec<Vec<f64>>>,
    /// Per fold left out (then none), per column: its products with the residual, summed.
    rhs: Vec<Vec<f64>>,
}

/// Where [`NormalSums`] keeps a column's sums.
#[derive(Debug, Clone, Copy)]
enum SumPlace {
    /// No used row holds the column.
    Nowhere,
    /// On one row: the row and the column's index among that row's Gram columns.
    Row(usize, usize),
    /// On several rows: its index in [`NormalSums::multi`].
    Multi(usize),
}

impl NormalSums {
    /// The sums of `grams` (each row's columns ascending) over `columns` columns and `folds` folds.
    fn new(grams: &[RowGram], columns: usize, folds: usize) -> Self {
        let mut rows_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); columns];
        for (r, g) in grams.iter().enumerate() {
            for (la, &c) in g.columns.iter().enumerate() {
                rows_of[c].push((r, la));
            }
        }
        let mut multi_count = 0;
        let place: Vec<SumPlace> = rows_of
            .iter()
            .map(|rows| match rows.as_slice() {
                [] => SumPlace::Nowhere,
                &[(r, la)] => SumPlace::Row(r, la),
                _ => {
                    multi_count += 1;
                    SumPlace::Multi(multi_count - 1)
                }
            })
            .collect();
        let multi =
            (0..columns).filter(|&c| matches!(place[c], SumPlace::Multi(_))).map(|u| Self::multi_sums(grams, &rows_of, u, folds)).collect();
        let row_grams = grams.iter().map(|g| (g.columns.len(), (0..=folds).map(|skip| Self::row_sum(g, skip)).collect())).collect();
        // Rows ascending, then folds other than the one left out, as the assembly adds them.
        let rhs = (0..=folds)
            .map(|skip| {
                rows_of
                    .iter()
                    .map(|rows| {
                        let mut total = 0.0;
                        for &(r, la) in rows {
                            for f in other_folds(&grams[r], skip) {
                                total += f.1[la];
                            }
                        }
                        total
                    })
                    .collect()
            })
            .collect();
        Self { rows_of, place, row_grams, multi, rhs }
    }

    /// Row `g`'s Gram matrix summed over its folds other than `skip`.
    fn row_sum(g: &RowGram, skip: usize) -> Vec<f64> {
        let m = g.columns.len();
        let mut sum = vec![0.0; m * m];
        for f in other_folds(g, skip) {
            sum.iter_mut().zip(&f.0).for_each(|(s, v)| *s += v);
        }
        sum
    }

    /// Column `u`'s sums with every column, per fold left out (then none): over the rows both are
    /// on, ascending, then the folds.
    fn multi_sums(grams: &[RowGram], rows_of: &[Vec<(usize, usize)>], u: usize, folds: usize) -> Vec<Vec<f64>> {
        let mut per_skip = vec![vec![0.0; rows_of.len()]; folds + 1];
        for (c, rows_c) in rows_of.iter().enumerate() {
            // The rows both columns are on, with `u`'s index there and `c`'s.
            let shared: Vec<(usize, usize, usize)> =
                rows_of[u].iter().filter_map(|&(r, lu)| rows_c.iter().find(|(rc, _)| *rc == r).map(|&(_, lc)| (r, lu, lc))).collect();
            if shared.is_empty() {
                continue;
            }
            for (skip, sums) in per_skip.iter_mut().enumerate() {
                let mut total = 0.0;
                for &(r, lu, lc) in &shared {
                    let m = grams[r].columns.len();
                    for f in other_folds(&grams[r], skip) {
                        total += f.0[lu * m + lc];
                    }
                }
                sums[c] = total;
            }
        }
        per_skip
    }

    /// The normal equations (p × p row-major, and p) of the columns `cols`, per fold left out
    /// (then over all folds: the last).
    fn normal_equations(&self, cols: &[usize]) -> Vec<(Vec<f64>, Vec<f64>)> {
        let p = cols.len();
        let mut systems: Vec<(Vec<f64>, Vec<f64>)> =
            self.rhs.iter().map(|rhs| (vec![0.0; p * p], cols.iter().map(|&c| rhs.get(c).copied().unwrap_or(0.0)).collect())).collect();
        // Every sum is symmetric to the bit (the rows' Gram matrices are mirrored copies, and
        // both halves are added in one order): the lower half is filled, then mirrored.
        for (i, &ci) in cols.iter().enumerate() {
            for (j, &cj) in cols.iter().enumerate().take(i + 1) {
                let Some((per_skip, at)) = self.pair(ci, cj) else { continue };
                for ((a, _), sums) in systems.iter_mut().zip(per_skip) {
                    a[i * p + j] = sums[at];
                    a[j * p + i] = sums[at];
                }
            }
        }
        systems
    }

    /// The sums of columns `ci` and `cj` (`ci` the later in a fit's order) per fold left out
    /// (then none), and the entry there; None where they never meet.
    fn pair(&self, ci: usize, cj: usize) -> Option<(&[Vec<f64>], usize)> {
        match (self.place[ci], self.place[cj]) {
            (SumPlace::Multi(u), _) => Some((&self.multi[u], cj)),
            (_, SumPlace::Multi(u)) => Some((&self.multi[u], ci)),
            (SumPlace::Row(ri, li), SumPlace::Row(rj, lj)) if ri == rj => {
                let (m, sums) = &self.row_grams[ri];
                Some((sums, li * m + lj))
            }
            _ => None,
        }
    }

    /// Entry (`ci`, `cj`) of the normal equations of system `s` ([`Self::normal_equations`]).
    fn entry(&self, s: usize, ci: usize, cj: usize) -> f64 {
        let (later, earlier) = if ci >= cj { (ci, cj) } else { (cj, ci) };
        self.pair(later, earlier).map_or(0.0, |(per_skip, at)| per_skip[s][at])
    }

    /// Entry `c` of the right-hand side of system `s`.
    fn rhs_entry(&self, s: usize, c: usize) -> f64 {
        self.rhs[s].get(c).copied().unwrap_or(0.0)
    }
}

/// Row `g`'s folds other than `skip`, in order.
fn other_folds(g: &RowGram, skip: usize) -> impl Iterator<Item = &(Vec<f64>, Vec<f64>, f64, usize)> {
    g.folds.iter().enumerate().filter(move |(k, _)| *k != skip).map(|(_, f)| f)
}

/// One identified joint (an effort row).
#[derive(Debug, Clone)]
pub struct RowInfo {
    /// Model joint index.
    pub joint: usize,
    /// Dof index.
    pub dof: usize,
    /// Residual effort of the model as written, per sample (NaN where not used).
    pub residual: Vec<f64>,
    /// RMS of the joint's own effort over the used samples (the practical scale).
    pub effort_rms: f64,
    /// RMS of the effort the model needs to hold the tree still against gravity at the joint
    /// ([`SelectionRules::min_static_load_share`]).
    pub gravity_rms: f64,
    /// RMS of the effort the model needs at the joint to move the tree as recorded beyond
    /// holding it against gravity (its inertial, centrifugal and Coriolis effort:
    /// [`SelectionRules::min_inertial_load_share`]).
    pub inertial_rms: f64,
    /// RMS of the whole effort the model needs at the joint (inertial and gravity together: what a
    /// heavier part scales).
    pub model_rms: f64,
    /// Correlation of the recorded effort with the effort the model needs, over the used
    /// samples (near 1 where the model holds; strongly negative where the recording's sign
    /// convention is the opposite of the model's: [`EFFORT_AGAINST_MODEL`]).
    pub model_correlation: f64,
}

/// A correlation of the recorded effort with the effort the model needs below this says the two
/// run against each other: where the named terms leave the effort unexplained, the report asks
/// whether the recording's sign convention (positive along the joint's axis, spec §2) is the
/// model's. A missing stiff spring turns the correlation round too, but is named and explains it.
pub const EFFORT_AGAINST_MODEL: f64 = -0.5;

/// Pearson correlation of the pairs (0 with fewer than two or no spread).
fn correlation(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
    let v: Vec<(f64, f64)> = pairs.filter(|(a, b)| a.is_finite() && b.is_finite()).collect();
    if v.len() < 2 {
        return 0.0;
    }
    let n = v.len() as f64;
    let (ma, mb) = (v.iter().map(|p| p.0).sum::<f64>() / n, v.iter().map(|p| p.1).sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (a, b) in &v {
        sab += (a - ma) * (b - mb);
        saa += (a - ma).powi(2);
        sbb += (b - mb).powi(2);
    }
    if saa > 0.0 && sbb > 0.0 { sab / (saa * sbb).sqrt() } else { 0.0 }
}

/// What effort-space identification found for one joint.
#[derive(Debug, Clone)]
pub struct JointFinding {
    /// Model joint index.
    pub joint: usize,
    /// Effects in the effort-mode parameter layout (`coulomb_friction`: friction, transition
    /// speed, reverse level or NaN).
    pub effects: Vec<Effect>,
    /// One σ of each effect's parameters (jackknife over the folds).
    pub param_std: Vec<Vec<f64>>,
    /// Confidence of each effect.
    pub confidence: Vec<f64>,
    /// RMS effort of each effect over the motion.
    pub effect_rms: Vec<f64>,
    /// Held-out RMS residual effort before (model as written) and after.
    pub cv_rms_before: f64,
    /// After.
    pub cv_rms_after: f64,
    /// The joint's own RMS effort.
    pub effort_rms: f64,
    /// The model's RMS gravity effort at the joint.
    pub gravity_rms: f64,
    /// [`RowInfo::model_correlation`].
    pub model_correlation: f64,
    /// Residual effort before and after, per sample (NaN where not used).
    pub residual_before: Vec<f64>,
    /// After.
    pub residual_after: Vec<f64>,
    /// Terms considered and not reported, with the reason.
    pub rejected: Vec<String>,
    /// The model's own first-moment error fitted beside the terms ([`super::accuracy`]), for
    /// the bodies whose nearest identified joint this is: (tree body, added mass × centre of
    /// mass in the body's frame, kg·m).
    pub first_moments: Vec<(usize, DVec3)>,
    /// Share of the joint's usable samples left out of effort space as rests its dry friction
    /// holds, with the filters' support around them ([`super::rests`]); None where none were.
    pub rests_left_out: Option<f64>,
}

impl JointFinding {
    /// RMS effort over the motion of its term of `kind` (0 without one).
    #[must_use]
    pub fn effect_rms_of(&self, kind: EffectKind) -> f64 {
        self.effects.iter().zip(&self.effect_rms).find(|(e, _)| e.kind == kind).map_or(0.0, |(_, rms)| *rms)
    }

    /// The static level and the speed below which the joint counts as at rest, of the dry
    /// friction found on it ([`dry_friction_at_rest`] of its first dry-friction effect).
    pub(super) fn friction_at_rest(&self) -> Option<(f64, f64)> {
        self.effects.iter().find_map(dry_friction_at_rest)
    }

    /// The finding with dry friction granted its whole range at rest. Stuck, a joint's friction
    /// is whatever holds it, up to its static level, not the smooth law's value near zero speed;
    /// a residual within that level where the joint rests (`speed`, the smoothed velocity, below
    /// the friction's transition) is friction, not an unexplained effort. Without dry friction,
    /// or where it changes nothing, the finding as it is.
    #[must_use]
    pub fn with_friction_at_rest(&self, speed: &[f64]) -> Self {
        let Some((level, rest_speed)) = self.friction_at_rest() else { return self.clone() };
        let residual_after: Vec<f64> = self
            .residual_after
            .iter()
            .zip(speed)
            .map(|(&r, &v)| {
                if !(r.is_finite() && v.abs() <= rest_speed) {
                    return r;
                }
                // The smooth law's share at this speed back in, then the static range out.
                let held = r + level * (v / rest_speed.max(1e-12)).tanh();
                held.signum() * (held.abs() - level).max(0.0)
            })
            .collect();
        let before = rms(self.residual_after.iter().copied().filter(|x| x.is_finite()));
        let after = rms(residual_after.iter().copied().filter(|x| x.is_finite()));
        if after.partial_cmp(&before) != Some(std::cmp::Ordering::Less) {
            return self.clone();
        }
        Self { cv_rms_after: self.cv_rms_after * after / before, residual_after, ..self.clone() }
    }
}

/// The static level and the speed below which the joint counts as at rest of a dry-friction
/// effect in the effort-mode parameter layout (`coulomb_friction`: the larger of its two levels
/// within its transition speed; `stribeck_friction`: its break-away within its Stribeck speed);
/// None for any other kind.
pub(super) fn dry_friction_at_rest(e: &Effect) -> Option<(f64, f64)> {
    match e.kind {
        EffectKind::CoulombFriction => Some((e.params[0].max(e.params[2].abs()).max(0.0), e.params[1])),
        EffectKind::StribeckFriction => Some((e.params[0].max(e.params[1]).max(0.0), e.params[2])),
        _ => None,
    }
}

/// A set of candidate terms of an [`EffortProblem`] (opaque: only the problem reads it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Terms(Vec<usize>);

/// The whole effort-space problem.
pub struct EffortProblem<'a> {
    model: &'a GapModel,
    rules: SelectionRules,
    rows: Vec<RowInfo>,
    columns: Vec<Column>,
    candidates: Vec<Candidate>,
    grams: Vec<RowGram>,
    /// The normal equations of every pair of columns, summed ([`NormalSums`]).
    sums: NormalSums,
    fold_of: Vec<usize>,
    weights: Vec<f64>,
    used: Vec<Vec<bool>>,
    /// Per row and fold: whether the joint moves there ([`MOVING_FOLD_SHARE`]).
    moving: Vec<Vec<bool>>,
    /// Per row and sample: whether the sample's filtered terms draw on a reversal of the joint's
    /// motion ([`near_reversals`]), where dry friction turns round; None for a joint that keeps
    /// fewer than [`MIN_AWAY_SHARE`] of its used samples away from its reversals (it turns too
    /// often for a reading there).
    reversals: Vec<Option<Vec<bool>>>,
    /// Blocks of columns already fitted ([`Self::fit_block`]).
    block_fits: Mutex<HashMap<Vec<usize>, Arc<BlockFit>>>,
    /// Blocks of columns already factored, for the bordered fits of forward selection
    /// ([`Self::factored`]).
    factors: Mutex<HashMap<Vec<usize>, Option<Arc<Factored>>>>,
    /// Blocks already fitted by extending a base's factors ([`Self::bordered_fit`]).
    bordered_fits: Mutex<HashMap<BorderedKey, Option<Arc<BlockFit>>>>,
    /// Sizes of terms already measured ([`Self::change_rms`]).
    change_sizes: Mutex<HashMap<ChangeKey, f64>>,
    /// Forward steps already weighed, per chosen set and kind of step ([`Self::best_step`]).
    steps: Mutex<HashMap<StepKey, Arc<WeighedStep>>>,
    /// The columns of the model's own first-moment error, in every fit ([`super::accuracy`]),
    /// each with its body, the axis of the body's frame, and the row that owns the body (its
    /// nearest identified joint).
    nuisance: BTreeMap<usize, (usize, usize, usize)>,
    /// Per row (or empty): its rests left out ([`Exclusions::rests`]).
    rests: Vec<Option<RestsLeftOut>>,
}

/// What an [`EffortProblem`] leaves out of its rows.
#[derive(Debug, Clone, Default)]
pub struct Exclusions {
    /// Per row and sample: left out (in contact with a stop, or a rest its dry friction holds,
    /// each widened by the filters' support).
    pub samples: Vec<Vec<bool>>,
    /// Per row (or empty: none): where its rests are among them ([`super::rests`]).
    pub rests: Vec<Option<RestsLeftOut>>,
}

/// A row whose rests were left out ([`super::rests`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestsLeftOut {
    /// The transition speed its Coulomb candidates take (rad/s or m/s), the only one, since the
    /// samples that show a law's shape through zero speed are the ones left out: that of the dry
    /// friction read with the rests, or, where that reading held none, the speed below which the
    /// joint counts as at rest (a law that holds it there turns within it: [`super::rests`]).
    pub transition_speed: f64,
    /// Share of the row's usable samples left out for them.
    pub share: f64,
}

/// The candidates weighed in one forward step (every one not banned, chosen or unresolved that
/// may take it), in candidate order, each with its held-out gain and whether it passed, with the
/// bans they were weighed under ([`EffortProblem::best_step`]; [`EffortProblem::best_pair`] reads
/// the gains of a stalled step's single terms).
#[derive(Debug)]
struct WeighedStep {
    banned: Vec<bool>,
    weighed: Vec<Weighed>,
}

/// One candidate weighed as a forward step ([`WeighedStep`]).
#[derive(Debug, Clone, Copy)]
struct Weighed {
    candidate: usize,
    gain: f64,
    passes: bool,
}

/// A forward step: the chosen set it starts from, and whether it weighs whole refinements.
type StepKey = (Vec<usize>, bool);

/// A block fitted by extension: its base's columns, its new columns, the rows it scores.
type BorderedKey = (Vec<usize>, Vec<usize>, Vec<usize>);

/// A term's size, by candidate and its parameters' bits, and the replaced term's, if any.
type ChangeKey = (usize, Vec<u64>, Option<(usize, Vec<u64>)>);

/// Fitted parameters by column id; a column outside the fit holds 0 (no term). Dense rather
/// than a map: forward selection builds nine of these (every fold left out, and all) for every
/// candidate set it weighs, and a map's inserts and frees were a tenth of a chain's analysis.
#[derive(Debug, Clone, PartialEq)]
struct Params(Vec<f64>);

impl Params {
    /// All `columns` parameters 0.
    fn zeros(columns: usize) -> Self {
        Self(vec![0.0; columns])
    }

    /// Column `col`'s parameter (0 outside the fit).
    fn get(&self, col: usize) -> f64 {
        self.0.get(col).copied().unwrap_or(0.0)
    }

    /// Sets the parameters of the columns `cols` to `values`, in order.
    fn set(&mut self, cols: &[usize], values: &[f64]) {
        for (&c, &v) in cols.iter().zip(values) {
            self.0[c] = v;
        }
    }
}

impl std::ops::Index<&usize> for Params {
    type Output = f64;
    fn index(&self, col: &usize) -> &f64 {
        &self.0[*col]
    }
}

/// What one block of columns fits ([`EffortProblem::fit_block`]).
#[derive(Debug)]
struct BlockFit {
    /// The effort rows the block's columns touch, ascending.
    rows: Vec<usize>,
    /// Held-out weighted squared error per touched row and fold.
    fold_sse: Vec<Vec<f64>>,
    /// Parameters fitted on all folds, in the block's column order.
    theta: Vec<f64>,
    /// Parameters fitted without each fold.
    theta_without: Vec<Vec<f64>>,
}

/// A block of columns' normal equations factored ([`EffortProblem::factored`]).
#[derive(Debug)]
struct Factored {
    /// Per system (every fold left out, then all): the lower Cholesky factor `L` of the ridged
    /// matrix and `L⁻¹ b`.
    systems: Vec<(Vec<f64>, Vec<f64>)>,
}

/// The parameters of `base`'s columns (`theta_b`) and the others' (`theta_c`, in order) in
/// the order of `cols` (sorted, `base` a sorted part of it).
fn merged(cols: &[usize], base: &[usize], theta_b: &[f64], theta_c: &[f64]) -> Vec<f64> {
    let (mut b, mut c) = (theta_b.iter(), theta_c.iter());
    cols.iter().map(|col| if base.binary_search(col).is_ok() { b.next() } else { c.next() }.copied().unwrap_or(0.0)).collect()
}

/// Whether `gain` beats `best` by more than a tie: ties (look-alike laws, whose held-out cuts
/// differ in the fourth digit) go to the one weighed first, whatever the gains' sign.
fn outgains(gain: f64, best: f64) -> bool {
    gain > best + 1e-3 * best.abs() + 1e-12
}

/// Entries kept in each of [`EffortProblem`]'s caches before it starts afresh (a bound on their
/// memory: an entry holds a few dozen numbers).
const MAX_CACHED: usize = 200_000;

/// The value `cache` holds for `key`, or `compute`'s, then remembered (the cache emptied first
/// when it holds [`MAX_CACHED`] entries). A poisoned lock only costs the remembering.
fn remembered<K: std::hash::Hash + Eq, V: Clone>(cache: &Mutex<HashMap<K, V>>, key: K, compute: impl FnOnce() -> V) -> V {
    if let Some(hit) = cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
        return hit;
    }
    let value = compute();
    if let Ok(mut c) = cache.lock() {
        if c.len() >= MAX_CACHED {
            c.clear();
        }
        c.insert(key, value.clone());
    }
    value
}

/// Least RMS speed of a joint over a block's samples, as a share of its RMS speed over all of
/// them, for the block to show a law of its motion (friction, damping, a rotor's inertia): a
/// door that rests through a block, held by its friction or left alone, tells such a law nothing
/// there, whatever the fit does with the noise.
const MOVING_FOLD_SHARE: f64 = 0.1;

/// The effort the model as written needs at every sample, per dof: inverse dynamics plus the
/// URDF's own `<dynamics>`; and per body the effort of its inertia alone (mass regressors).
struct Efforts {
    tau: Vec<Vec<f64>>,
    /// Gravity's share of `tau` (the effort that holds the tree still at q).
    gravity: Vec<Vec<f64>>,
    /// body → per dof, per sample.
    body_tau: BTreeMap<usize, Vec<Vec<f64>>>,
}

/// The model's efforts for the regression (from the raw derivatives, parallel-filtered) and for
/// judging sizes (from the smoothed description of the motion).
struct ModelEfforts {
    filtered: Efforts,
    size: Efforts,
    /// The efforts a tilted base adds, where a chain's base joint is identified ([`super::tilt`]).
    base_tilt: Option<BaseTiltEfforts>,
}

/// The two columns of a chain's base tilt: per horizontal direction ([`tilt_directions`]), per
/// dof and sample, the effort of gravity along it at rest ([`tilt_efforts`]).
struct BaseTiltEfforts {
    /// The base joint's index among the effort joints (the candidate's row).
    row: usize,
    /// The two horizontal unit directions of the columns, world frame.
    directions: [DVec3; 2],
    /// Parallel-filtered like the measured efforts, NaN outside the usable samples.
    filtered: [Vec<Vec<f64>>; 2],
    /// On the motion's description, unfiltered (sizes).
    size: [Vec<Vec<f64>>; 2],
}

/// The base-tilt columns over `sig`, where the model's chain has a base joint among the effort
/// joints whose axis is near vertical.
fn base_tilt_efforts(
    model: &GapModel,
    tree: &MultiBody,
    sig: &Signals,
    gravity: DVec3,
    effort_joints: &[usize],
) -> Option<BaseTiltEfforts> {
    let j = base_joint(model)?;
    let row = effort_joints.iter().position(|&x| x == j)?;
    let directions = tilt_directions(model, j, gravity.normalize_or_zero())?;
    let (raw, size) = rayon::join(|| tilt_efforts(tree, &sig.raw, gravity, directions), || tilt_efforts(tree, &sig.q, gravity, directions));
    let filtered = raw.map(|dofs| sig.filtered_usable(&dofs));
    Some(BaseTiltEfforts { row, directions, filtered, size })
}

/// The model's efforts evaluated sample by sample at the motion `q` (NaN where it is not finite).
fn efforts_at(model: &GapModel, tree: &MultiBody, q_of: &[Vec<[f64; 3]>], gravity: DVec3, bodies: &[usize]) -> Efforts {
    let dofs = model.dofs();
    let nd = dofs.len();
    let n = q_of.first().map_or(0, Vec::len);
    let mut tau = vec![vec![f64::NAN; n]; nd];
    let mut held = vec![vec![f64::NAN; n]; nd];
    let mut body_tau: BTreeMap<usize, Vec<Vec<f64>>> = bodies.iter().map(|&b| (b, vec![vec![f64::NAN; n]; nd])).collect();
    let (mut q, mut qd, mut qdd) = (vec![0.0; nd], vec![0.0; nd], vec![0.0; nd]);
    for i in (0..n).filter(|&i| q_of.iter().all(|d| d[i].iter().all(|v| v.is_finite()))) {
        for d in 0..nd {
            [q[d], qd[d], qdd[d]] = q_of[d][i];
        }
        let k = tree.kinematics(&q, &qd, &qdd, gravity);
        let all = tree.efforts_with(&k, |b| Some(tree.bodies()[b].inertia));
        let still = tree.inverse_dynamics(&q, &[], &[], gravity);
        for (d, &j) in dofs.iter().enumerate() {
            held[d][i] = still[d];
            let joint = &model.joints[j];
            let v = qd[d];
            let speed_scale = 1e-3;
            tau[d][i] = all[d] + joint.damping * v + joint.friction * (v / speed_scale).tanh();
        }
        for (&b, out) in &mut body_tau {
            let one = tree.efforts_with(&k, |x| (x == b).then(|| tree.bodies()[x].inertia));
            for d in 0..nd {
                out[d][i] = one[d];
            }
        }
    }
    Efforts { tau, gravity: held, body_tau }
}

fn model_efforts(model: &GapModel, tree: &MultiBody, sig: &Signals, gravity: DVec3, bodies: &[usize]) -> ModelEfforts {
    let (raw, size) =
        rayon::join(|| efforts_at(model, tree, &sig.raw, gravity, bodies), || efforts_at(model, tree, &sig.q, gravity, bodies));
    // Parallel filtering: each term passes the filter the measured efforts passed.
    let filtered = |v: Vec<Vec<f64>>| -> Vec<Vec<f64>> { sig.filtered_usable(&v) };
    let filtered = Efforts {
        tau: filtered(raw.tau),
        gravity: filtered(raw.gravity),
        body_tau: raw.body_tau.into_iter().map(|(b, v)| (b, filtered(v))).collect(),
    };
    ModelEfforts { filtered, size, base_tilt: None }
}

/// The moving part of a joint: its child body and the bodies welded to it.
#[must_use]
pub fn moving_part(tree: &MultiBody, body: usize) -> Vec<usize> {
    let mut out = vec![body];
    for (i, b) in tree.bodies().iter().enumerate() {
        if b.dof.is_none() && b.parent.is_some_and(|p| out.contains(&p)) {
            out.push(i);
        }
    }
    out
}

/// RMS of the finite values of `v` (0 without one).
pub(super) fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, c) = v.filter(|x| x.is_finite()).fold((0.0, 0usize), |(s, c), x| (s + x * x, c + 1));
    if c == 0 { 0.0 } else { (s / c as f64).sqrt() }
}

/// What every reading of one set of signals shares (the whole recording's, the training part's,
/// one with more samples excluded at stops): the model's efforts and the first-moment efforts
/// of the bodies its chain joints carry, filtered like the measured efforts. The readings differ
/// only in the samples they use, which [`EffortProblem::new`] masks; computed once, they are the
/// same numbers as each reading's own.
pub struct ModelReading {
    /// The effort joints (model joint indices) it was made for: the readings' rows.
    effort_joints: Vec<usize>,
    gravity: DVec3,
    tree: MultiBody,
    /// Per effort joint: the bodies of its moving part.
    part_of: Vec<Vec<usize>>,
    /// Per effort joint: the bodies it carries, none for a joint alone on its body.
    beyond: Vec<Vec<usize>>,
    me: ModelEfforts,
    /// body → per axis of its frame → per dof: the filtered effort of its unit first moment
    /// (every sample, unmasked); empty without model-accuracy columns.
    moments: BTreeMap<usize, [Vec<Vec<f64>>; 3]>,
}

impl ModelReading {
    /// The model's efforts over `sig` for the effort joints `effort_joints` (model joint
    /// indices); None where the model has no tree.
    #[must_use]
    pub fn new(model: &GapModel, sig: &Signals, gravity: DVec3, effort_joints: &[usize], rules: &SelectionRules) -> Option<Self> {
        let (tree, body_of_link) = model.multibody().ok()?;
        let part_of: Vec<Vec<usize>> =
            effort_joints.iter().map(|&j| body_of_link[model.joints[j].child].map(|b| moving_part(&tree, b)).unwrap_or_default()).collect();
        let mut bodies: Vec<usize> = part_of.iter().flatten().copied().collect();
        bodies.sort_unstable();
        bodies.dedup();
        let beyond: Vec<Vec<usize>> = effort_joints
            .iter()
            .map(|&j| match body_of_link[model.joints[j].child] {
                Some(b) if in_serial_chain(model, j) => bodies_beyond(&tree, b),
                _ => Vec::new(),
            })
            .collect();
        let dof_of: Vec<usize> = effort_joints.iter().map(|&j| model.dofs().iter().position(|&x| x == j)).collect::<Option<_>>()?;
        let (mut me, moments) = rayon::join(
            || model_efforts(model, &tree, sig, gravity, &bodies),
            || first_moment_columns(&tree, sig, gravity, &beyond, &dof_of, rules),
        );
        me.base_tilt = base_tilt_efforts(model, &tree, sig, gravity, effort_joints);
        Some(Self { effort_joints: effort_joints.to_vec(), gravity, tree, part_of, beyond, me, moments })
    }
}

/// The filtered first-moment efforts ([`ModelReading::moments`]) of the bodies in `beyond`, on
/// the dofs (`dof_of[r]`: effort joint r's) of the effort joints that carry each; empty on the
/// others.
fn first_moment_columns(
    tree: &MultiBody,
    sig: &Signals,
    gravity: DVec3,
    beyond: &[Vec<usize>],
    dof_of: &[usize],
    rules: &SelectionRules,
) -> BTreeMap<usize, [Vec<Vec<f64>>; 3]> {
    let mut bodies: Vec<usize> = beyond.iter().flatten().copied().collect();
    bodies.sort_unstable();
    bodies.dedup();
    if bodies.is_empty() || rules.first_moment_tolerance <= 0.0 {
        return BTreeMap::new();
    }
    first_moment_efforts(tree, &sig.raw, gravity, &bodies)
        .into_iter()
        .map(|(b, axes)| {
            let carried = |d: usize| (0..beyond.len()).any(|r| dof_of[r] == d && beyond[r].contains(&b));
            let filtered = |dofs: Vec<Vec<f64>>| -> Vec<Vec<f64>> {
                dofs.par_iter().enumerate().map(|(d, x)| if carried(d) { sig.filter.apply(x) } else { Vec::new() }).collect()
            };
            (b, axes.map(filtered))
        })
        .collect()
}

impl<'a> EffortProblem<'a> {
    /// Sets up the rows (the effort joints `reading` was made for over `sig`: model joint
    /// indices with a recorded effort), the candidate columns and their Gram matrices.
    /// `excluded.samples[row][i]` marks samples left out (in contact with a stop, or a rest dry
    /// friction holds); `train`, the samples the reading may use.
    #[must_use]
    pub fn new(
        model: &'a GapModel,
        sig: &Signals,
        reading: &ModelReading,
        excluded: &Exclusions,
        train: &[bool],
        rules: SelectionRules,
    ) -> Option<Self> {
        let Exclusions { samples: excluded, rests } = excluded;
        let (effort_joints, gravity) = (&reading.effort_joints, reading.gravity);
        let dofs = model.dofs();
        let n = sig.time_s.len();
        let me = &reading.me;
        let mut rows = Vec::new();
        let mut used = Vec::new();
        for (r, &j) in effort_joints.iter().enumerate() {
            let d = dofs.iter().position(|&x| x == j)?;
            let measured = sig.effort[d].as_ref()?;
            let ok: Vec<bool> = (0..n).map(|i| sig.usable[i] && train[i] && !excluded[r][i] && me.filtered.tau[d][i].is_finite()).collect();
            let residual: Vec<f64> = (0..n).map(|i| if ok[i] { measured[i] - me.filtered.tau[d][i] } else { f64::NAN }).collect();
            // The joint's own efforts over the motion, in its description: what the motion asks
            // of it beyond holding it still against gravity, and what is applied beyond that
            // holding effort (on a passive joint, the gravity that moves it). The static holding
            // effort of a loaded arm is left out: next to it every dynamic term of a heavy link
            // would look small, though the motion depends on nothing else.
            let z = &me.size;
            let applied = &sig.effort_size[d];
            let rms_of = |f: &dyn Fn(usize) -> f64| rms((0..n).filter(|&i| ok[i]).map(f));
            let scale =
                rms_of(&|i| applied.as_ref().map_or(0.0, |e| e[i]) - z.gravity[d][i]).max(rms_of(&|i| z.tau[d][i] - z.gravity[d][i]));
            let gravity_rms = rms_of(&|i| z.gravity[d][i]);
            let inertial_rms = rms_of(&|i| z.tau[d][i] - z.gravity[d][i]);
            let model_rms = rms_of(&|i| z.tau[d][i]);
            let model_correlation = correlation((0..n).filter(|&i| ok[i]).map(|i| (measured[i], me.filtered.tau[d][i])));
            rows.push(RowInfo { joint: j, dof: d, residual, effort_rms: scale, gravity_rms, inertial_rms, model_rms, model_correlation });
            used.push(ok);
        }
        if used.iter().all(|u| u.iter().filter(|&&x| x).count() < 50) {
            return None;
        }
        let mut problem = Self {
            model,
            rules,
            rows,
            columns: Vec::new(),
            candidates: Vec::new(),
            grams: Vec::new(),
            sums: NormalSums::default(),
            fold_of: Vec::new(),
            weights: Vec::new(),
            used,
            moving: Vec::new(),
            reversals: Vec::new(),
            block_fits: Mutex::new(HashMap::new()),
            factors: Mutex::new(HashMap::new()),
            bordered_fits: Mutex::new(HashMap::new()),
            change_sizes: Mutex::new(HashMap::new()),
            steps: Mutex::new(HashMap::new()),
            nuisance: BTreeMap::new(),
            rests: rests.clone(),
        };
        problem.fold_of = problem.assign_folds(sig);
        problem.moving = problem.moving_folds(sig);
        problem.reversals = problem
            .rows
            .iter()
            .zip(&problem.used)
            .map(|(row, used)| {
                let speed = sig.speed(row.dof);
                let near = near_reversals(&sig.time_s, &speed, sig.band.support_s());
                let (count, away) =
                    (0..near.len()).filter(|&i| used[i]).fold((0usize, 0usize), |(c, a), i| (c + 1, a + usize::from(!near[i])));
                (away as f64 >= MIN_AWAY_SHARE * count as f64).then_some(near)
            })
            .collect();
        problem.build_candidates(sig, me, &reading.part_of, gravity.normalize_or_zero());
        problem.add_model_accuracy(reading, sig);
        problem.weights = problem.rows.iter().map(|r| 1.0 / robust_scale(&r.residual).max(1e-9).powi(2)).collect();
        problem.build_grams();
        problem.sums = NormalSums::new(&problem.grams, problem.columns.len(), problem.rules.folds.max(2));
        Some(problem)
    }

    /// Adds the model's first-moment error as nuisance columns ([`super::accuracy`]): per body
    /// carried by a chain joint and per axis of its frame, one column on every chain row that
    /// carries it, with its prior's precision; every fit includes them ([`Self::columns_of`]).
    fn add_model_accuracy(&mut self, reading: &ModelReading, sig: &Signals) {
        let (tree, beyond, moments) = (&reading.tree, &reading.beyond, &reading.moments);
        if moments.is_empty() {
            return;
        }
        // The weighted sums of the normal equations count every sample, but the filtered terms
        // and efforts are correlated over the filter's width: one independent piece of evidence
        // per 2√π σ of time (a Gaussian filter's equivalent width). The prior is weighed against
        // that evidence, not against the sample count, or any data would swamp it.
        let dt = median_step_s(&sig.time_s).max(1e-9);
        let samples_per_piece = (2.0 * std::f64::consts::PI.sqrt() * sig.band.sigma_s / dt).max(1.0);
        // A body's owner: the row that carries it with the fewest bodies (its nearest joint).
        let owner = |b: usize| (0..beyond.len()).filter(|&r| beyond[r].contains(&b)).min_by_key(|&r| (beyond[r].len(), r));
        for &b in moments.keys() {
            let Some(owner) = owner(b) else { continue };
            let sd = first_moment_prior(tree, b, self.rules.first_moment_tolerance, self.rules.first_moment_min_lever_m);
            if sd <= 0.0 {
                continue;
            }
            for (a, axis) in moments[&b].iter().enumerate() {
                let mut rows = BTreeMap::new();
                for (r, info) in self.rows.iter().enumerate().filter(|(r, _)| beyond[*r].contains(&b)) {
                    let used = &self.used[r];
                    let values: Vec<f64> = axis[info.dof].iter().zip(used).map(|(&v, &u)| if u { v } else { f64::NAN }).collect();
                    if values.iter().any(|v| v.is_finite() && v.abs() > 1e-12) {
                        rows.insert(r, values);
                    }
                }
                if !rows.is_empty() {
                    self.columns.push(Column { rows, size: Vec::new(), precision: samples_per_piece / (sd * sd) });
                    self.nuisance.insert(self.columns.len() - 1, (b, a, owner));
                }
            }
        }
    }

    /// The identified joints, with their residual effort under the model as written.
    #[must_use]
    pub fn rows(&self) -> &[RowInfo] {
        &self.rows
    }

    /// Per row and fold: whether the joint's RMS speed over the block's used samples reaches
    /// [`MOVING_FOLD_SHARE`] of its RMS speed over all of them.
    fn moving_folds(&self, sig: &Signals) -> Vec<Vec<bool>> {
        let k = self.rules.folds.max(2);
        self.rows
            .iter()
            .zip(&self.used)
            .map(|(row, used)| {
                let mut sum = vec![(0.0, 0usize); k];
                for i in (0..used.len()).filter(|&i| used[i]) {
                    let v = sig.q[row.dof][i][1];
                    if v.is_finite() {
                        let f = &mut sum[self.fold_of[i]];
                        f.0 += v * v;
                        f.1 += 1;
                    }
                }
                let (all, count) = sum.iter().fold((0.0, 0usize), |(a, n), &(s, c)| (a + s, n + c));
                let rms_all = (all / count.max(1) as f64).sqrt();
                sum.iter().map(|&(s, c)| c > 0 && (s / c as f64).sqrt() >= MOVING_FOLD_SHARE * rms_all).collect()
            })
            .collect()
    }

    /// Contiguous blocks of equal duration over the used samples.
    fn assign_folds(&self, sig: &Signals) -> Vec<usize> {
        let n = sig.time_s.len();
        let any: Vec<usize> = (0..n).filter(|&i| self.used.iter().any(|u| u[i])).collect();
        let (Some(&a), Some(&b)) = (any.first(), any.last()) else { return vec![0; n] };
        let (t0, t1) = (sig.time_s[a], sig.time_s[b]);
        let k = self.rules.folds.max(2);
        (0..n).map(|i| (((sig.time_s[i] - t0) / (t1 - t0).max(1e-12) * k as f64) as usize).min(k - 1)).collect()
    }
}

/// Whether joint j has a movable joint above or below it (an arm, a pendulum chain) rather than
/// hanging alone off a fixed body (a door, a drawer).
#[must_use]
pub fn in_serial_chain(model: &GapModel, j: usize) -> bool {
    let movable_below =
        model.subtree(j).iter().skip(1).any(|&l| model.parent_joint[l].is_some_and(|k| model.joints[k].kind != DofKind::Fixed));
    movable_below || model.moving_joint_of(model.joints[j].parent).is_some()
}

/// Median (the upper middle value) of the finite values; 0 when there are none.
#[must_use]
pub fn median(v: &[f64]) -> f64 {
    let mut x: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if x.is_empty() {
        return 0.0;
    }
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

/// Median step between successive time stamps, s (0 for fewer than two).
#[must_use]
pub fn median_step_s(time_s: &[f64]) -> f64 {
    median(&time_s.windows(2).map(|w| w[1] - w[0]).collect::<Vec<f64>>())
}

/// 1.4826 · MAD of the finite values.
#[must_use]
pub fn robust_scale(v: &[f64]) -> f64 {
    let med = median(v);
    let d: Vec<f64> = v.iter().filter(|x| x.is_finite()).map(|x| (x - med).abs()).collect();
    1.4826 * median(&d)
}

/// Per sample: whether it lies within `half_width_s` of a reversal of `speed` (its sign changes
/// between two finite samples, or it is exactly zero), the reversal placed midway between them.
#[must_use]
pub fn near_reversals(time_s: &[f64], speed: &[f64], half_width_s: f64) -> Vec<bool> {
    let finite: Vec<usize> = (0..speed.len().min(time_s.len())).filter(|&i| speed[i].is_finite()).collect();
    let mut turns: Vec<f64> = finite.iter().filter(|&&i| speed[i] == 0.0).map(|&i| time_s[i]).collect();
    turns.extend(finite.windows(2).filter(|w| speed[w[0]] * speed[w[1]] < 0.0).map(|w| 0.5 * (time_s[w[0]] + time_s[w[1]])));
    turns.sort_by(f64::total_cmp);
    // Both lists ascend: each sample looks at the nearest reversal at or after it and the one before.
    let mut next = 0;
    time_s
        .iter()
        .map(|&t| {
            while next < turns.len() && turns[next] < t {
                next += 1;
            }
            let after = turns.get(next).map_or(f64::INFINITY, |&z| z - t);
            let before = next.checked_sub(1).map_or(f64::INFINITY, |k| t - turns[k]);
            after.min(before) <= half_width_s
        })
        .collect()
}

/// Multipliers of a joint's RMS speed for the transition speeds tried (smooth Coulomb), each up
/// to [`SelectionRules::max_transition_speed`]. Beyond the RMS speed: real joints' friction is
/// smooth over 0.05-0.4 rad/s (the Panda's published law, 0.12-0.39 rad/s), as wide as a slow
/// excitation's speeds; at 0.3× at most, such friction came out as a sharper law plus viscous
/// damping, or damping alone. Steps of 1.4× at the wide end, where the law's shape shows over the
/// speeds recorded and a law between two steps leaves a misfit that damping would take up; and
/// no more than 1.8× from 0.03× up, for the same reason: with steps of 3× there, Drake's smooth
/// friction (0.05 rad/s on an iiwa's joints) was read at 0.5-1.8× its transition on half its
/// joints, with a false viscous damping beside it on eight.
/// Up to 3.4×, as far as the joint's fastest speed: a slow joint's friction can be smooth over
/// more than its RMS speed and still round off at its fastest (`MuJoCo`'s Panda under the
/// published law, its joint 5 at 0.11 rad/s RMS and 0.32 at most, smooth over 0.24: with the
/// grid ending at 1.2× it was read as viscous damping and a lighter part). A law smooth over more
/// than the joint's fastest speed is straight over every speed recorded, damping's shape, which
/// the viscous candidate is.
const TRANSITION_GRID: [f64; 14] = [0.002, 0.01, 0.03, 0.055, 0.1, 0.17, 0.3, 0.42, 0.6, 0.85, 1.2, 1.7, 2.4, 3.4];
/// Multipliers of the RMS speed for the Stribeck speeds tried.
const STRIBECK_GRID: [f64; 3] = [0.05, 0.15, 0.4];
/// Where a Stribeck law departs from its base law while the joint slides: from this many
/// transition speeds (the base law is at its full level there) to this many Stribeck speeds
/// (the excess is under 2 % of the break-away beyond).
const STRIBECK_ZONE: (f64, f64) = (3.0, 2.0);

/// Whether dof `d` slides one way with a smoothed speed inside `zone` (low, high; absolute)
/// over used samples (`ok`) for at least the equation filter's support at a stretch.
fn slides_within(sig: &Signals, d: usize, ok: &[bool], zone: (f64, f64)) -> bool {
    let span_s = sig.band.support_s();
    // Start time and direction of the current stretch.
    let mut start: Option<(f64, bool)> = None;
    for (i, &used) in ok.iter().enumerate() {
        let v = sig.q[d][i][1];
        let inside = used && (zone.0..=zone.1).contains(&v.abs());
        start = match start {
            Some((t0, forward)) if inside && (v > 0.0) == forward => {
                if sig.time_s[i] - t0 >= span_s {
                    return true;
                }
                Some((t0, forward))
            }
            _ if inside => Some((sig.time_s[i], v > 0.0)),
            _ => None,
        };
    }
    false
}

/// Shares of the travel from the closed end for the soft-close engage positions tried.
const ENGAGE_GRID: [f64; 5] = [0.1, 0.2, 0.35, 0.5, 0.7];

/// The candidates of one effort row and their columns, built apart from the other rows' (in
/// parallel) and then appended in row order ([`EffortProblem::build_candidates`]); a candidate's
/// column indices are local to its row's sink until then.
#[derive(Default)]
struct CandidateSink {
    columns: Vec<Column>,
    candidates: Vec<Candidate>,
}

impl CandidateSink {
    fn push_column(&mut self, row: usize, (values, size): (Vec<f64>, Vec<f64>)) -> usize {
        self.columns.push(Column { rows: BTreeMap::from([(row, values)]), size, precision: 0.0 });
        self.columns.len() - 1
    }

    fn push(&mut self, row: usize, kind: EffectKind, family: Family, hyper: Vec<f64>, asymmetric: bool, cols: Vec<(Vec<f64>, Vec<f64>)>) {
        let columns = cols.into_iter().map(|c| self.push_column(row, c)).collect();
        self.candidates.push(Candidate { row, kind, hyper, asymmetric, columns, family, unresolved: None });
    }
}

impl EffortProblem<'_> {
    /// The dry-friction candidates of row r (`ok`: its used samples; `v_rms`: its RMS speed):
    /// smooth Coulomb over a grid of transition speeds, the same by direction, Stribeck.
    ///
    /// Dry friction's law is a sharp function of the speed, so which speed it is evaluated on
    /// matters where the joint is slow. On the narrowly differentiated speed (like every other
    /// term) a sharp law keeps its shape through the filter on a joint that slides and turns;
    /// where the joint is stuck or creeping that speed's sign is noise and the filtered law is
    /// mush. On the smoothed speed the law is near zero at rest, which is what a stuck joint's
    /// friction is where little pushes it, but smeared over a reversal. Neither is right for
    /// every engine: Klamp't's door (ODE, friction and damping, stuck most of the time) was read
    /// as friction alone on the narrow speed and right on the smoothed one; the Panda in
    /// `MuJoCo`, whose friction holds a joint at its reversals, got a false armature on the
    /// smoothed one alone.
    /// So each law is a candidate both ways, one family: the held-out error picks the reading,
    /// and on a tie the narrow one, which comes first.
    ///
    /// A Stribeck law departs from its base law only at low speed, which an excited joint passes
    /// through where it turns; there dry friction that holds the joint for a moment (any level up
    /// to its own) looks like a break-away once filtered (`MuJoCo`'s friction loss on a `UR5e` named
    /// 1.5 N·m of Coulomb friction a Stribeck law breaking away at 2.3). So a Stribeck law is
    /// named only where the joint also slides at its low speeds for the filter's span at a
    /// stretch ([`slides_within`], [`STRIBECK_ZONE`]).
    fn push_dry_friction(&self, sink: &mut CandidateSink, r: usize, sig: &Signals, ok: &[bool], v_rms: f64) {
        let (d, n) = (self.rows[r].dof, sig.time_s.len());
        let dry = |smoothed: bool, f: &dyn Fn([f64; 3]) -> f64| -> (Vec<f64>, Vec<f64>) {
            let values = if smoothed { sig.motion_term(d, ok, f) } else { sig.term(d, ok, f) };
            (values, (0..n).map(|i| if ok[i] { f(sig.q[d][i]) } else { f64::NAN }).collect())
        };
        let vt = TRANSITION_GRID[1] * v_rms;
        let rotational = self.model.joints[self.rows[r].joint].kind.is_rotational();
        let unit = if rotational { "rad/s" } else { "m/s" };
        // The narrowest transition is kept on any joint, so that a law is always tried.
        let widest = if rotational { self.rules.max_transition_speed.0 } else { self.rules.max_transition_speed.1 };
        // Without its rests, the row keeps the transition it was given with them, and tries no
        // Stribeck law (its break-away lives in the rests too: [`super::rests`]).
        let held = self.rests.get(r).copied().flatten().map(|h| h.transition_speed);
        // Per Stribeck speed tried, why the recording cannot tell its law (either reading) from
        // Coulomb's.
        let stribeck_grid: &[f64] = if held.is_some() { &[] } else { &STRIBECK_GRID };
        let unresolved: Vec<Option<String>> = stribeck_grid
            .iter()
            .map(|&m| {
                let zone = (STRIBECK_ZONE.0 * vt, STRIBECK_ZONE.1 * m * v_rms);
                (!slides_within(sig, d, ok, zone)).then(|| {
                    format!(
                        "the joint never slides between {:.3} and {:.3} {unit} for {:.2} s at a stretch (the span the efforts \
                         are filtered over), only passes those speeds where it turns: a break-away there cannot be told from \
                         dry friction holding the joint while it turns",
                        zone.0,
                        zone.1,
                        sig.band.support_s()
                    )
                })
            })
            .collect();
        let speeds: Vec<f64> = held.map_or_else(
            || {
                // No wider than real joints' friction, nor than the joint's fastest speed.
                let fastest = (0..n).filter(|&i| ok[i]).map(|i| sig.q[d][i][1].abs()).fold(0.0, f64::max);
                let reach = widest.min(fastest);
                TRANSITION_GRID.iter().enumerate().filter(|&(k, &m)| k == 0 || m * v_rms <= reach).map(|(_, &m)| m * v_rms).collect()
            },
            |vs| vec![vs],
        );
        for smoothed in [false, true] {
            for &vs in &speeds {
                sink.push(r, EffectKind::CoulombFriction, Family::Friction, vec![vs], false, vec![dry(smoothed, &|x| (x[1] / vs).tanh())]);
                let pos = dry(smoothed, &|x| if x[1] > 0.0 { (x[1] / vs).tanh() } else { 0.0 });
                let neg = dry(smoothed, &|x| if x[1] < 0.0 { (x[1] / vs).tanh() } else { 0.0 });
                sink.push(r, EffectKind::CoulombFriction, Family::Friction, vec![vs], true, vec![pos, neg]);
            }
            for (m, why) in stribeck_grid.iter().zip(&unresolved) {
                let ss = m * v_rms;
                let base = dry(smoothed, &|x| (x[1] / vt).tanh());
                let extra = dry(smoothed, &|x| (-(x[1] / ss).powi(2)).exp() * (x[1] / vt).tanh());
                sink.push(r, EffectKind::StribeckFriction, Family::Friction, vec![ss], false, vec![base, extra]);
                if let Some(last) = sink.candidates.last_mut() {
                    last.unresolved.clone_from(why);
                }
            }
        }
    }

    /// Every candidate term of every row, with its regressor columns: each row's built apart
    /// (in parallel), then appended in row order, so that the columns' and candidates' order is
    /// the rows' whatever the threads do.
    fn build_candidates(&mut self, sig: &Signals, me: &ModelEfforts, part_of: &[Vec<usize>], gravity_dir: DVec3) {
        let sinks: Vec<CandidateSink> =
            (0..self.rows.len()).into_par_iter().map(|r| self.row_candidates(r, sig, me, part_of, gravity_dir)).collect();
        for sink in sinks {
            let offset = self.columns.len();
            self.columns.extend(sink.columns);
            self.candidates.extend(sink.candidates.into_iter().map(|mut c| {
                c.columns.iter_mut().for_each(|col| *col += offset);
                c
            }));
        }
    }

    /// The candidate terms of row r, with their regressor columns.
    fn row_candidates(&self, r: usize, sig: &Signals, me: &ModelEfforts, part_of: &[Vec<usize>], gravity_dir: DVec3) -> CandidateSink {
        let mut sink = CandidateSink::default();
        let n = sig.time_s.len();
        let (j, d) = (self.rows[r].joint, self.rows[r].dof);
        let joint = &self.model.joints[j];
        let chain = in_serial_chain(self.model, j);
        let ok = &self.used[r];
        let col = |f: &dyn Fn([f64; 3]) -> f64| -> (Vec<f64>, Vec<f64>) {
            (sig.term(d, ok, f), (0..n).map(|i| if ok[i] { f(sig.q[d][i]) } else { f64::NAN }).collect())
        };
        let v_rms = rms((0..n).filter(|&i| ok[i]).map(|i| sig.q[d][i][1])).max(1e-6);
        let qs: Vec<f64> = (0..n).filter(|&i| ok[i]).map(|i| sig.q[d][i][0]).collect();
        let (lo, hi) = qs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| (a.min(q), b.max(q)));
        self.push_dry_friction(&mut sink, r, sig, ok, v_rms);
        sink.push(r, EffectKind::ViscousDamping, Family::Viscous, Vec::new(), false, vec![col(&|x| x[1])]);
        sink.push(r, EffectKind::EffortOffset, Family::Constant, Vec::new(), false, vec![col(&|_| -1.0)]);
        sink.push(r, EffectKind::Spring, Family::Constant, Vec::new(), false, vec![col(&|x| x[0]), col(&|_| -1.0)]);
        // A motor's rotor is the likelier extra inertia of a joint in an actuated chain, a
        // heavier part that of a single pushed joint: when the two cannot be told apart
        // (gravity does no work on the joint), the earlier candidate wins the tie.
        // (The heavier part's column comes first either way.)
        let mass = self.mass_candidate(&mut sink, r, me, part_of, n);
        if chain {
            sink.push(r, EffectKind::Armature, Family::Inertia, Vec::new(), false, vec![col(&|x| x[2])]);
            sink.candidates.extend(mass);
        } else {
            sink.candidates.extend(mass);
            sink.push(r, EffectKind::Armature, Family::Inertia, Vec::new(), false, vec![col(&|x| x[2])]);
        }
        // A tilted axis is a property of a joint alone on its body; in a chain the sin law of
        // its own angle does not hold.
        if joint.kind.is_rotational() && !chain && tilt_applies(self.model, j, gravity_dir) {
            sink.push(r, EffectKind::GravityTilt, Family::Tilt, Vec::new(), false, vec![col(&|x| x[0].sin()), col(&|x| -x[0].cos())]);
        }
        self.push_base_tilt(&mut sink, r, me, n);
        if joint.kind != DofKind::Continuous && hi > lo {
            let closed = joint.lower.unwrap_or(0.0);
            let far = if (hi - closed).abs() >= (lo - closed).abs() { hi } else { lo };
            for frac in ENGAGE_GRID {
                let engage = closed + frac * (far - closed);
                let inside = move |q: f64| (q - closed) * (engage - closed) >= 0.0 && (q - closed).abs() <= (engage - closed).abs();
                let c = col(&|x| if inside(x[0]) { x[1] } else { 0.0 });
                sink.push(r, EffectKind::SoftClose, Family::SoftClose, vec![engage], false, vec![c]);
            }
        }
        sink
    }

    /// The base-tilt candidate of row r where it is the chain's base joint ([`super::tilt`]): two
    /// columns, the efforts of gravity along two horizontal directions on every identified joint
    /// (a tilted base loads them all). Its hyper-parameters are the two directions (world frame).
    fn push_base_tilt(&self, sink: &mut CandidateSink, r: usize, me: &ModelEfforts, n: usize) {
        let Some(bt) = me.base_tilt.as_ref().filter(|bt| bt.row == r) else { return };
        let d = self.rows[r].dof;
        let made: Vec<Column> = (0..2)
            .map(|k| {
                let rows = self.rows_loaded(n, |d, i| bt.filtered[k][d][i]);
                let size = (0..n).map(|i| if self.used[r][i] { bt.size[k][d][i] } else { f64::NAN }).collect();
                Column { rows, size, precision: 0.0 }
            })
            .collect();
        if !made.iter().all(|c| c.rows.contains_key(&r)) {
            return;
        }
        let mut columns = Vec::new();
        for column in made {
            sink.columns.push(column);
            columns.push(sink.columns.len() - 1);
        }
        let hyper = bt.directions.iter().flat_map(DVec3::to_array).collect();
        sink.candidates.push(Candidate {
            row: r,
            kind: EffectKind::GravityTilt,
            hyper,
            asymmetric: false,
            columns,
            family: Family::Tilt,
            unresolved: None,
        });
    }

    /// A column over every row: `value(dof, sample)` on each row's used samples (NaN elsewhere),
    /// kept on the rows it loads (a finite value beyond 1e-12 somewhere).
    fn rows_loaded(&self, n: usize, value: impl Fn(usize, usize) -> f64) -> BTreeMap<usize, Vec<f64>> {
        let mut rows = BTreeMap::new();
        for (rr, info) in self.rows.iter().enumerate() {
            let values: Vec<f64> = (0..n).map(|i| if self.used[rr][i] { value(info.dof, i) } else { f64::NAN }).collect();
            if values.iter().any(|v| v.is_finite() && v.abs() > 1e-12) {
                rows.insert(rr, values);
            }
        }
        rows
    }

    /// The heavier-part candidate of row r: the effort of its moving part's inertia on every
    /// identified joint (a heavier forearm loads the shoulder too). Its column goes into `sink`;
    /// the candidate is returned for the caller to place.
    fn mass_candidate(&self, sink: &mut CandidateSink, r: usize, me: &ModelEfforts, part_of: &[Vec<usize>], n: usize) -> Option<Candidate> {
        if part_of[r].is_empty() {
            return None;
        }
        let rows = self.rows_loaded(n, |d, i| part_of[r].iter().map(|b| me.filtered.body_tau[b][d][i]).sum());
        rows.get(&r)?;
        let d = self.rows[r].dof;
        let size =
            (0..n).map(|i| if self.used[r][i] { part_of[r].iter().map(|b| me.size.body_tau[b][d][i]).sum() } else { f64::NAN }).collect();
        sink.columns.push(Column { rows, size, precision: 0.0 });
        Some(Candidate {
            row: r,
            kind: EffectKind::MassScale,
            hyper: Vec::new(),
            asymmetric: false,
            columns: vec![sink.columns.len() - 1],
            family: Family::Mass,
            unresolved: None,
        })
    }

    /// Per row (in parallel), the Gram matrices of its columns fold by fold.
    fn build_grams(&mut self) {
        let k = self.rules.folds.max(2);
        self.grams = (0..self.rows.len()).into_par_iter().map(|r| self.row_gram(r, k)).collect();
    }

    /// Row r's weighted sums over each of the `k` folds' used samples (those with a finite
    /// residual), taken in sample order: of each pair of its columns (a value that is not finite
    /// counts as zero), of each column times the residual, of the residual squared; and the
    /// samples' count. Each sum is a dot product over the fold's samples gathered apart, four
    /// pairs at a time, so that it reads memory in order and runs four sums side by side; each
    /// adds the same products in the same order as a pass sample by sample would.
    fn row_gram(&self, r: usize, k: usize) -> RowGram {
        let columns: Vec<usize> = (0..self.columns.len()).filter(|&c| self.columns[c].rows.contains_key(&r)).collect();
        let m = columns.len();
        let values: Vec<&Vec<f64>> = columns.iter().map(|&c| &self.columns[c].rows[&r]).collect();
        let (w, residual) = (self.weights[r], &self.rows[r].residual);
        let mut samples = vec![Vec::new(); k];
        for (i, &res) in residual.iter().enumerate() {
            if self.used[r][i] && res.is_finite() {
                samples[self.fold_of[i]].push(i);
            }
        }
        let folds = samples
            .iter()
            .map(|idx| {
                let phi: Vec<Vec<f64>> =
                    values.iter().map(|v| idx.iter().map(|&i| if v[i].is_finite() { v[i] } else { 0.0 }).collect()).collect();
                let res: Vec<f64> = idx.iter().map(|&i| residual[i]).collect();
                let mut gram = vec![0.0; m * m];
                let mut cr = vec![0.0; m];
                for a in 0..m {
                    let wa: Vec<f64> = phi[a].iter().map(|&p| w * p).collect();
                    cr[a] = ordered_dot(&wa, &res);
                    let row = &mut gram[a * m..(a + 1) * m];
                    let mut b = a;
                    while b + 4 <= m {
                        row[b..b + 4].copy_from_slice(&ordered_dot4(&wa, [&phi[b], &phi[b + 1], &phi[b + 2], &phi[b + 3]]));
                        b += 4;
                    }
                    for (x, p) in row[b..].iter_mut().zip(&phi[b..]) {
                        *x = ordered_dot(&wa, p);
                    }
                }
                for a in 0..m {
                    for b in 0..a {
                        gram[a * m + b] = gram[b * m + a];
                    }
                }
                let rr = res.iter().fold(0.0, |s, &x| s + w * x * x);
                (gram, cr, rr, idx.len())
            })
            .collect();
        RowGram { columns, folds }
    }
}

/// Σ x·y, added in order.
fn ordered_dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).fold(0.0, |s, (a, b)| s + a * b)
}

/// Four [`ordered_dot`]s of `x` at once, each added in order.
fn ordered_dot4(x: &[f64], y: [&[f64]; 4]) -> [f64; 4] {
    let mut s = [0.0; 4];
    for ((((&a, &b0), &b1), &b2), &b3) in x.iter().zip(y[0]).zip(y[1]).zip(y[2]).zip(y[3]) {
        s[0] += a * b0;
        s[1] += a * b1;
        s[2] += a * b2;
        s[3] += a * b3;
    }
    s
}

/// A model (a set of candidates) evaluated by cross-validation.
#[derive(Debug, Clone)]
struct Evaluation {
    /// Held-out weighted squared error per row and fold.
    fold_sse: Vec<Vec<f64>>,
    /// Parameters fitted on all folds, per column id.
    theta: Params,
    /// Parameters fitted without each fold (jackknife), per column id.
    theta_without: Vec<Params>,
}

impl Evaluation {
    fn row_sse(&self, r: usize) -> f64 {
        self.fold_sse[r].iter().sum()
    }

    /// Held-out squared error summed over `rows`, in their order.
    fn sse_over(&self, rows: &[usize]) -> f64 {
        rows.iter().map(|&r| self.row_sse(r)).sum()
    }

    /// Held-out squared error summed over every row.
    fn total_sse(&self) -> f64 {
        (0..self.fold_sse.len()).map(|r| self.row_sse(r)).sum()
    }
}

impl EffortProblem<'_> {
    /// The columns of the candidates `set` and the model's own error's, sorted.
    fn columns_of(&self, set: &[usize]) -> Vec<usize> {
        let mut cols: Vec<usize> =
            set.iter().flat_map(|&c| self.candidates[c].columns.iter().copied()).chain(self.nuisance.keys().copied()).collect();
        cols.sort_unstable();
        cols.dedup();
        cols
    }

    /// The columns `cols` (sorted) split into the independent blocks of their normal equations:
    /// two columns meet in a solve only where they share an effort row, directly or through
    /// other columns (a heavier part's column spans the joints its weight loads). Each block keeps
    /// its columns' order; blocks come in the order of their first column. Solving the blocks
    /// apart gives the joint solve's numbers exactly (Cholesky adds exact zeros across blocks),
    /// and a block that a candidate does not touch is fitted once ([`Self::fit_block`]'s cache).
    fn blocks_of(&self, cols: &[usize]) -> Vec<Vec<usize>> {
        fn root(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        let mut parent: Vec<usize> = (0..self.rows.len()).collect();
        for &c in cols {
            let mut rows = self.columns[c].rows.keys();
            if let Some(&first) = rows.next() {
                let a = root(&mut parent, first);
                for &r in rows {
                    let b = root(&mut parent, r);
                    parent[b] = a;
                }
            }
        }
        let mut blocks: Vec<(usize, Vec<usize>)> = Vec::new();
        for &c in cols {
            let Some(&r) = self.columns[c].rows.keys().next() else { continue };
            let top = root(&mut parent, r);
            match blocks.iter_mut().find(|(x, _)| *x == top) {
                Some((_, v)) => v.push(c),
                None => blocks.push((top, vec![c])),
            }
        }
        blocks.into_iter().map(|(_, v)| v).collect()
    }

    /// Per effort row, the pairs (index among the row's Gram columns, index in `cols`) of the
    /// columns of `cols` (sorted) that the row holds, in the row's column order.
    fn local_maps(&self, cols: &[usize]) -> Vec<Vec<(usize, usize)>> {
        let mut maps = vec![Vec::new(); self.grams.len()];
        for (gi, &c) in cols.iter().enumerate() {
            for &(r, li) in self.sums.rows_of.get(c).map_or(&[][..], Vec::as_slice) {
                maps[r].push((li, gi));
            }
        }
        maps
    }

    /// Weighted least squares of the columns `cols` (sorted) with their normal equations
    /// `(a, b)` ([`NormalSums::normal_equations`]).
    fn solve(&self, cols: &[usize], (mut a, b): (Vec<f64>, Vec<f64>)) -> Vec<f64> {
        let p = cols.len();
        self.ridge(cols, &mut a);
        solve_spd(&a, &b, p).unwrap_or_else(|| vec![0.0; p])
    }

    /// The normal equations `a` of the columns `cols` with each diagonal entry [`Self::ridged`].
    fn ridge(&self, cols: &[usize], a: &mut [f64]) {
        let p = cols.len();
        for (i, &c) in cols.iter().enumerate() {
            a[i * p + i] = self.ridged(c, a[i * p + i]);
        }
    }

    /// Column c's diagonal entry `d` of the normal equations with its ridge: a whisper keeps
    /// exactly collinear columns (look-alike kinds) solvable; the model's own error has its prior.
    fn ridged(&self, c: usize, d: f64) -> f64 {
        d + (1e-9 * d + 1e-300 + self.columns[c].precision)
    }

    /// One block of columns ([`Self::blocks_of`]) fitted on every fold left out in turn and on
    /// all, with the held-out error of each row it touches; remembered, since forward selection
    /// asks for the same blocks over and over (every candidate of one joint beside the others'
    /// terms).
    fn fit_block(&self, cols: &[usize]) -> Arc<BlockFit> {
        remembered(&self.block_fits, cols.to_vec(), || Arc::new(self.fit_block_afresh(cols)))
    }

    /// [`Self::fit_block`] without the cache.
    fn fit_block_afresh(&self, cols: &[usize]) -> BlockFit {
        // One system per fold left out, then the one over all folds.
        let thetas = self.sums.normal_equations(cols).into_iter().map(|system| self.solve(cols, system)).collect();
        self.block_fit_from(cols, thetas, None)
    }

    /// The block `cols` under its parameters per system (`thetas`: every fold left out, then
    /// all), with the held-out error of each row it touches; with `only`, of those rows alone
    /// and without the parameters fitted without each fold (what weighing a candidate needs).
    fn block_fit_from(&self, cols: &[usize], thetas: Vec<Vec<f64>>, only: Option<&[usize]>) -> BlockFit {
        let k = self.rules.folds.max(2);
        let maps = self.local_maps(cols);
        let touched: Vec<usize> =
            (0..self.rows.len()).filter(|&r| !maps[r].is_empty() && only.is_none_or(|rows| rows.contains(&r))).collect();
        let mut fold_sse = vec![vec![0.0; k]; touched.len()];
        let mut theta_without = Vec::with_capacity(k);
        let mut systems = thetas.into_iter();
        for (fold, theta) in (0..k).zip(systems.by_ref()) {
            for (row_sse, &r) in fold_sse.iter_mut().zip(&touched) {
                let g = &self.grams[r];
                let (gram, cr, rr, _) = &g.folds[fold];
                let m = g.columns.len();
                // The row's parameters beside their Gram indices, then r·r − 2 θ·c + θᵀ G θ in
                // the order of the row's columns.
                let local: Vec<(usize, f64)> = maps[r].iter().map(|&(la, ga)| (la, theta[ga])).collect();
                let mut sse = *rr;
                for &(la, ta) in &local {
                    sse -= 2.0 * ta * cr[la];
                    let gram_row = &gram[la * m..(la + 1) * m];
                    for &(lb, tb) in &local {
                        sse += ta * tb * gram_row[lb];
                    }
                }
                row_sse[fold] = sse.max(0.0);
            }
            if only.is_none() {
                theta_without.push(theta);
            }
        }
        let theta = systems.next().unwrap_or_else(|| vec![0.0; cols.len()]);
        BlockFit { rows: touched, fold_sse, theta, theta_without }
    }

    /// The block `base` (columns sorted) with its normal equations factored, system by system;
    /// None where one is not positive definite. Remembered: a round of forward selection weighs
    /// every candidate beside the same chosen terms.
    fn factored(&self, base: &[usize]) -> Option<Arc<Factored>> {
        remembered(&self.factors, base.to_vec(), || {
            let p = base.len();
            let systems = self
                .sums
                .normal_equations(base)
                .into_iter()
                .map(|(mut a, mut b)| {
                    self.ridge(base, &mut a);
                    let l = cholesky(&a, p)?;
                    forward_substitute(&l, &mut b, p);
                    Some((l, b))
                })
                .collect::<Option<Vec<_>>>()?;
            Some(Arc::new(Factored { systems }))
        })
    }

    /// The block `cols` (sorted) fitted by extending the factors of its columns other than
    /// `new` (`base`; both sorted), system by system. With B the base's columns and C the new
    /// ones: `L_B W = A_BC`, the Schur complement `A_CC − WᵀW = L_S L_Sᵀ`, then
    /// `L_S L_Sᵀ θ_C = b_C − Wᵀ z` and `L_Bᵀ θ_B = z − W θ_C` with `z = L_B⁻¹ b_B`: the least
    /// squares of [`Self::fit_block_afresh`] (to rounding) at q·p² a system instead of p³.
    /// Forward selection weighs every candidate (q columns) beside the same chosen terms and the
    /// model's own accuracy (p columns). The held-out error of the rows `rows` alone, and no
    /// parameters fitted without each fold ([`Self::block_fit_from`]). None where the extension
    /// is not positive definite. Remembered by (base, new, rows).
    fn bordered_fit(&self, cols: &[usize], base: &[usize], new: &[usize], rows: &[usize]) -> Option<Arc<BlockFit>> {
        remembered(&self.bordered_fits, (base.to_vec(), new.to_vec(), rows.to_vec()), || {
            let factors = self.factored(base)?;
            let thetas = factors
                .systems
                .iter()
                .enumerate()
                .map(|(s, (l, z))| self.bordered_solve(s, l, z, base, new).map(|(theta_b, theta_c)| merged(cols, base, &theta_b, &theta_c)))
                .collect::<Option<Vec<_>>>()?;
            Some(Arc::new(self.block_fit_from(cols, thetas, Some(rows))))
        })
    }

    /// System s of [`Self::bordered_fit`]: (`θ_B`, `θ_C`) from the base's factor `l` and `z`.
    fn bordered_solve(&self, s: usize, l: &[f64], z: &[f64], base: &[usize], new: &[usize]) -> Option<(Vec<f64>, Vec<f64>)> {
        let (p, q) = (base.len(), new.len());
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        // W, one new column at a time.
        let w: Vec<Vec<f64>> = new
            .iter()
            .map(|&c| {
                let mut col: Vec<f64> = base.iter().map(|&b| self.sums.entry(s, b, c)).collect();
                forward_substitute(l, &mut col, p);
                col
            })
            .collect();
        let mut schur = vec![0.0; q * q];
        for i in 0..q {
            for j in 0..=i {
                let a = self.sums.entry(s, new[i], new[j]);
                let v = if i == j { self.ridged(new[i], a) } else { a } - dot(&w[i], &w[j]);
                schur[i * q + j] = v;
                schur[j * q + i] = v;
            }
        }
        let ls = cholesky(&schur, q)?;
        let mut theta_c: Vec<f64> = new.iter().zip(&w).map(|(&c, wi)| self.sums.rhs_entry(s, c) - dot(wi, z)).collect();
        forward_substitute(&ls, &mut theta_c, q);
        back_substitute(&ls, &mut theta_c, q);
        let mut theta_b = z.to_vec();
        for (wi, &t) in w.iter().zip(&theta_c) {
            for (v, x) in theta_b.iter_mut().zip(wi) {
                *v -= x * t;
            }
        }
        back_substitute(l, &mut theta_b, p);
        Some((theta_b, theta_c))
    }

    fn evaluate(&self, set: &[usize]) -> Evaluation {
        self.evaluate_by(set, true, |block| self.fit_block(block))
    }

    /// [`Self::evaluate`] of `set` = `chosen` with candidate c ([`Self::with`]) for weighing c
    /// on its rows `rows` ([`Self::rows_of`], [`Self::verdict`]): each block that holds columns of c's that the rest of the set lacks
    /// is fitted by extending the rest's factors ([`Self::bordered_fit`]), the others as
    /// `evaluate` does. What weighing needs only: the held-out error of c's rows (the other
    /// rows of an extended block keep the model's own, unread) and the parameters fitted on all
    /// folds (none fitted without each fold). The sets forward selection keeps are fitted afresh
    /// ([`Self::best_step`]), so a kept set's numbers never depend on the path that reached it.
    fn evaluate_beside(&self, set: &[usize], c: usize, rows: &[usize]) -> Evaluation {
        let rest: Vec<usize> = set.iter().copied().filter(|&x| x != c).collect();
        let rest_cols = self.columns_of(&rest);
        let mut new: Vec<usize> = self.candidates[c].columns.iter().copied().filter(|col| rest_cols.binary_search(col).is_err()).collect();
        new.sort_unstable();
        new.dedup();
        self.evaluate_by(set, false, |block| {
            let (block_new, base): (Vec<usize>, Vec<usize>) = block.iter().partition(|col| new.binary_search(col).is_ok());
            if block_new.is_empty() || base.is_empty() {
                return self.fit_block(block);
            }
            self.bordered_fit(block, &base, &block_new, rows).unwrap_or_else(|| self.fit_block(block))
        })
    }

    /// The held-out errors and parameters of `set`, each of its blocks fitted by `fit`; with
    /// `jackknife`, the parameters fitted without each fold too.
    fn evaluate_by(&self, set: &[usize], jackknife: bool, fit: impl Fn(&[usize]) -> Arc<BlockFit>) -> Evaluation {
        let cols = self.columns_of(set);
        let k = self.rules.folds.max(2);
        // A row no column touches keeps the residual of the model as written.
        let mut fold_sse: Vec<Vec<f64>> = self.grams.iter().map(|g| g.folds.iter().map(|f| f.2.max(0.0)).collect()).collect();
        let mut theta = Params::zeros(self.columns.len());
        let mut theta_without = vec![theta.clone(); if jackknife { k } else { 0 }];
        for block in self.blocks_of(&cols) {
            let fit = fit(&block);
            for (&r, sse) in fit.rows.iter().zip(&fit.fold_sse) {
                fold_sse[r].clone_from(sse);
            }
            theta.set(&block, &fit.theta);
            for (all, without) in theta_without.iter_mut().zip(&fit.theta_without) {
                all.set(&block, without);
            }
        }
        Evaluation { fold_sse, theta, theta_without }
    }

    /// The rows where `set` holds dry friction beside an inertia (an armature, a heavier part)
    /// and at least [`MIN_AWAY_SHARE`] of the used samples lie away from the joint's reversals:
    /// their reading is taken there ([`Self::fit_away_from_reversals`],
    /// [`Self::inertia_only_at_reversals`]); a joint that turns more often keeps its reading.
    fn rows_turning_round(&self, set: &[usize]) -> Vec<usize> {
        let has = |r: usize, f: &dyn Fn(&Candidate) -> bool| set.iter().any(|&x| self.candidates[x].row == r && f(&self.candidates[x]));
        (0..self.rows.len())
            .filter(|&r| self.reversals[r].is_some() && has(r, &|c| c.family == Family::Friction) && has(r, &|c| c.kind.adds_inertia()))
            .collect()
    }

    /// The parameters of `set` fitted with the samples of the rows `rows` that draw on a
    /// reversal of their joint ([`Self::reversals`]) left out, the other rows keeping all theirs:
    /// each block's normal equations less those samples' products, on all folds and without
    /// each fold in turn (the jackknife's).
    fn fit_away_from_reversals(&self, set: &[usize], rows: &[usize]) -> (Params, Vec<Params>) {
        let k = self.rules.folds.max(2);
        let mut theta = Params::zeros(self.columns.len());
        let mut theta_without = vec![theta.clone(); k];
        for block in self.blocks_of(&self.columns_of(set)) {
            let touched: Vec<usize> =
                rows.iter().copied().filter(|r| block.iter().any(|c| self.columns[*c].rows.contains_key(r))).collect();
            let thetas: Vec<Vec<f64>> = if touched.is_empty() {
                let fit = self.fit_block(&block);
                fit.theta_without.iter().chain(std::iter::once(&fit.theta)).cloned().collect()
            } else {
                let (removed_a, removed_b) = self.reversal_sums(&block, &touched);
                self.sums
                    .normal_equations(&block)
                    .into_iter()
                    .enumerate()
                    .map(|(skip, (mut a, mut b))| {
                        // System `skip` holds every fold but `skip` (the last: all of them).
                        for f in (0..k).filter(|&f| f != skip) {
                            a.iter_mut().zip(&removed_a[f]).for_each(|(x, y)| *x -= y);
                            b.iter_mut().zip(&removed_b[f]).for_each(|(x, y)| *x -= y);
                        }
                        self.solve(&block, (a, b))
                    })
                    .collect()
            };
            if let Some((all, without)) = thetas.split_last() {
                theta.set(&block, all);
                for (t, w) in theta_without.iter_mut().zip(without) {
                    t.set(&block, w);
                }
            }
        }
        (theta, theta_without)
    }

    /// Per fold, the weighted products (p × p row-major, and p) of the columns `block` over the
    /// used samples of the rows `rows` that draw on a reversal of their joint.
    fn reversal_sums(&self, block: &[usize], rows: &[usize]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let (k, p) = (self.rules.folds.max(2), block.len());
        let mut a = vec![vec![0.0; p * p]; k];
        let mut b = vec![vec![0.0; p]; k];
        for &r in rows {
            let (w, residual) = (self.weights[r], &self.rows[r].residual);
            let values: Vec<Option<&Vec<f64>>> = block.iter().map(|col| self.columns[*col].rows.get(&r)).collect();
            let Some(near) = &self.reversals[r] else { continue };
            for i in (0..residual.len()).filter(|&i| self.used[r][i] && residual[i].is_finite() && near[i]) {
                let x: Vec<f64> = values.iter().map(|v| v.map_or(0.0, |v| if v[i].is_finite() { v[i] } else { 0.0 })).collect();
                let f = self.fold_of[i];
                for (j, &xj) in x.iter().enumerate() {
                    b[f][j] += w * xj * residual[i];
                    for (l, &xl) in x.iter().enumerate() {
                        a[f][j * p + l] += w * xj * xl;
                    }
                }
            }
        }
        (a, b)
    }

    /// Rows a candidate is judged on: those whose fit it changes, but for a chain's base tilt its
    /// base joint's row alone. A tilt's signature is the gravity effort it puts on the vertical
    /// base joint, which the level model has none of and no error of its first moments can make
    /// (gravity has no moment about a vertical axis); on the joints beyond it looks like those
    /// errors, and judged there too a real Panda's 0.5° "tilt" took in part of its shoulder's
    /// friction (which then read as damping). It is still fitted on every joint it loads, and may
    /// not enter where it raises the held-out error summed over them all.
    fn rows_of(&self, c: usize) -> Vec<usize> {
        if self.candidates[c].is_base_tilt() {
            return vec![self.candidates[c].row];
        }
        self.candidates[c]
            .columns
            .iter()
            .flat_map(|&col| self.columns[col].rows.keys().copied())
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect()
    }

    /// RMS effort of candidate c's term on its own row under `theta`, in the motion's description.
    fn term_rms(&self, c: usize, theta: &Params) -> f64 {
        self.change_rms(c, theta, None)
    }

    /// Candidate c's term under `theta` in the motion's description: its columns' values, each
    /// with its parameter.
    fn term_parts<'s>(&'s self, c: usize, theta: &Params) -> Vec<(f64, &'s [f64])> {
        self.candidates[c].columns.iter().map(|col| (theta.get(*col), self.columns[*col].size.as_slice())).collect()
    }

    /// RMS of what candidate c under `theta` changes on its row: its whole term, or, where it
    /// replaces a member of its family (`replaced`, under `theta_replaced`), the difference
    /// (a Stribeck law in place of a Coulomb one changes only the break-away).
    /// Remembered by the parameters' bits: forward selection asks for the same terms under the
    /// same fits round after round (a joint's candidates while another joint's term enters).
    fn change_rms(&self, c: usize, theta: &Params, replaced: Option<(usize, &Params)>) -> f64 {
        let row = self.candidates[c].row;
        let n = self.rows[row].residual.len();
        let at = |parts: &[(f64, &[f64])], i: usize| parts.iter().map(|(k, v)| k * v[i]).sum::<f64>();
        let mine = self.term_parts(c, theta);
        let other = replaced.map(|(r, t)| (r, self.term_parts(r, t)));
        let bits = |parts: &[(f64, &[f64])]| parts.iter().map(|(k, _)| k.to_bits()).collect::<Vec<u64>>();
        let key = (c, bits(&mine), other.as_ref().map(|(r, o)| (*r, bits(o))));
        remembered(&self.change_sizes, key, || {
            rms((0..n).filter(|&i| self.used[row][i]).map(|i| at(&mine, i) - other.as_ref().map_or(0.0, |(_, o)| at(o, i))))
        })
    }

    /// The member of c's family on c's joint in `set`, other than c.
    fn family_member(&self, set: &[usize], c: usize) -> Option<usize> {
        let cand = &self.candidates[c];
        set.iter().copied().find(|&x| x != c && self.candidates[x].row == cand.row && self.candidates[x].family == cand.family)
    }
}

/// The rows of two terms together, ascending and each once.
fn rows_of_both(a: &[usize], b: &[usize]) -> Vec<usize> {
    let mut rows: Vec<usize> = a.iter().chain(b).copied().collect();
    rows.sort_unstable();
    rows.dedup();
    rows
}

/// The jackknife standard deviation of an estimate from its leave-one-fold-out values (`folds`
/// of them; non-finite ones skipped).
fn jackknife_sd(values: &[f64], folds: usize) -> f64 {
    let vals: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let mean = vals.iter().sum::<f64>() / vals.len().max(1) as f64;
    let k = folds as f64;
    ((k - 1.0) / k * vals.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt()
}

/// A candidate put into a set of terms ([`EffortProblem::best_in_place`]).
struct InPlace {
    candidate: usize,
    /// The set with it.
    set: Vec<usize>,
    fit: Evaluation,
    /// Held-out squared error of its joint under `fit`.
    sse: f64,
}

/// Fewest held-out samples for a fold to count in the fold share.
const MIN_FOLD_SAMPLES: usize = 10;

/// Least share of a row's used samples that must lie away from its joint's reversals for an
/// inertia beside dry friction to be judged there ([`EffortProblem::inertia_only_at_reversals`]);
/// a joint that turns more often keeps its reading.
const MIN_AWAY_SHARE: f64 = 0.1;

/// Largest relative rise of the held-out error at which a rotor's inertia and a heavier part
/// count as the same explanation ([`EffortProblem::look_alike`]).
pub const LOOK_ALIKE_SSE_SHARE: f64 = 0.01;

/// How a candidate fared against the current model.
#[derive(Debug, Clone, Copy)]
struct Verdict {
    /// Relative cut of the held-out error on the rows it touches.
    gain: f64,
    /// Share of the folds where it lowered the held-out error.
    fold_share: f64,
    /// Its RMS effort over the joint's RMS effort.
    effort_share: f64,
    /// For a term that depends on the position alone, its RMS effort over the model's RMS
    /// gravity effort at the joint (infinite for other terms and where gravity does no work).
    static_share: f64,
    /// For an armature, its RMS effort over the model's RMS inertial effort at the joint; for a
    /// heavier part, over the model's whole RMS effort there (infinite for other terms and where
    /// the model needs none): [`SelectionRules::min_inertial_load_share`].
    inertial_share: f64,
    /// Its fitted parameters are physical.
    plausible: bool,
}

trait NanOrNonNegative {
    fn nan_or_nonneg(self) -> bool;
}

impl NanOrNonNegative for f64 {
    fn nan_or_nonneg(self) -> bool {
        self.is_nan() || self >= 0.0
    }
}

impl EffortProblem<'_> {
    /// `set` with `c` added, replacing the member of c's family on c's joint.
    fn with(&self, set: &[usize], c: usize) -> Vec<usize> {
        let cand = &self.candidates[c];
        let mut out: Vec<usize> =
            set.iter().copied().filter(|&x| !(self.candidates[x].row == cand.row && self.candidates[x].family == cand.family)).collect();
        out.push(c);
        out
    }

    /// Compares `after` (with candidate c) with `before` on the rows `rows`; `replaced` is the
    /// member of c's family that c replaces in `before`, if any.
    fn verdict(&self, before: &Evaluation, after: &Evaluation, rows: &[usize], c: usize, replaced: Option<usize>) -> Verdict {
        let (gain, fold_share) = self.held_out_cut(before, after, rows, c);
        let row = self.candidates[c].row;
        let size = self.change_rms(c, &after.theta, replaced.map(|r| (r, &before.theta)));
        let gravity_rms = self.rows[row].gravity_rms;
        Verdict {
            gain,
            fold_share,
            effort_share: size / self.rows[row].effort_rms.max(1e-12),
            static_share: if self.candidates[c].kind.depends_on_position_alone() && gravity_rms > 0.0 {
                size / gravity_rms
            } else {
                f64::INFINITY
            },
            inertial_share: self.inertial_share(c, size),
            plausible: self.plausible(c, &after.theta),
        }
    }

    /// Whether a held-out cut of `gain` shared by `fold_share` of the folds is enough to enter.
    fn cut_passes(&self, gain: f64, fold_share: f64) -> bool {
        gain >= self.rules.min_cv_gain && fold_share >= self.rules.min_fold_share
    }

    /// [`Verdict::gain`] and [`Verdict::fold_share`] of `after` against `before`.
    fn held_out_cut(&self, before: &Evaluation, after: &Evaluation, rows: &[usize], c: usize) -> (f64, f64) {
        let k = self.rules.folds.max(2);
        let (b, a) = (before.sse_over(rows), after.sse_over(rows));
        // Folds where these rows have held-out samples (a drawer resting on its stop for a whole
        // block says nothing about it), and for a law of the joint's motion, where it moves.
        let follows_motion = self.candidates[c].family.follows_motion();
        let informative: Vec<usize> = (0..k)
            .filter(|&f| rows.iter().map(|&r| self.grams[r].folds[f].3).sum::<usize>() >= MIN_FOLD_SAMPLES)
            .filter(|&f| !follows_motion || rows.iter().any(|&r| self.moving[r][f]))
            .collect();
        let better = informative
            .iter()
            .filter(|&&f| {
                rows.iter().map(|&r| after.fold_sse[r][f]).sum::<f64>() < rows.iter().map(|&r| before.fold_sse[r][f]).sum::<f64>()
            })
            .count();
        (if b > 0.0 { (b - a) / b } else { 0.0 }, better as f64 / informative.len().max(1) as f64)
    }

    /// [`Verdict::inertial_share`] of candidate c whose RMS effort is `size`.
    fn inertial_share(&self, c: usize, size: f64) -> f64 {
        let info = &self.rows[self.candidates[c].row];
        let scale = match self.candidates[c].kind {
            EffectKind::Armature => info.inertial_rms,
            EffectKind::MassScale => info.model_rms,
            _ => 0.0,
        };
        if scale > 0.0 { size / scale } else { f64::INFINITY }
    }

    /// Where candidate c, an inertia (an armature, a heavier part) on a joint whose chosen
    /// friction in `set` is dry, is not material once fitted away from the joint's reversals
    /// ([`Self::fit_away_from_reversals`]): its share of the joint's own effort and of the
    /// model's inertial (or whole) effort there. Dry friction turns round over a few
    /// milliseconds that no law of the speed alone follows: `MuJoCo`'s regularised friction loss
    /// turns ahead of the speed's sign (its constraint's time constant), real friction's
    /// pre-sliding behind it. Either way the effort it leaves at each reversal, where the joint
    /// accelerates most, is shaped like inertia, by as much as the friction is strong: a Panda
    /// joint with 2 N·m of friction loss and no rotor read an armature of 0.041 kg·m² (0.023 away
    /// from its reversals), a `UR5e` shoulder 0.16 for its 0.1 (0.093 away). A rotor's or a part's
    /// inertia acts at every acceleration, so it holds away from the reversals too (the true
    /// armatures beside the `MuJoCo` arms' friction kept 60-106 % of their reading there, the
    /// false ones 28-47 %).
    fn inertia_only_at_reversals(&self, set: &[usize], c: usize) -> Option<(f64, f64)> {
        let cand = &self.candidates[c];
        if !cand.kind.adds_inertia() || !self.rows_turning_round(set).contains(&cand.row) {
            return None;
        }
        let (theta, _) = self.fit_away_from_reversals(set, &[cand.row]);
        let size = self.term_rms(c, &theta);
        let (effort_share, inertial_share) = (size / self.rows[cand.row].effort_rms.max(1e-12), self.inertial_share(c, size));
        let material = effort_share >= self.rules.min_effort_share
            && inertial_share >= self.rules.min_inertial_load_share
            && self.plausible(c, &theta);
        (!material).then_some((effort_share, inertial_share))
    }

    /// Whether candidate c is shaped like an error of the model's rigid bodies: its weights and
    /// centres of mass (an offset, a spring, a tilt) or its masses and inertias (an armature, a
    /// heavier part), judged against the model's own effort by [`Self::select`].
    fn shaped_like_model_error(&self, c: usize) -> bool {
        let kind = self.candidates[c].kind;
        kind.depends_on_position_alone() || kind.adds_inertia()
    }

    fn passes(&self, v: &Verdict) -> bool {
        self.cut_passes(v.gain, v.fold_share) && self.material(v)
    }

    /// Whether a term's size and parameters matter, whatever the held-out data say (the static
    /// load test is applied after the selection rounds, [`Self::select`]).
    fn material(&self, v: &Verdict) -> bool {
        v.effort_share >= self.rules.min_effort_share && v.plausible
    }

    /// Whether the fitted parameters of candidate c are physical (a heavier part within the
    /// plausible range, non-negative friction and damping levels, a base tilted at most
    /// [`SelectionRules::max_base_tilt_deg`]).
    fn plausible(&self, c: usize, theta: &Params) -> bool {
        if self.candidates[c].unresolved.is_some() {
            return false;
        }
        let e = self.effect_of(c, theta);
        let (lo, hi) = self.rules.mass_scale_range;
        match e.kind {
            EffectKind::MassScale => (lo..=hi).contains(&e.params[0]) && (e.params[0] - 1.0).abs() >= self.rules.min_mass_change,
            EffectKind::CoulombFriction => e.params[0] >= 0.0 && e.params[2].nan_or_nonneg(),
            EffectKind::StribeckFriction => {
                e.params[0] >= 0.0 && e.params[1] > e.params[0] && !self.rules.breakaway_beyond_ratio(e.params[0], e.params[1])
            }
            EffectKind::ViscousDamping | EffectKind::Armature | EffectKind::SoftClose | EffectKind::Spring => e.params[0] >= 0.0,
            EffectKind::GravityTilt if base_lean(&e).is_some() => e.params[0] <= self.rules.max_base_tilt_deg.to_radians().sin(),
            _ => true,
        }
    }

    /// The selection: [`Self::select_without`] bans nothing, then again without the terms shaped
    /// like an error of the model's rigid bodies that are too small next to the effort the model
    /// needs ([`SelectionRules::min_static_load_share`], [`SelectionRules::min_inertial_load_share`]).
    fn select(&self) -> Vec<usize> {
        // Terms shaped like an error of the model's rigid bodies (an offset, a spring, a tilt; an
        // armature, a heavier part) are chosen as any other, then those too small next to the
        // joint's gravity or inertial effort are banned and the selection is run again without
        // them: judged inside the rounds, such a term can pass when it enters and fail later, and
        // take a real term out with it each time (a spring beside a joint's friction). Both
        // readings of a joint's inertia are judged alike: a heavier part takes a banned
        // armature's place, and must pass the rule too.
        let mut banned = vec![false; self.candidates.len()];
        loop {
            let chosen = self.select_without(&banned);
            let fitted = self.evaluate(&chosen);
            let weak: Vec<usize> = chosen
                .iter()
                .copied()
                .filter(|&c| self.shaped_like_model_error(c))
                .filter(|&c| {
                    let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).collect();
                    let v = self.verdict(&self.evaluate(&rest), &fitted, &self.rows_of(c), c, None);
                    v.static_share < self.rules.min_static_load_share
                        || v.inertial_share < self.rules.min_inertial_load_share
                        || self.inertia_only_at_reversals(&chosen, c).is_some()
                })
                .collect();
            // Bans only grow, so this ends; a weak term already banned (none should come back)
            // would otherwise repeat the round for ever.
            if weak.is_empty() || weak.iter().all(|&c| banned[c]) {
                let mut chosen: Vec<usize> = chosen.into_iter().filter(|c| !weak.contains(c)).collect();
                self.prefer_damped_friction(&mut chosen, &banned);
                chosen.sort_unstable();
                return chosen;
            }
            for c in weak {
                let (row, kind) = (self.candidates[c].row, self.candidates[c].kind);
                for (x, b) in banned.iter_mut().enumerate() {
                    *b |= self.candidates[x].row == row && self.candidates[x].kind == kind;
                }
            }
        }
    }

    /// Forward selection with replacement inside a family, then backward pruning, over the
    /// candidates not `banned`.
    fn select_without(&self, banned: &[bool]) -> Vec<usize> {
        let mut chosen: Vec<usize> = Vec::new();
        let mut current = self.evaluate(&chosen);
        // Forward steps, sequential replacement, then pruning; a swapped or pruned term can make
        // room for one that was masked, so the three alternate until none changes the set
        // (three rounds at most).
        for _ in 0..3 {
            self.forward(&mut chosen, &mut current, banned);
            let replaced = self.replace(&mut chosen, &mut current, banned);
            if !self.prune(&mut chosen, &mut current) && !replaced {
                break;
            }
        }
        self.settle_refinements(&mut chosen, banned);
        self.prefer_offset_reading(&mut chosen, banned);
        self.prefer_better_pull(&mut chosen, banned);
        self.settle_springs(&mut chosen, banned);
        self.prefer_inertia_alone(&mut chosen, banned);
        chosen.sort_unstable();
        chosen
    }

    /// How far refinement c departs from its base law under `theta`: Stribeck's break-away over
    /// its sliding level, an asymmetric Coulomb law's reverse level over its forward one.
    fn refinement_excess(&self, c: usize, theta: &Params) -> f64 {
        let p = self.effect_of(c, theta).params;
        match self.candidates[c].kind {
            EffectKind::StribeckFriction => p[1] - p[0],
            _ => p.get(2).map_or(f64::NAN, |r| r - p[0]),
        }
    }

    /// Whether refinement c is friction that differs by direction by `excess` (reverse level
    /// less forward level) so little that the constant it adds while the joint moves, half of
    /// it, lies within [`SelectionRules::min_static_load_share`] of the joint's gravity effort:
    /// that constant is shaped like an error of the modelled weights, the rule an offset obeys.
    fn asymmetry_within_weight_error(&self, c: usize, excess: f64) -> bool {
        let cand = &self.candidates[c];
        let gravity_rms = self.rows[cand.row].gravity_rms;
        cand.kind == EffectKind::CoulombFriction
            && cand.asymmetric
            && gravity_rms > 0.0
            && 0.5 * excess.abs() < self.rules.min_static_load_share * gravity_rms
    }

    /// A refinement whose departure from its base law lies within two jackknife σ of none is
    /// its base law (the rule position space applies to every level): an engine's regularised
    /// friction on a loaded shoulder gave a "break-away" 1.8× the sliding level, 1.7σ from none.
    /// So is friction that differs by direction by less than a weight error could
    /// ([`Self::asymmetry_within_weight_error`]), and a refinement whose change over its best
    /// base law is under [`SelectionRules::min_effort_share`] of the joint's effort, or that cuts
    /// the held-out error of that best base law by less than [`SelectionRules::min_cv_gain`]
    /// (Bullet's ideal friction motor on an iiwa read as a Stribeck law breaking away at
    /// 1.2-1.3× its sliding level, 1.3-1.4 % better than Coulomb's). It is replaced by the
    /// base-law variant on its joint that fits best, if that passes on its own, and dropped
    /// otherwise.
    fn settle_refinements(&self, chosen: &mut Vec<usize>, banned: &[bool]) {
        loop {
            let fitted = self.evaluate(chosen);
            let doubtful = chosen.iter().copied().filter(|&c| self.candidates[c].is_refinement()).find_map(|c| {
                let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).collect();
                let base = self.best_base(&rest, c, banned);
                let excess = |t: &Params| self.refinement_excess(c, t);
                let base_fit = base.as_ref().map(|(b, e)| (*b, e));
                (self.adds_too_little(c, &fitted, excess, base_fit) || self.asymmetry_within_weight_error(c, excess(&fitted.theta)))
                    .then_some((rest, base))
            });
            let Some((rest, base)) = doubtful else { return };
            *chosen = self.settle_to_base(rest, base.as_ref().map(|(b, e)| (*b, e)));
        }
    }

    /// Whether what term c adds over `base` (the reading c stands in place of, fitted beside
    /// the others; none when no such reading fits) is too small to report: its `excess` over
    /// that reading within [`SelectionRules::min_resolved_sigmas`] jackknife σ of none, its
    /// change over it under [`SelectionRules::min_effort_share`] of the joint's effort (c may
    /// have entered whole, judged by its full size), or its cut of the error that reading leaves
    /// under [`SelectionRules::min_cv_gain`] (c may have entered against a worse reading than the
    /// one the final terms around it make best). `fitted` is the evaluation of the set with c.
    fn adds_too_little(&self, c: usize, fitted: &Evaluation, excess: impl Fn(&Params) -> f64, base: Option<(usize, &Evaluation)>) -> bool {
        let row = self.candidates[c].row;
        let jack: Vec<f64> = fitted.theta_without.iter().map(&excess).collect();
        let unresolved = excess(&fitted.theta).abs() < self.rules.min_resolved_sigmas * jackknife_sd(&jack, self.rules.folds.max(2));
        let immaterial = base.is_some_and(|(b, e)| {
            self.change_rms(c, &fitted.theta, Some((b, &e.theta))) < self.rules.min_effort_share * self.rows[row].effort_rms
        });
        let thin = base.is_some_and(|(_, e)| {
            let (before, after) = (e.row_sse(row), fitted.row_sse(row));
            before > 0.0 && (before - after) / before < self.rules.min_cv_gain
        });
        unresolved || immaterial || thin
    }

    /// `rest` with `base` (the reading a term too small to report stood in place of) where it
    /// passes on its own beside `rest`, whichever way the term entered; `rest` alone where it
    /// does not: a reading that passes only with the term's extra level is not reported.
    fn settle_to_base(&self, rest: Vec<usize>, base: Option<(usize, &Evaluation)>) -> Vec<usize> {
        let rest_fit = self.evaluate(&rest);
        match base {
            Some((b, e)) if self.passes(&self.verdict(&rest_fit, e, &self.rows_of(b), b, None)) => self.with(&rest, b),
            _ => rest,
        }
    }

    /// A spring is a constant and a stiffness (its columns: the joint's position and the
    /// constant an offset has): what its stiffness adds over the best offset in its place must
    /// matter as a refinement's must ([`Self::settle_refinements`]), or it is an offset. A
    /// spring is kept where its stiffness lies two jackknife σ from none, what it changes over
    /// that offset is [`SelectionRules::min_effort_share`] of the joint's effort, and it cuts
    /// the offset's held-out error by [`SelectionRules::min_cv_gain`]; otherwise the offset
    /// takes its place if it passes on its own, and neither is reported if it does not. Judged
    /// whole, a spring is as large as its constant: the real Panda's friction law, smooth and
    /// different by direction, beside its model's weight error, read as springs whose rest lay
    /// beyond the motion (0.30 N·m/rad towards 0.62 rad on a shoulder moving over -1.1..-0.45).
    fn settle_springs(&self, chosen: &mut Vec<usize>, banned: &[bool]) {
        let springs: Vec<usize> = chosen.iter().copied().filter(|&c| self.candidates[c].kind == EffectKind::Spring).collect();
        for c in springs {
            let fitted = self.evaluate(chosen);
            let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).collect();
            let offset = |x: usize| self.candidates[x].kind == EffectKind::EffortOffset && !banned[x];
            let base = self.best_in_place(&rest, self.candidates[c].row, offset, |_, _| true);
            let base_fit = base.as_ref().map(|b| (b.candidate, &b.fit));
            if self.adds_too_little(c, &fitted, |t| self.effect_of(c, t).params[0], base_fit) {
                *chosen = self.settle_to_base(rest, base_fit);
            }
        }
    }

    /// The base-law variant of refinement c's family on c's joint, not `banned`, that fits
    /// best beside `rest`, with its evaluation.
    fn best_base(&self, rest: &[usize], c: usize, banned: &[bool]) -> Option<(usize, Evaluation)> {
        let cand = &self.candidates[c];
        let base = |b: usize| {
            let x = &self.candidates[b];
            x.family == cand.family && !x.is_refinement() && !banned[b]
        };
        // Every term of the joint physical beside it: a wide law can fit best beside a negative
        // damping, which no joint has.
        let physical = |b: usize, fit: &Evaluation| {
            self.with(rest, b).into_iter().filter(|&x| self.candidates[x].row == cand.row).all(|x| self.plausible(x, &fit.theta))
        };
        self.best_in_place(rest, cand.row, base, physical).map(|v| (v.candidate, v.fit))
    }

    /// Among the candidates on joint `row` that `pick` takes, the one that, put into `rest` in
    /// place of its family's member there, leaves the least held-out error on that joint and
    /// that `accept` takes with its fit (the earliest on a tie).
    fn best_in_place(
        &self,
        rest: &[usize],
        row: usize,
        pick: impl Fn(usize) -> bool,
        accept: impl Fn(usize, &Evaluation) -> bool,
    ) -> Option<InPlace> {
        (0..self.candidates.len())
            .filter(|&x| self.candidates[x].row == row && pick(x))
            .filter_map(|x| {
                let set = self.with(rest, x);
                let fit = self.evaluate(&set);
                accept(x, &fit).then(|| InPlace { candidate: x, sse: fit.row_sse(row), set, fit })
            })
            .min_by(|a, b| a.sse.total_cmp(&b.sse))
    }

    /// The first candidate of `kind` on joint `row` that is not `banned` (the kinds without a
    /// grid have one).
    fn unbanned_of(&self, row: usize, kind: EffectKind, banned: &[bool]) -> Option<usize> {
        (0..self.candidates.len()).find(|&x| !banned[x] && self.candidates[x].row == row && self.candidates[x].kind == kind)
    }

    /// Dry friction smooth over a wide transition and sharper dry friction beside viscous damping
    /// are alike over the speeds a recording holds: both rise through zero speed and keep growing
    /// towards its fastest motion. Forward selection takes the wide law first (one term explains
    /// most of both) and the damping then adds too little to enter: engines' doors with dry
    /// friction and a damper (`MuJoCo`, Bullet, DART, `JaxSim`, Klamp't) were read as friction
    /// smooth over 0.5-0.9 rad/s alone. So on the final selection, a joint whose Coulomb law has a
    /// transition and no damping beside it is also read as a sharper Coulomb law (same both ways)
    /// beside viscous damping, the law that fits best with the damping passing beside it; that
    /// reading replaces the wide one where it passes as a new term must against it (a cut of the
    /// joint's held-out error by [`SelectionRules::min_cv_gain`] in
    /// [`SelectionRules::min_fold_share`] of the blocks, the damping material). On those doors it
    /// cut the held-out error 4-18×; where the friction levels off as a real joint's does (the
    /// Panda's published law) it does not pass. Else damping alone replaces the wide law where
    /// it explains the joint as well ([`LOOK_ALIKE_SSE_SHARE`]): a law smooth over the joint's own
    /// speeds is linear in them, and forward selection breaks near-ties towards the friction law,
    /// which comes first (a damped door tracked by its pose: friction smooth over 0.7 rad/s).
    fn prefer_damped_friction(&self, chosen: &mut Vec<usize>, banned: &[bool]) {
        let wide: Vec<usize> = chosen
            .iter()
            .copied()
            .filter(|&c| {
                self.candidates[c].kind == EffectKind::CoulombFriction && self.candidates[c].hyper.first().is_some_and(|&vs| vs > 0.0)
            })
            .collect();
        for c in wide {
            let row = self.candidates[c].row;
            if !chosen.contains(&c) || chosen.iter().any(|&x| self.candidates[x].row == row && self.candidates[x].family == Family::Viscous)
            {
                continue;
            }
            let Some(damping) = self.unbanned_of(row, EffectKind::ViscousDamping, banned) else { continue };
            let fitted = self.evaluate(chosen);
            let vs = self.candidates[c].hyper[0];
            let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).chain([damping]).collect();
            let sharper = |x: usize| {
                let cand = &self.candidates[x];
                cand.kind == EffectKind::CoulombFriction
                    && !cand.is_refinement()
                    && !banned[x]
                    && cand.hyper.first().is_some_and(|&s| s < vs)
            };
            let damping_passes = |x: usize, fit: &Evaluation| {
                let without: Vec<usize> = self.with(&rest, x).into_iter().filter(|&y| y != damping).collect();
                self.plausible(x, &fit.theta) && self.passes(&self.verdict(&self.evaluate(&without), fit, &[row], damping, None))
            };
            // The swap must pass as a new term would: cut the joint's held-out error by
            // `min_cv_gain`, in `min_fold_share` of the blocks, the damping material.
            if let Some(pair) = self.best_in_place(&rest, row, sharper, damping_passes)
                && self.passes(&self.verdict(&fitted, &pair.fit, &[row], damping, None))
            {
                *chosen = pair.set;
                continue;
            }
            // Damping alone, where it explains the joint as well: a law smooth over the joint's
            // own speeds is linear in them.
            let alone = self.evaluate(&rest);
            if self.plausible(damping, &alone.theta) && alone.row_sse(row) <= fitted.row_sse(row) * (1.0 + LOOK_ALIKE_SSE_SHARE) {
                *chosen = rest;
            }
        }
    }

    /// Friction that differs by direction and the same friction both ways beside a constant
    /// offset are one law while the joint moves (levels f and r ≡ (f + r)/2 both ways, offset
    /// (f − r)/2); only rests and reversals tell them apart. Where the offset reading explains
    /// the recording as well ([`LOOK_ALIKE_SSE_SHARE`]), it is reported: it is the friction model
    /// of robot identification (Coulomb, viscous, offset: Gautier; Swevers), and a torque
    /// sensor's bias or a gravity compensation's error is the commoner cause. The other reading
    /// is named among the rejected.
    fn prefer_offset_reading(&self, chosen: &mut Vec<usize>, banned: &[bool]) {
        let asymmetric: Vec<usize> = chosen
            .iter()
            .copied()
            .filter(|&c| self.candidates[c].kind == EffectKind::CoulombFriction && self.candidates[c].asymmetric)
            .collect();
        for c in asymmetric {
            if let Some(swapped) = self.offset_reading(chosen, c, banned) {
                *chosen = swapped;
            }
        }
    }

    /// `chosen` with the friction by direction c read as the same friction both ways (its best
    /// variant) and an offset, when that reading is physical and explains c's joint as well;
    /// None otherwise, or when the joint's constant is taken (an offset or a spring chosen).
    fn offset_reading(&self, chosen: &[usize], c: usize, banned: &[bool]) -> Option<Vec<usize>> {
        let row = self.candidates[c].row;
        let on_row = |x: usize, family: Family| self.candidates[x].row == row && self.candidates[x].family == family;
        if chosen.iter().any(|&x| on_row(x, Family::Constant)) {
            return None;
        }
        let offset = self.unbanned_of(row, EffectKind::EffortOffset, banned)?;
        let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).chain([offset]).collect();
        let mine = self.evaluate(chosen).row_sse(row);
        let both_ways = |x: usize| self.candidates[x].family == Family::Friction && !self.candidates[x].is_refinement() && !banned[x];
        let InPlace { set, fit, sse, .. } = self.best_in_place(&rest, row, both_ways, |x, e| self.plausible(x, &e.theta))?;
        // The offset must matter as a term of its own.
        let without_offset: Vec<usize> = set.iter().copied().filter(|&x| x != offset).collect();
        let material = self.material(&self.verdict(&self.evaluate(&without_offset), &fit, &[row], offset, None));
        (material && sse.is_finite() && sse <= mine * (1.0 + LOOK_ALIKE_SSE_SHARE)).then_some(set)
    }

    /// A spring and a tilted axis (a sine of the angle) pull alike over a short swing, and forward
    /// selection takes whichever helps more first, before the terms beside it have entered (a
    /// rapier3d door with a spring and a damper: the tilt entered, and the spring in its place,
    /// beside the damper, leaves 16 % less held-out error). Where the other pull, put in place of
    /// the chosen one in the final set, lowers the joint's held-out error by the gain a new term
    /// must bring ([`SelectionRules::min_cv_gain`]), it replaces it.
    fn prefer_better_pull(&self, chosen: &mut Vec<usize>, banned: &[bool]) {
        let pulls: Vec<usize> =
            chosen.iter().copied().filter(|&c| matches!(self.candidates[c].kind, EffectKind::Spring | EffectKind::GravityTilt)).collect();
        for c in pulls {
            let (row, kind) = (self.candidates[c].row, self.candidates[c].kind);
            let other = if kind == EffectKind::Spring { EffectKind::GravityTilt } else { EffectKind::Spring };
            // Not where the row holds a member of the other's family already: the other itself, or
            // a constant the spring would take in (an offset that another reading put there).
            let Some(other_family) = self.candidates.iter().find(|x| x.row == row && x.kind == other).map(|x| x.family) else {
                continue;
            };
            let taken = chosen.iter().any(|&x| x != c && self.candidates[x].row == row && self.candidates[x].family == other_family);
            if !chosen.contains(&c) || taken {
                continue;
            }
            let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).collect();
            let mine = self.evaluate(chosen).row_sse(row);
            let pick = |x: usize| self.candidates[x].kind == other && !banned[x];
            let Some(better) = self.best_in_place(&rest, row, pick, |x, e| self.plausible(x, &e.theta)) else { continue };
            if better.sse < (1.0 - self.rules.min_cv_gain) * mine {
                *chosen = better.set;
            }
        }
    }

    /// The spec's rule: a heavier part (`mass_scale`) is inertia and weight together; inertia
    /// alone is `armature`. Where a rotor's inertia on the same joint explains the recording as
    /// well (gravity does next to no work on it: a knob turning about its centre of mass, a
    /// horizontal drawer), the weight was never seen, so the narrower reading is reported and
    /// the heavier part is named as the other reading among the rejected.
    fn prefer_inertia_alone(&self, chosen: &mut Vec<usize>, banned: &[bool]) {
        let heavier: Vec<usize> = chosen.iter().copied().filter(|&c| self.candidates[c].kind == EffectKind::MassScale).collect();
        for m in heavier {
            let fitted = self.evaluate(chosen);
            let row = self.candidates[m].row;
            // Not where a rotor's inertia is already named beside the heavier part.
            let rotor = self
                .unbanned_of(row, EffectKind::Armature, banned)
                .filter(|_| !chosen.iter().any(|&c| self.candidates[c].row == row && self.candidates[c].kind == EffectKind::Armature));
            if let Some((swapped, _, _)) = rotor.and_then(|a| self.as_good_in_place(chosen, &fitted, a, m)) {
                *chosen = swapped;
            }
        }
    }

    /// Candidate c put in place of `twin` in `chosen`: the new set and the relative rise of the
    /// held-out error on the rows of both, when c is physical and the rise is within
    /// [`LOOK_ALIKE_SSE_SHARE`].
    fn as_good_in_place(&self, chosen: &[usize], fitted: &Evaluation, c: usize, twin: usize) -> Option<(Vec<usize>, Evaluation, f64)> {
        let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != twin).collect();
        // In place of its family's member too: a spring takes the constant of an offset in.
        let swapped = self.with(&rest, c);
        let e = self.evaluate(&swapped);
        let rows = rows_of_both(&self.rows_of(c), &self.rows_of(twin));
        let (mine, theirs) = (fitted.sse_over(&rows), e.sse_over(&rows));
        let as_good = theirs.is_finite() && theirs <= mine * (1.0 + LOOK_ALIKE_SSE_SHARE);
        let rise = (theirs - mine) / mine.max(f64::MIN_POSITIVE);
        (as_good && self.plausible(c, &e.theta)).then_some((swapped, e, rise))
    }

    /// Adds (or swaps within a family) the candidate that passes and cuts the held-out error most,
    /// while one does.
    fn forward(&self, chosen: &mut Vec<usize>, current: &mut Evaluation, banned: &[bool]) {
        for _ in 0..4 * self.rows.len() + 8 {
            // A refinement enters in place of its base law, so that what it adds is judged on
            // its own; only where no term passes alone may one enter whole. Friction that
            // differs by direction on a joint that moves one way for long spells is two
            // levels that neither a symmetric law nor an offset matches alone: each is better
            // in only half of the held-out blocks.
            // Where no term passes alone, two may pass together (below).
            let step = self
                .best_step(chosen, current, banned, false)
                .or_else(|| self.best_step(chosen, current, banned, true))
                .map(|(c, e)| (self.with(chosen, c), e))
                .or_else(|| self.best_pair(chosen, current, banned));
            let Some((set, e)) = step else { return };
            *chosen = set;
            *current = e;
        }
    }

    /// Two terms of one joint that pass only together, where no term passes alone: each biases
    /// the other's fit while it is missing (omitted-variable bias; Miller, *Subset Selection in
    /// Regression*, §3.2, on forward selection missing a pair that explains together). A lid
    /// heavier than modelled with a damped hinge: the model's own first moments take the
    /// heavier part's weight, so alone it reads as inertia and its fit bends to the damping's
    /// effort it lacks; alone, the damping is fitted half again too strong and fails where the
    /// lid is pushed hardest; together both come out right and explain nearly all the effort.
    ///
    /// A pair is two families' best single steps on one joint (families the joint does not have
    /// yet), at least one of them a law of the joint's own (friction, damping, a soft-close): two
    /// terms shaped like the model's own rigid-body error (an offset and a tilt, a heavier part
    /// and a spring) together fit what a 5 % weight error does, and on a vertical door they did.
    /// Alone either may make the held-out error worse (`JaxSim`'s heavier, damped lid: each term
    /// alone fails the block where the lid is pushed hardest, together they cut the error a
    /// hundredfold). The pair must cut the held-out error as a step must, and each member must pass
    /// against the set with the other (the test [`Self::prune`] applies), so neither is carried
    /// by its partner. On a joint that has terms already, a pair enters only in place of one of
    /// them, that fails beside it (what stood in for the two: dry friction for a heavier, damped
    /// lid), as sequential replacement swaps one term for one ([`Self::replace`]); beside terms
    /// that still hold, later terms enter one by one. The best pair by its cut enters: the new
    /// set and its evaluation.
    fn best_pair(&self, chosen: &[usize], current: &Evaluation, banned: &[bool]) -> Option<(Vec<usize>, Evaluation)> {
        let weighed: Vec<Weighed> = self.steps.lock().ok()?.get(&(chosen.to_vec(), false))?.weighed.clone();
        let has_family =
            |row: usize, family: Family| chosen.iter().any(|&x| self.candidates[x].row == row && self.candidates[x].family == family);
        // Each family's best single step per row (its other laws fare alike beside a partner).
        let mut best_of: BTreeMap<(usize, Family), Weighed> = BTreeMap::new();
        for w in weighed.iter().filter(|w| !banned[w.candidate]) {
            let cand = &self.candidates[w.candidate];
            if cand.is_refinement() || has_family(cand.row, cand.family) {
                continue;
            }
            let slot = best_of.entry((cand.row, cand.family)).or_insert(*w);
            if outgains(w.gain, slot.gain) {
                *slot = *w;
            }
        }
        let pairs: BTreeSet<(usize, usize)> = best_of
            .iter()
            .flat_map(|(&(row, family), first)| {
                best_of
                    .iter()
                    .filter(move |((r, f), _)| {
                        *r == row && *f > family && !(f.mimics_rigid_body_error() && family.mimics_rigid_body_error())
                    })
                    .map(move |(_, second)| (first.candidate.min(second.candidate), first.candidate.max(second.candidate)))
            })
            .collect();
        let passing: Vec<(Vec<usize>, f64, Evaluation)> =
            pairs.into_iter().collect::<Vec<_>>().into_par_iter().filter_map(|(a, b)| self.pair_step(chosen, current, a, b)).collect();
        let mut best: Option<(Vec<usize>, f64, Evaluation)> = None;
        for (set, gain, e) in passing {
            if best.as_ref().is_none_or(|(_, best_gain, _)| outgains(gain, *best_gain)) {
                best = Some((set, gain, e));
            }
        }
        best.map(|(set, _, e)| (set, e))
    }

    /// The set [`Self::best_pair`] reaches from `chosen` with candidates a and b, the pair's
    /// held-out cut and the set's evaluation, where the pair passes.
    fn pair_step(&self, chosen: &[usize], current: &Evaluation, a: usize, b: usize) -> Option<(Vec<usize>, f64, Evaluation)> {
        let rows = rows_of_both(&self.rows_of(a), &self.rows_of(b));
        let with_pair = self.with(&self.with(chosen, a), b);
        let e = self.evaluate(&with_pair);
        let each_passes = |base: &[usize], e: &Evaluation| {
            [(a, b), (b, a)].into_iter().all(|(x, partner)| {
                let v = self.verdict(&self.evaluate(&self.with(base, partner)), e, &self.rows_of(x), x, None);
                self.passes(&v)
            })
        };
        // The pair's terms act where the joint rests unless both follow its motion.
        let judged_as = if self.candidates[a].family.follows_motion() { b } else { a };
        let on_rows: Vec<usize> = chosen.iter().copied().filter(|&x| rows.contains(&self.candidates[x].row)).collect();
        if on_rows.is_empty() {
            let (gain, fold_share) = self.held_out_cut(current, &e, &rows, judged_as);
            // A base tilt refits every joint it loads: the error summed over them may not rise
            // (as for a single step, `weigh_steps`).
            let tilt_holds = ![a, b].iter().any(|&x| self.candidates[x].is_base_tilt()) || e.total_sse() <= current.total_sse();
            return (self.cut_passes(gain, fold_share) && tilt_holds && each_passes(chosen, &e)).then_some((with_pair, gain, e));
        }
        // In place of the first of the joint's terms (in the order they entered) that fails
        // beside the pair, judged as a swap is (`replace`): over the rows of all three, and the
        // error summed over every row may not rise.
        let displaced = on_rows.into_iter().find(|&x| {
            let rest: Vec<usize> = with_pair.iter().copied().filter(|&y| y != x).collect();
            !self.passes(&self.verdict(&self.evaluate(&rest), &e, &self.rows_of(x), x, None))
        })?;
        let base: Vec<usize> = chosen.iter().copied().filter(|&y| y != displaced).collect();
        let set = self.with(&self.with(&base, a), b);
        let e = self.evaluate(&set);
        let swap_rows = rows_of_both(&rows, &self.rows_of(displaced));
        let (gain, fold_share) = self.held_out_cut(current, &e, &swap_rows, judged_as);
        let passes = self.cut_passes(gain, fold_share) && each_passes(&base, &e) && e.total_sse() <= current.total_sse();
        passes.then_some((set, gain, e))
    }

    /// The candidate not `banned` that passes and cuts the held-out error most against
    /// `current`: among those that may enter ([`Self::may_enter`]), or, with `whole_refinements`,
    /// among the refinements that may not (their family absent from the joint).
    ///
    /// `current` is the evaluation of `chosen` (as [`Self::forward`] and [`Self::prune`] keep
    /// it), so a step is determined by `chosen`, the kind of step and the bans. [`Self::select`]
    /// runs forward selection again with more bans, through the same sets until it departs from
    /// the earlier run: a step weighed under fewer bans is not weighed again, its weighed
    /// candidates less the newly banned ones are what weighing them again would give (each
    /// candidate's verdict depends on the set alone), and the tie-break runs over them afresh.
    fn best_step(&self, chosen: &[usize], current: &Evaluation, banned: &[bool], whole_refinements: bool) -> Option<(usize, Evaluation)> {
        let key = (chosen.to_vec(), whole_refinements);
        let weighed = self.steps.lock().ok().and_then(|steps| steps.get(&key).cloned());
        let weighed: Vec<Weighed> = match weighed {
            Some(w) if w.banned.iter().zip(banned).all(|(&then, &now)| now || !then) => {
                w.weighed.iter().copied().filter(|w| !banned[w.candidate]).collect()
            }
            _ => {
                let weighed = self.weigh_steps(chosen, current, banned, whole_refinements);
                if let Ok(mut steps) = self.steps.lock() {
                    steps.insert(key, Arc::new(WeighedStep { banned: banned.to_vec(), weighed: weighed.clone() }));
                }
                weighed
            }
        };
        let mut best: Option<(usize, f64)> = None;
        for Weighed { candidate: c, gain, .. } in weighed.into_iter().filter(|w| w.passes) {
            if best.is_none_or(|(_, best_gain)| outgains(gain, best_gain)) {
                best = Some((c, gain));
            }
        }
        best.map(|(c, _)| (c, self.evaluate(&self.with(chosen, c))))
    }

    /// The candidates not `banned` that may take the step of [`Self::best_step`], each with its
    /// gain and whether it passes, in candidate order.
    fn weigh_steps(&self, chosen: &[usize], current: &Evaluation, banned: &[bool], whole_refinements: bool) -> Vec<Weighed> {
        // The candidates are weighed in parallel (each fit depends on its set alone; the caches
        // hold what the set's key determines), then taken in candidate order.
        (0..banned.len())
            .into_par_iter()
            // An unresolved law never passes (`plausible`): not worth its evaluation.
            .filter(|&c| {
                !(banned[c]
                    || chosen.contains(&c)
                    || self.candidates[c].unresolved.is_some()
                    || self.may_enter(chosen, c) == whole_refinements)
            })
            .map(|c| {
                let rows = self.rows_of(c);
                let e = self.evaluate_beside(&self.with(chosen, c), c, &rows);
                let (gain, fold_share) = self.held_out_cut(current, &e, &rows, c);
                let failed = Weighed { candidate: c, gain, passes: false };
                if !self.cut_passes(gain, fold_share) {
                    return failed;
                }
                // Judged on its base joint, a base tilt still refits every joint it loads: it may
                // not raise the held-out error summed over them all (as a swap may not, `replace`).
                if self.candidates[c].is_base_tilt() && self.evaluate(&self.with(chosen, c)).total_sse() > current.total_sse() {
                    return failed;
                }
                let v = self.verdict(current, &e, &rows, c, self.family_member(chosen, c));
                Weighed { candidate: c, gain: v.gain, passes: self.passes(&v) }
            })
            .collect()
    }

    /// Sequential replacement (Miller, *Subset Selection in Regression*, §3.5): forward selection
    /// takes the term that cuts the held-out error most at each step, and where two candidates
    /// explain overlapping rows the first taken can mask a better one. A heavier distal part
    /// loads every joint above it and can take a proximal joint's own term (on `MuJoCo`'s
    /// identified Panda a spring on joint 3 entered before the part of joint 5 that explains
    /// both joints better). Each chosen term is tried in place by every candidate of another
    /// family touching its rows (within a family, forward steps swap already), not banned,
    /// resolved and not a refinement (those enter only in place of their base law); the best
    /// swap is kept when the newcomer passes against the rest, the swap cuts the held-out error
    /// summed over the rows of both as a step must ([`Self::cut_passes`]), and the error summed
    /// over every row does not rise (the model's own first moments tie a chain's rows into one
    /// fit, so a swap refits rows beyond the two terms'). True when a swap was made.
    fn replace(&self, chosen: &mut Vec<usize>, current: &mut Evaluation, banned: &[bool]) -> bool {
        let mut any = false;
        for _ in 0..chosen.len() {
            let current_total = current.total_sse();
            let swaps: Vec<(f64, Vec<usize>)> = chosen
                .par_iter()
                .flat_map_iter(|&out| {
                    let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != out).collect();
                    let without = self.evaluate(&rest);
                    let out_rows = self.rows_of(out);
                    let (out_row, out_family) = (self.candidates[out].row, self.candidates[out].family);
                    (0..banned.len())
                        .filter(|&c| {
                            let cand = &self.candidates[c];
                            !(banned[c]
                                || chosen.contains(&c)
                                || cand.unresolved.is_some()
                                || cand.is_refinement()
                                || (cand.row == out_row && cand.family == out_family)
                                || self.family_member(&rest, c).is_some())
                        })
                        .filter_map(|c| {
                            let c_rows = self.rows_of(c);
                            if !c_rows.iter().any(|r| out_rows.contains(r)) {
                                return None;
                            }
                            let rows = rows_of_both(&c_rows, &out_rows);
                            let set = self.with(&rest, c);
                            let e = self.evaluate(&set);
                            let (gain, fold_share) = self.held_out_cut(current, &e, &rows, c);
                            if !self.cut_passes(gain, fold_share) || e.total_sse() > current_total {
                                return None;
                            }
                            let v = self.verdict(&without, &e, &c_rows, c, None);
                            self.passes(&v).then_some((gain, set))
                        })
                        .collect::<Vec<_>>()
                })
                .collect();
            // Ties go to the earlier swap (chosen order, then candidate order).
            let best = swaps.into_iter().fold(None::<(f64, Vec<usize>)>, |best, (gain, set)| match best {
                Some((g, _)) if !outgains(gain, g) => best,
                _ => Some((gain, set)),
            });
            let Some((_, set)) = best else { break };
            *current = self.evaluate(&set);
            *chosen = set;
            any = true;
        }
        any
    }

    /// Whether candidate c may join `chosen`: a refinement enters only in place of its base law,
    /// so that what it adds is judged on its own.
    fn may_enter(&self, chosen: &[usize], c: usize) -> bool {
        !self.candidates[c].is_refinement() || self.family_member(chosen, c).is_some()
    }

    /// Drops chosen terms that no longer pass against the others; true when one was dropped.
    fn prune(&self, chosen: &mut Vec<usize>, current: &mut Evaluation) -> bool {
        let mut any = false;
        loop {
            // A term that is not material (too small, not physical) goes before one that only
            // fails on held-out data: the immaterial one may be what masks the other.
            let mut failing: Option<(bool, Vec<usize>, Evaluation)> = None;
            for idx in 0..chosen.len() {
                let rest: Vec<usize> = chosen.iter().copied().enumerate().filter(|&(k, _)| k != idx).map(|(_, c)| c).collect();
                let e = self.evaluate(&rest);
                let v = self.verdict(&e, current, &self.rows_of(chosen[idx]), chosen[idx], None);
                if !self.passes(&v) {
                    let immaterial = !self.material(&v);
                    if failing.as_ref().is_none_or(|(first_immaterial, _, _)| immaterial && !first_immaterial) {
                        failing = Some((immaterial, rest, e));
                    }
                    if immaterial {
                        break;
                    }
                }
            }
            let Some((_, rest, e)) = failing else { return any };
            *chosen = rest;
            *current = e;
            any = true;
        }
    }

    /// The effect of candidate c with parameters from `theta` (effort-mode layout).
    fn effect_of(&self, c: usize, theta: &Params) -> Effect {
        let cand = &self.candidates[c];
        let t: Vec<f64> = cand.columns.iter().map(|col| theta.get(*col)).collect();
        let params = match cand.kind {
            EffectKind::CoulombFriction if cand.asymmetric => vec![t[0], cand.hyper[0], t[1]],
            EffectKind::CoulombFriction => vec![t[0], cand.hyper[0], f64::NAN],
            EffectKind::StribeckFriction => vec![t[0], t[0] + t[1], cand.hyper[0]],
            EffectKind::Spring => vec![t[0], if t[0].abs() > 1e-12 { t[1] / t[0] } else { 0.0 }],
            // A base tilt ([`super::tilt`]): its lean w along the two directions, sin tilt = |w|.
            EffectKind::GravityTilt if cand.is_base_tilt() => {
                let w = t[0] * DVec3::from_slice(&cand.hyper[..3]) + t[1] * DVec3::from_slice(&cand.hyper[3..]);
                let params = vec![t[0].hypot(t[1]), t[1].atan2(t[0]), w.x, w.y, w.z];
                debug_assert_eq!(params.len(), BASE_TILT_PARAMS);
                params
            }
            EffectKind::GravityTilt => vec![t[0].hypot(t[1]), t[1].atan2(t[0])],
            EffectKind::MassScale => vec![1.0 + t[0]],
            EffectKind::SoftClose => vec![t[0], cand.hyper[0]],
            _ => t,
        };
        Effect { kind: cand.kind, params, blocks_upward: false }
    }

    /// The terms the selection rules choose.
    #[must_use]
    pub fn chosen_terms(&self) -> Terms {
        Terms(self.select())
    }

    /// Row r's held-out squared effort error under `terms` (every fold's held-out part).
    #[must_use]
    pub fn held_out_sse(&self, terms: &Terms, r: usize) -> f64 {
        self.evaluate(&terms.0).row_sse(r)
    }

    /// The law `terms` read row r's friction by: a dry friction kind or viscous damping; None
    /// when it holds both or neither.
    #[must_use]
    pub fn friction_law(&self, terms: &Terms, r: usize) -> Option<EffectKind> {
        let mut on_row =
            terms.0.iter().map(|&c| &self.candidates[c]).filter(|c| c.row == r && matches!(c.family, Family::Friction | Family::Viscous));
        match (on_row.next(), on_row.next()) {
            (Some(c), None) => Some(c.kind),
            _ => None,
        }
    }

    /// The kinds of `terms` on row r whose effort has a shape the model's own rigid-body error
    /// takes ([`Family::mimics_rigid_body_error`]).
    #[must_use]
    pub fn rigid_body_shaped(&self, terms: &Terms, r: usize) -> Vec<EffectKind> {
        terms.0.iter().map(|&c| &self.candidates[c]).filter(|c| c.row == r && c.family.mimics_rigid_body_error()).map(|c| c.kind).collect()
    }

    /// `terms` with row r's refinement of its friction law (a Stribeck law, friction by
    /// direction) replaced by the base-law variant that fits best beside the other terms; None
    /// when the row holds no refinement.
    #[must_use]
    pub fn base_reading(&self, terms: &Terms, r: usize) -> Option<Terms> {
        let c = terms.0.iter().copied().find(|&c| self.candidates[c].row == r && self.candidates[c].is_refinement())?;
        let rest: Vec<usize> = terms.0.iter().copied().filter(|&x| x != c).collect();
        let banned = vec![false; self.candidates.len()];
        self.best_base(&rest, c, &banned).map(|(b, _)| {
            let mut set = self.with(&rest, b);
            set.sort_unstable();
            Terms(set)
        })
    }

    /// `terms` without the terms whose levels, fitted together, are not physical (a negative
    /// damping or friction level, a part outside the plausible weights: [`Self::plausible`]) or
    /// no longer material (under [`SelectionRules::min_effort_share`] of the joint's effort, the
    /// size every term had to have to enter), the least material first, fitted again after each
    /// drop; with the (row, kind) of each drop and, for one no longer material, its share. Each
    /// stage of the reading keeps its own terms physical and material, but a later stage that
    /// drops or swaps a term fits the others again, and a term that leant on the one gone can turn
    /// round (a damping of −0.27 N·m·s/rad beside dry friction once its refinement was settled) or
    /// shrink to nothing (Drake's iiwa: a damping of 0.0033 ± 0.18 N·m·s/rad, 0.1 % of its joint's
    /// effort, beside friction whose transition a replay had sharpened).
    #[must_use]
    pub fn physical_reading(&self, terms: &Terms) -> (Terms, Vec<(usize, EffectKind, Option<f64>)>) {
        let mut set = terms.0.clone();
        let mut dropped = Vec::new();
        loop {
            let fit = self.evaluate(&set);
            let share = |c: usize| self.term_rms(c, &fit.theta) / self.rows[self.candidates[c].row].effort_rms.max(1e-12);
            let worst = set
                .iter()
                .copied()
                .filter(|&c| !self.plausible(c, &fit.theta) || share(c) < self.rules.min_effort_share)
                .min_by(|&a, &b| self.term_rms(a, &fit.theta).total_cmp(&self.term_rms(b, &fit.theta)));
            let Some(c) = worst else { return (Terms(set), dropped) };
            let immaterial = self.plausible(c, &fit.theta).then(|| share(c));
            dropped.push((self.candidates[c].row, self.candidates[c].kind, immaterial));
            set.retain(|&x| x != c);
        }
    }

    /// Candidate c's level under `theta`: its first parameter (the friction, damping,
    /// stiffness, offset, inertia or tilt), for a heavier part its change of weight; 0 is none.
    fn level_of(&self, c: usize, theta: &Params) -> f64 {
        let first = self.effect_of(c, theta).params[0];
        if self.candidates[c].kind == EffectKind::MassScale { first - 1.0 } else { first }
    }

    /// The terms of `terms` whose levels, fitted together, lie within
    /// [`SelectionRules::min_resolved_sigmas`] jackknife σ of none, the least material first: per
    /// term its (row, kind), level and σ. Forward selection judges a term by its held-out error,
    /// so a term can enter on a cut the folds share while its level swings from fold to fold
    /// (`MuJoCo`'s Panda: a damping of 0.046 ± 0.025 N·m·s/rad beside a wrist's dry friction).
    #[must_use]
    pub fn unresolved_terms(&self, terms: &Terms) -> Vec<(usize, EffectKind, f64, f64)> {
        let fit = self.evaluate(&terms.0);
        let mut out: Vec<(f64, usize, EffectKind, f64, f64)> = terms
            .0
            .iter()
            .filter_map(|&c| {
                let (level, sd) = self.unresolved(c, &fit)?;
                Some((self.term_rms(c, &fit.theta), self.candidates[c].row, self.candidates[c].kind, level, sd))
            })
            .collect();
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.into_iter().map(|(_, r, kind, level, sd)| (r, kind, level, sd)).collect()
    }

    /// Candidate c's level under `fit` and its jackknife σ, where the level lies within
    /// [`SelectionRules::min_resolved_sigmas`] σ of none.
    fn unresolved(&self, c: usize, fit: &Evaluation) -> Option<(f64, f64)> {
        let level = self.level_of(c, &fit.theta);
        let jack: Vec<f64> = fit.theta_without.iter().map(|t| self.level_of(c, t)).collect();
        let sd = jackknife_sd(&jack, self.rules.folds.max(2));
        (level.abs() < self.rules.min_resolved_sigmas * sd).then_some((level, sd))
    }

    /// `terms` without row r's term of `kind`; None when it holds none. The other terms keep
    /// their place; their levels are fitted again by [`Self::findings`].
    #[must_use]
    pub fn without(&self, terms: &Terms, r: usize, kind: EffectKind) -> Option<Terms> {
        let rest: Vec<usize> =
            terms.0.iter().copied().filter(|&c| !(self.candidates[c].row == r && self.candidates[c].kind == kind)).collect();
        (rest.len() < terms.0.len()).then_some(Terms(rest))
    }

    /// `other_terms`, a reading of `other` (the same model and rows on other samples: the
    /// whole recording's problem and the training part's), as a reading of this problem; None
    /// when the two problems' candidates differ. How the training part is given the whole
    /// recording's reading, to replay it ([`super::effort_mode`]).
    #[must_use]
    pub fn read_as(&self, other: &EffortProblem<'_>, other_terms: &Terms) -> Option<Terms> {
        let same = self.candidates.len() == other.candidates.len()
            && self
                .candidates
                .iter()
                .zip(&other.candidates)
                .all(|(a, b)| a.row == b.row && a.kind == b.kind && a.asymmetric == b.asymmetric);
        same.then(|| other_terms.clone())
    }

    /// `terms` with row r's friction read the other way, when it holds exactly one of dry
    /// friction and viscous damping: the other law in its place (its variant with the least
    /// held-out error, the other terms kept). None when the row holds both or neither, or no
    /// variant of the other law passes the selection rules beside the other terms. On a fast joint a dry friction law smooth over a wide
    /// transition and viscous damping fit the efforts nearly alike; what tells them apart is
    /// how the motion they predict goes on ([`super::effort_mode`] replays both).
    #[must_use]
    pub fn other_friction_reading(&self, terms: &Terms, r: usize) -> Option<Terms> {
        let (from, to) = if self.friction_law(terms, r)? == EffectKind::ViscousDamping {
            (Family::Viscous, Family::Friction)
        } else {
            (Family::Friction, Family::Viscous)
        };
        let rest: Vec<usize> =
            terms.0.iter().copied().filter(|&c| !(self.candidates[c].row == r && self.candidates[c].family == from)).collect();
        let rest_fit = self.evaluate(&rest);
        let other = |c: usize| self.candidates[c].family == to && self.may_enter(&rest, c);
        // The other law must be a term the rules accept beside the rest.
        let passes = |c: usize, e: &Evaluation| self.passes(&self.verdict(&rest_fit, e, &self.rows_of(c), c, None));
        self.best_in_place(&rest, r, other, passes).map(|mut v| {
            v.set.sort_unstable();
            Terms(v.set)
        })
    }

    /// The findings of `terms`: per joint, the terms with jackknife σ, confidence, sizes, the
    /// held-out error before and after, and what was considered and not reported.
    #[must_use]
    pub fn findings(&self, terms: &Terms) -> Vec<JointFinding> {
        let chosen = terms.0.clone();
        let k = self.rules.folds.max(2);
        let fitted = self.evaluate(&chosen);
        let mut findings: Vec<JointFinding> = self
            .rows
            .iter()
            .enumerate()
            .map(|(r, info)| {
                let count = self.grams[r].folds.iter().map(|f| f.3).sum::<usize>().max(1) as f64;
                let to_rms = |sse: f64| (sse / count / self.weights[r]).sqrt();
                JointFinding {
                    joint: info.joint,
                    effects: Vec::new(),
                    param_std: Vec::new(),
                    confidence: Vec::new(),
                    effect_rms: Vec::new(),
                    // The model as written: its own first-moment error not fitted either.
                    cv_rms_before: to_rms(self.grams[r].folds.iter().map(|f| f.2.max(0.0)).sum()),
                    cv_rms_after: to_rms(fitted.row_sse(r)),
                    effort_rms: info.effort_rms,
                    gravity_rms: info.gravity_rms,
                    model_correlation: info.model_correlation,
                    residual_before: info.residual.clone(),
                    residual_after: self.residual_after(r, &chosen, &fitted.theta),
                    rejected: Vec::new(),
                    first_moments: self.first_moments_of(r, &fitted.theta),
                    rests_left_out: self.rests.get(r).copied().flatten().map(|h| h.share),
                }
            })
            .collect();
        // A chain joint's inertia beside dry friction is read away from the joint's reversals,
        // where friction turning round adds effort of its shape
        // ([`Self::inertia_only_at_reversals`]); the friction's own shape (its transition, a
        // break-away, a level by direction) lives at the low speeds there, and is read with
        // them. (A joint alone on its body has its levels refined by its exact simulation,
        // where friction sticks and turns round as it does in the recording: effort space's
        // reading is only where that starts.)
        let turning: Vec<usize> =
            self.rows_turning_round(&chosen).into_iter().filter(|&r| in_serial_chain(self.model, self.rows[r].joint)).collect();
        let away = (!turning.is_empty()).then(|| self.fit_away_from_reversals(&chosen, &turning));
        for &c in &chosen {
            let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != c).collect();
            let without = self.evaluate(&rest);
            let v = self.verdict(&without, &fitted, &self.rows_of(c), c, None);
            let cand = &self.candidates[c];
            let (theta, theta_without) = match &away {
                Some((theta, without)) if turning.contains(&cand.row) && cand.kind.adds_inertia() => (theta, without),
                _ => (&fitted.theta, &fitted.theta_without),
            };
            let effect = self.effect_of(c, theta);
            let jack: Vec<Effect> = theta_without.iter().map(|t| self.effect_of(c, t)).collect();
            let std: Vec<f64> =
                (0..effect.params.len()).map(|p| jackknife_sd(&jack.iter().map(|e| e.params[p]).collect::<Vec<f64>>(), k)).collect();
            let f = &mut findings[self.candidates[c].row];
            f.confidence.push((v.fold_share * (1.0 - (-v.gain / 0.03).exp())).clamp(0.0, 1.0));
            f.effect_rms.push(self.term_rms(c, theta));
            f.effects.push(effect);
            f.param_std.push(std);
        }
        self.explain_rejections(&chosen, &fitted, &mut findings);
        findings
    }

    /// The first-moment changes `theta` fits for the bodies row r owns, by body.
    fn first_moments_of(&self, r: usize, theta: &Params) -> Vec<(usize, DVec3)> {
        let mut out: BTreeMap<usize, DVec3> = BTreeMap::new();
        for (c, &(b, axis, owner)) in &self.nuisance {
            if owner == r {
                out.entry(b).or_default()[axis] += theta.get(*c);
            }
        }
        out.into_iter().collect()
    }

    fn residual_after(&self, r: usize, chosen: &[usize], theta: &Params) -> Vec<f64> {
        let cols: Vec<usize> = self.columns_of(chosen).into_iter().filter(|c| self.columns[*c].rows.contains_key(&r)).collect();
        self.rows[r]
            .residual
            .iter()
            .enumerate()
            .map(|(i, res)| res - cols.iter().map(|c| theta[c] * self.columns[*c].rows[&r][i]).filter(|x| x.is_finite()).sum::<f64>())
            .collect()
    }

    /// When candidate c (a rotor's inertia or a heavier part) explains the recording as well as
    /// its chosen look-alike on the same joint, in place of it: what the report should say
    /// about the other reading. The two differ only through gravity's work on the joint; where
    /// that is nil (a knob or turntable turning about its centre of mass, a horizontal drawer),
    /// no recording can tell them apart, and a user who knows the mechanism must choose.
    fn look_alike(&self, chosen: &[usize], fitted: &Evaluation, c: usize) -> Option<String> {
        let cand = &self.candidates[c];
        let twin_kind = match cand.kind {
            EffectKind::Armature => EffectKind::MassScale,
            EffectKind::MassScale => EffectKind::Armature,
            EffectKind::Spring => EffectKind::GravityTilt,
            EffectKind::GravityTilt => EffectKind::Spring,
            _ => return None,
        };
        let &twin = chosen.iter().find(|&&x| self.candidates[x].row == cand.row && self.candidates[x].kind == twin_kind)?;
        let (_, e, rise) = self.as_good_in_place(chosen, fitted, c, twin)?;
        let params = self.effect_of(c, &e.theta).params;
        let (why, reading) = match cand.kind {
            EffectKind::Armature | EffectKind::MassScale => (
                "gravity does next to no work on this joint, so the recording cannot tell a heavier part from a rotor's inertia \
                 (inertia alone is reported as armature, weight unseen)",
                if cand.kind == EffectKind::Armature {
                    format!("a rotor's inertia of {:.3e} kg·m² (or kg)", params[0])
                } else {
                    format!("a part {:.3} × as heavy as modelled", params[0])
                },
            ),
            _ => (
                "over the swing recorded a spring and a tilted axis (a sine of the angle) pull alike; a wider swing tells them apart",
                if cand.kind == EffectKind::Spring {
                    format!("a spring of {:.4} N·m/rad towards {:.3} rad", params[0], params[1])
                } else if cand.is_base_tilt() {
                    format!("the base tilted {:.2}°, the joint pulled towards {:.3} rad", params[0].min(1.0).asin().to_degrees(), params[1])
                } else {
                    format!("a tilted axis whose gravity pulls towards {:.3} rad, {:.4} N·m at its peak", params[1], params[0])
                },
            ),
        };
        Some(format!(
            "explains the recording as well as the reported {} (held-out error {:+.1} %): {why}; the other reading is {reading}",
            twin_kind.name(),
            100.0 * rise
        ))
    }

    /// For every kind not chosen on a joint, its best variant that could have joined the final
    /// model, and why it was not reported. A refinement that would pass but was settled away
    /// ([`Self::settle_refinements`]: its base law was not reported) is named beside its base
    /// law's reason.
    fn explain_rejections(&self, chosen: &[usize], fitted: &Evaluation, findings: &mut [JointFinding]) {
        let mut best: BTreeMap<(usize, EffectKind), (Verdict, usize)> = BTreeMap::new();
        let mut refinements: BTreeMap<usize, (Verdict, usize, Params)> = BTreeMap::new();
        for c in 0..self.candidates.len() {
            let cand = &self.candidates[c];
            if chosen.iter().any(|&x| self.candidates[x].row == cand.row && self.candidates[x].kind == cand.kind) {
                continue;
            }
            let e = self.evaluate(&self.with(chosen, c));
            let v = self.verdict(fitted, &e, &self.rows_of(c), c, self.family_member(chosen, c));
            if self.may_enter(chosen, c) {
                let into = best.entry((cand.row, cand.kind)).or_insert((v, c));
                if v.gain > into.0.gain {
                    *into = (v, c);
                }
            } else if self.passes(&v) && refinements.get(&cand.row).is_none_or(|(rv, _, _)| v.gain > rv.gain) {
                refinements.insert(cand.row, (v, c, e.theta));
            }
        }
        for ((row, kind), (v, c)) in best {
            let refined = refinements.get(&row).filter(|(_, r, _)| self.candidates[*r].family == self.candidates[c].family);
            let why = self.rejection_reason(chosen, fitted, v, c);
            let why = match refined {
                Some((rv, r, theta)) => format!(
                    "{why}; {} would cut the held-out error by {:.0} %, but departs from the same law both ways by no more than \
                     the recording can tell (within two σ, a weight error or a negligible effort), and that law alone does not pass",
                    refinement_text(&self.effect_of(*r, theta)),
                    100.0 * rv.gain
                ),
                None => why,
            };
            findings[row].rejected.push(format!("{}: {why}", kind.name()));
        }
        for (row, note) in self.direction_readings(chosen, fitted) {
            findings[row].rejected.push(note);
        }
    }

    /// Per joint reported with the same friction both ways and an offset: the friction that
    /// differs by direction that explains it as well, as the other reading
    /// ([`Self::prefer_offset_reading`]).
    fn direction_readings(&self, chosen: &[usize], fitted: &Evaluation) -> Vec<(usize, String)> {
        let mut out = Vec::new();
        for &o in chosen.iter().filter(|&&o| self.candidates[o].kind == EffectKind::EffortOffset) {
            let row = self.candidates[o].row;
            let Some(&f) = chosen.iter().find(|&&f| self.candidates[f].row == row && self.candidates[f].family == Family::Friction) else {
                continue;
            };
            let rest: Vec<usize> = chosen.iter().copied().filter(|&x| x != o && x != f).collect();
            let mine = fitted.row_sse(row);
            let by_direction = |x: usize| self.candidates[x].kind == EffectKind::CoulombFriction && self.candidates[x].asymmetric;
            let best = self.best_in_place(&rest, row, by_direction, |_, _| true);
            if let Some(InPlace { candidate: x, fit: e, sse, .. }) =
                best.filter(|v| v.sse <= mine * (1.0 + LOOK_ALIKE_SSE_SHARE) && self.plausible(v.candidate, &v.fit.theta))
            {
                out.push((
                    row,
                    format!(
                        "coulomb_friction with friction_reverse: {} explains the recording as well as the reported {} and \
                         effort_offset (held-out error {:+.1} %): while the joint moves the two are one law, and the reading of robot \
                         identification (the same friction both ways, an offset) is reported",
                        refinement_text(&self.effect_of(x, &e.theta)),
                        self.candidates[f].kind.name(),
                        100.0 * (sse - mine) / mine.max(f64::MIN_POSITIVE)
                    ),
                ));
            }
        }
        out
    }

    /// Why candidate c, with verdict v against the final model, was not reported.
    fn rejection_reason(&self, chosen: &[usize], fitted: &Evaluation, v: Verdict, c: usize) -> String {
        if let Some(why) = self.look_alike(chosen, fitted, c) {
            why
        } else if let Some(why) = &self.candidates[c].unresolved {
            why.clone()
        } else if !v.plausible && self.candidates[c].is_base_tilt() {
            format!(
                "it fits the base tilted beyond {}°, steeper than a robot stands: the tilt would be taking in something else",
                self.rules.max_base_tilt_deg
            )
        } else if !v.plausible {
            format!(
                "its fitted parameters are not physical or not material (a negative level; a part within 10 % of, or far from, its modelled weight; a break-away beyond {}× the sliding friction)",
                self.rules.max_breakaway_ratio
            )
        } else if v.effort_share < self.rules.min_effort_share {
            format!("{:.1} % of the joint's own effort — too small to matter", 100.0 * v.effort_share)
        } else if v.static_share < self.rules.min_static_load_share {
            format!(
                "{:.1} % of the gravity effort the model needs at the joint — an error of the modelled weights and centres of \
                 mass of that size acts the same way (a documented model is rarely better than {:.0} %)",
                100.0 * v.static_share,
                100.0 * self.rules.min_static_load_share
            )
        } else if v.inertial_share < self.rules.min_inertial_load_share {
            format!(
                "{:.1} % of the {} effort the model needs at the joint — an error of the modelled masses and inertias of \
                 that size acts the same way (a documented model is rarely better than {:.0} %)",
                100.0 * v.inertial_share,
                if self.candidates[c].kind == EffectKind::Armature { "inertial" } else { "whole" },
                100.0 * self.rules.min_inertial_load_share
            )
        } else if let Some((effort_share, inertial_share)) = self.inertia_only_at_reversals(&self.with(chosen, c), c) {
            format!(
                "fitted away from the joint's reversals it is {:.1} % of the joint's own and {:.1} % of the {} effort the model \
                 needs: what it stands for is dry friction turning round at the reversals (ahead of or behind the speed's sign), \
                 not inertia",
                100.0 * effort_share,
                100.0 * inertial_share,
                if self.candidates[c].kind == EffectKind::Armature { "inertial" } else { "whole" },
            )
        } else if v.gain < self.rules.min_cv_gain {
            format!("held-out error {:+.1} % — not better on data it was not fitted to", -100.0 * v.gain)
        } else if self.passes(&v) {
            let why_not = if self.shaped_like_model_error(c) {
                format!(
                    "beside the terms first chosen it lay within what an error of the modelled rigid bodies does (under {:.0} % of \
                     the gravity or {:.0} % of the inertial effort the model needs), or a term of its joint's family replaced it",
                    100.0 * self.rules.min_static_load_share,
                    100.0 * self.rules.min_inertial_load_share
                )
            } else {
                "a term of its joint's family replaced it or it was settled away".to_owned()
            };
            format!(
                "beside the reported terms it passes (held-out error {:+.1} %, better in {:.0} % of the blocks), but {why_not}",
                -100.0 * v.gain,
                100.0 * v.fold_share
            )
        } else {
            format!("better in only {:.0} % of the held-out blocks", 100.0 * v.fold_share)
        }
    }
}

/// A refinement of a friction law in a few words.
fn refinement_text(e: &Effect) -> String {
    match e.kind {
        EffectKind::StribeckFriction => format!("Stribeck friction ({:.4} sliding, {:.4} to break away)", e.params[0], e.params[1]),
        _ => format!("friction that differs by direction ({:.4} forward, {:.4} backward)", e.params[0], e.params[2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(values: &[f64], folds: usize, expected: f64) {
        let got = jackknife_sd(values, folds);
        assert!((got - expected).abs() < 1e-12, "{values:?}: {got} vs {expected}");
    }

    #[test]
    fn jackknife_sd_spreads_the_fold_estimates_and_skips_nan() {
        check(&[1.0, 1.0, 1.0], 3, 0.0);
        // √((k − 1)/k · Σ(x − x̄)²) = √(1/2 · 2) = 1.
        check(&[0.0, 2.0], 2, 1.0);
        check(&[0.0, f64::NAN, 2.0], 2, 1.0);
        check(&[], 4, 0.0);
    }

    /// The residual left after granting dry friction of `effects` its static range where the
    /// joint rests, for residuals `residual` at smoothed speeds `speed`.
    fn check_at_rest(effects: Vec<Effect>, residual: &[f64], speed: &[f64], expected: &[f64]) {
        let finding = JointFinding {
            joint: 0,
            param_std: vec![Vec::new(); effects.len()],
            confidence: vec![1.0; effects.len()],
            effect_rms: vec![1.0; effects.len()],
            effects,
            cv_rms_before: 2.0,
            cv_rms_after: 1.0,
            effort_rms: 5.0,
            gravity_rms: 0.0,
            model_correlation: 1.0,
            residual_before: residual.to_vec(),
            residual_after: residual.to_vec(),
            rejected: Vec::new(),
            first_moments: Vec::new(),
            rests_left_out: None,
        };
        let got = finding.with_friction_at_rest(speed);
        assert_eq!(got.residual_after, expected);
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        assert!((got.cv_rms_after - rms(expected) / rms(residual)).abs() < 1e-12, "{}", got.cv_rms_after);
    }

    #[test]
    fn a_drawer_stuck_under_its_friction_leaves_no_unknown_effort() {
        // Regression: a loaded drawer (DART, exact sticking) pushed at 3–6 N under its 6 N dry
        // friction for most of its recording was reported with an `unknown` of 1.7 N beside the
        // friction found: the smooth law gives no force at rest, the stuck joint's friction does.
        let coulomb = |forward: f64, reverse: f64| Effect {
            kind: EffectKind::CoulombFriction,
            params: vec![forward, 0.02, reverse],
            blocks_upward: false,
        };
        check_at_rest(vec![coulomb(6.0, f64::NAN)], &[4.0, -5.0, 7.0, 3.0], &[0.0, 0.0, 0.0, 0.5], &[0.0, 0.0, 1.0, 3.0]);
        // The larger level of a direction-dependent friction bounds what holds it.
        check_at_rest(vec![coulomb(2.0, 4.0)], &[3.0, -5.0], &[0.0, 0.0], &[0.0, -1.0]);
        // Without dry friction nothing changes.
        let damping = Effect { kind: EffectKind::ViscousDamping, params: vec![1.0], blocks_upward: false };
        check_at_rest(vec![damping], &[4.0, -5.0], &[0.0, 0.0], &[4.0, -5.0]);
    }

    /// Whether a joint moving as `position(t)` (200 Hz, 10 s) slides within `zone` for the
    /// filter's span at a stretch.
    fn check_slides(position: &dyn Fn(f64) -> f64, zone: (f64, f64), expected: bool) {
        let time_s: Vec<f64> = (0..2000).map(|i| f64::from(i) / 200.0).collect();
        let q = vec![time_s.iter().map(|&t| position(t)).collect::<Vec<f64>>()];
        let band = bandwidth(&time_s, &q, 0.05, 5.0);
        let sig = signals(&time_s, &q, &[None], &band);
        assert_eq!(slides_within(&sig, 0, &sig.usable, zone), expected, "zone {zone:?}, span {} s", band.support_s());
    }

    #[test]
    fn a_stribeck_law_needs_slow_sliding_not_only_turns() {
        // Regression: MuJoCo's friction loss on a UR5e's elbow, an exact Coulomb law that holds
        // the joint a moment where it turns, was named a Stribeck law breaking away at 1.5× its
        // level; the multisine only passed through the low speeds at its turns.
        let swing = |t: f64| 0.8 * (1.3 * t).sin() + 0.3 * (3.1 * t).sin();
        check_slides(&swing, (0.015, 0.05), false);
        // A slow pull at 0.03 rad/s for 2 s between two swings slides there.
        let pull = |t: f64| if t < 4.0 { 0.5 * (1.3 * t).sin() } else { 0.5 * (5.2_f64).sin() + 0.03 * (t - 4.0).min(2.0) };
        check_slides(&pull, (0.015, 0.05), true);
        // The same pull backwards, and not at speeds outside the zone.
        check_slides(&|t| -pull(t), (0.015, 0.05), true);
        check_slides(&pull, (0.05, 0.2), false);
    }

    const TWO_LINK_ARM: &str = r#"<robot name="arm"><link name="base"/>
          <link name="upper"><inertial><origin xyz="0 0 -0.15"/><mass value="1.2"/><inertia ixx="0.01" iyy="0.01" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <link name="fore"><inertial><origin xyz="0 0 -0.12"/><mass value="0.7"/><inertia ixx="0.005" iyy="0.005" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
          <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0 0 -0.3"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
        </robot>"#;

    /// The effort problem of a two-link arm swinging in a vertical plane (10 s at 200 Hz),
    /// analysed with `model`, its efforts those of the tree `truth` with Coulomb friction 0.3 on
    /// both joints.
    fn two_link_problem<'m>(model: &'m GapModel, truth: &MultiBody, rules: SelectionRules) -> EffortProblem<'m> {
        two_link_problem_noisy(model, truth, rules, 0.0, 0.0)
    }

    /// [`two_link_problem`] with viscous damping `damping` on both joints besides the friction,
    /// and seeded white noise of `noise_sd` N·m on both efforts (a torque sensor's).
    fn two_link_problem_noisy<'m>(
        model: &'m GapModel,
        truth: &MultiBody,
        rules: SelectionRules,
        damping: f64,
        noise_sd: f64,
    ) -> EffortProblem<'m> {
        two_link_problem_with(model, truth, rules, damping, noise_sd, &|_, _| 0.0, &[])
    }

    /// [`two_link_problem_noisy`] with `extra(dof, [position, speed, acceleration])` added to
    /// each effort (an offset, a spring, a friction law of another shape, a rotor), and `rests`
    /// ([`Exclusions::rests`]: the rows whose rests are left out, none of their samples here).
    fn two_link_problem_with<'m>(
        model: &'m GapModel,
        truth: &MultiBody,
        rules: SelectionRules,
        damping: f64,
        noise_sd: f64,
        extra: &dyn Fn(usize, [f64; 3]) -> f64,
        rests: &[Option<RestsLeftOut>],
    ) -> EffortProblem<'m> {
        use rand::SeedableRng;
        use rand_distr::Distribution;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let normal = rand_distr::Normal::new(0.0, 1.0).expect("unit normal");
        let time_s: Vec<f64> = (0..2000).map(|i| f64::from(i) / 200.0).collect();
        let q: Vec<Vec<f64>> = [(0.7, 1.3), (0.5, 2.1)]
            .iter()
            .map(|&(a, w)| time_s.iter().map(|&t| a * (w * t).sin() + 0.2 * (2.9 * w * t).cos()).collect())
            .collect();
        let gravity = DVec3::new(0.0, 0.0, -9.81);
        let motion: Vec<Vec<[f64; 3]>> = q.iter().map(|y| local_cubic(&time_s, y, 0.02)).collect();
        let efforts: Vec<Option<Vec<f64>>> = (0..2)
            .map(|d| {
                Some(
                    (0..time_s.len())
                        .map(|i| {
                            let at = |k: usize| motion.iter().map(|m| m[i][k]).collect::<Vec<f64>>();
                            let tau = truth.inverse_dynamics(&at(0), &at(1), &at(2), gravity)[d];
                            tau + 0.3 * (at(1)[d] / 0.01).tanh()
                                + damping * at(1)[d]
                                + extra(d, [at(0)[d], at(1)[d], at(2)[d]])
                                + noise_sd * normal.sample(&mut rng)
                        })
                        .collect(),
                )
            })
            .collect();
        let band = bandwidth(&time_s, &q, 0.05, 5.0);
        let sig = signals(&time_s, &q, &efforts, &band);
        let rows: Vec<usize> = model.dofs();
        let excluded = Exclusions { samples: vec![vec![false; time_s.len()]; rows.len()], rests: rests.to_vec() };
        let reading = ModelReading::new(model, &sig, gravity, &rows, &rules).expect("reading");
        EffortProblem::new(model, &sig, &reading, &excluded, &vec![true; time_s.len()], rules).expect("problem")
    }

    /// [`EffortProblem::solve`] with its normal equations added up afresh from the rows' Gram
    /// matrices (rows ascending, then folds), not picked from [`NormalSums`].
    fn assembled_solve(problem: &EffortProblem<'_>, cols: &[usize], skip: Option<usize>) -> Vec<f64> {
        let p = cols.len();
        let mut a = vec![0.0; p * p];
        let mut b = vec![0.0; p];
        for g in &problem.grams {
            let m = g.columns.len();
            let local: Vec<(usize, usize)> =
                g.columns.iter().enumerate().filter_map(|(li, c)| cols.binary_search(c).ok().map(|gi| (li, gi))).collect();
            for (_, f) in g.folds.iter().enumerate().filter(|(k, _)| Some(*k) != skip) {
                for &(la, ga) in &local {
                    b[ga] += f.1[la];
                    for &(lb, gb) in &local {
                        a[ga * p + gb] += f.0[la * m + lb];
                    }
                }
            }
        }
        for (i, &c) in cols.iter().enumerate() {
            a[i * p + i] += 1e-9 * a[i * p + i] + 1e-300 + problem.columns[c].precision;
        }
        solve_spd(&a, &b, p).expect("normal equations positive definite")
    }

    /// The first candidate of `kind` on effort row `row`.
    fn first_candidate(problem: &EffortProblem<'_>, row: usize, kind: EffectKind) -> usize {
        (0..problem.candidates.len()).find(|&c| problem.candidates[c].row == row && problem.candidates[c].kind == kind).expect("candidate")
    }

    fn two_link_model() -> GapModel {
        super::super::model::parse_model(TWO_LINK_ARM, std::path::Path::new("arm.urdf")).expect("model")
    }

    #[test]
    fn blocks_solved_apart_give_the_joint_solve_and_a_heavier_part_couples_its_joints() {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        // Without the model's own first-moment error, which couples every joint of a chain.
        let rules = SelectionRules { first_moment_tolerance: 0.0, ..SelectionRules::default() };
        let problem = two_link_problem(&model, &tree, rules);
        let first_of = |row: usize, kind: EffectKind| first_candidate(&problem, row, kind);
        // The forearm's heavier part loads the shoulder too: one block with both joints' terms.
        let heavier = first_of(1, EffectKind::MassScale);
        assert_eq!(problem.rows_of(heavier), vec![0, 1]);
        let coupled = [first_of(0, EffectKind::CoulombFriction), first_of(1, EffectKind::ViscousDamping), heavier];
        let apart = [first_of(0, EffectKind::CoulombFriction), first_of(1, EffectKind::ViscousDamping)];
        for (set, blocks) in [(&coupled[..], 1), (&apart[..], 2)] {
            let cols = problem.columns_of(set);
            assert_eq!(problem.blocks_of(&cols).len(), blocks, "{set:?}");
            // One solve over every column at once, the whole Gram matrix assembled from the rows'.
            let joint_solve = |skip: Option<usize>| assembled_solve(&problem, &cols, skip);
            let got = problem.evaluate(set);
            for (k, without) in got.theta_without.iter().enumerate() {
                let want = joint_solve(Some(k));
                for (i, c) in cols.iter().enumerate() {
                    assert_eq!(without[c].to_bits(), want[i].to_bits(), "fold {k}, column {c}");
                }
            }
            let want = joint_solve(None);
            assert!(cols.iter().enumerate().all(|(i, c)| got.theta[c].to_bits() == want[i].to_bits()));
            // Asked again (now from the cache), the same numbers.
            let again = problem.evaluate(set);
            assert_eq!(again.fold_sse, got.fold_sse);
            assert_eq!(again.theta, got.theta);
        }
        // The friction put in explains the shoulder: its fitted level is the one put in.
        let fit = problem.evaluate(&[first_of(0, EffectKind::CoulombFriction), first_of(1, EffectKind::CoulombFriction)]);
        let level = problem.effect_of(first_of(0, EffectKind::CoulombFriction), &fit.theta).params[0];
        assert!((level - 0.3).abs() < 0.03, "shoulder friction {level}");
        // With it, the forearm's first moment loads both joints: one block for any terms.
        let with_accuracy = two_link_problem(&model, &tree, SelectionRules::default());
        assert_eq!(with_accuracy.nuisance.len(), 4, "two axes of each link: along the joints' axis gravity does nothing");
        assert_eq!(with_accuracy.blocks_of(&with_accuracy.columns_of(&apart)).len(), 1);
    }

    /// Forward selection run again with more bans (as [`EffortProblem::select`] does) reuses
    /// the steps the earlier run weighed through the sets both pass; the terms are those a
    /// problem that never ran the earlier selection chooses under the same bans. Here the ban
    /// is the term the first step chose: the reused step takes the next best from what passed.
    #[test]
    fn a_step_weighed_under_fewer_bans_chooses_as_weighing_it_again_would() {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let problem = || two_link_problem_noisy(&model, &tree, SelectionRules::default(), 0.05, 0.01);
        let (earlier, fresh) = (problem(), problem());
        let none = vec![false; earlier.candidates.len()];
        let first = earlier.select_without(&none);
        let entered = earlier.best_step(&[], &earlier.evaluate(&[]), &none, false).expect("a first step").0;
        assert!(first.len() >= 2, "{first:?}");
        let mut banned = none.clone();
        banned[entered] = true;
        let again = earlier.select_without(&banned);
        let reused = earlier.steps.lock().expect("steps")[&(Vec::new(), false)].banned == none;
        assert!(reused, "the first step was weighed again");
        assert_eq!(again, fresh.select_without(&banned));
        assert!(!again.contains(&entered));
    }

    /// The rows' Gram matrices are summed pair by pair over each fold's samples gathered apart
    /// (`row_gram`): bit for bit the sums of one pass sample by sample, which the findings of
    /// earlier releases were made from.
    #[test]
    fn grams_summed_pair_by_pair_are_the_sums_sample_by_sample_bit_for_bit() {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let problem = two_link_problem_noisy(&model, &tree, SelectionRules::default(), 0.05, 0.01);
        let k = problem.rules.folds.max(2);
        for (r, g) in problem.grams.iter().enumerate() {
            let m = g.columns.len();
            assert!(m > 20, "row {r}: {m} columns");
            let values: Vec<&Vec<f64>> = g.columns.iter().map(|&c| &problem.columns[c].rows[&r]).collect();
            let w = problem.weights[r];
            let mut want = vec![(vec![0.0; m * m], vec![0.0; m], 0.0, 0usize); k];
            for (i, &res) in problem.rows[r].residual.iter().enumerate() {
                if !problem.used[r][i] || !res.is_finite() {
                    continue;
                }
                let phi: Vec<f64> = values.iter().map(|v| if v[i].is_finite() { v[i] } else { 0.0 }).collect();
                let f = &mut want[problem.fold_of[i]];
                for a in 0..m {
                    f.1[a] += w * phi[a] * res;
                    for b in 0..m {
                        f.0[a * m + b] += w * phi[a] * phi[b];
                    }
                }
                f.2 += w * res * res;
                f.3 += 1;
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
            for (fold, (got, want)) in g.folds.iter().zip(&want).enumerate() {
                // The lower triangle mirrors the upper one, as the normal equations read it.
                let upper = |x: &[f64]| (0..m * m).map(|ij| x[(ij / m).min(ij % m) * m + (ij / m).max(ij % m)]).collect::<Vec<f64>>();
                assert_eq!(bits(&got.0), bits(&upper(&want.0)), "row {r}, fold {fold}: Gram");
                assert_eq!(bits(&got.1), bits(&want.1), "row {r}, fold {fold}: c·r");
                assert_eq!((got.2.to_bits(), got.3), (want.2.to_bits(), want.3), "row {r}, fold {fold}: r·r");
            }
        }
    }

    /// Forward selection weighs each candidate by extending the factors of the set it joins
    /// (`evaluate_beside`): the same least squares as fitting the whole set afresh, to rounding,
    /// for a candidate of one column and of two (friction by direction), beside the model's own
    /// accuracy (which puts every column in one block) and beside another joint's heavier part.
    #[test]
    fn a_candidate_weighed_beside_the_chosen_terms_fits_as_the_whole_set_afresh() {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let problem = two_link_problem(&model, &tree, SelectionRules::default());
        let first_of = |row: usize, kind: EffectKind| first_candidate(&problem, row, kind);
        let asymmetric = (0..problem.candidates.len())
            .find(|&c| problem.candidates[c].row == 1 && problem.candidates[c].asymmetric)
            .expect("friction by direction on the forearm");
        assert_eq!(problem.candidates[asymmetric].columns.len(), 2);
        let chosen = [first_of(0, EffectKind::CoulombFriction), first_of(1, EffectKind::MassScale)];
        for c in [first_of(1, EffectKind::ViscousDamping), asymmetric, first_of(0, EffectKind::Armature)] {
            let set = problem.with(&chosen, c);
            let extensions = || problem.bordered_fits.lock().expect("cache").values().filter(|f| f.is_some()).count();
            let extended = extensions();
            let (beside, afresh) = (problem.evaluate_beside(&set, c, &problem.rows_of(c)), problem.evaluate(&set));
            assert_eq!(extensions(), extended + 1, "candidate {c}: not fitted by extension");
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()));
            for col in problem.columns_of(&set) {
                assert!(close(beside.theta[&col], afresh.theta[&col]), "candidate {c}, column {col}");
            }
            // What weighing reads: the candidate's rows' held-out error, fold by fold.
            for r in problem.rows_of(c) {
                for (x, y) in beside.fold_sse[r].iter().zip(&afresh.fold_sse[r]) {
                    assert!(close(*x, *y), "candidate {c}, row {r}: held-out error {x} against {y}");
                }
            }
            assert!(beside.theta_without.is_empty());
            assert!(beside.theta[&problem.candidates[c].columns[0]].abs() > 0.0, "candidate {c} fitted");
        }
    }

    /// A model whose forearm's centre of mass is 6 mm off the arm's (3 mm aside and 5 mm lower,
    /// within the 5 % of its first moment the model is trusted to): its gravity error is fitted
    /// as the model's accuracy, the friction comes out as put in, nothing of the error's shape is
    /// named, and the fitted first moment points the way the true one does, pulled towards the
    /// model by its prior (here to about a third: the efforts' residual scale weighs the data,
    /// one piece per filter width).
    #[test]
    fn a_centre_of_mass_off_is_the_models_accuracy_not_an_offset_or_a_spring() {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let fore = tree.bodies().iter().position(|b| b.name == "fore").expect("forearm");
        let true_shift = DVec3::new(0.003, 0.0, -0.005);
        let truth = tree.with_first_moment_added(fore, 0.7 * true_shift);
        let problem = two_link_problem(&model, &truth, SelectionRules::default());
        let terms = problem.chosen_terms();
        let findings = problem.findings(&terms);
        for f in &findings {
            let kinds: Vec<EffectKind> = f.effects.iter().map(|e| e.kind).collect();
            assert_eq!(kinds, vec![EffectKind::CoulombFriction], "joint {}: {:?}", f.joint, f.effects);
            assert!((f.effects[0].params[0] - 0.3).abs() < 0.03, "joint {}: {:?}", f.joint, f.effects[0]);
        }
        // The forearm belongs to the elbow. Along the joints' axis (y) gravity says nothing.
        let fitted: Vec<(usize, DVec3)> = findings.iter().flat_map(|f| f.first_moments.iter().copied()).collect();
        let (_, h) = fitted.iter().find(|(b, _)| *b == fore).expect("the forearm's first moment");
        let got = *h / 0.7;
        let cosine = got.dot(true_shift) / (got.length() * true_shift.length()).max(1e-12);
        assert!(
            cosine > 0.9 && got.length() > 0.2 * true_shift.length() && got.length() < true_shift.length(),
            "{got:?} against {true_shift:?}"
        );
    }

    /// `check` of the two-link arm's problem (efforts damped by `damping`, white noise of
    /// `noise_sd` N·m) and the terms Coulomb friction on both joints and damping on the elbow.
    fn with_friction_and_elbow_damping<T>(damping: f64, noise_sd: f64, check: impl FnOnce(&EffortProblem<'_>, &Terms) -> T) -> T {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let rules = SelectionRules { first_moment_tolerance: 0.0, ..SelectionRules::default() };
        let problem = two_link_problem_noisy(&model, &tree, rules, damping, noise_sd);
        let first_of = |row: usize, kind: EffectKind| first_candidate(&problem, row, kind);
        let mut set = vec![
            first_of(0, EffectKind::CoulombFriction),
            first_of(1, EffectKind::CoulombFriction),
            first_of(1, EffectKind::ViscousDamping),
        ];
        set.sort_unstable();
        check(&problem, &Terms(set))
    }

    /// What [`EffortProblem::physical_reading`] keeps of Coulomb friction on both joints and
    /// damping on the elbow, the arm's efforts damped by `damping`: the kinds kept on the elbow,
    /// and the share of a damping dropped as immaterial.
    fn check_material(damping: f64, kept: &[EffectKind], dropped_share_under: Option<f64>) {
        with_friction_and_elbow_damping(damping, 0.0, |problem, set| check_material_of(problem, set, damping, kept, dropped_share_under));
    }

    fn check_material_of(problem: &EffortProblem<'_>, set: &Terms, damping: f64, kept: &[EffectKind], dropped_share_under: Option<f64>) {
        let (reading, dropped) = problem.physical_reading(set);
        let elbow: Vec<EffectKind> =
            reading.0.iter().filter(|&&c| problem.candidates[c].row == 1).map(|&c| problem.candidates[c].kind).collect();
        assert_eq!(elbow, kept, "damping {damping}: dropped {dropped:?}");
        match dropped_share_under {
            Some(limit) => {
                let [(1, EffectKind::ViscousDamping, Some(share))] = dropped[..] else { panic!("damping {damping}: {dropped:?}") };
                assert!(share > 0.0 && share < limit, "damping {damping}: share {share}");
            }
            None => assert!(dropped.is_empty(), "damping {damping}: {dropped:?}"),
        }
    }

    /// Whether the elbow's damping, fitted beside Coulomb friction on both joints, is among
    /// [`EffortProblem::unresolved_terms`] for an arm damped by `damping` whose efforts carry
    /// white noise of `noise_sd`.
    fn check_resolved(damping: f64, noise_sd: f64, unresolved: bool) {
        let (elbow_damping, found) = with_friction_and_elbow_damping(damping, noise_sd, |problem, set| {
            let found = problem.unresolved_terms(set);
            (found.iter().copied().find(|(r, kind, _, _)| *r == 1 && *kind == EffectKind::ViscousDamping), found)
        });
        assert_eq!(elbow_damping.is_some(), unresolved, "damping {damping}, noise {noise_sd}: {found:?}");
        // Friction far above the noise is resolved either way.
        assert!(found.iter().all(|(_, kind, _, _)| *kind != EffectKind::CoulombFriction), "{found:?}");
        if let Some((_, _, level, sd)) = elbow_damping {
            assert!(level.abs() < 2.0 * sd, "level {level} ± {sd}");
        }
    }

    #[test]
    fn a_level_the_folds_cannot_tell_from_none_is_unresolved() {
        // Regression: MuJoCo's Panda read a damping of 0.046 ± 0.025 N·m·s/rad beside a wrist's
        // dry friction, entered on a held-out cut the folds shared.
        check_resolved(0.0, 0.2, true);
        // Damping the efforts show stays, through the same noise.
        check_resolved(0.3, 0.2, false);
    }

    #[test]
    fn a_term_the_final_fit_shrinks_below_any_terms_size_is_not_reported() {
        // Regression: Drake's iiwa against a 5 %-off model kept a damping of 0.0033 ± 0.18
        // N·m·s/rad, 0.1 % of its joint's effort, beside dry friction whose transition a later
        // stage had sharpened; every term had to be 3 % to enter.
        check_material(0.003, &[EffectKind::CoulombFriction], Some(0.03));
        // A damping that matters stays.
        check_material(0.3, &[EffectKind::CoulombFriction, EffectKind::ViscousDamping], None);
    }

    /// The kinds chosen on the two-link arm's elbow when `extra([position, speed,
    /// acceleration])` is added to its effort, the model's own first-moment error not fitted.
    fn check_elbow(extra: &dyn Fn([f64; 3]) -> f64, expected: &[EffectKind]) {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let rules = SelectionRules { first_moment_tolerance: 0.0, ..SelectionRules::default() };
        let problem = two_link_problem_with(&model, &tree, rules, 0.0, 0.01, &|d, x| if d == 1 { extra(x) } else { 0.0 }, &[]);
        let terms = problem.chosen_terms();
        let findings = problem.findings(&terms);
        let elbow = findings.iter().find(|f| f.joint == model.dofs()[1]).expect("the elbow's finding");
        let kinds: Vec<EffectKind> = elbow.effects.iter().map(|e| e.kind).collect();
        assert_eq!(kinds, expected, "{:?}", elbow.effects);
    }

    #[test]
    fn a_spring_whose_stiffness_does_not_matter_is_an_offset() {
        // Regression: MuJoCo's Panda with the real arm's friction law, against a 5 %-off model,
        // read springs whose constant was all that mattered (0.30 N·m/rad towards 0.62 rad on a
        // shoulder moving over -1.1..-0.45 rad: 0.43 N·m RMS, 0.05 of it from the stiffness).
        // Here the stiffness wins the forward step (it cuts the held-out error beyond the tie
        // margin) but changes the effort by 1.5 % of the elbow's.
        check_elbow(&|x| 0.1 + 0.02 * x[0], &[EffectKind::CoulombFriction, EffectKind::EffortOffset]);
        // A spring whose stiffness the efforts show stays one.
        check_elbow(&|x| 0.4 * (x[0] - 0.1), &[EffectKind::CoulombFriction, EffectKind::Spring]);
    }

    /// The elbow's 0.3 N·m of dry friction turning round `lead_s` ahead of its speed's sign
    /// (`MuJoCo`'s regularised friction loss turns at v + a·τ = 0), plus a rotor of `armature`.
    fn turning_ahead(lead_s: f64, armature: f64) -> impl Fn([f64; 3]) -> f64 {
        move |x: [f64; 3]| 0.3 * (((x[1] + lead_s * x[2]) / 0.01).tanh() - (x[1] / 0.01).tanh()) + armature * x[2]
    }

    #[test]
    fn dry_friction_turning_ahead_of_the_speed_is_not_a_rotor() {
        // Regression: MuJoCo's Panda with 2 N·m of friction loss on joint 4 and no rotor read an
        // armature of 0.041 kg·m² beside the friction (0.023 away from the joint's reversals).
        check_elbow(&turning_ahead(0.01, 0.0), &[EffectKind::CoulombFriction]);
        // A rotor (a fifth of the forearm's inertia about the elbow) acts at every acceleration,
        // away from the reversals too, and stays.
        check_elbow(&turning_ahead(0.01, 0.003), &[EffectKind::CoulombFriction, EffectKind::Armature]);
    }

    #[test]
    fn a_distal_heavier_part_standing_in_for_a_proximal_offset_is_swapped_out() {
        // A heavier forearm loads the shoulder too, so taken first it can stand in for the
        // shoulder's own sensor bias; in its place the bias explains both joints better.
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let rules = SelectionRules { first_moment_tolerance: 0.0, ..SelectionRules::default() };
        let problem = two_link_problem_with(&model, &tree, rules, 0.0, 0.01, &|d, _| if d == 0 { 0.4 } else { 0.0 }, &[]);
        let first_of = |row: usize, kind: EffectKind| first_candidate(&problem, row, kind);
        let friction = [first_of(0, EffectKind::CoulombFriction), first_of(1, EffectKind::CoulombFriction)];
        let none = vec![false; problem.candidates.len()];
        let check = |start: &[usize], expected: &[usize]| {
            let mut chosen = start.to_vec();
            let mut current = problem.evaluate(&chosen);
            let swapped = problem.replace(&mut chosen, &mut current, &none);
            chosen.sort_unstable();
            let mut want = expected.to_vec();
            want.sort_unstable();
            assert_eq!(chosen, want, "from {start:?}");
            assert_eq!(swapped, start != expected);
        };
        let offset = first_of(0, EffectKind::EffortOffset);
        check(&[friction[0], friction[1], first_of(1, EffectKind::MassScale)], &[friction[0], friction[1], offset]);
        // The right terms stay as they are.
        check(&[friction[0], friction[1], offset], &[friction[0], friction[1], offset]);
    }

    #[test]
    fn samples_near_a_reversal_of_the_speed_are_marked() {
        let time_s: Vec<f64> = (0..10).map(f64::from).collect();
        let check = |speed: &[f64], half_width_s: f64, expected: &[usize]| {
            let near = near_reversals(&time_s, speed, half_width_s);
            let got: Vec<usize> = (0..near.len()).filter(|&i| near[i]).collect();
            assert_eq!(got, expected, "{speed:?} ± {half_width_s}");
        };
        // A change of sign between samples 4 and 5 sits at 4.5.
        check(&[1.0, 1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0, -1.0], 1.5, &[3, 4, 5, 6]);
        // An exact zero is a reversal at its sample; a missing speed is skipped over.
        check(&[1.0, 1.0, 0.0, 1.0, 1.0, f64::NAN, -1.0, -1.0, -1.0, -1.0], 1.0, &[1, 2, 3, 4, 5, 6]);
        check(&[1.0; 10], 5.0, &[]);
    }

    /// The transition speeds of row r's Coulomb candidates, sorted, duplicates removed.
    fn coulomb_transitions(problem: &EffortProblem<'_>, r: usize) -> Vec<f64> {
        let mut out: Vec<f64> =
            problem.candidates.iter().filter(|c| c.row == r && c.kind == EffectKind::CoulombFriction).map(|c| c.hyper[0]).collect();
        out.sort_by(f64::total_cmp);
        out.dedup();
        out
    }

    #[test]
    fn a_row_read_without_its_rests_keeps_the_transition_read_with_them() {
        let model = two_link_model();
        let (tree, _) = model.multibody().expect("tree");
        let held = RestsLeftOut { transition_speed: 0.037, share: 0.4 };
        let problem = two_link_problem_with(&model, &tree, SelectionRules::default(), 0.0, 0.01, &|_, _| 0.0, &[None, Some(held)]);
        // The shoulder's rests stay: it tries the whole grid; the elbow only the speed it kept.
        assert!(coulomb_transitions(&problem, 0).len() > 3);
        assert_eq!(coulomb_transitions(&problem, 1), vec![0.037]);
        let findings = problem.findings(&problem.chosen_terms());
        assert_eq!(findings.iter().map(|f| f.rests_left_out).collect::<Vec<_>>(), vec![None, Some(0.4)]);
    }
}
