//! The reality-gap analysis of a 10 s, 100 Hz recording (two joints, effects on both): locate,
//! select, fit, validate. The issue's budget is 2 s in a release build on 2 cores.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};

use partscene::gap::generate::{GenerateConfig, TrueEffect, generate_recording};
use partscene::gap::{GapConfig, analyze, parse_model, parse_recording};

const CABINET: &str = r#"<robot name="cabinet">
  <link name="body"><inertial><mass value="20"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="door"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.02 0.8"/></geometry></collision></link>
  <link name="drawer"><collision><origin xyz="0 0.25 0"/><geometry><box size="0.5 0.5 0.02"/></geometry></collision></link>
  <joint name="door_hinge" type="revolute"><parent link="body"/><child link="door"/><origin xyz="0 -0.01 0.4"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="2.0" effort="10" velocity="3"/></joint>
  <joint name="drawer_slide" type="prismatic"><parent link="body"/><child link="drawer"/><origin xyz="0.3 0.0 0.2"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.45" effort="50" velocity="1"/></joint>
</robot>"#;

fn bench(c: &mut Criterion) {
    let model = parse_model(CABINET, Path::new("cabinet.urdf")).expect("model");
    let cfg = GenerateConfig {
        effects: vec![
            ("door_hinge".into(), TrueEffect::ViscousDamping { damping: 0.3 }),
            ("drawer_slide".into(), TrueEffect::CoulombFriction { friction: 3.0 }),
        ],
        dropout_fraction: 0.02,
        ..GenerateConfig::default()
    };
    let csv = generate_recording(&model, &cfg).expect("recording");
    let rec = parse_recording(&csv, Path::new("bench.csv")).expect("parses");
    let config = GapConfig::default();
    let mut group = c.benchmark_group("gap");
    group.sample_size(10);
    group.bench_function("analyze 10 s @ 100 Hz, 2 joints", |b| b.iter(|| analyze(&model, &rec, &config).expect("analyses")));
    // Two effects on one joint: the selection goes through every pair of kinds.
    let combined = GenerateConfig {
        effects: vec![
            ("door_hinge".into(), TrueEffect::ViscousDamping { damping: 0.2 }),
            ("door_hinge".into(), TrueEffect::Spring { stiffness: 1.0, rest_position: 1.0 }),
        ],
        dropout_fraction: 0.02,
        ..GenerateConfig::default()
    };
    let rec2 = parse_recording(&generate_recording(&model, &combined).expect("recording"), Path::new("bench2.csv")).expect("parses");
    group.bench_function("analyze 10 s @ 100 Hz, damping + spring on one joint", |b| {
        b.iter(|| analyze(&model, &rec2, &config).expect("analyses"));
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
