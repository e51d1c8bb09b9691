//! Edmonds' (Chu–Liu/Edmonds) maximum-weight spanning arborescence, exact, generic over any
//! weighted digraph given as an edge list.
//!
//! Hand-written: petgraph has minimum spanning trees for undirected graphs only, and no kept
//! crate offers directed arborescences. Ties are broken by edge order (the first of equal
//! incoming edges wins), so the result is a pure function of the input order.

/// A directed edge `from → to` with a weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedEdge {
    pub from: usize,
    pub to: usize,
    pub weight: f64,
}

/// The maximum-weight arborescence rooted at `root` over nodes `0..n`.
///
/// Returns the indices (into `edges`) of the chosen edges, one per non-root node, sorted by the
/// node they enter; `None` when some node cannot be reached from the root.
#[must_use]
pub fn max_arborescence(n: usize, root: usize, edges: &[WeightedEdge]) -> Option<Vec<usize>> {
    if root >= n {
        return None;
    }
    let mut chosen = solve(n, root, edges)?;
    chosen.sort_by_key(|&k| edges[k].to);
    Some(chosen)
}

fn solve(n: usize, root: usize, edges: &[WeightedEdge]) -> Option<Vec<usize>> {
    const NONE: usize = usize::MAX;
    // 1. Best incoming edge of every node.
    let mut best: Vec<Option<usize>> = vec![None; n];
    for (k, e) in edges.iter().enumerate() {
        if e.to == root || e.from == e.to || e.to >= n || e.from >= n {
            continue;
        }
        if best[e.to].is_none_or(|b| e.weight > edges[b].weight) {
            best[e.to] = Some(k);
        }
    }
    let mut parent = vec![usize::MAX; n];
    for v in 0..n {
        if v == root {
            continue;
        }
        parent[v] = edges[best[v]?].from;
    }
    // 2. Cycles among the chosen edges.
    let mut cycle_of = vec![NONE; n];
    let mut visited_from = vec![NONE; n];
    let mut cycles = 0;
    for v in 0..n {
        let mut x = v;
        while x != root && visited_from[x] == NONE && cycle_of[x] == NONE {
            visited_from[x] = v;
            x = parent[x];
        }
        if x != root && visited_from[x] == v && cycle_of[x] == NONE {
            let mut y = x;
            loop {
                cycle_of[y] = cycles;
                y = parent[y];
                if y == x {
                    break;
                }
            }
            cycles += 1;
        }
    }
    if cycles == 0 {
        return Some((0..n).filter(|&v| v != root).filter_map(|v| best[v]).collect());
    }
    // 3. Contract every cycle into one node and solve the smaller problem.
    let mut map = vec![0; n];
    let mut next = cycles;
    for v in 0..n {
        if cycle_of[v] == NONE {
            map[v] = next;
            next += 1;
        } else {
            map[v] = cycle_of[v];
        }
    }
    let mut sub_edges = Vec::with_capacity(edges.len());
    let mut sub_origin = Vec::with_capacity(edges.len());
    for (k, e) in edges.iter().enumerate() {
        if e.from >= n || e.to >= n || e.to == root {
            continue;
        }
        let (a, b) = (map[e.from], map[e.to]);
        if a == b {
            continue;
        }
        let weight = match best[e.to] {
            Some(bk) if cycle_of[e.to] != NONE => e.weight - edges[bk].weight,
            _ => e.weight,
        };
        sub_edges.push(WeightedEdge { from: a, to: b, weight });
        sub_origin.push(k);
    }
    let sub = solve(next, map[root], &sub_edges)?;
    // 4. Expand: the edge entering a cycle replaces that node's cycle edge.
    let mut entering: Vec<Option<usize>> = vec![None; n];
    for s in sub {
        let k = sub_origin[s];
        entering[edges[k].to] = Some(k);
    }
    let mut out = Vec::with_capacity(n.saturating_sub(1));
    for v in 0..n {
        if v == root {
            continue;
        }
        match entering[v] {
            Some(k) => out.push(k),
            None if cycle_of[v] != NONE => out.push(best[v]?),
            None => return None,
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    fn e(from: usize, to: usize, weight: f64) -> WeightedEdge {
        WeightedEdge { from, to, weight }
    }

    fn total(edges: &[WeightedEdge], chosen: &[usize]) -> f64 {
        chosen.iter().map(|&k| edges[k].weight).sum()
    }

    /// Exhaustive optimum: every choice of one incoming edge per non-root node that forms a tree.
    fn brute_force(n: usize, root: usize, edges: &[WeightedEdge]) -> Option<f64> {
        let incoming: Vec<Vec<usize>> =
            (0..n).map(|v| (0..edges.len()).filter(|&k| edges[k].to == v && edges[k].from != v).collect()).collect();
        let nodes: Vec<usize> = (0..n).filter(|&v| v != root).collect();
        let mut best: Option<f64> = None;
        let mut idx = vec![0usize; nodes.len()];
        if nodes.iter().any(|&v| incoming[v].is_empty()) {
            return None;
        }
        loop {
            let mut parent = vec![usize::MAX; n];
            let mut w = 0.0;
            for (i, &v) in nodes.iter().enumerate() {
                let k = incoming[v][idx[i]];
                parent[v] = edges[k].from;
                w += edges[k].weight;
            }
            let acyclic = nodes.iter().all(|&v| {
                let mut x = v;
                for _ in 0..=n {
                    if x == root {
                        return true;
                    }
                    x = parent[x];
                }
                false
            });
            if acyclic && best.is_none_or(|b| w > b) {
                best = Some(w);
            }
            // Next combination.
            let mut i = 0;
            loop {
                if i == nodes.len() {
                    return best;
                }
                idx[i] += 1;
                if idx[i] < incoming[nodes[i]].len() {
                    break;
                }
                idx[i] = 0;
                i += 1;
            }
        }
    }

    #[test]
    fn picks_the_known_optimum_through_a_cycle() {
        // Classic example: the greedy choice 1→2, 2→1 forms a cycle that must be broken.
        let edges = [e(0, 1, 1.0), e(0, 2, 1.0), e(1, 2, 10.0), e(2, 1, 9.0), e(2, 3, 5.0), e(1, 3, 1.0)];
        let chosen = max_arborescence(4, 0, &edges).expect("spanning");
        assert!((total(&edges, &chosen) - 16.0).abs() < 1e-9); // 0→1, 1→2, 2→3
        let parents: Vec<usize> = chosen.iter().map(|&k| edges[k].from).collect();
        assert_eq!(parents, vec![0, 1, 2]);
    }

    #[test]
    fn unreachable_node_gives_none() {
        let edges = [e(0, 1, 1.0), e(2, 1, 1.0)];
        assert!(max_arborescence(3, 0, &edges).is_none());
    }

    #[test]
    fn ties_break_by_edge_order() {
        let edges = [e(0, 1, 1.0), e(0, 2, 1.0), e(1, 2, 1.0)];
        let chosen = max_arborescence(3, 0, &edges).expect("spanning");
        assert_eq!(chosen, vec![0, 1]);
        let swapped = [e(0, 1, 1.0), e(1, 2, 1.0), e(0, 2, 1.0)];
        assert_eq!(max_arborescence(3, 0, &swapped).expect("spanning"), vec![0, 1]);
    }

    #[test]
    fn matches_brute_force_on_random_graphs() {
        let mut rng = crate::math::rng(7);
        for trial in 0..300 {
            let n = rng.random_range(2..=6);
            let mut edges = Vec::new();
            for a in 0..n {
                for b in 1..n {
                    if a != b && rng.random_bool(0.6) {
                        // Coarse weights make ties and nested cycles common.
                        edges.push(e(a, b, f64::from(rng.random_range(0..5_u8))));
                    }
                }
            }
            let got = max_arborescence(n, 0, &edges);
            let want = brute_force(n, 0, &edges);
            match (got, want) {
                (Some(c), Some(w)) => {
                    assert!((total(&edges, &c) - w).abs() < 1e-9, "trial {trial}: {} vs {w}", total(&edges, &c));
                    // One edge per non-root node, forming a tree.
                    assert_eq!(c.len(), n - 1);
                }
                (None, None) => {}
                (g, w) => panic!("trial {trial}: got {g:?}, brute force {w:?}"),
            }
        }
    }
}
