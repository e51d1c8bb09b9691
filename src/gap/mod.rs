//! The reality gap (issue 5): when a recording of the real object disagrees with simulation of
//! the model, find where and why, fit the missing physics and prove it on held-out data.
//!
//! `recording` reads the CSV (spec `gap-recording.md`), `model` the URDF, `observe` turns columns
//! and tracked poses into joint positions, `sim` is the fitter's 1-DoF integrator, `effects` the
//! library of candidate terms, `locate` the noise estimate and change-point search, `fit` the
//! multiple-shooting output-error LM, `select` the BIC model selection, `report` the JSON and
//! fitted model, `plot` the SVG figures, `generate` recordings with concealed effects (different
//! physics code: RK4 with event location) for tests and demos.

pub mod accuracy;
pub mod bench;
pub mod chain;
pub mod effects;
pub mod effort;
mod effort_mode;
pub mod error;
pub mod fit;
pub mod generate;
mod held_out;
pub mod locate;
#[cfg(not(target_arch = "wasm32"))]
pub mod mcap;
pub mod model;
pub mod observe;
pub mod plot;
pub mod recording;
pub mod report;
pub mod rests;
pub mod select;
pub mod sim;
pub mod smooth;
pub mod stops;
pub mod tilt;

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

pub use effects::{Effect, EffectKind, JointPhysics};
pub use error::GapError;
pub use model::{GapModel, load_model, parse_model};
pub use recording::{Recording, parse_recording, read_recording};
pub use report::{EffectReport, GapReport, JointSeries, Mismatch, RmsePair};

use effort_mode::analyze_effort_space;
use locate::{Span, mismatch_spans, noise_sigma, rmse_over};
use report::{Conditions, FitSummary, HeldOut};
use sim::SimInput;

/// Analysis settings.
#[derive(Debug, Clone)]
pub struct GapConfig {
    /// Share of the recording (at the end) held out for validation.
    pub held_out_fraction: f64,
    /// Most effects per joint.
    pub max_terms: usize,
    /// Shortest mismatch, samples.
    pub min_mismatch_samples: usize,
    /// Name of the fitted URDF written beside the report.
    pub fitted_model_name: String,
}

impl Default for GapConfig {
    fn default() -> Self {
        Self { held_out_fraction: 0.3, max_terms: 3, min_mismatch_samples: 10, fitted_model_name: "model.fitted.urdf".into() }
    }
}

struct JointOutcome {
    mismatches: Vec<Mismatch>,
    effects: Vec<EffectReport>,
    all: RmsePair,
    held: RmsePair,
    sq: (f64, f64, usize),
    series: JointSeries,
    analysis: report::JointAnalysis,
}

/// Analyses a recording against a model: mismatches, effects, fit, held-out validation, series.
///
/// Each joint goes in one of two ways, chosen from what the recording holds: **effort space**
/// ([`effort`]) for joints whose effort is recorded while every joint of the model has its
/// position recorded, a subtree no column measures welded at 0 (inverse dynamics of the whole
/// tree gives the residual effort), **position
/// space** ([`fit`], [`select`]) for the others (simulation of the joint, the recorded motion of
/// the other joints driving it through the coupling efforts).
pub fn analyze(model: &GapModel, rec: &Recording, cfg: &GapConfig) -> Result<GapReport, GapError> {
    let dof_names: Vec<&str> = model.dofs().into_iter().map(|j| model.joints[j].name.as_str()).collect();
    let link_names: Vec<&str> = model.links.iter().map(|l| l.name.as_str()).collect();
    rec.check_names(&dof_names, &link_names)?;
    let n = rec.time_s.len();
    if n < 20 {
        return Err(GapError::Analysis { file: rec.file.clone(), message: format!("{n} samples; at least 20 are needed") });
    }
    let observe::Observed { positions: observed, notes: stale_notes } = observe::observed_positions(model, rec)?;
    if observed.is_empty() {
        return Err(GapError::Analysis {
            file: rec.file.clone(),
            message: "no joint of the model is observed (no .q or pose columns)".into(),
        });
    }
    let mut notes = model.notes.clone();
    notes.extend(stale_notes);
    // A subtree nothing measures (a gripper on an arm whose joints alone are logged) is held at
    // 0 wherever the analysis needs its position; effort space carries it welded to its parent,
    // so that the measured joints above it keep their inverse dynamics.
    let observed_joints: Vec<usize> = observed.keys().copied().collect();
    let unobserved_leaves = model.unobserved_subtrees(&observed_joints);
    for &j in &model.dofs() {
        if !observed.contains_key(&j) {
            let welded = if unobserved_leaves.contains(&j) { ", welded to its parent (nothing below it is observed)" } else { "" };
            notes.push(format!("joint {} is not observed: held at 0{welded}", model.joints[j].name));
        }
    }
    let held_still = model.with_welded(&unobserved_leaves);
    let effort_joints = effort_space_joints(&held_still, rec, &observed);
    let read_every;
    let (rec, observed) = match at_working_rate(&held_still, rec, &observed, &effort_joints) {
        Some((working, averaged, note)) => {
            read_every = working;
            notes.push(note);
            (&read_every, averaged)
        }
        None => (rec, observed),
    };
    let n = rec.time_s.len();
    let gravity = DVec3::from_array(rec.gravity_mps2);
    let t_split = rec.time_s[0] + (1.0 - cfg.held_out_fraction) * (rec.time_s[n - 1] - rec.time_s[0]);
    let effort_mode::EffortOutcome { joints: mut outcomes, given, com_shift_m, implausible_accuracy } = if effort_joints.is_empty() {
        effort_mode::EffortOutcome::default()
    } else {
        analyze_effort_space(&held_still, rec, cfg, &observed, &effort_joints, gravity, t_split)?
    };
    notes.extend(accuracy_note(&com_shift_m));
    notes.extend(implausible_accuracy_note(&implausible_accuracy));
    let done: Vec<usize> = outcomes.iter().filter_map(|o| model.joint_index(&o.series.joint)).collect();
    let filled: Vec<Vec<f64>> =
        (0..model.joints.len()).map(|j| observed.get(&j).map_or_else(|| vec![0.0; n], |q| observe::fill_gaps(q))).collect();
    let coupling = coupling_efforts(model, rec, &observed, gravity);
    let jobs: Vec<(usize, &Vec<f64>)> = observed.iter().filter(|(j, _)| !done.contains(j)).map(|(j, q)| (*j, q)).collect();
    let why = position_space_reason(&held_still, rec, &observed);
    outcomes.extend(
        jobs.par_iter()
            .map(|&(j, y)| {
                let mut o = analyze_joint(
                    model,
                    rec,
                    cfg,
                    j,
                    y,
                    &filled,
                    coupling.as_ref().map(|c| c[j].as_slice()),
                    gravity,
                    t_split,
                    given.get(&j),
                );
                if !given.contains_key(&j) {
                    o.analysis.why.clone_from(&why);
                }
                o
            })
            .collect::<Vec<_>>(),
    );
    outcomes.sort_by_key(|o| model.joint_index(&o.series.joint));
    let mut report = assemble_report(cfg, notes, t_split, outcomes);
    report.com_shift_m = com_shift_m;
    Ok(report)
}

