//! Rooms furnished with the procedural furniture: the built-in demo scene and a large scene for
//! benchmarks.
//!
//! A room's interior is `[0, lx] × [0, ly]` with the floor at z = 0. The walls are not objects:
//! the scanner puts them on the bounds of the furniture (see [`super::scanner::room_bounds`]), so
//! every room here has furniture with its back against each of its four walls.
//!
//! Ids: objects are numbered 1, 2, ... in placement order; the parts of object `o` are
//! `100·o + 1, 100·o + 2, ...` with `100·o + 1` the root (body, top, seat or frame), so a part id
//! names its object at a glance and is unique in the scene.

use std::f32::consts::{FRAC_PI_2, PI};

use rand::Rng;

use super::builder::Furniture;
use super::furniture::{self, CabinetLayout, SynthRng, small_yaw, uniform};
use crate::math::{Pose, Quat, Vec2, rng};
use crate::scan::{ObjectId, PartId};
use crate::truth::{GroundTruth, TRUTH_FORMAT, TruthObject};

/// Part ids of an object start at `PART_IDS_PER_OBJECT · object id + 1`.
pub const PART_IDS_PER_OBJECT: PartId = 100;

/// Clearance kept between objects standing on the floor, metres.
const CLEARANCE_M: f32 = 0.05;

/// A rectangle on the floor: centre, half extents along its own axes, yaw (radians).
#[derive(Clone, Copy, Debug)]
struct Rect2 {
    center: Vec2,
    half: Vec2,
    yaw: f32,
}

impl Rect2 {
    fn axes(&self) -> [Vec2; 2] {
        let (s, c) = self.yaw.sin_cos();
        [Vec2::new(c, s), Vec2::new(-s, c)]
    }

    fn corners(&self) -> [Vec2; 4] {
        let [ax, ay] = self.axes();
        let (hx, hy) = (ax * self.half.x, ay * self.half.y);
        [self.center - hx - hy, self.center + hx - hy, self.center + hx + hy, self.center - hx + hy]
    }

    /// Whether the two rectangles come closer than `clearance` (separating-axis test).
    fn overlaps(&self, other: &Rect2, clearance: f32) -> bool {
        let (a, b) = (self.corners(), other.corners());
        for axis in self.axes().into_iter().chain(other.axes()) {
            let project = |pts: &[Vec2; 4]| {
                pts.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                    let d = p.dot(axis);
                    (lo.min(d), hi.max(d))
                })
            };
            let (a_lo, a_hi) = project(&a);
            let (b_lo, b_hi) = project(&b);
            if a_hi + clearance <= b_lo || b_hi + clearance <= a_lo {
                return false;
            }
        }
        true
    }

    fn inside(&self, size: Vec2) -> bool {
        self.corners().iter().all(|c| c.x >= -1e-4 && c.y >= -1e-4 && c.x <= size.x + 1e-4 && c.y <= size.y + 1e-4)
    }
}

/// The walls of a room, named by compass direction (+y is north).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wall {
    South,
    North,
    West,
    East,
}

/// Id counter shared by the rooms of one scene.
struct Ids {
    next_object: ObjectId,
}

/// Objects being placed into one room whose interior corner (0, 0) lies at `origin` in the world.
struct Layout<'a> {
    origin: Vec2,
    size: Vec2,
    rects: Vec<Rect2>,
    objects: &'a mut Vec<TruthObject>,
    ids: &'a mut Ids,
}

impl Layout<'_> {
    /// The rectangle `f` covers with its footprint centre at `center`, turned by `yaw`.
    fn rect(f: &Furniture, center: Vec2, yaw: f32) -> Rect2 {
        let (lo, hi) = f.footprint();
        Rect2 { center, half: 0.5 * (hi - lo), yaw }
    }

    /// Adds the object without checks; returns its id.
    fn commit(&mut self, f: &Furniture, center: Vec2, yaw: f32, base_z: f32, supported_by: Option<ObjectId>) -> ObjectId {
        let id = self.ids.next_object;
        self.ids.next_object += 1;
        let (lo, hi) = f.footprint();
        let footprint_center = 0.5 * (lo + hi);
        let rotation = Quat::from_rotation_z(yaw);
        let offset = (rotation * footprint_center.extend(0.0)).truncate();
        let world = (self.origin + center - offset).extend(base_z);
        let pose = Pose::from_parts(world, rotation);
        self.objects.push(f.place(pose, id, PART_IDS_PER_OBJECT * id + 1, supported_by));
        id
    }

    /// Places a floor-standing object if it fits in the room and keeps clear of the others.
    fn try_floor(&mut self, f: &Furniture, center: Vec2, yaw: f32, clearance: f32) -> Option<ObjectId> {
        let rect = Self::rect(f, center, yaw);
        if !rect.inside(self.size) || self.rects.iter().any(|r| r.overlaps(&rect, clearance)) {
            return None;
        }
        self.rects.push(rect);
        Some(self.commit(f, center, yaw, 0.0, None))
    }

    /// Places `f` with its back against `wall`, its centre along the wall sampled in `along`
    /// (fractions of the wall's length).
    fn on_wall(&mut self, rng: &mut SynthRng, f: &Furniture, wall: Wall, along: (f32, f32)) -> Option<ObjectId> {
        let (lo, hi) = f.footprint();
        let half = 0.5 * (hi - lo);
        let (yaw, length) = match wall {
            Wall::South => (0.0, self.size.x),
            Wall::North => (PI, self.size.x),
            Wall::West => (-FRAC_PI_2, self.size.y),
            Wall::East => (FRAC_PI_2, self.size.y),
        };
        let a_lo = (along.0 * length).max(half.x + 0.02);
        let a_hi = (along.1 * length).min(length - half.x - 0.02);
        for _ in 0..60 {
            let a = uniform(rng, a_lo, a_hi);
            let center = match wall {
                Wall::South => Vec2::new(a, half.y),
                Wall::North => Vec2::new(a, self.size.y - half.y),
                Wall::West => Vec2::new(half.y, a),
                Wall::East => Vec2::new(self.size.x - half.y, a),
            };
            if let Some(id) = self.try_floor(f, center, yaw, CLEARANCE_M) {
                return Some(id);
            }
        }
        None
    }
}

