//! A virtual depth scanner: pinhole cameras standing in the room ray-cast the ground-truth
//! primitives plus floor and walls, and every hit becomes a labelled point, with the flaws of a
//! real part-segmented scan: depth noise growing with range, dropouts at grazing angles,
//! segmentation bleed between touching parts, a few outliers, and occlusion from the ray casting.
//! Truth parts may also carry triangle meshes (imported assets): rays hit them through parry's
//! `TriMesh` (its own BVH).

use std::collections::BTreeMap;

use parry3d::query::{PointQuery, Ray, RayCast};
use parry3d::shape::TriMesh;
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

use super::bvh::Bvh;
use crate::math::{Vec2, Vec3, rng};
use crate::primitive::Primitive;
use crate::scan::{ObjectId, PartId, Scan, ScanObject, ScanPart};
use crate::truth::{GroundTruth, TruthObject};

/// Settings of the virtual scanner.
#[derive(Clone, Debug, PartialEq)]
pub struct ScannerConfig {
    /// Viewpoints per tile of the floor (a room-sized square of `tile_size_m`).
    pub viewpoints: usize,
    /// Edge of the floor tiles that each get `viewpoints` cameras, metres.
    pub tile_size_m: f32,
    /// Image width in pixels (one ray per pixel): with `image_height`, the resolution knob.
    pub image_width: usize,
    /// Image height in pixels.
    pub image_height: usize,
    /// Horizontal field of view, degrees.
    pub horizontal_fov_deg: f32,
    /// Camera heights are drawn from this range, metres above the floor.
    pub camera_height_m: (f32, f32),
    /// Distance from a camera to the bounding circle of the object it looks at, metres.
    pub view_distance_m: (f32, f32),
    /// Cameras stand up to this far off the line from their object towards the tile centre, degrees.
    pub view_angle_jitter_deg: f32,
    /// Hits farther than this are dropped, metres.
    pub max_range_m: f32,
    /// Hits whose surface is seen more obliquely than this are dropped, degrees.
    pub max_incidence_deg: f32,
    /// Depth noise σ along the ray at 1 m range; σ grows linearly with range, metres.
    pub depth_noise_m: f32,
    /// Noise of the per-point normals, radians (σ of a tangential perturbation).
    pub normal_noise_rad: f32,
    /// Probability that a point within `stray_radius_m` of another part's surface takes that
    /// part's label (segmentation bleed).
    pub stray_fraction: f32,
    /// How near another part a point must be to bleed into it, metres.
    pub stray_radius_m: f32,
    /// Fraction of points pushed off the surface as outliers.
    pub outlier_fraction: f32,
    /// Range of the outliers' offsets from the surface, metres.
    pub outlier_offset_m: (f32, f32),
    /// Height of the walls put around the furniture, metres.
    pub wall_height_m: f32,
    /// Distance from the furniture's bounds to the walls' inner faces, metres.
    pub wall_gap_m: f32,
    /// Whether the scan carries per-point normals.
    pub normals: bool,
    /// Raise the highest camera to 0.4 m above the tallest object (a complete scan must see the
    /// top of a 2.4 m oven); off for hand-held-like partial scans.
    pub cameras_above_objects: bool,
}

impl Default for ScannerConfig {
    /// A hand-held-sensor-like partial scan: 14 viewpoints per room at 1.2–1.8 m, 208 × 156 rays
    /// each over a 60° field of view, 5 m range, 1.5 mm/m depth noise, 15 % bleed near part
    /// borders, 0.2 % outliers.
    fn default() -> Self {
        Self {
            viewpoints: 14,
            tile_size_m: 6.5,
            image_width: 208,
            image_height: 156,
            horizontal_fov_deg: 60.0,
            camera_height_m: (1.2, 1.8),
            view_distance_m: (1.0, 1.8),
            view_angle_jitter_deg: 35.0,
            max_range_m: 5.0,
            max_incidence_deg: 80.0,
            depth_noise_m: 0.0015,
            normal_noise_rad: 0.05,
            stray_fraction: 0.15,
            stray_radius_m: 0.015,
            outlier_fraction: 0.002,
            outlier_offset_m: (0.02, 0.08),
            wall_height_m: 2.6,
            wall_gap_m: 0.0,
            normals: true,
            cameras_above_objects: false,
        }
    }
}

