//! The reality gap end to end: recordings with concealed effects from `gap::generate` (RK4 with
//! event location, geometric axis tilt — different physics code from the fitter) drive the
//! analysis; each case states the joint, the kinds and the parameters it must find. Also reader
//! errors with line and column, the written outputs, and (feature `sim`) the fitter's integrator
//! against rapier3d.

use std::path::Path;

use partscene::gap::generate::{GenerateConfig, TrueEffect, generate_recording};
use partscene::gap::{GapConfig, GapError, GapModel, analyze, parse_model, parse_recording, write_outputs};

const CABINET: &str = r#"<robot name="cabinet">
  <link name="body"><inertial><mass value="20"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.3 0.3 0.4"/><geometry><box size="0.6 0.6 0.8"/></geometry></collision></link>
  <link name="door"><inertial><origin xyz="0.3 0 0"/><mass value="4"/>
    <inertia ixx="0.2134" iyy="0.3334" izz="0.1201" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.02 0.8"/></geometry></collision></link>
  <link name="drawer"><collision><origin xyz="0 0.25 0"/><geometry><box size="0.5 0.5 0.02"/></geometry></collision></link>
  <joint name="door_hinge" type="revolute"><parent link="body"/><child link="door"/><origin xyz="0 -0.01 0.4"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="2.0" effort="10" velocity="3"/></joint>
  <joint name="drawer_slide" type="prismatic"><parent link="body"/><child link="drawer"/><origin xyz="0.3 0.0 0.2"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.45" effort="50" velocity="1"/></joint>
</robot>"#;

