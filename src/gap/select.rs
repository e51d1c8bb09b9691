//! Choosing the physics terms: equation-error least squares on smoothed derivatives gives starting
//! values, output-error LM ([`super::fit`]) fits each candidate structure, and greedy forward
//! selection by BIC keeps a term only when it pays for its parameters. Look-alikes (spring vs
//! tilt, viscous vs Coulomb, damping vs mass) compete on the same data, and each kept term's
//! confidence weighs it against dropping it and against swapping it for every other kind.

use std::collections::BTreeMap;

use rayon::prelude::*;

use super::effects::{Effect, EffectKind, JointPhysics, clamp_params};
use super::fit::{FitResult, Problem, fit, segment_residual, solve_spd};
use super::locate::mismatch_spans;

/// BIC improvement a new term must bring (strong evidence on Kass–Raftery's scale).
pub const BIC_MARGIN: f64 = 10.0;
/// Share of the remaining misfit a new term must explain: BIC alone accepts terms that only
/// soak up integrator differences once n is large.
pub const MIN_GAIN: f64 = 0.05;
/// LM iterations per candidate.
const MAX_ITER: usize = 25;

/// The outcome of selection on one joint.
#[derive(Debug, Clone)]
pub struct Selection {
    /// The model as written (segment states only).
    pub nominal: FitResult,
    /// The chosen structure, fitted.
    pub chosen: FitResult,
    /// Confidence of each chosen effect (same order as `chosen.effects`).
    pub confidence: Vec<f64>,
    /// Every candidate kind not chosen, and why (`kind: reason`), as the report lists them.
    pub rejected: Vec<String>,
}

fn effect(kind: EffectKind, params: Vec<f64>, blocks_upward: bool) -> Effect {
    let mut e = Effect { kind, params, blocks_upward };
    clamp_params(kind, &mut e.params);
    e
}

/// Starting values for the linear-in-parameter kinds by equation error: I·a − known forces
/// regressed on the kinds' features over samples away from stops.
fn equation_error(problem: &Problem<'_>, derivs: &[[f64; 3]], kinds: &[EffectKind], known: &[Effect]) -> Vec<Effect> {
    let physics = JointPhysics::with_effects(problem.joint, known);
    let vmax = derivs.iter().filter(|d| d[1].is_finite()).map(|d| d[1].abs()).fold(0.0, f64::max);
    let linear: Vec<EffectKind> = kinds
        .iter()
        .copied()
        .filter(|k| {
            matches!(
                k,
                EffectKind::ViscousDamping
                    | EffectKind::CoulombFriction
                    | EffectKind::Spring
                    | EffectKind::GravityTilt
                    | EffectKind::MassScale
            )
        })
        .collect();
    let width: usize = linear.iter().map(|k| k.param_count()).sum();
    let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
    let used: Vec<usize> = problem.rows.iter().flatten().copied().collect();
    for &i in &used {
        let [q, v, a] = derivs[i];
        if !(q.is_finite() && v.is_finite() && a.is_finite()) {
            continue;
        }
        let near = |lim: Option<f64>| lim.is_some_and(|l| (q - l).abs() < 0.02 * (1.0 + l.abs()));
        if near(physics.lower) || near(physics.upper) || physics.stops.iter().any(|s| (q - s.position).abs() < 0.02) {
            continue;
        }
        let terms = &problem.input.terms[i];
        let inertia = terms.inertia * physics.mass_scale;
        let sign = if v.abs() > 0.05 * vmax { v.signum() } else { 0.0 };
        let known_force =
            problem.input.effort[i] + terms.gravity(q) + physics.position_effort(q) - physics.damping_at(q) * v - physics.friction * sign;
        let target = inertia * a - known_force;
        let mut phi = Vec::with_capacity(width);
        for k in &linear {
            match k {
                EffectKind::ViscousDamping => phi.push(-v),
                EffectKind::CoulombFriction => phi.push(-sign),
                EffectKind::Spring => phi.extend([-q, 1.0]),
                EffectKind::GravityTilt => phi.extend([-q.sin(), q.cos()]),
                EffectKind::MassScale => phi.push(-inertia * a),
                _ => {}
            }
        }
        rows.push((phi, target));
    }
    let solve = |rows: &[(Vec<f64>, f64)]| {
        let mut a = vec![0.0; width * width];
        let mut b = vec![0.0; width];
        for (phi, t) in rows {
            for r in 0..width {
                b[r] += phi[r] * t;
                for c in 0..width {
                    a[r * width + c] += phi[r] * phi[c];
                }
            }
        }
        for r in 0..width {
            a[r * width + r] += 1e-9 * (1.0 + a[r * width + r]);
        }
        solve_spd(&a, &b, width).unwrap_or_else(|| vec![0.0; width])
    };
    let mut coef = solve(&rows);
    // One robust pass: drop rows beyond 3 MAD (impacts, stick-slip transitions).
    let mut res: Vec<f64> = rows.iter().map(|(phi, t)| (t - phi.iter().zip(&coef).map(|(p, c)| p * c).sum::<f64>()).abs()).collect();
    let mut sorted = res.clone();
    sorted.sort_by(f64::total_cmp);
    if let Some(&mad) = sorted.get(sorted.len() / 2) {
        let keep: Vec<(Vec<f64>, f64)> =
            rows.iter().zip(&res).filter(|(_, r)| **r <= 3.0 * 1.4826 * mad.max(1e-12)).map(|(row, _)| row.clone()).collect();
        if keep.len() > width * 3 {
            coef = solve(&keep);
        }
    }
    res.clear();
    let q_mean = used.iter().map(|&i| problem.y[i]).sum::<f64>() / used.len().max(1) as f64;
    let mut out = Vec::new();
    let mut c = coef.into_iter();
    for k in linear {
        let mut next = || c.next().unwrap_or(0.0);
        let params = match k {
            EffectKind::Spring => {
                let (s, offset) = (next(), next());
                vec![s, if s.abs() > 1e-9 { offset / s } else { q_mean }]
            }
            EffectKind::GravityTilt => {
                let (c0, c1) = (next(), next());
                vec![c0.hypot(c1), c1.atan2(c0)]
            }
            EffectKind::MassScale => vec![1.0 + next()],
            _ => vec![next()],
        };
        out.push(effect(k, params, false));
    }
    out
}

