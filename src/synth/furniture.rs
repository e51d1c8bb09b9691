//! Procedural furniture with ground-truth parts and kinematics, built in the object frame
//! (x right, y = outward front normal, z up, base at z = 0; see [`super::builder`]).
//!
//! Conventions the reconstruction relies on (they match real furniture):
//! - bodies are solid boxes; drawer fronts and doors are thin boards (1.5–2.5 cm) whose back face
//!   lies on the body's front face (no gap, no penetration), inside the body's front outline;
//! - every drawer and door has a handle: a small bar (cuboid or cylinder) touching its front;
//!   a door's handle sits near the edge opposite its hinge;
//! - drawers slide along the front normal, limits `[0, 0.8–0.9 × body depth]`, origin at the
//!   drawer's centre; doors turn about their hinge edge (origin on the hinge line at the door's back
//!   face, positive angle = outward), limits `[0, π/2]`; everything else is fixed.

use std::f32::consts::{FRAC_PI_2, PI};

use rand::Rng;

use super::builder::{Furniture, box_between, cylinder_along};
use crate::math::Vec3;
use crate::primitive::Primitive;

/// The random generator every generator draws from.
pub type SynthRng = rand_chacha::ChaCha8Rng;

/// Uniform sample in `[lo, hi)` (returns `lo` for an empty range).
pub(crate) fn uniform(rng: &mut SynthRng, lo: f32, hi: f32) -> f32 {
    if hi > lo { rng.random_range(lo..hi) } else { lo }
}

/// Uniform integer in `[lo, hi]`.
fn count(rng: &mut SynthRng, lo: usize, hi: usize) -> usize {
    if hi > lo { rng.random_range(lo..=hi) } else { lo }
}

/// Which edge of a door the hinge is on (seen from the front).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hinge {
    /// Vertical hinge on the left edge (seen from the front).
    Left,
    /// Vertical hinge on the right edge.
    Right,
    /// Horizontal hinge on the bottom edge (the door folds down, like an oven's).
    Bottom,
    /// Horizontal hinge on the top edge.
    Top,
}

/// How handles of one object look.
#[derive(Clone, Copy, Debug)]
struct HandleStyle {
    /// Cylinder (rod) or cuboid (bar).
    rod: bool,
    /// Thickness across the bar (diameter for rods), metres.
    thickness_m: f32,
    /// How far a cuboid bar stands off the board (rods: their diameter).
    depth_m: f32,
}

impl HandleStyle {
    fn random(rng: &mut SynthRng) -> Self {
        let rod = rng.random_bool(0.5);
        let thickness_m = uniform(rng, 0.015, 0.024);
        let depth_m = if rod { thickness_m } else { uniform(rng, 0.02, 0.03) };
        Self { rod, thickness_m, depth_m }
    }

    /// A handle whose back touches the board's front face (plane y = `front_y`) at (`x`, `z`),
    /// running along `along` (x or z).
    fn make(self, front_y: f32, x: f32, z: f32, along: Vec3, length_m: f32) -> Primitive {
        let center = Vec3::new(x, front_y + 0.5 * self.depth_m, z);
        if self.rod {
            cylinder_along(along, center, self.thickness_m, length_m)
        } else {
            let across = Vec3::ONE - along.abs() - Vec3::Y;
            let size = along.abs() * length_m + Vec3::Y * self.depth_m + across * self.thickness_m;
            Primitive::cuboid_at(center, size)
        }
    }
}

/// A front board (drawer front or door) on the body's front face `front_y`.
fn board(front_y: f32, x0: f32, x1: f32, z0: f32, z1: f32, thickness_m: f32) -> Primitive {
    box_between(Vec3::new(x0, front_y, z0), Vec3::new(x1, front_y + thickness_m, z1))
}

