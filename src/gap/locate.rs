//! Where simulation and recording disagree: a robust noise estimate from the data, binary
//! segmentation of the standardized squared residual (change points with a BIC penalty), and the
//! conditions during each mismatch (position range, direction of motion, nearness to a stop).

/// Measurement noise σ of a sampled signal: each sample against the straight line through its
/// valid neighbours (exact for linear motion, irregular sampling allowed), normalized to unit
/// variance for white noise, then 1.4826 · MAD (robust to impacts and dropouts).
#[must_use]
pub fn noise_sigma(time_s: &[f64], y: &[f64]) -> f64 {
    let valid: Vec<usize> = (0..y.len()).filter(|&i| y[i].is_finite()).collect();
    let mut r: Vec<f64> = valid
        .windows(3)
        .filter_map(|w| {
            let (t0, t1, t2) = (time_s[w[0]], time_s[w[1]], time_s[w[2]]);
            let span = t2 - t0;
            if span <= 0.0 {
                return None;
            }
            let (w0, w2) = ((t2 - t1) / span, (t1 - t0) / span);
            let line = w0 * y[w[0]] + w2 * y[w[2]];
            Some(((y[w[1]] - line) / (1.0 + w0 * w0 + w2 * w2).sqrt()).abs())
        })
        .collect();
    if r.is_empty() {
        return 0.0;
    }
    r.sort_by(f64::total_cmp);
    1.4826 * r[r.len() / 2]
}

/// A stretch of samples `start..=end` (indices into the recording).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// First sample.
    pub start: usize,
    /// Last sample.
    pub end: usize,
}

/// Change points of the mean of `z2` (squared standardized residual, NaN = missing) by binary
/// segmentation: a split is kept when it lowers the Gaussian cost by more than `penalty`.
#[must_use]
pub fn change_points(z2: &[f64], penalty: f64, min_len: usize) -> Vec<usize> {
    let idx: Vec<usize> = (0..z2.len()).filter(|&i| z2[i].is_finite()).collect();
    let vals: Vec<f64> = idx.iter().map(|&i| z2[i]).collect();
    let mut prefix = vec![0.0; vals.len() + 1];
    let mut prefix2 = vec![0.0; vals.len() + 1];
    for (k, v) in vals.iter().enumerate() {
        prefix[k + 1] = prefix[k] + v;
        prefix2[k + 1] = prefix2[k] + v * v;
    }
    // Cost of a segment: n · variance (sum of squared deviations from its mean).
    let cost = |a: usize, b: usize| {
        let n = (b - a) as f64;
        let s = prefix[b] - prefix[a];
        (prefix2[b] - prefix2[a]) - s * s / n
    };
    let total_var = (cost(0, vals.len()) / vals.len().max(1) as f64).max(1e-12);
    let mut cuts = Vec::new();
    let mut stack = vec![(0usize, vals.len())];
    while let Some((a, b)) = stack.pop() {
        if b - a < 2 * min_len {
            continue;
        }
        let whole = cost(a, b);
        let best = (a + min_len..=b - min_len).map(|k| (cost(a, k) + cost(k, b), k)).min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        if let Some((c, k)) = best
            && (whole - c) / total_var > penalty
        {
            cuts.push(k);
            stack.push((a, k));
            stack.push((k, b));
        }
    }
    cuts.sort_unstable();
    cuts.into_iter().map(|k| idx[k]).collect()
}

/// Mean squared standardized residual above which a stretch is a mismatch (noise gives ≈ 1;
/// the margin covers an imperfect σ estimate).
pub const MISMATCH_LEVEL: f64 = 2.5;

/// Stretches where the residual exceeds the noise: change points split the record, pieces whose
/// mean z² exceeds [`MISMATCH_LEVEL`] are merged with mismatching neighbours.
#[must_use]
pub fn mismatch_spans(residual: &[f64], sigma: f64, min_len: usize) -> Vec<Span> {
    let n = residual.len();
    if n == 0 || sigma <= 0.0 {
        return Vec::new();
    }
    let z2: Vec<f64> = residual.iter().map(|r| (r / sigma).powi(2)).collect();
    let valid = z2.iter().filter(|v| v.is_finite()).count();
    let penalty = 3.0 * (valid.max(2) as f64).ln();
    let mut bounds = vec![0];
    bounds.extend(change_points(&z2, penalty, min_len.max(2)));
    bounds.push(n);
    let mut spans: Vec<Span> = Vec::new();
    for w in bounds.windows(2) {
        let (a, b) = (w[0], w[1]);
        let vals: Vec<f64> = z2[a..b].iter().copied().filter(|v| v.is_finite()).collect();
        if vals.len() < min_len.max(2) {
            continue;
        }
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        if mean > MISMATCH_LEVEL {
            match spans.last_mut() {
                Some(last) if last.end + 1 == a => last.end = b - 1,
                _ => spans.push(Span { start: a, end: b - 1 }),
            }
        }
    }
    spans
}

/// Root mean square of the finite entries of `r` over `span`.
#[must_use]
pub fn rmse_over(r: &[f64], span: Span) -> f64 {
    let vals: Vec<f64> = r[span.start..=span.end].iter().copied().filter(|v| v.is_finite()).collect();
    if vals.is_empty() { 0.0 } else { (vals.iter().map(|v| v * v).sum::<f64>() / vals.len() as f64).sqrt() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_estimate_ignores_smooth_motion() {
        let mut rng = crate::math::rng(3);
        let normal = rand_distr::Normal::new(0.0, 0.002).expect("normal");
        let t: Vec<f64> = (0..1000).map(|i| f64::from(i) * 0.01 + if i % 3 == 0 { 0.003 } else { 0.0 }).collect();
        let y: Vec<f64> = t.iter().map(|t| (1.3 * t).sin() + rand_distr::Distribution::sample(&normal, &mut rng)).collect();
        let s = noise_sigma(&t, &y);
        assert!((s - 0.002).abs() < 0.0003, "{s}");
    }

    #[test]
    fn finds_the_bad_stretch() {
        let mut rng = crate::math::rng(4);
        let normal = rand_distr::Normal::new(0.0, 1.0).expect("normal");
        let r: Vec<f64> = (0..1000)
            .map(|i| {
                let e: f64 = rand_distr::Distribution::sample(&normal, &mut rng);
                if (400..600).contains(&i) { e + 5.0 } else { e }
            })
            .collect();
        let spans = mismatch_spans(&r, 1.0, 10);
        assert_eq!(spans.len(), 1);
        assert!((spans[0].start as i64 - 400).abs() <= 3 && (spans[0].end as i64 - 599).abs() <= 3, "{spans:?}");
        let quiet: Vec<f64> = r.iter().enumerate().map(|(i, v)| if (400..600).contains(&i) { v - 5.0 } else { *v }).collect();
        assert!(mismatch_spans(&quiet, 1.0, 10).is_empty());
    }
}
