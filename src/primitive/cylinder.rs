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
