//! The effort-space way through [`super::analyze`]: identification on the whole recording and on
//! its first part ([`super::effort`]), replays of the model as written and as fitted through the
//! whole tree ([`super::chain`]), and the report's pieces per joint.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use glam::DVec3;
use rayon::prelude::*;

use super::chain::{ChainInput, instability_rate, replay};
use super::effects::{Effect, EffectKind, JointPhysics};
use super::effort::{Bandwidth, EffortProblem, Exclusions, HELD_OUT_HORIZON_S, JointFinding, ModelReading, RestsLeftOut, RowInfo};
use super::effort::{SelectionRules, Signals, Terms, signals};
use super::effort::{in_serial_chain, moving_part};
use super::locate::{Span, mismatch_spans, rmse_over};
use super::report::{self, Conditions, EffectReport, JointSeries, Mismatch, RmsePair};
use super::rests::{coulomb_at_rest, dwelling_rests, held_rests};
use super::smooth::Smoother;
use super::stops::{FoundStop, StopRules, find_stops};
use super::tilt::{base_lean, world_from_base};
use super::{GapConfig, GapError, GapModel, Given, JointOutcome, Recording, effect_report, rmse_pair};
use crate::dynamics::MultiBody;

/// Samples within this share of the travel (or this many noise σ) of a modelled stop are in
/// contact with it: the stop's force is not in inverse dynamics, so they are left out.
const CONTACT_SHARE: f64 = 0.01;

/// Least share of the samples free of contact with modelled stops for effort space: a fifth of
/// the recording (a lid pushed open now and then and resting shut in between still gives the
/// regression some hundreds of free samples; below that, cross-validation blocks run empty).
const MIN_FREE_SHARE: f64 = 0.2;

/// Half-gain frequencies of the parallel filter tried, as multiples of the motion's dominant
/// frequency, widest first ([`analyze_effort_space`]).
pub(super) const EQUATION_BANDS: [f64; 3] = [5.0, 2.5, 1.5];

/// Per identified joint: samples in contact with a modelled stop, from the measured positions
/// (within [`CONTACT_SHARE`] of the travel or four noise σ of the limit, and a turning point
/// within a sample's travel of it: [`unseen_approach`]), widened by the smoothing window, since
/// the smoothed acceleration smears an impact over it.
fn contact_masks(model: &GapModel, time_s: &[f64], positions: &[Vec<f64>], rows: &[usize], bandwidth: &Bandwidth) -> Vec<Vec<bool>> {
    let half_width_s = bandwidth.support_s();
    let dofs = model.dofs();
    let n = time_s.len();
    rows.iter()
        .map(|&j| {
            let joint = &model.joints[j];
            let y = &positions[dofs.iter().position(|&x| x == j).unwrap_or(0)];
            let (lo, hi) = y.iter().filter(|q| q.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| (a.min(q), b.max(q)));
            let band = (CONTACT_SHARE * (hi - lo).max(1e-6)).max(4.0 * super::locate::noise_sigma(time_s, y));
            let (below, above) = (unseen_approach(y, -1.0), unseen_approach(y, 1.0));
            let mut touching: Vec<bool> = (0..n)
                .map(|i| {
                    y[i].is_finite()
                        && (joint.lower.is_some_and(|l| y[i] <= l + band + below[i])
                            || joint.upper.is_some_and(|u| y[i] >= u - band - above[i]))
                })
                .collect();
            touch_through_gaps(&mut touching, time_s, y, bandwidth.narrow_s);
            let mut mask = vec![false; n];
            widen_into(&mut mask, &touching, time_s, half_width_s);
            mask
        })
        .collect()
}

/// Per sample, how close to a stop it lets the joint have come unseen: at a turning point (a
/// sample beyond neither finite neighbour towards `side`, -1 for a lower stop and +1 for an upper
/// one), the shorter of its distances to those neighbours (a bounce moves on both sides); 0
/// elsewhere. A joint that bounces off its stop between two samples (ODE's stops, a real lid
/// dropped shut) turns round short of it in the record, its impact never seen within the contact
/// band, yet the impulse lands in the smoothed acceleration.
fn unseen_approach(y: &[f64], side: f64) -> Vec<f64> {
    let finite: Vec<usize> = (0..y.len()).filter(|&i| y[i].is_finite()).collect();
    let mut reach = vec![0.0; y.len()];
    for w in finite.windows(3) {
        let (a, i, b) = (y[w[0]], y[w[1]], y[w[2]]);
        // A bounce moves on both sides of its turn (a joint leaving a rest is no turn): the
        // shorter of its two steps.
        if side * (i - a) >= 0.0 && side * (i - b) >= 0.0 {
            reach[w[1]] = (i - a).abs().min((i - b).abs());
        }
    }
    reach
}

/// Marks every run of missing positions in `y` longer than `narrow_s` (the differentiator's
/// half-width) that a contact sample borders (just before or just after it) as contact too:
/// nothing measured says where the joint was meanwhile, and a lid seen falling before a tracking
/// dropout and resting shut after it hit its stop inside the gap, where the derivatives are
/// interpolated across the impact. A shorter gap lies within the smoothing window of the contact
/// beside it, whose widening covers it already.
fn touch_through_gaps(touching: &mut [bool], time_s: &[f64], y: &[f64], narrow_s: f64) {
    let n = y.len();
    let mut i = 0;
    while i < n {
        if y[i].is_finite() {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && !y[i].is_finite() {
            i += 1;
        }
        let bordered = (start > 0 && touching[start - 1]) || (i < n && touching[i]);
        let before = time_s[start.saturating_sub(1)];
        let after = time_s[i.min(n - 1)];
        let long = after - before > narrow_s;
        if bordered && long {
            touching[start..i].iter_mut().for_each(|t| *t = true);
        }
    }
}

/// The physics of every dof under `effects` (per model joint), and the tree with heavier parts
/// and its base turned by a base tilt (under `gravity`).
fn fitted_physics(
    model: &GapModel,
    tree: &MultiBody,
    body_of_link: &[Option<usize>],
    effects: &BTreeMap<usize, Vec<Effect>>,
    first_moments: &[(usize, DVec3)],
    gravity: DVec3,
) -> (Vec<JointPhysics>, MultiBody) {
    let mut scaled = tree.clone();
    for w in effects.values().flatten().filter_map(base_lean) {
        scaled = scaled.with_base_rotated(world_from_base(w, gravity.normalize_or_zero()));
    }
    let physics = model
        .dofs()
        .into_iter()
        .map(|j| {
            let list = effects.get(&j).map_or(&[][..], Vec::as_slice);
            let mut p = JointPhysics::with_effects(&model.joints[j], list);
            // The tree carries a heavier part (inertia and weight); the joint's own scale is not
            // applied twice.
            if (p.mass_scale - 1.0).abs() > 1e-12 {
                if let Some(b) = body_of_link[model.joints[j].child] {
                    for part in moving_part(tree, b) {
                        scaled = scaled.with_body_scaled(part, p.mass_scale);
                    }
                }
                p.mass_scale = 1.0;
            }
            p
        })
        .collect();
    // The model's own first-moment error, fitted beside the effects, after any heavier part.
    for &(body, h) in first_moments {
        scaled = scaled.with_first_moment_added(body, h);
    }
    (physics, scaled)
}

/// The first-moment changes of all `findings` ([`JointFinding::first_moments`]).
fn first_moments_of(findings: &[JointFinding]) -> Vec<(usize, DVec3)> {
    findings.iter().flat_map(|f| f.first_moments.iter().copied()).collect()
}

/// Unmodelled stops of every identified joint (same order as `rows_info`).
fn unmodelled_stops(model: &GapModel, rec: &Recording, positions: &[Vec<f64>], rows_info: &[RowInfo]) -> Vec<Vec<FoundStop>> {
    let rules = StopRules::default();
    rows_info
        .iter()
        .map(|info| {
            let joint = &model.joints[info.joint];
            if joint.kind == super::model::DofKind::Continuous {
                return Vec::new();
            }
            let y = &positions[info.dof];
            let noise = super::locate::noise_sigma(&rec.time_s, y);
            find_stops(&rec.time_s, y, &info.residual, info.effort_rms, noise, (joint.lower, joint.upper), &rules)
        })
        .collect()
}

/// Marks samples within `half_width_s` of a contact sample.
fn widen_into(mask: &mut [bool], contact: &[bool], time_s: &[f64], half_width_s: f64) {
    let times: Vec<f64> = (0..contact.len()).filter(|&i| contact[i]).map(|i| time_s[i]).collect();
    for (i, m) in mask.iter_mut().enumerate() {
        let t = time_s[i];
        let k = times.partition_point(|&x| x < t - half_width_s);
        if times.get(k).is_some_and(|&x| x <= t + half_width_s) {
            *m = true;
        }
    }
}

fn add_stop(f: &mut JointFinding, stop: &FoundStop) {
    f.effects.push(stop.effect.clone());
    f.param_std.push(vec![f64::NAN; 2]);
    f.confidence.push(stop.confidence);
    f.effect_rms.push(stop.push);
}

fn effects_by_joint(findings: &[JointFinding]) -> BTreeMap<usize, Vec<Effect>> {
    findings.iter().map(|f| (f.joint, f.effects.clone())).collect()
}

/// The findings of `terms` in `problem`, with the unmodelled stops found per row.
/// A stop whose push the joint's dry friction could hold by itself ([`FoundStop::beyond`]) is
/// not reported: friction holds a joint wherever it rests, a stop only at its position.
fn findings_with_stops(problem: &EffortProblem<'_>, terms: &Terms, stops: &[Vec<FoundStop>]) -> Vec<JointFinding> {
    let mut findings = problem.findings(terms);
    let rules = StopRules::default();
    for (f, found) in findings.iter_mut().zip(stops) {
        let (held, effort_rms) = (f.friction_at_rest().map_or(0.0, |(level, _)| level), f.effort_rms);
        for stop in found.iter().filter(|s| s.beyond(held, effort_rms, &rules)) {
            add_stop(f, stop);
        }
    }
    findings
}

/// What identification at one bandwidth found: on the whole recording and on its part before the
/// held-out part (`train`), each problem with the terms it holds now.
struct Identified<'a> {
    band: Bandwidth,
    /// Length of the pieces the held-out part is replayed in: one period of the motion, and
    /// once the tree is known ([`analyze_effort_space`]) no longer than [`chain_horizon_s`].
    horizon_s: f64,
    sig: Signals,
    rows: Vec<usize>,
    problem: EffortProblem<'a>,
    terms: Terms,
    train: Option<(EffortProblem<'a>, Terms)>,
    stops: Vec<Vec<FoundStop>>,
    findings: Vec<JointFinding>,
    train_findings: Option<Vec<JointFinding>>,
    /// What the chain's held-out replay overruled, per row: the term effort space chose and the
    /// line that says why it is not reported (added to the row's rejected once the findings are
    /// final: every change of the terms computes the findings again).
    overruled: Vec<(usize, String, String)>,
}

impl Identified<'_> {
    /// The findings with what the replay overruled named among each row's rejected (in place of
    /// any earlier line on the same kind).
    fn findings_with_overruled(&self) -> Vec<JointFinding> {
        let mut findings = self.findings.clone();
        for (r, term, line) in &self.overruled {
            let rejected = &mut findings[*r].rejected;
            rejected.retain(|l| !l.starts_with(&format!("{term}:")));
            rejected.push(line.clone());
        }
        findings
    }

    /// The largest share of its joint's own effort that the fitted model leaves unexplained, over
    /// the joints whose verdict effort space gives (a joint alone on its body is judged again by
    /// its simulation, where stops and sticking are modelled).
    fn unexplained_share(&self, model: &GapModel) -> f64 {
        self.findings
            .iter()
            .filter(|f| in_serial_chain(model, f.joint))
            .map(|f| f.cv_rms_after / f.effort_rms.max(1e-12))
            .fold(0.0, f64::max)
    }
}

