//! `--rerun FILE.rrd`: every pipeline stage is in the recording. The file is read back with
//! Rerun's own decoder and checked entity by entity.
#![cfg(feature = "rerun")]

use std::collections::BTreeSet;
use std::io::BufReader;

use partscene::kinematics::JointKind;
use partscene::observe::rerun::{RerunObserver, STAGE_TIMELINE};
use partscene::pipeline::{PinnedEdits, PipelineConfig, Quiet, reconstruct_observed};
use re_log_encoding::DecoderApp;
use rerun::log::{Chunk, LogMsg};

#[test]
fn the_recording_holds_every_stage_of_the_demo_room() {
    let (_, scan) = partscene::synth::demo(0);
    let dir = tempfile::tempdir().unwrap();
    let (scene, path) = recorded_demo(&scan, dir.path());

    let mut entities = BTreeSet::new();
    let mut stages = BTreeSet::new();
    for (entity, chunk) in chunks(&path) {
        entities.insert(entity);
        if let Some(column) = chunk.timelines().iter().find(|(name, _)| name.as_str() == STAGE_TIMELINE).map(|(_, c)| c) {
            stages.extend(column.times_raw().iter().copied());
        }
    }
    for part in &scan.parts {
        let e = format!("scan/object_{}/part_{}", part.object, part.id);
        assert!(entities.contains(&e), "missing {e}");
    }
    for part in &scene.parts {
        let e = format!("primitives/object_{}/part_{}", part.object, part.id);
        assert!(entities.contains(&e), "missing {e}");
    }
    for object in &scene.objects {
        for e in [format!("contact_graph/object_{}", object.id), format!("contact_graph/object_{}/tree", object.id)] {
            assert!(entities.contains(&e), "missing {e}");
        }
    }
    for j in scene.joints.iter().filter(|j| j.kind != JointKind::Fixed) {
        let object = scene.part(j.child).unwrap().object;
        let e = format!("joints/object_{object}/part_{}", j.child);
        assert!(entities.contains(&e), "missing {e}");
    }
    assert!(entities.iter().any(|e| e.starts_with("refinement/")), "no refinement steps");
    // Scan, fit, contact graph, then one step per refined part, then the final scene.
    let refined: usize = scene.joints.len();
    assert!(stages.contains(&0) && stages.contains(&1) && stages.contains(&2), "{stages:?}");
    assert!(stages.len() >= 3 + refined.min(10), "{} stages for {refined} refined parts", stages.len());
}

/// `scan` reconstructed while logging to `dir/demo.rrd`: the scene and the recording's path.
fn recorded_demo(scan: &partscene::scan::Scan, dir: &std::path::Path) -> (partscene::model::SceneModel, std::path::PathBuf) {
    let path = dir.join("demo.rrd");
    let observer = RerunObserver::save(&path).expect("the recording starts");
    let scene = reconstruct_observed(scan, &PipelineConfig::default(), &PinnedEdits::default(), &Quiet, &observer);
    drop(observer);
    (scene, path)
}

/// Every chunk of a `.rrd`: (entity path without the leading `/`, chunk).
fn chunks(path: &std::path::Path) -> Vec<(String, Chunk)> {
    let file = std::fs::File::open(path).expect("the recording exists");
    DecoderApp::decode_lazy(BufReader::new(file))
        .filter_map(|msg| match msg.expect("a message decodes") {
            LogMsg::ArrowMsg(_, arrow) => {
                let chunk = Chunk::from_arrow_msg(&arrow).expect("a chunk decodes");
                Some((chunk.entity_path().to_string().trim_start_matches('/').to_owned(), chunk))
            }
            _ => None,
        })
        .collect()
}

/// The strings of the component whose name ends with `field` in `chunk`, all rows.
fn strings(chunk: &Chunk, field: &str) -> Vec<String> {
    let Some(descriptor) = chunk.component_descriptors().find(|d| d.component.as_str().ends_with(field)).cloned() else {
        return Vec::new();
    };
    chunk.iter_slices::<String>(descriptor.component).flatten().map(|s| s.to_string()).collect()
}

