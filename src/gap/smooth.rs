//! Zero-phase smoothing and differentiation of sampled signals, for effort-space identification.
//! [`local_cubic`]: a local cubic least-squares fit over ±`half_width_s` around each sample
//! (Savitzky–Golay on irregular time, dropouts skipped) gives value, velocity and acceleration;
//! a cubic keeps the acceleration unbiased at turning points, where a quadratic would flatten it.
//! [`Smoother`]: a Gaussian low-pass applied alike to every term of the equation of motion and
//! to the measured efforts, so both sides see the same delay (none) and the same bandwidth
//! ("parallel filtering", Gautier).

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

/// A zero-phase Gaussian low-pass as a fixed linear filter: per output time, the normalised
/// weights `exp(−Δt²/2σ²)` of the valid samples within ±[`GAUSS_SUPPORT_SIGMAS`]σ. Built once,
/// applied to many signals of the same sampling (the terms of an effort regression and the
/// efforts themselves, "parallel filtering"). A Gaussian has no side lobes: what lies above the
/// cut-off (torque ripple, a controller's chatter, a sensor's own dynamics) is removed, not
/// folded back at −20 dB as a local polynomial's side lobes would. Its attenuation of the motion
/// band needs no correction: both sides of the equation pass the same filter. Irregular time and
/// dropouts are handled by the normalisation (a kernel average, Nadaraya–Watson).
#[derive(Debug, Clone)]
pub struct Smoother {
    /// Per output time: its taps' range in `index` and `weight` (empty where no valid sample is
    /// in reach), and its first sample where the taps' samples are consecutive (no dropout in
    /// reach: the weights then meet the signal as one slice).
    taps: Vec<(std::ops::Range<usize>, Option<usize>)>,
    /// Sample index of each tap.
    index: Vec<usize>,
    /// Normalised weight of each tap.
    weight: Vec<f64>,
}

/// Reach of the Gaussian filter in σ (weights below e^−4.5 ≈ 1 % are dropped).
pub const GAUSS_SUPPORT_SIGMAS: f64 = 3.0;

/// The frequency at which a Gaussian filter of width σ halves an amplitude, times σ:
/// `exp(−(2π f σ)²/2) = ½` ⇒ `f σ = √(2 ln 2) / 2π`.
pub const GAUSS_HALF_GAIN_F_SIGMA: f64 = 0.187_390_6;

impl Smoother {
    /// The Gaussian filter of width `sigma_s` over the samples at `time_s` for which `valid`
    /// holds, evaluated at `eval_s`.
    #[must_use]
    pub fn new(time_s: &[f64], valid: &[bool], eval_s: &[f64], sigma_s: f64) -> Self {
        let idx: Vec<usize> = (0..time_s.len()).filter(|&i| valid[i] && time_s[i].is_finite()).collect();
        let times: Vec<f64> = idx.iter().map(|&i| time_s[i]).collect();
        let reach = GAUSS_SUPPORT_SIGMAS * sigma_s;
        let (mut taps, mut index, mut weight) = (Vec::with_capacity(eval_s.len()), Vec::new(), Vec::new());
        for &t0 in eval_s {
            let from = index.len();
            if t0.is_finite() {
                let lo = times.partition_point(|&t| t < t0 - reach);
                let hi = times.partition_point(|&t| t <= t0 + reach);
                let raw: Vec<f64> = (lo..hi).map(|k| (-0.5 * ((times[k] - t0) / sigma_s).powi(2)).exp()).collect();
                let total: f64 = raw.iter().sum();
                if total > 0.0 {
                    index.extend_from_slice(&idx[lo..hi]);
                    weight.extend(raw.into_iter().map(|w| w / total));
                }
            }
            let run = &index[from..];
            let consecutive = run.first().filter(|&&first| run.iter().enumerate().all(|(k, &i)| i == first + k)).copied();
            taps.push((from..index.len(), consecutive));
        }
        Self { taps, index, weight }
    }

    /// The filtered signal: NaN where no sample is in reach or a value in reach is not finite.
    #[must_use]
    pub fn apply(&self, y: &[f64]) -> Vec<f64> {
        self.taps
            .iter()
            .map(|(range, consecutive)| {
                let w = &self.weight[range.clone()];
                match consecutive {
                    _ if w.is_empty() => f64::NAN,
                    Some(first) => w.iter().zip(&y[*first..first + w.len()]).map(|(c, v)| c * v).sum(),
                    None => w.iter().zip(&self.index[range.clone()]).map(|(c, &i)| c * y[i]).sum(),
                }
            })
            .collect()
    }
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
    fn the_gaussian_filter_keeps_a_constant_and_halves_its_cut_off_frequency() {
        let time: Vec<f64> = (0..2000).map(|i| f64::from(i) * 0.002).collect();
        let sigma = 0.03;
        let f_half = GAUSS_HALF_GAIN_F_SIGMA / sigma;
        let filter = Smoother::new(&time, &vec![true; time.len()], &time, sigma);
        let constant = filter.apply(&vec![2.5; time.len()]);
        assert!(constant.iter().all(|v| (v - 2.5).abs() < 1e-12));
        let wave: Vec<f64> = time.iter().map(|t| (std::f64::consts::TAU * f_half * t).sin()).collect();
        let out = filter.apply(&wave);
        let peak = out[500..1500].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!((peak - 0.5).abs() < 0.01, "gain {peak} at the half-gain frequency");
        let fast: Vec<f64> = time.iter().map(|t| (std::f64::consts::TAU * 3.0 * f_half * t).sin()).collect();
        let peak = filter.apply(&fast)[500..1500].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(peak < 1e-2, "gain {peak} at three times the cut-off");
    }

    #[test]
    fn the_gaussian_filter_skips_a_dropout_and_weighs_its_neighbours_by_their_distance() {
        // Regression guard for the filter's two layouts (consecutive taps, and taps around a
        // dropout): both must be the normalised Gaussian average of the valid samples in reach.
        let time: Vec<f64> = (0..400).map(|i| f64::from(i) * 0.005).collect();
        let y: Vec<f64> = time.iter().map(|t| (7.0 * t).sin() + 0.3 * (23.0 * t).cos()).collect();
        let mut valid = vec![true; time.len()];
        valid[200] = false;
        // Reach 0.0639 s: no sample at its edge, where rounding would decide.
        let sigma = 0.0213;
        let filter = Smoother::new(&time, &valid, &time, sigma);
        let out = filter.apply(&y);
        for i in [10, 195, 200, 203, 390] {
            let (mut num, mut den) = (0.0, 0.0);
            for k in (0..time.len()).filter(|&k| valid[k] && (time[k] - time[i]).abs() <= GAUSS_SUPPORT_SIGMAS * sigma) {
                let w = (-0.5 * ((time[k] - time[i]) / sigma).powi(2)).exp();
                num += w * y[k];
                den += w;
            }
            assert!((out[i] - num / den).abs() < 1e-12, "sample {i}: {} vs {}", out[i], num / den);
        }
    }

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
