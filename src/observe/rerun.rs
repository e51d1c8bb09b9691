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
    log_primitive_from(rec, path, id, prim, crate::math::Vec3::ZERO);
}

/// [`log_primitive`] in a frame at `origin` (world-aligned): a URDF link's frame.
fn log_primitive_from(rec: &RecordingStream, path: &str, id: PartId, prim: &Primitive, origin: crate::math::Vec3) {
    let c = (prim.center() - origin).to_array();
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
            let start = prim.world_from_primitive.transform_point(crate::math::Vec3::new(0.0, 0.0, -0.5 * length)) - origin;
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
        self.log_urdf(scene);
        self.flush();
    }
}

/// Entity prefix of the URDF's joints: `urdf/joints/<joint>` holds the transform from its parent
/// link's frame to its child link's frame, frames named as the URDF's links (Rerun's convention
/// for URDF: a `.rrd` and `scene.urdf` opened together line up).
pub const URDF_JOINTS: &str = "urdf/joints";
/// Entity prefix of the URDF's links: `urdf/links/<link>`, in the frame named `<link>`, holds the
/// part's primitive.
pub const URDF_LINKS: &str = "urdf/links";
/// Entity prefix of the joint positions of the articulation sweep: `urdf/joint_positions/<joint>`.
pub const URDF_JOINT_POSITIONS: &str = "urdf/joint_positions";
/// The timeline on which every movable joint of the scene sweeps its range and back.
pub const JOINT_TIMELINE: &str = "joint_motion";
/// Steps of the sweep: 0 → upper limit → 0 → lower limit → 0.
pub const SWEEP_STEPS: i64 = 48;
/// The root frame of the URDF, tied to the recording's root entity.
const URDF_ROOT_LINK: &str = "world";

/// A joint's position at `step` of the sweep: at rest (0) at both ends, the upper limit a quarter
/// in, the lower limit three quarters in; a continuous joint turns once.
fn sweep_position(kind: &urdf_rs::JointType, lower: f64, upper: f64, step: i64) -> f64 {
    let phase = step as f64 / SWEEP_STEPS as f64;
    if *kind == urdf_rs::JointType::Continuous {
        return std::f64::consts::TAU * phase;
    }
    let bump = (2.0 * std::f64::consts::PI * phase).sin().powi(2);
    if phase <= 0.5 { upper.max(0.0) * bump } else { lower.min(0.0) * bump }
}

/// The transform of URDF joint `j` at position `q`: its origin (rpy is zero in partscene's URDF:
/// link frames are world-aligned) plus the motion along or about its axis.
fn joint_transform(j: &urdf_rs::Joint, q: f64) -> rerun::Transform3D {
    let o = j.origin.xyz.0;
    let a = glam::DVec3::from_array(j.axis.xyz.0).normalize_or(glam::DVec3::X);
    let (t, r) = match j.joint_type {
        urdf_rs::JointType::Prismatic => (glam::DVec3::from_array(o) + a * q, glam::DQuat::IDENTITY),
        urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => (glam::DVec3::from_array(o), glam::DQuat::from_axis_angle(a, q)),
        _ => (glam::DVec3::from_array(o), glam::DQuat::IDENTITY),
    };
    let t = t.as_vec3();
    let r = r.as_quat();
    rerun::Transform3D::from_translation_rotation(t.to_array(), rerun::Quaternion::from_xyzw([r.x, r.y, r.z, r.w]))
        .with_parent_frame(j.parent.link.as_str())
        .with_child_frame(j.child.link.as_str())
}