/// A recording whose every observed joint is a chain joint of effort space (`effort_joints`),
/// logged far faster than its motion needs, read at a working rate ([`effort::working_step`]):
/// at every step-th sample, each position the mean of the readings around it as observed (stale
/// readings already missing, angles unwrapped; [`observe::centred_means`]), each effort the mean
/// over the holds it stands for ([`Recording::every`]); with the note that says so. A chain's identification costs
/// its samples times its few hundred candidate columns, each through the parallel filter, and
/// the filter's reach in samples grows with the rate too: a real Panda's 21 s at 1 kHz took
/// 19.7 s, its 200 Hz rows 1.6 s, for the same findings. A joint alone on its body keeps every
/// sample: its levels are refined by its exact simulation, which follows the recorded efforts
/// sample by sample (the real DFKI pendulum's 500 Hz swing-up read at 250 Hz replayed 3× worse).
fn at_working_rate(
    model: &GapModel,
    rec: &Recording,
    observed: &std::collections::BTreeMap<usize, Vec<f64>>,
    effort_joints: &[usize],
) -> Option<(Recording, std::collections::BTreeMap<usize, Vec<f64>>, String)> {
    let chains_only = !effort_joints.is_empty()
        && observed.keys().all(|j| effort_joints.contains(j))
        && effort_joints.iter().all(|&j| effort::in_serial_chain(model, j));
    if !chains_only {
        return None;
    }
    let positions: Vec<Vec<f64>> = observed.values().cloned().collect();
    let rules = effort::SelectionRules::default();
    let step = effort::working_step(&rec.time_s, &positions, rules.smoothing_half_width_s, effort_mode::EQUATION_BANDS[0]);
    if step < 2 {
        return None;
    }
    let working = rec.every(step);
    let (n, kept) = (rec.time_s.len(), working.time_s.len());
    let span = (rec.time_s[n - 1] - rec.time_s[0]).max(1e-12);
    let note = format!(
        "the log holds {:.0} samples a second, far more than the chain's motion needs: read at every {step}th sample ({:.0} a \
         second, five or more within the differentiator's half-width), each position the mean of the readings around it, \
         each effort the mean over the holds it stands for",
        (n - 1) as f64 / span,
        (kept.max(2) - 1) as f64 / span,
    );
    let averaged = observed.iter().map(|(&j, q)| (j, observe::centred_means(q, step))).collect();
    Some((working, averaged, note))
}

/// The note that says how far effort space moved each link's centre of mass as the model's own
/// accuracy ([`accuracy`]); none when it moved none.
fn accuracy_note(com_shift_m: &std::collections::BTreeMap<String, [f64; 3]>) -> Option<String> {
    (!com_shift_m.is_empty()).then(|| {
        let moved: Vec<String> =
            com_shift_m.iter().map(|(link, d)| format!("{link} {:.1} mm", 1e3 * DVec3::from_array(*d).length())).collect();
        format!(
            "the model's centres of mass were fitted beside the effects as its own accuracy (a prior of {:.0} % of each \
             link's first moment, not reported as effects; written into the fitted URDF): {}",
            100.0 * effort::SelectionRules::default().first_moment_tolerance,
            moved.join(", ")
        )
    })
}

/// The note that says the model's rigid bodies do not describe the recording, naming the links
/// whose fitted first-moment error no model's accuracy allows; none when every link's is within
/// it.
fn implausible_accuracy_note(links: &std::collections::BTreeMap<String, (f64, f64)>) -> Option<String> {
    (!links.is_empty()).then(|| {
        let moved: Vec<String> =
            links.iter().map(|(link, (shift_m, sigmas))| format!("{link} {:.1} mm ({sigmas:.0} σ)", 1e3 * shift_m)).collect();
        format!(
            "the model's rigid bodies do not describe this recording: to explain its efforts, centres of mass had to move \
             beyond {:.0} σ of the model's accuracy ({:.0} % of each link's first moment, or of its mass × 5 cm): {}. A \
             different robot or payload, \
             efforts that are not the joints' own (units, sign, a gear ratio), or a log that does not resolve the motion; \
             the effects named beside them are doubtful",
            effort::SelectionRules::default().first_moment_implausible_sigmas,
            100.0 * effort::SelectionRules::default().first_moment_tolerance,
            moved.join(", ")
        )
    })
}

fn assemble_report(cfg: &GapConfig, notes: Vec<String>, t_split: f64, outcomes: Vec<JointOutcome>) -> GapReport {
    let mut report = GapReport {
        format: report::REPORT_FORMAT,
        mismatches: Vec::new(),
        effects: Vec::new(),
        fit: FitSummary::default(),
        fitted_model: cfg.fitted_model_name.clone(),
        held_out: HeldOut { t_start: t_split, per_joint: std::collections::BTreeMap::default() },
        noise_sigma: std::collections::BTreeMap::default(),
        notes,
        joints: std::collections::BTreeMap::default(),
        com_shift_m: std::collections::BTreeMap::default(),
        series: Vec::new(),
    };
    let (mut sb, mut sa, mut count) = (0.0, 0.0, 0usize);
    for o in outcomes {
        let name = o.series.joint.clone();
        report.fit.per_joint.insert(name.clone(), o.all);
        report.held_out.per_joint.insert(name.clone(), o.held);
        report.noise_sigma.insert(name.clone(), o.series.noise_sigma);
        report.joints.insert(name, o.analysis);
        report.mismatches.extend(o.mismatches);
        report.effects.extend(o.effects);
        sb += o.sq.0;
        sa += o.sq.1;
        count += o.sq.2;
        report.series.push(o.series);
    }
    let c = count.max(1) as f64;
    (report.fit.rmse_before, report.fit.rmse_after) = ((sb / c).sqrt(), (sa / c).sqrt());
    report.mismatches.sort_by(|a, b| b.rmse.total_cmp(&a.rmse).then_with(|| a.joint.cmp(&b.joint)));
    report
}

/// Joints analysed in effort space: every degree of freedom of the model observed (inverse
/// dynamics needs the whole tree's motion; `model` has its unobserved subtrees welded) and every
/// applied effort known — recorded, or zero
/// where the recording has no effort column (spec §2: such a joint has zero applied effort, as a
/// released door or a swinging pendulum has).
fn effort_space_joints(model: &GapModel, _rec: &Recording, observed: &std::collections::BTreeMap<usize, Vec<f64>>) -> Vec<usize> {
    let dofs = model.dofs();
    if !dofs.iter().all(|j| observed.contains_key(j)) {
        return Vec::new();
    }
    dofs
}

fn position_space_reason(model: &GapModel, rec: &Recording, observed: &std::collections::BTreeMap<usize, Vec<f64>>) -> String {
    let unobserved: Vec<&str> =
        model.dofs().into_iter().filter(|j| !observed.contains_key(j)).map(|j| model.joints[j].name.as_str()).collect();
    if unobserved.is_empty() {
        // Every joint observed, yet effort space handed the joint on: it spends most of the
        // recording against its stops (or at rest), where inverse dynamics sees only the stop.
        "too little free motion away from its stops for inverse dynamics: its motion is simulated through the stops and fitted".into()
    } else if rec.joint_effort.is_empty() {
        "no effort recorded: its motion is simulated and fitted".into()
    } else {
        format!(
            "joints {} are not observed, so inverse dynamics is not possible: its motion is simulated and fitted",
            unobserved.join(", ")
        )
    }
}

/// Per model joint, per sample: the effort on it from the recorded motion of the other joints
/// (their accelerations and the Coriolis/centrifugal terms), which a 1-DoF replay would drop.
/// None for a one-joint model.
fn coupling_efforts(
    model: &GapModel,
    rec: &Recording,
    observed: &std::collections::BTreeMap<usize, Vec<f64>>,
    gravity: DVec3,
) -> Option<Vec<Vec<f64>>> {
    let dofs = model.dofs();
    if dofs.len() < 2 {
        return None;
    }
    let (tree, _) = model.multibody().ok()?;
    let n = rec.time_s.len();
    let smoothed: Vec<Vec<[f64; 3]>> = dofs
        .iter()
        .map(|j| {
            observed.get(j).map_or_else(
                || vec![[0.0; 3]; n],
                |y| smooth::local_cubic(&rec.time_s, &observe::fill_gaps(y), smooth::DEFAULT_HALF_WIDTH_S),
            )
        })
        .collect();
    let mut out = vec![vec![0.0; n]; model.joints.len()];
    let (mut q, mut qd, mut qdd) = (vec![0.0; dofs.len()], vec![0.0; dofs.len()], vec![0.0; dofs.len()]);
    for i in 0..n {
        for d in 0..dofs.len() {
            let s = smoothed[d][i];
            (q[d], qd[d], qdd[d]) = if s.iter().all(|v| v.is_finite()) { (s[0], s[1], s[2]) } else { (0.0, 0.0, 0.0) };
        }
        let held = tree.inverse_dynamics(&q, &[], &[], gravity);
        for (d, &j) in dofs.iter().enumerate() {
            let mut others = qdd.clone();
            others[d] = 0.0;
            let moving = tree.inverse_dynamics(&q, &qd, &others, gravity);
            out[j][i] = -(moving[d] - held[d]);
        }
    }
    Some(out)
}