/// Fits one structure (set of kinds), trying the few starting points the switch-like kinds need;
/// `within`: the terms of the structure chosen so far, from which [`nested_start`] starts.
fn fit_structure(problem: &Problem<'_>, derivs: &[[f64; 3]], kinds: &[EffectKind], warm: &[Effect], within: &[Effect]) -> FitResult {
    let warm_of = |k: EffectKind| warm.iter().find(|e| e.kind == k).cloned();
    let known: Vec<Effect> =
        kinds.iter().filter(|k| matches!(k, EffectKind::EndStop | EffectKind::SoftClose)).filter_map(|&k| warm_of(k)).collect();
    let mut joint_start = equation_error(problem, derivs, kinds, &known);
    let mut base = joint_start.clone();
    let mut warmed = false;
    for e in &mut base {
        if let Some(w) = warm_of(e.kind) {
            *e = w;
            warmed = true;
        }
    }
    base.extend(known.iter().cloned());
    joint_start.extend(known);
    let used: Vec<f64> = problem.rows.iter().flatten().map(|&i| problem.y[i]).collect();
    let (lo, hi) = used.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let inertia = problem.input.terms.first().map_or(1.0, |t| t.inertia.max(1e-6));
    let mut starts: Vec<Vec<Effect>> = vec![base.clone()];
    // Warm starts come from other structures; the joint equation-error solution of these kinds
    // together is the other natural start (two terms that each half-explain the data).
    if warmed {
        starts.push(joint_start);
    }
    starts.extend(nested_start(&base, within));
    // Equilibrium-like parameters: also start from the middle of the observed range.
    for kind in [EffectKind::Spring, EffectKind::GravityTilt] {
        if kinds.contains(&kind) && warm_of(kind).is_none() {
            let mut s = base.clone();
            if let Some(e) = s.iter_mut().find(|e| e.kind == kind) {
                e.params[0] = e.params[0].abs().max(inertia);
                e.params[1] = 0.5 * (lo + hi);
                starts.push(s);
            }
        }
    }
    if kinds.contains(&EffectKind::EndStop) && warm_of(EffectKind::EndStop).is_none() {
        let sides: Vec<(f64, bool)> = [(hi, true), (lo, false)]
            .into_iter()
            .filter(|&(p, up)| {
                let lim = if up { problem.joint.upper } else { problem.joint.lower };
                lim.is_none_or(|l| (l - p).abs() > 0.02 * (hi - lo).max(1e-6))
            })
            .collect();
        starts = starts
            .iter()
            .flat_map(|s| {
                sides.iter().map(move |&(p, up)| {
                    let mut s = s.clone();
                    s.push(effect(EffectKind::EndStop, vec![p, 0.2], up));
                    s
                })
            })
            .collect();
        if starts.is_empty() {
            starts.push(base.clone());
        }
    }
    if kinds.contains(&EffectKind::SoftClose) && warm_of(EffectKind::SoftClose).is_none() {
        let closed = problem.joint.lower.unwrap_or(0.0);
        let far = if (hi - closed).abs() >= (lo - closed).abs() { hi } else { lo };
        let mut grid = Vec::new();
        for s in &starts {
            for frac in [0.1, 0.2, 0.35, 0.5, 0.7] {
                let mut st = s.clone();
                st.push(effect(EffectKind::SoftClose, vec![5.0 * inertia, closed + frac * (far - closed)], false));
                let free: Vec<Vec<bool>> =
                    st.iter().map(|e| (0..e.params.len()).map(|p| !(e.kind == EffectKind::SoftClose && p == 1)).collect()).collect();
                let r = fit(problem, &st, Some(&free), None, 8);
                grid.push((r.cost, r.effects));
            }
        }
        grid.sort_by(|a, b| a.0.total_cmp(&b.0));
        starts = grid.into_iter().take(1).map(|g| g.1).collect();
    }
    starts
        .iter()
        .map(|s| fit(problem, s, None, None, MAX_ITER))
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .unwrap_or_else(|| fit(problem, &base, None, None, MAX_ITER))
}

