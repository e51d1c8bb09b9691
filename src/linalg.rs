//! Small dense linear algebra in `f64`: the normal equations of the gap fits and the joint-space
//! mass matrices of the multibody dynamics are a few dozen unknowns at most. Hand-written because
//! a linear-algebra crate (nalgebra & co.) would be a heavy dependency of the core for a Cholesky
//! factorisation and a triangular solve.

/// The lower Cholesky factor `L` (row-major n×n, `a = L Lᵀ`) of a symmetric positive definite
/// `a`; None when `a` is not positive definite (or not finite).
#[must_use]
pub fn cholesky(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        // Row i from the rows above it (done) and its own entries left of j; every sum runs
        // k = 0, 1, … as the textbook loop does, on slices (no bounds check per product).
        let (done, rest) = l.split_at_mut(i * n);
        let row_i = &mut rest[..n];
        for j in 0..i {
            let row_j = &done[j * n..j * n + j];
            let mut s = a[i * n + j];
            for (x, y) in row_i[..j].iter().zip(row_j) {
                s -= x * y;
            }
            row_i[j] = s / done[j * n + j];
        }
        let mut s = a[i * n + i];
        for x in &row_i[..i] {
            s -= x * x;
        }
        if s <= 0.0 || !s.is_finite() {
            return None;
        }
        row_i[i] = s.sqrt();
    }
    Some(l)
}

/// Solves `L Lᵀ x = b` for a Cholesky factor from [`cholesky`].
#[must_use]
pub fn cholesky_solve(l: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut y = b.to_vec();
    cholesky_solve_in_place(l, &mut y, n);
    y
}

/// [`cholesky_solve`] over `y`, which holds `b` and receives `x`.
fn cholesky_solve_in_place(l: &[f64], y: &mut [f64], n: usize) {
    forward_substitute(l, y, n);
    back_substitute(l, y, n);
}

/// Solves `L z = b` over `y` (holding `b`, receiving `z`) for a Cholesky factor from [`cholesky`].
pub fn forward_substitute(l: &[f64], y: &mut [f64], n: usize) {
    for i in 0..n {
        let row = &l[i * n..i * n + i];
        let (before, rest) = y.split_at_mut(i);
        let mut v = rest[0];
        for (x, yk) in row.iter().zip(before.iter()) {
            v -= x * yk;
        }
        rest[0] = v / l[i * n + i];
    }
}

/// Solves `Lᵀ x = z` over `y` (holding `z`, receiving `x`) for a Cholesky factor from [`cholesky`].
pub fn back_substitute(l: &[f64], y: &mut [f64], n: usize) {
    for i in (0..n).rev() {
        // Column i of L below the diagonal (k = i + 1, …), walked down without an index check.
        let below = l.get((i + 1) * n + i..).unwrap_or(&[]).iter().step_by(n);
        let (head, done) = y.split_at_mut(i + 1);
        let mut v = head[i];
        for (x, yk) in below.zip(done.iter()) {
            v -= x * yk;
        }
        head[i] = v / l[i * n + i];
    }
}

/// Solves `a x = b` for a symmetric positive definite `a` (row-major n×n); None if not SPD.
#[must_use]
pub fn solve_spd(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    cholesky(a, n).map(|l| cholesky_solve(&l, b, n))
}

/// The inverse of a symmetric positive definite matrix (row-major); None if not SPD.
#[must_use]
pub fn inverse_spd(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let l = cholesky(a, n)?;
    let mut inv = vec![0.0; n * n];
    let mut column = vec![0.0; n];
    for c in 0..n {
        column.iter_mut().enumerate().for_each(|(i, u)| *u = f64::from(u8::from(i == c)));
        cholesky_solve_in_place(&l, &mut column, n);
        for (r, v) in column.iter().enumerate() {
            inv[r * n + c] = *v;
        }
    }
    Some(inv)
}

/// The eigenvalues of a symmetric matrix (row-major n×n), ascending: cyclic Jacobi rotations
/// until the off-diagonal is negligible against the diagonal (a few sweeps at these sizes).
#[must_use]
pub fn symmetric_eigenvalues(a: &[f64], n: usize) -> Vec<f64> {
    let mut a = a.to_vec();
    for _ in 0..64 {
        let off: f64 = (0..n).flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j))).map(|(i, j)| a[i * n + j].powi(2)).sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i].powi(2)).sum();
        if off <= 1e-30 * diag.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                // The rotation that zeroes (p, q): tan of its angle, the smaller root of the
                // textbook quadratic (1 where the two diagonal entries are equal).
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = if theta >= 0.0 { 1.0 } else { -1.0 } / (theta.abs() + theta.hypot(1.0));
                let c = 1.0 / t.hypot(1.0);
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
        }
    }
    let mut values: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
    values.sort_by(f64::total_cmp);
    values
}