fn open_loop_from(input: &SimInput<'_>, physics: &JointPhysics, start: usize, state: (f64, f64)) -> Vec<f64> {
    let n = input.time_s.len();
    let mut out = vec![f64::NAN; n];
    sim::simulate(input, physics, start, n - 1, state.0, state.1, &mut out[start..]);
    out
}

/// RMSE of two replays against the measurement over the samples `keep` selects (both over the
/// samples where the measurement and the first replay are finite), and the squared sums and count
/// behind them (the report's overall RMSE adds them up over joints).
fn rmse_pair(y: &[f64], before: &[f64], after: &[f64], keep: impl Fn(usize) -> bool) -> (RmsePair, (f64, f64, usize)) {
    let (sb, c) = rmse_mask(y, before, &keep);
    let (sa, _) = rmse_mask(y, after, &keep);
    let cf = c.max(1) as f64;
    (RmsePair { rmse_before: (sb / cf).sqrt(), rmse_after: (sa / cf).sqrt() }, (sb, sa, c))
}

fn rmse_mask(y: &[f64], sim: &[f64], keep: impl Fn(usize) -> bool) -> (f64, usize) {
    let (mut s, mut c) = (0.0, 0usize);
    for i in 0..y.len() {
        if keep(i) && y[i].is_finite() && sim[i].is_finite() {
            s += (y[i] - sim[i]).powi(2);
            c += 1;
        }
    }
    (s, c)
}

