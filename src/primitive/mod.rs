//! Primitive shapes that replace scanned parts: their geometry in one place (closest points,
//! containment, surface samples, volume, inertia, ray casts). One file per kind.
//!
//! Every primitive lives in its own frame (`world_from_primitive`) and is centred there; `size`
//! holds full extents along the primitive's own x, y, z. Cylinders and capsules have their axis
//! on z: a cylinder's size is `[d, d, h]`, a capsule's `[d, d, h]` with `h` the total length
//! including both caps, a sphere's `[d, d, d]`.

mod capsule;
mod cuboid;
mod cylinder;
mod mesh;
mod sphere;

pub use mesh::PrimitiveMesh;

use serde::{Deserialize, Serialize};

use crate::math::{Pose, Quat, Vec3};

/// The kinds of primitive the fitter can choose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrimitiveKind {
    Cuboid,
    Cylinder,
    Sphere,
    /// A cylinder with hemispherical caps; axis z, size `[d, d, total length]`.
    Capsule,
}

impl PrimitiveKind {
    pub const ALL: [PrimitiveKind; 4] = [PrimitiveKind::Cuboid, PrimitiveKind::Cylinder, PrimitiveKind::Sphere, PrimitiveKind::Capsule];

    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            PrimitiveKind::Cuboid => "cuboid",
            PrimitiveKind::Cylinder => "cylinder",
            PrimitiveKind::Sphere => "sphere",
            PrimitiveKind::Capsule => "capsule",
        }
    }

    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Makes `size` consistent with the kind (round cross-sections, spheres, caps that fit).
    #[must_use]
    pub fn normalize_size(self, size: Vec3) -> Vec3 {
        let size = size.max(Vec3::splat(1e-4));
        match self {
            PrimitiveKind::Cuboid => size,
            PrimitiveKind::Cylinder => {
                let d = 0.5 * (size.x + size.y);
                Vec3::new(d, d, size.z)
            }
            PrimitiveKind::Sphere => Vec3::splat((size.x + size.y + size.z) / 3.0),
            PrimitiveKind::Capsule => {
                let d = 0.5 * (size.x + size.y);
                Vec3::new(d, d, size.z.max(d))
            }
        }
    }
}

/// A primitive placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Primitive {
    pub kind: PrimitiveKind,
    /// Full extents along the primitive's own axes, metres.
    pub size: Vec3,
    pub world_from_primitive: Pose,
}

impl Primitive {
    #[must_use]
    pub fn new(kind: PrimitiveKind, size: Vec3, world_from_primitive: Pose) -> Self {
        Self { kind, size: kind.normalize_size(size), world_from_primitive }
    }