/// The bands of [`EQUATION_BANDS`] for these positions, widest first; bands that clamp to the
/// same filter (a slow motion reaches the widest filter allowed at every multiple) are one band,
/// identified once.
fn equation_bands(time_s: &[f64], positions: &[Vec<f64>], rules: &SelectionRules) -> Vec<Bandwidth> {
    let mut bands: Vec<Bandwidth> = Vec::new();
    for &cutoff in &EQUATION_BANDS {
        let band = super::effort::bandwidth(time_s, positions, rules.smoothing_half_width_s, cutoff);
        // σ grows as the band narrows; one clamped to the last band's σ is that band.
        if bands.last().is_none_or(|last| band.sigma_s > last.sigma_s * (1.0 + SAME_FILTER_SHARE)) {
            bands.push(band);
        }
    }
    bands
}

/// Relative difference of two filters' σ within which they are one filter ([`equation_bands`]).
const SAME_FILTER_SHARE: f64 = 1e-9;

/// Whether the rigid bodies stop making the recorded motion between this band and a narrower one
/// (its filter σ `narrower_sigma_s`): on some chain joint with a recorded effort, the model as
/// written and the fitted model both need there at least [`BEYOND_THE_BODIES`] × the effort the
/// recording holds there. Then neither explains the recording there however the two align
/// (‖m‖ ≥ 2‖e‖ ⇒ ‖e − m‖ ≥ ‖e‖: worse than no model), though the fit chose its terms to: the
/// positions move where the efforts do not, as a sensor read through a compliant drive sways
/// or a controller chatters. The real double pendulum's encoders show its excitation's third
/// harmonic, which its motors never drive (the model as written needs 4× the recorded effort
/// there, the fitted 2.4×); the fit in that band took a lighter lower link and 56 % of the
/// shoulder's friction to match it. A model's weight error scales what it needs at every
/// frequency, and the fitted model takes it out; friction that turns round ahead of the
/// speed (`MuJoCo`'s regularised friction loss) leaves the fitted model needing more than the
/// recording (1.8× on a Panda's wrist), the model as written not. What the bodies need there
/// must also be material, [`SelectionRules::min_effort_share`] of the joint's own effort (a
/// smooth drive leaves a band above its motion all but empty, where the ratio of two nothings
/// says nothing).
fn beyond_the_bodies(found: &Identified, input: &BandInput, narrower_sigma_s: f64) -> bool {
    let (model, rec) = (input.model, input.rec);
    let sig = &found.sig;
    // Gaussians compose: the narrower filter is this one followed by one of σ² = σn² − σ².
    let extra_s = (narrower_sigma_s.powi(2) - sig.band.sigma_s.powi(2)).max(0.0).sqrt();
    let dofs = model.dofs();
    found.findings.iter().any(|f| {
        let name = &model.joints[f.joint].name;
        let Some(e) = dofs.iter().position(|&x| x == f.joint).and_then(|d| sig.effort[d].as_ref()) else { return false };
        if !in_serial_chain(model, f.joint) || !rec.joint_effort.contains_key(name) {
            return false;
        }
        let n = e.len();
        let (written, fitted) = (&f.residual_before, &f.residual_after);
        let valid: Vec<bool> = (0..n).map(|i| e[i].is_finite() && written[i].is_finite() && fitted[i].is_finite()).collect();
        let narrower = Smoother::new(&sig.time_s, &valid, &sig.time_s, extra_s);
        let used: Vec<usize> = (0..n).filter(|&i| valid[i]).collect();
        let above = |y: &[f64]| {
            let low = narrower.apply(y);
            let (sum, count) =
                used.iter().filter(|&&i| low[i].is_finite()).fold((0.0, 0usize), |(s, c), &i| (s + (y[i] - low[i]).powi(2), c + 1));
            (sum / count.max(1) as f64).sqrt()
        };
        let need = |residual: &[f64]| above(&(0..n).map(|i| e[i] - residual[i]).collect::<Vec<f64>>());
        let (recorded, needed) = (above(e), need(written).min(need(fitted)));
        // Nothing to compare (no sample in reach of both filters) is no evidence.
        needed > 0.0 && needed >= BEYOND_THE_BODIES * recorded && needed >= input.rules.min_effort_share * f.effort_rms
    })
}

/// What the rigid bodies may need, above a band, over the effort recorded there before the band
/// is beyond them ([`beyond_the_bodies`]): from ‖e − m‖ ≥ ‖m‖ − ‖e‖, the least ratio at which a
/// model explains less than nothing however it aligns with the recording.
const BEYOND_THE_BODIES: f64 = 2.0;

/// What every band's identification reads: the model, the recording, its positions and applied
/// efforts per dof (NaN where a position is not observed; zero where no effort is recorded), the
/// identified rows (model joint indices), gravity, the start of the held-out part and the rules.
struct BandInput<'a> {
    model: &'a GapModel,
    rec: &'a Recording,
    positions: &'a [Vec<f64>],
    efforts: &'a [Option<Vec<f64>>],
    rows: &'a [usize],
    gravity: DVec3,
    t_split: f64,
    rules: &'a SelectionRules,
}

/// Identification with the equation of motion low-passed as `band` says: on the whole recording
/// and on its part before `t_split`, unmodelled stops found and their contacts left out. None
/// when no joint has enough free motion.
fn identify_at<'a>(input: &BandInput<'a>, band: Bandwidth) -> Option<Identified<'a>> {
    let BandInput { model, rec, positions, efforts, rows, gravity, t_split, rules } = *input;
    let n = rec.time_s.len();
    // The contact exclusions cover the whole support of the filters.
    let support_s = band.support_s();
    let sig = signals(&rec.time_s, positions, efforts, &band);
    // Joints that spend most of the recording against their stops leave effort space too little
    // free motion to regress on; position space (simulation through the stops) takes them.
    let (rows, excluded): (Vec<usize>, Vec<Vec<bool>>) = rows
        .iter()
        .copied()
        .zip(contact_masks(model, &rec.time_s, positions, rows, &band))
        .filter(|(_, mask)| mask.iter().filter(|&&x| !x).count() as f64 >= MIN_FREE_SHARE * n as f64)
        .unzip();
    if rows.is_empty() {
        return None;
    }
    let everything = vec![true; n];
    let train_part: Vec<bool> = rec.time_s.iter().map(|&t| t < t_split).collect();
    // The model's efforts are the same for every reading below: computed once.
    let reading = ModelReading::new(model, &sig, gravity, &rows, rules)?;
    let mut excluded = Exclusions { samples: excluded, rests: Vec::new() };
    let first = EffortProblem::new(model, &sig, &reading, &excluded, &everything, rules.clone())?;
    let stops = unmodelled_stops(model, rec, positions, first.rows());
    for (r, found) in stops.iter().enumerate() {
        for stop in found {
            widen_into(&mut excluded.samples[r], &stop.contact, &rec.time_s, support_s);
        }
    }
    // The whole recording's reading (reusing `first` where no stop was left out) and the training
    // part's.
    let read_whole = |excluded: &Exclusions, first: Option<EffortProblem<'a>>| {
        let problem = match first {
            Some(p) if stops.iter().all(Vec::is_empty) => p,
            first => EffortProblem::new(model, &sig, &reading, excluded, &everything, rules.clone()).or(first)?,
        };
        let terms = problem.chosen_terms();
        let findings = findings_with_stops(&problem, &terms, &stops);
        Some((problem, terms, findings))
    };
    let read_train = |excluded: &Exclusions| {
        let train = EffortProblem::new(model, &sig, &reading, excluded, &train_part, rules.clone()).map(|p| {
            let t = p.chosen_terms();
            (p, t)
        });
        let train_findings = train.as_ref().map(|(p, t)| findings_with_stops(p, t, &stops));
        (train, train_findings)
    };
    // The two are independent: in parallel.
    let (whole, train) = rayon::join(|| read_whole(&excluded, Some(first)), || read_train(&excluded));
    let ((problem, terms, findings), (train, train_findings)) =
        read_without_rests(&read_whole, &read_train, (whole?, train), &sig, excluded, rules);
    let horizon_s = band.held_out_horizon_s();
    Some(Identified { band, horizon_s, sig, rows, problem, terms, train, stops, findings, train_findings, overruled: Vec::new() })
}

/// One reading of the whole recording: the problem, its chosen terms, its findings.
type WholeReading<'a> = (EffortProblem<'a>, Terms, Vec<JointFinding>);
/// One reading of the training part, where it could be made, and its findings.
type TrainReading<'a> = (Option<(EffortProblem<'a>, Terms)>, Option<Vec<JointFinding>>);

