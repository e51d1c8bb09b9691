//! Cylinder geometry: radius `r`, half height `hz`, axis z, centred at the origin.

use super::{r2, split_counts};
use crate::math::{Vec2, Vec3};
use std::f32::consts::TAU;

pub(super) fn closest_surface_point(r: f32, hz: f32, p: Vec3) -> Vec3 {
    let radial = Vec2::new(p.x, p.y);
    let rho = radial.length();
    let dir = if rho > 1e-9 { radial / rho } else { Vec2::X };
    let inside_r = rho <= r;
    let inside_z = p.z.abs() <= hz;
    if inside_r && inside_z {
        // Inside: nearest of side and caps.
        let to_side = r - rho;
        let to_cap = hz - p.z.abs();
        if to_side < to_cap {
            let s = dir * r;
            Vec3::new(s.x, s.y, p.z)
        } else {
            Vec3::new(p.x, p.y, hz.copysign(p.z))
        }
    } else {
        let rr = rho.min(r);
        let s = dir * rr;
        Vec3::new(s.x, s.y, p.z.clamp(-hz, hz))
    }
}

pub(super) fn contains(r: f32, hz: f32, p: Vec3) -> bool {
    p.z.abs() <= hz && p.x * p.x + p.y * p.y <= r * r
}

pub(super) fn area(r: f32, hz: f32) -> f32 {
    TAU * r * r + TAU * r * 2.0 * hz
}

pub(super) fn inertia(r: f32, h: f32, m: f32) -> Vec3 {
    let lateral = m * (3.0 * r * r + h * h) / 12.0;
    Vec3::new(lateral, lateral, 0.5 * m * r * r)
}

/// Points on a disk of radius `r` (area-uniform).
pub(super) fn disk(r: f32, i: usize) -> Vec2 {
    let (u, v) = r2(i);
    let rho = r * u.sqrt();
    let a = TAU * v;
    Vec2::new(rho * a.cos(), rho * a.sin())
}

pub(super) fn sample_surface(r: f32, hz: f32, n: usize) -> Vec<Vec3> {
    let cap = std::f32::consts::PI * r * r;
    let side = TAU * r * 2.0 * hz;
    let counts = split_counts(n, &[cap, cap, side]);
    let mut out = Vec::with_capacity(n + 3);
    for (k, z) in [hz, -hz].into_iter().enumerate() {
        for i in 0..counts[k] {
            let d = disk(r, i);
            out.push(Vec3::new(d.x, d.y, z));
        }
    }
    for i in 0..counts[2] {
        let (u, v) = r2(i);
        let a = TAU * u;
        out.push(Vec3::new(r * a.cos(), r * a.sin(), (2.0 * v - 1.0) * hz));
    }
    out
}

/// First hit of a ray (local frame, from outside) with the cylinder: (distance, outward normal).
/// Closed form: parry casts rays on cylinders by an iterative support-map search that lands up
/// to a few millimetres off the surface, too coarse for a depth scanner or for picking.
pub(super) fn ray_cast(r: f32, hz: f32, o: Vec3, d: Vec3, max_dist: f32) -> Option<(f32, Vec3)> {
    // Start the ray just outside the bounding sphere: solving from far away loses digits to
    // cancellation.
    let shift = (-o.dot(d) / d.length_squared().max(1e-12) - (r + hz)).max(0.0);
    let o = o + d * shift;
    let mut best: Option<(f32, Vec3)> = None;
    let mut consider = |t: f32, n: Vec3| {
        let t = t + shift;
        if t >= shift && t <= max_dist && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, n));
        }
    };
    let a = d.x * d.x + d.y * d.y;
    if a > 1e-12 {
        let b = 2.0 * (o.x * d.x + o.y * d.y);
        let c = o.x * o.x + o.y * o.y - r * r;
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let t = (-b - disc.sqrt()) / (2.0 * a);
            let q = o + d * t;
            if q.z.abs() <= hz {
                consider(t, Vec3::new(q.x, q.y, 0.0).normalize_or(Vec3::X));
            }
        }
    }
    if d.z.abs() > 1e-12 {
        for side in [-1.0_f32, 1.0] {
            if d.z * side >= 0.0 {
                continue; // the ray leaves through this cap
            }
            let t = (side * hz - o.z) / d.z;
            let q = o + d * t;
            if q.x * q.x + q.y * q.y <= r * r {
                consider(t, Vec3::Z * side);
            }
        }
    }
    best
}