    /// An axis-aligned cuboid from its centre and full size (handy for generators and tests).
    #[must_use]
    pub fn cuboid_at(center: Vec3, size: Vec3) -> Self {
        Self::new(PrimitiveKind::Cuboid, size, Pose::from_translation(center))
    }

    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.world_from_primitive.translation
    }

    #[must_use]
    pub fn rotation(&self) -> Quat {
        self.world_from_primitive.rotation
    }

    /// The primitive's own axes in world coordinates (columns x, y, z).
    #[must_use]
    pub fn axes_world(&self) -> [Vec3; 3] {
        let r = self.rotation();
        [r * Vec3::X, r * Vec3::Y, r * Vec3::Z]
    }

    /// Unsigned distance from a world point to the primitive's surface.
    #[must_use]
    pub fn surface_distance(&self, world_point: Vec3) -> f32 {
        let p = self.world_from_primitive.inverse_transform_point(world_point);
        (self.closest_surface_point_local(p) - p).length()
    }

    /// Mean distance from points to the surface, over a stride subsample of at most `max_points`.
    #[must_use]
    pub fn mean_surface_distance(&self, points: &[Vec3], max_points: usize) -> f32 {
        let step = (points.len() / max_points.max(1)).max(1);
        let (sum, n) = points.iter().step_by(step).fold((0.0_f32, 0usize), |(s, n), p| (s + self.surface_distance(*p), n + 1));
        sum / n.max(1) as f32
    }

    /// Closest surface point, in the primitive's frame.
    #[must_use]
    pub fn closest_surface_point_local(&self, p: Vec3) -> Vec3 {
        let h = self.size * 0.5;
        match self.kind {
            PrimitiveKind::Cuboid => cuboid::closest_surface_point(h, p),
            PrimitiveKind::Cylinder => cylinder::closest_surface_point(h.x, h.z, p),
            PrimitiveKind::Sphere => sphere::closest_surface_point(h.x, p),
            PrimitiveKind::Capsule => capsule::closest_surface_point(h.x, (h.z - h.x).max(0.0), p),
        }
    }

    /// Closest surface point in world coordinates.
    #[must_use]
    pub fn closest_surface_point(&self, world_point: Vec3) -> Vec3 {
        let p = self.world_from_primitive.inverse_transform_point(world_point);
        self.world_from_primitive.transform_point(self.closest_surface_point_local(p))
    }

    /// Whether a world point is inside the solid primitive.
    #[must_use]
    pub fn contains(&self, world_point: Vec3) -> bool {
        let p = self.world_from_primitive.inverse_transform_point(world_point);
        let h = self.size * 0.5;
        match self.kind {
            PrimitiveKind::Cuboid => cuboid::contains(h, p),
            PrimitiveKind::Cylinder => cylinder::contains(h.x, h.z, p),
            PrimitiveKind::Sphere => sphere::contains(h.x, p),
            PrimitiveKind::Capsule => capsule::contains(h.x, (h.z - h.x).max(0.0), p),
        }
    }

    /// About `n` evenly spread surface points in world coordinates; deterministic
    /// (low-discrepancy sequences, no randomness), area-uniform.
    #[must_use]
    pub fn sample_surface(&self, n: usize) -> Vec<Vec3> {
        let mut local = self.sample_surface_local(n);
        for p in &mut local {
            *p = self.world_from_primitive.transform_point(*p);
        }
        local
    }

    /// Surface samples in the primitive's frame.
    #[must_use]
    pub fn sample_surface_local(&self, n: usize) -> Vec<Vec3> {
        let h = self.size * 0.5;
        // Callers size n from areas and densities; a huge (fuzzed) part must not turn into an
        // allocation of that size.
        let n = n.clamp(1, MAX_SURFACE_SAMPLES);
        match self.kind {
            PrimitiveKind::Cuboid => cuboid::sample_surface(h, n),
            PrimitiveKind::Cylinder => cylinder::sample_surface(h.x, h.z, n),
            PrimitiveKind::Sphere => sphere::sample_surface(h.x, n),
            PrimitiveKind::Capsule => capsule::sample_surface(h.x, (h.z - h.x).max(0.0), n),
        }
    }

    #[must_use]
    pub fn volume(&self) -> f32 {
        let h = self.size * 0.5;
        match self.kind {
            PrimitiveKind::Cuboid => self.size.x * self.size.y * self.size.z,
            PrimitiveKind::Cylinder => std::f32::consts::PI * h.x * h.x * self.size.z,
            PrimitiveKind::Sphere => 4.0 / 3.0 * std::f32::consts::PI * h.x.powi(3),
            PrimitiveKind::Capsule => capsule::volume(h.x, (h.z - h.x).max(0.0)),
        }
    }

    #[must_use]
    pub fn surface_area(&self) -> f32 {
        let h = self.size * 0.5;
        match self.kind {
            PrimitiveKind::Cuboid => cuboid::area(h),
            PrimitiveKind::Cylinder => cylinder::area(h.x, h.z),
            PrimitiveKind::Sphere => sphere::area(h.x),
            PrimitiveKind::Capsule => capsule::area(h.x, (h.z - h.x).max(0.0)),
        }
    }

    /// Principal moments of inertia about the centre, in the primitive's frame, for a mass in kg.
    #[must_use]
    pub fn principal_inertia(&self, mass_kg: f32) -> Vec3 {
        let h = self.size * 0.5;
        match self.kind {
            PrimitiveKind::Cuboid => cuboid::inertia(self.size, mass_kg),
            PrimitiveKind::Cylinder | PrimitiveKind::Capsule => cylinder::inertia(h.x, self.size.z, mass_kg),
            PrimitiveKind::Sphere => Vec3::splat(0.4 * mass_kg * h.x * h.x),
        }
    }

    /// First hit of a world ray (origin, unit direction) within `max_dist`: (distance, outward normal).
    /// Cylinders in closed form (see `cylinder::ray_cast`), the other kinds through parry3d.
    #[must_use]
    pub fn ray_cast(&self, origin: Vec3, dir: Vec3, max_dist: f32) -> Option<(f32, Vec3)> {
        use parry3d::query::{Ray, RayCast};
        let o = self.world_from_primitive.inverse_transform_point(origin);
        let d = self.world_from_primitive.inverse_transform_vector(dir);
        let h = self.size * 0.5;
        // parry's cylinders and capsules have their axis on y; ours is z: swap y and z.
        let swap = |v: Vec3| Vec3::new(v.x, v.z, v.y);
        let hit = match self.kind {
            PrimitiveKind::Cuboid => parry3d::shape::Cuboid::new(h)
                .cast_local_ray_and_get_normal(&Ray::new(o, d), max_dist, false)
                .map(|i| (i.time_of_impact, i.normal)),
            PrimitiveKind::Sphere => parry3d::shape::Ball::new(h.x)
                .cast_local_ray_and_get_normal(&Ray::new(o, d), max_dist, false)
                .map(|i| (i.time_of_impact, i.normal)),
            PrimitiveKind::Cylinder => cylinder::ray_cast(h.x, h.z, o, d, max_dist),
            PrimitiveKind::Capsule => parry3d::shape::Capsule::new_y((h.z - h.x).max(0.0), h.x)
                .cast_local_ray_and_get_normal(&Ray::new(swap(o), swap(d)), max_dist, false)
                .map(|i| (i.time_of_impact, swap(i.normal))),
        };
        hit.map(|(t, n)| (t, self.world_from_primitive.transform_vector(n)))
    }

    /// World-space axis-aligned bounds (min, max).
    #[must_use]
    pub fn aabb(&self) -> (Vec3, Vec3) {
        let r = glam::Mat3::from_quat(self.rotation());
        let h = self.size * 0.5;
        let ext = r.x_axis.abs() * h.x + r.y_axis.abs() * h.y + r.z_axis.abs() * h.z;
        (self.center() - ext, self.center() + ext)
    }

    /// Width of the primitive's box along a world direction `dir` (unit), metres.
    #[must_use]
    pub fn extent_along(&self, dir: Vec3) -> f32 {
        let axes = self.axes_world();
        (0..3).map(|k| axes[k].dot(dir).abs() * self.size[k]).sum()
    }

    /// The 8 corners of the primitive's bounding box, world frame.
    #[must_use]
    pub fn box_corners(&self) -> [Vec3; 8] {
        let h = self.size * 0.5;
        let mut out = [Vec3::ZERO; 8];
        for (i, c) in out.iter_mut().enumerate() {
            let s =
                Vec3::new(if i & 1 == 0 { -1.0 } else { 1.0 }, if i & 2 == 0 { -1.0 } else { 1.0 }, if i & 4 == 0 { -1.0 } else { 1.0 });
            *c = self.world_from_primitive.transform_point(s * h);
        }
        out
    }
}