/// The start that nests a fitted structure in a larger one: the terms of `within` as fitted, each new
/// linear term at the level that means none (no damping, friction, spring or tilt; the modelled
/// weight). From it the larger structure cannot end worse than the one it holds; from a start
/// far from it, it can stick (friction that holds a lid shut loses every gradient). `None` when
/// no new term has such a level.
fn nested_start(base: &[Effect], within: &[Effect]) -> Option<Vec<Effect>> {
    let mut nested = base.to_vec();
    let mut any = false;
    for e in &mut nested {
        if let Some(fitted) = within.iter().find(|w| w.kind == e.kind) {
            e.clone_from(fitted);
            continue;
        }
        let none = match e.kind {
            EffectKind::ViscousDamping | EffectKind::CoulombFriction | EffectKind::Spring | EffectKind::GravityTilt => 0.0,
            EffectKind::MassScale => 1.0,
            _ => return None,
        };
        if let Some(level) = e.params.first_mut() {
            *level = none;
            any = true;
        }
    }
    (any && !within.is_empty()).then_some(nested)
}

fn key(kinds: &[EffectKind]) -> Vec<EffectKind> {
    let mut k = kinds.to_vec();
    k.sort_unstable();
    k
}

/// Whether a fitted structure is a look-alike of a smaller one: a soft-close zone that holds
/// (nearly) every observed sample is plain viscous damping, one that holds (nearly) none does
/// nothing. Such fits are not offered: the smaller structure says the same with fewer words.
fn degenerate(problem: &Problem<'_>, f: &FitResult) -> bool {
    let physics = JointPhysics::with_effects(problem.joint, &f.effects);
    let Some((_, engage)) = physics.soft_close else { return false };
    let closed = physics.closed_end;
    // Measured positions held to the model's travel (noise at a stop is at the stop).
    let (lo, hi) = (physics.lower.unwrap_or(f64::NEG_INFINITY), physics.upper.unwrap_or(f64::INFINITY));
    let used: Vec<f64> = problem.rows.iter().flatten().map(|&i| problem.y[i].clamp(lo.min(hi), hi)).collect();
    // Distance from the closed end towards the open side (samples a little past the closed end
    // count as inside).
    let reach = (engage - closed).abs();
    let side = (engage - closed).signum();
    let inside = used.iter().filter(|&&q| (q - closed) * side <= reach).count();
    let share = inside as f64 / used.len().max(1) as f64;
    !(0.02..=0.98).contains(&share)
}

