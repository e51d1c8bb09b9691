//! Watching the pipeline work: every stage reports what it produced to an [`Observer`] (the scan,
//! the fitted primitives, each object's contact graph and tree, every refinement step, the final
//! scene). The core knows only the trait; viewers implement it behind features (`rerun.rs`,
//! feature `rerun`).

use std::collections::BTreeMap;

use crate::model::{ContactEdge, PartModel, SceneModel};
use crate::primitive::Primitive;
use crate::scan::{ObjectId, PartId, Scan};

#[cfg(feature = "rerun")]
pub mod rerun;

/// Receives the pipeline's intermediate results. Calls for different objects may come from
/// different threads, in any order; each call carries what it is about.
pub trait Observer: Sync {
    /// The input scan.
    fn scan(&self, _scan: &Scan) {}
    /// The primitives as fitted, before refinement.
    fn fitted(&self, _parts: &[PartModel]) {}
    /// One object's candidate contact edges (the directed graph) with the tree Edmonds kept
    /// (`in_tree`), rooted at `root`.
    fn contact_graph(&self, _object: ObjectId, _root: PartId, _edges: &[ContactEdge]) {}
    /// One step of refinement (Algorithm 1) on one object: `moved` and its subtree were aligned
    /// to their parent; `primitives` is the whole object after the step.
    fn refine_step(&self, _object: ObjectId, _step: usize, _moved: PartId, _primitives: &BTreeMap<PartId, Primitive>) {}
    /// The finished scene (refined primitives, joints, scene graph).
    fn scene(&self, _scene: &SceneModel) {}
}

/// Observes nothing.
pub struct NoObserver;

impl Observer for NoObserver {}
