//! Unit meshes the primitives are drawn with (instanced): a cube of side 1, a cylinder of
//! diameter 1 and height 1 along z, a sphere of diameter 1, all centred at the origin — the same
//! conventions as [`crate::primitive`] sizes, so an instance transform is pose × scale(size).

use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MeshVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
}

/// Triangle list with 32-bit indices.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<MeshVertex>,
    pub indices: Vec<u32>,
}

impl Mesh {
    fn push(&mut self, position: [f32; 3], normal: [f32; 3]) -> u32 {
        self.vertices.push(MeshVertex { position, normal });
        (self.vertices.len() - 1) as u32
    }
}

#[must_use]
pub fn unit_cube() -> Mesh {
    let mut m = Mesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = m.vertices.len() as u32;
            for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                let mut p = [0.0; 3];
                p[axis] = 0.5 * sign;
                p[u] = a;
                p[v] = b;
                m.push(p, n);
            }
            // Counter-clockwise seen from outside.
            let quad = if sign > 0.0 { [0, 1, 2, 0, 2, 3] } else { [0, 2, 1, 0, 3, 2] };
            m.indices.extend(quad.iter().map(|i| base + i));
        }
    }
    m
}

#[must_use]
pub fn unit_cylinder(segments: u32) -> Mesh {
    let mut m = Mesh::default();
    let ring = |i: u32| {
        let a = i as f32 / segments as f32 * std::f32::consts::TAU;
        (0.5 * a.cos(), 0.5 * a.sin())
    };
    // Side.
    let base = m.vertices.len() as u32;
    for i in 0..=segments {
        let (x, y) = ring(i);
        m.push([x, y, -0.5], [2.0 * x, 2.0 * y, 0.0]);
        m.push([x, y, 0.5], [2.0 * x, 2.0 * y, 0.0]);
    }
    for i in 0..segments {
        let (a, b, c, d) = (base + 2 * i, base + 2 * i + 1, base + 2 * i + 2, base + 2 * i + 3);
        m.indices.extend([a, c, b, b, c, d]);
    }
    // Caps.
    for (z, nz) in [(-0.5f32, -1.0f32), (0.5, 1.0)] {
        let centre = m.push([0.0, 0.0, z], [0.0, 0.0, nz]);
        let first = m.vertices.len() as u32;
        for i in 0..=segments {
            let (x, y) = ring(i);
            m.push([x, y, z], [0.0, 0.0, nz]);
        }
        for i in 0..segments {
            let (a, b) = (first + i, first + i + 1);
            if nz > 0.0 {
                m.indices.extend([centre, a, b]);
            } else {
                m.indices.extend([centre, b, a]);
            }
        }
    }
    m
}

#[must_use]
pub fn unit_sphere(rings: u32, segments: u32) -> Mesh {
    let mut m = Mesh::default();
    for r in 0..=rings {
        let theta = r as f32 / rings as f32 * std::f32::consts::PI;
        for s in 0..=segments {
            let phi = s as f32 / segments as f32 * std::f32::consts::TAU;
            let n = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
            m.push([0.5 * n[0], 0.5 * n[1], 0.5 * n[2]], n);
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (r * row + s, r * row + s + 1, (r + 1) * row + s, (r + 1) * row + s + 1);
            m.indices.extend([a, c, b, b, c, d]);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed volume of a closed triangle mesh (positive when faces wind outwards).
    fn volume(m: &Mesh) -> f32 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [0, 1, 2].map(|k| glam::Vec3::from(m.vertices[t[k] as usize].position));
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn unit_meshes_wind_outwards_and_have_the_primitive_volumes() {
        assert!((volume(&unit_cube()) - 1.0).abs() < 1e-5);
        let cyl = std::f32::consts::PI * 0.25;
        assert!((volume(&unit_cylinder(64)) - cyl).abs() < 0.01 * cyl);
        let sph = std::f32::consts::PI / 6.0;
        assert!((volume(&unit_sphere(32, 64)) - sph).abs() < 0.01 * sph);
    }
}