/// Adds a drawer front with a centred horizontal handle.
fn add_drawer(
    f: &mut Furniture,
    rng: &mut SynthRng,
    body: usize,
    front_y: f32,
    depth_m: f32,
    (x0, x1, z0, z1): (f32, f32, f32, f32),
    thickness_m: f32,
    style: HandleStyle,
) {
    let front = board(front_y, x0, x1, z0, z1, thickness_m);
    let travel = uniform(rng, 0.8, 0.9) * depth_m;
    let drawer = f.add_prismatic(body, "drawer", front, Vec3::Y, travel);
    let length = uniform(rng, 0.1, 0.2).min(0.5 * (x1 - x0));
    let z = 0.5 * (z0 + z1) + uniform(rng, 0.0, 0.2) * (z1 - z0) * 0.5;
    let handle = style.make(front_y + thickness_m, 0.5 * (x0 + x1), z, Vec3::X, length);
    f.add_fixed(drawer, "handle", handle);
}

/// Adds a door on the body's front face with its hinge on `hinge` and a handle near the opposite
/// edge. `handle_len_m` is the handle's length; `handle_z` overrides its height for side hinges.
fn add_door(
    f: &mut Furniture,
    body: usize,
    front_y: f32,
    (x0, x1, z0, z1): (f32, f32, f32, f32),
    thickness_m: f32,
    hinge: Hinge,
    style: HandleStyle,
    handle_len_m: f32,
    handle_z: Option<f32>,
) {
    let door_board = board(front_y, x0, x1, z0, z1, thickness_m);
    let (xc, zc) = (0.5 * (x0 + x1), 0.5 * (z0 + z1));
    // u: from the hinge line towards the door; the axis u × n (n = +y) makes +angle swing out.
    let (origin, towards_door) = match hinge {
        Hinge::Left => (Vec3::new(x0, front_y, zc), Vec3::X),
        Hinge::Right => (Vec3::new(x1, front_y, zc), Vec3::NEG_X),
        Hinge::Bottom => (Vec3::new(xc, front_y, z0), Vec3::Z),
        Hinge::Top => (Vec3::new(xc, front_y, z1), Vec3::NEG_Z),
    };
    let axis = towards_door.cross(Vec3::Y);
    let door = f.add_revolute(body, "door", door_board, axis, origin, FRAC_PI_2);
    let inset = style.thickness_m * 0.5 + 0.035;
    let face = front_y + thickness_m;
    let handle = match hinge {
        Hinge::Left | Hinge::Right => {
            let length = handle_len_m.min(0.6 * (z1 - z0));
            let half = 0.5 * length + 0.03;
            let z = handle_z.unwrap_or(zc).clamp(z0 + half, z1 - half);
            let x = if hinge == Hinge::Left { x1 - inset } else { x0 + inset };
            style.make(face, x, z, Vec3::Z, length)
        }
        Hinge::Bottom | Hinge::Top => {
            let length = handle_len_m.min(0.6 * (x1 - x0));
            let z = if hinge == Hinge::Bottom { z1 - inset } else { z0 + inset };
            style.make(face, xc, z, Vec3::X, length)
        }
    };
    f.add_fixed(door, "handle", handle);
}

/// Front layouts of a cabinet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CabinetLayout {
    /// A column of drawers (2–4).
    Drawers(usize),
    /// One door (hinge left or right) or a pair (hinges on the outer edges).
    Doors(usize),
    /// Drawers in the upper part, doors below.
    DrawersOverDoors { drawers: usize, doors: usize },
}

impl CabinetLayout {
    /// A random layout.
    pub fn random(rng: &mut SynthRng) -> Self {
        match rng.random_range(0..3) {
            0 => CabinetLayout::Drawers(count(rng, 2, 4)),
            1 => CabinetLayout::Doors(count(rng, 1, 2)),
            _ => CabinetLayout::DrawersOverDoors { drawers: count(rng, 1, 2), doors: count(rng, 1, 2) },
        }
    }
}