/// Furnishes one room: a bed, three cabinets (one of each front layout), a refrigerator against the
/// walls; a table in the middle with a microwave on it and `chairs` chairs at it. Returns `None`
/// when something did not fit (the caller retries with another draw).
fn furnish(layout: &mut Layout<'_>, rng: &mut SynthRng, chairs: usize) -> Option<()> {
    let (lx, ly) = (layout.size.x, layout.size.y);
    let bed = furniture::bed(rng);
    layout.on_wall(rng, &bed, Wall::West, (0.0, 0.55))?;
    let mut layouts = [
        CabinetLayout::Drawers(rng.random_range(2..=4)),
        CabinetLayout::Doors(rng.random_range(1..=2)),
        CabinetLayout::DrawersOverDoors { drawers: rng.random_range(1..=2), doors: rng.random_range(1..=2) },
    ];
    // A seeded shuffle, so each wall sees every layout across seeds.
    for i in (1..layouts.len()).rev() {
        layouts.swap(i, rng.random_range(0..=i));
    }
    let cabinet = furniture::cabinet(rng, layouts[0]);
    layout.on_wall(rng, &cabinet, Wall::North, (0.0, 0.55))?;
    let fridge = furniture::refrigerator(rng);
    layout.on_wall(rng, &fridge, Wall::North, (0.5, 1.0))?;
    let cabinet = furniture::cabinet(rng, layouts[1]);
    layout.on_wall(rng, &cabinet, Wall::East, (0.0, 0.7))?;
    let cabinet = furniture::cabinet(rng, layouts[2]);
    layout.on_wall(rng, &cabinet, Wall::South, (0.35, 1.0))?;

    let table = furniture::table(rng);
    let (t_lo, t_hi) = table.footprint();
    let table_half = 0.5 * (t_hi - t_lo);
    let mut placed_table = None;
    for _ in 0..80 {
        let quarter = if rng.random_bool(0.5) { 0.0 } else { FRAC_PI_2 };
        let yaw = quarter + if rng.random_bool(0.7) { small_yaw(rng, 10.0) } else { 0.0 };
        let center = Vec2::new(uniform(rng, 0.3 * lx, 0.75 * lx), uniform(rng, 0.3 * ly, 0.7 * ly));
        // Leave room for a chair around the table.
        if let Some(id) = layout.try_floor(&table, center, yaw, 0.6) {
            placed_table = Some((id, center, yaw));
            break;
        }
    }
    let (table_id, table_center, table_yaw) = placed_table?;
    let table_rotation = Quat::from_rotation_z(table_yaw);
    let table_height = table.height_m();

    // The microwave stands on the table top, facing the table's front or back.
    let microwave = furniture::microwave(rng);
    let (m_lo, m_hi) = microwave.footprint();
    let m_half = 0.5 * (m_hi - m_lo);
    let free = (table_half - m_half - Vec2::splat(0.03)).max(Vec2::ZERO);
    let offset = Vec2::new(uniform(rng, -free.x, free.x), uniform(rng, -free.y, free.y));
    let m_center = table_center + (table_rotation * offset.extend(0.0)).truncate();
    let m_yaw = table_yaw + if rng.random_bool(0.5) { 0.0 } else { PI };
    layout.commit(&microwave, m_center, m_yaw, table_height, Some(table_id));

    for _ in 0..chairs {
        let chair = furniture::chair(rng);
        let (c_lo, c_hi) = chair.footprint();
        let c_half = 0.5 * (c_hi - c_lo);
        let mut placed = false;
        for _ in 0..60 {
            // Chair front (+y) faces the table: on the table's −y side it keeps the table's yaw.
            let side = if rng.random_bool(0.5) { -1.0 } else { 1.0 };
            let along = uniform(rng, -(table_half.x - c_half.x).max(0.0), (table_half.x - c_half.x).max(0.0));
            let local = Vec2::new(along, side * (table_half.y + c_half.y + uniform(rng, 0.08, 0.2)));
            let center = table_center + (table_rotation * local.extend(0.0)).truncate();
            let yaw = table_yaw + if side < 0.0 { 0.0 } else { PI } + small_yaw(rng, 10.0);
            if layout.try_floor(&chair, center, yaw, 0.03).is_some() {
                placed = true;
                break;
            }
        }
        if !placed {
            return None;
        }
    }
    Some(())
}

