//! Output-error fitting: Levenberg–Marquardt on multiple-shooting segments. The unknowns are the
//! effects' parameters plus a free initial state (q, v) per segment; the residual is measured
//! minus simulated position, in units of the noise σ. Jacobians by forward differences (a segment
//! state only touches its own segment). Normal equations are small and dense (`crate::linalg`).

use super::effects::{Effect, JointPhysics, clamp_params};
use super::locate::Span;
use super::model::GapJoint;
use super::sim::{SimInput, simulate};

pub use crate::linalg::solve_spd;

/// One joint's fitting problem.
#[derive(Debug, Clone)]
pub struct Problem<'a> {
    /// Recorded inputs.
    pub input: SimInput<'a>,
    /// Measured positions (NaN = dropout).
    pub y: &'a [f64],
    /// Noise σ (residuals are divided by it).
    pub sigma: f64,
    /// The model joint (nominal dynamics and limits).
    pub joint: &'a GapJoint,
    /// Shooting segments; each has its own free initial state.
    pub segments: Vec<Span>,
    /// Per segment, the samples that count (valid and in the training set).
    pub rows: Vec<Vec<usize>>,
}

/// Length of a shooting segment, seconds.
pub const SEGMENT_S: f64 = 2.0;

impl<'a> Problem<'a> {
    /// Segments of about [`SEGMENT_S`] over the samples where `use_sample` holds (at least 8
    /// samples each; a short tail joins the previous segment).
    #[must_use]
    pub fn new(input: SimInput<'a>, y: &'a [f64], use_sample: &[bool], sigma: f64, joint: &'a GapJoint) -> Self {
        Self::with_segments_of(input, y, use_sample, sigma, joint, SEGMENT_S)
    }

    /// The same with segments of about `segment_s` seconds.
    #[must_use]
    pub fn with_segments_of(
        input: SimInput<'a>,
        y: &'a [f64],
        use_sample: &[bool],
        sigma: f64,
        joint: &'a GapJoint,
        segment_s: f64,
    ) -> Self {
        let used: Vec<usize> = (0..y.len()).filter(|&i| use_sample[i] && y[i].is_finite()).collect();
        let mut segments: Vec<Span> = Vec::new();
        let mut rows: Vec<Vec<usize>> = Vec::new();
        let mut k = 0;
        while k < used.len() {
            let start = used[k];
            let t_end = input.time_s[start] + segment_s;
            let mut e = k;
            while e + 1 < used.len() && input.time_s[used[e + 1]] < t_end {
                e += 1;
            }
            let chunk: Vec<usize> = used[k..=e].to_vec();
            let tail_short = chunk.len() < 8;
            if tail_short && let (Some(last_seg), Some(last_rows)) = (segments.last_mut(), rows.last_mut()) {
                last_seg.end = used[e];
                last_rows.extend(chunk);
            } else {
                segments.push(Span { start, end: used[e] });
                rows.push(chunk);
            }
            k = e + 1;
        }
        Self { input, y, sigma: sigma.max(1e-9), joint, segments, rows }
    }

    /// One segment per span of `spans` (in order, disjoint), over its finite samples; a span
    /// with fewer than 2 of them is left out.
    #[must_use]
    pub fn with_spans(input: SimInput<'a>, y: &'a [f64], spans: &[Span], sigma: f64, joint: &'a GapJoint) -> Self {
        let (mut segments, mut rows) = (Vec::new(), Vec::new());
        for span in spans {
            let chunk: Vec<usize> = (span.start..=span.end.min(y.len().saturating_sub(1))).filter(|&i| y[i].is_finite()).collect();
            if chunk.len() >= 2 {
                segments.push(*span);
                rows.push(chunk);
            }
        }
        Self { input, y, sigma: sigma.max(1e-9), joint, segments, rows }
    }

