//! The command line as a user runs it: demo → files; reconstruct a written scan; eval; bad input.

use std::process::Command;

fn partscene(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_partscene")).args(args).output().expect("run partscene")
}

#[test]
fn demo_writes_a_scene_that_reconstructs_and_evaluates() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("demo");
    let o = partscene(&["demo", "--seed", "1", "--out", out.to_str().expect("utf-8"), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints JSON");
    assert!(report["total"]["joint_type_accuracy"].as_f64().is_some());
    for f in ["scan.ply", "scan.json", "gt.json", "scene.urdf", "scene.json", "eval.json"] {
        assert!(out.join(f).is_file(), "{f} written");
    }
    // The written scan reads back and reconstructs through the public command.
    let rec = dir.path().join("rec");
    let o = partscene(&["reconstruct", out.join("scan.ply").to_str().expect("utf-8"), "--out", rec.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("parts"));
    let o = partscene(&[
        "eval",
        "--scene",
        rec.join("scene.json").to_str().expect("utf-8"),
        "--truth",
        out.join("gt.json").to_str().expect("utf-8"),
        "--scan",
        out.join("scan.ply").to_str().expect("utf-8"),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert!(v["part_level"]["summary"]["map"].as_f64().unwrap_or(0.0) > 0.8, "{v}");
}

#[test]
fn reconstructing_a_missing_or_bad_file_fails_with_its_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.ply");
    std::fs::write(&bad, b"this is not a ply file").expect("write");
    let o = partscene(&["reconstruct", bad.to_str().expect("utf-8"), "--out", dir.path().join("o").to_str().expect("utf-8")]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.ply"), "{err}");
    assert!(!dir.path().join("o").exists(), "nothing written for a bad scan");
}

#[test]
fn contact_thresholds_are_validated_and_change_the_result() {
    let o = partscene(&["--dist-max=-1", "demo", "--json"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--dist-max"), "{}", String::from_utf8_lossy(&o.stderr));
    let dir = tempfile::tempdir().expect("tempdir");
    let candidate_edges = |name: &str, args: &[&str]| {
        let out = dir.path().join(name);
        let mut all = args.to_vec();
        all.extend(["demo", "--out", out.to_str().expect("utf-8")]);
        let o = partscene(&all);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(out.join("scene.json")).expect("scene.json");
        let v: serde_json::Value = serde_json::from_str(&text).expect("json");
        v["contact_edges"].as_array().expect("edges").len()
    };
    // θd = 5 mm instead of 3 cm: contacts across fitting noise no longer pass the Dist test.
    let strict = candidate_edges("strict", &["--dist-max", "0.005"]);
    let default = candidate_edges("default", &[]);
    assert!(strict < default, "strict θd {strict} candidate edges, default {default}");
}

/// Reality gap to simulator: a recording of a demo door with a damper the reconstruction cannot
/// know → `partscene gap` finds it → `partscene mjcf --effects` writes it into the MJCF joint.
#[test]
fn a_damper_found_by_gap_lands_in_the_mjcf() {
    use partscene::gap::generate::{GenerateConfig, TrueEffect, generate_recording};
    let dir = tempfile::tempdir().expect("tempdir");
    let demo = dir.path().join("demo");
    let o = partscene(&["demo", "--out", demo.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let urdf = std::fs::read_to_string(demo.join("scene.urdf")).expect("urdf");
    let model = partscene::gap::parse_model(&urdf, &demo.join("scene.urdf")).expect("model");
    let robot = urdf_rs::read_from_string(&urdf).expect("urdf parses");
    let door =
        robot.joints.iter().find(|j| j.name.contains("door") && matches!(j.joint_type, urdf_rs::JointType::Revolute)).expect("a door");
    let cfg = GenerateConfig {
        duration_s: 6.0,
        effects: vec![(door.name.clone(), TrueEffect::ViscousDamping { damping: 0.4 })],
        ..GenerateConfig::default()
    };
    let csv = format!("# model: demo/scene.urdf\n{}", generate_recording(&model, &cfg).expect("csv"));
    let rec = dir.path().join("door.csv");
    std::fs::write(&rec, csv).expect("write");
    let gap_out = dir.path().join("gap");
    let o = partscene(&["gap", "--recording", rec.to_str().expect("utf-8"), "--out", gap_out.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mjcf = dir.path().join("fitted.mjcf.xml");
    let o = partscene(&[
        "mjcf",
        "--scene",
        demo.join("scene.json").to_str().expect("utf-8"),
        "--effects",
        gap_out.join("model.fitted.json").to_str().expect("utf-8"),
        "--out",
        mjcf.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&mjcf).expect("mjcf");
    let doc = roxmltree::Document::parse(&text).expect("MJCF is XML");
    let joint = doc.descendants().find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(door.name.as_str())).expect("door joint");
    let damping: f64 = joint.attribute("damping").expect("damping written").parse().expect("number");
    assert!((damping - 0.4).abs() < 0.1, "damping {damping}");
    // Every other joint keeps the model's (no) damping.
    let others = doc.descendants().filter(|n| n.has_tag_name("joint") && n.attribute("name") != Some(door.name.as_str()));
    assert!(others.clone().count() > 5 && others.filter(|n| n.attribute("damping").is_some()).count() == 0);
}

/// Scans made by others (issue 11): a `MultiScan` folder imported, reconstructed and scored; a
/// numpy-written `.npz` scan reconstructed; a folder without annotations refused by name.
#[test]
fn multiscan_import_and_npz_scans_through_the_cli() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let out = dir.path().join("ms");
    let ms = fixtures.join("multiscan/scene_00000_00");
    let args = ["import", "multiscan", ms.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8"), "--points", "6000", "--json"];
    let o = partscene(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints JSON");
    assert_eq!((v["parts"].as_u64(), v["objects"].as_u64(), v["movable_joints"].as_u64()), (Some(3), Some(2), Some(1)), "{v}");
    let rec = dir.path().join("rec");
    let o = partscene(&["reconstruct", out.join("scan.ply").to_str().expect("utf-8"), "--out", rec.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let scene = rec.join("scene.json");
    let o =
        partscene(&["eval", "--scene", scene.to_str().expect("utf-8"), "--truth", out.join("gt.json").to_str().expect("utf-8"), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["part_level"]["objects"].as_array().map(Vec::len), Some(2), "{v}");
    assert_eq!(v["part_level"]["summary"]["joints"].as_u64(), Some(1), "{v}");

    let npz = fixtures.join("npz/room_compressed.npz");
    let o = partscene(&["reconstruct", npz.to_str().expect("utf-8"), "--out", dir.path().join("npz").to_str().expect("utf-8"), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let o =
        partscene(&["import", "multiscan", dir.path().to_str().expect("utf-8"), "--out", dir.path().join("x").to_str().expect("utf-8")]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no `*.annotations.json`"), "{}", String::from_utf8_lossy(&o.stderr));
    let o = partscene(&[
        "import",
        "multiscan",
        ms.to_str().expect("utf-8"),
        "--out",
        dir.path().join("y").to_str().expect("utf-8"),
        "--points",
        "0",
    ]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--points"));
}

/// An ASCII PLY scan of a cabinet (body + drawer, points on a grid over each box's faces) and its
/// labels, written as `NAME.ply` + `NAME.json` in `dir`.
fn write_cabinet_scan(dir: &std::path::Path, name: &str, drawer_z: f32) {
    let boxes = [(70, [0.0, 0.0, 0.5], [0.8, 0.5, 1.0]), (71, [0.0, 0.26, drawer_z], [0.7, 0.02, 0.25])];
    let mut rows = Vec::new();
    for (part, c, s) in boxes {
        for axis in 0..3 {
            for side in [-0.5_f32, 0.5] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for i in 0..=24 {
                    for j in 0..=24 {
                        let mut p = c;
                        p[axis] += side * s[axis];
                        p[u] += (i as f32 / 24.0 - 0.5) * s[u];
                        p[v] += (j as f32 / 24.0 - 0.5) * s[v];
                        rows.push(format!("{} {} {} 7 {part}", p[0], p[1], p[2]));
                    }
                }
            }
        }
    }
    let header = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty int object\nproperty int part\nend_header\n",
        rows.len()
    );
    std::fs::write(dir.join(format!("{name}.ply")), header + &rows.join("\n") + "\n").expect("write ply");
    let labels = r#"{"objects": {"7": {"category": "cabinet"}}, "parts": {"70": {"label": "body"}, "71": {"label": "drawer"}}}"#;
    std::fs::write(dir.join(format!("{name}.json")), labels).expect("write labels");
}

/// `partscene batch`: a folder of scans with one bad file gets one output folder per good scan
/// (the same files `reconstruct` writes), the bad one recorded as failed; a re-run skips what is
/// done and retries the failure; a changed scan is redone.
#[test]
fn batch_runs_every_scan_survives_a_bad_one_and_resumes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scans = dir.path().join("scans");
    std::fs::create_dir_all(&scans).expect("mkdir");
    write_cabinet_scan(&scans, "kitchen", 0.8);
    write_cabinet_scan(&scans, "office", 0.6);
    std::fs::write(scans.join("broken.ply"), b"ply\nnot really").expect("write");
    let out = dir.path().join("out");
    let run = |args: &[&str]| {
        let mut all = vec!["batch", "--out", out.to_str().expect("utf-8"), "--json"];
        all.extend_from_slice(args);
        partscene(&all)
    };
    let o = run(&[scans.to_str().expect("utf-8")]);
    assert!(!o.status.success(), "a failed scan makes the exit status non-zero");
    assert!(String::from_utf8_lossy(&o.stderr).contains("1 of 3 scans failed"), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints the report");
    let status = |r: &serde_json::Value| -> Vec<(String, String)> {
        r["scans"]
            .as_array()
            .expect("scans")
            .iter()
            .map(|s| (s["name"].as_str().unwrap_or("").to_owned(), s["status"].as_str().unwrap_or("").to_owned()))
            .collect()
    };
    let pairs = |v: &[(&str, &str)]| -> Vec<(String, String)> { v.iter().map(|(a, b)| ((*a).to_owned(), (*b).to_owned())).collect() };
    assert_eq!(status(&report), pairs(&[("broken", "failed"), ("kitchen", "done"), ("office", "done")]));
    assert!(report["scans"][0]["error"].as_str().unwrap_or("").contains("broken.ply"), "{report}");
    assert_eq!(report["scans"][1]["movable_joints"], 1);
    for f in ["batch.json", "batch.md", "kitchen/scene.urdf", "kitchen/batch-entry.json", "office/objects/cabinet7.urdf"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // The same files as `partscene reconstruct`.
    let single = dir.path().join("single");
    let o = partscene(&["reconstruct", scans.join("kitchen.ply").to_str().expect("utf-8"), "--out", single.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["scene.json", "scene.urdf", "scene.mjcf.xml", "scene.srdf"] {
        assert_eq!(std::fs::read(single.join(f)).expect("single"), std::fs::read(out.join("kitchen").join(f)).expect("batch"), "{f}");
    }
    // A re-run after removing the bad file and changing one scan: one skipped, one redone.
    std::fs::remove_file(scans.join("broken.ply")).expect("rm");
    write_cabinet_scan(&scans, "office", 0.7);
    let o = run(&[scans.join("*.ply").to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("report");
    assert_eq!(status(&report), pairs(&[("kitchen", "skipped"), ("office", "done")]));
    // Inputs that name nothing are refused before anything runs.
    let o = run(&[dir.path().join("nothing-here").to_str().expect("utf-8")]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("no such file or folder"), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `partscene check-urdf`: our exports pass; a broken URDF fails naming the file and the problem.
#[test]
fn check_urdf_passes_our_exports_and_names_what_is_wrong() {
    let dir = tempfile::tempdir().expect("tempdir");
    write_cabinet_scan(dir.path(), "cabinet", 0.8);
    let out = dir.path().join("out");
    let o = partscene(&["reconstruct", dir.path().join("cabinet.ply").to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = partscene(&[
        "check-urdf",
        out.join("scene.urdf").to_str().expect("utf-8"),
        out.join("objects/cabinet7.urdf").to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(String::from_utf8_lossy(&o.stdout).matches(": ok (").count(), 2);
    let bad = dir.path().join("bad.urdf");
    std::fs::write(&bad, r#"<robot name="r"><link name="a"/><link name="b"/></robot>"#).expect("write");
    let o = partscene(&["check-urdf", bad.to_str().expect("utf-8")]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.urdf: error: 2 root links (a, b)"), "{err}");
}

#[test]
fn a_ros_recording_needs_a_model_and_a_rosbag2_in_another_storage_is_named() {
    let dir = tempfile::tempdir().expect("tmp");
    let mcap = dir.path().join("run.mcap");
    std::fs::write(&mcap, b"not read before the model is known").expect("write");
    let out = dir.path().join("out");
    let run = partscene(&["gap", "--recording", mcap.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8")]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success() && err.contains("run.mcap: a ROS recording names no model: give --model"), "{err}");

    let bag = dir.path().join("bag");
    std::fs::create_dir(&bag).expect("bag");
    std::fs::write(bag.join("metadata.yaml"), "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: sqlite3\n").expect("yaml");
    let model = dir.path().join("door.urdf");
    std::fs::write(
        &model,
        r#"<robot name="door"><link name="frame"/><link name="leaf"><inertial><mass value="5"/>
        <inertia ixx="0.3" iyy="0.3" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial></link>
        <joint name="hinge" type="revolute"><parent link="frame"/><child link="leaf"/><axis xyz="0 0 1"/>
        <limit lower="0" upper="2" effort="10" velocity="3"/></joint></robot>"#,
    )
    .expect("model");
    let args = [
        "gap",
        "--model",
        model.to_str().expect("utf-8"),
        "--recording",
        bag.to_str().expect("utf-8"),
        "--out",
        out.to_str().expect("utf-8"),
    ];
    let run = partscene(&args);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && err.contains("metadata.yaml") && err.contains("rosbag2 storage \"sqlite3\": only MCAP is read"),
        "{err}"
    );
}

/// `partscene render` from the command line, without a window (lavapipe where there is no GPU): the
/// demo room reconstructed and drawn to a PNG of the size asked, not one flat colour. Without an
/// adapter it skips loudly, except under CI (`CI` set), which installs lavapipe.
#[cfg(feature = "gui")]
#[test]
fn render_draws_the_demo_room_to_a_png_headless() {
    if let Err(e) = partscene::render::Headless::new() {
        assert!(std::env::var_os("CI").is_none(), "CI must have a GPU adapter (lavapipe): {e}");
        eprintln!("\n!!! SKIPPING render_draws_the_demo_room_to_a_png_headless: {e}\n");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("shot.png");
    let o = partscene(&["render", "demo", "--out", out.to_str().expect("utf-8"), "--width", "160", "--height", "100", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints JSON");
    assert_eq!((report["width"].as_u64(), report["height"].as_u64()), (Some(160), Some(100)), "{report}");
    let image = image::open(&out).expect("the PNG reads back").to_rgba8();
    assert_eq!(image.dimensions(), (160, 100));
    let first = image.get_pixel(0, 0);
    let differing = image.pixels().filter(|p| *p != first).count();
    assert!(differing > 160 * 100 / 10, "the shot is nearly one colour: {differing} pixels differ from the corner");
}