/// The readings `read` (the whole recording's and the training part's, both with `excluded` left
/// out) made again without the rests they should not be read through ([`super::rests`]). Where dry
/// friction holds a joint at rest ([`without_rests`]), both are made again without the rests the
/// whole recording's reading finds, with the transition it read: the training part's leaves out
/// the same rests so that its candidates are the whole reading's term for term (the held-out
/// replay's settling reads one in the other's terms: `EffortProblem::read_as`); the held-out part
/// takes part in choosing which samples are rests and the transition kept. Then rows whose rests
/// may keep the reading from explaining them, or whose held rests the first pass kept for want of
/// samples ([`without_unexplained_rests`]), are read again without them, kept where the reading
/// then names Coulomb friction that could hold those rests ([`held_rests`]), and for a row its
/// reading with the rests explained, where the training part's reading does too. Where either
/// reading fails without the rests, both stay as they were.
fn read_without_rests<'a>(
    read_whole: &(impl Fn(&Exclusions, Option<EffortProblem<'a>>) -> Option<WholeReading<'a>> + Sync),
    read_train: &(impl Fn(&Exclusions) -> TrainReading<'a> + Sync),
    read: (WholeReading<'a>, TrainReading<'a>),
    sig: &Signals,
    mut excluded: Exclusions,
    rules: &SelectionRules,
) -> (WholeReading<'a>, TrainReading<'a>) {
    let (mut whole, mut train) = read;
    if let Some(without) = without_rests(&whole.2, whole.0.rows(), sig, &excluded, rules)
        && let (Some(w), t @ (Some(_), _)) = rayon::join(|| read_whole(&without, None), || read_train(&without))
    {
        (whole, train) = (w, t);
        excluded = without;
    }
    let Some((without, tried)) = without_unexplained_rests(&whole.2, whole.0.rows(), sig, &excluded, rules) else {
        return (whole, train);
    };
    let (Some(w), t @ (Some(_), _)) = rayon::join(|| read_whole(&without, None), || read_train(&without)) else {
        return (whole, train);
    };
    let n = sig.time_s.len();
    // The new reading must name friction that could hold the rests. A row its reading with the
    // rests explained went below the first pass's floor ([`SelectionRules::min_kept_without_rests`])
    // for its rests alone, and that floor guards the training part's reading, whose replay judges
    // the held-out part: there the training part's reading must hold them too.
    let holds = |&(r, explained): &(usize, bool)| {
        let (Some(info), Some(f)) = (w.0.rows().get(r), w.2.get(r)) else { return false };
        let used: Vec<bool> = (0..n).map(|i| sig.usable[i] && !excluded.samples[r][i]).collect();
        let speed = sig.speed(info.dof);
        let held = |f: &JointFinding| held_rests(f, &speed, &used, rules).is_some();
        let train_holds = !explained || t.1.as_ref().is_none_or(|found| found.get(r).is_some_and(held));
        held(f) && train_holds
    };
    if tried.iter().all(holds) { (w, t) } else { (whole, train) }
}

/// `excluded` with the rests that dry friction holds ([`super::rests`]) of each row of the
/// reading `findings` (`rows`: its rows, over `sig`) left out too ([`leave_out_rests`], keeping
/// [`SelectionRules::min_kept_without_rests`]); None where no row has such rests.
fn without_rests(
    findings: &[JointFinding],
    rows: &[RowInfo],
    sig: &Signals,
    excluded: &Exclusions,
    rules: &SelectionRules,
) -> Option<Exclusions> {
    let (out, _) = leave_out_rests(rows, sig, excluded, rules.min_kept_without_rests, |r, speed, used| {
        let held = held_rests(findings.get(r)?, speed, used, rules)?;
        Some((held.rests, held.transition_speed, ()))
    })?;
    Some(out)
}

/// `excluded` with the rests of each row that dwells at rest ([`dwelling_rests`]) while the
/// reading `findings` leaves a material share of its effort unexplained ([`unexplained`], dry
/// friction granted its whole range at rest), or whose rests that reading's friction holds
/// ([`held_rests`]) but [`without_rests`] kept for want of samples, left out too
/// ([`leave_out_rests`], keeping [`SelectionRules::min_kept_without_unexplained_rests`]), with
/// those rows, each with whether its reading explained it (tried for its held rests alone); None
/// where no row is such. What holds a joint at rest can be what keeps a reading
/// from explaining it: stuck, the residual is whatever holds the joint, often of the other sign
/// to what the motion shows (Bullet's heavier lid, held near upright by its hinge's friction for
/// 78 % of the usable samples, was read with its rests as viscous damping and `unknown` at 54 %;
/// without them, numpy on the same residual: the heavier lid and a Coulomb level of 1.203 against
/// the truth's 1.2), and a reading that names the friction may still be pulled off its level and
/// the part's weight by rests too many for [`SelectionRules::min_kept_without_rests`] (the `MuJoCo`
/// Panda stuck by its friction: joint 2's damping unnamed and its friction 12 % high). The Coulomb
/// candidates keep the transition of the dry friction read with the rests, or, without one, the
/// speed below which the joint counts as at rest (a law that holds it there turns within it). The reading is kept only
/// where it then names Coulomb friction that could hold these rests, as [`held_rests`] judges it
/// (its level at least [`SelectionRules::min_held_friction_over_gravity`] of the gravity effort
/// the joint carries without them): a reading consistent with its own exclusions
/// ([`read_without_rests`]).
fn without_unexplained_rests(
    findings: &[JointFinding],
    rows: &[RowInfo],
    sig: &Signals,
    excluded: &Exclusions,
    rules: &SelectionRules,
) -> Option<(Exclusions, Vec<(usize, bool)>)> {
    leave_out_rests(rows, sig, excluded, rules.min_kept_without_unexplained_rests, |r, speed, used| {
        let f = findings.get(r)?;
        // Rests that keep the reading from explaining the joint, or rests its dry friction holds
        // that the first pass kept for want of samples.
        let explained = !unexplained(rules, &f.with_friction_at_rest(speed));
        if explained && held_rests(f, speed, used, rules).is_none() {
            return None;
        }
        let dwelling = dwelling_rests(speed, used, rules)?;
        let transition_speed = coulomb_at_rest(f).map_or(dwelling.rest_speed, |(_, speed)| speed);
        Some((dwelling.rests, transition_speed, explained))
    })
}

/// `excluded` with the rests `rests_of` gives a row (from its index, its smoothed speed and the
/// samples its row uses: the rests, the transition speed of the dry friction read with them or
/// the speed it turns within, and a note of the caller's on the row) left out too, widened by the
/// filters' support (every filtered term there blends the rest in), where the row keeps
/// `min_kept` of the usable samples, with the rows so left out and their notes; None where no row
/// not yet without its rests has such rests.
fn leave_out_rests<T>(
    rows: &[RowInfo],
    sig: &Signals,
    excluded: &Exclusions,
    min_kept: f64,
    rests_of: impl Fn(usize, &[f64], &[bool]) -> Option<(Vec<bool>, f64, T)>,
) -> Option<(Exclusions, Vec<(usize, T)>)> {
    let n = sig.time_s.len();
    let usable = sig.usable.iter().filter(|&&u| u).count().max(1) as f64;
    let rests_before = |r: usize| excluded.rests.get(r).copied().flatten();
    let mut out = Exclusions { samples: excluded.samples.clone(), rests: (0..rows.len()).map(rests_before).collect() };
    let mut left_out = Vec::new();
    for (r, info) in rows.iter().enumerate() {
        if rests_before(r).is_some() {
            continue;
        }
        let speed = sig.speed(info.dof);
        let used: Vec<bool> = (0..n).map(|i| sig.usable[i] && !excluded.samples[r][i]).collect();
        let Some((rests, transition_speed, note)) = rests_of(r, &speed, &used) else { continue };
        let mut mask = excluded.samples[r].clone();
        widen_into(&mut mask, &rests, &sig.time_s, sig.band.support_s());
        if ((0..n).filter(|&i| sig.usable[i] && !mask[i]).count() as f64) < min_kept * usable {
            continue;
        }
        let share = (0..n).filter(|&i| used[i] && mask[i]).count() as f64 / usable;
        out.samples[r] = mask;
        out.rests[r] = Some(RestsLeftOut { transition_speed, share });
        left_out.push((r, note));
    }
    (!left_out.is_empty()).then_some((out, left_out))
}

/// A training reading without one term, replayed ([`HeldOutReplay::replay_without`]).
struct WithoutTerm {
    terms: Terms,
    findings: Vec<JointFinding>,
    /// Its held-out replay.
    held: Vec<Vec<f64>>,
    /// The joint's held-out replay error (relative to the model as written) with the term and
    /// without it.
    with_it: f64,
    without_it: f64,
}

/// What a chain's held-out replay is judged against: the recording, the tree, and the replay of
/// the model as written from the same states.
struct HeldOutReplay<'a> {
    model: &'a GapModel,
    rec: &'a Recording,
    positions: &'a [Vec<f64>],
    tree: &'a MultiBody,
    body_of_link: &'a [Option<usize>],
    input: &'a ChainInput<'a>,
    t_split: f64,
    held_before: &'a [Vec<f64>],
}