    /// Number of residuals.
    #[must_use]
    pub fn n_rows(&self) -> usize {
        self.rows.iter().map(Vec::len).sum()
    }

    fn segment_residuals(&self, k: usize, physics: &JointPhysics, state: (f64, f64), buf: &mut Vec<f64>, out: &mut Vec<f64>) {
        let span = self.segments[k];
        buf.resize(span.end - span.start + 1, 0.0);
        simulate(&self.input, physics, span.start, span.end, state.0, state.1, buf);
        out.extend(self.rows[k].iter().map(|&i| (self.y[i] - buf[i - span.start]) / self.sigma));
    }

    /// Initial segment states from the data: first measured position, velocity from a line
    /// through the first few samples.
    #[must_use]
    pub fn data_states(&self) -> Vec<(f64, f64)> {
        self.rows
            .iter()
            .map(|rows| {
                let take = &rows[..rows.len().min(6)];
                let t0 = self.input.time_s[take[0]];
                let n = take.len() as f64;
                let mt = take.iter().map(|&i| self.input.time_s[i] - t0).sum::<f64>() / n;
                let my = take.iter().map(|&i| self.y[i]).sum::<f64>() / n;
                let sxx: f64 = take.iter().map(|&i| (self.input.time_s[i] - t0 - mt).powi(2)).sum();
                let sxy: f64 = take.iter().map(|&i| (self.input.time_s[i] - t0 - mt) * (self.y[i] - my)).sum();
                let v = if sxx > 0.0 { sxy / sxx } else { 0.0 };
                (my - v * mt, v)
            })
            .collect()
    }
}

/// Horizons (s from the segment start) over which [`refine_states`] fits each segment's state in
/// turn: output error with stops and friction is not convex in the initial state over a whole
/// segment (a start that hits a stop early loses all gradient), but is over a short stretch.
const HORIZONS_S: [f64; 4] = [0.15, 0.4, 1.0, f64::INFINITY];

/// Each segment's initial state fitted under `physics` by Levenberg–Marquardt over growing
/// horizons (continuation), starting from `states`.
#[must_use]
pub fn refine_states(problem: &Problem<'_>, physics: &JointPhysics, states: &[(f64, f64)]) -> Vec<(f64, f64)> {
    refine_states_within(problem, physics, states, f64::INFINITY)
}

