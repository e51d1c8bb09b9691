//! The built-in demo: procedural furniture with ground truth ([`furniture`]), rooms furnished with
//! it ([`room`]), and a virtual depth scanner that turns a ground truth into a part-segmented
//! partial scan ([`scanner`]). `partscene demo` needs no files: [`demo`] gives both.

pub mod builder;
mod bvh;
pub mod furniture;
pub mod room;
pub mod scanner;

#[cfg(test)]
mod tests;

use std::collections::BTreeMap;

use rand::Rng;

use crate::math::rng;
use crate::scan::{PartId, Scan};
use crate::truth::GroundTruth;

pub use room::{demo_room, large_scene};
pub use scanner::{ScannerConfig, room_bounds, scan};

/// The demo scene for a seed and its scan with the default scanner (seed 0 is the default demo).
#[must_use]
pub fn demo(seed: u64) -> (GroundTruth, Scan) {
    let truth = demo_room(seed);
    let mut scan = scan(&truth, &ScannerConfig::default(), seed);
    scan.source = format!("demo seed {seed}");
    (truth, scan)
}

/// The demo scene scanned with the clean complete setting (the paper's *annotation* input).
#[must_use]
pub fn demo_clean(seed: u64) -> (GroundTruth, Scan) {
    let truth = demo_room(seed);
    let mut scan = scan(&truth, &ScannerConfig::clean_complete(), seed);
    scan.source = format!("demo seed {seed} (clean complete)");
    (truth, scan)
}

/// Colour of background points (floor, walls) for writers and viewers.
pub const BACKGROUND_RGB: [u8; 3] = [190, 186, 178];

/// Display colours of every truth part (for PLY export and viewers), varied by seed: wooden or
/// painted furniture, white or steel appliances, light mattresses, dark or metal handles and knobs.
#[must_use]
pub fn part_colors(truth: &GroundTruth, seed: u64) -> BTreeMap<PartId, [u8; 3]> {
    const WOOD: [[u8; 3]; 4] = [[150, 111, 51], [193, 154, 107], [101, 67, 33], [222, 184, 135]];
    const PAINT: [[u8; 3]; 4] = [[235, 235, 230], [96, 125, 139], [120, 144, 96], [176, 58, 46]];
    const APPLIANCE: [[u8; 3]; 3] = [[240, 240, 240], [170, 172, 175], [40, 40, 42]];
    const METAL: [[u8; 3]; 3] = [[200, 200, 205], [60, 60, 60], [184, 134, 11]];
    const FABRIC: [[u8; 3]; 3] = [[245, 245, 240], [176, 196, 222], [230, 220, 200]];
    let mut out = BTreeMap::new();
    for object in &truth.objects {
        let mut r = rng(seed ^ (object.id as u64).wrapping_mul(0x2545_F491_4F6C_DD1D));
        let appliance = matches!(object.category.as_str(), "microwave" | "refrigerator");
        let base = if appliance {
            APPLIANCE[r.random_range(0..APPLIANCE.len())]
        } else if r.random_bool(0.6) {
            WOOD[r.random_range(0..WOOD.len())]
        } else {
            PAINT[r.random_range(0..PAINT.len())]
        };
        // Fronts a shade lighter or darker than the body.
        let shade = |c: [u8; 3], f: f32| c.map(|v| (f32::from(v) * f).clamp(0.0, 255.0) as u8);
        let front = shade(base, if r.random_bool(0.5) { 0.9 } else { 1.08 });
        let metal = METAL[r.random_range(0..METAL.len())];
        let fabric = FABRIC[r.random_range(0..FABRIC.len())];
        for part in &object.parts {
            let rgb = match part.label.as_str() {
                "handle" | "knob" => metal,
                "mattress" => fabric,
                "door" | "drawer" => front,
                _ => base,
            };
            out.insert(part.id, rgb);
        }
    }
    out
}
