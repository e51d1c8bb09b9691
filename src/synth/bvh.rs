//! A bounding-volume hierarchy over primitives, for the virtual scanner's ray casts and
//! neighbourhood queries. Built once per scan; deterministic (median splits, index tie-breaks).

use crate::math::Vec3;
use crate::primitive::Primitive;

const LEAF_SIZE: usize = 4;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: range `[start, start + count)` of `order`; inner: `count == 0`, children
    /// `start` and `start + 1`.
    start: u32,
    count: u32,
}

/// A BVH over a slice of primitives (indices refer to that slice).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    bounds: Vec<(Vec3, Vec3)>,
}

/// Slab test of a ray against a box: entry distance if it hits within `[0, t_max]`.
fn ray_box(origin: Vec3, inv_dir: Vec3, lo: Vec3, hi: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let t_near = t0.min(t1).max_element().max(0.0);
    let t_far = t0.max(t1).min_element().min(t_max);
    (t_near <= t_far).then_some(t_near)
}

impl Bvh {
    /// Builds the hierarchy over `primitives` (their world bounds).
    #[must_use]
    pub fn new(primitives: &[Primitive]) -> Self {
        let bounds: Vec<(Vec3, Vec3)> = primitives.iter().map(Primitive::aabb).collect();
        let mut order: Vec<u32> = (0..primitives.len() as u32).collect();
        let mut nodes = vec![Node { lo: Vec3::ZERO, hi: Vec3::ZERO, start: 0, count: 0 }];
        if !order.is_empty() {
            Self::build(&mut nodes, 0, &mut order, 0, &bounds);
        }
        Self { nodes, order, bounds }
    }

    fn build(nodes: &mut Vec<Node>, node: usize, order: &mut [u32], offset: usize, bounds: &[(Vec3, Vec3)]) {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for &i in order.iter() {
            lo = lo.min(bounds[i as usize].0);
            hi = hi.max(bounds[i as usize].1);
        }
        if order.len() <= LEAF_SIZE {
            nodes[node] = Node { lo, hi, start: offset as u32, count: order.len() as u32 };
            return;
        }
        let center = |i: u32| 0.5 * (bounds[i as usize].0 + bounds[i as usize].1);
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |&a, &b| center(a)[axis].total_cmp(&center(b)[axis]).then(a.cmp(&b)));
        let first_child = nodes.len();
        nodes.push(Node { lo, hi, start: 0, count: 0 });
        nodes.push(Node { lo, hi, start: 0, count: 0 });
        nodes[node] = Node { lo, hi, start: first_child as u32, count: 0 };
        let (left, right) = order.split_at_mut(mid);
        Self::build(nodes, first_child, left, offset, bounds);
        Self::build(nodes, first_child + 1, right, offset + mid, bounds);
    }

    /// Closest hit of a ray (unit `dir`) within `max_dist`: (primitive index, distance, normal).
    #[must_use]
    pub fn ray_cast(&self, primitives: &[Primitive], origin: Vec3, dir: Vec3, max_dist: f32) -> Option<(usize, f32, Vec3)> {
        if self.order.is_empty() {
            return None;
        }
        let inv_dir = dir.recip();
        let mut best: Option<(usize, f32, Vec3)> = None;
        let mut t_max = max_dist;
        let mut stack = Vec::with_capacity(32);
        stack.push(0_usize);
        while let Some(n) = stack.pop() {
            let node = self.nodes[n];
            if ray_box(origin, inv_dir, node.lo, node.hi, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                for &i in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    let i = i as usize;
                    let (lo, hi) = self.bounds[i];
                    if ray_box(origin, inv_dir, lo, hi, t_max).is_none() {
                        continue;
                    }
                    if let Some((t, normal)) = primitives[i].ray_cast(origin, dir, t_max) {
                        let better = match best {
                            None => true,
                            Some((j, bt, _)) => t.total_cmp(&bt).then(i.cmp(&j)).is_lt(),
                        };
                        if better {
                            best = Some((i, t, normal));
                            t_max = t;
                        }
                    }
                }
            } else {
                let (a, b) = (node.start as usize, node.start as usize + 1);
                let ta = ray_box(origin, inv_dir, self.nodes[a].lo, self.nodes[a].hi, t_max);
                let tb = ray_box(origin, inv_dir, self.nodes[b].lo, self.nodes[b].hi, t_max);
                // Push the farther child first so the nearer one is searched first.
                match (ta, tb) {
                    (Some(x), Some(y)) if x <= y => stack.extend([b, a]),
                    (Some(_), Some(_)) => stack.extend([a, b]),
                    (Some(_), None) => stack.push(a),
                    (None, Some(_)) => stack.push(b),
                    (None, None) => {}
                }
            }
        }
        best
    }

    /// Calls `visit(i)` for every primitive whose bounds, grown by `radius`, contain `point`
    /// (in increasing tree order, deterministic).
    pub fn for_each_near(&self, point: Vec3, radius: f32, mut visit: impl FnMut(usize)) {
        if self.order.is_empty() {
            return;
        }
        let near = |lo: Vec3, hi: Vec3| (point.cmpge(lo - radius) & point.cmple(hi + radius)).all();
        let mut stack = vec![0_usize];
        while let Some(n) = stack.pop() {
            let node = self.nodes[n];
            if !near(node.lo, node.hi) {
                continue;
            }
            if node.count > 0 {
                for &i in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    let (lo, hi) = self.bounds[i as usize];
                    if near(lo, hi) {
                        visit(i as usize);
                    }
                }
            } else {
                stack.extend([node.start as usize + 1, node.start as usize]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<Primitive> {
        let mut out = Vec::new();
        for i in 0..7 {
            for j in 0..5 {
                out.push(Primitive::cuboid_at(Vec3::new(i as f32, j as f32, 0.0), Vec3::splat(0.5)));
            }
        }
        out
    }

    #[test]
    fn ray_cast_matches_brute_force() {
        let prims = grid();
        let bvh = Bvh::new(&prims);
        for k in 0..200 {
            let a = k as f32 * 0.37;
            let origin = Vec3::new(3.0 + 6.0 * a.cos(), 2.0 + 5.0 * a.sin(), 0.3 * (a * 1.7).sin());
            let target = Vec3::new((k % 7) as f32 + 0.1, (k % 5) as f32 - 0.1, 0.05);
            let dir = (target - origin).normalize();
            let brute = prims
                .iter()
                .enumerate()
                .filter_map(|(i, p)| p.ray_cast(origin, dir, 100.0).map(|(t, _)| (i, t)))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            let got = bvh.ray_cast(&prims, origin, dir, 100.0).map(|(i, t, _)| (i, t));
            assert_eq!(got.map(|g| g.0), brute.map(|b| b.0), "ray {k}");
        }
    }

    #[test]
    fn near_query_finds_neighbours() {
        let prims = grid();
        let bvh = Bvh::new(&prims);
        let mut found = Vec::new();
        // Between four boxes at (1,1), (2,1), (1,2), (2,2): gaps of 0.5, so radius 0.3 reaches all.
        bvh.for_each_near(Vec3::new(1.5, 1.5, 0.0), 0.3, |i| found.push(i));
        found.sort_unstable();
        let want: Vec<usize> = [(1, 1), (1, 2), (2, 1), (2, 2)].iter().map(|(i, j)| i * 5 + j).collect();
        assert_eq!(found, want);
    }
}
