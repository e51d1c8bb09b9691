//! 2D polygons: convex hulls, minimum-area rectangles (for boxes and footprints) and convex
//! polygon overlap (for the contact ratio). One place for them, used by fit, contact, scene and eval.
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

#[must_use]
/// Convex hull of 2D points, counter-clockwise, no repeated or collinear vertices
/// (Andrew's monotone chain).
pub fn convex_hull(mut pts: Vec<Vec2>) -> Vec<Vec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    // Turn test with a relative tolerance: nearly collinear vertices are dropped.
    let cross = |o: Vec2, a: Vec2, b: Vec2| {
        let (u, v) = (a - o, b - o);
        u.perp_dot(v) - 1e-5 * u.length() * v.length()
    };
    let mut hull: Vec<Vec2> = Vec::with_capacity(pts.len() + 1);
    for &p in &pts {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    let lower_len = hull.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while hull.len() >= lower_len && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop(); // the first point again
    hull
}

/// Direction (unit) of the first side of the minimum-area enclosing rectangle of a CCW convex
/// polygon, by rotating calipers. Areas use extents clamped to `min_extent` so segments and
/// points get a sensible answer.
#[must_use]
pub fn min_area_rect_dir(h: &[Vec2], min_extent: f32) -> Vec2 {
    let m = h.len();
    if m < 2 {
        return Vec2::X;
    }
    if m == 2 {
        return (h[1] - h[0]).try_normalize().unwrap_or(Vec2::X);
    }
    let next = |i: usize| (i + 1) % m;
    let clamp = |x: f32| x.max(min_extent);
    let mut best_dir = Vec2::X;
    let mut best_area = f32::INFINITY;
    // Calipers: j = farthest along the edge, k = farthest from the edge, l = farthest backwards.
    let (mut j, mut k, mut l) = (0usize, 0usize, 0usize);
    for i in 0..m {
        let Some(e) = (h[next(i)] - h[i]).try_normalize() else {
            continue;
        };
        let nrm = e.perp(); // inward for a CCW polygon
        if i == 0 {
            j = next(i);
        }
        let mut steps = 0;
        while (h[next(j)] - h[j]).dot(e) > 0.0 && steps < m {
            j = next(j);
            steps += 1;
        }
        if i == 0 {
            k = j;
        }
        steps = 0;
        while (h[next(k)] - h[k]).dot(nrm) > 0.0 && steps < m {
            k = next(k);
            steps += 1;
        }
        if i == 0 {
            l = k;
        }
        steps = 0;
        while (h[next(l)] - h[l]).dot(e) < 0.0 && steps < m {
            l = next(l);
            steps += 1;
        }
        let width = (h[j] - h[l]).dot(e);
        let height = (h[k] - h[i]).dot(nrm);
        let area = clamp(width) * clamp(height);
        if area < best_area {
            best_area = area;
            best_dir = e;
        }
    }
    best_dir
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

    #[test]
    fn calipers_find_the_tilted_rectangle() {
        let a = 0.4_f32;
        let (e, n) = (Vec2::new(a.cos(), a.sin()), Vec2::new(-a.sin(), a.cos()));
        let mut pts = Vec::new();
        for i in 0..=10 {
            for j in 0..=5 {
                pts.push(e * (i as f32 * 0.2) + n * (j as f32 * 0.1) + Vec2::new(3.0, -1.0));
            }
        }
        let hull = convex_hull(pts);
        assert_eq!(hull.len(), 4, "{hull:?}");
        let d = min_area_rect_dir(&hull, 1e-3);
        assert!(d.dot(e).abs() > 0.9999 || d.dot(n).abs() > 0.9999, "{d}");
    }
}