/// [`refine_states`] on the samples within `max_horizon_s` of each segment's start only: the
/// state a prediction starts from, measured at the start and not fitted to what it predicts.
#[must_use]
pub fn refine_states_within(problem: &Problem<'_>, physics: &JointPhysics, states: &[(f64, f64)], max_horizon_s: f64) -> Vec<(f64, f64)> {
    let mut out = states.to_vec();
    let mut buf = Vec::new();
    for (k, span) in problem.segments.iter().enumerate() {
        let t0 = problem.input.time_s[span.start];
        let mut state = out[k];
        // A segment already at the noise level (over the samples the state is measured on) keeps
        // its state (most segments of a good fit).
        buf.resize(span.end - span.start + 1, 0.0);
        simulate(&problem.input, physics, span.start, span.end, state.0, state.1, &mut buf);
        let measured: Vec<usize> = problem.rows[k].iter().copied().filter(|&i| problem.input.time_s[i] - t0 <= max_horizon_s).collect();
        let z2: f64 = measured.iter().map(|&i| ((problem.y[i] - buf[i - span.start]) / problem.sigma).powi(2)).sum();
        if z2 <= 2.0 * measured.len() as f64 {
            continue;
        }
        let mut horizons: Vec<f64> = HORIZONS_S.iter().map(|h| h.min(max_horizon_s)).collect();
        horizons.dedup();
        for horizon in horizons {
            let rows: Vec<usize> = problem.rows[k].iter().copied().filter(|&i| problem.input.time_s[i] - t0 <= horizon).collect();
            if rows.len() < 3 {
                continue;
            }
            let end = rows[rows.len() - 1];
            let residual = |s: (f64, f64), buf: &mut Vec<f64>| -> Vec<f64> {
                buf.resize(end - span.start + 1, 0.0);
                simulate(&problem.input, physics, span.start, end, s.0, s.1, buf);
                rows.iter().map(|&i| (problem.y[i] - buf[i - span.start]) / problem.sigma).collect()
            };
            let mut r = residual(state, &mut buf);
            let mut cost: f64 = r.iter().map(|v| v * v).sum();
            let mut lambda = 1e-3;
            for _ in 0..15 {
                let hq = 1e-6 * (1.0 + state.0.abs());
                let hv = 1e-6 * (1.0 + state.1.abs());
                let rq = residual((state.0 + hq, state.1), &mut buf);
                let rv = residual((state.0, state.1 + hv), &mut buf);
                let (mut a, mut g) = ([0.0; 4], [0.0; 2]);
                for i in 0..r.len() {
                    let j = [(rq[i] - r[i]) / hq, (rv[i] - r[i]) / hv];
                    a[0] += j[0] * j[0];
                    a[1] += j[0] * j[1];
                    a[3] += j[1] * j[1];
                    g[0] -= j[0] * r[i];
                    g[1] -= j[1] * r[i];
                }
                a[2] = a[1];
                let mut accepted = false;
                for _ in 0..8 {
                    let damped = [a[0] * (1.0 + lambda) + 1e-12, a[1], a[2], a[3] * (1.0 + lambda) + 1e-12];
                    let Some(d) = solve_spd(&damped, &g, 2) else {
                        lambda *= 10.0;
                        continue;
                    };
                    let trial = (state.0 + d[0], state.1 + d[1]);
                    let rt = residual(trial, &mut buf);
                    let ct: f64 = rt.iter().map(|v| v * v).sum();
                    if ct.is_finite() && ct < cost {
                        accepted = (cost - ct) > 1e-9 * cost;
                        (state, r, cost) = (trial, rt, ct);
                        lambda = (lambda * 0.3).max(1e-9);
                        break;
                    }
                    lambda *= 10.0;
                }
                if !accepted {
                    break;
                }
            }
        }
        out[k] = state;
    }
    out
}

/// A fitted model of one joint.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The effects with fitted parameters.
    pub effects: Vec<Effect>,
    /// Fitted initial state per segment.
    pub states: Vec<(f64, f64)>,
    /// Sum of squared standardized residuals.
    pub cost: f64,
    /// Number of residuals.
    pub n: usize,
    /// Number of free parameters (effects + segment states).
    pub n_params: usize,
    /// Standard deviation of each effect parameter (same layout as `effects[i].params`).
    pub param_std: Vec<Vec<f64>>,
}

impl FitResult {
    /// Bayesian information criterion (Gaussian, variance profiled out).
    #[must_use]
    pub fn bic(&self) -> f64 {
        let n = self.n.max(1) as f64;
        n * (self.cost / n).max(1e-300).ln() + self.n_params as f64 * n.ln()
    }
}

fn unpack(effects: &mut [Effect], x: &[f64], slots: &[(usize, usize)]) {
    for (&(e, p), v) in slots.iter().zip(x) {
        effects[e].params[p] = *v;
    }
    for e in effects.iter_mut() {
        clamp_params(e.kind, &mut e.params);
    }
}