impl ScannerConfig {
    /// Many viewpoints all around each tile at heights from knee to above head, at twice the
    /// resolution (so knobs and handles get dense samples), no noise, no bleed, no outliers: as
    /// complete a scan as cameras in the room can give (the paper's *annotation* input).
    #[must_use]
    pub fn clean_complete() -> Self {
        Self {
            viewpoints: 24,
            image_width: 320,
            image_height: 240,
            camera_height_m: (0.5, 2.3),
            view_angle_jitter_deg: 60.0,
            max_incidence_deg: 89.0,
            depth_noise_m: 0.0,
            normal_noise_rad: 0.0,
            stray_fraction: 0.0,
            outlier_fraction: 0.0,
            cameras_above_objects: true,
            ..Self::default()
        }
    }
}

/// A pinhole camera: eye and orthonormal forward / right / up.
#[derive(Clone, Copy, Debug)]
struct Camera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

impl Camera {
    fn looking_at(eye: Vec3, target: Vec3) -> Self {
        let forward = (target - eye).normalize_or(Vec3::X);
        let right = forward.cross(Vec3::Z).normalize_or(Vec3::Y);
        let up = right.cross(forward);
        Self { eye, forward, right, up }
    }
}

/// Floor bounds (min, max corner in x, y) of a scene: the bounds of every truth primitive, or a
/// 4 m square around the origin for an empty scene. The scanner puts the walls on them.
#[must_use]
pub fn room_bounds(truth: &GroundTruth) -> (Vec2, Vec2) {
    let mut lo = Vec2::splat(f32::INFINITY);
    let mut hi = Vec2::splat(f32::NEG_INFINITY);
    for (a, b) in truth.objects.iter().flat_map(|o| o.parts.iter()).filter_map(crate::truth::TruthPart::aabb) {
        lo = lo.min(a.truncate());
        hi = hi.max(b.truncate());
    }
    if lo.x > hi.x || !lo.is_finite() || !hi.is_finite() {
        return (Vec2::splat(-2.0), Vec2::splat(2.0));
    }
    (lo, hi)
}

/// Label of a scanned primitive: background (floor, walls) or a truth part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Label {
    object: ObjectId,
    part: PartId,
}

const BACKGROUND: Label = Label { object: -1, part: -1 };

/// A truth mesh the rays can hit.
struct MeshTarget {
    mesh: TriMesh,
    label: Label,
    lo: Vec3,
    hi: Vec3,
}

/// Everything the rays can hit.
struct World {
    primitives: Vec<Primitive>,
    labels: Vec<Label>,
    bvh: Bvh,
    meshes: Vec<MeshTarget>,
}

/// Slab test of a ray against a box: whether it enters within `[0, t_max]`.
fn ray_hits_box(origin: Vec3, dir: Vec3, lo: Vec3, hi: Vec3, t_max: f32) -> bool {
    let inv = dir.recip();
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    t0.min(t1).max_element().max(0.0) <= t0.max(t1).min_element().min(t_max)
}

impl World {
    /// Closest hit within `max_dist`: (label, distance, surface normal).
    fn ray_cast(&self, origin: Vec3, dir: Vec3, max_dist: f32) -> Option<(Label, f32, Vec3)> {
        let mut best = self.bvh.ray_cast(&self.primitives, origin, dir, max_dist).map(|(i, t, n)| (self.labels[i], t, n));
        let ray = Ray::new(origin, dir);
        for m in &self.meshes {
            let t_max = best.map_or(max_dist, |b| b.1);
            if !ray_hits_box(origin, dir, m.lo, m.hi, t_max) {
                continue;
            }
            if let Some(hit) = m.mesh.cast_local_ray_and_get_normal(&ray, t_max, false)
                && best.is_none_or(|b| hit.time_of_impact < b.1)
            {
                best = Some((m.label, hit.time_of_impact, hit.normal));
            }
        }
        best
    }