#[test]
fn the_urdf_frames_are_the_links_and_the_joints_sweep_their_ranges() {
    use partscene::observe::rerun::{JOINT_TIMELINE, SWEEP_STEPS, URDF_JOINT_POSITIONS, URDF_JOINTS, URDF_LINKS};
    let (_, scan) = partscene::synth::demo(1);
    let dir = tempfile::tempdir().unwrap();
    let (scene, path) = recorded_demo(&scan, dir.path());
    let robot = partscene::export::scene_urdf_robot(&scene, &partscene::export::UrdfConfig::default());
    let chunks = chunks(&path);

    // Each link entity lives in the frame named as the link.
    for link in robot.links.iter().filter(|l| l.name != "world") {
        let entity = format!("{URDF_LINKS}/{}", link.name);
        let frames: Vec<String> = chunks.iter().filter(|(e, _)| *e == entity).flat_map(|(_, c)| strings(c, "frame")).collect();
        assert_eq!(frames, vec![link.name.clone()], "{entity}");
    }
    // Each URDF joint is a transform from its parent link's frame to its child link's.
    for joint in &robot.joints {
        let entity = format!("{URDF_JOINTS}/{}", joint.name);
        let of = |field| -> BTreeSet<String> { chunks.iter().filter(|(e, _)| *e == entity).flat_map(|(_, c)| strings(c, field)).collect() };
        assert_eq!(of("child_frame"), BTreeSet::from([joint.child.link.clone()]), "{entity}");
        assert_eq!(of("parent_frame"), BTreeSet::from([joint.parent.link.clone()]), "{entity}");
    }
    // Every movable joint moves on the joint timeline, one row per step, its position logged.
    let movable: Vec<&urdf_rs::Joint> = robot.joints.iter().filter(|j| j.joint_type != urdf_rs::JointType::Fixed).collect();
    assert!(!movable.is_empty());
    for joint in movable {
        let steps: BTreeSet<i64> = chunks
            .iter()
            .filter(|(e, _)| *e == format!("{URDF_JOINT_POSITIONS}/{}", joint.name))
            .filter_map(|(_, c)| c.timelines().iter().find(|(n, _)| n.as_str() == JOINT_TIMELINE).map(|(_, col)| col.times_raw().to_vec()))
            .flatten()
            .collect();
        assert_eq!(steps, (0..=SWEEP_STEPS).collect::<BTreeSet<_>>(), "{}", joint.name);
    }
}

#[test]
fn gap_logs_the_recording_the_replays_and_the_residuals_per_joint() {
    use partscene::gap::generate::{GenerateConfig, TrueEffect, generate_recording};
    use partscene::gap::{GapConfig, analyze, parse_model, parse_recording};
    use partscene::observe::rerun::{GAP_ENTITY, GAP_TIMELINE};
    const DOOR: &str = r#"<robot name="door">
      <link name="frame"/>
      <link name="leaf"><inertial><origin xyz="0.4 0 0"/><mass value="5"/>
        <inertia ixx="0.3" iyy="0.3" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="hinge" type="revolute"><parent link="frame"/><child link="leaf"/>
        <axis xyz="0 0 1"/><limit lower="0" upper="2.0" effort="10" velocity="3"/></joint>
    </robot>"#;
    let model = parse_model(DOOR, std::path::Path::new("door.urdf")).unwrap();
    let cfg = GenerateConfig {
        duration_s: 4.0,
        effects: vec![("hinge".to_owned(), TrueEffect::ViscousDamping { damping: 2.0 })],
        ..GenerateConfig::default()
    };
    let csv = generate_recording(&model, &cfg).unwrap();
    let rec = parse_recording(&csv, std::path::Path::new("door.csv")).unwrap();
    let report = analyze(&model, &rec, &GapConfig::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gap.rrd");
    let observer = RerunObserver::save(&path).unwrap();
    observer.gap_report(&report);
    drop(observer);
    let chunks = chunks(&path);
    let series = &report.series[0];
    for (name, values) in [
        ("measured", &series.measured),
        ("model", &series.simulated_before),
        ("fitted", &series.simulated_after),
        ("residual/model", &series.residual_before),
        ("residual/fitted", &series.residual_after),
    ] {
        let entity = format!("{GAP_ENTITY}/hinge/{name}");
        let rows: usize = chunks
            .iter()
            .filter(|(e, c)| *e == entity && c.timelines().iter().any(|(n, _)| n.as_str() == GAP_TIMELINE))
            .map(|(_, c)| c.num_rows())
            .sum();
        assert_eq!(rows, values.iter().filter(|v| v.is_finite()).count(), "{entity}");
    }
    let effects: Vec<String> =
        chunks.iter().filter(|(e, _)| *e == format!("{GAP_ENTITY}/hinge/effects")).flat_map(|(_, c)| strings(c, "text")).collect();
    assert!(effects.iter().any(|t| t.contains("viscous_damping")), "{effects:?}");
}
