//! The reality gap end to end: recordings with concealed effects from `gap::generate` (RK4 with
//! event location, geometric axis tilt — different physics code from the fitter) drive the
//! analysis; each case states the joint, the kinds and the parameters it must find. Also reader
//! errors with line and column, the written outputs, and (feature `sim`) the fitter's integrator
//! against rapier3d.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::OnceLock;

use rand::{Rng, SeedableRng};

use partscene::gap::generate::{GenerateConfig, TrueEffect, generate_recording};
use partscene::gap::{GapConfig, GapError, GapModel, GapReport, analyze, parse_model, parse_recording, write_outputs};

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
    /// The model's URDF text.
    urdf: &'static str,
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
            urdf: CABINET,
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
    let model = parse_model(case.urdf, Path::new("model.urdf")).expect("model parses");
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
fn a_compliant_stop_is_named_with_its_contact_time() {
    // A drawer stop that holds the drawer 50 ms per impact and throws it back at 0.8 of its
    // speed (a penalty limit): a hard stop with any restitution replays each impact's timing
    // wrong, and every later one with it. Five samples per contact at 100 Hz: the position is
    // measured to 0.3 mm, a tenth of how deep the drawer sinks in.
    let stop = TrueEffect::CompliantStop { position: 0.3, restitution: 0.8, contact_time_s: 0.05 };
    check(
        &Case { noise: 0.0003, ..Case::new("compliant_stop", vec![("drawer_slide", stop)]) },
        &vec![("drawer_slide", "end_stop", vec![("position", 0.3), ("restitution", 0.8), ("contact_time", 0.05)])],
    );
}

/// A pendulum on a horizontal axis: gravity does work on it, so its weight is seen.
const PENDULUM: &str = r#"<robot name="pendulum">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0 0 -0.17"/><mass value="0.6"/>
    <inertia ixx="0.004" iyy="0.004" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="pivot" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint>
</robot>"#;

#[test]
fn mass_scale() {
    check(
        &Case { urdf: PENDULUM, ..Case::new("mass_scale", vec![("pivot", TrueEffect::ExtraInertia { scale: 1.5 })]) },
        &vec![("pivot", "mass_scale", vec![("scale", 1.5)])],
    );
}

/// A lid hinged along its back edge, closed at 0 and opening past upright to 1.9 rad (its weight
/// holds it open there, as it holds it shut at 0).
const LID: &str = r#"<robot name="chest"><link name="box"/>
  <link name="lid"><inertial><origin xyz="0.2 0 0.01"/><mass value="1.5"/>
    <inertia ixx="0.0313" iyy="0.02005" izz="0.05125" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="lid_hinge" type="revolute"><parent link="box"/><child link="lid"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="1.9" effort="1000" velocity="100"/></joint>
</robot>"#;

/// How [`LID`]'s hinge resists: viscous damping (N·m·s/rad) and dry friction (N·m) that holds the
/// lid exactly while the rest of the effort on it stays within that level.
#[derive(Clone, Copy)]
struct Hinge {
    damping: f64,
    friction: f64,
}

/// [`LID`] `scale` × as heavy (inertia and weight) on a `hinge` of its own, released at 0.6 rad,
/// then pushed by a hand toward random openings a little past either stop (a PD holding the
/// modelled weight, effort within ±4.5 N·m beyond twice the hinge's friction, decided every 0.1 s
/// and held) for 0.6–1.2 s at a time, let go for 0.5–1.0 s in between: it falls shut or open onto
/// its stops (inelastic) and rests there, or where its friction holds it. RK4 at 1 ms (the friction of the step's start
/// held through it; friction stops the lid rather than turning it round), logged at 200 Hz with
/// 0.7 mrad of encoder noise, seeded.
fn lid_csv(scale: f64, hinge: Hinge, seed: u64) -> String {
    let (mass, lever, rise, inertia_com) = (1.5, 0.2, 0.01, 0.02005);
    let inertia = inertia_com + mass * (lever * lever + rise * rise);
    // The effort that holds the modelled lid still at q (its centre of mass at height
    // lever·sin q + rise·cos q).
    let weight = |q: f64| mass * 9.81 * (lever * q.cos() - rise * q.sin());
    let accel = |q: f64, v: f64, u: f64, dry: f64| (u - scale * weight(q) - hinge.damping * v - dry) / (scale * inertia);
    // The hand's reach: 4.5 N·m beyond twice what the hinge's friction holds.
    let reach = 4.5 + 2.0 * hinge.friction;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let (mut q, mut v, mut u) = (0.6_f64, 0.0_f64, 0.0);
    let (mut pushing, mut phase_end, mut target) = (false, 0.3, 0.6);
    let mut csv = String::from("time,lid_hinge.q,lid_hinge.effort\n");
    for step in 0..8000 {
        let t = f64::from(step) * 1e-3;
        if step % 100 == 0 {
            if t >= phase_end {
                pushing = !pushing;
                phase_end = t + if pushing { rng.random_range(0.6..1.2) } else { rng.random_range(0.5..1.0) };
                target = rng.random_range(-0.2..2.1);
            }
            u = if pushing { (8.0 * (target - q) - 1.5 * v + weight(q)).clamp(-reach, reach) } else { 0.0 };
        }
        if step % 5 == 0 {
            let noise: f64 = rng.random_range(-1.0..1.0) * 0.0007 * 3.0_f64.sqrt();
            writeln!(csv, "{t:.3},{:.6},{u:.6}", q + noise).expect("writes to a string");
        }
        let net = u - scale * weight(q);
        if v == 0.0 && net.abs() <= hinge.friction {
            continue;
        }
        let dry = hinge.friction * if v == 0.0 { net.signum() } else { v.signum() };
        let before = v;
        [q, v, _, _] = rk4_step([q, v, 0.0, 0.0], t, 1e-3, &|s, _| [s[1], accel(s[0], s[1], u, dry), 0.0, 0.0]);
        if before != 0.0 && v.signum() != before.signum() && hinge.friction > 0.0 {
            v = 0.0;
        }
        // The stops: the lid lands and stays (until pushed off).
        if q <= 0.0 || q >= 1.9 {
            q = q.clamp(0.0, 1.9);
            v = 0.0;
        }
    }
    csv
}

