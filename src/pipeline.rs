//! The whole method, stage by stage: fit every part (parallel), then per object the contact
//! graph, Edmonds' tree and the top-down refinement, then the scene graph (support, proximity,
//! object poses), then joints from labels and the final geometry.
//!
//! Editor corrections are data ([`PinnedEdits`]) passed in, so re-running the pipeline keeps
//! them and tests replay them without a GUI. [`assemble`] re-runs everything after fitting; it is
//! what the editor calls on every edit.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::fit::{FitConfig, fit_part, point_span};
use crate::kinematics::evidence::CONF_PINNED;
use crate::kinematics::{
    Joint, JointContext, JointEvidence, JointKind, JointSpec, KinematicsConfig, Template, Vocabulary, decide, fit_joint,
    hinge_edge_evidence, parent_confidence,
};
use crate::math::Vec3;
use crate::model::{ContactEdge, ObjectModel, PartModel, SceneModel};
use crate::observe::{NoObserver, Observer};
use crate::primitive::{Primitive, PrimitiveKind};
use crate::refine::{RefineConfig, RefineStats, refine_object_observed};
use crate::report::Warning;
use crate::scan::{ObjectId, PartId, Scan, ScanPart};
use crate::scene::{SceneConfig, SceneObject, build_scene, estimate_floor};
use crate::tree::{PartTree, TreeConfig, TreePart, build_part_tree, root_preference};

/// Every threshold of the method in one place.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PipelineConfig {
    pub fit: FitConfig,
    pub tree: TreeConfig,
    pub refine: RefineConfig,
    pub kinematics: KinematicsConfig,
    pub scene: SceneConfig,
    /// The part vocabulary (`assets/vocabulary.toml`, `--vocab FILE`).
    pub vocabulary: std::sync::Arc<Vocabulary>,
}

/// Corrections pinned by a person; every run of the pipeline honours them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PinnedEdits {
    /// child → parent.
    pub parent: BTreeMap<PartId, PartId>,
    pub joint_kind: BTreeMap<PartId, JointKind>,
    pub primitive_kind: BTreeMap<PartId, PrimitiveKind>,
    /// Joint axis (world), keyed by child part.
    pub axis: BTreeMap<PartId, Vec3>,
    /// Joint limits (lower, upper), keyed by child part.
    pub limits: BTreeMap<PartId, (f32, f32)>,
    /// The edge a person chose for a door's or lid's hinge, keyed by the door: a world direction
    /// from the part's centre towards that edge.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub hinge_edge: BTreeMap<PartId, Vec3>,
}

/// Progress reporting for long stages (the CLI draws bars, the editor a spinner).
pub trait Progress: Sync {
    fn update(&self, stage: &str, done: usize, total: usize);
}

/// No progress reporting.
pub struct Quiet;

impl Progress for Quiet {
    fn update(&self, _stage: &str, _done: usize, _total: usize) {}
}

/// Fitted parts before the relational stages (the expensive, cacheable half of the pipeline).
#[derive(Clone, Debug, Default)]
pub struct FittedParts {
    pub parts: Vec<PartModel>,
    /// Parts that could not be fitted (each also has a warning).
    pub skipped: Vec<PartId>,
    pub warnings: Vec<Warning>,
}

/// Fits a primitive to every part, in parallel; parts that cannot be fitted are reported and
/// left out.
#[must_use]
pub fn fit_parts(scan: &Scan, cfg: &PipelineConfig, edits: &PinnedEdits, progress: &dyn Progress) -> FittedParts {
    let total = scan.parts.len();
    let done = AtomicUsize::new(0);
    let results: Vec<Result<PartModel, (PartId, Warning)>> = scan
        .parts
        .par_iter()
        .map(|part| {
            let r = fit_part_model(part, cfg, edits.primitive_kind.get(&part.id).copied());
            progress.update("fit", done.fetch_add(1, Ordering::Relaxed) + 1, total);
            r.map_err(|w| (part.id, w))
        })
        .collect();
    let mut out = FittedParts::default();
    for r in results {
        match r {
            Ok(p) => out.parts.push(p),
            Err((id, w)) => {
                out.skipped.push(id);
                out.warnings.push(w);
            }
        }
    }
    coalign_parts(scan, &mut out.parts, edits, &cfg.vocabulary);
    // Where each part's points end, once, along its final primitive.
    out.parts.par_iter_mut().for_each(|p| {
        p.points_span = scan.part(p.id).and_then(|s| point_span(&s.points, &p.primitive));
    });
    out
}