impl HeldOutReplay<'_> {
    /// The dof index of model joint `joint` where it is a joint of a chain (whose replay is the
    /// whole tree's); None for a joint alone on its body.
    fn chain_dof(&self, joint: usize) -> Option<usize> {
        in_serial_chain(self.model, joint).then(|| self.model.dofs().iter().position(|&j| j == joint)).flatten()
    }

    /// The chain under `findings` replayed through the held-out part (samples from `t_split`
    /// on) in pieces of `horizon_s`, each from the measured state.
    fn replay(&self, findings: &[JointFinding], sig: &Signals, horizon_s: f64) -> Vec<Vec<f64>> {
        let (physics, fitted) = fitted_physics(
            self.model,
            self.tree,
            self.body_of_link,
            &effects_by_joint(findings),
            &first_moments_of(findings),
            self.input.gravity,
        );
        replay_pieces(&fitted, &physics, self.input, sig, self.t_split, horizon_s)
    }

    /// Row r's refinement of dry friction in the reading `(problem, terms)` replaced by its base
    /// law ([`EffortProblem::base_reading`]): the base reading, its findings and its held-out
    /// replay (`at`: the stops, signals and piece length the replays use); None where the reading
    /// holds no refinement on row r.
    fn base_replayed(
        &self,
        problem: &EffortProblem<'_>,
        terms: &Terms,
        (stops, sig, horizon_s): (&[Vec<FoundStop>], &Signals, f64),
        r: usize,
    ) -> Option<(Terms, Vec<JointFinding>, Vec<Vec<f64>>)> {
        let base = problem.base_reading(terms, r)?;
        let findings = findings_with_stops(problem, &base, stops);
        let replayed = self.replay(&findings, sig, horizon_s);
        Some((base, findings, replayed))
    }

    /// Row r's term of `kind` taken out of the training reading `(problem, terms)` and the
    /// held-out part replayed without it (`at`: the stops, signals and piece length the replays
    /// use): the reading without it, its findings and replay, and the joint's (chain dof d)
    /// replay error with it (its replay `held`) and without. None where the reading holds no
    /// such term.
    fn replay_without(
        &self,
        (problem, terms): (&EffortProblem<'_>, &Terms),
        (stops, sig, horizon_s): (&[Vec<FoundStop>], &Signals, f64),
        held: &[Vec<f64>],
        (r, d, kind): (usize, usize, EffectKind),
    ) -> Option<WithoutTerm> {
        let terms = problem.without(terms, r, kind)?;
        let findings = findings_with_stops(problem, &terms, stops);
        let replayed = self.replay(&findings, sig, horizon_s);
        let (with_it, without_it) = (self.score(held, &[d]), self.score(&replayed, &[d]));
        Some(WithoutTerm { terms, findings, held: replayed, with_it, without_it })
    }

    /// Mean over `dofs` of the held-out squared error of `replayed` ([`Self::replay`]), each
    /// relative to that of the model as written over the same samples; infinite when the replay
    /// leaves the finite numbers where the recording and the model as written do not (an
    /// unstable law); NaN when no dof can be judged.
    fn score(&self, replayed: &[Vec<f64>], dofs: &[usize]) -> f64 {
        let mut ratios = Vec::new();
        for &d in dofs {
            let (mut mine, mut theirs, mut count) = (0.0, 0.0, 0usize);
            for i in (0..self.rec.time_s.len()).filter(|&i| self.rec.time_s[i] >= self.t_split) {
                let (y, reference) = (self.positions[d][i], self.held_before[d][i]);
                if !(y.is_finite() && reference.is_finite()) {
                    continue;
                }
                let e = y - replayed[d][i];
                if !e.is_finite() {
                    return f64::INFINITY;
                }
                mine += e * e;
                theirs += (y - reference).powi(2);
                count += 1;
            }
            if count > 0 && theirs > 0.0 {
                ratios.push(mine / theirs);
            }
        }
        if ratios.is_empty() { f64::NAN } else { ratios.iter().sum::<f64>() / ratios.len() as f64 }
    }
}

/// Effort space's reading of each chain joint's friction, checked against the motion it
/// predicts: where a joint holds dry friction or viscous damping (one of the two), and the other
/// law passes the selection rules in its place, it is fitted on the same data before the
/// held-out part, and the whole chain is replayed through that part under both, where effort
/// space cannot tell the two apart (the other law's held-out effort error is within
/// 1 / (1 − [`SelectionRules::min_replay_gain`]) of its reading's); the other
/// reading replaces effort space's when its replay error is lower by
/// [`SelectionRules::min_replay_gain`], the joint's own replay error is no higher, and the
/// whole recording's problem reads the joint the same way. Equation error (effort space) weighs
/// the efforts sample by sample and is blind to how a difference in the law adds up over a
/// swing; output error sees it (Gautier's DIDIM validates an IDIM model the same way). A joint
/// alone on its body is refined by its own simulation. The reading replaced is named among the
/// rejected, with the replay's figures.
///
/// Returns the held-out replay of the training findings it ends with, when it made one (none
/// without a joint in a chain).
fn settle_friction_by_replay(replay: &HeldOutReplay<'_>, found: &mut Identified<'_>, rules: &SelectionRules) -> Option<Vec<Vec<f64>>> {
    let (train_problem, train_terms) = found.train.as_mut()?;
    let train_findings = found.train_findings.as_mut()?;
    let dofs = replay.model.dofs();
    let chain: Vec<usize> = (0..found.rows.len()).filter(|&r| in_serial_chain(replay.model, found.rows[r])).collect();
    if chain.is_empty() {
        return None;
    }
    let chain_dofs: Vec<usize> = chain.iter().filter_map(|&r| dofs.iter().position(|&j| j == found.rows[r])).collect();
    let horizon_s = found.horizon_s;
    let mut held = replay.replay(train_findings, &found.sig, horizon_s);
    let mut current = replay.score(&held, &chain_dofs);
    for &r in &chain {
        let Some(alt) = found.problem.other_friction_reading(&found.terms, r) else { continue };
        // The motion arbitrates only where the efforts cannot: the other law's held-out effort
        // error within the margin the replay must win by. `MuJoCo`'s Pandas against 5 %-off
        // models (one with the real arm's smooth friction, one with plain dry friction) had four
        // joints of dry friction turned to damping whose held-out effort error effort space put
        // 2.8–11× above dry friction's; the real double pendulum's elbow, turned the other way,
        // 1.03×. Judged first: the training part's other reading is not needed where this fails.
        if found.problem.held_out_sse(&alt, r) * (1.0 - rules.min_replay_gain) > found.problem.held_out_sse(&found.terms, r) {
            continue;
        }
        let Some(alt_train) = train_problem.other_friction_reading(train_terms, r) else { continue };
        let (Some(law), Some(old)) = (found.problem.friction_law(&alt, r), found.problem.friction_law(&found.terms, r)) else {
            continue;
        };
        if Some(law) != train_problem.friction_law(&alt_train, r) {
            continue;
        }
        let alt_train_findings = findings_with_stops(train_problem, &alt_train, &found.stops);
        let alt_held = replay.replay(&alt_train_findings, &found.sig, horizon_s);
        let s = replay.score(&alt_held, &chain_dofs);
        // The other law must predict its own joint's motion no worse: a chain's mean can fall
        // by what the swap does to the others while the joint itself replays worse (an
        // identified Panda's shoulder read as damping: the chain 71 % better, the joint 41 %
        // worse).
        let own_no_worse = replay.chain_dof(found.rows[r]).is_some_and(|d| replay.score(&alt_held, &[d]) <= replay.score(&held, &[d]));
        if s < (1.0 - rules.min_replay_gain) * current && own_no_worse {
            held = alt_held;
            *train_terms = alt_train;
            *train_findings = alt_train_findings;
            found.findings = findings_with_stops(&found.problem, &alt, &found.stops);
            found.terms = alt;
            found.overruled.push((
                r,
                old.name().to_string(),
                format!(
                    "{}: effort space chose it, but with {} in its place the chain replays its held-out part with {:.0} % less \
                 squared error (relative to the model as written: {:.2e} against {:.2e}), so the law that predicts the motion is reported",
                    old.name(),
                    law.name(),
                    100.0 * (1.0 - s / current),
                    s,
                    current
                ),
            ));
            current = s;
        }
    }
    Some(held)
}

/// Whether a term shows in the motion: the joint's held-out replay error with it (`with_it`,
/// relative to the model as written) is below the one without it by the cut a term must bring in
/// effort space ([`SelectionRules::min_cv_gain`]). A replay that cannot be judged (not finite)
/// keeps the term.
fn shows_in_motion(rules: &SelectionRules, with_it: f64, without_it: f64) -> bool {
    !(with_it.is_finite() && without_it.is_finite()) || with_it < (1.0 - rules.min_cv_gain) * without_it
}

/// A refinement of a chain joint's dry friction (a Stribeck law, friction by direction) is
/// reported only where the motion shows it: under its base law (the best variant, every level
/// fitted again) the joint's held-out replay must be worse by [`SelectionRules::min_cv_gain`].
/// Each reading is judged by its own replay of the held-out part: the training one (fitted
/// before it) and the whole recording's, which may hold a refinement the training one does not.
/// Equation error sees dry friction that holds a joint for a moment at each reversal, once
/// filtered, as a break-away: `MuJoCo`'s, DART's, Klamp't's and `JaxSim`'s friction on a `UR5e`'s
/// wrist and a double pendulum's elbow came out as Stribeck laws breaking away at 1.2–1.7× their
/// sliding level, and in every such case Coulomb friction replays the held-out motion 30–98 %
/// better.
/// `held` is the held-out replay of the training findings; the one of those kept is returned.
fn settle_refinements_by_replay(
    replay: &HeldOutReplay<'_>,
    found: &mut Identified<'_>,
    rules: &SelectionRules,
    mut held: Vec<Vec<f64>>,
) -> Vec<Vec<f64>> {
    let horizon_s = found.horizon_s;
    // The whole recording's findings replayed through the held-out part, once it is needed.
    let mut whole_held: Option<Vec<Vec<f64>>> = None;
    let Identified { sig, rows, problem, terms, train, stops, findings, train_findings, overruled, .. } = found;
    let at: (&[Vec<FoundStop>], &Signals, f64) = (stops, sig, horizon_s);
    for (r, &joint) in rows.iter().enumerate() {
        let Some(d) = replay.chain_dof(joint) else { continue };
        // The training reading and the whole recording's are settled apart: side by side.
        let ((), settled) = rayon::join(
            || {
                if let (Some((train_problem, train_terms)), Some(train_findings)) = (train.as_mut(), train_findings.as_mut())
                    && let Some((base, base_findings, replayed)) = replay.base_replayed(train_problem, train_terms, at, r)
                    && !shows_in_motion(rules, replay.score(&held, &[d]), replay.score(&replayed, &[d]))
                {
                    held = replayed;
                    *train_terms = base;
                    *train_findings = base_findings;
                }
            },
            || settle_whole_refinement(replay, (&*problem, &*terms, &*findings), at, &mut whole_held, rules, (r, d)),
        );
        if let Some(settled) = settled {
            *findings = settled.findings;
            *terms = settled.terms;
            overruled.push(settled.overruled);
        }
    }
    held
}

/// A reading with a refinement of dry friction replaced by its base law
/// ([`settle_whole_refinement`]).
struct BaseReading {
    terms: Terms,
    findings: Vec<JointFinding>,
    /// The row, the term overruled and why ([`Identified::overruled`]).
    overruled: (usize, String, String),
}