fn analyze_joint(
    model: &GapModel,
    rec: &Recording,
    cfg: &GapConfig,
    j: usize,
    y: &[f64],
    filled: &[Vec<f64>],
    coupling: Option<&[f64]>,
    gravity: DVec3,
    t_split: f64,
    given: Option<&Given>,
) -> JointOutcome {
    let joint = &model.joints[j];
    let n = y.len();
    let mut config = vec![0.0; model.joints.len()];
    let terms: Vec<model::JointTerms> = (0..n)
        .map(|i| {
            for (c, s) in config.iter_mut().zip(filled) {
                *c = s[i];
            }
            let mut t = model.joint_terms(j, &config, gravity);
            t.coupling = coupling.map_or(0.0, |c| c[i]);
            t
        })
        .collect();
    let effort: Vec<f64> = (0..n).map(|i| rec.effort(&joint.name, i)).collect();
    let input = SimInput { time_s: &rec.time_s, effort: &effort, terms: &terms };
    let sigma = noise_sigma(&rec.time_s, y).max(1e-7);
    let derivs = observe::smoothed_derivatives(&rec.time_s, y, 7);
    let all = vec![true; n];
    let problem = fit::Problem::new(input, y, &all, sigma, joint);
    // The span a stop's position must be told within (a joint resting on its stop all along
    // moves only by the noise).
    let stop_span = observed_range(y).max(STOP_SPAN_NOISE_SIGMAS * sigma);
    let nominal_physics = JointPhysics::nominal(joint);
    let nominal = fit::fit(&problem, &[], None, None, 25);
    let residual = fit::segment_residual(&problem, &nominal_physics, &nominal.states);
    let spans = mismatch_spans(&residual, sigma, cfg.min_mismatch_samples);
    let unit = if joint.kind.is_rotational() { "rad" } else { "m" };
    let mismatches: Vec<Mismatch> = spans.iter().map(|s| describe_mismatch(rec, joint, y, &derivs, &residual, *s)).collect();

    let vertical = tilt::tilt_applies(model, j, gravity.normalize_or_zero());
    let candidates: Vec<EffectKind> =
        EffectKind::FITTABLE.into_iter().filter(|k| k.applies_to(joint.kind) && (*k != EffectKind::GravityTilt || vertical)).collect();
    let select_here = || {
        let s = select::select(&problem, &derivs, &candidates, cfg.max_terms, cfg.min_mismatch_samples);
        (s.chosen, s.confidence, s.rejected)
    };
    let mut fell_back = false;
    // Whether output error contradicted effort space's reading ([`refine_given`]).
    let mut contradicted = false;
    let (chosen, confidence, mut rejected_here) = match given {
        // A joint whose replay is already within its noise floor gets no effects, whatever the
        // effort space saw (a joint at rest tells nothing about its physics).
        _ if spans.is_empty() => (nominal.clone(), Vec::new(), Vec::new()),
        // Structure from effort space; parameters refined by output error (DIDIM). When the
        // motion is still far from explained (effort space could not see an effect that acts
        // mostly near a stop, say), the terms are chosen here instead.
        Some(g) => {
            let (mut refined, contradiction) = refine_given(&problem, &nominal, g, (&terms, &derivs, &effort));
            // Where output error contradicted the efforts, the joint's simulation is what
            // disagrees with them (how it meets its stops or sticks): it does not choose the
            // terms again.
            contradicted = contradiction.is_some();
            let mut dropped: Vec<String> = contradiction.into_iter().collect();
            // The refined levels face the same rules as in effort space: a weight change that
            // shrank below materiality, or a level the refinement cannot tell from none (within
            // two σ of it), is dropped, one at a time, and the rest refitted.
            let rules = effort::SelectionRules::default();
            // (Levels held at effort space's reading are not refined, and were judged there.)
            while let Some(k) = (0..refined.effects.len()).find(|&k| {
                let held = contradicted && !unseen_in_effort(refined.effects[k].kind);
                !held && not_material(&refined.effects[k], &refined.param_std[k], &rules, stop_span)
            }) {
                dropped.push(format!(
                    "{}: refined to {} ± {} on the measured positions — not told from none (a stop: not located within the motion), not reported",
                    refined.effects[k].kind.name(),
                    refined.effects[k].params.first().map_or_else(|| "nothing".to_owned(), |v| format!("{v:.4}")),
                    refined.param_std[k].first().map_or_else(|| "?".to_owned(), |v| format!("{v:.2e}"))
                ));
                let mut rest = refined.effects.clone();
                rest.remove(k);
                refined = if rest.is_empty() {
                    nominal.clone()
                } else if contradicted {
                    held_at_effort_reading(&problem, &rest, g)
                } else {
                    fit::fit(&problem, &rest, Some(&free_mask(&rest)), None, 25)
                };
            }
            let physics = JointPhysics::with_effects(joint, &refined.effects);
            let left = fit::segment_residual(&problem, &physics, &refined.states);
            let worst = mismatch_spans(&left, sigma, cfg.min_mismatch_samples).iter().map(|s| rmse_over(&left, *s)).fold(0.0, f64::max);
            // Relative to the model as written: on real data the encoder noise is far below any
            // model's error, so σ alone would send every joint back.
            let rms = |r: &[f64]| {
                let v: Vec<f64> = r.iter().copied().filter(|x| x.is_finite()).collect();
                (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
            };
            let unexplained = rms(&left) > 0.5 * rms(&residual);
            // Only where effort space itself could not explain the efforts with its smooth laws: when it
            // could, a position misfit comes from how stops are simulated (an engine's soft limits
            // against our hard ones), not from missing physics.
            let effort_unexplained = g.effort_unexplained;
            let alternative =
                (effort_unexplained && !contradicted && !spans.is_empty() && unexplained && worst >= UNKNOWN_SIGMAS_AFTER_EFFORT * sigma)
                    .then(select_here);
            // The alternative must prove itself on data it was not fitted to.
            let better = alternative.as_ref().is_some_and(|(alt, _, _)| {
                let mine = held_out::held_out(rec, input, y, sigma, joint, &refined.effects, t_split).rmse_after;
                let theirs = held_out::held_out(rec, input, y, sigma, joint, &alt.effects, t_split).rmse_after;
                theirs * FALLBACK_HELD_OUT_GAIN < mine
            });
            if let Some(alt) = alternative.filter(|_| better) {
                fell_back = true;
                alt
            } else {
                let confidence = refined
                    .effects
                    .iter()
                    .map(|e| g.effects.iter().position(|x| x.kind == e.kind).and_then(|k| g.confidence.get(k).copied()).unwrap_or(0.5))
                    .collect();
                (refined, confidence, dropped)
            }
        }
        None => select_here(),
    };
    // Whichever way the terms were chosen, each must be something: not a level its own σ cannot
    // tell from none, and not an effort too small to matter next to the joint's own.
    let (chosen, confidence) = {
        let rules = effort::SelectionRules::default();
        let keep: Vec<bool> = chosen
            .effects
            .iter()
            .zip(&chosen.param_std)
            .map(|(e, sd)| {
                // Stops act only at their position: their size is judged where they are found.
                let sized = !unseen_in_effort(e.kind);
                let share = if sized { effort_share(e, joint, &terms, &derivs, &effort) } else { 1.0 };
                // Levels held at effort space's reading were judged there, by its own rules.
                let judged = contradicted && sized;
                let keep = (judged || !not_material(e, sd, &rules, stop_span)) && share >= rules.min_effort_share;
                if !keep {
                    rejected_here.push(format!(
                        "{}: fitted to {} ({:.1} % of the joint's own effort) — not material, not reported",
                        e.kind.name(),
                        e.params.first().map_or_else(|| "nothing".to_owned(), |v| format!("{v:.4}")),
                        100.0 * share
                    ));
                }
                keep
            })
            .collect();
        if keep.iter().all(|&k| k) {
            (chosen, confidence)
        } else {
            let rest: Vec<Effect> = chosen.effects.iter().zip(&keep).filter(|(_, k)| **k).map(|(e, _)| e.clone()).collect();
            let conf: Vec<f64> = confidence.iter().zip(&keep).filter(|(_, k)| **k).map(|(c, _)| *c).collect();
            let refit = if rest.is_empty() { nominal.clone() } else { fit::fit(&problem, &rest, Some(&free_mask(&rest)), None, 25) };
            (refit, conf)
        }
    };
    // A stop the recording shows compliant is judged as such (a hard one in its place may be
    // what makes the held-out replay worse).
    let chosen = match compliant_stop(rec, &problem, &chosen, t_split) {
        Ok(compliant) => compliant,
        Err(note) => {
            rejected_here.extend(note);
            chosen
        }
    };
    // Terms chosen in position space must hold on data they were not fitted to: a structure
    // that makes the held-out replay worse is not reported (it fits how stops or friction are
    // simulated, not missing physics). A held-out part that both replays follow to within the
    // noise (a lid resting open on its stop after the split) tests nothing, and vetoes nothing.
    let mut held = held_out::held_out(rec, input, y, sigma, joint, &chosen.effects, t_split);
    let held_tests = held.rmse_before.max(held.rmse_after) > HELD_OUT_NOISE_SIGMAS * sigma;
    let (chosen, confidence) = if given.is_none() && !chosen.effects.is_empty() && held_tests && held.rmse_after >= held.rmse_before {
        let kinds: Vec<&str> = chosen.effects.iter().map(|e| e.kind.name()).collect();
        rejected_here.push(format!(
            "{}: fitted, but the held-out replay got worse ({:.4} → {:.4} {unit}) — not reported",
            kinds.join(" + "),
            held.rmse_before,
            held.rmse_after
        ));
        held.rmse_after = held.rmse_before;
        (nominal.clone(), Vec::new())
    } else {
        (chosen, confidence)
    };
    // Effort space applied the rule itself to the terms it chose (`prefer_inertia_alone`), where
    // it sees the weight: only terms chosen here face it here.
    let chosen_here = given.is_none() || fell_back;
    let chosen = match chosen_here.then(|| inertia_alone(&problem, &chosen)).flatten() {
        Some((armature, note)) => {
            rejected_here.push(note);
            armature
        }
        None => chosen,
    };
    let fitted_physics = JointPhysics::with_effects(joint, &chosen.effects);
    let mut effects: Vec<EffectReport> = chosen
        .effects
        .iter()
        .zip(&chosen.param_std)
        .zip(&confidence)
        .map(|((e, sd), c)| {
            effect_report(joint, &terms[0], gravity, e, sd, *c, observed_range(y), fitted_physics.inertia(terms[0].inertia))
        })
        .collect();
    if let Some(g) = given.filter(|_| !fell_back) {
        // Effort space's `unknown` stands when the exact simulation confirms that the motion is
        // not explained either (impacts and smoothing inflate the residual effort of a joint that
        // often hits its stops).
        let after = fit::segment_residual(&problem, &fitted_physics, &chosen.states);
        let worst = mismatch_spans(&after, sigma, cfg.min_mismatch_samples).iter().map(|s| rmse_over(&after, *s)).fold(0.0, f64::max);
        if worst >= UNKNOWN_SIGMAS_AFTER_EFFORT * sigma {
            effects.extend(g.extra.iter().cloned());
        }
    }
    if !spans.is_empty() {
        let after = fit::segment_residual(&problem, &fitted_physics, &chosen.states);
        // Misfit that lies against a modelled stop is how the stop is simulated (hard here, soft
        // or compliant in the recording), not missing physics: the mismatch says where it is.
        let left: Vec<Span> =
            mismatch_spans(&after, sigma, cfg.min_mismatch_samples).into_iter().filter(|s| !mostly_at_a_stop(joint, y, *s)).collect();
        let worst = left.iter().map(|s| rmse_over(&after, *s)).fold(0.0, f64::max);
        // After effort space chose the terms, `unknown` is effort space's (sized in effort
        // units against the joint's own efforts), unless the terms were chosen here.
        // And what the named terms leave must matter next to the misfit they were fitted to cut:
        // a tenth of it is how an engine integrates, not missing physics.
        let worst_before = spans.iter().map(|s| rmse_over(&residual, *s)).fold(0.0, f64::max);
        let material = (given.is_none() || (fell_back && worst >= UNKNOWN_SIGMAS_AFTER_EFFORT * sigma))
            && (chosen.effects.is_empty() || worst >= UNKNOWN_SHARE_OF_MISFIT * worst_before);
        if !left.is_empty() && material {
            let ranges: Vec<String> = left.iter().map(|s| format!("{:.2}–{:.2} s", rec.time_s[s.start], rec.time_s[s.end])).collect();
            effects.push(EffectReport {
                joint: joint.name.clone(),
                kind: EffectKind::Unknown.name().into(),
                params: std::collections::BTreeMap::default(),
                uncertainty: std::collections::BTreeMap::default(),
                confidence: (1.0 - (sigma / worst).powi(2)).clamp(0.0, 1.0),
                description: format!(
                    "residual still {:.1}× the noise at {} after fitting the known kinds: physics no known kind explains",
                    worst / sigma,
                    ranges.join(", ")
                ),
            });
        }
    }

    // Open loop over the whole record from the first segment's state, the model's limits bouncing
    // as the recording shows.
    let start = problem.segments.first().map_or(0, |s| s.start);
    let everywhere = vec![true; n];
    let replay = |physics: &JointPhysics, state: Option<(f64, f64)>| {
        held_out::replay_with_bounce(&input, y, &everywhere, sigma, physics, start, state.unwrap_or((y[start], 0.0)))
    };
    let (before_sim, _) = replay(&nominal_physics, nominal.states.first().copied());
    let (after_sim, bouncing) = replay(&fitted_physics, chosen.states.first().copied());
    let (all_pair, sq) = rmse_pair(y, &before_sim, &after_sim, |_| true);
    let series = JointSeries::new(&joint.name, unit, &rec.time_s, y, before_sim, after_sim, sigma);
    let mut analysis = given.map_or_else(
        || report::JointAnalysis { mode: "position".into(), rejected: rejected_here.clone(), ..report::JointAnalysis::default() },
        |g| {
            let mut a = g.analysis.clone();
            if fell_back {
                a.mode = "position".into();
                a.why.push_str("; the refined terms left the motion unexplained, so they were chosen in position space");
                a.rejected.clone_from(&rejected_here);
            } else {
                // What the output-error refinement dropped, after what effort space turned down.
                a.rejected.extend(rejected_here.iter().cloned());
            }
            a
        },
    );
    if let Some(note) = held_out::bounce_note(bouncing.limit_restitution) {
        analysis.why.push_str(if analysis.why.is_empty() { "" } else { "; " });
        analysis.why.push_str(&note);
    }
    JointOutcome { mismatches, effects, all: all_pair, held, sq, series, analysis }
}

/// Relative uncertainty every fitted level carries on top of its statistical σ: the recording
/// was made by physics that is not our model (another engine's integrator, regularised
/// friction, soft stops; a real mechanism), and that difference biases a level by more than the
/// data's noise does. Measured on the cross-engine suite; reported as part of each σ.
const MODEL_FORM_FLOOR: f64 = 0.1;

/// The same for positions (a spring's rest, a tilt's equilibrium, a stop, a soft-close zone), as
/// a share of the joint's observed range of motion: where a position lies is known only as well
/// as the motion around it is modelled.
const POSITION_MODEL_FORM_SHARE: f64 = 0.02;

/// Parameters that are positions (no relative floor).
const POSITION_PARAMS: [&str; 4] = ["rest_position", "equilibrium_position", "position", "engage_position"];

/// Held-out RMSE (in noise σ) within which a replay follows the recording as well as its noise
/// lets any replay: where both the model as written and the fitted one do, the held-out part
/// cannot tell them apart.
const HELD_OUT_NOISE_SIGMAS: f64 = 2.0;

/// How much better on held-out data a structure chosen in position space must be than the one
/// effort space chose, to replace it.
const FALLBACK_HELD_OUT_GAIN: f64 = 2.0;

/// Share of the model-as-written's worst misfit that the worst misfit left after the named terms
/// must keep for `unknown` (position space).
const UNKNOWN_SHARE_OF_MISFIT: f64 = 0.1;

/// Residual (in noise σ) that a joint whose terms came from effort space must still show, after
/// the output-error refinement, for `unknown`.
const UNKNOWN_SIGMAS_AFTER_EFFORT: f64 = 8.0;

/// Whether most measured samples of `span` are within 5 % of the travel of a modelled stop.
fn mostly_at_a_stop(joint: &model::GapJoint, y: &[f64], span: Span) -> bool {
    let (Some(lo), Some(hi)) = (joint.lower, joint.upper) else { return false };
    let band = 0.05 * (hi - lo).abs();
    let vals: Vec<f64> = y[span.start..=span.end].iter().copied().filter(|v| v.is_finite()).collect();
    let near = vals.iter().filter(|&&q| q <= lo + band || q >= hi - band).count();
    2 * near >= vals.len().max(1)
}

/// RMS effort of effect `e` alone along the measured motion (`derivs`: smoothed position,
/// velocity, acceleration per sample), over the joint's own dynamic effort there (what its
/// inertia and the recorded coupling ask, or what is applied beyond holding it against gravity;
/// on a passive joint, gravity itself): the practical size a term found in position space must
/// have, measured as effort space measures it.
fn effort_share(e: &Effect, joint: &model::GapJoint, terms: &[model::JointTerms], derivs: &[[f64; 3]], applied: &[f64]) -> f64 {
    change_share(std::slice::from_ref(e), &[], joint, terms, derivs, applied)
}

/// The RMS difference between the efforts effects `a` and effects `b` add to the model joint
/// along the measured motion, as a share of the joint's own effort (its inertial and coupling
/// effort, or its applied effort less gravity, whichever is larger). End stops act only where
/// they are, and add nothing here.
fn change_share(
    a: &[Effect],
    b: &[Effect],
    joint: &model::GapJoint,
    terms: &[model::JointTerms],
    derivs: &[[f64; 3]],
    applied: &[f64],
) -> f64 {
    let (with_a, with_b) = (JointPhysics::with_effects(joint, a), JointPhysics::with_effects(joint, b));
    let extra = |p: &JointPhysics, t: &model::JointTerms, [q, v, a]: [f64; 3]| {
        let friction = if p.friction_shape.transition_speed > 0.0 { p.smooth_friction(v) } else { -p.friction_level(v) * v.signum() };
        let inertia = (p.mass_scale - 1.0) * (t.inertia * a - t.gravity(q)) + p.armature * a;
        p.position_effort(q) + p.effort_offset + friction - p.damping_at(q) * v - inertia
    };
    let (mut term, mut own, mut count) = (0.0, 0.0f64, 0usize);
    let mut own_applied = 0.0;
    for ((t, d), u) in terms.iter().zip(derivs).zip(applied) {
        if !d.iter().all(|x| x.is_finite()) {
            continue;
        }
        let size = extra(&with_a, t, *d) - extra(&with_b, t, *d);
        term += size * size;
        own += (t.inertia * d[2] + t.coupling).powi(2);
        own_applied += (if u.is_finite() { *u } else { 0.0 } - t.gravity(d[0])).powi(2);
        count += 1;
    }
    if count == 0 {
        return 0.0;
    }
    let scale = (own.max(own_applied) / count as f64).sqrt();
    (term / count as f64).sqrt() / scale.max(1e-12)
}

/// Whether a refined effect is nothing: a weight change below materiality, a level within two
/// standard deviations of the level that means no effect, or a Stribeck break-away beyond
/// [`effort::SelectionRules::max_breakaway_ratio`] × its sliding level.
/// Noise σs a stop's position span is floored at ([`not_material`]).
const STOP_SPAN_NOISE_SIGMAS: f64 = 20.0;

fn not_material(e: &Effect, std: &[f64], rules: &effort::SelectionRules, range: f64) -> bool {
    let level = e.params.first().copied().unwrap_or(f64::NAN);
    let sd = std.first().copied().unwrap_or(f64::NAN);
    match e.kind {
        EffectKind::MassScale => (level - 1.0).abs() < rules.min_mass_change || (sd.is_finite() && (level - 1.0).abs() < 2.0 * sd),
        // A stop the replay does not feel (its position could lie anywhere beyond the whole
        // observed range, `range` floored at the noise by the caller) is the edge of the motion,
        // not a stop: a push reversing the joint at its peak, or a spring not yet fitted when the
        // stop was found, looked like one.
        EffectKind::EndStop => sd.is_finite() && sd > range,
        EffectKind::Unknown => false,
        // A break-away far above the sliding level is no static friction (see the rule).
        EffectKind::StribeckFriction if e.params.get(1).is_some_and(|&b| rules.breakaway_beyond_ratio(level, b)) => true,
        _ => sd.is_finite() && level.abs() < 2.0 * sd,
    }
}

/// Effects found in effort space for a joint whose parameters are refined in position space.
#[derive(Debug, Clone)]
struct Given {
    /// The structure and starting parameters.
    effects: Vec<Effect>,
    /// One σ of each effect's parameters in effort space (jackknife over its folds).
    param_std: Vec<Vec<f64>>,
    /// Confidence from effort space.
    confidence: Vec<f64>,
    /// Reports that stay as effort space gave them (`unknown`).
    extra: Vec<EffectReport>,
    /// Whether effort space's smooth laws left effort unexplained (dry friction held to its
    /// smooth law at rest): then the joint's exact simulation may choose the terms again.
    effort_unexplained: bool,
    /// How the joint was analysed.
    analysis: report::JointAnalysis,
}

/// The spec's rule in position space: a heavier part (`mass_scale`) is inertia and weight
/// together, inertia alone is `armature`. Where the fit with a rotor's inertia in place of the
/// heavier part is as good (cost within [`effort::LOOK_ALIKE_SSE_SHARE`]: gravity does no work
/// on the joint, a horizontal drawer or a knob turning about its centre of mass), the weight was
/// never seen: the armature fit, and what the report says of the other reading. (A drawer that
/// rests on its stop most of the time reaches position space without effort space's own rule.)
fn inertia_alone(problem: &fit::Problem<'_>, chosen: &fit::FitResult) -> Option<(fit::FitResult, String)> {
    let k = chosen.effects.iter().position(|e| e.kind == EffectKind::MassScale)?;
    if chosen.effects.iter().any(|e| e.kind == EffectKind::Armature) {
        return None;
    }
    let scale = chosen.effects[k].params[0];
    let inertia = problem.input.terms.iter().map(|t| t.inertia).find(|i| i.is_finite())?;
    let mut effects = chosen.effects.clone();
    effects[k] = Effect { kind: EffectKind::Armature, params: vec![((scale - 1.0) * inertia).max(0.0)], blocks_upward: false };
    let fitted = fit::fit(problem, &effects, Some(&free_mask(&effects)), None, 25);
    let as_good = fitted.cost <= chosen.cost * (1.0 + effort::LOOK_ALIKE_SSE_SHARE);
    let armature = fitted.effects.get(k).and_then(|e| e.params.first()).copied().unwrap_or(0.0);
    (as_good && armature > 0.0).then(|| {
        let note = format!(
            "mass_scale: a part {scale:.3}× as heavy fits as well as a rotor's inertia of {armature:.4} — gravity does no work on \
             the joint, so the weight was never seen; inertia alone is reported as armature (the other reading)"
        );
        (fitted, note)
    })
}

/// Restitutions an end stop's output-error refinement also starts from ([`refine_from_bounces`]).
const STOP_RESTITUTION_STARTS: [f64; 3] = [0.3, 0.6, 0.9];

/// `effects` refined by output error; where they hold an end stop, also from each of
/// [`STOP_RESTITUTION_STARTS`], the fit with the least cost kept. A replay's fit is not smooth in a
/// stop's restitution (each bounce changes where the next impact falls), and the estimate
/// from short impacts sees nothing of a compliant stop that holds the joint for tens of
/// milliseconds and throws it back at 0.6–0.9 of its speed (a penalty-spring limit): from 0 the
/// refinement stayed at 0 on such a door.
fn refine_from_bounces(problem: &fit::Problem<'_>, effects: &[Effect], mask: &[Vec<bool>]) -> fit::FitResult {
    let mut best = fit::fit(problem, effects, Some(mask), None, 25);
    if !effects.iter().any(|e| e.kind == EffectKind::EndStop) {
        return best;
    }
    for r in STOP_RESTITUTION_STARTS {
        let start: Vec<Effect> = effects
            .iter()
            .map(|e| {
                let mut e = e.clone();
                if e.kind == EffectKind::EndStop && e.params.len() > 1 {
                    e.params[1] = r;
                }
                e
            })
            .collect();
        let fitted = fit::fit(problem, &start, Some(mask), None, 25);
        if fitted.cost < best.cost * (1.0 - 1e-9) {
            best = fitted;
        }
    }
    best
}

/// Effort space's effects refined by output error on the measured positions, with what the
/// refinement said (a line for the report's `rejected`, or none).
///
/// Output error refines the levels effort space read; it does not read the physics again. Its
/// cost, on a joint that bounces off its stops or is pushed against them, has valleys far from
/// the efforts' reading: a lid with a damper and a heavier panel, read in effort space as
/// 0.200 N·m·s/rad and ×1.301 (a recording by `JaxSim`; truth 0.2 and ×1.3), was "refined" to 1.76
/// and ×0.50, and the real DFKI pendulum's (Coulomb 0.165 N·m, ×1.23, a rotor's inertia of
/// 0.009 kg·m²) to 0.149, ×1.29 and 0.016, each replaying the recording worse. Where the refined
/// effects add an effort that differs from effort space's along the measured motion by a
/// material share of the joint's own ([`effort::SelectionRules::min_effort_share`], the share
/// below which an effect is too small to matter), the two readings disagree on what the joint
/// does, not on a detail. The refined one is kept only if it replays the whole recording open
/// loop (which multiple shooting does not fit) clearly better
/// ([`effort::SelectionRules::min_replay_gain`]): dry friction that holds a drawer or a knob
/// between pushes is read low by effort space's smooth law, and output error corrects it by a
/// material share of a small effort, replaying the motion 8 to 2000 times better. Otherwise the
/// reading that saw the efforts stands, its levels held with their effort-space σ, and only what
/// effort space cannot see (an end stop's position and bounce) is refined.
fn refine_given(
    problem: &fit::Problem<'_>,
    nominal: &fit::FitResult,
    given: &Given,
    (terms, derivs, applied): (&[model::JointTerms], &[[f64; 3]], &[f64]),
) -> (fit::FitResult, Option<String>) {
    if given.effects.is_empty() {
        return (nominal.clone(), None);
    }
    let refined = refine_from_bounces(problem, &given.effects, &free_mask(&given.effects));
    let moved = change_share(&refined.effects, &given.effects, problem.joint, terms, derivs, applied);
    let rules = effort::SelectionRules::default();
    if moved < rules.min_effort_share {
        return (refined, None);
    }
    let held = held_at_effort_reading(problem, &given.effects, given);
    let (theirs, mine) = (replay_rmse(problem, &refined), replay_rmse(problem, &held));
    if theirs.powi(2) < (1.0 - rules.min_replay_gain) * mine.powi(2) {
        return (refined, None);
    }
    let levels: Vec<String> = refined
        .effects
        .iter()
        .filter(|e| !unseen_in_effort(e.kind))
        .map(|e| format!("{} {}", e.kind.name(), e.params.first().map_or_else(String::new, |v| format!("{v:.4}"))))
        .collect();
    let unit = if problem.joint.kind.is_rotational() { "rad" } else { "m" };
    let note = format!(
        "output-error refinement: moved to {} ({:.0} % of the joint's own effort away from the efforts' reading), replaying the \
         recording no clearly better ({theirs:.4} against {mine:.4} {unit}) — another reading the efforts contradict, not a \
         refinement; effort space's levels kept",
        levels.join(", "),
        100.0 * moved
    );
    (held, Some(note))
}

/// Kinds effort space cannot see (it leaves the samples at a stop out), refined by output error
/// even where the levels it read are held ([`held_at_effort_reading`]).
fn unseen_in_effort(kind: EffectKind) -> bool {
    matches!(kind, EffectKind::EndStop | EffectKind::Unknown)
}

/// `effects` (some of effort space's reading `given`) fitted by output error with the levels
/// effort space read held, and their σ its jackknife σ: only what it cannot see is refined.
fn held_at_effort_reading(problem: &fit::Problem<'_>, effects: &[Effect], given: &Given) -> fit::FitResult {
    let mask: Vec<Vec<bool>> = free_mask(effects)
        .into_iter()
        .zip(effects)
        .map(|(free, e)| free.into_iter().map(|f| f && unseen_in_effort(e.kind)).collect())
        .collect();
    let mut held = refine_from_bounces(problem, effects, &mask);
    for ((e, sd), free) in held.effects.iter().zip(held.param_std.iter_mut()).zip(&mask) {
        let read = given.effects.iter().position(|g| g.kind == e.kind).and_then(|k| given.param_std.get(k));
        for (p, s) in sd.iter_mut().enumerate() {
            if !free[p] {
                *s = read.and_then(|r| r.get(p)).copied().unwrap_or(f64::NAN);
            }
        }
    }
    held
}

/// The RMS error of `fitted`'s open-loop replay of the whole recording from its first segment's
/// state, the model's limits bouncing as the recording shows.
fn replay_rmse(problem: &fit::Problem<'_>, fitted: &fit::FitResult) -> f64 {
    let physics = JointPhysics::with_effects(problem.joint, &fitted.effects);
    let start = problem.segments.first().map_or(0, |s| s.start);
    let state = fitted.states.first().copied().unwrap_or((problem.y[start], 0.0));
    let everywhere = vec![true; problem.y.len()];
    let (sim, _) = held_out::replay_with_bounce(&problem.input, problem.y, &everywhere, problem.sigma, &physics, start, state);
    let (sse, count) = rmse_mask(problem.y, &sim, |_| true);
    (sse / count.max(1) as f64).sqrt()
}

/// Contact times a compliant stop's fit starts from, in sample intervals: a contact shorter than
/// a few samples is not seen as one.
const CONTACT_STARTS_SAMPLES: [f64; 3] = [3.0, 8.0, 20.0];

/// Restitutions a compliant stop's fit also starts from (besides the hard stop's).
const COMPLIANT_RESTITUTION_STARTS: [f64; 1] = [0.9];

/// Share of the hard stop's held-out error a compliant stop must remove to be reported: a stop
/// that is a little soft in an engine's integration is still a hard stop to its user.
const COMPLIANT_HELD_OUT_GAIN: f64 = 0.25;

/// `chosen` with its end stop made compliant (a contact time: a spring–damper the joint sinks
/// into and is thrown back from), where that is material on data it was not fitted to: no worse
/// on the training part, and [`COMPLIANT_HELD_OUT_GAIN`] of the hard stop's held-out error
/// removed. Training cost alone cannot judge it: where the model's own limits are soft too,
/// their misfit swamps the stop's. `Err` carries what the report says when a compliant stop was
/// fitted and turned down (nothing when `chosen` has no stop). Hard stops are the default; an
/// engine's penalty limit or a rubber bumper holds the joint for tens of milliseconds, which a
/// hard stop with any restitution replays wrong, since each impact's timing shifts every later
/// one.
fn compliant_stop(
    rec: &Recording,
    problem: &fit::Problem<'_>,
    chosen: &fit::FitResult,
    t_split: f64,
) -> Result<fit::FitResult, Option<String>> {
    let k = chosen.effects.iter().position(|e| e.kind == EffectKind::EndStop).ok_or(None)?;
    let dt = effort::median_step_s(problem.input.time_s);
    let hard_restitution = chosen.effects[k].params[1];
    let mut best: Option<fit::FitResult> = None;
    for n in CONTACT_STARTS_SAMPLES {
        for r in std::iter::once(hard_restitution).chain(COMPLIANT_RESTITUTION_STARTS) {
            let mut start = chosen.effects.clone();
            start[k].params = vec![start[k].params[0], r, n * dt];
            let fitted = fit::fit(problem, &start, Some(&free_mask(&start)), None, 25);
            if best.as_ref().is_none_or(|b| fitted.cost < b.cost) {
                best = Some(fitted);
            }
        }
    }
    let compliant = best.ok_or(None)?;
    let contact_ms = 1e3 * compliant.effects[k].params[2];
    if compliant.cost > chosen.cost {
        return Err(Some(format!("end_stop: a compliant stop ({contact_ms:.0} ms contacts) fits worse than a hard one — kept hard")));
    }
    let held =
        |effects: &[Effect]| held_out::held_out(rec, problem.input, problem.y, problem.sigma, problem.joint, effects, t_split).rmse_after;
    let (hard_held, compliant_held) = (held(&chosen.effects), held(&compliant.effects));
    if hard_held > HELD_OUT_NOISE_SIGMAS * problem.sigma && compliant_held <= (1.0 - COMPLIANT_HELD_OUT_GAIN) * hard_held {
        return Ok(compliant);
    }
    Err(Some(format!(
        "end_stop: a compliant stop ({contact_ms:.0} ms contacts) replays the held-out part to {compliant_held:.4} against the hard \
         stop's {hard_held:.4} (needs {:.0} % less, beyond the noise) — kept hard",
        100.0 * COMPLIANT_HELD_OUT_GAIN
    )))
}

/// Which parameters output error refines: the levels, not the shape parameters effort space
/// chose on its grid (transition and Stribeck speeds), nor parameters that are absent (NaN).
fn free_mask(effects: &[Effect]) -> Vec<Vec<bool>> {
    effects
        .iter()
        .map(|e| {
            e.params
                .iter()
                .enumerate()
                .map(|(p, v)| v.is_finite() && !matches!((e.kind, p), (EffectKind::CoulombFriction, 1) | (EffectKind::StribeckFriction, 2)))
                .collect()
        })
        .collect()
}

fn describe_mismatch(rec: &Recording, joint: &model::GapJoint, y: &[f64], derivs: &[[f64; 3]], residual: &[f64], span: Span) -> Mismatch {
    let idx: Vec<usize> = (span.start..=span.end).filter(|&i| y[i].is_finite()).collect();
    let (lo, hi) = idx.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| (a.min(y[i]), b.max(y[i])));
    let vmax = derivs.iter().filter(|d| d[1].is_finite()).map(|d| d[1].abs()).fold(0.0, f64::max);
    let moving: Vec<f64> = idx.iter().map(|&i| derivs[i][1]).filter(|v| v.is_finite() && v.abs() > 0.05 * vmax).collect();
    let up = moving.iter().filter(|v| **v > 0.0).count();
    let down = moving.len() - up;
    let direction = if moving.len() < idx.len() / 5 {
        "at rest"
    } else if up > 4 * down {
        "increasing"
    } else if down > 4 * up {
        "decreasing"
    } else {
        "both"
    };
    let range = match (joint.lower, joint.upper) {
        (Some(l), Some(u)) => u - l,
        _ => (hi - lo).max(1e-6),
    };
    let near_stop = if joint.lower.is_some_and(|l| lo - l < 0.05 * range) {
        Some("lower limit".to_owned())
    } else if joint.upper.is_some_and(|u| u - hi < 0.05 * range) {
        Some("upper limit".to_owned())
    } else {
        None
    };
    // Measured vs simulated speed over the span (simulated: the nominal segments).
    let mut sim_v = Vec::new();
    let sim_pos: Vec<f64> = residual.iter().zip(y).map(|(r, y)| y - r).collect();
    for w in idx.windows(2) {
        let dt = rec.time_s[w[1]] - rec.time_s[w[0]];
        if sim_pos[w[0]].is_finite() && sim_pos[w[1]].is_finite() && dt > 0.0 {
            sim_v.push(((sim_pos[w[1]] - sim_pos[w[0]]) / dt).abs());
        }
    }
    let meas_v: Vec<f64> = idx.iter().map(|&i| derivs[i][1].abs()).filter(|v| v.is_finite()).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let ratio = mean(&meas_v) / mean(&sim_v).max(1e-9);
    let what = if ratio < 0.7 {
        "the simulated joint keeps moving; the measured one is slower or stops"
    } else if ratio > 1.4 {
        "the measured joint moves faster than the simulated one"
    } else {
        "measured and simulated positions drift apart at similar speed"
    };
    let unit = if joint.kind.is_rotational() { "rad" } else { "m" };
    let stop_text = near_stop.as_ref().map_or(String::new(), |s| format!(", near the {s}"));
    Mismatch {
        joint: joint.name.clone(),
        t_start: rec.time_s[span.start],
        t_end: rec.time_s[span.end],
        rmse: rmse_over(residual, span),
        description: format!("{what} (q {lo:.3}–{hi:.3} {unit}, motion {direction}{stop_text})"),
        conditions: Conditions { position_min: lo, position_max: hi, direction: direction.into(), near_stop },
    }
}