/// Fits one part on its own: with `forced` the kind a person pinned, else the best kind under the
/// label shape prior. (Co-alignment within the object is left to [`fit_parts`].)
pub fn fit_one_part(part: &ScanPart, cfg: &PipelineConfig, forced: Option<PrimitiveKind>) -> Result<PartModel, Warning> {
    let model = fit_part_model(part, cfg, forced)?;
    Ok(PartModel { points_span: point_span(&part.points, &model.primitive), ..model })
}

/// [`fit_one_part`] without the points' span (the caller measures it on the final primitive).
fn fit_part_model(part: &ScanPart, cfg: &PipelineConfig, forced: Option<PrimitiveKind>) -> Result<PartModel, Warning> {
    let fit = fit_part(&part.points, &cfg.fit, forced)
        .map(|fit| if forced.is_none() { prefer_box_for_boards(&cfg.vocabulary, &part.label, &part.points, fit) } else { fit })
        .map_err(|e| Warning::new("fit", format!("part {}", part.id), format!("{e}; part left out")))?;
    Ok(PartModel {
        id: part.id,
        object: part.object,
        label: part.label.clone(),
        primitive: fit.primitive,
        fit_error: fit.fit_error,
        point_count: part.points.len(),
        points_span: None,
    })
}

/// Co-alignment, a Manhattan prior within each object: a part whose box axes lie within 45° of
/// its object's base part (body, frame, top; else the largest part) is re-fitted with the base's
/// axes, and the result is kept when its fit error grows by at most 20 % (or 1 mm). Small parts
/// such as handles have a near-square cross-section whose roll the points barely determine; left
/// as fitted, their faces miss the Align test (θa) against the part they are mounted on.
fn coalign_parts(scan: &Scan, parts: &mut [PartModel], edits: &PinnedEdits, vocab: &Vocabulary) {
    // Base parts first: furniture stands upright.
    parts.par_iter_mut().for_each(|p| {
        if !vocab.is_base(&p.label) || p.primitive.kind != PrimitiveKind::Cuboid || edits.primitive_kind.contains_key(&p.id) {
            return;
        }
        let Some(points) = scan.part(p.id).map(|s| s.points.as_slice()) else { return };
        if let Some((prim, err)) = upright_refit(points, &p.primitive, p.fit_error) {
            p.primitive = prim;
            p.fit_error = err;
        }
    });
    // The reference of each object: its most base-like part (the tree's preferred root).
    let mut reference: BTreeMap<ObjectId, ((bool, f32), PartId, Primitive)> = BTreeMap::new();
    for p in parts.iter() {
        let pref = root_preference(vocab, &p.label, &p.primitive);
        if reference.get(&p.object).is_none_or(|r| pref > r.0) {
            reference.insert(p.object, (pref, p.id, p.primitive));
        }
    }
    parts.par_iter_mut().for_each(|p| {
        let Some(&(_, ref_id, ref_prim)) = reference.get(&p.object) else { return };
        if ref_id == p.id || p.primitive.kind == PrimitiveKind::Sphere || edits.primitive_kind.contains_key(&p.id) {
            return;
        }
        let Some(points) = scan.part(p.id).map(|s| s.points.as_slice()) else { return };
        if let Some((prim, err)) = coalign(points, &p.primitive, &ref_prim, p.fit_error) {
            p.primitive = prim;
            p.fit_error = err;
        }
    });
}

