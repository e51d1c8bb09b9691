//! Capsule geometry: radius `r`, half length of the straight segment `hs`, axis z.

use super::{r2, sphere, split_counts};
use crate::math::Vec3;
use std::f32::consts::{PI, TAU};

fn segment_point(hs: f32, p: Vec3) -> Vec3 {
    Vec3::new(0.0, 0.0, p.z.clamp(-hs, hs))
}

pub(super) fn closest_surface_point(r: f32, hs: f32, p: Vec3) -> Vec3 {
    let c = segment_point(hs, p);
    let d = p - c;
    let dir = if d.length_squared() > 1e-18 { d.normalize() } else { Vec3::X };
    c + dir * r
}

pub(super) fn contains(r: f32, hs: f32, p: Vec3) -> bool {
    (p - segment_point(hs, p)).length_squared() <= r * r
}

pub(super) fn volume(r: f32, hs: f32) -> f32 {
    PI * r * r * 2.0 * hs + 4.0 / 3.0 * PI * r * r * r
}

pub(super) fn area(r: f32, hs: f32) -> f32 {
    TAU * r * 2.0 * hs + 4.0 * PI * r * r
}

pub(super) fn sample_surface(r: f32, hs: f32, n: usize) -> Vec<Vec3> {
    let side = TAU * r * 2.0 * hs;
    let caps = 4.0 * PI * r * r;
    let counts = split_counts(n, &[side, caps]);
    let mut out = Vec::with_capacity(n + 2);
    for i in 0..counts[0] {
        let (u, v) = r2(i);
        let a = TAU * u;
        out.push(Vec3::new(r * a.cos(), r * a.sin(), (2.0 * v - 1.0) * hs));
    }
    let m = counts[1];
    for i in 0..m {
        let s = sphere::fibonacci(i, m) * r;
        let shift = if s.z >= 0.0 { hs } else { -hs };
        out.push(Vec3::new(s.x, s.y, s.z + shift));
    }
    out
}