/// A cabinet: solid box body with drawers and/or doors on its front, each with a handle.
pub fn cabinet(rng: &mut SynthRng, layout: CabinetLayout) -> Furniture {
    let (width, height) = match layout {
        CabinetLayout::Drawers(n) => (uniform(rng, 0.5, 1.0), n as f32 * uniform(rng, 0.16, 0.22) + 0.1),
        CabinetLayout::Doors(1) => (uniform(rng, 0.45, 0.65), uniform(rng, 0.7, 1.9)),
        CabinetLayout::Doors(_) => (uniform(rng, 0.75, 1.2), uniform(rng, 0.7, 1.9)),
        CabinetLayout::DrawersOverDoors { .. } => (uniform(rng, 0.7, 1.1), uniform(rng, 0.85, 1.1)),
    };
    let depth = uniform(rng, 0.4, 0.6);
    let margin = uniform(rng, 0.02, 0.04);
    let gap = uniform(rng, 0.004, 0.008);
    let thickness = uniform(rng, 0.015, 0.025);
    let style = HandleStyle::random(rng);
    let front_y = 0.5 * depth;
    let mut f = Furniture::new("cabinet");
    let body = f.add_part("body", box_between(Vec3::new(-0.5 * width, -0.5 * depth, 0.0), Vec3::new(0.5 * width, 0.5 * depth, height)));
    let (x_lo, x_hi) = (-0.5 * width + margin, 0.5 * width - margin);
    let (z_lo, z_hi) = (margin, height - margin);
    let drawer_column = |f: &mut Furniture, rng: &mut SynthRng, n: usize, z0: f32, z1: f32| {
        let h = (z1 - z0 - (n as f32 - 1.0) * gap) / n as f32;
        for i in 0..n {
            let a = z0 + i as f32 * (h + gap);
            add_drawer(f, rng, body, front_y, depth, (x_lo, x_hi, a, a + h), thickness, style);
        }
    };
    let handle_len = uniform(rng, 0.1, 0.22);
    let doors = |f: &mut Furniture, rng: &mut SynthRng, n: usize, z0: f32, z1: f32| {
        let handle_z = Some((z0 + 0.6 * (z1 - z0)).min(1.1));
        if n == 1 {
            let hinge = if rng.random_bool(0.5) { Hinge::Left } else { Hinge::Right };
            add_door(f, body, front_y, (x_lo, x_hi, z0, z1), thickness, hinge, style, handle_len, handle_z);
        } else {
            let mid = 0.5 * (x_lo + x_hi);
            let left = (x_lo, mid - 0.5 * gap, z0, z1);
            let right = (mid + 0.5 * gap, x_hi, z0, z1);
            add_door(f, body, front_y, left, thickness, Hinge::Left, style, handle_len, handle_z);
            add_door(f, body, front_y, right, thickness, Hinge::Right, style, handle_len, handle_z);
        }
    };
    match layout {
        CabinetLayout::Drawers(n) => drawer_column(&mut f, rng, n.max(1), z_lo, z_hi),
        CabinetLayout::Doors(n) => doors(&mut f, rng, n.clamp(1, 2), z_lo, z_hi),
        CabinetLayout::DrawersOverDoors { drawers, doors: n } => {
            let drawers = drawers.max(1);
            let drawer_h = uniform(rng, 0.13, 0.18);
            let split = z_hi - drawers as f32 * (drawer_h + gap);
            drawer_column(&mut f, rng, drawers, split + gap, z_hi);
            doors(&mut f, rng, n.clamp(1, 2), z_lo, split);
        }
    }
    f.centred()
}

