//! Logging every pipeline stage to a Rerun recording (feature `rerun`): the scan's points by part,
//! the fitted primitives, each object's contact graph and kinematic tree, every refinement step,
//! and the final primitives and joints, on a `stage` timeline.
//!
//! Entities: `scan/object_{o}/part_{p}` (points), `primitives/object_{o}/part_{p}` (one box,
//! cylinder, ellipsoid or capsule), `contact_graph/object_{o}` (graph nodes and directed edges;
//! the tree's edges are the kept ones), `contact_edges/object_{o}` (3D lines between part centres),
//! `joints/object_{o}/part_{p}` (an arrow along the axis at the pivot), `refinement/object_{o}`
//! (a text log per step).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicI64, Ordering};

use rerun::RecordingStream;

use super::Observer;
use crate::kinematics::JointKind;
use crate::model::{ContactEdge, PartModel, SceneModel};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::scan::{ObjectId, PartId, Scan};

/// The timeline the stages are logged on.
pub const STAGE_TIMELINE: &str = "stage";

/// Stage numbers on the timeline: scan 0, fitted 1, contact graphs 2, refinement steps from 3,
/// the final scene after them.
const STAGE_SCAN: i64 = 0;
const STAGE_FITTED: i64 = 1;
const STAGE_CONTACT: i64 = 2;
const STAGE_REFINE: i64 = 3;

/// Why a recording could not be started.
#[derive(Debug, thiserror::Error)]
pub enum RerunError {
    #[error("cannot write the Rerun recording {path}: {message}")]
    Save { path: String, message: String },
    #[error(
        "cannot start a Rerun viewer ({message}); is the `rerun` viewer installed (`pip install rerun-sdk` or `cargo install rerun-cli`)?"
    )]
    Spawn { message: String },
}

/// An [`Observer`] that logs to Rerun. Logging errors are reported by the SDK and never stop the
/// pipeline.
pub struct RerunObserver {
    rec: RecordingStream,
    /// The last refinement step logged (steps of all objects share the timeline after `STAGE_REFINE`).
    refine_steps: AtomicI64,
}

impl RerunObserver {
    /// Logs into a `.rrd` file.
    pub fn save(path: &Path) -> Result<Self, RerunError> {
        let rec = rerun::RecordingStreamBuilder::new("partscene")
            .save(path)
            .map_err(|e| RerunError::Save { path: path.display().to_string(), message: e.to_string() })?;
        Ok(Self::new(rec))
    }

    /// Logs to a newly spawned Rerun viewer.
    pub fn spawn() -> Result<Self, RerunError> {
        let rec = rerun::RecordingStreamBuilder::new("partscene").spawn().map_err(|e| RerunError::Spawn { message: e.to_string() })?;
        Ok(Self::new(rec))
    }

    fn new(rec: RecordingStream) -> Self {
        // z up, right-handed, as the whole pipeline.
        let _ = rec.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP());
        Self { rec, refine_steps: AtomicI64::new(0) }
    }

    /// Writes everything out (also done on drop).
    pub fn flush(&self) {
        let _ = self.rec.flush_blocking();
    }

    fn at(&self, stage: i64) {
        self.rec.set_time_sequence(STAGE_TIMELINE, stage);
    }

    fn log_primitives<'a>(&self, object: ObjectId, prims: impl Iterator<Item = (PartId, &'a Primitive)>) {
        for (id, prim) in prims {
            log_primitive(&self.rec, &format!("primitives/object_{object}/part_{id}"), id, prim);
        }
    }
}

fn color(id: PartId) -> rerun::Color {
    rgb(crate::model::part_color(id))
}

/// An sRGB 0..1 colour as Rerun's 8-bit colour.
fn rgb([r, g, b]: [f32; 3]) -> rerun::Color {
    let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    rerun::Color::from_rgb(q(r), q(g), q(b))
}

fn quat(prim: &Primitive) -> rerun::Quaternion {
    let q = prim.world_from_primitive.rotation;
    rerun::Quaternion::from_xyzw([q.x, q.y, q.z, q.w])
}

fn log_primitive(rec: &RecordingStream, path: &str, id: PartId, prim: &Primitive) {
    let c = prim.center().to_array();
    let s = prim.size;
    let result = match prim.kind {
        PrimitiveKind::Cuboid => rec.log(
            path,
            &rerun::Boxes3D::from_centers_and_half_sizes([c], [(0.5 * s).to_array()])
                .with_quaternions([quat(prim)])
                .with_colors([color(id)])
                .with_fill_mode(rerun::FillMode::Solid),
        ),
        PrimitiveKind::Cylinder => rec.log(
            path,
            &rerun::Cylinders3D::from_lengths_and_radii([s.z], [0.5 * s.x])
                .with_centers([c])
                .with_quaternions([quat(prim)])
                .with_colors([color(id)])
                .with_fill_mode(rerun::FillMode::Solid),
        ),
        PrimitiveKind::Sphere => rec.log(
            path,
            &rerun::Ellipsoids3D::from_centers_and_half_sizes([c], [(0.5 * s).to_array()])
                .with_colors([color(id)])
                .with_fill_mode(rerun::FillMode::Solid),
        ),
        PrimitiveKind::Capsule => {
            // Rerun's capsules start at their origin and run along +z.
            let length = (s.z - s.x).max(0.0);
            let start = prim.world_from_primitive.transform_point(crate::math::Vec3::new(0.0, 0.0, -0.5 * length));
            rec.log(
                path,
                &rerun::Capsules3D::from_lengths_and_radii([length], [0.5 * s.x])
                    .with_translations([start.to_array()])
                    .with_quaternions([quat(prim)])
                    .with_colors([color(id)]),
            )
        }
    };
    if let Err(e) = result {
        eprintln!("warning: rerun: cannot log {path}: {e}");
    }
}

