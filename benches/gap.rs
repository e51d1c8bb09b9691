//! The reality-gap analysis of a 10 s, 100 Hz recording (three joints, effects on each): locate,
//! select, fit, validate (issue budget 2 s in a release build on 2 cores); and of a 7-joint arm,
//! 20 s at 200 Hz, efforts recorded (effort space, budget 3 s). The arm's recording is a replay of
//! its own model with friction and damping on every joint (our integrator: speed, not a claim).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};

use std::fmt::Write as _;

use partscene::gap::chain::{ChainInput, replay};
use partscene::gap::generate::{GenerateConfig, TrueEffect, generate_recording};
use partscene::gap::{GapConfig, JointPhysics, analyze, parse_model, parse_recording};

const CABINET: &str = r#"<robot name="cabinet">
  <link name="body"><inertial><mass value="20"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="door"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.02 0.8"/></geometry></collision></link>
  <link name="drawer"><collision><origin xyz="0 0.25 0"/><geometry><box size="0.5 0.5 0.02"/></geometry></collision></link>
  <joint name="door_hinge" type="revolute"><parent link="body"/><child link="door"/><origin xyz="0 -0.01 0.4"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="2.0" effort="10" velocity="3"/></joint>
  <link name="lid"><collision><origin xyz="0 0.2 0"/><geometry><box size="0.6 0.4 0.02"/></geometry></collision></link>
  <joint name="drawer_slide" type="prismatic"><parent link="body"/><child link="drawer"/><origin xyz="0.3 0.0 0.2"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.45" effort="50" velocity="1"/></joint>
  <joint name="lid_hinge" type="revolute"><parent link="body"/><child link="lid"/><origin xyz="0.3 0.0 0.85"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="1.6" effort="10" velocity="3"/></joint>
</robot>"#;

/// A 7-joint serial arm, axes alternating z / y, links 0.3 m.
fn arm_urdf() -> String {
    let mut s = String::from("<robot name=\"arm\"><link name=\"l0\"/>");
    for i in 1..=7 {
        let m = 3.0 - 0.3 * f64::from(i);
        let _ = write!(
            s,
            "<link name=\"l{i}\"><inertial><origin xyz=\"0 0 0.15\"/><mass value=\"{m}\"/>\
             <inertia ixx=\"0.03\" iyy=\"0.03\" izz=\"0.005\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\
             <joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/><origin xyz=\"0 0 {}\"/>\
             <axis xyz=\"0 {} {}\"/><limit lower=\"-6\" upper=\"6\" effort=\"100\" velocity=\"10\"/></joint>",
            i - 1,
            if i == 1 { 0.0 } else { 0.3 },
            i % 2,
            1 - i % 2
        );
    }
    s.push_str("</robot>");
    s
}

/// 20 s at 200 Hz of the arm driven by multisine efforts, friction and damping on every joint.
fn arm_recording(model: &partscene::gap::GapModel) -> String {
    let (tree, _) = model.multibody().expect("tree");
    let n = 4000;
    let time: Vec<f64> = (0..n).map(|i| i as f64 * 0.005).collect();
    let effort: Vec<Vec<f64>> = (0..7)
        .map(|d| time.iter().map(|t| 2.0 * ((1.3 + 0.4 * f64::from(d)) * t).sin() + 1.0 * ((3.1 + 0.7 * f64::from(d)) * t).cos()).collect())
        .collect();
    let physics: Vec<JointPhysics> = model
        .dofs()
        .into_iter()
        .map(|j| {
            let mut p = JointPhysics::nominal(&model.joints[j]);
            (p.friction, p.damping) = (0.3, 0.5);
            p
        })
        .collect();
    let input = ChainInput { time_s: &time, effort: &effort, gravity: glam::DVec3::ZERO };
    let q = replay(&tree, &physics, &input, &[0.0; 7], &[0.0; 7]);
    let mut csv = String::from("# gravity: 0 0 0\ntime");
    for d in 1..=7 {
        let _ = write!(csv, ",j{d}.q,j{d}.effort");
    }
    for i in 0..n {
        let _ = write!(csv, "\n{:.4}", time[i]);
        for d in 0..7 {
            let _ = write!(csv, ",{:.6},{:.5}", q[d][i], effort[d][i]);
        }
    }
    csv.push('\n');
    csv
}

fn bench(c: &mut Criterion) {
    let model = parse_model(CABINET, Path::new("cabinet.urdf")).expect("model");
    let cfg = GenerateConfig {
        effects: vec![
            ("door_hinge".into(), TrueEffect::ViscousDamping { damping: 0.3 }),
            ("drawer_slide".into(), TrueEffect::CoulombFriction { friction: 3.0 }),
            ("lid_hinge".into(), TrueEffect::ViscousDamping { damping: 0.2 }),
        ],
        dropout_fraction: 0.02,
        ..GenerateConfig::default()
    };
    let csv = generate_recording(&model, &cfg).expect("recording");
    let rec = parse_recording(&csv, Path::new("bench.csv")).expect("parses");
    let config = GapConfig::default();
    let mut group = c.benchmark_group("gap");
    group.sample_size(10);
    group.bench_function("analyze 10 s @ 100 Hz, 3 joints", |b| b.iter(|| analyze(&model, &rec, &config).expect("analyses")));
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
    let arm = parse_model(&arm_urdf(), Path::new("arm.urdf")).expect("arm");
    let rec3 = parse_recording(&arm_recording(&arm), Path::new("arm.csv")).expect("parses");
    group.bench_function("analyze 20 s @ 200 Hz, 7-joint arm, efforts recorded", |b| {
        b.iter(|| analyze(&arm, &rec3, &config).expect("analyses"));
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