    /// The nearest other truth part within `radius` of a surface point (ties: smaller part id).
    fn nearest_other_part(&self, surface: Vec3, label: Label, radius: f32) -> Option<Label> {
        let mut nearest: Option<(f32, Label)> = None;
        let mut consider = |d: f32, other: Label| {
            let closer = match nearest {
                None => true,
                Some((bd, bl)) => d.total_cmp(&bd).then(other.part.cmp(&bl.part)).is_lt(),
            };
            if d < radius && closer {
                nearest = Some((d, other));
            }
        };
        self.bvh.for_each_near(surface, radius, |j| {
            let other = self.labels[j];
            if other.part >= 0 && other.part != label.part {
                consider(self.primitives[j].surface_distance(surface), other);
            }
        });
        for m in &self.meshes {
            if m.label.part == label.part || !(surface.cmpge(m.lo - radius) & surface.cmple(m.hi + radius)).all() {
                continue;
            }
            consider(m.mesh.distance_to_local_point(surface, false), m.label);
        }
        nearest.map(|(_, l)| l)
    }
}

fn build_world(truth: &GroundTruth, cfg: &ScannerConfig) -> World {
    let mut primitives = Vec::new();
    let mut labels = Vec::new();
    for object in &truth.objects {
        for part in &object.parts {
            for shape in &part.shapes {
                primitives.push(*shape);
                labels.push(Label { object: object.id, part: part.id });
            }
        }
    }
    let (lo, hi) = room_bounds(truth);
    let (lo, hi) = (lo - Vec2::splat(cfg.wall_gap_m), hi + Vec2::splat(cfg.wall_gap_m));
    let z0 = truth.floor_z;
    let wall_t = 0.1;
    let h = cfg.wall_height_m.max(0.1);
    let boxes = [
        // Floor slab, top face at floor_z.
        (Vec3::new(lo.x - wall_t, lo.y - wall_t, z0 - 0.05), Vec3::new(hi.x + wall_t, hi.y + wall_t, z0)),
        (Vec3::new(lo.x - wall_t, lo.y - wall_t, z0), Vec3::new(lo.x, hi.y + wall_t, z0 + h)),
        (Vec3::new(hi.x, lo.y - wall_t, z0), Vec3::new(hi.x + wall_t, hi.y + wall_t, z0 + h)),
        (Vec3::new(lo.x, lo.y - wall_t, z0), Vec3::new(hi.x, lo.y, z0 + h)),
        (Vec3::new(lo.x, hi.y, z0), Vec3::new(hi.x, hi.y + wall_t, z0 + h)),
    ];
    for (a, b) in boxes {
        primitives.push(Primitive::cuboid_at(0.5 * (a + b), b - a));
        labels.push(BACKGROUND);
    }
    let bvh = Bvh::new(&primitives);
    let mut meshes = Vec::new();
    for object in &truth.objects {
        for part in &object.parts {
            for m in &part.meshes {
                let (Some((lo, hi)), Ok(mesh)) = (m.aabb(), TriMesh::new(m.vertices.clone(), m.triangles.clone())) else { continue };
                meshes.push(MeshTarget { mesh, label: Label { object: object.id, part: part.id }, lo, hi });
            }
        }
    }
    World { primitives, labels, bvh, meshes }
}

/// Whether a camera standing at `xy` keeps 0.35 m from every object.
fn is_free(truth: &GroundTruth, xy: Vec2) -> bool {
    truth.objects.iter().flat_map(|o| o.parts.iter()).filter_map(crate::truth::TruthPart::aabb).all(|(a, b)| {
        let margin = 0.35;
        xy.x < a.x - margin || xy.x > b.x + margin || xy.y < a.y - margin || xy.y > b.y + margin
    })
}

/// World bounds of an object's shapes.
fn object_bounds(object: &TruthObject) -> (Vec3, Vec3) {
    object.aabb().unwrap_or((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)))
}

