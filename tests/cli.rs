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