/// Furnishes a room of `size` at `origin`, retrying with fresh draws until everything fits.
fn furnished_room(seed: u64, origin: Vec2, size: Vec2, chairs: usize, objects: &mut Vec<TruthObject>, ids: &mut Ids) {
    let first_object = ids.next_object;
    for attempt in 0..64_u64 {
        let mut rng = rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(attempt));
        let kept = objects.len();
        let mut layout = Layout { origin, size, rects: Vec::new(), objects, ids };
        if furnish(&mut layout, &mut rng, chairs).is_some() {
            return;
        }
        objects.truncate(kept);
        ids.next_object = first_object;
    }
    // With the room sizes used here a layout is found within a few attempts; if not, the room
    // stays empty rather than holding a half-placed set.
}

fn truth(objects: Vec<TruthObject>) -> GroundTruth {
    GroundTruth { format: TRUTH_FORMAT.to_string(), objects, floor_z: 0.0 }
}

/// The built-in demo scene for a seed (seed 0 is the default demo): one room of about
/// 5.6–6.4 m × 4.6–5.2 m with a bed, three cabinets (a drawer column, doors, drawers over doors),
/// a refrigerator against the walls, a table in the middle with a microwave on it
/// (`supported_by` = the table) and a chair at it. Some free-standing objects carry a small yaw.
#[must_use]
pub fn demo_room(seed: u64) -> GroundTruth {
    let mut r = rng(seed ^ 0x5EED_0D0E_u64);
    let size = Vec2::new(uniform(&mut r, 5.6, 6.4), uniform(&mut r, 4.6, 5.2));
    let mut objects = Vec::new();
    let mut ids = Ids { next_object: 1 };
    furnished_room(seed, Vec2::ZERO, size, 1, &mut objects, &mut ids);
    truth(objects)
}

/// A large open floor for benchmarks: furnished 6 m × 5 m bays (each like the demo room, with two
/// chairs) on a grid with 1.2 m aisles, added until the scene has at least `min_parts` parts.
#[must_use]
pub fn large_scene(seed: u64, min_parts: usize) -> GroundTruth {
    const BAY: Vec2 = Vec2::new(6.0, 5.0);
    const AISLE_M: f32 = 1.2;
    // About 45 parts per bay; lay the bays out in a near-square grid.
    let estimate = min_parts.div_ceil(40).max(1);
    let columns = (estimate as f32).sqrt().ceil().max(1.0) as usize;
    let mut objects = Vec::new();
    let mut ids = Ids { next_object: 1 };
    let mut bay = 0_usize;
    let part_count = |objects: &Vec<TruthObject>| objects.iter().map(|o| o.parts.len()).sum::<usize>();
    while part_count(&objects) < min_parts.max(1) {
        let (col, row) = (bay % columns, bay / columns);
        let origin = Vec2::new(col as f32, row as f32) * (BAY + Vec2::splat(AISLE_M));
        let before = objects.len();
        furnished_room(seed.wrapping_mul(1000).wrapping_add(bay as u64 + 1), origin, BAY, 2, &mut objects, &mut ids);
        bay += 1;
        if objects.len() == before && bay > estimate * 4 {
            break; // Nothing fits any more (cannot happen with these sizes); never loop forever.
        }
    }
    truth(objects)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangles_overlap_only_when_close() {
        let a = Rect2 { center: Vec2::ZERO, half: Vec2::new(1.0, 0.5), yaw: 0.0 };
        let b = Rect2 { center: Vec2::new(2.1, 0.0), half: Vec2::new(1.0, 0.5), yaw: 0.0 };
        assert!(!a.overlaps(&b, 0.05));
        assert!(a.overlaps(&b, 0.2));
        // A diamond whose bounding box overlaps `a` but which itself stays clear of it.
        let c = Rect2 { center: Vec2::new(1.6, 1.1), half: Vec2::new(0.5, 0.5), yaw: PI / 4.0 };
        assert!(!a.overlaps(&c, 0.0));
        // Its lowest corner (y = 1.1 − 0.707) inside `a`.
        let d = Rect2 { center: Vec2::new(0.8, 1.1), ..c };
        assert!(a.overlaps(&d, 0.0));
    }
}