/// The whole recording's reading `(problem, terms, findings)` of row r (chain dof d) with its
/// refinement of dry friction replaced by the base law, where the held-out replay does not show
/// the refinement ([`shows_in_motion`]); `whole_held` is the replay of the findings kept (made
/// when first needed).
fn settle_whole_refinement(
    replay: &HeldOutReplay<'_>,
    (problem, terms, findings): (&EffortProblem<'_>, &Terms, &[JointFinding]),
    at: (&[Vec<FoundStop>], &Signals, f64),
    whole_held: &mut Option<Vec<Vec<f64>>>,
    rules: &SelectionRules,
    (r, d): (usize, usize),
) -> Option<BaseReading> {
    let refined = findings[r].effects.iter().find(|e| matches!(e.kind, EffectKind::StribeckFriction | EffectKind::CoulombFriction))?;
    let (term, what) = if refined.kind == EffectKind::StribeckFriction {
        (refined.kind.name().to_string(), "a Stribeck law")
    } else {
        (format!("{} with friction_reverse", refined.kind.name()), "friction that differs by direction")
    };
    let (base, base_findings, replayed) = replay.base_replayed(problem, terms, at, r)?;
    let (_, sig, horizon_s) = at;
    let whole = whole_held.get_or_insert_with(|| replay.replay(findings, sig, horizon_s));
    let (with_it, without_it) = (replay.score(whole, &[d]), replay.score(&replayed, &[d]));
    if shows_in_motion(rules, with_it, without_it) {
        return None;
    }
    *whole_held = Some(replayed);
    let line = format!(
        "{term}: effort space read the joint's dry friction as {what}, but its base law replays the held-out part {} \
         ({without_it:.2e} against {with_it:.2e} relative to the model as written): the motion does not show the refinement",
        if without_it <= with_it { "as well or better" } else { "hardly worse" },
    );
    Some(BaseReading { terms: base, findings: base_findings, overruled: (r, term, line) })
}

/// A term of a chain joint whose effort has the shape of the model's own rigid-body error (an
/// armature, a heavier part, an offset, a spring, a tilt: [`EffortProblem::rigid_body_shaped`])
/// is reported only where the motion shows it: without it (the other terms fitted again) the
/// joint's own held-out replay must be worse by [`SelectionRules::min_cv_gain`], the cut a term
/// must bring in effort space. Equation error weighs a small term sample by sample, where a law's
/// imperfect shape leaks into whatever column correlates with its error: a `MuJoCo` Panda's dry
/// friction, held at every reversal, came out with a false armature of 3 % of the joint's effort,
/// and inertias 5 % off came out as armatures that replay the motion worse than none. The least
/// material term is tried first; `held` is the held-out replay of the training findings, and the
/// one of the findings kept is returned.
fn drop_what_the_motion_does_not_show(
    replay: &HeldOutReplay<'_>,
    found: &mut Identified<'_>,
    rules: &SelectionRules,
    mut held: Vec<Vec<f64>>,
) -> Vec<Vec<f64>> {
    let (Some((train_problem, train_terms)), Some(train_findings)) = (found.train.as_mut(), found.train_findings.as_mut()) else {
        return held;
    };
    let horizon_s = found.horizon_s;
    for r in 0..found.rows.len() {
        let Some(d) = replay.chain_dof(found.rows[r]) else { continue };
        let mut kinds: Vec<(f64, EffectKind)> =
            train_problem.rigid_body_shaped(train_terms, r).into_iter().map(|k| (train_findings[r].effect_rms_of(k), k)).collect();
        kinds.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (_, kind) in kinds {
            let at = (&found.stops[..], &found.sig, horizon_s);
            let Some(w) = replay.replay_without((train_problem, train_terms), at, &held, (r, d, kind)) else { continue };
            let (with_it, without_it) = (w.with_it, w.without_it);
            if shows_in_motion(rules, with_it, without_it) {
                continue;
            }
            (held, *train_terms, *train_findings) = (w.held, w.terms, w.findings);
            if let Some(whole) = found.problem.without(&found.terms, r, kind) {
                found.findings = findings_with_stops(&found.problem, &whole, &found.stops);
                found.terms = whole;
            }
            found.overruled.push((r, kind.name().to_string(), not_shown_line(kind, with_it, without_it)));
        }
    }
    for r in 0..found.rows.len() {
        if let Some(d) = replay.chain_dof(found.rows[r]) {
            drop_whole_only_terms(replay, found, rules, r, d);
        }
    }
    held
}

/// Nothing unphysical or immaterial is reported: a term whose level the final reading fits
/// negative (or a part outside the plausible weights), or whose effort it fits under the share
/// every term needed to enter, is dropped, the others fitted again, and named among the rejected
/// ([`EffortProblem::physical_reading`]).
fn keep_physical(found: &mut Identified<'_>) {
    let (terms, dropped) = found.problem.physical_reading(&found.terms);
    if dropped.is_empty() {
        return;
    }
    found.findings = findings_with_stops(&found.problem, &terms, &found.stops);
    found.terms = terms;
    for (r, kind, immaterial) in dropped {
        let line = match immaterial {
            Some(share) => format!(
                "{}: with the other terms settled, it comes to {:.1} % of the joint's own effort, under what any term must \
                 be to enter, so it is not reported",
                kind.name(),
                100.0 * share
            ),
            None => format!(
                "{}: with the other terms settled, its level fits outside what the kind can physically be (a negative \
                 damping or friction level, a part outside the plausible weights), so it is not reported",
                kind.name()
            ),
        };
        found.overruled.push((r, kind.name().to_string(), line));
    }
}

/// The rule of [`drop_what_the_motion_does_not_show`] for the terms of row r (chain dof d) that
/// only the whole recording's reading holds: the training part's reading has no such term, so
/// its held-out replay never tested it. The training part is read as the whole recording reads
/// every joint (its terms fitted on the training part), and each such term is kept only if the
/// joint's held-out replay is worse without it by [`SelectionRules::min_cv_gain`]; the training
/// reading itself is left as it was. The real double pendulum's shoulder rotor (run 03: 0.0038
/// kg·m², published 0.0037) replayed 3× worse when only the shoulder was read as the whole
/// recording reads it, beside an elbow read as the training part reads it (a part 0.8× as heavy
/// and a spring the whole reading does not hold), and was dropped for `unknown`.
fn drop_whole_only_terms(replay: &HeldOutReplay<'_>, found: &mut Identified<'_>, rules: &SelectionRules, r: usize, d: usize) {
    let Some((train_problem, train_terms)) = found.train.as_ref() else {
        return;
    };
    let in_training = train_problem.rigid_body_shaped(train_terms, r);
    let horizon_s = found.horizon_s;
    let mut whole_only: Vec<EffectKind> =
        found.problem.rigid_body_shaped(&found.terms, r).into_iter().filter(|k| !in_training.contains(k)).collect();
    if whole_only.is_empty() {
        return;
    }
    // Least material first, as for the training reading's terms.
    whole_only.sort_by(|a, b| found.findings[r].effect_rms_of(*a).total_cmp(&found.findings[r].effect_rms_of(*b)));
    // Every joint read as the whole recording reads it: a chain's joints share one fit (the
    // model's own first moments tie them), and one joint read so beside the others read as the
    // training part reads them replays a mix of two readings.
    let Some(read_as_whole) = train_problem.read_as(&found.problem, &found.terms) else { return };
    let replay_of = |terms: &Terms| replay.replay(&findings_with_stops(train_problem, terms, &found.stops), &found.sig, horizon_s);
    let mut with_all = replay_of(&read_as_whole);
    let mut kept = read_as_whole;
    let mut dropped = Vec::new();
    for kind in whole_only {
        let Some(without) = train_problem.without(&kept, r, kind) else { continue };
        let replayed = replay_of(&without);
        let (with_it, without_it) = (replay.score(&with_all, &[d]), replay.score(&replayed, &[d]));
        if shows_in_motion(rules, with_it, without_it) {
            continue;
        }
        kept = without;
        with_all = replayed;
        dropped.push((kind, with_it, without_it));
    }
    if dropped.is_empty() {
        return;
    }
    for (kind, with_it, without_it) in dropped {
        if let Some(whole) = found.problem.without(&found.terms, r, kind) {
            found.terms = whole;
            found.overruled.push((r, kind.name().to_string(), not_shown_line(kind, with_it, without_it)));
        }
    }
    // Fitted once, for the terms left.
    found.findings = findings_with_stops(&found.problem, &found.terms, &found.stops);
}

/// A term whose level the whole recording's reading fits within
/// [`SelectionRules::min_resolved_sigmas`] jackknife σ of none (the efforts do not resolve it
/// from none) is reported only where the motion shows it: without it (the training reading's
/// term of that kind dropped, the others kept) the joint's held-out replay must be worse by
/// [`SelectionRules::min_cv_gain`]. A term the training reading does not hold was never tested
/// there, and is dropped. The least material first, each judged beside what is kept so far.
/// Where no held-out replay can judge (no training reading; a joint outside any chain, whose
/// levels output error refines) the terms are kept as they are.
/// `MuJoCo`'s Panda read a damping of 0.046 ± 0.025 N·m·s/rad beside a wrist's dry friction; the
/// real simple pendulum's rotor inertia, 0.009 ± 0.005 kg·m², is kept: its held-out replay is
/// 2.5× worse without it.
fn drop_unresolved(
    replay: &HeldOutReplay<'_>,
    found: &mut Identified<'_>,
    rules: &SelectionRules,
    mut held: Vec<Vec<f64>>,
) -> Vec<Vec<f64>> {
    let unresolved = found.problem.unresolved_terms(&found.terms);
    let (Some((train_problem, train_terms)), Some(train_findings)) = (found.train.as_mut(), found.train_findings.as_mut()) else {
        return held;
    };
    let horizon_s = found.horizon_s;
    let mut dropped = false;
    for (r, kind, level, sd) in unresolved {
        let Some(d) = replay.chain_dof(found.rows[r]) else { continue };
        let at = (&found.stops[..], &found.sig, horizon_s);
        let mut tested = None;
        if let Some(w) = replay.replay_without((train_problem, train_terms), at, &held, (r, d, kind)) {
            if shows_in_motion(rules, w.with_it, w.without_it) {
                continue;
            }
            tested = Some((w.with_it, w.without_it));
            (held, *train_terms, *train_findings) = (w.held, w.terms, w.findings);
        }
        if let Some(whole) = found.problem.without(&found.terms, r, kind) {
            found.terms = whole;
            dropped = true;
            found.overruled.push((r, kind.name().to_string(), unresolved_line(rules, kind, level, sd, tested)));
        }
    }
    if dropped {
        found.findings = findings_with_stops(&found.problem, &found.terms, &found.stops);
    }
    held
}

/// Why a term the efforts do not resolve from none was dropped ([`drop_unresolved`]); `tested`:
/// the joint's held-out replay error with and without it, where the training reading held it.
fn unresolved_line(rules: &SelectionRules, kind: EffectKind, level: f64, sd: f64, tested: Option<(f64, f64)>) -> String {
    let motion = match tested {
        Some((with_it, without_it)) => format!(
            "the joint's held-out replay is {} without it ({without_it:.2e} against {with_it:.2e} relative to the model as written)",
            if without_it <= with_it { "as good or better" } else { "hardly worse" }
        ),
        None => "the reading of the training part, whose held-out replay judges the terms, does not hold it".to_string(),
    };
    format!(
        "{}: its level {level:.4} ± {sd:.4} (jackknife σ over the time blocks left out) lies within {}σ of none, and {motion}: \
         the recording does not resolve it",
        kind.name(),
        rules.min_resolved_sigmas
    )
}

/// Why a term of the shape of the model's own rigid-body error was dropped.
fn not_shown_line(kind: EffectKind, with_it: f64, without_it: f64) -> String {
    format!(
        "{}: effort space found it, but the joint's held-out replay is {} without it ({:.2e} against {:.2e} relative to \
         the model as written): a term of the shape the model's own inertia and weight errors take, which the motion does not show",
        kind.name(),
        if without_it <= with_it { "as good or better" } else { "hardly worse" },
        without_it,
        with_it
    )
}

/// The equation of motion is identified in the widest of [`EQUATION_BANDS`] that the model
/// explains: above some frequency a real mechanism stops being the rigid-body model (torque
/// ripple, a controller's chatter, a sensor's own dynamics, compliance), and there the residual
/// is no missing joint physics. Starting wide keeps what the motion's fast parts tell (a push's
/// onset, a friction reversal). The first band whose fitted effects leave no material part of a
/// chain joint's effort unexplained (`unknown`) is kept, else the one that leaves the least; a
/// band whose stretch above the next narrower one is beyond the rigid bodies
/// ([`beyond_the_bodies`]) is not kept, nor is any wider one (it passes that stretch too), and
/// is read only where no narrower band can be.
fn identify_in_bands<'a>(input: &BandInput<'a>) -> Option<Identified<'a>> {
    let mut best: Option<Identified> = None;
    // The last band passed over as beyond the rigid bodies, read where no narrower band reads.
    let mut beyond: Option<Identified> = None;
    let bands = equation_bands(&input.rec.time_s, input.positions, input.rules);
    for (k, band) in bands.iter().enumerate() {
        let Some(found) = identify_at(input, *band) else { continue };
        let share = found.unexplained_share(input.model);
        if bands.get(k + 1).is_some_and(|narrower| beyond_the_bodies(&found, input, narrower.sigma_s)) {
            // A wider band kept so far passes that stretch too, at a higher gain.
            best = None;
            beyond = Some(found);
            continue;
        }
        if best.as_ref().is_none_or(|b| share < b.unexplained_share(input.model)) {
            best = Some(found);
        }
        if share <= input.rules.unknown_share {
            break;
        }
    }
    best.or(beyond)
}

