//! Triangle meshes in the geometric metrics: deterministic area-weighted surface samples (Chamfer)
//! and voxel occupancy (`IoU`). A closed mesh (every edge shared by exactly two triangles once
//! coincident vertices are welded) fills the voxels whose centres it encloses, by ray parity along
//! vertical columns; an open mesh has no inside, so it occupies only the voxels its surface passes
//! through (surface-voxel occupancy).

use std::collections::HashMap;

use crate::math::Vec3;
use crate::truth::TruthMesh;

/// Area of a triangle, square metres.
pub(crate) fn triangle_area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Total surface area of a mesh, square metres.
pub(crate) fn mesh_area(mesh: &TruthMesh) -> f32 {
    mesh.triangle_vertices().map(|t| triangle_area(&t)).filter(|a| a.is_finite()).sum()
}

/// R2 low-discrepancy sequence constants (1/φ₂ and 1/φ₂², φ₂ the plastic number).
const A1: f64 = 0.754_877_666_246_692_7;
const A2: f64 = 0.569_840_290_998_053_3;

/// About `n` surface samples spread by area: triangle `i` gets the samples whose systematic
/// positions `(k + 0.5) / n` of the cumulative area fall on it, placed on a low-discrepancy (R2)
/// sequence folded into the triangle. Deterministic.
pub(crate) fn sample_mesh(mesh: &TruthMesh, n: usize) -> Vec<Vec3> {
    let triangles: Vec<([Vec3; 3], f64)> =
        mesh.triangle_vertices().map(|t| (t, f64::from(triangle_area(&t)))).filter(|(_, a)| a.is_finite() && *a > 0.0).collect();
    let total: f64 = triangles.iter().map(|(_, a)| a).sum();
    if n == 0 || total <= 0.0 {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(n);
    let mut cumulative = 0.0_f64;
    let mut next = 0_usize;
    for (t, area) in &triangles {
        cumulative += area;
        let end = ((cumulative / total) * n as f64 - 0.5).floor() as i64 + 1;
        let end = (end.max(0) as usize).min(n);
        for k in next..end {
            let (mut u, mut v) = ((0.5 + A1 * k as f64).fract(), (0.5 + A2 * k as f64).fract());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            out.push(t[0] + (t[1] - t[0]) * u as f32 + (t[2] - t[0]) * v as f32);
        }
        next = next.max(end);
    }
    out
}

/// Whether every edge of the mesh is shared by exactly two triangles, after welding vertices that
/// coincide to within 1e-5 m (mesh files split vertices at texture seams).
pub(crate) fn is_closed(mesh: &TruthMesh) -> bool {
    let key = |v: Vec3| -> [i64; 3] { [v.x, v.y, v.z].map(|c| (f64::from(c) * 1e5).round() as i64) };
    let mut edges: HashMap<([i64; 3], [i64; 3]), u32> = HashMap::new();
    let mut any = false;
    for t in mesh.triangle_vertices() {
        let k = t.map(key);
        if k[0] == k[1] || k[1] == k[2] || k[0] == k[2] {
            continue; // degenerate: no area, no edges
        }
        any = true;
        for (a, b) in [(k[0], k[1]), (k[1], k[2]), (k[2], k[0])] {
            *edges.entry(if a < b { (a, b) } else { (b, a) }).or_default() += 1;
        }
    }
    any && edges.values().all(|&c| c == 2)
}

/// A voxel lattice in world coordinates: voxel `(i, j, k)` (lattice-relative, from 0) has its
/// centre at `origin_world + (i + 0.5, j + 0.5, k + 0.5) · pitch_m`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WorldLattice {
    pub origin_world: Vec3,
    pub pitch_m: f32,
    pub dims: [usize; 3],
}

impl WorldLattice {
    pub(crate) fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (i * self.dims[1] + j) * self.dims[2] + k
    }

    /// The voxel holding a world point, if the lattice has one there.
    fn voxel_of(&self, p: Vec3) -> Option<usize> {
        let c = (p - self.origin_world) / self.pitch_m;
        let ok = (0..3).all(|a| c[a] >= 0.0 && (c[a] as usize) < self.dims[a]);
        ok.then(|| self.index(c.x as usize, c.y as usize, c.z as usize))
    }

    /// Lattice column range whose centres lie within `[lo, hi]` along `axis` (may be empty).
    fn centre_range(&self, axis: usize, lo: f32, hi: f32) -> std::ops::Range<usize> {
        let to = |w: f32| (w - self.origin_world[axis]) / self.pitch_m - 0.5;
        let a = to(lo).ceil().max(0.0) as usize;
        let b = (to(hi).floor() + 1.0).clamp(0.0, self.dims[axis] as f32) as usize;
        a..b.max(a)
    }
}

/// Marks the voxels a mesh occupies: inside by vertical ray parity when the mesh is closed, else
/// the voxels its surface passes through. Returns whether the mesh was treated as closed.
pub(crate) fn rasterise_mesh(mesh: &TruthMesh, lattice: &WorldLattice, grid: &mut [bool]) -> bool {
    if is_closed(mesh) {
        fill_by_parity(mesh, lattice, grid);
        true
    } else {
        mark_surface(mesh, lattice, grid);
        false
    }
}