/// A 2D low-discrepancy sequence (Roberts' R2) in [0,1)²: deterministic, evenly spread.
pub(crate) fn r2(i: usize) -> (f32, f32) {
    const G: f64 = 1.324_717_957_244_746;
    let a1 = 1.0 / G;
    let a2 = 1.0 / (G * G);
    let i = i as f64 + 0.5;
    ((i * a1).fract() as f32, (i * a2).fract() as f32)
}

/// Most surface samples one primitive is ever asked for (a metre-scale part at millimetre
/// spacing needs about 10⁶).
pub const MAX_SURFACE_SAMPLES: usize = 4_000_000;

/// Splits `n` samples over areas proportionally (at least one each where the area is positive).
/// The counts add up to at most `n + areas.len()` whatever the areas (huge, overflowing to
/// infinity, NaN): a share that is not a finite number in [0, 1] gets one sample, so no size can
/// turn into an allocation.
pub(crate) fn split_counts(n: usize, areas: &[f32]) -> Vec<usize> {
    let total: f64 = areas.iter().map(|a| f64::from(*a)).sum();
    areas
        .iter()
        .map(|a| {
            let share = f64::from(*a) / total;
            if *a <= 0.0 || total <= 0.0 || a.is_nan() {
                0
            } else if share.is_finite() {
                ((n as f64 * share.clamp(0.0, 1.0)).round() as usize).max(1)
            } else {
                1
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prim(kind: PrimitiveKind, size: Vec3) -> Primitive {
        let pose = Pose::from_parts(Vec3::new(1.0, -2.0, 0.5), Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.2, 1.0));
        Primitive::new(kind, size, pose)
    }

    /// A 4.8 KB PLY with coordinates near 1e37 made `split_counts` ask for `usize::MAX` samples
    /// (n · area overflowed to infinity) and the reconstruction abort after allocating 13 GB.
    #[test]
    fn huge_primitives_get_a_bounded_number_of_samples() {
        for kind in PrimitiveKind::ALL {
            for size in [Vec3::new(3e37, 2e37, 1e37), Vec3::new(f32::MAX, 1.0, f32::MAX), Vec3::new(1e-30, 1e30, 1e-30)] {
                let p = prim(kind, size);
                let samples = p.sample_surface(500);
                assert!(samples.len() <= 510, "{kind:?} {size}: {} samples", samples.len());
            }
        }
    }

    #[test]
    fn surface_samples_lie_on_the_surface() {
        for kind in PrimitiveKind::ALL {
            let p = prim(kind, Vec3::new(0.4, 0.4, 0.9));
            let samples = p.sample_surface(500);
            assert!(samples.len() >= 400, "{kind:?}: {}", samples.len());
            for s in samples {
                assert!(p.surface_distance(s) < 1e-4, "{kind:?} sample {s} off surface");
            }
        }
    }

    #[test]
    fn ray_cast_hits_the_near_face() {
        for kind in PrimitiveKind::ALL {
            let size = if kind == PrimitiveKind::Sphere { Vec3::splat(0.4) } else { Vec3::new(0.4, 0.4, 0.8) };
            let p = Primitive::new(kind, size, Pose::from_translation(Vec3::ZERO));
            let (t, n) = p.ray_cast(Vec3::new(0.0, -5.0, 0.0), Vec3::Y, 100.0).expect("hit");
            assert!((t - 4.8).abs() < 1e-4, "{kind:?}: t = {t}");
            assert!(n.dot(-Vec3::Y) > 0.99, "{kind:?}: n = {n}");
            // Along the axis: the cap of a cylinder at z = 0.4, of a capsule at 0.4 as well.
            let (t, _) = p.ray_cast(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, 100.0).expect("hit");
            let want = if kind == PrimitiveKind::Sphere { 4.8 } else { 4.6 };
            assert!((t - want).abs() < 1e-4, "{kind:?}: t = {t}");
        }
    }

    #[test]
    fn containment_and_volume_agree() {
        // Monte-Carlo-free check: count grid cells inside and compare with the volume.
        for kind in PrimitiveKind::ALL {
            let p = prim(kind, Vec3::new(0.3, 0.3, 0.6));
            let (lo, hi) = p.aabb();
            let n = 60;
            let step = (hi - lo) / n as f32;
            let mut inside = 0usize;
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        let q = lo + step * Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5);
                        if p.contains(q) {
                            inside += 1;
                        }
                    }
                }
            }
            let vol = inside as f32 * step.x * step.y * step.z;
            assert!((vol / p.volume() - 1.0).abs() < 0.03, "{kind:?}: {vol} vs {}", p.volume());
        }
    }

    #[test]
    fn closest_point_of_interior_point_is_on_nearest_face() {
        let p = Primitive::cuboid_at(Vec3::ZERO, Vec3::new(2.0, 1.0, 4.0));
        let c = p.closest_surface_point(Vec3::new(0.1, 0.3, 0.0));
        assert!((c - Vec3::new(0.1, 0.5, 0.0)).length() < 1e-6);
    }
    #[test]
    fn exact_cylinder_hits_lie_on_the_surface() {
        use crate::math::{Pose, Quat};
        let pose = Pose::from_parts(Vec3::new(0.3, -0.2, 1.0), Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.3, 0.8));
        let cyl = Primitive::new(PrimitiveKind::Cylinder, Vec3::new(0.04, 0.04, 0.02), pose);
        let mut hits = 0;
        for k in 0..400 {
            let a = k as f32 * 0.61;
            let origin = cyl.center() + Vec3::new(a.cos() * 2.0, a.sin() * 2.0, (a * 0.3).sin() * 1.5);
            let aim = cyl.center() + Vec3::new((a * 3.1).sin(), (a * 2.3).cos(), (a * 1.3).sin()) * 0.02;
            let dir = (aim - origin).normalize();
            if let Some((t, n)) = cyl.ray_cast(origin, dir, 10.0) {
                hits += 1;
                let q = origin + dir * t;
                assert!(cyl.surface_distance(q) < 1e-5, "hit {q} off the surface by {}, t {t}, n {n}", cyl.surface_distance(q));
                assert!(n.dot(dir) < 0.0);
                // The first hit: nothing of the cylinder lies on the ray before it.
                assert!((0..400).all(|k| !cyl.contains(origin + dir * (t * k as f32 / 400.0 - 1e-4))));
            } else {
                assert!((0..4000).all(|k| !cyl.contains(origin + dir * (k as f32 * 0.001))), "missed ray {k}");
            }
        }
        assert!(hits > 150, "{hits} hits");
    }
}

/// The JSON form of a primitive, as `scene.json` spells it.
#[derive(Serialize, Deserialize)]
struct PrimitiveJson {
    kind: PrimitiveKind,
    size: [f32; 3],
    world_from_primitive: PoseJson,
}

/// A pose as `scene.json` spells it.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct PoseJson {
    pub translation: [f32; 3],
    pub rotation_xyzw: [f32; 4],
}

impl From<Pose> for PoseJson {
    fn from(p: Pose) -> Self {
        Self { translation: p.translation.to_array(), rotation_xyzw: p.rotation.to_array() }
    }
}

impl From<PoseJson> for Pose {
    fn from(p: PoseJson) -> Self {
        let q = Quat::from_array(p.rotation_xyzw);
        let q = if q.length_squared() > 1e-12 { q.normalize() } else { Quat::IDENTITY };
        Pose::from_parts(Vec3::from_array(p.translation), q)
    }
}

impl Serialize for Primitive {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        PrimitiveJson { kind: self.kind, size: self.size.to_array(), world_from_primitive: self.world_from_primitive.into() }.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Primitive {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let j = PrimitiveJson::deserialize(d)?;
        Ok(Primitive::new(j.kind, Vec3::from_array(j.size), j.world_from_primitive.into()))
    }
}
