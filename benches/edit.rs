//! The editor's live loop on a large scene (≥ 150 parts): one correction re-runs the relational
//! stages (contact graph, tree, refinement, scene graph, joints) on cached fits, and the 3D view's
//! draw data is rebuilt. Target: an edit within a frame (< 5 ms for 150 parts).

use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};

use partscene::edit::{Document, EditCommand, SceneSource};
use partscene::kinematics::JointKind;
use partscene::pipeline::{PinnedEdits, PipelineConfig, Quiet};
use partscene::synth::{ScannerConfig, large_scene, scan};

fn bench(c: &mut Criterion) {
    let truth = large_scene(1, 150);
    let cfg = ScannerConfig { image_width: 160, image_height: 120, ..ScannerConfig::default() };
    let input = scan(&truth, &cfg, 1);
    let parts = input.parts.len();
    assert!(parts >= 150, "benchmark scene too small: {parts} parts");
    let source = SceneSource::Demo { seed: 1, clean: false };
    let mut doc = Document::from_scan(source, Arc::new(input), PipelineConfig::default(), PinnedEdits::default(), &Quiet);
    let child = doc.model().joints.iter().find(|j| j.kind == JointKind::Revolute).map(|j| j.child).expect("a revolute joint");
    eprintln!("large scene: {parts} parts, {} joints", doc.model().joints.len());
    let mut group = c.benchmark_group("editor");
    group.sample_size(30);
    // Alternate the joint's type so every iteration is a real change and a full re-run.
    let mut fixed = false;
    group.bench_function("edit: change a joint type (re-run contact, tree, refinement, joints)", |b| {
        b.iter(|| {
            fixed = !fixed;
            let kind = if fixed { JointKind::Fixed } else { JointKind::Revolute };
            doc.apply(EditCommand::SetJointKind { child, kind }).expect("edit applies");
        });
    });
    group.bench_function("undo + redo", |b| {
        b.iter(|| {
            doc.undo();
            doc.redo();
        });
    });
    #[cfg(feature = "gui")]
    {
        use partscene::render::{DrawOptions, SceneView, scene_draw_data};
        let motions = std::collections::BTreeMap::new();
        group.bench_function("3D view draw data (primitives, joints, all scan points)", |b| {
            b.iter(|| {
                let view =
                    SceneView { model: doc.model(), scan: Some(doc.scan()), motions: &motions, selected: Some(child), hovered: None };
                scene_draw_data(&view, &DrawOptions::default())
            });
        });
        let no_points = DrawOptions { show_points: false, ..DrawOptions::default() };
        group.bench_function("3D view draw data without points", |b| {
            b.iter(|| {
                let view = SceneView { model: doc.model(), scan: None, motions: &motions, selected: Some(child), hovered: None };
                scene_draw_data(&view, &no_points)
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