/// Effort-space analysis of `rows` (model joint indices); one outcome per row, read in the band
/// [`identify_in_bands`] chooses.
pub(super) fn analyze_effort_space(
    model: &GapModel,
    rec: &Recording,
    cfg: &GapConfig,
    observed: &BTreeMap<usize, Vec<f64>>,
    rows: &[usize],
    gravity: DVec3,
    t_split: f64,
) -> Result<EffortOutcome, GapError> {
    let rules = SelectionRules::default();
    let dofs = model.dofs();
    let n = rec.time_s.len();
    let positions: Vec<Vec<f64>> = dofs.iter().map(|j| observed.get(j).cloned().unwrap_or_else(|| vec![f64::NAN; n])).collect();
    // No effort column: zero applied effort (spec §2).
    let efforts: Vec<Option<Vec<f64>>> =
        dofs.iter().map(|&j| Some(rec.joint_effort.get(&model.joints[j].name).cloned().unwrap_or_else(|| vec![0.0; n]))).collect();
    let input = BandInput { model, rec, positions: &positions, efforts: &efforts, rows, gravity, t_split, rules: &rules };
    let Some(mut found) = identify_in_bands(&input) else {
        return Ok(EffortOutcome::default());
    };

    let (tree, body_of_link) = model.multibody()?;
    found.horizon_s = chain_horizon_s(&tree, &found.sig, gravity, t_split, found.band.held_out_horizon_s());
    let recorded: Vec<Vec<f64>> = dofs.iter().map(|&j| (0..n).map(|i| rec.effort(&model.joints[j].name, i)).collect()).collect();
    let input = ChainInput { time_s: &rec.time_s, effort: &recorded, gravity };
    // The whole recording is replayed open loop from its start (the plots), the held-out part in
    // pieces from the measured state ([`Bandwidth::held_out_horizon_s`]).
    let start = replay_start(&found.sig, rec.time_s.first().copied().unwrap_or(0.0));
    let horizon_s = found.horizon_s;
    let (nominal_physics, _) = fitted_physics(model, &tree, &body_of_link, &BTreeMap::new(), &[], gravity);
    let held_before = replay_pieces(&tree, &nominal_physics, &input, &found.sig, t_split, horizon_s);
    let replay = HeldOutReplay {
        model,
        rec,
        positions: &positions,
        tree: &tree,
        body_of_link: &body_of_link,
        input: &input,
        t_split,
        held_before: &held_before,
    };
    let settled = settle_friction_by_replay(&replay, &mut found, &rules)
        .map(|held| settle_refinements_by_replay(&replay, &mut found, &rules, held))
        .map(|held| drop_what_the_motion_does_not_show(&replay, &mut found, &rules, held))
        .map(|held| drop_unresolved(&replay, &mut found, &rules, held));
    keep_physical(&mut found);
    let findings = found.findings_with_overruled();
    let Identified { band, sig, rows, train_findings, .. } = found;
    let rows = rows.as_slice();
    let first_moments = first_moments_of(&findings);
    let (physics, tree_fitted) = fitted_physics(model, &tree, &body_of_link, &effects_by_joint(&findings), &first_moments, gravity);
    let (before, after) = rayon::join(
        || replay_from(&tree, &nominal_physics, &input, &sig, start),
        || replay_from(&tree_fitted, &physics, &input, &sig, start),
    );
    // The settling replayed the training findings it kept; otherwise they are replayed here.
    let held = settled.or_else(|| train_findings.as_ref().map(|f| replay.replay(f, &sig, horizon_s)));

    let mut out = Vec::with_capacity(rows.len());
    let mut given = BTreeMap::new();
    for f in &findings {
        let d = dofs.iter().position(|&x| x == f.joint).unwrap_or(0);
        let y = &positions[d];
        let replays =
            Replays { before: &before[d], after: &after[d], held_before: &held_before[d], held: held.as_ref().map(|h| h[d].as_slice()) };
        // The smooth friction law cannot hold a joint still: a residual within the friction's
        // static range where the joint rests is friction, not `unknown` (it still lets a lone
        // joint's exact simulation, which sticks, choose the terms again).
        let smooth_law_unexplained = unexplained(&rules, f);
        let speed = sig.speed(d);
        let f = &f.with_friction_at_rest(&speed);
        let mut outcome = joint_outcome(&band, model, rec, cfg, &rules, f, y, &replays, gravity, t_split);
        if in_serial_chain(model, f.joint) {
            out.push(outcome);
        } else {
            // A joint alone on its body: effort space chose the terms, output error refines their
            // levels and validates them through the joint's exact 1-DoF simulation (stops, sticking).
            outcome.analysis.why.push_str("; levels refined by output error (multiple shooting) on the measured positions");
            given.insert(
                f.joint,
                Given {
                    effects: f.effects.clone(),
                    param_std: f.param_std.clone(),
                    confidence: f.confidence.clone(),
                    extra: outcome.effects.into_iter().filter(|e| e.kind == EffectKind::Unknown.name()).collect(),
                    effort_unexplained: smooth_law_unexplained,
                    analysis: outcome.analysis,
                },
            );
        }
    }
    Ok(EffortOutcome {
        joints: out,
        given,
        com_shift_m: com_shifts(&tree, &first_moments),
        implausible_accuracy: implausible_accuracy(&tree, &first_moments, &rules),
    })
}

/// What effort space gives the rest of the analysis.
#[derive(Default)]
pub(super) struct EffortOutcome {
    /// The chain joints' outcomes.
    pub joints: Vec<JointOutcome>,
    /// Per joint alone on its body: the terms for output error to refine.
    pub given: BTreeMap<usize, Given>,
    /// Per link: its centre of mass moved by the model's own first-moment error fitted beside
    /// the effects (m, link frame; [`super::report::GapReport::com_shift_m`]).
    pub com_shift_m: BTreeMap<String, [f64; 3]>,
    /// The links whose fitted first-moment error lies beyond what the model's accuracy allows
    /// ([`SelectionRules::first_moment_implausible_sigmas`]), by name: (centre-of-mass shift, m;
    /// the error's length in the prior's standard deviations per axis).
    pub implausible_accuracy: BTreeMap<String, (f64, f64)>,
}

/// First-moment changes as centre-of-mass shifts by link name (a massless body has none).
fn com_shifts(tree: &MultiBody, first_moments: &[(usize, DVec3)]) -> BTreeMap<String, [f64; 3]> {
    first_moments
        .iter()
        .filter_map(|&(b, h)| {
            let body = tree.bodies().get(b)?;
            (body.inertia.mass_kg > 0.0).then(|| (body.name.clone(), (h / body.inertia.mass_kg).to_array()))
        })
        .collect()
}