/// Forward selection by BIC over `candidates`, at most `max_terms` terms: every single kind, then
/// (while a mismatch is left) every pair of kinds — not only pairs that keep the best single,
/// since look-alikes (spring vs tilt, damping vs soft close) make the greedy path go astray when
/// two effects act together — then greedy additions to the best pair.
///
/// A larger structure replaces the current one only when it lowers BIC by [`BIC_MARGIN`] and the
/// misfit by [`MIN_GAIN`]; terms are added only while the current model still leaves a mismatch
/// (a stretch of residual beyond the noise, [`super::locate::mismatch_spans`]): once the residual
/// is noise, a further term would fit integrator differences, not physics.
#[must_use]
pub fn select(problem: &Problem<'_>, derivs: &[[f64; 3]], candidates: &[EffectKind], max_terms: usize, min_mismatch: usize) -> Selection {
    let nominal = fit(problem, &[], None, None, MAX_ITER);
    let mut cache: BTreeMap<Vec<EffectKind>, FitResult> = BTreeMap::new();
    cache.insert(Vec::new(), nominal.clone());
    let mut chosen_kinds: Vec<EffectKind> = Vec::new();
    let mut current = nominal.clone();
    let leaves_mismatch = |f: &FitResult| {
        let physics = JointPhysics::with_effects(problem.joint, &f.effects);
        let residual = segment_residual(problem, &physics, &f.states);
        !mismatch_spans(&residual, problem.sigma, min_mismatch).is_empty()
    };
    for size in 1..=max_terms.min(candidates.len()) {
        if size > 1 && !leaves_mismatch(&current) {
            break;
        }
        let trials: Vec<Vec<EffectKind>> = if size == 2 {
            let mut pairs = Vec::new();
            for (a, &ka) in candidates.iter().enumerate() {
                for &kb in &candidates[a + 1..] {
                    pairs.push(key(&[ka, kb]));
                }
            }
            pairs
        } else {
            candidates.iter().filter(|k| !chosen_kinds.contains(k)).map(|&k| key(&[chosen_kinds.as_slice(), &[k]].concat())).collect()
        };
        // Warm starts: the current fit's terms, else each kind's own single fit.
        let warm_for = |kinds: &[EffectKind]| -> Vec<Effect> {
            kinds
                .iter()
                .filter_map(|k| {
                    current
                        .effects
                        .iter()
                        .find(|e| e.kind == *k)
                        .cloned()
                        .or_else(|| cache.get(&vec![*k]).and_then(|f| f.effects.iter().find(|e| e.kind == *k).cloned()))
                })
                .collect()
        };
        let jobs: Vec<(Vec<EffectKind>, Vec<Effect>)> =
            trials.iter().filter(|k| !cache.contains_key(*k)).map(|k| (k.clone(), warm_for(k))).collect();
        let fits: Vec<FitResult> =
            jobs.par_iter().map(|(kinds, warm)| fit_structure(problem, derivs, kinds, warm, &current.effects)).collect();
        for ((kinds, _), f) in jobs.into_iter().zip(fits) {
            cache.insert(kinds, f);
        }
        let best = trials
            .iter()
            .filter_map(|k| cache.get(k).map(|f| (k, f)))
            .filter(|(_, f)| !degenerate(problem, f))
            .min_by(|a, b| a.1.bic().total_cmp(&b.1.bic()));
        match best {
            Some((kinds, f)) if f.bic() < current.bic() - BIC_MARGIN && f.cost < (1.0 - MIN_GAIN) * current.cost => {
                chosen_kinds.clone_from(kinds);
                current = f.clone();
            }
            // No single kind helps on its own: pairs may still (two effects that mask each other).
            _ if size == 1 => {}
            _ => break,
        }
    }
    // Backward pruning: a term whose removal (refitted warm from the chosen fit) costs less than
    // MIN_GAIN of the misfit only rode along with a better start of the others.
    let mut pruned = true;
    while pruned && current.effects.len() > 1 {
        pruned = false;
        for e in 0..current.effects.len() {
            let rest: Vec<Effect> = current.effects.iter().enumerate().filter(|&(k, _)| k != e).map(|(_, x)| x.clone()).collect();
            let refit = fit(problem, &rest, None, Some(current.states.clone()), MAX_ITER);
            if refit.cost < (1.0 + MIN_GAIN) * current.cost {
                let kind = current.effects[e].kind;
                chosen_kinds.retain(|&k| k != kind);
                cache.insert(key(&chosen_kinds), refit.clone());
                current = refit;
                pruned = true;
                break;
            }
        }
    }
    // Confidence: the chosen model against dropping each term and against swapping it.
    let mut needed: Vec<Vec<EffectKind>> = Vec::new();
    for &e in &chosen_kinds {
        let rest: Vec<EffectKind> = chosen_kinds.iter().copied().filter(|&k| k != e).collect();
        needed.push(key(&rest));
        for &k in candidates.iter().filter(|k| !chosen_kinds.contains(k)) {
            needed.push(key(&[rest.as_slice(), &[k]].concat()));
        }
    }
    needed.retain(|k| !cache.contains_key(k));
    needed.dedup();
    let extra: Vec<FitResult> =
        needed.par_iter().map(|kinds| fit_structure(problem, derivs, kinds, &current.effects, &current.effects)).collect();
    cache.extend(needed.into_iter().zip(extra));
    let bic = current.bic();
    let confidence = current
        .effects
        .iter()
        .map(|e| {
            let rest: Vec<EffectKind> = chosen_kinds.iter().copied().filter(|&k| k != e.kind).collect();
            let mut odds = cache.get(&key(&rest)).map_or(0.0, |f| (-(f.bic() - bic) / 2.0).exp());
            for &k in candidates.iter().filter(|k| !chosen_kinds.contains(k)) {
                if let Some(f) = cache.get(&key(&[rest.as_slice(), &[k]].concat())) {
                    odds += (-(f.bic() - bic) / 2.0).min(50.0).exp();
                }
            }
            1.0 / (1.0 + odds)
        })
        .collect();
    let rejected = rejections(candidates, &chosen_kinds, &current, &nominal, &cache);
    Selection { nominal, chosen: current, confidence, rejected }
}