/// An upright prior for the parts furniture is built on (body, base, frame, top): when the fit is
/// tilted by more than 3°, the part is re-fitted as a box with a vertical axis (minimum-area
/// footprint rectangle, robust extents), kept when its fit error stays within 1.5× (or +2 mm).
/// A fridge body seen only through the margins around its doors is otherwise free to tilt, and
/// a tilted base misplaces every hinge and drawer axis derived from it.
fn upright_refit(points: &[Vec3], fitted: &Primitive, err_before: f32) -> Option<(Primitive, f32)> {
    let tilt = fitted.axes_world().iter().map(|a| a.dot(crate::math::UP).abs()).fold(0.0_f32, f32::max);
    if tilt > 3.0_f32.to_radians().cos() || points.len() < 10 {
        return None;
    }
    let step = (points.len() / 4000).max(1);
    let sample: Vec<Vec3> = points.iter().step_by(step).copied().collect();
    let hull = crate::polygon::convex_hull(sample.iter().map(|p| p.truncate()).collect());
    let u = crate::polygon::min_area_rect_dir(&hull, 1e-3);
    let (ux, uy) = (Vec3::new(u.x, u.y, 0.0), Vec3::new(-u.y, u.x, 0.0));
    // Robust extents (0.5 % trimmed on each side) along (u, v, up).
    let mut coords: [Vec<f32>; 3] = [Vec::new(), Vec::new(), Vec::new()];
    for p in &sample {
        coords[0].push(p.dot(ux));
        coords[1].push(p.dot(uy));
        coords[2].push(p.z);
    }
    let mut lo = [0.0_f32; 3];
    let mut hi = [0.0_f32; 3];
    for (k, c) in coords.iter_mut().enumerate() {
        c.sort_by(f32::total_cmp);
        let n = c.len();
        lo[k] = c[n / 200];
        hi[k] = c[n - 1 - n / 200];
    }
    let mid = Vec3::new(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    let center = ux * mid.x + uy * mid.y + Vec3::Z * mid.z;
    let size = Vec3::new(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    let rotation = crate::math::Quat::from_mat3(&glam::Mat3::from_cols(ux, uy, Vec3::Z));
    let candidate = Primitive::new(PrimitiveKind::Cuboid, size, crate::math::Pose::from_parts(center, rotation));
    let err_after = candidate.mean_surface_distance(points, 4000);
    (err_after <= (err_before * 1.5).max(err_before + 0.002)).then_some((candidate, err_after))
}

/// Re-fits `fitted` with its axes snapped onto `reference`'s; `None` when the axes are not within
/// 45° of a permutation of the reference's or the fit gets worse.
fn coalign(points: &[Vec3], fitted: &Primitive, reference: &Primitive, err_before: f32) -> Option<(Primitive, f32)> {
    const COS_45: f32 = 0.707;
    let rot = crate::refine::aligning_rotation(reference, fitted, COS_45)?;
    let snapped_rot = (rot * fitted.rotation()).normalize();
    // A proper snap maps all three axes onto reference axes.
    let ref_axes = reference.axes_world();
    let aligned = |v: Vec3| ref_axes.iter().any(|a| a.dot(v).abs() > 0.9999);
    let axes = [snapped_rot * Vec3::X, snapped_rot * Vec3::Y, snapped_rot * Vec3::Z];
    if !axes.iter().all(|a| aligned(*a)) || rot.angle_between(crate::math::Quat::IDENTITY) < 1e-5 {
        return None;
    }
    // Same size and centre, snapped rotation; then a few translation-only ICP steps (rotation and
    // size held) so the faces sit on the points again.
    let step = (points.len() / 2000).max(1);
    let sample: Vec<Vec3> = points.iter().step_by(step).copied().collect();
    let mut candidate = Primitive::new(fitted.kind, fitted.size, crate::math::Pose::from_parts(fitted.center(), snapped_rot));
    for _ in 0..5 {
        let mut residuals: Vec<Vec3> = sample.iter().map(|p| *p - candidate.closest_surface_point(*p)).collect();
        residuals.sort_by(|a, b| a.length_squared().total_cmp(&b.length_squared()));
        residuals.truncate((residuals.len() * 9 / 10).max(1));
        let shift = residuals.iter().copied().sum::<Vec3>() / residuals.len() as f32;
        candidate.world_from_primitive.translation += shift;
        if shift.length() < 1e-5 {
            break;
        }
    }
    let err_after = candidate.mean_surface_distance(points, 4000);
    (err_after <= (err_before * 1.2).max(err_before + 0.001)).then_some((candidate, err_after))
}

/// A label shape prior: parts whose label names a board or a box keep the cuboid candidate unless
/// another kind scores clearly better (by more than 25 %). A cabinet body seen only through the
/// margins around its drawers is a thin frame of points that a cylinder can fit about as well.
fn prefer_box_for_boards(vocab: &Vocabulary, label: &str, points: &[Vec3], fit: crate::fit::PartFit) -> crate::fit::PartFit {
    if fit.primitive.kind == PrimitiveKind::Cuboid || !vocab.prefers_box(label) {
        return fit;
    }
    let Some(cuboid) =
        fit.candidates.iter().filter(|c| c.primitive.kind == PrimitiveKind::Cuboid).min_by(|a, b| a.score.total_cmp(&b.score))
    else {
        return fit;
    };
    if cuboid.score > fit.score * 1.25 {
        return fit;
    }
    let fit_error = cuboid.primitive.mean_surface_distance(points, 4000);
    crate::fit::PartFit { primitive: cuboid.primitive, fit_error, score: cuboid.score, candidates: fit.candidates }
}

/// Runs the whole pipeline on a scan.
#[must_use]
pub fn reconstruct(scan: &Scan, cfg: &PipelineConfig, edits: &PinnedEdits, progress: &dyn Progress) -> SceneModel {
    reconstruct_observed(scan, cfg, edits, progress, &NoObserver)
}

/// [`reconstruct`], reporting every stage to `observer`.
#[must_use]
pub fn reconstruct_observed(
    scan: &Scan,
    cfg: &PipelineConfig,
    edits: &PinnedEdits,
    progress: &dyn Progress,
    observer: &dyn Observer,
) -> SceneModel {
    observer.scan(scan);
    let fitted = fit_parts(scan, cfg, edits, progress);
    observer.fitted(&fitted.parts);
    let categories: BTreeMap<ObjectId, String> = scan.objects.iter().map(|(id, o)| (*id, o.category.clone())).collect();
    let floor_hint = FloorHint::Points(&scan.background);
    let mut scene = assemble_observed(&fitted, &categories, floor_hint, cfg, edits, observer).0;
    scene.source.clone_from(&scan.source);
    observer.scene(&scene);
    scene
}

/// Where the floor is: estimated from background points, or known.
#[derive(Clone, Copy, Debug)]
pub enum FloorHint<'a> {
    Points(&'a [Vec3]),
    Height(f32),
}

/// One object after its contact graph, tree and refinement.
type ObjectStage = (ObjectId, PartTree, BTreeMap<PartId, Primitive>, RefineStats, Vec<Warning>);

/// Everything after fitting: contact graph, tree, refinement, scene graph, joints.
/// Returns the scene and what refinement changed.
#[must_use]
pub fn assemble(
    fitted: &FittedParts,
    categories: &BTreeMap<ObjectId, String>,
    floor: FloorHint<'_>,
    cfg: &PipelineConfig,
    edits: &PinnedEdits,
) -> (SceneModel, RefineStats) {
    assemble_observed(fitted, categories, floor, cfg, edits, &NoObserver)
}

/// [`assemble`], reporting each object's contact graph and refinement steps to `observer`.
#[must_use]
pub fn assemble_observed(
    fitted: &FittedParts,
    categories: &BTreeMap<ObjectId, String>,
    floor: FloorHint<'_>,
    cfg: &PipelineConfig,
    edits: &PinnedEdits,
    observer: &dyn Observer,
) -> (SceneModel, RefineStats) {
    let mut warnings = fitted.warnings.clone();
    let mut by_object: BTreeMap<ObjectId, Vec<&PartModel>> = BTreeMap::new();
    for p in &fitted.parts {
        by_object.entry(p.object).or_default().push(p);
    }
    // Per object: contact graph → tree → refinement (parallel over objects, in order).
    let per_object: Vec<ObjectStage> = by_object
        .par_iter()
        .map(|(&obj, parts)| {
            let view: Vec<TreePart> = parts.iter().map(|p| TreePart { id: p.id, label: &p.label, primitive: &p.primitive }).collect();
            let (tree, w) = build_part_tree(&view, &cfg.tree, &cfg.vocabulary, &edits.parent);
            observer.contact_graph(obj, tree.root, &tree.edges);
            let mut prims: BTreeMap<PartId, Primitive> = parts.iter().map(|p| (p.id, p.primitive)).collect();
            let mut step = 0;
            let stats = refine_object_observed(&mut prims, &tree, &cfg.refine, &cfg.tree.contact, &mut |moved, now| {
                observer.refine_step(obj, step, moved, now);
                step += 1;
            });
            (obj, tree, prims, stats, w)
        })
        .collect();
    let mut stats = RefineStats::default();
    let mut trees = BTreeMap::new();
    let mut scene_objects = Vec::new();
    let mut contact_edges: Vec<ContactEdge> = Vec::new();
    for (obj, tree, prims, s, w) in per_object {
        stats.merge(s);
        warnings.extend(w);
        contact_edges.extend(tree.edges.iter().copied());
        scene_objects.push(SceneObject { id: obj, root_part: tree.root, parts: prims.into_iter().collect() });
        trees.insert(obj, tree);
    }
    // Scene graph: floor, support, proximity, object poses.
    let floor_z = match floor {
        FloorHint::Points(points) => estimate_floor(points, &scene_objects),
        FloorHint::Height(z) => z,
    };
    let (graph, w) = build_scene(&mut scene_objects, floor_z, &cfg.scene);
    warnings.extend(w);
    // Final geometry, then joints from it.
    let mut final_prims: BTreeMap<PartId, Primitive> = BTreeMap::new();
    for o in &scene_objects {
        final_prims.extend(o.parts.iter().copied());
    }
    let fitted_parts: BTreeMap<PartId, &PartModel> = fitted.parts.iter().map(|p| (p.id, p)).collect();
    let mut joints = Vec::new();
    let mut evidence = Vec::new();
    for (obj, tree) in &trees {
        let category = categories.get(obj).map_or("", String::as_str);
        for (&child, &parent) in &tree.parent {
            let (joint, why) = make_joint(tree, (parent, child), category, &final_prims, &fitted_parts, cfg, edits);
            joints.push(joint);
            evidence.push(why);
        }
    }
    joints.sort_by_key(|j| j.child);
    evidence.sort_by_key(|e| e.child);
    let mut parts: Vec<PartModel> =
        fitted.parts.iter().map(|p| PartModel { primitive: final_prims.get(&p.id).copied().unwrap_or(p.primitive), ..p.clone() }).collect();
    parts.sort_by_key(|p| p.id);
    let objects = scene_objects
        .iter()
        .map(|o| ObjectModel {
            id: o.id,
            category: categories.get(&o.id).cloned().unwrap_or_else(|| "object".to_owned()),
            root_part: o.root_part,
            supported_by_part: graph.support.get(&o.id).copied().flatten(),
        })
        .collect();
    contact_edges.sort_by_key(|e| (e.parent, e.child));
    let scene = SceneModel {
        source: String::new(),
        parts,
        joints,
        evidence,
        contact_edges,
        objects,
        relations: graph.relations,
        floor_z,
        warnings,
        skipped_parts: fitted.skipped.clone(),
    };
    (scene, stats)
}

/// How far behind a door's box its pin must stand, because the door's points reach there, for
/// the evidence to say so (below it: the box's own fit noise).
const PIN_PAST_BOX_NOTED_M: f32 = 0.005;

fn make_joint(
    tree: &PartTree,
    (parent, child): (PartId, PartId),
    category: &str,
    prims: &BTreeMap<PartId, Primitive>,
    fitted: &BTreeMap<PartId, &PartModel>,
    cfg: &PipelineConfig,
    edits: &PinnedEdits,
) -> (Joint, JointEvidence) {
    let vocab = cfg.vocabulary.as_ref();
    let label_of = |id: &PartId| fitted.get(id).map(|p| p.label.as_str());
    let label = label_of(&child).unwrap_or("");
    // A handle mounted on the child tells the front; a handle, knob or latch the side that opens.
    let mounted = |grip_only: bool| {
        tree.children(child)
            .into_iter()
            .find(|c| label_of(c).is_some_and(|l| if grip_only { vocab.is_grip(l) } else { vocab.marks_free_edge(l) }))
            .and_then(|c| prims.get(&c))
            .map(Primitive::center)
    };
    let (Some(pp), Some(cp)) = (prims.get(&parent), prims.get(&child)) else {
        let joint = Joint { parent, child, kind: JointKind::Fixed, axis_world: Vec3::X, origin_world: Vec3::ZERO, lower: 0.0, upper: 0.0 };
        return (joint, JointEvidence { child, label_rule: "a part without geometry: fixed".into(), ..JointEvidence::default() });
    };
    // Every part of the object is the root or has a parent in its tree.
    let object_parts: Vec<(&Primitive, &str)> = std::iter::once(tree.root)
        .chain(tree.parent.keys().copied())
        .filter(|&id| id != child && id != parent)
        .filter_map(|id| Some((prims.get(&id)?, label_of(&id).unwrap_or(""))))
        .collect();
    let ctx = JointContext { label, category, parent: pp, child: cp, grip: mounted(true), others: object_parts };
    let mut decision = decide(vocab, &ctx);
    decision.evidence.child = child;
    if let Some(&pinned) = edits.joint_kind.get(&child) {
        decision.kind = pinned;
        decision.evidence.template = vocab.classify_in(label, category).map_or(Template::default_for(pinned), |m| m.class.template(pinned));
        decision.evidence.tests.push(format!("type pinned by a person: {}", pinned.name()));
        decision.evidence.type_confidence = CONF_PINNED;
    }
    // The parent face the child is mounted on (same face index on the refined primitive).
    let mount_normal = decision.front.or_else(|| {
        tree.contacts.get(&(parent, child)).and_then(|c| crate::contact::surface_planes(pp).get(c.parent_face).map(|f| f.normal))
    });
    let spec = JointSpec {
        kind: decision.kind,
        template: decision.evidence.template,
        handle: mounted(false),
        mount_normal,
        axis_line: decision.axis_line,
        hinge_edge_world: edits.hinge_edge.get(&child).copied(),
        child_span: fitted.get(&child).and_then(|p| p.points_span),
    };
    let (mut joint, hinge) = fit_joint(parent, pp, child, cp, &spec, &cfg.kinematics);
    if let Some(axis) = edits.axis.get(&child) {
        joint.axis_world = axis.normalize_or(joint.axis_world);
    }
    if let Some(&(lo, hi)) = edits.limits.get(&child) {
        joint.lower = lo;
        joint.upper = hi;
    }
    let mut evidence = decision.evidence;
    let (parent_rule, parent_conf) = parent_evidence(tree, parent, child, edits.parent.contains_key(&child));
    evidence.parent_rule = parent_rule;
    evidence.parent_confidence = parent_conf;
    if let Some(placement) = hinge {
        (evidence.axis_rule, evidence.axis_confidence) = hinge_edge_evidence(placement.edge);
        if placement.past_box_m >= PIN_PAST_BOX_NOTED_M {
            evidence.tests.push(format!(
                "pin at the back of the part's points, {:.1} cm behind its box (the box stops short of the part's material: a grip in its mesh?)",
                100.0 * placement.past_box_m
            ));
        }
    }
    evidence.confidence = evidence.type_confidence * parent_conf * evidence.axis_confidence;
    (joint, evidence)
}

/// Why `parent` was chosen for `child`, and the parent confidence ([`parent_confidence`]).
fn parent_evidence(tree: &PartTree, parent: PartId, child: PartId, pinned: bool) -> (String, f32) {
    let weight_of = |p: PartId| tree.edges.iter().find(|e| e.parent == p && e.child == child).map(|e| e.weight);
    let chosen = weight_of(parent);
    let runner_up = tree
        .edges
        .iter()
        .filter(|e| e.child == child && e.parent != parent)
        .max_by(|a, b| a.weight.total_cmp(&b.weight).then(b.parent.cmp(&a.parent)));
    let conf = parent_confidence(chosen, runner_up.map(|e| e.weight), pinned);
    let rule = if pinned {
        format!("parent {parent} pinned by a person")
    } else {
        match (chosen, runner_up) {
            (None, _) => format!("touches no part: hung off the nearest part {parent}"),
            (Some(w), None) => format!("contact with part {parent} (weight {w:.2}); no other part touches it"),
            (Some(w), Some(e)) => format!("contact with part {parent} (weight {w:.2}) over part {} (weight {:.2})", e.parent, e.weight),
        }
    };
    (rule, conf)
}