impl Observer for RerunObserver {
    fn scan(&self, scan: &Scan) {
        self.at(STAGE_SCAN);
        for part in &scan.parts {
            let points: Vec<[f32; 3]> = part.points.iter().map(glam::Vec3::to_array).collect();
            let path = format!("scan/object_{}/part_{}", part.object, part.id);
            let points = rerun::Points3D::new(points).with_colors([color(part.id)]).with_radii([0.003]);
            if let Err(e) = self.rec.log(path.as_str(), &points) {
                eprintln!("warning: rerun: cannot log {path}: {e}");
            }
        }
    }

    fn fitted(&self, parts: &[PartModel]) {
        self.at(STAGE_FITTED);
        let mut by_object: BTreeMap<ObjectId, Vec<&PartModel>> = BTreeMap::new();
        for p in parts {
            by_object.entry(p.object).or_default().push(p);
        }
        for (object, parts) in by_object {
            self.log_primitives(object, parts.iter().map(|p| (p.id, &p.primitive)));
        }
    }

    fn contact_graph(&self, object: ObjectId, root: PartId, edges: &[ContactEdge]) {
        self.at(STAGE_CONTACT);
        let mut nodes: Vec<PartId> = edges.iter().flat_map(|e| [e.parent, e.child]).chain([root]).collect();
        nodes.sort_unstable();
        nodes.dedup();
        let names: Vec<String> = nodes.iter().map(|n| format!("part_{n}")).collect();
        let path = format!("contact_graph/object_{object}");
        let graph_nodes = rerun::GraphNodes::new(names.clone()).with_labels(names).with_colors(nodes.iter().map(|n| color(*n)));
        let tree: Vec<(String, String)> =
            edges.iter().filter(|e| e.in_tree).map(|e| (format!("part_{}", e.parent), format!("part_{}", e.child))).collect();
        let candidates: Vec<(String, String)> =
            edges.iter().filter(|e| !e.in_tree).map(|e| (format!("part_{}", e.parent), format!("part_{}", e.child))).collect();
        let results = [
            self.rec.log(path.as_str(), &graph_nodes),
            self.rec.log(format!("{path}/tree"), &rerun::GraphEdges::new(tree).with_directed_edges()),
            self.rec.log(format!("{path}/candidates"), &rerun::GraphEdges::new(candidates).with_directed_edges()),
        ];
        for r in results {
            if let Err(e) = r {
                eprintln!("warning: rerun: cannot log {path}: {e}");
            }
        }
    }

    fn refine_step(&self, object: ObjectId, _step: usize, moved: PartId, primitives: &BTreeMap<PartId, Primitive>) {
        let step = self.refine_steps.fetch_add(1, Ordering::Relaxed);
        self.at(STAGE_REFINE + step);
        // The moved part and its subtree may have changed: log the whole object (a few parts).
        self.log_primitives(object, primitives.iter().map(|(id, p)| (*id, p)));
        let _ = self.rec.log(format!("refinement/object_{object}"), &rerun::TextLog::new(format!("aligned part {moved} to its parent")));
    }

    fn scene(&self, scene: &SceneModel) {
        self.at(STAGE_REFINE + self.refine_steps.load(Ordering::Relaxed) + 1);
        for p in &scene.parts {
            log_primitive(&self.rec, &format!("primitives/object_{}/part_{}", p.object, p.id), p.id, &p.primitive);
        }
        let object_of: BTreeMap<PartId, ObjectId> = scene.parts.iter().map(|p| (p.id, p.object)).collect();
        let centre: BTreeMap<PartId, [f32; 3]> = scene.parts.iter().map(|p| (p.id, p.primitive.center().to_array())).collect();
        for j in scene.joints.iter().filter(|j| j.kind != JointKind::Fixed) {
            let object = object_of.get(&j.child).copied().unwrap_or_default();
            let length = scene.part(j.child).map_or(0.3, |p| p.primitive.size.max_element().clamp(0.1, 1.0));
            let color = rgb(crate::model::joint_kind_color(j.kind));
            let arrow = rerun::Arrows3D::from_vectors([(j.axis_world * length).to_array()])
                .with_origins([j.origin_world.to_array()])
                .with_colors([color])
                .with_labels([format!("{} [{:.2}, {:.2}]", j.kind.name(), j.lower, j.upper)]);
            let _ = self.rec.log(format!("joints/object_{object}/part_{}", j.child), &arrow);
        }
        let mut by_object: BTreeMap<ObjectId, Vec<Vec<[f32; 3]>>> = BTreeMap::new();
        for e in &scene.contact_edges {
            let (Some(a), Some(b), Some(o)) = (centre.get(&e.parent), centre.get(&e.child), object_of.get(&e.child)) else { continue };
            by_object.entry(*o).or_default().push(vec![*a, *b]);
        }
        for (object, strips) in by_object {
            let _ = self.rec.log(format!("contact_edges/object_{object}"), &rerun::LineStrips3D::new(strips));
        }
        self.flush();
    }
}