/// A microwave: body, a door (hinge left, or bottom like an oven) with a handle, 1–2 knobs on the
/// control panel.
pub fn microwave(rng: &mut SynthRng) -> Furniture {
    let width = uniform(rng, 0.45, 0.56);
    let depth = uniform(rng, 0.34, 0.42);
    let height = uniform(rng, 0.26, 0.32);
    let panel = uniform(rng, 0.1, 0.13);
    let margin = uniform(rng, 0.012, 0.02);
    let thickness = uniform(rng, 0.015, 0.022);
    let style = HandleStyle::random(rng);
    let front_y = 0.5 * depth;
    let mut f = Furniture::new("microwave");
    let body = f.add_part("body", box_between(Vec3::new(-0.5 * width, -0.5 * depth, 0.0), Vec3::new(0.5 * width, 0.5 * depth, height)));
    let hinge = if rng.random_bool(0.25) { Hinge::Bottom } else { Hinge::Left };
    let door = (-0.5 * width + margin, 0.5 * width - panel, margin, height - margin);
    let handle_len = uniform(rng, 0.12, 0.2);
    add_door(&mut f, body, front_y, door, thickness, hinge, style, handle_len, None);
    let knobs = count(rng, 1, 2);
    let knob_d = uniform(rng, 0.035, 0.045);
    let knob_h = uniform(rng, 0.015, 0.02);
    let knob_x = 0.5 * width - 0.5 * panel;
    for i in 0..knobs {
        let z = height * if knobs == 1 { 0.5 } else { [0.68, 0.32][i] };
        let knob = cylinder_along(Vec3::Y, Vec3::new(knob_x, front_y + 0.5 * knob_h, z), knob_d, knob_h);
        f.add_revolute(body, "knob", knob, Vec3::Y, knob.center(), std::f32::consts::TAU);
    }
    f.centred()
}

/// A table: top with 4 legs (square or round) under its corners.
pub fn table(rng: &mut SynthRng) -> Furniture {
    let width = uniform(rng, 1.0, 1.6);
    let depth = uniform(rng, 0.7, 0.9);
    let height = uniform(rng, 0.72, 0.77);
    let top_t = uniform(rng, 0.03, 0.05);
    let leg_w = uniform(rng, 0.04, 0.06);
    let inset = uniform(rng, 0.03, 0.08);
    let round = rng.random_bool(0.5);
    let mut f = Furniture::new("table");
    let under = height - top_t;
    let top = f.add_part("top", box_between(Vec3::new(-0.5 * width, -0.5 * depth, under), Vec3::new(0.5 * width, 0.5 * depth, height)));
    add_legs(&mut f, top, width, depth, under, leg_w, inset, round);
    f.centred()
}

/// Four legs from the floor to the underside (`under`) of a `width × depth` root part.
fn add_legs(f: &mut Furniture, root: usize, width: f32, depth: f32, under: f32, leg_w: f32, inset: f32, round: bool) {
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let c = Vec3::new(sx * (0.5 * width - inset - 0.5 * leg_w), sy * (0.5 * depth - inset - 0.5 * leg_w), 0.5 * under);
        let leg = if round { cylinder_along(Vec3::Z, c, leg_w, under) } else { Primitive::cuboid_at(c, Vec3::new(leg_w, leg_w, under)) };
        f.add_fixed(root, "leg", leg);
    }
}

/// A chair: seat on 4 legs, a back board standing on the seat's rear edge. Front is +y.
pub fn chair(rng: &mut SynthRng) -> Furniture {
    let width = uniform(rng, 0.42, 0.5);
    let depth = uniform(rng, 0.4, 0.48);
    let seat_top = uniform(rng, 0.44, 0.48);
    let seat_t = uniform(rng, 0.03, 0.05);
    let leg_w = uniform(rng, 0.03, 0.04);
    let inset = uniform(rng, 0.01, 0.025);
    let back_t = uniform(rng, 0.02, 0.03);
    let back_h = uniform(rng, 0.35, 0.5);
    let round = rng.random_bool(0.4);
    let mut f = Furniture::new("chair");
    let under = seat_top - seat_t;
    let seat = f.add_part("seat", box_between(Vec3::new(-0.5 * width, -0.5 * depth, under), Vec3::new(0.5 * width, 0.5 * depth, seat_top)));
    add_legs(&mut f, seat, width, depth, under, leg_w, inset, round);
    let back =
        box_between(Vec3::new(-0.5 * width, -0.5 * depth, seat_top), Vec3::new(0.5 * width, -0.5 * depth + back_t, seat_top + back_h));
    f.add_fixed(seat, "back", back);
    f.centred()
}

