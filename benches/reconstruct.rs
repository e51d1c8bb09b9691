//! Reconstruction of a large generated scene (≥ 150 parts, ≥ 500k points), whole and by stage,
//! side by side in one run so the stage shares are ratios of the same machine state.

use criterion::{Criterion, criterion_group, criterion_main};

use partscene::pipeline::{FloorHint, PinnedEdits, PipelineConfig, Quiet, assemble, fit_parts, reconstruct};
use partscene::synth::{ScannerConfig, large_scene, scan};

fn bench(c: &mut Criterion) {
    let truth = large_scene(1, 150);
    let cfg = ScannerConfig { image_width: 160, image_height: 120, ..ScannerConfig::default() };
    let input = scan(&truth, &cfg, 1);
    let parts: usize = input.parts.len();
    let points = input.point_count();
    eprintln!("large scene: {} objects, {parts} parts, {points} points", input.objects.len());
    assert!(parts >= 150 && points >= 500_000, "benchmark scene too small: {parts} parts, {points} points");
    let config = PipelineConfig::default();
    let edits = PinnedEdits::default();
    let mut group = c.benchmark_group("large_scene");
    group.sample_size(10);
    group.bench_function("reconstruct", |b| b.iter(|| reconstruct(&input, &config, &edits, &Quiet)));
    group.bench_function("fit_parts", |b| b.iter(|| fit_parts(&input, &config, &edits, &Quiet)));
    let fitted = fit_parts(&input, &config, &edits, &Quiet);
    let categories = input.objects.iter().map(|(id, o)| (*id, o.category.clone())).collect();
    group.bench_function("assemble (contact, tree, refine, scene, joints)", |b| {
        b.iter(|| assemble(&fitted, &categories, FloorHint::Height(0.0), &config, &edits));
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