/// The range of the finite values of `y` (0 when there are none).
fn observed_range(y: &[f64]) -> f64 {
    let (lo, hi) = y.iter().filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if hi >= lo { hi - lo } else { 0.0 }
}

/// The report of one effect; `range` is the joint's observed range of motion (position σ floor),
/// `inertia` the joint's inertia under the fitted physics (a compliant stop's stiffness).
#[allow(clippy::too_many_arguments)]
fn effect_report(
    joint: &model::GapJoint,
    terms: &model::JointTerms,
    gravity: DVec3,
    e: &Effect,
    sd: &[f64],
    confidence: f64,
    range: f64,
    inertia: f64,
) -> EffectReport {
    let rot = joint.kind.is_rotational();
    let (force, length) = if rot { ("N·m", "rad") } else { ("N", "m") };
    let x = &e.params;
    let mut params = std::collections::BTreeMap::new();
    let mut unc = std::collections::BTreeMap::new();
    let mut put = |k: &str, v: f64, s: f64| {
        params.insert(k.to_owned(), v);
        // Levels (a weight scale too: the weight is the level) carry the model-form floor,
        // positions a share of the observed motion.
        let floor = if POSITION_PARAMS.contains(&k) { POSITION_MODEL_FORM_SHARE * range } else { MODEL_FORM_FLOOR * v.abs() };
        if s.is_finite() {
            unc.insert(k.to_owned(), s.hypot(floor));
        }
    };
    let description = match e.kind {
        EffectKind::ViscousDamping => {
            put("damping", x[0], sd[0]);
            format!("viscous damping {:.4} ± {:.4} {force}·s/{length}", x[0], sd[0])
        }
        EffectKind::CoulombFriction => {
            put("friction", x[0], sd[0]);
            let mut text = format!("Coulomb friction {:.4} ± {:.4} {force}", x[0], sd[0]);
            if let Some(&speed) = x.get(1).filter(|s| **s > 0.0) {
                put("transition_speed", speed, sd.get(1).copied().unwrap_or(f64::NAN));
                let _ = write!(text, ", smooth through zero speed over {speed:.3} {length}/s");
            }
            if let Some(&reverse) = x.get(2).filter(|r| r.is_finite()) {
                put("friction_reverse", reverse, sd.get(2).copied().unwrap_or(f64::NAN));
                let _ = write!(text, ", {reverse:.4} {force} when moving backwards");
            }
            text
        }
        EffectKind::StribeckFriction => {
            put("friction", x[0], sd[0]);
            put("breakaway", x[1], sd[1]);
            put("stribeck_speed", x[2], sd[2]);
            format!("Stribeck friction: {:.4} {force} sliding, {:.4} {force} to break away, over {:.3} {length}/s", x[0], x[1], x[2])
        }
        EffectKind::EffortOffset => {
            put("offset", x[0], sd[0]);
            format!("a constant {:.4} ± {:.4} {force} adds to the recorded effort (sensor bias or gravity compensation)", x[0], sd[0])
        }
        EffectKind::Armature => {
            put("armature", x[0], sd[0]);
            let unit = if rot { "kg·m²" } else { "kg" };
            format!("reflected rotor inertia {:.5} ± {:.5} {unit} on the joint (inertia without weight)", x[0], sd[0])
        }
        EffectKind::Spring => {
            put("stiffness", x[0], sd[0]);
            put("rest_position", x[1], sd[1]);
            format!("spring {:.4} {force}/{length} towards {:.3} {length}", x[0], x[1])
        }
        EffectKind::GravityTilt if tilt::base_lean(e).is_some() => base_tilt_text(x, sd, gravity, &mut put),
        EffectKind::GravityTilt => {
            let lever = terms.subtree_mass_kg * gravity.length() * terms.com_radius_m;
            let ratio = if lever > 0.0 { (x[0] / lever).clamp(-1.0, 1.0) } else { 0.0 };
            let tilt = ratio.asin();
            let sd_tilt = if lever > 0.0 { sd[0] / lever / tilt.cos().max(1e-6) } else { f64::NAN };
            let eq = (x[1] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            put("tilt_deg", tilt.to_degrees(), sd_tilt.to_degrees());
            put("equilibrium_position", eq, sd[1]);
            format!("axis tilted {:.2}° from the model; gravity pulls towards {eq:.3} rad ({:.3} N·m peak)", tilt.to_degrees(), x[0])
        }
        EffectKind::EndStop => {
            put("position", x[0], sd[0]);
            put("restitution", x[1], sd[1]);
            let side = if e.blocks_upward { "above" } else { "below" };
            match x.get(2).copied().filter(|t| t.is_finite() && *t > 0.0) {
                Some(contact_s) => {
                    put("contact_time", contact_s, sd.get(2).copied().unwrap_or(f64::NAN));
                    let stop =
                        effects::Stop { position: x[0], restitution: x[1], blocks_upward: e.blocks_upward, contact_time_s: contact_s };
                    let (stiffness, damping) = stop.penalty(inertia);
                    // Derived at the joint's inertia: no σ of their own.
                    put("stiffness", stiffness, f64::NAN);
                    put("damping", damping, f64::NAN);
                    format!(
                        "a compliant stop at {:.4} {length} (blocks from {side}): restitution {:.2}, each impact {:.0} ms long \
                         (stiffness {stiffness:.4e} {force}/{length}, damping {damping:.4} {force}·s/{length})",
                        x[0],
                        x[1],
                        1e3 * contact_s
                    )
                }
                None => format!("a hard stop at {:.4} {length} (blocks from {side}), restitution {:.2}", x[0], x[1]),
            }
        }
        EffectKind::MassScale => {
            put("scale", x[0], sd[0]);
            format!("the moving part is {:.3} × as heavy as modelled (inertia and weight)", x[0])
        }
        EffectKind::SoftClose => {
            put("damping", x[0], sd[0]);
            put("engage_position", x[1], sd[1]);
            format!("soft-close damping {:.3} {force}·s/{length} from {:.4} {length} to the closed end", x[0], x[1])
        }
        EffectKind::Unknown => String::new(),
    };
    EffectReport { joint: joint.name.clone(), kind: e.kind.name().into(), params, uncertainty: unc, confidence, description }
}

/// The report of a chain's base tilt (internal parameters [`tilt::BASE_TILT_PARAMS`]): its
/// `tilt_deg`, the base joint's `equilibrium_position` and the turn's axis in the root link's
/// frame (`tilt_axis_x/y/z`: what the fitted URDF turns the base by); `put` records each.
fn base_tilt_text(x: &[f64], sd: &[f64], gravity: DVec3, put: &mut impl FnMut(&str, f64, f64)) -> String {
    let w = DVec3::new(x[2], x[3], x[4]);
    let tilt_rad = tilt::tilt_rad(w);
    let (axis, _) = tilt::world_from_base(w, gravity.normalize_or_zero()).to_axis_angle();
    let eq = (x[1] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    put("tilt_deg", tilt_rad.to_degrees(), (sd[0] / tilt_rad.cos().max(1e-6)).to_degrees());
    put("equilibrium_position", eq, sd[1]);
    for (name, v) in ["tilt_axis_x", "tilt_axis_y", "tilt_axis_z"].into_iter().zip(axis.to_array()) {
        put(name, v, f64::NAN);
    }
    format!(
        "the base is tilted {:.2}° from the model about ({:.3}, {:.3}, {:.3}), everything beyond this joint with it; \
         a part along the joint's x axis rests at {eq:.3} rad",
        tilt_rad.to_degrees(),
        axis.x,
        axis.y,
        axis.z
    )
}

/// Writes `report.json`, the fitted URDF, `model.fitted.json` and one SVG per joint into `dir`.
pub fn write_outputs(dir: &Path, model: &GapModel, report: &GapReport) -> Result<Vec<std::path::PathBuf>, GapError> {
    std::fs::create_dir_all(dir).map_err(|source| crate::io::IoError { path: dir.to_path_buf(), action: "create", source })?;
    let mut written = Vec::new();
    let mut put = |name: &str, bytes: &[u8]| -> Result<(), GapError> {
        let path = dir.join(name);
        crate::io::atomic_write(&path, bytes)?;
        written.push(path);
        Ok(())
    };
    let json = serde_json::to_string_pretty(report).unwrap_or_default();
    put("report.json", json.as_bytes())?;
    put(&report.fitted_model, report::fitted_urdf(model, &report.effects, &report.com_shift_m)?.as_bytes())?;
    let model_name = model.file.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned());
    put("model.fitted.json", report::sidecar_json(report, &model_name).as_bytes())?;
    for s in &report.series {
        let safe: String = s.joint.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '_' }).collect();
        put(&format!("plot_{safe}.svg"), plot::joint_svg(s).as_bytes())?;
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_placed_at_the_edge_of_the_motion_that_no_replay_feels_is_not_material() {
        // Regression (PhysX flap with a spring): a stop at the highest recorded angle, 1.8 rad,
        // whose position the output error left at ± 1.3e6 rad, was reported beside the spring.
        let rules = effort::SelectionRules::default();
        let stop = Effect { kind: EffectKind::EndStop, params: vec![1.799, 0.0], blocks_upward: true };
        assert!(not_material(&stop, &[1.3e6, 1.3e6], &rules, 1.8));
        // A stop the motion runs into is located to millimetres.
        assert!(!not_material(&stop, &[0.006, 0.014], &rules, 1.8));
        // Not yet refined (effort space gives no σ): kept for the refinement to judge.
        assert!(!not_material(&stop, &[f64::NAN, f64::NAN], &rules, 1.8));
    }
}