/// The eigenvalues μ of `k x = μ m x` (k symmetric, m symmetric positive definite; row-major
/// n×n), ascending: those of `L⁻¹ k L⁻ᵀ` with `m = L Lᵀ`. None where m is not positive definite.
#[must_use]
pub fn generalized_eigenvalues(k: &[f64], m: &[f64], n: usize) -> Option<Vec<f64>> {
    let l = cholesky(m, n)?;
    // X = L⁻¹ k column by column, then L⁻¹ Xᵀ = L⁻¹ k L⁻ᵀ (k symmetric).
    let mut x = vec![0.0; n * n];
    let mut column = vec![0.0; n];
    for c in 0..n {
        column.iter_mut().enumerate().for_each(|(r, u)| *u = k[r * n + c]);
        forward_substitute(&l, &mut column, n);
        (0..n).for_each(|r| x[r * n + c] = column[r]);
    }
    let mut reduced = vec![0.0; n * n];
    for c in 0..n {
        column.iter_mut().enumerate().for_each(|(r, u)| *u = x[c * n + r]);
        forward_substitute(&l, &mut column, n);
        (0..n).for_each(|r| reduced[r * n + c] = column[r]);
    }
    // Symmetric up to rounding: its mean with its transpose.
    let sym: Vec<f64> = (0..n * n).map(|i| 0.5 * (reduced[i] + reduced[(i % n) * n + i / n])).collect();
    Some(symmetric_eigenvalues(&sym, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalues_of_a_symmetric_and_a_generalized_problem() {
        // [[2, 1, 0], [1, 2, 1], [0, 1, 2]]: 2 − √2, 2, 2 + √2.
        let a = [2.0, 1.0, 0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0];
        let r2 = 2f64.sqrt();
        let got = symmetric_eigenvalues(&a, 3);
        assert!(got.iter().zip([2.0 - r2, 2.0, 2.0 + r2]).all(|(g, w)| (g - w).abs() < 1e-12), "{got:?}");
        // k x = μ m x with m = diag(1, 4): μ of [[1, 0], [0, −2]] are 1 and −0.5.
        let got = generalized_eigenvalues(&[1.0, 0.0, 0.0, -2.0], &[1.0, 0.0, 0.0, 4.0], 2).expect("m is positive definite");
        assert!(got.iter().zip([-0.5, 1.0]).all(|(g, w)| (g - w).abs() < 1e-12), "{got:?}");
        assert!(generalized_eigenvalues(&[1.0], &[-1.0], 1).is_none());
    }

    #[test]
    fn cholesky_solves() {
        let a = [4.0, 2.0, 0.6, 2.0, 2.0, 0.5, 0.6, 0.5, 3.0];
        let b = [1.0, 2.0, 3.0];
        let got = solve_spd(&a, &b, 3).expect("spd");
        for i in 0..3 {
            let r: f64 = (0..3).map(|k| a[i * 3 + k] * got[k]).sum();
            assert!((r - b[i]).abs() < 1e-12);
        }
        assert!(solve_spd(&[1.0, 2.0, 2.0, 1.0], &[1.0, 1.0], 2).is_none());
        let inv = inverse_spd(&a, 3).expect("spd");
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i * 3 + k] * inv[k * 3 + j]).sum();
                assert!((p - f64::from(u8::from(i == j))).abs() < 1e-12);
            }
        }
    }

    /// The textbook Cholesky–Banachiewicz loops, indexed, and their triangular solves: what
    /// [`cholesky`] and [`cholesky_solve`] compute, in the same order of operations.
    fn textbook_solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
        let mut l = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                if i == j {
                    if s <= 0.0 || !s.is_finite() {
                        return None;
                    }
                    l[i * n + i] = s.sqrt();
                } else {
                    l[i * n + j] = s / l[j * n + j];
                }
            }
        }
        let mut y = b.to_vec();
        for i in 0..n {
            for k in 0..i {
                y[i] -= l[i * n + k] * y[k];
            }
            y[i] /= l[i * n + i];
        }
        for i in (0..n).rev() {
            for k in i + 1..n {
                y[i] -= l[k * n + i] * y[k];
            }
            y[i] /= l[i * n + i];
        }
        Some(y)
    }

    /// The gap fits' findings are compared bit for bit across releases: a faster loop must not
    /// change a single rounding.
    #[test]
    fn slice_loops_round_as_the_textbook_loops_do() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for n in [1, 2, 5, 13, 40] {
            // A Gram matrix of random columns (positive definite), scaled unevenly like the fits'.
            let rows = n + 3;
            let x: Vec<f64> = (0..rows * n).map(|i| rng.random_range(-1.0..1.0) * 10f64.powi((i % n) as i32 % 4 - 2)).collect();
            let a: Vec<f64> = (0..n * n).map(|ij| (0..rows).map(|r| x[r * n + ij / n] * x[r * n + ij % n]).sum()).collect();
            let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let got = solve_spd(&a, &b, n).expect("spd");
            let want = textbook_solve(&a, &b, n).expect("spd");
            assert!(got.iter().zip(&want).all(|(g, w)| g.to_bits() == w.to_bits()), "n = {n}");
        }
        assert!(solve_spd(&[1.0, 2.0, 2.0, 1.0], &[1.0, 1.0], 2).is_none());
    }
}