/// Sum of the horizontal directions an object's movable parts face (the outward normal of each
/// door or drawer board): where a scanner operator would stand to see its fronts.
fn facing(object: &TruthObject) -> Vec2 {
    let shape = |id: PartId| object.parts.iter().find(|p| p.id == id).and_then(|p| p.shapes.first());
    object
        .joints
        .iter()
        .filter(|j| j.kind.is_movable())
        .filter_map(|j| {
            let (child, parent) = (shape(j.child)?, shape(j.parent)?);
            let axes = child.axes_world();
            let thin = (0..3).min_by(|&a, &b| child.size[a].total_cmp(&child.size[b]))?;
            let n = axes[thin];
            let n = if n.dot(child.center() - parent.center()) < 0.0 { -n } else { n };
            Some(n.truncate())
        })
        .sum()
}

/// Objects one camera aims at: bounds and the direction their fronts face.
#[derive(Clone, Copy, Debug)]
struct Group {
    lo: Vec3,
    hi: Vec3,
    facing: Vec2,
}

impl Group {
    fn merged(self, other: Group) -> Group {
        Group { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi), facing: self.facing + other.facing }
    }

    fn diagonal(&self) -> f32 {
        (self.hi - self.lo).truncate().length()
    }
}

/// Cameras: the floor is cut into tiles of about `tile_size_m`; each tile gets `viewpoints`
/// cameras. The floor-standing objects of a tile (with whatever stands on them) are merged into
/// groups, smallest joint bounds first, until there are no more groups than cameras; each
/// group gets a camera on the side its doors and drawers face (towards the tile centre when it
/// has none), the remaining cameras revisit the groups nearest the tile centre from the other
/// side. A camera stands `view_distance_m` beyond its group's bounding circle, or far enough to
/// fit the group in view, turned by up to `view_angle_jitter_deg`, where the floor is free
/// (moving closer if needed); a group with no free spot gets no camera.
fn cameras(truth: &GroundTruth, cfg: &ScannerConfig, seed: u64) -> Vec<Camera> {
    let mut r = rng(seed ^ 0xCA3E_5A11);
    // Cameras may stand anywhere inside the walls (`wall_gap_m` beyond the furniture).
    let (lo, hi) = room_bounds(truth);
    let gap = Vec2::splat(cfg.wall_gap_m.max(0.0));
    let (lo, hi) = (lo - gap, hi + gap);
    let extent = (hi - lo).max(Vec2::splat(0.5));
    let tiles_x = (extent.x / cfg.tile_size_m.max(1.0)).ceil().max(1.0) as usize;
    let tiles_y = (extent.y / cfg.tile_size_m.max(1.0)).ceil().max(1.0) as usize;
    let tile = extent / Vec2::new(tiles_x as f32, tiles_y as f32);
    let (h_lo, mut h_hi) = cfg.camera_height_m;
    if cfg.cameras_above_objects {
        let tallest = truth.objects.iter().map(|o| object_bounds(o).1.z).fold(0.0_f32, f32::max);
        h_hi = h_hi.max(tallest + 0.4);
    }
    let (d_lo, d_hi) = cfg.view_distance_m;
    let jitter = cfg.view_angle_jitter_deg.abs().to_radians();
    let fit_tan = (0.45 * cfg.horizontal_fov_deg.clamp(1.0, 170.0)).to_radians().tan();
    let inside = |xy: Vec2| xy.cmpge(lo + Vec2::splat(0.3)).all() && xy.cmple(hi - Vec2::splat(0.3)).all();

    // One group per floor-standing object, including what stands on it.
    let mut per_tile: BTreeMap<(usize, usize), Vec<Group>> = BTreeMap::new();
    for object in truth.objects.iter().filter(|o| o.supported_by.is_none()) {
        let (mut a, mut b) = object_bounds(object);
        if a.x > b.x {
            continue;
        }
        let mut face = facing(object);
        for above in truth.objects.iter().filter(|o| o.supported_by == Some(object.id)) {
            let (c, d) = object_bounds(above);
            a = a.min(c);
            b = b.max(d);
            face += facing(above);
        }
        let cell = ((0.5 * (a + b)).truncate() - lo) / tile;
        let ix = (cell.x.max(0.0) as usize).min(tiles_x - 1);
        let iy = (cell.y.max(0.0) as usize).min(tiles_y - 1);
        per_tile.entry((ix, iy)).or_default().push(Group { lo: a, hi: b, facing: face });
    }

    let mut out = Vec::new();
    for ((tx, ty), mut groups) in per_tile {
        let center = lo + tile * Vec2::new(tx as f32 + 0.5, ty as f32 + 0.5);
        let n = cfg.viewpoints.max(1);
        while groups.len() > n {
            let mut best = (f32::INFINITY, 0, 1);
            for i in 0..groups.len() {
                for j in i + 1..groups.len() {
                    let size = groups[i].merged(groups[j]).diagonal();
                    if size < best.0 {
                        best = (size, i, j);
                    }
                }
            }
            let (_, i, j) = best;
            groups[i] = groups[i].merged(groups[j]);
            groups.remove(j);
        }
        // Central groups first: they are the ones worth seeing from a second side.
        let dist = |g: &Group| ((0.5 * (g.lo + g.hi)).truncate() - center).length();
        groups.sort_by(|a, b| dist(a).total_cmp(&dist(b)));
        let bases: Vec<f32> = groups
            .iter()
            .map(|g| {
                let toward_center = center - (0.5 * (g.lo + g.hi)).truncate();
                if g.facing.length() > 0.1 {
                    g.facing.to_angle()
                } else if toward_center.length() > 0.6 {
                    toward_center.to_angle()
                } else {
                    r.random::<f32>() * std::f32::consts::TAU
                }
            })
            .collect();
        for i in 0..n {
            let k = i % groups.len();
            let g = groups[k];
            let revisit = i >= groups.len();
            // A revisit looks from the other side at central groups, and from 50° to the side
            // (alternating) at groups against a wall, as a person walking past them would.
            let side = if (i / groups.len()) % 2 == 1 { 0.87 } else { -0.87 };
            let base = bases[k]
                + match (revisit, dist(&g) < 1.5) {
                    (false, _) => 0.0,
                    (true, true) => std::f32::consts::PI,
                    (true, false) => side,
                };
            let c = 0.5 * (g.lo + g.hi);
            let reach = 0.5 * g.diagonal();
            let fit = reach / fit_tan;
            let height = if h_hi > h_lo { r.random_range(h_lo..h_hi) } else { h_lo };
            let mut spot = None;
            for attempt in 0..32 {
                let angle = base + if jitter > 0.0 { r.random_range(-jitter..=jitter) } else { 0.0 };
                let shrink = 1.0 - attempt as f32 / 40.0;
                let d = if d_hi > d_lo { r.random_range(d_lo..d_hi) } else { d_lo } * shrink;
                let xy = c.truncate() + Vec2::from_angle(angle) * (reach + d).max(fit * shrink);
                if inside(xy) && is_free(truth, xy) {
                    spot = Some(xy);
                    break;
                }
            }
            let Some(xy) = spot else { continue };
            let eye = xy.extend(truth.floor_z + height);
            let target = Vec3::new(c.x, c.y, c.z.clamp(truth.floor_z + 0.3, truth.floor_z + 1.2));
            out.push(Camera::looking_at(eye, target));
        }
    }
    out
}