/// The links of `first_moments` whose fitted error is beyond
/// [`SelectionRules::first_moment_implausible_sigmas`] of its prior
/// ([`super::accuracy::first_moment_prior`]): no rigid-body error a model is published with.
fn implausible_accuracy(tree: &MultiBody, first_moments: &[(usize, DVec3)], rules: &SelectionRules) -> BTreeMap<String, (f64, f64)> {
    first_moments
        .iter()
        .filter_map(|&(b, h)| {
            let body = tree.bodies().get(b)?;
            let prior_sd = super::accuracy::first_moment_prior(tree, b, rules.first_moment_tolerance, rules.first_moment_min_lever_m);
            if body.inertia.mass_kg <= 0.0 || prior_sd <= 0.0 {
                return None;
            }
            let sigmas = h.length() / prior_sd;
            (sigmas > rules.first_moment_implausible_sigmas).then(|| (body.name.clone(), (h.length() / body.inertia.mass_kg, sigmas)))
        })
        .collect()
}

/// Whether `f` leaves effort unexplained beyond the joint's own effort and beyond what the
/// model's weights and centres of mass can be trusted to ([`SelectionRules::min_static_load_share`]).
fn unexplained(rules: &SelectionRules, f: &JointFinding) -> bool {
    f.cv_rms_after > rules.unknown_share * f.effort_rms && f.cv_rms_after > rules.min_static_load_share * f.gravity_rms
}

struct Replays<'a> {
    before: &'a [f64],
    after: &'a [f64],
    /// The model as written, replayed from the start of the held-out part.
    held_before: &'a [f64],
    /// The model fitted before the held-out part, replayed from its start.
    held: Option<&'a [f64]>,
}

/// Length of the pieces a chain's held-out part is replayed in: one period of the motion
/// ([`Bandwidth::held_out_horizon_s`], `period_s`), or, where gravity drives the chain away from
/// its typical configuration, [`super::held_out::HELD_OUT_E_FOLDS`] e-folds of that divergence
/// ([`instability_rate`], its median over up to 64 configurations of the training part), if
/// shorter, and never under [`HELD_OUT_HORIZON_S`]'s shortest piece. A real Panda held up by its
/// controller through a 0.35 Hz excitation was replayed in 2 s pieces, over which every model
/// falls away (held-out errors of 1-2.6 rad before and after fitting alike); in pieces of 0.25 s
/// the fitted model cut them 2-8× on every joint, and the replay could judge terms again.
fn chain_horizon_s(tree: &MultiBody, sig: &Signals, gravity: DVec3, t_split: f64, period_s: f64) -> f64 {
    let training: Vec<usize> =
        (0..sig.time_s.len()).filter(|&i| sig.time_s[i] < t_split && sig.q.iter().all(|d| d[i][0].is_finite())).collect();
    let every = training.len().div_ceil(64).max(1);
    let rates: Vec<f64> = training
        .iter()
        .step_by(every)
        .map(|&i| instability_rate(tree, &sig.q.iter().map(|d| d[i][0]).collect::<Vec<f64>>(), gravity))
        .collect();
    let rate = super::effort::median(&rates);
    if rate > 0.0 { period_s.min(super::held_out::HELD_OUT_E_FOLDS / rate).max(HELD_OUT_HORIZON_S.0) } else { period_s }
}

/// The first sample at or after `t_s` whose smoothing window lies inside the recording, with
/// every dof's smoothed state finite: a replay starts there. (At the very first samples the
/// differentiating windows are one-sided or too short; a replay that started from a state
/// missing there started at rest at zero, whatever the recording did.)
fn replay_start(sig: &Signals, t_s: f64) -> Option<usize> {
    let t0 = sig.time_s.first().copied().unwrap_or(0.0);
    let from = t_s.max(t0 + sig.band.half_width_s);
    (0..sig.time_s.len()).find(|&i| sig.time_s[i] >= from && sig.q.iter().all(|d| d[i][0].is_finite() && d[i][1].is_finite()))
}

/// Replays from `from_s` to the end in pieces of `horizon_s`, each from the smoothed measured
/// state at its start (NaN before `from_s`).
fn replay_pieces(
    tree: &MultiBody,
    physics: &[JointPhysics],
    input: &ChainInput<'_>,
    sig: &Signals,
    from_s: f64,
    horizon_s: f64,
) -> Vec<Vec<f64>> {
    let n = input.time_s.len();
    let mut spans = Vec::new();
    let mut next = replay_start(sig, from_s);
    while let Some(s) = next {
        let end = input.time_s.partition_point(|&t| t < input.time_s[s] + horizon_s).clamp(s + 1, n);
        spans.push(s..end);
        next = if end < n { replay_start(sig, input.time_s[end]).filter(|&i| i >= end) } else { None };
    }
    replay_spans(tree, physics, input, sig, &spans)
}

/// A replay from sample `start`'s smoothed state (NaN before it; all NaN without a start).
fn replay_from(tree: &MultiBody, physics: &[JointPhysics], input: &ChainInput<'_>, sig: &Signals, start: Option<usize>) -> Vec<Vec<f64>> {
    let spans: Vec<std::ops::Range<usize>> = start.map(|s| s..input.time_s.len()).into_iter().collect();
    replay_spans(tree, physics, input, sig, &spans)
}

/// Per dof and sample, the replays of `spans` (each from the smoothed state at its first sample;
/// NaN outside them). The spans are independent, so they run in parallel; each writes only its
/// own samples.
fn replay_spans(
    tree: &MultiBody,
    physics: &[JointPhysics],
    input: &ChainInput<'_>,
    sig: &Signals,
    spans: &[std::ops::Range<usize>],
) -> Vec<Vec<f64>> {
    let pieces: Vec<Vec<Vec<f64>>> = spans.par_iter().map(|span| replay_span(tree, physics, input, sig, span.clone())).collect();
    let mut out = vec![vec![f64::NAN; input.time_s.len()]; sig.q.len()];
    for (span, piece) in spans.iter().zip(pieces) {
        for (d, q) in piece.into_iter().enumerate() {
            out[d][span.clone()].copy_from_slice(&q);
        }
    }
    out
}

/// Replays samples `span` from the smoothed state at its first sample: per dof, its positions
/// over the span.
fn replay_span(
    tree: &MultiBody,
    physics: &[JointPhysics],
    input: &ChainInput<'_>,
    sig: &Signals,
    span: std::ops::Range<usize>,
) -> Vec<Vec<f64>> {
    let s = span.start;
    let effort: Vec<Vec<f64>> = input.effort.iter().map(|e| e.get(span.clone()).map_or_else(Vec::new, <[f64]>::to_vec)).collect();
    let piece = ChainInput { time_s: &input.time_s[span], effort: &effort, gravity: input.gravity };
    let q0: Vec<f64> = sig.q.iter().map(|d| d[s][0]).collect();
    let v0: Vec<f64> = sig.q.iter().map(|d| d[s][1]).collect();
    replay(tree, physics, &piece, &q0, &v0)
}

fn joint_outcome(
    band: &Bandwidth,
    model: &GapModel,
    rec: &Recording,
    cfg: &GapConfig,
    rules: &SelectionRules,
    f: &JointFinding,
    y: &[f64],
    replays: &Replays<'_>,
    gravity: DVec3,
    t_split: f64,
) -> JointOutcome {
    let joint = &model.joints[f.joint];
    let unit = if joint.kind.is_rotational() { "rad" } else { "m" };
    let force = if joint.kind.is_rotational() { "N·m" } else { "N" };
    let zeros = vec![0.0; model.joints.len()];
    let terms = model.joint_terms(f.joint, &zeros, gravity);
    let inertia = JointPhysics::with_effects(joint, &f.effects).inertia(terms.inertia);
    let mut effects: Vec<EffectReport> = f
        .effects
        .iter()
        .zip(&f.param_std)
        .zip(&f.confidence)
        .zip(&f.effect_rms)
        .map(|(((e, sd), c), size)| {
            let mut r = effect_report(joint, &terms, gravity, e, sd, *c, super::observed_range(y), inertia);
            let _ = write!(
                r.description,
                " — {size:.4} {force} RMS over the motion, {:.0} % of the joint's own effort",
                100.0 * size / f.effort_rms.max(1e-12)
            );
            r
        })
        .collect();
    let floor = f.cv_rms_after.max(1e-12);
    let spans = mismatch_spans(&f.residual_before, floor, cfg.min_mismatch_samples);
    let position_residual: Vec<f64> = y.iter().zip(replays.before).map(|(a, b)| a - b).collect();
    let mismatches: Vec<Mismatch> =
        spans.iter().map(|s| effort_mismatch(rec, joint, y, &f.residual_before, &position_residual, *s, force)).collect();
    if unexplained(rules, f) {
        let left = mismatch_spans(&f.residual_after, floor.min(rules.unknown_share * f.effort_rms), cfg.min_mismatch_samples);
        let at: Vec<String> = left.iter().take(4).map(|s| format!("{:.2}–{:.2} s", rec.time_s[s.start], rec.time_s[s.end])).collect();
        let share = f.cv_rms_after / f.effort_rms.max(1e-12);
        effects.push(EffectReport {
            joint: joint.name.clone(),
            kind: EffectKind::Unknown.name().into(),
            params: BTreeMap::from([("residual_rms".to_owned(), f.cv_rms_after)]),
            uncertainty: BTreeMap::new(),
            confidence: (share / (2.0 * rules.unknown_share)).clamp(0.0, 1.0),
            description: format!(
                "{:.4} {force} RMS of effort ({:.0} % of the joint's own) that no known kind explains{}",
                f.cv_rms_after,
                100.0 * share,
                if at.is_empty() { String::new() } else { format!(", largest at {}", at.join(", ")) }
            ),
        });
    }
    let (all, sq) = rmse_pair(y, replays.before, replays.after, |_| true);
    let held = replays.held.map_or_else(RmsePair::default, |h| rmse_pair(y, replays.held_before, h, |i| rec.time_s[i] >= t_split).0);
    let noise = super::locate::noise_sigma(&rec.time_s, y);
    let series = JointSeries::new(&joint.name, unit, &rec.time_s, y, replays.before.to_vec(), replays.after.to_vec(), noise);
    let analysis = report::JointAnalysis {
        mode: "effort".into(),
        why: format!(
            "every joint's position recorded and every applied effort known (recorded, or zero without a column): \
             residual effort from inverse dynamics of the whole tree \
             (every term and the efforts low-passed alike: a Gaussian of σ {:.0} ms, half gain at {:.1} Hz, \
             the motion's dominant frequency {:.2} Hz)",
            1000.0 * band.sigma_s,
            super::smooth::GAUSS_HALF_GAIN_F_SIGMA / band.sigma_s,
            band.motion_hz
        ) + &rests_line(f)
            + &sign_question(f.model_correlation, unexplained(rules, f)),
        effort_rms: Some(f.effort_rms),
        effort_residual: Some(RmsePair { rmse_before: f.cv_rms_before, rmse_after: f.cv_rms_after }),
        rejected: f.rejected.clone(),
    };
    JointOutcome { mismatches, effects, all, held, sq, series, analysis }
}

