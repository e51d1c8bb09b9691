//! Cuboid geometry (half extents `h`, centred at the origin).

use super::{r2, split_counts};
use crate::math::Vec3;

pub(super) fn closest_surface_point(h: Vec3, p: Vec3) -> Vec3 {
    let q = p.clamp(-h, h);
    if q != p {
        return q; // outside: the clamped point is on the surface
    }
    // Inside: push to the nearest face.
    let gap = h - p.abs();
    let mut out = p;
    if gap.x <= gap.y && gap.x <= gap.z {
        out.x = h.x.copysign(p.x);
    } else if gap.y <= gap.z {
        out.y = h.y.copysign(p.y);
    } else {
        out.z = h.z.copysign(p.z);
    }
    out
}

pub(super) fn contains(h: Vec3, p: Vec3) -> bool {
    p.abs().cmple(h).all()
}

pub(super) fn area(h: Vec3) -> f32 {
    8.0 * (h.x * h.y + h.y * h.z + h.x * h.z)
}

pub(super) fn inertia(size: Vec3, m: f32) -> Vec3 {
    let s = size * size;
    Vec3::new(s.y + s.z, s.x + s.z, s.x + s.y) * (m / 12.0)
}

pub(super) fn sample_surface(h: Vec3, n: usize) -> Vec<Vec3> {
    // Faces: ±x (area 4 hy hz), ±y, ±z.
    let areas = [4.0 * h.y * h.z, 4.0 * h.y * h.z, 4.0 * h.x * h.z, 4.0 * h.x * h.z, 4.0 * h.x * h.y, 4.0 * h.x * h.y];
    let counts = split_counts(n, &areas);
    let mut out = Vec::with_capacity(n + 6);
    for (face, count) in counts.into_iter().enumerate() {
        let axis = face / 2;
        let sign = if face % 2 == 0 { 1.0 } else { -1.0 };
        for i in 0..count {
            let (u, v) = r2(i);
            let (u, v) = (2.0 * u - 1.0, 2.0 * v - 1.0);
            let p = match axis {
                0 => Vec3::new(sign * h.x, u * h.y, v * h.z),
                1 => Vec3::new(u * h.x, sign * h.y, v * h.z),
                _ => Vec3::new(u * h.x, v * h.y, sign * h.z),
            };
            out.push(p);
        }
    }
    out
}