/// Fits the effects' parameters (those with `free[e][p]`, all when None) and the segment states.
///
/// After LM converges, each segment's state is refitted over growing horizons under the fitted
/// physics ([`refine_states`]); when that finds a better minimum for a segment (one stuck behind
/// a stop, say), LM runs once more from there.
#[must_use]
pub fn fit(
    problem: &Problem<'_>,
    init: &[Effect],
    free: Option<&[Vec<bool>]>,
    states: Option<Vec<(f64, f64)>>,
    max_iter: usize,
) -> FitResult {
    let first = fit_once(problem, init, free, states, max_iter);
    if max_iter < 10 || problem.segments.is_empty() {
        return first;
    }
    let physics = JointPhysics::with_effects(problem.joint, &first.effects);
    let refined = refine_states(problem, &physics, &first.states);
    let residual = segment_residual(problem, &physics, &refined);
    let cost: f64 = residual.iter().filter(|r| r.is_finite()).map(|r| (r / problem.sigma).powi(2)).sum();
    if cost < first.cost * (1.0 - 1e-4) {
        let second = fit_once(problem, &first.effects, free, Some(refined), max_iter);
        if second.cost < first.cost {
            return second;
        }
    }
    first
}

fn fit_once(
    problem: &Problem<'_>,
    init: &[Effect],
    free: Option<&[Vec<bool>]>,
    states: Option<Vec<(f64, f64)>>,
    max_iter: usize,
) -> FitResult {
    let mut effects = init.to_vec();
    let slots: Vec<(usize, usize)> = effects
        .iter()
        .enumerate()
        .flat_map(|(e, eff)| (0..eff.params.len()).map(move |p| (e, p)))
        .filter(|&(e, p)| free.is_none_or(|f| f[e][p]))
        .collect();
    let np = slots.len();
    let ns = problem.segments.len();
    let m = np + 2 * ns;
    let mut x: Vec<f64> = slots.iter().map(|&(e, p)| effects[e].params[p]).collect();
    let mut st = states.filter(|s| s.len() == ns).unwrap_or_else(|| {
        let physics = JointPhysics::with_effects(problem.joint, &effects);
        refine_states(problem, &physics, &problem.data_states())
    });
    let n_rows = problem.n_rows();
    let mut buf = Vec::new();

    let residuals = |effects: &[Effect], st: &[(f64, f64)], buf: &mut Vec<f64>| {
        let physics = JointPhysics::with_effects(problem.joint, effects);
        let mut r = Vec::with_capacity(n_rows);
        for (k, s) in st.iter().enumerate() {
            problem.segment_residuals(k, &physics, *s, buf, &mut r);
        }
        r
    };
    let cost_of = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    unpack(&mut effects, &x, &slots);
    let mut r = residuals(&effects, &st, &mut buf);
    let mut cost = cost_of(&r);
    let mut lambda = 1e-3;
    let mut normal = vec![0.0; m * m];
    let mut jac = vec![0.0; n_rows * m];
    let row_offsets: Vec<usize> = problem
        .rows
        .iter()
        .scan(0, |acc, rows| {
            let o = *acc;
            *acc += rows.len();
            Some(o)
        })
        .collect();
    for _ in 0..max_iter {
        // Jacobian (row-major n_rows × m), forward differences.
        jac.fill(0.0);
        for (c, slot) in slots.iter().enumerate() {
            let h = 1e-6 * (1.0 + x[c].abs());
            let mut trial = effects.clone();
            trial[slot.0].params[slot.1] = x[c] + h;
            let rp = residuals(&trial, &st, &mut buf);
            for (row, (a, b)) in rp.iter().zip(&r).enumerate() {
                jac[row * m + c] = (a - b) / h;
            }
        }
        let physics = JointPhysics::with_effects(problem.joint, &effects);
        for k in 0..ns {
            for d in 0..2 {
                let mut s = st[k];
                let h = 1e-6 * (1.0 + if d == 0 { s.0.abs() } else { s.1.abs() });
                if d == 0 {
                    s.0 += h;
                } else {
                    s.1 += h;
                }
                let mut rk = Vec::with_capacity(problem.rows[k].len());
                problem.segment_residuals(k, &physics, s, &mut buf, &mut rk);
                let c = np + 2 * k + d;
                for (j, v) in rk.iter().enumerate() {
                    let row = row_offsets[k] + j;
                    jac[row * m + c] = (v - r[row]) / h;
                }
            }
        }
        normal.fill(0.0);
        let mut grad = vec![0.0; m];
        for row in 0..n_rows {
            let jr = &jac[row * m..(row + 1) * m];
            for a in 0..m {
                if jr[a] == 0.0 {
                    continue;
                }
                grad[a] += jr[a] * r[row];
                for b in 0..=a {
                    normal[a * m + b] += jr[a] * jr[b];
                }
            }
        }
        for a in 0..m {
            for b in 0..a {
                normal[b * m + a] = normal[a * m + b];
            }
        }
        let mut improved = false;
        for _ in 0..10 {
            let mut damped = normal.clone();
            for a in 0..m {
                damped[a * m + a] += lambda * normal[a * m + a] + 1e-12;
            }
            let neg: Vec<f64> = grad.iter().map(|g| -g).collect();
            let Some(delta) = solve_spd(&damped, &neg, m) else {
                lambda *= 10.0;
                continue;
            };
            let x_new: Vec<f64> = x.iter().zip(&delta).map(|(a, d)| a + d).collect();
            let st_new: Vec<(f64, f64)> =
                st.iter().enumerate().map(|(k, s)| (s.0 + delta[np + 2 * k], s.1 + delta[np + 2 * k + 1])).collect();
            let mut eff_new = effects.clone();
            unpack(&mut eff_new, &x_new, &slots);
            let r_new = residuals(&eff_new, &st_new, &mut buf);
            let c_new = cost_of(&r_new);
            if c_new.is_finite() && c_new < cost {
                let rel = (cost - c_new) / cost.max(1e-300);
                x = slots.iter().map(|&(e, p)| eff_new[e].params[p]).collect();
                (effects, st, r, cost) = (eff_new, st_new, r_new, c_new);
                lambda = (lambda * 0.3).max(1e-9);
                improved = rel > 1e-7;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    // Parameter covariance: s² (JᵀJ)⁻¹ with the last Jacobian.
    let dof = n_rows.saturating_sub(m).max(1) as f64;
    let s2 = cost / dof;
    let mut param_std: Vec<Vec<f64>> = effects.iter().map(|e| vec![f64::NAN; e.params.len()]).collect();
    let mut reg = normal.clone();
    for a in 0..m {
        reg[a * m + a] += 1e-12 * (1.0 + reg[a * m + a]);
    }
    for (c, &(e, p)) in slots.iter().enumerate() {
        let mut unit = vec![0.0; m];
        unit[c] = 1.0;
        if let Some(col) = solve_spd(&reg, &unit, m) {
            param_std[e][p] = (s2 * col[c].max(0.0)).sqrt();
        }
    }
    FitResult { effects, states: st, cost, n: n_rows, n_params: m, param_std }
}

/// Residual (measured − simulated) of a fit's segments, NaN outside them or where not measured.
#[must_use]
pub fn segment_residual(problem: &Problem<'_>, physics: &JointPhysics, states: &[(f64, f64)]) -> Vec<f64> {
    let mut r = vec![f64::NAN; problem.y.len()];
    let mut buf = Vec::new();
    for (k, span) in problem.segments.iter().enumerate() {
        buf.resize(span.end - span.start + 1, 0.0);
        simulate(&problem.input, physics, span.start, span.end, states[k].0, states[k].1, &mut buf);
        for i in span.start..=span.end {
            if problem.y[i].is_finite() {
                r[i] = problem.y[i] - buf[i - span.start];
            }
        }
    }
    r
}

/// Open-loop simulation of the whole record from `state` at sample 0.
#[must_use]
pub fn open_loop(input: &SimInput<'_>, physics: &JointPhysics, state: (f64, f64)) -> Vec<f64> {
    let n = input.time_s.len();
    let mut out = vec![0.0; n];
    if n > 0 {
        simulate(input, physics, 0, n - 1, state.0, state.1, &mut out);
    }
    out
}