/// A bed: frame (base box), mattress lying on it, headboard standing on the floor against the
/// frame's head end (−y; the foot end faces +y).
pub fn bed(rng: &mut SynthRng) -> Furniture {
    let width = uniform(rng, 1.2, 1.8);
    let length = uniform(rng, 1.95, 2.1);
    let frame_h = uniform(rng, 0.25, 0.4);
    let inset = uniform(rng, 0.02, 0.04);
    let mattress_t = uniform(rng, 0.18, 0.26);
    let head_t = uniform(rng, 0.04, 0.07);
    let head_h = uniform(rng, 0.9, 1.2);
    let head_extra = uniform(rng, 0.0, 0.06);
    let mut f = Furniture::new("bed");
    let frame =
        f.add_part("frame", box_between(Vec3::new(-0.5 * width, -0.5 * length, 0.0), Vec3::new(0.5 * width, 0.5 * length, frame_h)));
    let mattress = box_between(
        Vec3::new(-0.5 * width + inset, -0.5 * length + inset, frame_h),
        Vec3::new(0.5 * width - inset, 0.5 * length - inset, frame_h + mattress_t),
    );
    f.add_fixed(frame, "mattress", mattress);
    let headboard = box_between(
        Vec3::new(-0.5 * width - head_extra, -0.5 * length - head_t, 0.0),
        Vec3::new(0.5 * width + head_extra, -0.5 * length, head_h),
    );
    f.add_fixed(frame, "headboard", headboard);
    f.centred()
}

/// A refrigerator: body with one full-height door, a freezer/fridge pair (same hinge side) or a
/// side-by-side pair; long vertical handles.
pub fn refrigerator(rng: &mut SynthRng) -> Furniture {
    let width = uniform(rng, 0.6, 0.8);
    let depth = uniform(rng, 0.6, 0.72);
    let height = uniform(rng, 1.6, 1.9);
    let margin = uniform(rng, 0.008, 0.015);
    let gap = uniform(rng, 0.006, 0.01);
    let thickness = uniform(rng, 0.02, 0.025);
    let style = HandleStyle::random(rng);
    let front_y = 0.5 * depth;
    let mut f = Furniture::new("refrigerator");
    let body = f.add_part("body", box_between(Vec3::new(-0.5 * width, -0.5 * depth, 0.0), Vec3::new(0.5 * width, 0.5 * depth, height)));
    let (x_lo, x_hi, z_lo, z_hi) = (-0.5 * width + margin, 0.5 * width - margin, margin, height - margin);
    let hinge = if rng.random_bool(0.5) { Hinge::Left } else { Hinge::Right };
    let handle_len = uniform(rng, 0.25, 0.6);
    match rng.random_range(0..3) {
        0 => {
            let z = Some(uniform(rng, 0.9, 1.1));
            add_door(&mut f, body, front_y, (x_lo, x_hi, z_lo, z_hi), thickness, hinge, style, handle_len, z);
        }
        1 => {
            let split = z_hi - uniform(rng, 0.3, 0.4) * (z_hi - z_lo);
            let lower = (x_lo, x_hi, z_lo, split - 0.5 * gap);
            let upper = (x_lo, x_hi, split + 0.5 * gap, z_hi);
            add_door(&mut f, body, front_y, lower, thickness, hinge, style, handle_len, Some(split));
            add_door(&mut f, body, front_y, upper, thickness, hinge, style, handle_len, Some(split));
        }
        _ => {
            let mid = 0.5 * (x_lo + x_hi);
            let z = Some(uniform(rng, 0.9, 1.1));
            let left = (x_lo, mid - 0.5 * gap, z_lo, z_hi);
            let right = (mid + 0.5 * gap, x_hi, z_lo, z_hi);
            add_door(&mut f, body, front_y, left, thickness, Hinge::Left, style, handle_len, z);
            add_door(&mut f, body, front_y, right, thickness, Hinge::Right, style, handle_len, z);
        }
    }
    f.centred()
}

/// Every furniture kind the generators make, by category.
pub const CATEGORIES: [&str; 6] = ["cabinet", "microwave", "table", "chair", "bed", "refrigerator"];

/// A random yaw offset in `[-max_deg, max_deg]`, radians.
pub(crate) fn small_yaw(rng: &mut SynthRng, max_deg: f32) -> f32 {
    uniform(rng, -max_deg, max_deg) * PI / 180.0
}
