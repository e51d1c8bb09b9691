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

#[cfg(test)]
mod tests {
    use super::*;

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
}