impl RerunObserver {
    /// The scene as `scene.urdf` has it: a frame per link (named as the link) holding the part's
    /// primitive, a transform per joint between link frames (static for fixed joints), and every
    /// movable joint swept through its range on [`JOINT_TIMELINE`], with its position as a scalar.
    fn log_urdf(&self, scene: &SceneModel) {
        let robot = crate::export::scene_urdf_robot(scene, &crate::export::UrdfConfig::default());
        let part_of: BTreeMap<String, &PartModel> = scene.parts.iter().map(|p| (crate::export::link_name(scene, p), p)).collect();
        // World position of every link frame: the joints' origins added up from the root.
        let mut origin: BTreeMap<&str, glam::DVec3> = BTreeMap::from([(URDF_ROOT_LINK, glam::DVec3::ZERO)]);
        for _ in 0..=robot.joints.len() {
            for j in &robot.joints {
                if let Some(&at) = origin.get(j.parent.link.as_str()) {
                    origin.insert(j.child.link.as_str(), at + glam::DVec3::from_array(j.origin.xyz.0));
                }
            }
        }
        let log = |path: String, what: &dyn rerun::AsComponents, fixed: bool| {
            let result = if fixed { self.rec.log_static(path.as_str(), what) } else { self.rec.log(path.as_str(), what) };
            if let Err(e) = result {
                eprintln!("warning: rerun: cannot log {path}: {e}");
            }
        };
        // The URDF's root frame is the recording's root entity's frame.
        log(
            format!("{URDF_JOINTS}/{URDF_ROOT_LINK}"),
            &rerun::Transform3D::from_translation([0.0, 0.0, 0.0]).with_parent_frame("tf#/").with_child_frame(URDF_ROOT_LINK),
            true,
        );
        for (link, part) in &part_of {
            let path = format!("{URDF_LINKS}/{link}");
            log(path.clone(), &rerun::CoordinateFrame::new(link.as_str()), true);
            let at = origin.get(link.as_str()).map_or(crate::math::Vec3::ZERO, |o| o.as_vec3());
            // Logged on the scene's stage, like the other primitives.
            log_primitive_from(&self.rec, &path, part.id, &part.primitive, at);
        }
        let movable: Vec<&urdf_rs::Joint> = robot.joints.iter().filter(|j| is_movable(&j.joint_type)).collect();
        for j in robot.joints.iter().filter(|j| !is_movable(&j.joint_type)) {
            log(format!("{URDF_JOINTS}/{}", j.name), &joint_transform(j, 0.0), true);
        }
        for step in 0..=SWEEP_STEPS {
            self.rec.set_time_sequence(JOINT_TIMELINE, step);
            for j in &movable {
                let q = sweep_position(&j.joint_type, j.limit.lower, j.limit.upper, step);
                log(format!("{URDF_JOINTS}/{}", j.name), &joint_transform(j, q), false);
                log(format!("{URDF_JOINT_POSITIONS}/{}", j.name), &rerun::Scalars::single(q), false);
            }
        }
        self.rec.disable_timeline(JOINT_TIMELINE);
    }
}

fn is_movable(kind: &urdf_rs::JointType) -> bool {
    matches!(kind, urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous | urdf_rs::JointType::Prismatic)
}

/// Timeline of a reality-gap recording: the recording's own time, s.
pub const GAP_TIMELINE: &str = "recording_time";
/// Entity prefix of the reality gap: `gap/<joint>/{measured,model,fitted}` (positions),
/// `gap/<joint>/residual/{model,fitted}` (measured − replay) and `gap/<joint>/effects` (text).
pub const GAP_ENTITY: &str = "gap";

impl RerunObserver {
    /// A reality-gap analysis (`partscene gap --rerun`): per joint, the recording, the open-loop
    /// replays of the model as written and of the fitted model, and both residuals, as scalars on
    /// [`GAP_TIMELINE`] (samples not measured or not replayed are left out); the named effects as
    /// text.
    pub fn gap_report(&self, report: &crate::gap::GapReport) {
        for s in &report.series {
            let base = format!("{GAP_ENTITY}/{}", s.joint);
            let series: [(&str, &[f64]); 5] = [
                ("measured", &s.measured),
                ("model", &s.simulated_before),
                ("fitted", &s.simulated_after),
                ("residual/model", &s.residual_before),
                ("residual/fitted", &s.residual_after),
            ];
            for (name, values) in series {
                let (times, kept): (Vec<f64>, Vec<f64>) =
                    s.time_s.iter().zip(values).filter(|(t, v)| t.is_finite() && v.is_finite()).map(|(t, v)| (*t, *v)).unzip();
                if times.is_empty() {
                    continue;
                }
                let path = format!("{base}/{name}");
                let sent = rerun::Scalars::update_fields().with_scalars(kept).columns_of_unit_batches().map(|columns| {
                    self.rec.send_columns(path.as_str(), [rerun::TimeColumn::new_duration_secs(GAP_TIMELINE, times)], columns)
                });
                if let Err(e) = sent.map_err(|e| e.to_string()).and_then(|r| r.map_err(|e| e.to_string())) {
                    eprintln!("warning: rerun: cannot log {path}: {e}");
                }
            }
            let named: Vec<String> = report
                .effects
                .iter()
                .filter(|e| e.joint == s.joint)
                .map(|e| format!("{} (confidence {:.2}): {}", e.kind, e.confidence, e.description))
                .collect();
            let text = if named.is_empty() { "no effect named".to_owned() } else { named.join("\n") };
            if let Err(err) = self.rec.log_static(format!("{base}/effects"), &rerun::TextLog::new(text)) {
                eprintln!("warning: rerun: cannot log {base}/effects: {err}");
            }
        }
        self.flush();
    }
}