/// Why each candidate kind not in `chosen` was not reported, from the fits selection made: beside
/// the chosen terms where that structure was fitted, else alone against the model as written.
fn rejections(
    candidates: &[EffectKind],
    chosen: &[EffectKind],
    current: &FitResult,
    nominal: &FitResult,
    cache: &BTreeMap<Vec<EffectKind>, FitResult>,
) -> Vec<String> {
    let verdict = |f: &FitResult, against: &FitResult| {
        format!(
            "BIC {:+.1} (a term must lower it by {BIC_MARGIN:.0}) and {:.1} % of the misfit cut (it must cut {:.0} %)",
            f.bic() - against.bic(),
            100.0 * (1.0 - f.cost / against.cost.max(f64::MIN_POSITIVE)),
            100.0 * MIN_GAIN
        )
    };
    let names: Vec<&str> = chosen.iter().map(|k| k.name()).collect();
    candidates
        .iter()
        .filter(|k| !chosen.contains(k))
        .filter_map(|&k| {
            let why = if let Some(f) = cache.get(&key(&[chosen, &[k]].concat())).filter(|_| !chosen.is_empty()) {
                format!("fitted beside {}: {} — not reported", names.join(" + "), verdict(f, current))
            } else {
                let f = cache.get(&vec![k])?;
                if chosen.is_empty() {
                    format!("fitted alone: {} — not reported", verdict(f, nominal))
                } else {
                    format!(
                        "alone it explains less than {} (BIC {:+.1} against {:+.1}, both from the model as written); not tried beside \
                         them, which left no misfit beyond the noise",
                        names.join(" + "),
                        f.bic() - nominal.bic(),
                        current.bic() - nominal.bic()
                    )
                }
            };
            Some(format!("{}: {why}", k.name()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(kind: EffectKind, level: f64) -> Effect {
        Effect { kind, params: vec![level], blocks_upward: false }
    }

    fn check(base: &[Effect], within: &[Effect], expected: Option<&[(EffectKind, f64)]>) {
        let got = nested_start(base, within).map(|s| s.iter().map(|x| (x.kind, x.params[0])).collect::<Vec<_>>());
        assert_eq!(got.as_deref(), expected);
    }

    #[test]
    fn a_lid_that_got_heavier_first_gets_its_friction_fitted_from_none() {
        // Regression: a heavier MuJoCo lid with a dry hinge; the pair fit started from the
        // friction's own single fit, held the lid shut, and ended 200× worse than the weight
        // alone, so the friction was never named. The nested start keeps the weight as fitted.
        use EffectKind::{CoulombFriction, EndStop, MassScale, ViscousDamping};
        check(&[e(CoulombFriction, 0.8), e(MassScale, 1.4)], &[e(MassScale, 1.5)], Some(&[(CoulombFriction, 0.0), (MassScale, 1.5)]));
        check(&[e(ViscousDamping, 0.3), e(MassScale, 1.4)], &[e(ViscousDamping, 0.2)], Some(&[(ViscousDamping, 0.2), (MassScale, 1.0)]));
        // Nothing fitted yet, nothing new, or a new term with no level that means none: no start.
        check(&[e(CoulombFriction, 0.8)], &[], None);
        check(&[e(MassScale, 1.4)], &[e(MassScale, 1.5)], None);
        check(&[e(EndStop, 0.3), e(MassScale, 1.4)], &[e(MassScale, 1.5)], None);
    }
}
