//! partscene: part-level interactive scene reconstruction from part-segmented 3D scans
//! (Part-level Scene Reconstruction Affords Robot Interaction, IROS 2023).
//!
//! Data flows one way: scan → parts → primitives → contact graph → tree → joints → refined
//! scene → exports. See `ARCHITECTURE.md` for the module map and invariants.

#[cfg(feature = "gui")]
pub mod app;
pub mod assets;
pub mod batch;
pub mod bench;
pub mod contact;
pub mod dynamics;
pub mod edit;
pub mod eval;
pub mod export;
pub mod fit;
pub mod gap;
pub mod import;
pub mod io;
pub mod kinematics;
pub mod linalg;
pub mod math;
pub mod model;
pub mod observe;
pub mod pipeline;
pub mod polygon;
pub mod primitive;
pub mod refine;
#[cfg(feature = "gui")]
pub mod render;
pub mod report;
pub mod scan;
pub mod scene;
pub mod synth;
pub mod tree;
pub mod truth;
#[cfg(all(feature = "gui", target_arch = "wasm32"))]
pub mod web;
