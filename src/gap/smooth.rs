//! Zero-phase smoothing and differentiation of sampled signals, for effort-space identification:
//! a local cubic least-squares fit over ±`half_width_s` around each sample (Savitzky–Golay on
//! irregular time, dropouts skipped). The same smoother is applied to positions (value, velocity,
//! acceleration) and to efforts (value), so both sides of the equation of motion see the same
//! delay (none) and the same bandwidth ("parallel filtering", Gautier). A cubic keeps the
//! acceleration unbiased at turning points, where a quadratic would flatten it.

use crate::linalg::solve_spd;

/// Half-width of the smoothing window, s: a cubic over 0.1 s passes motion up to ≈ 5 Hz with
/// little attenuation (hand pushes, excitation trajectories of arms and pendula) and averages
/// encoder quantisation over tens of samples at 200–500 Hz.
pub const DEFAULT_HALF_WIDTH_S: f64 = 0.05;

/// Fewest samples on each side of the centre.
const MIN_SIDE_SAMPLES: usize = 3;

/// Value, first and second derivative of `y` at every sample, dropouts included (from their
/// valid neighbours; NaN where the window holds too few valid samples). The window is
/// ±`half_width_s`, widened to [`MIN_SIDE_SAMPLES`] valid samples on each side where the sampling
/// is sparse.
#[must_use]
pub fn local_cubic(time_s: &[f64], y: &[f64], half_width_s: f64) -> Vec<[f64; 3]> {
    let valid: Vec<usize> = (0..y.len()).filter(|&i| y[i].is_finite() && time_s[i].is_finite()).collect();
    let mut out = vec![[f64::NAN; 3]; y.len()];
    if valid.len() < 2 * MIN_SIDE_SAMPLES + 1 {
        return out;
    }
    let times: Vec<f64> = valid.iter().map(|&i| time_s[i]).collect();
    for (i, slot) in out.iter_mut().enumerate() {
        let t0 = time_s[i];
        if !t0.is_finite() {
            continue;
        }
        // Valid samples within the window, at least MIN_SIDE_SAMPLES on each side.
        let centre = times.partition_point(|&t| t < t0);
        let lo = times.partition_point(|&t| t < t0 - half_width_s).min(centre.saturating_sub(MIN_SIDE_SAMPLES));
        let hi = times.partition_point(|&t| t <= t0 + half_width_s).max((centre + MIN_SIDE_SAMPLES + 1).min(times.len()));
        let window = &valid[lo..hi];
        if window.len() < 5 {
            continue;
        }
        if let Some(d) = fit_cubic(time_s, y, window, t0) {
            *slot = d;
        }
    }
    out
}

/// Value, first and second derivative at `t0` of the least-squares cubic through `window`.
fn fit_cubic(time_s: &[f64], y: &[f64], window: &[usize], t0: f64) -> Option<[f64; 3]> {
    // Scaled time keeps the normal equations well conditioned.
    let scale = window.iter().map(|&w| (time_s[w] - t0).abs()).fold(0.0, f64::max).max(1e-9);
    let mut ata = [0.0f64; 16];
    let mut atb = [0.0f64; 4];
    for &w in window {
        let s = (time_s[w] - t0) / scale;
        let phi = [1.0, s, s * s, s * s * s];
        for r in 0..4 {
            atb[r] += phi[r] * y[w];
            for c in 0..4 {
                ata[r * 4 + c] += phi[r] * phi[c];
            }
        }
    }
    solve_spd(&ata, &atb, 4).map(|x| [x[0], x[1] / scale, 2.0 * x[2] / (scale * scale)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cubic_is_reproduced_exactly_on_irregular_time_with_dropouts() {
        let time: Vec<f64> = (0..200).map(|i| f64::from(i) * 0.01 + 0.003 * (f64::from(i) * 1.7).sin()).collect();
        let f = |t: f64| 0.5 - 1.2 * t + 0.8 * t * t - 0.3 * t * t * t;
        let mut y: Vec<f64> = time.iter().map(|&t| f(t)).collect();
        for i in (5..200).step_by(17) {
            y[i] = f64::NAN;
        }
        let d = local_cubic(&time, &y, 0.05);
        for (i, &t) in time.iter().enumerate() {
            let [q, v, a] = d[i];
            assert!((q - f(t)).abs() < 1e-9, "q at {t}");
            assert!((v - (-1.2 + 1.6 * t - 0.9 * t * t)).abs() < 1e-7, "v at {t}");
            assert!((a - (1.6 - 1.8 * t)).abs() < 1e-5, "a at {t}");
        }
    }
}
