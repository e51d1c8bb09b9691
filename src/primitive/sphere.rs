//! Sphere geometry: radius `r`, centred at the origin.

use crate::math::Vec3;

pub(super) fn closest_surface_point(r: f32, p: Vec3) -> Vec3 {
    p.normalize_or(Vec3::Z) * r
}

pub(super) fn contains(r: f32, p: Vec3) -> bool {
    p.length_squared() <= r * r
}

pub(super) fn area(r: f32) -> f32 {
    4.0 * std::f32::consts::PI * r * r
}

/// Fibonacci lattice on the unit sphere: point `i` of `n`.
pub(super) fn fibonacci(i: usize, n: usize) -> Vec3 {
    let golden = std::f32::consts::PI * (3.0 - 5.0_f32.sqrt());
    let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
    let rho = (1.0 - z * z).max(0.0).sqrt();
    let a = golden * i as f32;
    Vec3::new(rho * a.cos(), rho * a.sin(), z)
}

pub(super) fn sample_surface(r: f32, n: usize) -> Vec<Vec3> {
    (0..n).map(|i| fibonacci(i, n) * r).collect()
}