struct Case {
    name: &'static str,
    effects: Vec<(&'static str, TrueEffect)>,
    noise: f64,
    dropouts: f64,
    irregular: bool,
    pose_only: bool,
    seed: u64,
}

impl Case {
    fn new(name: &'static str, effects: Vec<(&'static str, TrueEffect)>) -> Self {
        Self {
            name,
            effects,
            noise: 0.001,
            dropouts: 0.03,
            irregular: false,
            pose_only: false,
            seed: std::env::var("GAP_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(7),
        }
    }
}

/// (joint, kind, [(param, true value)]): what must be found; empty = nothing.
type Expected = Vec<(&'static str, &'static str, Vec<(&'static str, f64)>)>;

fn model() -> GapModel {
    parse_model(CABINET, Path::new("cabinet.urdf")).expect("model parses")
}

fn check(case: &Case, expected: &Expected) {
    let model = model();
    let cfg = GenerateConfig {
        noise: case.noise,
        dropout_fraction: case.dropouts,
        irregular: case.irregular,
        pose_only: case.pose_only,
        seed: case.seed,
        effects: case.effects.iter().map(|(j, e)| ((*j).to_owned(), *e)).collect(),
        ..GenerateConfig::default()
    };
    let csv = generate_recording(&model, &cfg).expect("generates");
    let rec = parse_recording(&csv, Path::new("gen.csv")).expect("generated recording parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let found: Vec<String> =
        report.effects.iter().map(|e| format!("{}:{} {:?} c={:.2}", e.joint, e.kind, e.params, e.confidence)).collect();
    for (joint, pair) in &report.held_out.per_joint {
        eprintln!(
            "FIGURES {} | {joint}: held-out rmse {:.5} -> {:.5} ({:.1}x), all {:.5} -> {:.5} | found {found:?}",
            case.name,
            pair.rmse_before,
            pair.rmse_after,
            pair.rmse_before / pair.rmse_after.max(1e-12),
            report.fit.per_joint[joint].rmse_before,
            report.fit.per_joint[joint].rmse_after
        );
    }
    for m in &report.mismatches {
        eprintln!(
            "MISMATCH {} | {} {:.2}-{:.2} rmse {:.5} sigma {:.5}: {}",
            case.name, m.joint, m.t_start, m.t_end, m.rmse, report.noise_sigma[&m.joint], m.description
        );
    }
    if expected.is_empty() {
        assert!(report.effects.is_empty(), "{}: null case found {found:?}", case.name);
        assert!(report.mismatches.is_empty(), "{}: null case has mismatches {:?}", case.name, report.mismatches);
        return;
    }
    assert_eq!(report.effects.len(), expected.len(), "{}: found {found:?}", case.name);
    for (joint, kind, params) in expected {
        let Some(e) = report.effects.iter().find(|e| e.joint == *joint && e.kind == *kind) else {
            panic!("{}: no {kind} on {joint}; found {found:?}", case.name);
        };
        for (name, truth) in params {
            let got = e.params[*name];
            let err = (got - truth).abs() / truth.abs();
            eprintln!("FIGURES {} | {joint} {kind}.{name}: true {truth} fitted {got:.4} (error {:.1} %)", case.name, 100.0 * err);
            assert!(err <= 0.25, "{}: {kind}.{name} = {got}, true {truth}", case.name);
        }
        let held = report.held_out.per_joint[*joint];
        assert!(held.rmse_before >= 5.0 * held.rmse_after, "{}: held-out rmse {} -> {}", case.name, held.rmse_before, held.rmse_after);
        assert!(report.mismatches.iter().any(|m| m.joint == *joint), "{}: no mismatch located on {joint}", case.name);
    }
    for joint in report.held_out.per_joint.keys() {
        if !expected.iter().any(|(j, _, _)| j == joint) {
            assert!(!report.effects.iter().any(|e| e.joint == *joint), "{}: effect on clean joint {joint}: {found:?}", case.name);
        }
    }
}

#[test]
fn null_case_finds_nothing() {
    check(&Case::new("null", vec![]), &vec![]);
}

#[test]
fn viscous_damping() {
    check(
        &Case::new("viscous_damping", vec![("door_hinge", TrueEffect::ViscousDamping { damping: 0.3 })]),
        &vec![("door_hinge", "viscous_damping", vec![("damping", 0.3)])],
    );
}

#[test]
fn coulomb_friction() {
    check(
        &Case::new("coulomb_friction", vec![("door_hinge", TrueEffect::CoulombFriction { friction: 0.5 })]),
        &vec![("door_hinge", "coulomb_friction", vec![("friction", 0.5)])],
    );
}

#[test]
fn spring() {
    check(
        &Case::new("spring", vec![("door_hinge", TrueEffect::Spring { stiffness: 1.5, rest_position: 0.8 })]),
        &vec![("door_hinge", "spring", vec![("stiffness", 1.5), ("rest_position", 0.8)])],
    );
}

#[test]
fn gravity_tilt() {
    check(
        &Case::new("gravity_tilt", vec![("door_hinge", TrueEffect::AxisTilt { tilt_deg: 3.0, azimuth_deg: 40.0 })]),
        &vec![("door_hinge", "gravity_tilt", vec![("tilt_deg", 3.0)])],
    );
}

#[test]
fn end_stop() {
    check(
        &Case::new("end_stop", vec![("door_hinge", TrueEffect::EndStop { position: 1.3, restitution: 0.3 })]),
        &vec![("door_hinge", "end_stop", vec![("position", 1.3), ("restitution", 0.3)])],
    );
}

#[test]
fn mass_scale() {
    check(
        &Case::new("mass_scale", vec![("drawer_slide", TrueEffect::ExtraInertia { scale: 1.8 })]),
        &vec![("drawer_slide", "mass_scale", vec![("scale", 1.8)])],
    );
}

#[test]
fn soft_close() {
    check(
        &Case::new("soft_close", vec![("drawer_slide", TrueEffect::SoftClose { damping: 40.0, engage_position: 0.1 })]),
        &vec![("drawer_slide", "soft_close", vec![("damping", 40.0), ("engage_position", 0.1)])],
    );
}

#[test]
fn damping_and_spring_combined() {
    check(
        &Case::new(
            "damping+spring",
            vec![
                ("door_hinge", TrueEffect::ViscousDamping { damping: 0.2 }),
                ("door_hinge", TrueEffect::Spring { stiffness: 1.0, rest_position: 1.0 }),
            ],
        ),
        &vec![
            ("door_hinge", "viscous_damping", vec![("damping", 0.2)]),
            ("door_hinge", "spring", vec![("stiffness", 1.0), ("rest_position", 1.0)]),
        ],
    );
}

#[test]
fn one_joint_of_several() {
    check(
        &Case::new("one_of_several", vec![("drawer_slide", TrueEffect::CoulombFriction { friction: 3.0 })]),
        &vec![("drawer_slide", "coulomb_friction", vec![("friction", 3.0)])],
    );
}

#[test]
fn pose_only_tracking_irregular_sampling() {
    let mut case = Case::new("pose_only", vec![("door_hinge", TrueEffect::ViscousDamping { damping: 0.3 })]);
    (case.pose_only, case.irregular, case.noise, case.dropouts) = (true, true, 0.002, 0.05);
    check(&case, &vec![("door_hinge", "viscous_damping", vec![("damping", 0.3)])]);
}

fn csv_error(text: &str) -> (usize, usize, String) {
    let model = model();
    let result = parse_recording(text, Path::new("bad.csv")).and_then(|r| analyze(&model, &r, &GapConfig::default()).map(|_| ()));
    match result {
        Err(GapError::Csv { line, column, field, .. }) => (line, column, field),
        other => panic!("expected a CSV error for {text:?}, got {other:?}"),
    }
}

#[test]
fn bad_recordings_are_rejected_with_line_and_column() {
    // Unknown column name in the header.
    assert_eq!(csv_error("# description: x\ntime,door_hinge.angle\n0,1\n"), (2, 2, "header".into()));
    // A joint the model does not have.
    assert_eq!(csv_error("time,lid.q\n0,1\n"), (1, 2, "lid.q".into()));
    // Time not strictly increasing.
    assert_eq!(csv_error("time,door_hinge.q\n0,0\n0.01,0\n0.01,0\n"), (4, 1, "time".into()));
    // A bad number.
    assert_eq!(csv_error("door_hinge.q,time\n0.1,0\n0.1x,0.01\n"), (3, 1, "door_hinge.q".into()));
    // A row with too few cells, a metadata line without a key, bad gravity.
    assert_eq!(csv_error("time,door_hinge.q\n0,0\n0.01\n").0, 3);
    assert_eq!(csv_error("# just words\ntime,door_hinge.q\n0,0\n").0, 1);
    assert_eq!(csv_error("# gravity: 0 0\ntime,door_hinge.q\n0,0\n").2, "gravity");
}

#[test]
fn writes_report_fitted_urdf_sidecar_and_plots() {
    let model = model();
    let cfg = GenerateConfig {
        effects: vec![("door_hinge".into(), TrueEffect::ViscousDamping { damping: 0.3 })],
        duration_s: 5.0,
        ..GenerateConfig::default()
    };
    let rec = parse_recording(&generate_recording(&model, &cfg).expect("csv"), Path::new("r.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let dir = tempfile::tempdir().expect("tempdir");
    write_outputs(dir.path(), &model, &report).expect("writes");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).expect("report")).expect("json");
    assert_eq!(json["format"], "partscene-gap-report/1");
    assert_eq!(json["fitted_model"], "model.fitted.urdf");
    assert_eq!(json["effects"][0]["kind"], "viscous_damping");
    assert!(json["fit"]["per_joint"]["door_hinge"]["rmse_after"].as_f64().expect("number") < 0.01);
    let fitted = parse_model(&std::fs::read_to_string(dir.path().join("model.fitted.urdf")).expect("urdf"), Path::new("f.urdf"))
        .expect("fitted URDF parses");
    let hinge = fitted.joint_index("door_hinge").expect("hinge");
    assert!((fitted.joints[hinge].damping - 0.3).abs() < 0.075, "{}", fitted.joints[hinge].damping);
    assert!(dir.path().join("model.fitted.json").exists());
    let svg = std::fs::read_to_string(dir.path().join("plot_door_hinge.svg")).expect("plot");
    assert!(svg.starts_with("<svg") && svg.contains("polyline"));
    // The fitted model explains the recording: re-analysis finds nothing missing.
    let again = analyze(&fitted, &rec, &GapConfig::default()).expect("analyses");
    assert!(again.effects.is_empty(), "{:?}", again.effects);
}
