//! Seeded, area-weighted points on triangles: what a scan of a mesh looks like when every face was
//! seen (no occlusion, no noise).

use rand::Rng;

use crate::math::Vec3;

/// `count` points on `triangles`, each triangle chosen with probability proportional to its area,
/// the point uniform on it. Returns (triangle index, point) in draw order; the same seed gives the
/// same points. Empty when the triangles have no area.
#[must_use]
pub fn sample_triangles(triangles: &[[Vec3; 3]], count: usize, seed: u64) -> Vec<(usize, Vec3)> {
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut total = 0.0_f64;
    for [a, b, c] in triangles {
        total += f64::from(0.5 * (*b - *a).cross(*c - *a).length());
        cumulative.push(total);
    }
    let Some(last) = triangles.len().checked_sub(1) else { return Vec::new() };
    if !(total > 0.0 && total.is_finite()) {
        return Vec::new();
    }
    let mut rng = crate::math::rng(seed);
    (0..count)
        .map(|_| {
            let u = rng.random::<f64>() * total;
            // The first triangle whose cumulative area passes u; zero-area triangles are never hit.
            let i = cumulative.partition_point(|&c| c <= u).min(last);
            let [a, b, c] = triangles[i];
            // Uniform on the triangle: the square-root warp of two uniforms.
            let (r1, r2): (f32, f32) = (rng.random(), rng.random());
            let s = r1.sqrt();
            (i, a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_area_and_stay_on_their_triangle() {
        // A unit right triangle and one three times its area; a degenerate one between them.
        let small = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let big = [Vec3::Z, Vec3::Z + Vec3::X * 3.0, Vec3::Z + Vec3::Y];
        let samples = sample_triangles(&[small, flat, big], 4000, 7);
        assert_eq!(samples.len(), 4000);
        assert_eq!(samples, sample_triangles(&[small, flat, big], 4000, 7), "deterministic");
        assert_ne!(samples, sample_triangles(&[small, flat, big], 4000, 8), "seeded");
        let on_big = samples.iter().filter(|(i, _)| *i == 2).count();
        assert!(samples.iter().all(|(i, _)| *i != 1), "a zero-area triangle gets no points");
        assert!((on_big as f32 / 4000.0 - 0.75).abs() < 0.03, "{on_big}");
        for (i, p) in &samples {
            let (z, bound) = if *i == 0 { (0.0, 1.0) } else { (1.0, 3.0) };
            assert!((p.z - z).abs() < 1e-6 && p.x >= -1e-6 && p.y >= -1e-6, "{p}");
            assert!(p.x / bound + p.y <= 1.0 + 1e-5, "{p} inside triangle {i}");
        }
        assert!(sample_triangles(&[flat], 10, 0).is_empty());
        assert!(sample_triangles(&[], 10, 0).is_empty());
    }
}