/// One scanned point.
#[derive(Clone, Copy, Debug)]
struct Sample {
    point: Vec3,
    normal: Vec3,
    label: Label,
}

/// A seed for one image row: decorrelated from its neighbours (`SplitMix64` finaliser).
fn row_seed(seed: u64, task: u64) -> u64 {
    let mut z = seed ^ task.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn gaussian(r: &mut rand_chacha::ChaCha8Rng) -> f32 {
    r.sample(StandardNormal)
}

/// Scans one image row of one camera.
fn scan_row(world: &World, cfg: &ScannerConfig, camera: &Camera, row: usize, seed: u64) -> Vec<Sample> {
    let mut r = rng(seed);
    let w = cfg.image_width.max(1);
    let h = cfg.image_height.max(1);
    let tan_x = (0.5 * cfg.horizontal_fov_deg.clamp(1.0, 170.0)).to_radians().tan();
    let tan_y = tan_x * h as f32 / w as f32;
    let y_ndc = (1.0 - 2.0 * (row as f32 + 0.5) / h as f32) * tan_y;
    let min_cos = cfg.max_incidence_deg.clamp(0.0, 90.0).to_radians().cos();
    let mut out = Vec::with_capacity(w);
    for col in 0..w {
        let x_ndc = (2.0 * (col as f32 + 0.5) / w as f32 - 1.0) * tan_x;
        let dir = (camera.forward + camera.right * x_ndc + camera.up * y_ndc).normalize();
        let Some((hit_label, t, normal)) = world.ray_cast(camera.eye, dir, cfg.max_range_m) else {
            continue;
        };
        let mut normal = normal.normalize_or(-dir);
        if normal.dot(dir) > 0.0 {
            normal = -normal;
        }
        if -normal.dot(dir) < min_cos {
            continue; // grazing: the sensor returns nothing
        }
        let surface = camera.eye + dir * t;
        let mut label = hit_label;
        if cfg.stray_fraction > 0.0
            && cfg.stray_radius_m > 0.0
            && let Some(other) = world.nearest_other_part(surface, label, cfg.stray_radius_m)
            && r.random::<f32>() < cfg.stray_fraction
        {
            label = other;
        }
        let sigma = cfg.depth_noise_m.max(0.0) * t;
        let mut point = camera.eye + dir * (t + sigma * gaussian(&mut r));
        if cfg.outlier_fraction > 0.0 && r.random::<f32>() < cfg.outlier_fraction {
            let offset_dir = Vec3::new(gaussian(&mut r), gaussian(&mut r), gaussian(&mut r)).normalize_or(normal);
            let (a, b) = cfg.outlier_offset_m;
            let len = if b > a { r.random_range(a..b) } else { a };
            point += offset_dir * len;
        }
        if cfg.normal_noise_rad > 0.0 {
            let jitter = Vec3::new(gaussian(&mut r), gaussian(&mut r), gaussian(&mut r)) * cfg.normal_noise_rad;
            normal = (normal + jitter - normal * jitter.dot(normal)).normalize_or(normal);
        }
        out.push(Sample { point, normal, label });
    }
    out
}

/// Scans a ground-truth scene (every truth primitive, the floor at `floor_z` and walls on the
/// furniture's bounds) with the configured cameras. Points are labelled with the object and part
/// their ray hit (floor and walls: background), then degraded as configured. Deterministic for a
/// seed: rows are cast in parallel and collected in order. Parts no ray reached are left out, and
/// so are objects with no scanned part.
#[must_use]
pub fn scan(truth: &GroundTruth, cfg: &ScannerConfig, seed: u64) -> Scan {
    let world = build_world(truth, cfg);
    let cams = cameras(truth, cfg, seed);
    let rows = cfg.image_height.max(1);
    let samples: Vec<Vec<Sample>> = (0..cams.len() * rows)
        .into_par_iter()
        .map(|task| scan_row(&world, cfg, &cams[task / rows], task % rows, row_seed(seed, task as u64)))
        .collect();

    let mut background = Vec::new();
    let mut by_part: BTreeMap<PartId, (Vec<Vec3>, Vec<Vec3>)> = BTreeMap::new();
    for s in samples.iter().flatten() {
        if s.label.part < 0 {
            background.push(s.point);
        } else {
            let entry = by_part.entry(s.label.part).or_default();
            entry.0.push(s.point);
            entry.1.push(s.normal);
        }
    }
    let mut part_info: BTreeMap<PartId, (ObjectId, &str)> = BTreeMap::new();
    for object in &truth.objects {
        for part in &object.parts {
            part_info.insert(part.id, (object.id, part.label.as_str()));
        }
    }
    let mut parts = Vec::with_capacity(by_part.len());
    let mut objects = BTreeMap::new();
    for (id, (points, normals)) in by_part {
        let Some(&(object, label)) = part_info.get(&id) else { continue };
        parts.push(ScanPart { id, object, label: label.to_string(), points, normals: cfg.normals.then_some(normals) });
        if let Some(o) = truth.objects.iter().find(|o| o.id == object) {
            objects.insert(object, ScanObject { id: object, category: o.category.clone() });
        }
    }
    Scan { source: format!("synthetic scan (seed {seed})"), parts, objects, background }
}