/// Ray parity along +z through every column centre: a voxel centre is inside when an odd number
/// of crossings lies below it.
fn fill_by_parity(mesh: &TruthMesh, lattice: &WorldLattice, grid: &mut [bool]) {
    let [nx, ny, nz] = lattice.dims;
    let mut columns: HashMap<(usize, usize), Vec<f32>> = HashMap::new();
    for t in mesh.triangle_vertices() {
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        let (a, b, c) = (t[0], t[1], t[2]);
        let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if det.abs() < 1e-14 {
            continue; // vertical or degenerate: a vertical ray does not cross it
        }
        for i in lattice.centre_range(0, lo.x, hi.x) {
            let x = lattice.origin_world.x + (i as f32 + 0.5) * lattice.pitch_m;
            for j in lattice.centre_range(1, lo.y, hi.y) {
                let y = lattice.origin_world.y + (j as f32 + 0.5) * lattice.pitch_m;
                let u = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
                let v = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
                    columns.entry((i, j)).or_default().push(a.z + u * (b.z - a.z) + v * (c.z - a.z));
                }
            }
        }
    }
    for ((i, j), mut zs) in columns {
        if i >= nx || j >= ny {
            continue;
        }
        zs.sort_by(f32::total_cmp);
        // A ray through a shared edge or vertex meets each adjacent triangle at the same height.
        zs.dedup_by(|x, y| (*x - *y).abs() < 1e-6);
        let mut below = 0_usize;
        for k in 0..nz {
            let z = lattice.origin_world.z + (k as f32 + 0.5) * lattice.pitch_m;
            while below < zs.len() && zs[below] < z {
                below += 1;
            }
            if below % 2 == 1 {
                grid[lattice.index(i, j, k)] = true;
            }
        }
    }
}

/// Marks every voxel a dense surface sampling (spacing about a quarter voxel) falls in.
fn mark_surface(mesh: &TruthMesh, lattice: &WorldLattice, grid: &mut [bool]) {
    let spacing = 0.25 * lattice.pitch_m;
    let n = ((mesh_area(mesh) / (spacing * spacing)).ceil() as usize).clamp(1, 4_000_000);
    for p in sample_mesh(mesh, n) {
        if let Some(idx) = lattice.voxel_of(p) {
            grid[idx] = true;
        }
    }
    // Vertices too, so thin slivers are not missed.
    for p in mesh.triangles.iter().flatten().filter_map(|&i| mesh.vertices.get(i as usize)) {
        if let Some(idx) = lattice.voxel_of(*p) {
            grid[idx] = true;
        }
    }
}

/// A closed axis-aligned box as a mesh (12 triangles, outward winding), for tests and callers
/// that need a mesh stand-in for a box.
#[must_use]
pub fn box_mesh(lo: Vec3, hi: Vec3) -> TruthMesh {
    let v = |x: bool, y: bool, z: bool| Vec3::new(if x { hi.x } else { lo.x }, if y { hi.y } else { lo.y }, if z { hi.z } else { lo.z });
    let vertices = vec![
        v(false, false, false),
        v(true, false, false),
        v(true, true, false),
        v(false, true, false),
        v(false, false, true),
        v(true, false, true),
        v(true, true, true),
        v(false, true, true),
    ];
    let triangles = vec![
        [0, 2, 1],
        [0, 3, 2],
        [4, 5, 6],
        [4, 6, 7],
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    TruthMesh { vertices, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_mesh_is_closed_and_an_open_one_is_not() {
        let m = box_mesh(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        assert!(is_closed(&m));
        assert!((mesh_area(&m) - 22.0).abs() < 1e-4);
        let mut open = m.clone();
        open.triangles.pop();
        assert!(!is_closed(&open));
    }

    #[test]
    fn samples_lie_on_the_surface_spread_by_area() {
        let m = box_mesh(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let s = sample_mesh(&m, 2200);
        assert_eq!(s.len(), 2200);
        // The two 2×3 faces at x = 0 and x = 1 hold 12/22 of the area.
        let on_x = s.iter().filter(|p| p.x.abs() < 1e-5 || (p.x - 1.0).abs() < 1e-5).count();
        assert!((on_x as f32 / 2200.0 - 12.0 / 22.0).abs() < 0.01, "{on_x}");
        assert_eq!(s, sample_mesh(&m, 2200), "deterministic");
    }

    #[test]
    fn parity_fills_a_closed_box_and_surface_marks_an_open_one() {
        let lattice = WorldLattice { origin_world: Vec3::ZERO, pitch_m: 0.1, dims: [20, 20, 20] };
        let m = box_mesh(Vec3::splat(0.3), Vec3::splat(1.3));
        let mut grid = vec![false; 8000];
        assert!(rasterise_mesh(&m, &lattice, &mut grid));
        assert_eq!(grid.iter().filter(|v| **v).count(), 1000, "10³ voxel centres inside");
        let mut open = m.clone();
        open.triangles.truncate(10);
        let mut shell = vec![false; 8000];
        assert!(!rasterise_mesh(&open, &lattice, &mut shell));
        let n = shell.iter().filter(|v| **v).count();
        assert!(n > 300 && n < 1000, "{n}");
    }
}