/// [`LID`] `scale` × as heavy on `hinge`, at each of `seeds`: exactly the two `expected` effects
/// (kind, parameter, truth) are named, each within 10 % of its truth.
fn check_lid(scale: f64, hinge: Hinge, seeds: &[u64], expected: [(&str, &str, f64); 2]) {
    let model = parse_model(LID, Path::new("chest.urdf")).expect("model parses");
    for &seed in seeds {
        let rec = parse_recording(&lid_csv(scale, hinge, seed), Path::new("lid.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
        eprintln!("FIGURES lid seed {seed} | found {found:?} | {:?}", report.joints["lid_hinge"].rejected);
        assert_eq!(report.effects.len(), 2, "seed {seed}: {found:?}");
        for (kind, param, truth) in expected {
            let e = report.effects.iter().find(|e| e.kind == kind).unwrap_or_else(|| panic!("seed {seed}: no {kind}: {found:?}"));
            assert!((e.params[param] - truth).abs() <= 0.1 * truth, "seed {seed}: {found:?}");
        }
    }
}

/// Broke (Genesis's lid at seed 4, JAX-sim's lids: nothing named, `unknown` at 70 % of the
/// effort): the model's first moments take the heavier lid's weight, so alone it reads as inertia
/// and the damping alone is fitted too strong; each failed the held-out blocks without the other.
/// At these seeds the release before named dry friction or a soft-close and `unknown` instead (36
/// of 40 seeds were right; all 40 now).
#[test]
fn a_heavier_lid_with_a_damped_hinge_is_named_both_though_neither_passes_alone() {
    check_lid(
        1.3,
        Hinge { damping: 0.2, friction: 0.0 },
        &[3, 14, 27, 38],
        [("mass_scale", "scale", 1.3), ("viscous_damping", "damping", 0.2)],
    );
}

/// Broke: a heavier lid whose dry hinge holds it at rest much of the time (Bullet's lid at seed 1,
/// held 78 % of its usable samples) was read as viscous damping and `unknown` at 54 %: at rest the
/// residual is whatever holds the lid, and a reading through those samples named neither the
/// friction nor the weight. Rests were left out only where a reading had named dry friction and a
/// third of the samples stayed. A joint that dwells at rest and is left unexplained is now read
/// again without its rests, the reading kept where it names dry friction that holds them. Of 40
/// seeds of this lid, 15 were read right before and 32 now; these four were dry friction at twice
/// its level with `unknown`, or dry friction, a soft-close and `unknown`.
#[test]
fn a_heavier_lid_that_its_dry_hinge_holds_at_rest_is_named_both() {
    check_lid(
        1.3,
        Hinge { damping: 0.0, friction: 1.2 },
        &[4, 17, 21, 38],
        [("mass_scale", "scale", 1.3), ("coulomb_friction", "friction", 1.2)],
    );
}

/// Broke: the same lid, held at rest so long that leaving its rests out kept under the third of
/// the samples the first pass needs, while its reading with them explained the efforts (so the
/// second pass, for rests that keep a reading from explaining a joint, was not tried): the rests
/// held the friction low and the weight high (seed 1: 0.971 N·m and ×1.366, seed 16: 0.919 and
/// ×1.486). Rests that the reading's friction holds are now read without down to the second
/// pass's floor too, kept where both readings, the whole recording's and the training part's,
/// name friction that holds them (of 40 seeds, 32 → 34 read right).
#[test]
fn a_lid_held_at_rest_too_long_for_the_first_rest_pass_is_read_without_its_rests() {
    check_lid(1.3, Hinge { damping: 0.0, friction: 1.2 }, &[1, 16], [("mass_scale", "scale", 1.3), ("coulomb_friction", "friction", 1.2)]);
}

#[test]
fn a_heavier_drawer_is_armature_for_its_weight_does_no_work() {
    // The spec: inertia alone, without weight, is armature; a horizontal drawer's weight does no
    // work on its slide. 0.8 × the drawer's 3 kg (600 kg/m³ of a 0.5 × 0.5 × 0.02 m board).
    check(
        &Case::new("heavier_drawer", vec![("drawer_slide", TrueEffect::ExtraInertia { scale: 1.8 })]),
        &vec![("drawer_slide", "armature", vec![("armature", 2.4)])],
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

/// A door and a light knob (inertia 5.8e-6 kg·m², stops at ±π) on one body, damping hidden on the
/// door only. The knob's efforts are ~1e-5 N·m: when the generator wrote them with six decimals,
/// its saturated pushes were recorded 0.5 % too strong, a real effort-gain error that the analysis
/// rightly explained as a 1.005 mass scale on a joint with no hidden effect. Only the door's
/// damping may be reported, and no mismatch on the knob.
const DOOR_AND_KNOB: &str = r#"<robot name="microwave">
  <link name="body"><inertial><mass value="15"/><inertia ixx="0.5" iyy="0.5" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.25 0.2 0.15"/><geometry><box size="0.5 0.4 0.3"/></geometry></collision></link>
  <link name="door"><inertial><origin xyz="0.2 0 0"/><mass value="3"/>
    <inertia ixx="0.03" iyy="0.05" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.02 0.3"/></geometry></collision></link>
  <link name="knob"><inertial><origin xyz="0 0 0"/><mass value="0.0269"/>
    <inertia ixx="0.0000057667" iyy="0.0000096611" izz="0.0000058480" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><box size="0.02 0.046 0.046"/></geometry></collision></link>
  <joint name="door_hinge" type="revolute"><parent link="body"/><child link="door"/><origin xyz="0 -0.01 0.15"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="1.8" effort="10" velocity="3"/></joint>
  <joint name="knob_joint" type="revolute"><parent link="body"/><child link="knob"/><origin xyz="0.45 -0.01 0.1"/>
    <axis xyz="-0.99913 -0.04159 0"/><limit lower="-3.1415927" upper="3.1415927" effort="100" velocity="1"/></joint>
</robot>"#;

#[test]
fn a_knob_rattling_between_its_stops_is_not_a_missing_mass() {
    let model = parse_model(DOOR_AND_KNOB, Path::new("microwave.urdf")).expect("model parses");
    for seed in [0, 1, 2, 3, 4, 5, 6, 7, 8] {
        let cfg = GenerateConfig {
            duration_s: 6.0,
            seed,
            effects: vec![("door_hinge".to_owned(), TrueEffect::ViscousDamping { damping: 0.5 })],
            ..GenerateConfig::default()
        };
        let csv = generate_recording(&model, &cfg).expect("generates");
        let rec = parse_recording(&csv, Path::new("gen.csv")).expect("generated recording parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
        eprintln!(
            "FIGURES knob seed {seed} | found {found:?} mismatches {:?}",
            report.mismatches.iter().map(|m| (&m.joint, m.t_start, m.t_end)).collect::<Vec<_>>()
        );
        assert_eq!(report.effects.len(), 1, "seed {seed}: found {found:?}");
        let door = &report.effects[0];
        assert_eq!((door.joint.as_str(), door.kind.as_str()), ("door_hinge", "viscous_damping"), "seed {seed}: found {found:?}");
        let err = (door.params["damping"] - 0.5).abs() / 0.5;
        assert!(err <= 0.25, "seed {seed}: damping {}", door.params["damping"]);
        assert!(!report.mismatches.iter().any(|m| m.joint == "knob_joint"), "seed {seed}: knob mismatch {:?}", report.mismatches);
    }
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

/// rapier3d cross-check model: a door on a vertical hinge and a lid on a horizontal one (gravity
/// swings it), both on a fixed body, masses from `<inertial>` only (no colliders, no contacts).
#[cfg(feature = "sim")]
const RIG: &str = r#"<robot name="rig">
  <link name="body"><inertial><mass value="20"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="door"><inertial><origin xyz="0.3 0 0"/><mass value="4"/>
    <inertia ixx="0.2134" iyy="0.3334" izz="0.1201" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="lid"><inertial><origin xyz="0.2 0 0"/><mass value="2"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="door_hinge" type="revolute"><parent link="body"/><child link="door"/><origin xyz="0 -0.01 0.4"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <joint name="lid_hinge" type="revolute"><parent link="body"/><child link="lid"/><origin xyz="0 0.5 0.8"/>
    <axis xyz="0 1 0"/><limit lower="-1.5" upper="4.5" effort="10" velocity="3"/></joint>
</robot>"#;

/// Extra physics given to rapier on one joint: (damping, friction, spring stiffness, rest).
#[cfg(feature = "sim")]
#[derive(Clone, Copy, Default)]
struct RapierDynamics {
    damping: f64,
    friction: f64,
    stiffness: f64,
    rest: f64,
}

/// Simulates `joint` of RIG in rapier3d (multibody from rapier3d-urdf, default 0.1 rotational
/// damping zeroed, per-DoF damping/friction/spring set by hand since the loader ignores
/// `<dynamics>`) under a held effort sampled at `time_s`; returns the joint angle per sample.
#[cfg(feature = "sim")]
fn rapier_run(joint: &str, dynamics: RapierDynamics, time_s: &[f64], effort: &[f64], substeps: usize) -> Vec<f64> {
    use rapier3d::prelude::*;
    use rapier3d_urdf::{UrdfLoaderOptions, UrdfMultibodyOptions, UrdfRobot};
    let options = UrdfLoaderOptions { make_roots_fixed: true, ..UrdfLoaderOptions::default() };
    let (robot, parsed) = UrdfRobot::from_str(RIG, options, Path::new(".")).expect("rapier3d-urdf loads the rig");
    let index = parsed.joints.iter().position(|j| j.name == joint).expect("joint in rig");
    let axis = parsed.joints[index].axis.xyz.0;
    let axis = Vector::new(axis[0] as f32, axis[1] as f32, axis[2] as f32);
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, 0.0, -9.81);
    let dt = (time_s[1] - time_s[0]) / substeps as f64;
    world.integration_parameters.dt = dt as f32;
    let handles = robot.insert_using_multibody_joints(
        &mut world.bodies,
        &mut world.colliders,
        &mut world.multibody_joints,
        UrdfMultibodyOptions::DISABLE_SELF_CONTACTS,
    );
    let child = handles.joints[index].link2;
    let joint_handle = handles.joints[index].joint.expect("multibody joint");
    for j in &handles.joints {
        let Some(h) = j.joint else { continue };
        let (mb, _) = world.multibody_joints.get_mut(h).expect("multibody");
        mb.damping_mut().fill(0.0);
    }
    let (mb, link_id) = world.multibody_joints.get_mut(joint_handle).expect("multibody");
    let link = mb.link_mut(link_id).expect("link");
    let dof = link.assembly_id();
    // Revolute: the free axis is AngX (spatial index 3) of the joint frame built on the URDF axis.
    link.joint.set_spring(3, dynamics.stiffness as f32, dynamics.rest as f32);
    mb.damping_mut()[dof] = dynamics.damping as f32;
    mb.frictions_mut()[dof] = dynamics.friction as f32;
    let angle = |world: &PhysicsWorld| {
        let r = *world.bodies[child].rotation();
        let s = Vector::new(r.x, r.y, r.z).dot(axis);
        2.0 * f64::from(s).atan2(f64::from(r.w))
    };
    let mut out = Vec::with_capacity(time_s.len());
    for (i, &e) in effort.iter().enumerate().take(time_s.len()) {
        out.push(angle(&world));
        if i + 1 == time_s.len() {
            break;
        }
        for _ in 0..substeps {
            let body = &mut world.bodies[child];
            body.reset_torques(true);
            body.add_torque(axis * e as f32, true);
            world.step();
        }
    }
    out
}

/// The fitter's 1-DoF integrator on the same joint, efforts and dynamics.
#[cfg(feature = "sim")]
fn fitter_run(joint: &str, dynamics: RapierDynamics, time_s: &[f64], effort: &[f64]) -> Vec<f64> {
    use partscene::gap::sim::{SimInput, simulate};
    use partscene::gap::{Effect, EffectKind, JointPhysics};
    let model = parse_model(RIG, Path::new("rig.urdf")).expect("rig parses");
    let j = model.joint_index(joint).expect("joint");
    let terms = vec![model.joint_terms(j, &vec![0.0; model.joints.len()], glam::DVec3::new(0.0, 0.0, -9.81)); time_s.len()];
    let mut effects = vec![
        Effect { kind: EffectKind::ViscousDamping, params: vec![dynamics.damping], blocks_upward: false },
        Effect { kind: EffectKind::CoulombFriction, params: vec![dynamics.friction], blocks_upward: false },
    ];
    if dynamics.stiffness > 0.0 {
        effects.push(Effect { kind: EffectKind::Spring, params: vec![dynamics.stiffness, dynamics.rest], blocks_upward: false });
    }
    let physics = JointPhysics::with_effects(&model.joints[j], &effects);
    let mut out = vec![0.0; time_s.len()];
    simulate(&SimInput { time_s, effort, terms: &terms }, &physics, 0, time_s.len() - 1, 0.0, 0.0, &mut out);
    out
}

/// Efforts at 100 Hz: pushes of a few hundred ms each way, then rests.
#[cfg(feature = "sim")]
fn push_pattern(duration_s: f64, amplitude: f64) -> (Vec<f64>, Vec<f64>) {
    let time: Vec<f64> = (0..=(duration_s * 100.0) as usize).map(|i| i as f64 * 0.01).collect();
    let effort = time
        .iter()
        .map(|&t| match t {
            t if t < 0.6 => amplitude,
            t if t < 1.6 => 0.0,
            t if t < 2.0 => -0.7 * amplitude,
            t if t < 3.0 => 0.0,
            t if t < 3.3 => 0.5 * amplitude,
            _ => 0.0,
        })
        .collect();
    (time, effort)
}

#[cfg(feature = "sim")]
#[test]
fn fitter_integrator_agrees_with_rapier3d() {
    let (time, door_effort) = push_pattern(5.0, 0.8);
    let (_, lid_effort) = push_pattern(5.0, 0.0);
    let cases: [(&str, &str, RapierDynamics, &[f64], f64); 5] = [
        ("door nominal (hits its stop at 3 rad)", "door_hinge", RapierDynamics::default(), &door_effort, 0.002),
        ("door viscous 0.3", "door_hinge", RapierDynamics { damping: 0.3, ..RapierDynamics::default() }, &door_effort, 0.002),
        (
            "door spring 1.0 @ 0.5 + damping 0.2",
            "door_hinge",
            RapierDynamics { damping: 0.2, stiffness: 1.0, rest: 0.5, ..RapierDynamics::default() },
            &door_effort,
            0.002,
        ),
        (
            "lid pendulum (gravity) + damping 0.05",
            "lid_hinge",
            RapierDynamics { damping: 0.05, ..RapierDynamics::default() },
            &lid_effort,
            0.002,
        ),
        ("door Coulomb 0.2", "door_hinge", RapierDynamics { friction: 0.2, ..RapierDynamics::default() }, &door_effort, 0.002),
    ];
    for (name, joint, dynamics, effort, tolerance) in cases {
        let a = rapier_run(joint, dynamics, &time, effort, 20);
        let b = fitter_run(joint, dynamics, &time, effort);
        let (range_lo, range_hi) = b.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
        let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        eprintln!("RAPIER {name}: max |q_rapier - q_fitter| = {worst:.2e} rad over 5 s (motion {range_lo:.3}..{range_hi:.3} rad)");
        assert!(range_hi - range_lo > 0.3, "{name}: the joint hardly moved");
        assert!(worst < tolerance, "{name}: rapier and the fitter differ by {worst} rad");
    }
}

/// A recording generated by rapier3d (not by `gap::generate`): random pushes on the rig's door,
/// noise σ = 1 mrad, in the spec's CSV form.
#[cfg(feature = "sim")]
fn rapier_recording(dynamics: RapierDynamics, seed: u64) -> String {
    use rand::Rng;
    use std::fmt::Write as _;
    let mut rng = partscene::math::rng(seed);
    let time: Vec<f64> = (0..=1000).map(|i| f64::from(i) * 0.01).collect();
    let mut effort = vec![0.0; time.len()];
    let mut t_next = 0.0;
    let mut value = 0.0;
    let mut pushing = false;
    for (e, &t) in effort.iter_mut().zip(&time) {
        if t >= t_next {
            pushing = !pushing;
            value = if pushing { rng.random_range(-0.6..0.6) } else { 0.0 };
            t_next = t + if pushing { rng.random_range(0.3..0.6) } else { rng.random_range(0.6..1.2) };
        }
        *e = value;
    }
    let q = rapier_run("door_hinge", dynamics, &time, &effort, 20);
    let noise = rand_distr::Normal::new(0.0, 0.001).expect("normal");
    let mut csv = String::from(
        "# description: rapier3d multibody, hidden dynamics on door_hinge\n# model: rig.urdf\ntime,door_hinge.q,door_hinge.effort\n",
    );
    for i in 0..time.len() {
        let y = q[i] + rand_distr::Distribution::sample(&noise, &mut rng);
        let _ = writeln!(csv, "{:.3},{y:.7},{:.6}", time[i], effort[i]);
    }
    csv
}

/// Broke: the door swings within 0.94 rad of its 0.6 rad rest, where a spring and a tilted axis (a
/// sine) differ by under 6 %; effort space, which this recording reaches since the unobserved lid
/// is welded where it stands, took the tilt first and then the damper, though the spring in the
/// tilt's place beside the damper leaves 16 % less held-out error (the test had passed in
/// position space, where the lid forced it). The better pull now replaces the one chosen first.
#[cfg(feature = "sim")]
#[test]
fn recordings_generated_by_rapier3d() {
    let model = parse_model(RIG, Path::new("rig.urdf")).expect("rig parses");
    let analyse = |dynamics: RapierDynamics| {
        let rec = parse_recording(&rapier_recording(dynamics, 11), Path::new("rapier.csv")).expect("parses");
        analyze(&model, &rec, &GapConfig::default()).expect("analyses")
    };
    // Null: rapier with the model as written.
    let null = analyse(RapierDynamics::default());
    assert!(null.effects.is_empty() && null.mismatches.is_empty(), "{:?} {:?}", null.effects, null.mismatches);
    // Hidden damping and spring.
    let truth = RapierDynamics { damping: 0.25, stiffness: 0.8, rest: 0.6, ..RapierDynamics::default() };
    let report = analyse(truth);
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
    let held = report.held_out.per_joint["door_hinge"];
    eprintln!(
        "FIGURES rapier damping+spring | door_hinge: held-out rmse {:.5} -> {:.5} | found {found:?}",
        held.rmse_before, held.rmse_after
    );
    assert_eq!(report.effects.len(), 2, "{found:?}");
    let param = |kind: &str, name: &str| {
        report.effects.iter().find(|e| e.kind == kind).map_or_else(|| panic!("no {kind}: {found:?}"), |e| e.params[name])
    };
    for (kind, name, truth) in [("viscous_damping", "damping", 0.25), ("spring", "stiffness", 0.8), ("spring", "rest_position", 0.6)] {
        let got = param(kind, name);
        assert!((got - truth).abs() <= 0.25 * truth, "{kind}.{name} = {got}, true {truth}");
    }
    assert!(held.rmse_before >= 5.0 * held.rmse_after, "held-out rmse {} -> {}", held.rmse_before, held.rmse_after);
}

#[test]
fn report_json_has_the_spec_fields_and_is_empty_when_nothing_is_missing() {
    let model = model();
    let cfg = GenerateConfig { duration_s: 6.0, noise: 0.001, seed: 3, ..GenerateConfig::default() };
    // Metadata lines the spec allows: unknown keys, values with colons.
    let csv = format!("# recorded: 2024-05-01 12:00:03\n# operator: a: b\n{}", generate_recording(&model, &cfg).expect("csv"));
    let rec = parse_recording(&csv, Path::new("null.csv")).expect("parses");
    assert_eq!(rec.metadata["recorded"], "2024-05-01 12:00:03");
    assert_eq!(rec.metadata["operator"], "a: b");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let dir = tempfile::tempdir().expect("tempdir");
    write_outputs(dir.path(), &model, &report).expect("writes");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).expect("report")).expect("json");
    let keys: Vec<&str> = json.as_object().expect("object").keys().map(String::as_str).collect();
    // The spec's five fields, plus clearly named extras.
    for k in ["format", "mismatches", "effects", "fit", "fitted_model"] {
        assert!(keys.contains(&k), "missing {k}: {keys:?}");
    }
    for k in &keys {
        assert!(
            ["format", "mismatches", "effects", "fit", "fitted_model", "held_out", "noise_sigma", "notes", "joints"].contains(k),
            "{k}"
        );
    }
    assert_eq!(json["effects"], serde_json::json!([]));
    assert_eq!(json["mismatches"], serde_json::json!([]));
    assert_eq!(json["fitted_model"], "model.fitted.urdf");
    assert!(dir.path().join("model.fitted.urdf").exists());
    for joint in ["door_hinge", "drawer_slide"] {
        let pair = &json["fit"]["per_joint"][joint];
        assert!(pair["rmse_before"].as_f64().expect("number") < 0.002, "{joint}: {pair}");
        assert!(pair["rmse_after"].is_number());
    }
    assert!(json["fit"]["rmse_before"].is_number() && json["fit"]["rmse_after"].is_number());
}

/// A planar double pendulum: continuous joints about +y, q = 0 hanging down, the elbow's angle
/// relative to the upper link.
const DOUBLE_PENDULUM: &str = r#"<robot name="double_pendulum">
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0 0 -0.17"/><mass value="0.6"/>
    <inertia ixx="0.004" iyy="0.004" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="lower"><inertial><origin xyz="0 0 -0.28"/><mass value="0.65"/>
    <inertia ixx="0.0034" iyy="0.0034" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="continuous"><parent link="base"/><child link="upper"/><axis xyz="0 1 0"/></joint>
  <joint name="elbow" type="continuous"><parent link="upper"/><child link="lower"/><origin xyz="0 0 -0.2"/>
    <axis xyz="0 1 0"/></joint>
</robot>"#;

/// The textbook equations of motion of [`DOUBLE_PENDULUM`] (Lagrange, written out by hand: not
/// the library's multibody code), with dry friction of `friction` N·m at the shoulder and the
/// elbow (smooth over 0.01 rad/s), released from (q1, q2) at rest and integrated by RK4 at
/// 10 kHz; a CSV sampled at 200 Hz.
fn double_pendulum_csv(q1: f64, q2: f64, duration_s: f64, friction: [f64; 2]) -> String {
    double_pendulum_with_load_csv(q1, q2, duration_s, friction, (0.0, 0.0))
}

/// [`double_pendulum_csv`] with a load of (mass kg, inertia kg·m² about its centre) carried
/// rigidly at the lower link's centre of mass.
fn double_pendulum_with_load_csv(q1: f64, q2: f64, duration_s: f64, friction: [f64; 2], load: (f64, f64)) -> String {
    logged_double_pendulum_csv(q1, q2, duration_s, friction, load, None, Log::AT_200_HZ)
}

/// The motor torques of [`logged_double_pendulum_csv`]'s driven runs, N·m at time `t` s: two
/// incommensurate sines per joint of amplitudes `drive`.
fn drive_torques(drive: (f64, f64), t: f64) -> [f64; 2] {
    [drive.0 * ((2.1 * t).sin() + 0.5 * (5.3 * t + 1.0).sin()), drive.1 * ((3.7 * t + 0.5).sin() + 0.4 * (7.1 * t).sin())]
}

/// How a run is logged: its rate, the step its positions are rounded to (an encoder's or a
/// logger's resolution; None: 9 decimals), how far each time stamp may lie from the instant
/// the sample was taken (a logger's clock; seeded, uniform), and a sway the position sensors
/// read that the links do not make (amplitude rad, frequency Hz: an encoder on the motor side
/// of a compliant drive).
#[derive(Clone, Copy)]
struct Log {
    rate_hz: u32,
    q_step: Option<f64>,
    stamp_jitter_s: f64,
    sway: (f64, f64),
}

impl Log {
    /// 200 Hz, 9 decimals, exact stamps, no sway.
    const AT_200_HZ: Self = Self { rate_hz: 200, q_step: None, stamp_jitter_s: 0.0, sway: (0.0, 0.0) };
}

/// The textbook equations of motion of [`DOUBLE_PENDULUM`] carrying `load` (see
/// [`double_pendulum_with_load_csv`]): the state's derivative under joint torques `u` and dry
/// friction of `friction` N·m (smooth over 0.01 rad/s).
fn double_pendulum_accel(s: [f64; 4], u: [f64; 2], friction: [f64; 2], load: (f64, f64)) -> [f64; 4] {
    let (m1, r1, ic1, l1, r2, g) = (0.6, 0.17, 0.004, 0.2, 0.28, 9.81);
    let (m2, ic2) = (0.65 + load.0, 0.0034 + load.1);
    let (i1, i2) = (ic1 + m1 * r1 * r1, ic2 + m2 * r2 * r2);
    let [a, b, va, vb] = s;
    let (c2, s2) = (b.cos(), b.sin());
    let h = m2 * l1 * r2;
    let (m11, m12, m22) = (i1 + i2 + m2 * l1 * l1 + 2.0 * h * c2, i2 + h * c2, i2);
    let gravity1 = (m1 * r1 + m2 * l1) * g * a.sin() + m2 * g * r2 * (a + b).sin();
    let gravity2 = m2 * g * r2 * (a + b).sin();
    let rhs1 = -(-2.0 * h * s2 * va * vb - h * s2 * vb * vb) - gravity1 - friction[0] * (va / 0.01).tanh() + u[0];
    let rhs2 = -(h * s2 * va * va) - gravity2 - friction[1] * (vb / 0.01).tanh() + u[1];
    let det = m11 * m22 - m12 * m12;
    [va, vb, (m22 * rhs1 - m12 * rhs2) / det, (m11 * rhs2 - m12 * rhs1) / det]
}

/// One classical Runge–Kutta step of `h` s from state `s` at time `t`.
fn rk4_step(s: [f64; 4], t: f64, h: f64, accel: &impl Fn([f64; 4], f64) -> [f64; 4]) -> [f64; 4] {
    let add = |x: [f64; 4], k: [f64; 4], f: f64| [x[0] + f * k[0], x[1] + f * k[1], x[2] + f * k[2], x[3] + f * k[3]];
    let k1 = accel(s, t);
    let k2 = accel(add(s, k1, h / 2.0), t + h / 2.0);
    let k3 = accel(add(s, k2, h / 2.0), t + h / 2.0);
    let k4 = accel(add(s, k3, h), t + h);
    [0, 1, 2, 3].map(|j| s[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]))
}

/// [`DOUBLE_PENDULUM`] held near `target` by a PD loop of gains (`kp` N·m/rad, `kd` N·m·s/rad)
/// on both joints that reads the state and sets the torques 200 times a second (held between):
/// a CSV of the positions and the torques it set, at 200 Hz.
fn held_double_pendulum_csv(target: [f64; 2], kp: f64, kd: f64, duration_s: f64) -> String {
    let mut s = [target[0] + 0.05, target[1] - 0.05, 0.0, 0.0];
    let mut csv = String::from("time,shoulder.q,elbow.q,shoulder.effort,elbow.effort\n");
    let h = 1e-4;
    for i in 0..=(duration_s * 200.0).round() as usize {
        let t0 = i as f64 / 200.0;
        let u = [0, 1].map(|d| kp * (target[d] - s[d]) - kd * s[2 + d]);
        assert!((0..2).all(|d| (s[d] - target[d]).abs() < 0.5), "the loop lets go at {t0} s: {s:?}");
        writeln!(csv, "{t0:.6},{:.9},{:.9},{:.9},{:.9}", s[0], s[1], u[0], u[1]).expect("writes to a string");
        for step in 0..50 {
            s = rk4_step(s, t0 + f64::from(step) * h, h, &|x, _| double_pendulum_accel(x, u, [0.0, 0.0], (0.0, 0.0)));
        }
    }
    csv
}

/// [`double_pendulum_with_load_csv`], driven by [`drive_torques`] (recorded as efforts) where
/// `drive` is given, logged as `log` says.
fn logged_double_pendulum_csv(
    q1: f64,
    q2: f64,
    duration_s: f64,
    friction: [f64; 2],
    load: (f64, f64),
    drive: Option<(f64, f64)>,
    log: Log,
) -> String {
    let accel = |s: [f64; 4], t: f64| double_pendulum_accel(s, drive.map_or([0.0, 0.0], |d| drive_torques(d, t)), friction, load);
    let mut s = [q1, q2, 0.0, 0.0];
    let h = 1e-4;
    let mut csv =
        String::from(if drive.is_some() { "time,shoulder.q,elbow.q,shoulder.effort,elbow.effort\n" } else { "time,shoulder.q,elbow.q\n" });
    let rate = f64::from(log.rate_hz);
    let samples = (duration_s * rate).round() as usize;
    let logged = |q: f64, t: f64| {
        let read = q + log.sway.0 * (std::f64::consts::TAU * log.sway.1 * t).sin();
        log.q_step.map_or(read, |step| (read / step).round() * step)
    };
    let mut clock = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for i in 0..=samples {
        let t0 = i as f64 / rate;
        let stamp = t0 + log.stamp_jitter_s * (2.0 * clock.random::<f64>() - 1.0);
        write!(csv, "{stamp:.6},{:.9},{:.9}", logged(s[0], t0), logged(s[1], t0)).expect("writes to a string");
        if let Some(d) = drive {
            let u = drive_torques(d, t0);
            write!(csv, ",{:.9},{:.9}", u[0], u[1]).expect("writes to a string");
        }
        csv.push('\n');
        for step in 0..(10_000 / log.rate_hz) {
            s = rk4_step(s, t0 + f64::from(step) * h, h, &accel);
        }
    }
    csv
}

/// Broke: a chain's replay started at rest at q = 0 (its smoothed state is missing at the very
/// first sample), so any recording that did not start hanging still reported a misfit before
/// and after fitting alike (about the swing itself, 0.3 rad here). A recording made from the
/// model's own equations must replay to the integration error (semi-implicit Euler at 0.5 ms
/// over 5 s: under 0.02 rad of a 1 rad swing), from wherever it starts, and name nothing.
#[test]
fn a_double_pendulum_released_away_from_rest_replays_from_its_own_start() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    let rec = parse_recording(&double_pendulum_csv(0.6, -0.4, 5.0, [0.0, 0.0]), Path::new("released.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    assert!(report.effects.is_empty(), "nothing is missing: {:?}", report.effects);
    for joint in ["shoulder", "elbow"] {
        let fit = &report.fit.per_joint[joint];
        assert!(fit.rmse_before < 0.02, "{joint}: the replay misses the recording by {} rad", fit.rmse_before);
        let held = &report.held_out.per_joint[joint];
        assert!(held.rmse_before < 0.02, "{joint}: the held-out replay misses by {} rad", held.rmse_before);
    }
}

/// Broke: one joint of the model without a recorded position (a gripper's finger on an arm
/// whose joints alone are logged) sent the whole tree to position space, where a 7-joint arm
/// took 50 s and was read as springs, dampers and `unknown` on every joint. A subtree nothing
/// measures is now welded where it stands (held at 0, as the note says) and the measured joints
/// keep effort space: a double pendulum carrying a gripper on a slide that no column records,
/// released, replays to the integration error and names nothing.
#[test]
fn a_gripper_that_is_not_recorded_rides_welded_and_the_arm_keeps_effort_space() {
    let with_gripper = DOUBLE_PENDULUM.replace(
        "</robot>",
        r#"<link name="finger"><inertial><origin xyz="0 0 0"/><mass value="0.2"/>
    <inertia ixx="0.0002" iyy="0.0002" izz="0.0001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="finger_slide" type="prismatic"><parent link="lower"/><child link="finger"/><origin xyz="0 0 -0.28"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.04" effort="10" velocity="0.2"/></joint>
</robot>"#,
    );
    let model = parse_model(&with_gripper, Path::new("gripper.urdf")).expect("model parses");
    let csv = double_pendulum_with_load_csv(0.6, -0.4, 5.0, [0.0, 0.0], (0.2, 0.0002));
    let rec = parse_recording(&csv, Path::new("arm_only.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    assert!(report.effects.is_empty(), "nothing is missing: {:?}", report.effects);
    for joint in ["shoulder", "elbow"] {
        assert_eq!(report.joints[joint].mode, "effort", "{joint}: {}", report.joints[joint].why);
        let fit = &report.fit.per_joint[joint];
        assert!(fit.rmse_before < 0.02, "{joint}: the replay misses the recording by {} rad", fit.rmse_before);
    }
    assert!(report.notes.iter().any(|n| n.contains("finger_slide") && n.contains("welded")), "{:?}", report.notes);
}

/// Broke: a log written at 1 kHz that holds a 200 Hz signal between its updates (topics merged at
/// different rates, a logger faster than its encoder) reads as a joint that stops and jumps every
/// five samples; a 7-joint arm logged so was read as viscous damping where it has dry friction,
/// Coulomb levels ×3 and `unknown`. The repeats are read as missing samples: the double pendulum
/// released, logged that way, replays to the integration error and names nothing.
#[test]
fn a_log_that_holds_each_reading_for_five_rows_is_read_as_its_updates() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    let csv = double_pendulum_csv(0.6, -0.4, 5.0, [0.0, 0.0]);
    let mut held = String::from("time,shoulder.q,elbow.q\n");
    for line in csv.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let t: f64 = cells[0].parse().expect("a time");
        for k in 0..5 {
            writeln!(held, "{:.4},{},{}", t + 0.001 * f64::from(k), cells[1], cells[2]).expect("writes to a string");
        }
    }
    let rec = parse_recording(&held, Path::new("held.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    assert!(report.effects.is_empty(), "nothing is missing: {:?}", report.effects);
    for joint in ["shoulder", "elbow"] {
        let fit = &report.fit.per_joint[joint];
        assert!(fit.rmse_before < 0.02, "{joint}: the replay misses the recording by {} rad", fit.rmse_before);
        assert!(report.notes.iter().any(|n| n.starts_with(&format!("{joint}.q:")) && n.contains("read as missing")), "{:?}", report.notes);
    }
}

/// A door on a vertical hinge (no gravity along it), 0.35 kg·m² about its axis.
const DOOR: &str = r#"<robot name="door"><link name="frame"/>
  <link name="panel"><inertial><origin xyz="0.25 0 0"/><mass value="4"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="frame"/><child link="panel"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="10"/></joint>
</robot>"#;

/// [`DOOR`] with dry friction of `friction` N·m that holds it exactly (written out by hand, not
/// the library's simulation): pushed 0.4 s at 1.5 N·m one way, then the other, then the first,
/// each push left to coast to a stop, a hand's effort under the friction varying between the
/// pushes (0.3 sin 4.1t N·m) and, from 4.2 s on, through the rest of the 8 s (0.4 sin 2.3t):
/// the door rests there, held by its friction. Noise-free (its rests repeat exactly), 200 Hz.
fn door_with_rests_csv(friction: f64) -> String {
    let inertia = 0.35;
    let effort = |t: f64| -> f64 {
        match t {
            t if t < 0.4 => 1.5,
            t if (1.4..1.8).contains(&t) => -1.5,
            t if (2.8..3.2).contains(&t) => 1.5,
            t if t >= 4.2 => 0.4 * (2.3 * t).sin(),
            t => 0.3 * (4.1 * t).sin(),
        }
    };
    let (mut q, mut v) = (0.0_f64, 0.0_f64);
    let mut csv = String::from("time,hinge.q,hinge.effort\n");
    for i in 0..1600 {
        let t = f64::from(i) / 200.0;
        let u = effort(t + 1e-9);
        writeln!(csv, "{t:.4},{q:.12},{u:.9}").expect("writes to a string");
        for _ in 0..50 {
            let h = 1e-4;
            if v == 0.0 && u.abs() <= friction {
                continue;
            }
            let resist = if v == 0.0 { friction * u.signum() } else { friction * v.signum() };
            let next = v + h * (u - resist) / inertia;
            // Friction stops it rather than turning it round.
            v = if v != 0.0 && next.signum() != v.signum() { 0.0 } else { next };
            q += h * v;
        }
    }
    csv
}

/// Broke: a door that its dry friction holds most of the time (`JaxSim`'s recording of a door
/// pushed toward random targets rests 66 % of the time and through the whole held-out part; DART
/// on the same pushes alike) got viscous damping and `unknown`: dry friction was "better in only
/// 62 % of the held-out blocks", the blocks where the door rests counting against it, though a
/// law of the joint's speed can say nothing where it does not move. Such blocks no longer count
/// for laws of the motion: here dry friction is better in every block where the door moves
/// (before: 7 of 8 blocks, confidence 0.87). And its exact rests, which break away slowly, are
/// readings, not a stale log's repeats (before the rule looked at the step after a jump, 124
/// samples were read as missing).
#[test]
fn a_door_that_its_friction_holds_through_the_held_out_part_is_read_as_dry_friction() {
    let model = parse_model(DOOR, Path::new("door.urdf")).expect("model parses");
    let rec = parse_recording(&door_with_rests_csv(0.5), Path::new("door.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let found: Vec<String> =
        report.effects.iter().map(|e| format!("{}:{} {:?} c={:.2}", e.joint, e.kind, e.params, e.confidence)).collect();
    assert_eq!(report.effects.len(), 1, "{found:?}");
    let dry = &report.effects[0];
    assert!(dry.kind == "coulomb_friction" && (dry.params["friction"] - 0.5).abs() < 0.125, "{found:?}");
    assert!(dry.confidence >= 0.95, "{found:?}");
    assert!(!report.notes.iter().any(|n| n.contains("read as missing")), "its exact rests are readings: {:?}", report.notes);
}

/// Broke: a chain held up by a discrete PD loop too stiff for its sampling (its efforts swing
/// from sample to sample faster than the 200 Hz positions resolve) was explained by the model's
/// own first-moment error: centres of mass moved by a metre, written into the fitted URDF
/// without a word. The report now says the model's rigid bodies do not describe the recording;
/// the same loop with gains its sampling resolves does not ask.
#[test]
fn efforts_no_rigid_body_error_explains_are_said_not_to_fit_the_model() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    let calm = held_double_pendulum_csv([2.8, 0.3], 8.0, 0.3, 6.0);
    let stiff = held_double_pendulum_csv([2.8, 0.3], 30.0, 3.0, 6.0);
    for (text, said) in [(calm.as_str(), false), (stiff.as_str(), true)] {
        let rec = parse_recording(text, Path::new("driven.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let note = report.notes.iter().find(|n| n.contains("do not describe this recording"));
        assert_eq!(note.is_some(), said, "{:?}", report.notes);
        assert!(note.is_none_or(|n| n.contains("lower") && n.contains("upper")), "{note:?}");
    }
}

/// A recording whose efforts are of the opposite sign to the model's convention (a driver that
/// reports the load's torque on the motor, say) was read as a spring of 63 N·m/rad and `unknown`
/// on a Panda's joint, with nothing to say why. The report now asks about the sign, and only
/// there: the same door with its efforts as recorded is not asked.
#[test]
fn efforts_of_the_opposite_sign_are_questioned_in_the_report() {
    let model = parse_model(DOOR, Path::new("door.urdf")).expect("model parses");
    let csv = door_with_rests_csv(0.5);
    let mut flipped = String::new();
    for (i, line) in csv.lines().enumerate() {
        if i == 0 {
            writeln!(flipped, "{line}").expect("writes to a string");
            continue;
        }
        let (head, effort) = line.rsplit_once(',').expect("three cells");
        let value: f64 = effort.parse().expect("a number");
        writeln!(flipped, "{head},{}", -value).expect("writes to a string");
    }
    for (text, asked) in [(csv.as_str(), false), (flipped.as_str(), true)] {
        let rec = parse_recording(text, Path::new("door.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let why = &report.joints["hinge"].why;
        assert_eq!(why.contains("runs against the effort the model needs"), asked, "{why}");
    }
}

/// The real recordings of `../shared/data/recordings/` (made by others on real hardware), or
/// None with a loud skip when the shared data are absent.
/// A real recording's folder in the shared data (which may be absent).
fn shared_case_dir(case: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/recordings").join(case)
}

/// A shared real recording's `reference.json` (its published model and effects).
fn shared_reference(case: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(shared_case_dir(case).join("reference.json")).expect("reference");
    serde_json::from_str(&text).expect("reference.json parses")
}

/// The real double pendulum's main run (`recording.csv`) analysed with the default config, once
/// for every test that reads it (None where the shared data are absent).
fn dfki_double_pendulum_main_run() -> Option<&'static GapReport> {
    static REPORT: OnceLock<Option<GapReport>> = OnceLock::new();
    REPORT
        .get_or_init(|| {
            let (model, rec) = shared_recording("dfki_double_pendulum", "recording.csv")?;
            Some(analyze(&model, &rec, &GapConfig::default()).expect("analyses"))
        })
        .as_ref()
}

fn shared_recording(case: &str, file: &str) -> Option<(GapModel, partscene::gap::Recording)> {
    let dir = shared_case_dir(case);
    if !dir.is_dir() {
        eprintln!("SKIPPED: {} is absent (real recordings are read from the shared data)", dir.display());
        return None;
    }
    let model_text = std::fs::read_to_string(dir.join("model.urdf")).expect("model");
    let model = parse_model(&model_text, &dir.join("model.urdf")).expect("model parses");
    let text = std::fs::read_to_string(dir.join(file)).expect("recording");
    Some((model, parse_recording(&text, &dir.join(file)).expect("recording parses")))
}

/// Broke: on the real double pendulum's second excitation run, a Stribeck law with a break-away
/// six times its sliding level (a speed-shaped bump, no static friction) and a spring stood in
/// for the elbow's friction, and the fitted model replayed no better than 0.5 rad. Whatever is
/// named, none of it may be a break-away beyond 3× the sliding level, and the fitted model must
/// replay the recorded torques far better than the model as written.
#[test]
fn a_real_double_pendulum_gets_no_speed_shaped_bump_for_friction() {
    let Some((model, rec)) = shared_recording("dfki_double_pendulum", "recording_traj00.csv") else { return };
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    for e in report.effects.iter().filter(|e| e.kind == "stribeck_friction") {
        assert!(e.params["breakaway"] <= 3.0 * e.params["friction"], "{}: {}", e.joint, e.description);
    }
    assert!(report.fit.rmse_after < 0.25 * report.fit.rmse_before, "replay {} -> {} rad", report.fit.rmse_before, report.fit.rmse_after);
}

/// A chain joint's term of the shape the model's own inertia and weight errors take is kept only
/// where the joint's held-out replay is worse without it. The real double pendulum's geared
/// rotors are such terms that the motion does show (the published model has them on both
/// joints; without the elbow's, its held-out replay error is hundreds of times larger): the check
/// must keep the elbow's, and the fitted chain must still replay its held-out part closely.
#[test]
fn a_real_double_pendulums_rotor_inertia_survives_the_replay_check() {
    let Some(report) = dfki_double_pendulum_main_run() else { return };
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
    assert!(report.effects.iter().any(|e| e.joint == "elbow" && e.kind == "armature"), "{found:?}");
    for joint in ["shoulder", "elbow"] {
        let held = &report.held_out.per_joint[joint];
        assert!(
            held.rmse_after < 0.1 * held.rmse_before,
            "{joint}: held-out replay {} -> {} rad: {found:?}",
            held.rmse_before,
            held.rmse_after
        );
    }
}

/// Broke: `MuJoCo`'s Panda with an exact model and dry friction on its first joint got a rotor
/// inertia of 0.006 kg·m² there (4 % of the inertial effort the joint needs), and against a model
/// a few percent off, armatures and heavier parts on joints whose inertia the errors change by that
/// much. An inertia error of the model's own size is not a missing rotor: the driven double
/// pendulum's lower link is 4.6 % heavier than modelled (and its inertia about its centre 0.0015
/// kg·m² larger), which no reading may call a rotor or a heavier part, and the report says why.
#[test]
fn a_link_a_few_percent_off_its_model_is_not_named_a_rotor() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    let csv = logged_double_pendulum_csv(0.6, -0.4, 10.0, [0.0, 0.0], (0.03, 0.0015), Some((0.6, 0.3)), Log::AT_200_HZ);
    let rec = parse_recording(&csv, Path::new("heavier_link.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    assert!(report.effects.is_empty(), "within the model's accuracy: {:?}", report.effects);
    let rejected = &report.joints["elbow"].rejected;
    assert!(rejected.iter().any(|r| r.starts_with("armature:") && r.contains("effort the model needs")), "{rejected:?}");
}

/// A heavier knob turning about its own centre of mass: gravity does no work on it, so a rotor's
/// inertia explains the recording exactly as well, and the report says so beside the heavier
/// part it names.
#[test]
fn a_heavier_knob_is_named_armature_with_the_heavier_part_as_the_other_reading() {
    // The spec: a heavier part scales inertia and weight together; inertia alone is armature.
    // Gravity does no work on a knob turning about its centre, so its weight is never seen.
    let model = parse_model(DOOR_AND_KNOB, Path::new("microwave.urdf")).expect("model parses");
    let cfg = GenerateConfig {
        duration_s: 8.0,
        seed: 7,
        effects: vec![("knob_joint".to_owned(), TrueEffect::ExtraInertia { scale: 2.0 })],
        ..GenerateConfig::default()
    };
    let rec = parse_recording(&generate_recording(&model, &cfg).expect("generates"), Path::new("gen.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{}", e.joint, e.kind)).collect();
    assert!(found.contains(&"knob_joint:armature".to_owned()), "the knob's extra inertia is armature: {found:?}");
    assert!(!found.contains(&"knob_joint:mass_scale".to_owned()), "{found:?}");
    let rejected = &report.joints["knob_joint"].rejected;
    let note = "mass_scale: explains the recording as well as the reported armature";
    assert!(rejected.iter().any(|r| r.starts_with(note)), "{rejected:?}");
}

/// A slider on a horizontal rail (gravity does no work on it).
const SLIDER: &str = r#"<robot name="rail"><link name="base"/>
  <link name="carriage"><inertial><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="carriage"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" effort="100" velocity="1"/></joint>
</robot>"#;

/// [`SLIDER`] driven forward for 8 s and back for 8 s (its speed wavers at 1.5 Hz but never
/// changes sign within a half), with the effort its 2 kg needs plus dry friction of
/// `friction` N (smooth over 5 mm/s) and a constant `offset` N added to the recorded effort.
fn slider_csv(friction: f64, offset: f64) -> String {
    let w = std::f64::consts::TAU * 1.5;
    let travel = |t: f64| 0.05 * t + 0.03 / w * (1.0 - (w * t).cos());
    let mut csv = String::from("time,slide.q,slide.effort\n");
    for i in 0..=3200 {
        let t = f64::from(i) / 200.0;
        let (x, v, a) = if t < 8.0 {
            (0.05 + travel(t), 0.05 + 0.03 * (w * t).sin(), 0.03 * w * (w * t).cos())
        } else {
            let s = t - 8.0;
            (0.05 + travel(8.0) - travel(s), -(0.05 + 0.03 * (w * s).sin()), -0.03 * w * (w * s).cos())
        };
        let effort = 2.0 * a + friction * (v / 0.005).tanh() + offset;
        writeln!(csv, "{t:.4},{x:.9},{effort:.9}").expect("writes to a string");
    }
    csv
}

/// Broke: dry friction of 0.45 N and a 0.3 N bias of the recorded effort on a slider that moves
/// forward for half the recording and back for the other half. Neither a symmetric friction law
/// nor an offset lowers the held-out error in more than half of the held-out blocks, and the law
/// that explains both (friction that differs by direction: 0.75 N forward, 0.15 N back) could
/// only enter in place of a symmetric one: 84 % of the effort was reported `unknown`, and the
/// rejection said the friction was "better in only 100 % of the held-out blocks". Now the law by
/// direction enters whole and is read as robot identification reads it: the same friction both
/// ways and an offset (the spec's sign: the offset is what adds to the recorded effort).
#[test]
fn friction_with_an_offset_on_a_slider_that_moves_one_way_at_a_time_is_found() {
    let model = parse_model(SLIDER, Path::new("rail.urdf")).expect("model parses");
    let rec = parse_recording(&slider_csv(0.45, 0.3), Path::new("rail.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let found: Vec<(&str, f64)> =
        report.effects.iter().map(|e| (e.kind.as_str(), e.params.values().next().copied().unwrap_or(f64::NAN))).collect();
    let level = |kind: &str, param: &str| report.effects.iter().find(|e| e.kind == kind).map(|e| e.params[param]);
    assert_eq!(report.effects.len(), 2, "{found:?}");
    assert!(level("coulomb_friction", "friction").is_some_and(|f| (f - 0.45).abs() < 0.02), "{found:?}");
    assert!(level("effort_offset", "offset").is_some_and(|o| (o + 0.3).abs() < 0.02), "{found:?}");
}

/// [`SLIDER`] pulled by a speed servo through slow and fast spells, both ways (+20 mm/s for
/// 1.5 s, +0.25 m/s for 0.4 s, then the same back; 0.1 s cosine ramps between), for 16 s, with
/// the effort its 2 kg needs plus dry friction `friction` N that breaks away at `breakaway` N
/// below `stribeck_speed` (the spec's law, smooth through zero over 2 mm/s).
fn slow_pull_csv(friction: f64, breakaway: f64, stribeck_speed: f64) -> String {
    const LEVELS: [(f64, f64); 4] = [(0.02, 1.5), (0.25, 0.4), (-0.25, 0.4), (-0.02, 1.5)];
    const RAMP_S: f64 = 0.1;
    let cycle_s: f64 = LEVELS.iter().map(|l| l.1).sum();
    let speed = |t: f64| -> (f64, f64) {
        let (mut start, mut previous, t) = (0.0, LEVELS[3].0, t % cycle_s);
        for (level, duration) in LEVELS {
            if t < start + duration {
                let s = t - start;
                if s >= RAMP_S {
                    return (level, 0.0);
                }
                let phase = std::f64::consts::PI * s / RAMP_S;
                return (
                    previous + (level - previous) * 0.5 * (1.0 - phase.cos()),
                    (level - previous) * 0.5 * phase.sin() * std::f64::consts::PI / RAMP_S,
                );
            }
            start += duration;
            previous = level;
        }
        (previous, 0.0)
    };
    let mut x = 0.2;
    let mut csv = String::from("time,slide.q,slide.effort\n");
    for i in 0..=3200 {
        let t = f64::from(i) / 200.0;
        let (v, a) = speed(t);
        let dry = (friction + (breakaway - friction) * (-(v / stribeck_speed).powi(2)).exp()) * (v / 0.002).tanh();
        writeln!(csv, "{t:.4},{x:.9},{:.9}", 2.0 * a + dry).expect("writes to a string");
        for k in 0..50 {
            x += 1e-4 * speed(t + (f64::from(k) + 0.5) * 1e-4).0;
        }
    }
    csv
}

/// A Stribeck law is named where the joint slides slowly, not only where it turns: a slider
/// pulled at 20 mm/s for spells of 1.5 s with 1 N of friction breaking away at 1.8 N below
/// 30 mm/s gets its break-away (the release before dry friction was also read on the smoothed
/// speed: 2.75 N), and the same pulls with plain Coulomb friction get Coulomb friction.
#[test]
fn a_slider_pulled_slowly_gets_its_break_away() {
    let model = parse_model(SLIDER, Path::new("rail.urdf")).expect("model parses");
    for (breakaway, kind) in [(1.8, "stribeck_friction"), (1.0, "coulomb_friction")] {
        let rec = parse_recording(&slow_pull_csv(1.0, breakaway, 0.03), Path::new("rail.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
        assert_eq!(report.effects.len(), 1, "{found:?}");
        let e = &report.effects[0];
        assert_eq!(e.kind, kind, "{found:?}");
        assert!((e.params["friction"] - 1.0).abs() < 0.15, "{found:?}");
        if let Some(b) = e.params.get("breakaway") {
            assert!((b - breakaway).abs() < 0.25 * breakaway, "{found:?}");
        }
    }
}

/// Broke: on the real double pendulum's main run, effort space read the elbow's friction as
/// viscous damping (its efforts fit a little better than with dry friction), and the fitted
/// model replayed the held-out part about twice as badly as with dry friction in its place
/// (elbow 0.019 against 0.010 rad). Both laws are now replayed; the elbow's friction is dry,
/// and the held-out replay of each joint is within 0.016 rad.
#[test]
fn a_real_double_pendulums_elbow_friction_is_read_by_the_motion_it_predicts() {
    let Some(report) = dfki_double_pendulum_main_run() else { return };
    let elbow: Vec<&str> = report.effects.iter().filter(|e| e.joint == "elbow").map(|e| e.kind.as_str()).collect();
    assert!(elbow.contains(&"coulomb_friction") && !elbow.contains(&"viscous_damping"), "{elbow:?}");
    for joint in ["shoulder", "elbow"] {
        let held = &report.held_out.per_joint[joint];
        assert!(held.rmse_after < 0.016, "{joint}: held-out replay {} rad", held.rmse_after);
    }
}

/// Broke: on the real double pendulum's main run, effort space was read in a band that passes the
/// excitation's third harmonic, which the encoders show and the motors never drive (the model as
/// written needs four times the recorded effort there), and matched it with a lower link 20 %
/// lighter than the published one and 56 % of the shoulder's published friction. Read below
/// that band, dry friction is named on both joints within 30 % of the levels published for
/// this run, and no part is lighter or heavier than modelled.
#[test]
fn a_real_double_pendulums_friction_is_read_below_what_its_encoders_sway() {
    let Some(report) = dfki_double_pendulum_main_run() else { return };
    let reference = shared_reference("dfki_double_pendulum");
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
    for joint in ["shoulder", "elbow"] {
        let published = reference["effects"]
            .as_array()
            .and_then(|effects| effects.iter().find(|e| e["joint"] == joint && e["kind"] == "coulomb_friction"))
            .and_then(|e| e["params"]["friction"].as_f64())
            .expect("the reference names each joint's friction");
        let dry = report.effects.iter().find(|e| e.joint == joint && e.kind == "coulomb_friction");
        assert!(dry.is_some_and(|e| (e.params["friction"] / published - 1.0).abs() < 0.3), "{joint} (published {published}): {found:?}");
    }
    assert!(!report.effects.iter().any(|e| e.kind == "mass_scale"), "{found:?}");
}

/// Broke: on the real double pendulum's main run, the shoulder's rotor that only the whole
/// recording's reading holds was tested by replaying the training part with the shoulder read as
/// the whole recording reads it but the elbow as the training part reads it (a part 0.8× as
/// heavy and a spring the whole reading does not hold); that mix replayed 3× worse, and the
/// rotor was dropped for `unknown` (21 % of the shoulder's effort). Every joint is now read as the
/// whole recording reads it: both rotors are named within 30 % of the published geared rotors'
/// inertia on each diagonal, nothing is `unknown`, and the fitted chain replays the whole run
/// open loop within 0.03 rad (the published model, integrated by the data's own check: 0.017).
#[test]
fn a_real_double_pendulums_shoulder_rotor_is_tested_beside_the_whole_readings_elbow() {
    let Some(report) = dfki_double_pendulum_main_run() else { return };
    let reference = shared_reference("dfki_double_pendulum");
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
    let rotors = &reference["not_expressible"][0]["mass_matrix_terms"];
    for (joint, term) in [("shoulder", "M11"), ("elbow", "M22")] {
        let published = rotors[term].as_f64().expect("the reference gives the rotors' mass-matrix terms");
        let rotor = report.effects.iter().find(|e| e.joint == joint && e.kind == "armature");
        assert!(rotor.is_some_and(|e| (e.params["armature"] / published - 1.0).abs() < 0.3), "{joint} (published {published}): {found:?}");
    }
    assert!(!report.effects.iter().any(|e| e.kind == "unknown"), "{found:?}");
    assert!(report.fit.rmse_after < 0.03, "replay {} rad: {found:?}", report.fit.rmse_after);
}

/// The replay rule must not turn a right reading round: a double pendulum with dry friction at
/// both joints (the library's multibody code plays no part in making it), released and left to
/// swing, is read as dry friction at both (levels within 25 %), with no viscous damping.
#[test]
fn a_chain_with_dry_friction_keeps_it_through_the_replay_check() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    let rec = parse_recording(&double_pendulum_csv(1.2, -0.6, 10.0, [0.1, 0.05]), Path::new("dry.csv")).expect("parses");
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
    for (joint, level) in [("shoulder", 0.1), ("elbow", 0.05)] {
        let dry = report.effects.iter().find(|e| e.joint == joint && e.kind == "coulomb_friction");
        assert!(dry.is_some_and(|e| (e.params["friction"] - level).abs() < 0.25 * level), "{joint}: {found:?}");
        assert!(!report.effects.iter().any(|e| e.joint == joint && e.kind == "viscous_damping"), "{joint}: {found:?}");
    }
}

/// Broke: a real Panda's 1 kHz log (positions to 10⁻⁴ rad, time stamps 0.7-1.8 ms apart) was
/// differentiated over three samples, 3 ms, whose noise friction's sign of the speed and the
/// velocity products turn into effort: `unknown` of 0.8-1 N·m and no friction on the three
/// proximal joints, where the same log taken at 200 Hz named friction on all seven. A driven
/// double pendulum with dry friction at both joints, logged at 1 and 2 kHz with its positions
/// rounded to 10⁻³ rad and its stamps up to 0.3 ms off (read that way at 1 kHz: `unknown` on both
/// joints, no friction), reads as logged at 200 Hz: dry friction at both joints (levels within
/// 25 %), nothing else; at 2 kHz it is read at a working rate, as every chain logged far faster
/// than its motion.
#[test]
fn a_fast_log_of_coarse_positions_reads_as_a_slower_one() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    // Stamps up to 0.3 ms off where they stay in order, 0.2 ms at 2 kHz.
    for (rate_hz, stamp_jitter_s) in [(200, 3e-4), (1000, 3e-4), (2000, 2e-4)] {
        let log = Log { rate_hz, q_step: Some(1e-3), stamp_jitter_s, ..Log::AT_200_HZ };
        let csv = logged_double_pendulum_csv(0.3, -0.2, 10.0, [0.1, 0.05], (0.0, 0.0), Some((0.6, 0.3)), log);
        let rec = parse_recording(&csv, Path::new("logged.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
        assert_eq!(report.effects.len(), 2, "{rate_hz} Hz: {found:?}");
        // The 2 kHz log is read at a working rate (the chain's identification costs its samples).
        assert_eq!(report.notes.iter().any(|n| n.contains("read at every")), rate_hz == 2000, "{:?}", report.notes);
        for (joint, level) in [("shoulder", 0.1), ("elbow", 0.05)] {
            let dry = report.effects.iter().find(|e| e.joint == joint && e.kind == "coulomb_friction");
            assert!(dry.is_some_and(|e| (e.params["friction"] - level).abs() < 0.25 * level), "{rate_hz} Hz, {joint}: {found:?}");
        }
    }
}

/// Broke: the real double pendulum's encoders read its excitation's third harmonic, which its
/// motors never drive (a sensor on the motor side of a compliant drive sways where the link does
/// not), and effort space, filtered to pass it, read the rigid bodies' effort for that sway as
/// a lower link 20 % lighter and 56 % of the shoulder's friction. A band where both the model as
/// written and the fitted one need more than twice the recorded effort is beyond the rigid
/// bodies, and a narrower one is read. A driven double pendulum with dry friction whose position
/// sensors sway by 10 mrad at 3 Hz (three times its motion's frequency; its efforts do not: read
/// in the band that passes it, `unknown` on both joints) reads as without the sway: dry friction
/// at both joints (levels within 25 %), nothing else.
#[test]
fn a_sway_the_position_sensors_read_and_the_efforts_do_not_is_not_read_as_physics() {
    let model = parse_model(DOUBLE_PENDULUM, Path::new("double_pendulum.urdf")).expect("model parses");
    for sway in [(0.0, 0.0), (1e-2, 3.0)] {
        let log = Log { sway, ..Log::AT_200_HZ };
        let csv = logged_double_pendulum_csv(0.3, -0.2, 10.0, [0.1, 0.05], (0.0, 0.0), Some((0.6, 0.3)), log);
        let rec = parse_recording(&csv, Path::new("swaying.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
        assert_eq!(report.effects.len(), 2, "sway {sway:?}: {found:?}");
        for (joint, level) in [("shoulder", 0.1), ("elbow", 0.05)] {
            let dry = report.effects.iter().find(|e| e.joint == joint && e.kind == "coulomb_friction");
            assert!(dry.is_some_and(|e| (e.params["friction"] - level).abs() < 0.25 * level), "sway {sway:?}, {joint}: {found:?}");
        }
    }
}

/// Broke: on the real DFKI pendulum, output error "refined" effort space's reading (Coulomb
/// 0.16 N·m, a part ×1.23 as heavy, a rotor's inertia of 0.009 kg·m²) to Coulomb 0.15, ×1.29 and
/// 0.016, a reading that replays the swing-up worse (0.110 against 0.042 rad) and the held-out
/// part too (0.114 against 0.028 rad). A refinement that moves the effects' effort by a
/// material share of the joint's own is now kept only where it replays the recording clearly
/// better. The fitted model must also replay the recording better than the published model
/// (its identified viscous and Coulomb friction in `<dynamics>`) does.
#[test]
fn a_real_pendulums_reading_is_not_refined_into_one_that_replays_worse() {
    let Some((model, rec)) = shared_recording("dfki_pendulum", "recording.csv") else { return };
    let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
    let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
    assert!(report.effects.iter().any(|e| e.kind == "coulomb_friction"), "{found:?}");
    let held = &report.held_out.per_joint["shoulder"];
    assert!(held.rmse_after < 0.05, "held-out replay {} -> {} rad: {found:?}", held.rmse_before, held.rmse_after);
    // The published model: the same URDF with the reference's friction in `<dynamics>`.
    let dir = shared_case_dir("dfki_pendulum");
    let reference = shared_reference("dfki_pendulum");
    let level = |kind: &str, name: &str| {
        reference["effects"]
            .as_array()
            .and_then(|effects| effects.iter().find(|e| e["kind"] == kind))
            .and_then(|e| e["params"][name].as_f64())
            .unwrap_or_else(|| panic!("the reference names {kind}"))
    };
    let urdf = std::fs::read_to_string(dir.join("model.urdf")).expect("model").replacen(
        "</joint>",
        &format!(
            r#"<dynamics damping="{}" friction="{}"/></joint>"#,
            level("viscous_damping", "damping"),
            level("coulomb_friction", "friction")
        ),
        1,
    );
    let published = parse_model(&urdf, &dir.join("model.urdf")).expect("published model parses");
    let published = analyze(&published, &rec, &GapConfig::default()).expect("analyses");
    let (ours, theirs) = (report.fit.per_joint["shoulder"].rmse_after, published.fit.per_joint["shoulder"].rmse_before);
    assert!(ours < theirs, "replay {ours} rad against the published model's {theirs}: {found:?}");
}

/// Broke: the real pendulum's swing-up logged as a driver keeps a continuous joint's angle, within
/// one turn ([0, 2π)), read as jumps of a full turn between samples: `unknown` of 137 N·m and a
/// held-out replay 4 rad off. Unwrapped, it reads as the recording that holds the whole angle.
#[test]
fn a_real_pendulum_logged_within_one_turn_reads_as_its_whole_angle() {
    let Some((model, rec)) = shared_recording("dfki_pendulum", "recording.csv") else { return };
    let dir = shared_case_dir("dfki_pendulum");
    let text = std::fs::read_to_string(dir.join("recording.csv")).expect("recording");
    let mut wrapped = String::new();
    let mut q_column: Option<usize> = None;
    for line in text.lines() {
        if line.starts_with('#') {
            writeln!(wrapped, "{line}").expect("writes to a string");
        } else if let Some(c) = q_column {
            let mut cells: Vec<String> = line.split(',').map(str::to_owned).collect();
            if let Ok(q) = cells[c].parse::<f64>() {
                cells[c] = format!("{}", q.rem_euclid(std::f64::consts::TAU));
            }
            writeln!(wrapped, "{}", cells.join(",")).expect("writes to a string");
        } else {
            q_column = line.split(',').position(|h| h == "shoulder.q");
            writeln!(wrapped, "{line}").expect("writes to a string");
        }
    }
    let logged = parse_recording(&wrapped, &dir.join("recording.csv")).expect("the wrapped recording parses");
    let turns = logged.joint_q["shoulder"].windows(2).filter(|w| (w[1] - w[0]).abs() > std::f64::consts::PI).count();
    assert!(turns > 0, "the swing-up crosses the wrap");
    let (whole, within) = (
        analyze(&model, &rec, &GapConfig::default()).expect("analyses"),
        analyze(&model, &logged, &GapConfig::default()).expect("analyses"),
    );
    let effects = |r: &partscene::gap::GapReport| r.effects.iter().map(|e| (e.kind.clone(), e.params.clone())).collect::<Vec<_>>();
    let (a, b) = (effects(&whole), effects(&within));
    assert_eq!(a.iter().map(|e| &e.0).collect::<Vec<_>>(), b.iter().map(|e| &e.0).collect::<Vec<_>>(), "{a:?} against {b:?}");
    for ((_, pa), (_, pb)) in a.iter().zip(&b) {
        for (name, x) in pa {
            assert!((x - pb[name]).abs() <= 1e-6 * x.abs().max(1e-9), "{name}: {x} against {}", pb[name]);
        }
    }
    assert!(within.notes.iter().any(|n| n.contains("wrapped round a full turn")), "{:?}", within.notes);
}

/// [`SLIDER`] moved by a sum of three sines about the middle of its travel (0.3, 0.7 and
/// 1.3 Hz; RMS speed 77 mm/s, 181 at most, times `sway`) for 16 s, with the effort its 2 kg
/// needs plus dry friction `friction` N smooth over `transition_speed` m/s and viscous damping
/// `damping` N·s/m.
fn swaying_slider_csv(sway: f64, friction: f64, transition_speed: f64, damping: f64) -> String {
    const SINES: [(f64, f64, f64); 3] = [(0.04, 0.3, 0.0), (0.015, 0.7, 1.1), (0.006, 1.3, 2.3)];
    let mut csv = String::from("time,slide.q,slide.effort\n");
    for i in 0..=3200 {
        let t = f64::from(i) / 200.0;
        let (mut x, mut v, mut a) = (0.25, 0.0, 0.0);
        for (amplitude, hz, phase) in SINES {
            let (amplitude, w) = (sway * amplitude, std::f64::consts::TAU * hz);
            x += amplitude * (w * t + phase).sin();
            v += amplitude * w * (w * t + phase).cos();
            a -= amplitude * w * w * (w * t + phase).sin();
        }
        let effort = 2.0 * a + friction * (v / transition_speed).tanh() + damping * v;
        writeln!(csv, "{t:.4},{x:.9},{effort:.9}").expect("writes to a string");
    }
    csv
}

/// (sway, friction N, transition m/s, damping N·s/m) -> the kinds named.
type SlideCase = ((f64, f64, f64, f64), &'static [&'static str]);

/// Broke: friction smooth over a transition as wide as the joint's own speeds (real joints'
/// friction is smooth over 0.05-0.4 rad/s; the Panda's published law over 0.12-0.39) was read
/// as a sharper law plus viscous damping, or as damping alone: the transition speeds tried
/// stopped at 0.3× the RMS speed. And once they reached it, dry friction beside a damper, and
/// damping alone, were read as friction smooth over a wide transition (engines' doors; a door
/// tracked by its pose). And friction smooth over more than a slow joint's RMS speed, though
/// less than its fastest, was read as a sharper law beside damping (the transitions tried
/// stopped at 1.2× the RMS speed; `MuJoCo`'s Panda under the published law, its joint 5 at 0.11
/// rad/s RMS against a transition of 0.24: damping and a lighter part). Each reading where it
/// belongs: (sway, friction N, transition m/s, damping N·s/m) -> the kinds named.
#[test]
fn friction_as_wide_as_the_motion_is_not_damping_and_damping_is_not_wide_friction() {
    let model = parse_model(SLIDER, Path::new("rail.urdf")).expect("model parses");
    let cases: [SlideCase; 6] = [
        ((1.0, 1.0, 0.06, 0.0), &["coulomb_friction"]),
        ((1.0, 1.0, 0.03, 0.0), &["coulomb_friction"]),
        ((1.0, 1.0, 0.002, 8.0), &["coulomb_friction", "viscous_damping"]),
        ((1.0, 0.0, 1.0, 8.0), &["viscous_damping"]),
        ((0.4, 1.0, 0.05, 0.0), &["coulomb_friction"]),
        ((0.4, 0.0, 1.0, 30.0), &["viscous_damping"]),
    ];
    for ((sway, friction, transition_speed, damping), kinds) in cases {
        let rec = parse_recording(&swaying_slider_csv(sway, friction, transition_speed, damping), Path::new("rail.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{} {:?}", e.kind, e.params)).collect();
        let mut named: Vec<&str> = report.effects.iter().map(|e| e.kind.as_str()).collect();
        named.sort_unstable();
        assert_eq!(named, kinds, "{transition_speed} m/s, {damping} N·s/m: {found:?}");
        let level = |kind: &str, param: &str| report.effects.iter().find(|e| e.kind == kind).map(|e| e.params[param]);
        if friction > 0.0 {
            assert!(level("coulomb_friction", "friction").is_some_and(|f| (f - friction).abs() < 0.15 * friction), "{found:?}");
        }
        if damping > 0.0 {
            assert!(level("viscous_damping", "damping").is_some_and(|d| (d - damping).abs() < 0.2 * damping), "{found:?}");
        } else {
            let got = level("coulomb_friction", "transition_speed").unwrap_or(0.0);
            assert!((got / transition_speed).ln().abs() < 0.5_f64.ln().abs(), "transition {got} against {transition_speed}: {found:?}");
        }
    }
}

/// Effort space's fitted centres of mass (the model's own accuracy) go into the fitted URDF's
/// `<inertial><origin>`; the links it did not move keep theirs.
#[test]
fn the_fitted_urdf_carries_the_centres_of_mass_effort_space_moved() {
    let model = model();
    let moved = model.links.iter().find(|l| l.mass_kg > 0.0).expect("a link with mass");
    let shift = [0.002, -0.001, 0.003];
    let text = partscene::gap::report::fitted_urdf(&model, &[], &[(moved.name.clone(), shift)].into_iter().collect()).expect("writes");
    let fitted = parse_model(&text, Path::new("f.urdf")).expect("fitted URDF parses");
    for (before, after) in model.links.iter().zip(&fitted.links) {
        let want = if before.name == moved.name { before.com_link_m + glam::DVec3::from_array(shift) } else { before.com_link_m };
        assert!((after.com_link_m - want).length() < 1e-9, "{}: {:?} against {want:?}", before.name, after.com_link_m);
    }
}

/// A turret arm: a yaw joint on a vertical axis, a shoulder and an elbow pitching beyond it,
/// each part's centre of mass off its joint.
const TURRET_ARM: &str = r#"<robot name="turret_arm"><link name="base"/>
  <link name="turret"><inertial><origin xyz="0.06 0.02 0.1"/><mass value="3"/><inertia ixx="0.03" iyy="0.03" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0.18 0 0"/><mass value="2"/><inertia ixx="0.004" iyy="0.03" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.15 0 0"/><mass value="1"/><inertia ixx="0.002" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="yaw" type="revolute"><parent link="base"/><child link="turret"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="50" velocity="3"/></joint>
  <joint name="shoulder" type="revolute"><parent link="turret"/><child link="upper"/><origin xyz="0 0 0.25"/><axis xyz="0 -1 0"/><limit lower="-2" upper="2.5" effort="80" velocity="3"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.35 0 0"/><axis xyz="0 -1 0"/><limit lower="-2.5" upper="2.5" effort="40" velocity="3"/></joint></robot>"#;

/// [`TURRET_ARM`] standing on a base turned by `world_from_base`, driven for `duration_s` by a
/// computed-torque loop on the level model (what a controller that believes the model sends)
/// towards three sines per joint, with smooth dry friction `friction` on each joint; 200 Hz.
fn turret_arm_csv(world_from_base: glam::DQuat, friction: [f64; 3], duration_s: f64) -> String {
    let model = parse_model(TURRET_ARM, Path::new("turret_arm.urdf")).expect("model parses");
    let (level, _) = model.multibody().expect("a tree");
    let plant = level.with_base_rotated(world_from_base);
    let gravity = glam::DVec3::new(0.0, 0.0, -9.81);
    let target = |t: f64| -> [f64; 3] {
        [
            1.2 * (0.31 * t).sin() + 0.3 * (1.13 * t).sin(),
            0.6 + 0.5 * (0.47 * t + 0.4).sin() + 0.15 * (1.7 * t).sin(),
            -0.9 + 0.6 * (0.59 * t + 1.0).sin() + 0.2 * (2.3 * t).sin(),
        ]
    };
    let accel = |s: &[f64; 6], u: &[f64; 3]| -> [f64; 3] {
        let tau: Vec<f64> = (0..3).map(|d| u[d] - friction[d] * (s[3 + d] / 0.01).tanh()).collect();
        let a = plant.forward_dynamics(&s[..3], &s[3..], &tau, gravity).expect("positive definite");
        [a[0], a[1], a[2]]
    };
    let mut s = {
        let q = target(0.0);
        [q[0], q[1], q[2], 0.0, 0.0, 0.0]
    };
    let mut csv = String::from("time,yaw.q,shoulder.q,elbow.q,yaw.effort,shoulder.effort,elbow.effort\n");
    let h = 1e-3;
    for i in 0..=(duration_s * 200.0).round() as usize {
        let t0 = i as f64 / 200.0;
        let goal = target(t0);
        let (kp, kd) = (60.0, 12.0);
        let want: Vec<f64> = (0..3).map(|d| kp * (goal[d] - s[d]) - kd * s[3 + d]).collect();
        let held = level.inverse_dynamics(&s[..3], &s[3..], &want, gravity);
        let u = [held[0], held[1], held[2]];
        writeln!(csv, "{t0:.6},{:.9},{:.9},{:.9},{:.9},{:.9},{:.9}", s[0], s[1], s[2], u[0], u[1], u[2]).expect("writes to a string");
        for _ in 0..5 {
            // RK4 on (q, q̇) with the effort held.
            let f = |x: &[f64; 6]| -> [f64; 6] {
                let a = accel(x, &u);
                [x[3], x[4], x[5], a[0], a[1], a[2]]
            };
            let add = |x: &[f64; 6], k: &[f64; 6], c: f64| -> [f64; 6] { std::array::from_fn(|m| x[m] + c * k[m]) };
            let k1 = f(&s);
            let k2 = f(&add(&s, &k1, h / 2.0));
            let k3 = f(&add(&s, &k2, h / 2.0));
            let k4 = f(&add(&s, &k3, h));
            s = std::array::from_fn(|m| s[m] + h / 6.0 * (k1[m] + 2.0 * k2[m] + 2.0 * k3[m] + k4[m]));
        }
    }
    csv
}

/// A chain's tilted base was either nothing (no tilt candidate in a chain) or a spring on its
/// vertical base joint (a real Panda's joint 1). An arm on a base tilted 1° towards one side,
/// with dry friction on every joint, is read as a tilt of its base joint (its size within 20 %,
/// the direction it leans within 10°) beside the friction, with no spring; the fitted URDF stands
/// its base turned by the tilt. The same arm level gets no tilt.
#[test]
fn a_chain_on_a_tilted_base_is_read_as_its_base_joints_tilt_not_a_spring() {
    let model = parse_model(TURRET_ARM, Path::new("turret_arm.urdf")).expect("model parses");
    let lean_axis = glam::DVec3::new(0.6, 0.8, 0.0);
    let tilt_deg: f64 = 1.0;
    let tilted = glam::DQuat::from_axis_angle(lean_axis, tilt_deg.to_radians());
    for (turn, want_tilt) in [(tilted, true), (glam::DQuat::IDENTITY, false)] {
        let rec = parse_recording(&turret_arm_csv(turn, [0.3, 0.5, 0.2], 20.0), Path::new("turret.csv")).expect("parses");
        let report = analyze(&model, &rec, &GapConfig::default()).expect("analyses");
        let found: Vec<String> = report.effects.iter().map(|e| format!("{}:{} {:?}", e.joint, e.kind, e.params)).collect();
        let tilt = report.effects.iter().find(|e| e.kind == "gravity_tilt");
        assert_eq!(tilt.is_some(), want_tilt, "{found:?}");
        assert!(!report.effects.iter().any(|e| e.kind == "spring"), "{found:?}");
        for joint in ["yaw", "shoulder", "elbow"] {
            assert!(report.effects.iter().any(|e| e.joint == joint && e.kind == "coulomb_friction"), "{joint}: {found:?}");
        }
        let Some(tilt) = tilt else { continue };
        assert_eq!(tilt.joint, "yaw", "{found:?}");
        assert!((tilt.params["tilt_deg"] - tilt_deg).abs() < 0.2 * tilt_deg, "{found:?}");
        let axis = glam::DVec3::new(tilt.params["tilt_axis_x"], tilt.params["tilt_axis_y"], tilt.params["tilt_axis_z"]);
        assert!(axis.angle_between(lean_axis).to_degrees() < 10.0, "{axis:?}: {found:?}");
        // Gravity, seen from the base, leans along (0.8, −0.6): a part along the turret's x axis
        // rests where that axis points that way.
        let rest = (-0.6_f64).atan2(0.8);
        assert!((tilt.params["equilibrium_position"] - rest).abs() < 0.05, "{found:?}");
        // The fitted URDF's base joint stands turned as the recording's was, not mirrored.
        let text = partscene::gap::report::fitted_urdf(&model, &report.effects, &report.com_shift_m).expect("writes");
        let fitted = parse_model(&text, Path::new("fitted.urdf")).expect("fitted URDF parses");
        let zero = [0.0; 3];
        let (_, axis_world) = fitted.joint_frame_world(fitted.joint_index("yaw").expect("yaw"), &zero);
        let off = axis_world.angle_between(turn * glam::DVec3::Z).to_degrees();
        assert!(off < 0.1 * tilt_deg, "the fitted base stands {off}° off the recording's");
    }
}
