//! Triangle meshes of primitive surfaces, in the primitive's own frame, for exporters (glTF) and
//! anything else in the core that needs a primitive as triangles. The GUI's unit meshes
//! (`render::mesh`, feature `gui`) are scaled per instance on the GPU; these are built at the
//! primitive's real size (a capsule does not scale) and need no GUI crate.

use super::{Primitive, PrimitiveKind};
use crate::math::Vec3;

/// A triangle mesh with per-vertex unit normals; triangles wind counter-clockwise seen from
/// outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrimitiveMesh {
    /// Vertex positions, primitive frame, metres.
    pub positions: Vec<Vec3>,
    /// Outward unit normals, one per vertex.
    pub normals: Vec<Vec3>,
    /// Vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

impl Primitive {
    /// The surface as triangles in the primitive's own frame. Round kinds use `segments` around
    /// the axis, rounded up to a multiple of 4 (at least 8), so the mesh reaches the primitive's
    /// extent along each of its axes exactly and the mesh bounds equal the primitive's.
    #[must_use]
    pub fn local_mesh(&self, segments: usize) -> PrimitiveMesh {
        let segments = segments.max(8).div_ceil(4) * 4;
        let h = self.size * 0.5;
        match self.kind {
            PrimitiveKind::Cuboid => box_mesh(h),
            PrimitiveKind::Cylinder => {
                let profile = [
                    (0.0, -h.z, 0.0, -1.0),
                    (h.x, -h.z, 0.0, -1.0),
                    (h.x, -h.z, 1.0, 0.0),
                    (h.x, h.z, 1.0, 0.0),
                    (h.x, h.z, 0.0, 1.0),
                    (0.0, h.z, 0.0, 1.0),
                ];
                lathe(&profile, segments)
            }
            PrimitiveKind::Sphere => lathe(&round_profile(h.x, 0.0, segments / 2), segments),
            PrimitiveKind::Capsule => lathe(&round_profile(h.x, 2.0 * (h.z - h.x).max(0.0), segments / 2), segments),
        }
    }
}

/// Profile (radius, z, normal radial, normal z) from the south pole to the north pole of a sphere
/// of radius `r` split at the equator and pulled apart by `straight` (a capsule; 0 = a sphere).
fn round_profile(r: f32, straight: f32, rings: usize) -> Vec<(f32, f32, f32, f32)> {
    let rings = rings.max(2) & !1;
    let mut out = Vec::with_capacity(rings + 2);
    for i in 0..=rings {
        let polar = std::f32::consts::PI * i as f32 / rings as f32;
        let (nr, nz) = (polar.sin(), -polar.cos());
        // Exact zeros at the poles and the equator keep the bounds exact.
        let nr = if i == 0 || i == rings {
            0.0
        } else if 2 * i == rings {
            1.0
        } else {
            nr
        };
        let nz = if 2 * i == rings { 0.0 } else { nz };
        let shift = if 2 * i < rings { -0.5 * straight } else { 0.5 * straight };
        if 2 * i == rings && straight > 0.0 {
            out.push((r, -0.5 * straight, 1.0, 0.0));
        }
        out.push((r * nr, shift + r * nz, nr, nz));
    }
    out
}

/// Revolves a profile (radius, z, normal radial, normal z), listed from bottom to top, about z.
/// Consecutive profile points at the same place (hard edges) start a new strip.
fn lathe(profile: &[(f32, f32, f32, f32)], segments: usize) -> PrimitiveMesh {
    let mut mesh = PrimitiveMesh::default();
    let ring = segments + 1;
    for &(r, z, nr, nz) in profile {
        for j in 0..ring {
            let (s, c) = exact_sin_cos(j, segments);
            mesh.positions.push(Vec3::new(r * c, r * s, z));
            mesh.normals.push(Vec3::new(nr * c, nr * s, nz).normalize_or(Vec3::Z));
        }
    }
    for (i, pair) in profile.windows(2).enumerate() {
        let ((r0, z0, ..), (r1, z1, ..)) = (pair[0], pair[1]);
        if (r0 - r1).abs() < 1e-9 && (z0 - z1).abs() < 1e-9 {
            continue;
        }
        for j in 0..segments {
            let idx = |row: usize, col: usize| u32::try_from(row * ring + col).unwrap_or(u32::MAX);
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j));
            if r0 > 0.0 {
                mesh.triangles.push([a, b, c]);
            }
            if r1 > 0.0 {
                mesh.triangles.push([a, c, d]);
            }
        }
    }
    mesh
}

/// sin and cos of 2πj/n with exact 0 and ±1 at the quarter turns (n is a multiple of 4).
fn exact_sin_cos(j: usize, n: usize) -> (f32, f32) {
    let j = j % n;
    if (j * 4).is_multiple_of(n) {
        return match j * 4 / n {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        };
    }
    (std::f32::consts::TAU * j as f32 / n as f32).sin_cos()
}

fn box_mesh(h: Vec3) -> PrimitiveMesh {
    let mut mesh = PrimitiveMesh::default();
    for axis in 0..3 {
        for sign in [1.0_f32, -1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u);
            let base = u32::try_from(mesh.positions.len()).unwrap_or(u32::MAX);
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push((n + u * su + v * sv) * h);
                mesh.normals.push(n);
            }
            mesh.triangles.push([base, base + 1, base + 2]);
            mesh.triangles.push([base, base + 2, base + 3]);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Pose, Quat};

    fn bounds(m: &PrimitiveMesh) -> (Vec3, Vec3) {
        m.positions.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
    }

    #[test]
    fn meshes_are_closed_outward_and_reach_the_primitive_extent() {
        let pose = Pose::from_parts(Vec3::ZERO, Quat::IDENTITY);
        for kind in PrimitiveKind::ALL {
            let prim = Primitive::new(kind, Vec3::new(0.3, 0.3, 0.8), pose);
            let mesh = prim.local_mesh(30);
            let (lo, hi) = bounds(&mesh);
            assert!((hi - prim.size * 0.5).abs().max_element() < 1e-6, "{kind:?} max {hi}");
            assert!((lo + prim.size * 0.5).abs().max_element() < 1e-6, "{kind:?} min {lo}");
            // Enclosed volume by the divergence theorem: positive (outward winding), close to the primitive's.
            let volume: f32 = mesh
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            let rel = (volume - prim.volume()).abs() / prim.volume();
            assert!(volume > 0.0 && rel < 0.02, "{kind:?}: mesh volume {volume}, primitive {}", prim.volume());
            // Normals point away from the centre line and have unit length.
            for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
                assert!((n.length() - 1.0).abs() < 1e-5);
                assert!(n.dot(*p) > -1e-6, "{kind:?}: inward normal {n} at {p}");
            }
            assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < mesh.positions.len()));
        }
    }
}
