//! Convex polygon overlap in 2D (for the contact ratio).
//!
//! Hand-written: every outline here is convex (box faces, cap polygons), for which
//! Sutherland–Hodgman clipping is exact and ~30 lines; the kept polygon crates (geo's boolean
//! operations, parry2d) would add a second geometry stack to the build for this one function.

use crate::math::Vec2;

/// Signed area (positive when counter-clockwise).
#[must_use]
pub fn signed_area(poly: &[Vec2]) -> f32 {
    let n = poly.len();
    if n < 3 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        s += a.x * b.y - b.x * a.y;
    }
    0.5 * s
}

/// Area of a simple polygon.
#[must_use]
pub fn polygon_area(poly: &[Vec2]) -> f32 {
    signed_area(poly).abs()
}

fn ccw(poly: &[Vec2]) -> Vec<Vec2> {
    let mut p = poly.to_vec();
    if signed_area(&p) < 0.0 {
        p.reverse();
    }
    p
}

/// Intersection of two convex polygons (any orientation); counter-clockwise result, possibly empty.
#[must_use]
pub fn convex_intersection(subject: &[Vec2], clip: &[Vec2]) -> Vec<Vec2> {
    if subject.len() < 3 || clip.len() < 3 {
        return Vec::new();
    }
    let clip = ccw(clip);
    let mut output = ccw(subject);
    let m = clip.len();
    for i in 0..m {
        if output.is_empty() {
            break;
        }
        let a = clip[i];
        let b = clip[(i + 1) % m];
        let edge = b - a;
        let inside = |p: Vec2| edge.perp_dot(p - a) >= -1e-9;
        let input = std::mem::take(&mut output);
        let k = input.len();
        for j in 0..k {
            let cur = input[j];
            let prev = input[(j + k - 1) % k];
            let (cin, pin) = (inside(cur), inside(prev));
            if cin != pin {
                // Intersection of segment prev→cur with the clip line.
                let d = cur - prev;
                let denom = edge.perp_dot(d);
                if denom.abs() > 1e-12 {
                    let t = edge.perp_dot(a - prev) / denom;
                    output.push(prev + d * t.clamp(0.0, 1.0));
                }
            }
            if cin {
                output.push(cur);
            }
        }
    }
    output
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: f32, y0: f32, x1: f32, y1: f32) -> Vec<Vec2> {
        vec![Vec2::new(x0, y0), Vec2::new(x1, y0), Vec2::new(x1, y1), Vec2::new(x0, y1)]
    }

    fn check(a: &[Vec2], b: &[Vec2], expected_area: f32) {
        let got = polygon_area(&convex_intersection(a, b));
        assert!((got - expected_area).abs() < 1e-5, "got {got}, expected {expected_area}");
        let sym = polygon_area(&convex_intersection(b, a));
        assert!((sym - expected_area).abs() < 1e-5, "not symmetric: {sym}");
    }

    #[test]
    fn overlaps_with_known_areas() {
        check(&rect(0.0, 0.0, 2.0, 2.0), &rect(1.0, 1.0, 3.0, 3.0), 1.0);
        check(&rect(0.0, 0.0, 2.0, 2.0), &rect(0.5, 0.5, 1.0, 1.0), 0.25); // contained
        check(&rect(0.0, 0.0, 1.0, 1.0), &rect(2.0, 2.0, 3.0, 3.0), 0.0); // disjoint
        check(&rect(0.0, 0.0, 1.0, 1.0), &rect(1.0, 0.0, 2.0, 1.0), 0.0); // touching edge
        // A diamond inside a square: area of the diamond.
        let diamond = vec![Vec2::new(1.0, 0.0), Vec2::new(2.0, 1.0), Vec2::new(1.0, 2.0), Vec2::new(0.0, 1.0)];
        check(&rect(0.0, 0.0, 2.0, 2.0), &diamond, 2.0);
        // Clockwise input is handled.
        let mut cw = rect(0.0, 0.0, 2.0, 2.0);
        cw.reverse();
        check(&cw, &rect(1.0, 0.0, 3.0, 1.0), 1.0);
    }
}