/// What the analysis says where the joint's rests were left out ([`super::rests`]); empty
/// otherwise.
fn rests_line(f: &JointFinding) -> String {
    f.rests_left_out.map_or_else(String::new, |share| {
        format!(
            "; {:.0} % of the samples left out as rests its dry friction holds, with the filters' support around them \
             (stuck, the friction is whatever holds the joint, not its law near zero speed; the law's transition is \
             the one read with them)",
            100.0 * share
        )
    })
}

/// What the report asks where the recorded effort runs against the effort the model needs
/// ([`super::effort::EFFORT_AGAINST_MODEL`]) and what is named leaves it `unexplained`; empty
/// otherwise. A missing spring stiffer than the swing's inertia turns the correlation round too
/// (q̈ ≈ −ω²q), but then it is named and explains the efforts.
fn sign_question(model_correlation: f64, unexplained: bool) -> String {
    if unexplained && model_correlation < super::effort::EFFORT_AGAINST_MODEL {
        format!(
            "; the recorded effort runs against the effort the model needs (correlation {model_correlation:.2}): is its sign \
             the model's, positive along the joint's axis? What is named here stands on that sign"
        )
    } else {
        String::new()
    }
}

fn effort_mismatch(
    rec: &Recording,
    joint: &super::model::GapJoint,
    y: &[f64],
    effort_residual: &[f64],
    position_residual: &[f64],
    span: Span,
    force: &str,
) -> Mismatch {
    let idx: Vec<usize> = (span.start..=span.end).filter(|&i| y[i].is_finite()).collect();
    let (lo, hi) = idx.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| (a.min(y[i]), b.max(y[i])));
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) };
    let mean: f64 = {
        let vals: Vec<f64> = effort_residual[span.start..=span.end].iter().copied().filter(|v| v.is_finite()).collect();
        vals.iter().sum::<f64>() / vals.len().max(1) as f64
    };
    let unit = if joint.kind.is_rotational() { "rad" } else { "m" };
    let direction = match (y.get(span.start), y.get(span.end)) {
        (Some(a), Some(b)) if b - a > 0.1 * (hi - lo) => "increasing",
        (Some(a), Some(b)) if a - b > 0.1 * (hi - lo) => "decreasing",
        _ => "both",
    };
    Mismatch {
        joint: joint.name.clone(),
        t_start: rec.time_s[span.start],
        t_end: rec.time_s[span.end],
        rmse: rmse_over(position_residual, span),
        description: format!(
            "the recorded effort differs from what the model needs by {:.4} {force} RMS (mean {mean:+.4}) (q {lo:.3}–{hi:.3} {unit})",
            rmse_over(effort_residual, span)
        ),
        conditions: Conditions { position_min: lo, position_max: hi, direction: direction.into(), near_stop: None },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Broke: a slow motion clamps every multiple of its frequency to the widest filter allowed,
    /// and the real Panda was identified twice over that one band. A motion at 0.05 Hz gets one
    /// band; one at 1.5 Hz three, narrowing.
    #[test]
    fn bands_that_clamp_to_one_filter_are_one_band() {
        let time_s: Vec<f64> = (0..4000).map(|i| f64::from(i) / 200.0).collect();
        let swing = |f_hz: f64| vec![time_s.iter().map(|t| 0.5 * (std::f64::consts::TAU * f_hz * t).sin()).collect::<Vec<f64>>()];
        let rules = SelectionRules::default();
        assert_eq!(equation_bands(&time_s, &swing(0.05), &rules).len(), 1);
        let sigmas_s: Vec<f64> = equation_bands(&time_s, &swing(1.5), &rules).iter().map(|b| b.sigma_s).collect();
        assert_eq!(sigmas_s.len(), EQUATION_BANDS.len(), "{sigmas_s:?}");
        assert!(sigmas_s.windows(2).all(|w| w[1] > w[0]), "{sigmas_s:?}");
    }

    /// [`chain_horizon_s`] of a two-link arm (1 kg at the middle of each 1 m link, 0.5 kg·m²
    /// about its centre) resting at `q` for 4 s at 200 Hz, the motion's period taken as 2 s.
    fn horizon_at(q: [f64; 2]) -> f64 {
        let link = |name: &str| {
            format!(
                r#"<link name="{name}"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/><inertia ixx="0.5" iyy="0.5" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial></link>"#
            )
        };
        let urdf = format!(
            r#"<robot name="arm"><link name="base"/>{}{}
              <joint name="shoulder" type="continuous"><parent link="base"/><child link="a"/><axis xyz="0 1 0"/></joint>
              <joint name="elbow" type="continuous"><parent link="a"/><child link="b"/><origin xyz="0 0 -1"/><axis xyz="0 1 0"/></joint></robot>"#,
            link("a"),
            link("b")
        );
        let model = super::super::model::parse_model(&urdf, std::path::Path::new("arm.urdf")).expect("model");
        let (tree, _) = model.multibody().expect("tree");
        let time_s: Vec<f64> = (0..800).map(|i| f64::from(i) / 200.0).collect();
        let positions: Vec<Vec<f64>> = q.iter().map(|&x| vec![x; time_s.len()]).collect();
        let band = super::super::effort::bandwidth(&time_s, &positions, 0.1, 5.0);
        let sig = signals(&time_s, &positions, &[None, None], &band);
        chain_horizon_s(&tree, &sig, DVec3::new(0.0, 0.0, -9.81), 3.0, 2.0)
    }

    #[test]
    fn a_chain_held_up_against_gravity_is_replayed_in_pieces_it_cannot_fall_away_in() {
        // Regression: a real Panda held up by its controller through a 0.35 Hz excitation was
        // replayed held out in 2 s pieces (one period), over which every model falls away.
        // Upright, this arm diverges at λ with λ² the largest root of det(−K − λ² M) = 0,
        // M = [[3.5, 1.25], [1.25, 0.75]], −K = g·[[2, 0.5], [0.5, 0.5]]: pieces of two e-folds;
        // hanging, one period.
        let g = 9.81;
        let roots = crate::linalg::generalized_eigenvalues(&[2.0 * g, 0.5 * g, 0.5 * g, 0.5 * g], &[3.5, 1.25, 1.25, 0.75], 2)
            .expect("positive definite");
        let two_e_folds = super::super::held_out::HELD_OUT_E_FOLDS / roots[1].sqrt();
        let upright = horizon_at([std::f64::consts::PI, 0.0]);
        assert!((upright - two_e_folds).abs() < 1e-4 && upright < 2.0, "{upright} s against {two_e_folds} s");
        assert!((horizon_at([0.0, 0.0]) - 2.0).abs() < 1e-12);
    }

    /// Contact after [`touch_through_gaps`], for positions `y` (NaN = missing) whose samples
    /// `at_stop` are in contact.
    fn check(y: &[f64], at_stop: &[usize], expected: &[usize]) {
        let mut touching: Vec<bool> = (0..y.len()).map(|i| at_stop.contains(&i)).collect();
        let time_s: Vec<f64> = (0..y.len()).map(|i| 0.01 * i as f64).collect();
        touch_through_gaps(&mut touching, &time_s, y, 0.025);
        let got: Vec<usize> = (0..y.len()).filter(|&i| touching[i]).collect();
        assert_eq!(got, expected, "{y:?}");
    }

    #[test]
    fn a_tracking_dropout_that_ends_at_the_stop_counts_as_contact() {
        // Regression: a lid (Drake) seen falling before a 170 ms tracking dropout and resting shut
        // after it hit its stop inside the gap; the accelerations interpolated across the impact
        // made an `unknown` of 0.75 N·m on a recording with nothing missing.
        let nan = f64::NAN;
        check(&[0.6, 0.4, nan, nan, 0.0, 0.0], &[4, 5], &[2, 3, 4, 5]);
        // Leaving the stop during a gap, likewise.
        check(&[0.0, nan, nan, 0.3], &[0], &[0, 1, 2]);
        // A gap no longer than the differentiator's half-width: the contact's widening covers it.
        check(&[0.6, 0.4, nan, 0.0, 0.0], &[3, 4], &[3, 4]);
        // A gap in free motion stays free.
        check(&[0.6, nan, 0.5, 0.0], &[3], &[3]);
        check(&[nan, nan], &[], &[]);
    }

    /// [`unseen_approach`] of positions `y` towards `side`: the samples with a reach, and each
    /// reach.
    fn check_approach(y: &[f64], side: f64, expected: &[(usize, f64)]) {
        let reach = unseen_approach(y, side);
        let got: Vec<(usize, f64)> = (0..y.len()).filter(|&i| reach[i] > 0.0).map(|i| (i, reach[i])).collect();
        assert_eq!(got.len(), expected.len(), "{y:?}: {got:?}");
        for ((i, r), (j, e)) in got.iter().zip(expected) {
            assert!(i == j && (r - e).abs() < 1e-12, "{y:?}: {got:?}, expected {expected:?}");
        }
    }

    #[test]
    fn a_lid_that_bounces_off_its_stop_between_samples_touched_it() {
        // Regression: a lid (Klamp't, ODE's stops) dropped shut at 5 rad/s bounced off its stop
        // between two samples at 200 Hz; the lowest sample, 0.0115 rad above the stop, lay
        // outside the contact band, the impulse landed in the smoothed acceleration and a
        // recording with nothing missing got an `unknown` of 2.6 N·m.
        check_approach(&[0.3, 0.1, 0.0115, 0.05, 0.2], -1.0, &[(2, 0.0385)]);
        // Towards an upper stop, and across a missing sample.
        check_approach(&[1.5, 1.8, f64::NAN, 1.88, 1.7], 1.0, &[(3, 0.08)]);
        // Leaving a rest fast is no turn.
        check_approach(&[0.2, 0.0, 0.0, 0.3], -1.0, &[]);
        // Moving on past a point, or turning away from the stop side, is no approach.
        check_approach(&[0.3, 0.2, 0.1, 0.0], -1.0, &[]);
        check_approach(&[0.1, 0.3, 0.1], -1.0, &[]);
    }
}
