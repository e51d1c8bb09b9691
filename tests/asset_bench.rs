//! The asset benchmark end to end: `scan-asset` output parses back through the scan reader with
//! labels and truth joints; one shared object runs through `bench` (skipped, loudly, where the
//! shared data is absent).

use std::path::{Path, PathBuf};
use std::process::Command;

use partscene::bench::{BenchConfig, asset_truth, bench_dir, find_assets};
use partscene::kinematics::JointKind;
use partscene::scan::read_scan;
use partscene::truth::GroundTruth;

/// The shared objects: `../shared/data/objects` from the crate root, else `/work/shared/...`.
fn shared_objects() -> Option<PathBuf> {
    let local = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/objects");
    [local, PathBuf::from("/work/shared/data/objects")].into_iter().find(|p| p.join("MANIFEST.tsv").is_file())
}

fn skip_loudly(test: &str) {
    eprintln!("\n*** SKIPPED {test}: ../shared/data/objects (shared benchmark objects) is absent ***\n");
}

/// A small MJCF cabinet: body, a drawer on a slide with a handle, a door on a hinge.
const CABINET: &str = r#"<mujoco model="test_cabinet">
  <worldbody>
    <body name="cabinet_body" pos="0 0 0.4">
      <geom type="box" size="0.3 0.25 0.4"/>
      <body name="drawer" pos="-0.3 0 0.2">
        <joint name="slide" type="slide" axis="-1 0 0" range="0 0.3"/>
        <geom type="box" size="0.02 0.22 0.15" pos="-0.02 0 0"/>
        <body name="drawer_handle" pos="-0.06 0 0">
          <geom type="box" size="0.015 0.08 0.015"/>
        </body>
      </body>
      <body name="door" pos="-0.3 0.23 -0.2">
        <joint name="hinge" type="hinge" axis="0 0 1" range="0 90"/>
        <geom type="box" size="0.02 0.22 0.17" pos="-0.02 -0.22 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"#;

#[test]
fn scan_asset_output_parses_back_with_labels_and_truth() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asset = dir.path().join("cabinet.xml");
    std::fs::write(&asset, CABINET).expect("write asset");
    let out = dir.path().join("scan/cabinet.ply");
    let run = Command::new(env!("CARGO_BIN_EXE_partscene"))
        .args(["scan-asset", asset.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--viewpoints", "6", "--seed", "3"])
        .output()
        .expect("run partscene");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let (scan, warnings) = read_scan(&out).expect("scan reads back");
    assert!(warnings.is_empty(), "{warnings:?}");
    let mut labels: Vec<&str> = scan.parts.iter().map(|p| p.label.as_str()).collect();
    labels.sort_unstable();
    assert_eq!(labels, ["body", "door", "drawer", "handle"]);
    assert!(scan.parts.iter().all(|p| p.points.len() > 50), "every part seen");
    assert!(!scan.background.is_empty(), "floor points");
    // The floor (most background points, the rest on the walls) at z = 0, where the asset stands.
    let mut zs: Vec<f32> = scan.background.iter().map(|p| p.z).collect();
    zs.sort_by(f32::total_cmp);
    let floor_z = zs[zs.len() / 10];
    assert!(floor_z.abs() < 0.02, "floor at {floor_z}");
    let lowest_part = scan.parts.iter().flat_map(|p| p.points.iter()).map(|p| p.z).fold(f32::INFINITY, f32::min);
    assert!(lowest_part > -0.1 && lowest_part < 0.05, "lowest part point {lowest_part}");
    let gt: GroundTruth =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scan/cabinet.gt.json")).expect("gt")).expect("gt parses");
    let o = &gt.objects[0];
    assert_eq!(o.category, "cabinet");
    let kinds: Vec<JointKind> = o.joints.iter().map(|j| j.kind).collect();
    assert_eq!(kinds, [JointKind::Prismatic, JointKind::Fixed, JointKind::Revolute]);
    let door = o.joints.iter().find(|j| j.kind == JointKind::Revolute).expect("hinge");
    assert!((door.axis_world.z.abs() - 1.0).abs() < 1e-5);
    // The hinge at x = -0.3, y = 0.23 in the file; the object's bounds (x from the handle's
    // front at -0.375 to the body's back at 0.3) are centred, so x moves by +0.0375.
    assert!((door.origin_world.x + 0.2625).abs() < 1e-4 && (door.origin_world.y - 0.23).abs() < 1e-4, "{}", door.origin_world);
}

#[test]
fn one_shared_object_runs_end_to_end() {
    let Some(objects) = shared_objects() else {
        skip_loudly("one_shared_object_runs_end_to_end");
        return;
    };
    let entries = find_assets(&objects).expect("manifest");
    assert_eq!(entries.len(), 15);
    // Fridge: Y-up habitat asset with two revolute doors.
    let fridge = entries.iter().find(|e| e.name.ends_with("fridge")).expect("fridge row");
    assert!(fridge.path.ends_with("fridge_obj.urdf"));
    let asset = partscene::assets::load_asset(&fridge.path).expect("load");
    let truth =
        asset_truth(&asset, &partscene::bench::AssetTruthOptions { category: "Refrigerator".into(), up: fridge.up }).expect("truth");
    let (lo, hi) = truth.truth.objects[0].aabb().expect("bounds");
    assert!(lo.z.abs() < 1e-4 && hi.z > 1.8, "stands 1.9 m tall on the floor: {lo} {hi}");

    let tmp = tempfile::tempdir().expect("tempdir");
    let one = tmp.path().join("objects");
    std::fs::create_dir_all(&one).expect("mkdir");
    let manifest = std::fs::read_to_string(objects.join("MANIFEST.tsv")).expect("manifest");
    let mut lines = manifest.lines();
    let header = lines.next().expect("header");
    let row = lines.find(|l| l.contains("habitat_replicacad/fridge")).expect("row");
    let local = tmp.path().join("objects/habitat_replicacad");
    std::fs::create_dir_all(&local).expect("mkdir");
    copy_dir(&objects.join("habitat_replicacad/fridge"), &local.join("fridge"));
    std::fs::write(one.join("MANIFEST.tsv"), format!("{header}\n{row}\n")).expect("manifest");
    let report = bench_dir(&one, &BenchConfig::default(), &|_, _, _| {}).expect("bench");
    assert!(report.failed.is_empty(), "{:?}", report.failed);
    assert_eq!(report.objects.len(), 1);
    let r = &report.objects[0];
    assert_eq!((r.parts, r.movable_joints), (3, 2));
    for setting in [&r.partial, &r.clean] {
        let row = &setting.metrics.objects[0];
        assert_eq!(row.joints.len(), 2);
        assert!(row.chamfer.expect("chamfer") < 0.1, "{:?}", row.chamfer);
        assert!(setting.metrics.summary.movable_correct_types == 2, "both doors revolute");
    }
    // Neither door carries a grip and both are centred on the body: nothing tells their hinge
    // edges apart, and the tool says so for both (whichever edge it took).
    for totals in [&report.partial, &report.clean] {
        assert_eq!(totals.hinges_in_doubt, 2, "{totals:?}");
        assert_eq!(totals.hinges_in_doubt_off, totals.hinges_off, "every hinge off its edge is in doubt: {totals:?}");
    }
    let md = report.markdown();
    assert!(md.contains("Refrigerator") && md.contains("| **all** (1) | clean |"), "{md}");
    assert!(md.contains("- clean: 2 in doubt"), "{md}");
}

#[test]
fn drawers_named_by_position_with_handles_slide() {
    // LIBERO's wooden cabinet: drawer bodies `cabinet_top/middle/bottom` hold their handles; the
    // handles become parts of their own, and the drawers (labels "top", "part") slide out of the
    // front by their geometry on the clean complete scan.
    let Some(objects) = shared_objects() else {
        skip_loudly("drawers_named_by_position_with_handles_slide");
        return;
    };
    let entries = find_assets(&objects).expect("manifest");
    let entry = entries.iter().find(|e| e.name.ends_with("wooden_cabinet")).expect("wooden_cabinet row");
    let r = partscene::bench::bench_asset(entry, &BenchConfig::default()).expect("bench");
    let handles = r.part_labels.values().filter(|(label, _)| label == "handle").count();
    assert_eq!((r.parts, handles, r.movable_joints), (7, 3, 3), "{:?}", r.part_labels);
    let row = &r.clean.metrics.objects[0];
    assert_eq!(row.movable_correct_types, 3, "{:?}", row.joints);
    for j in row.joints.iter().filter(|j| j.truth_kind.is_movable()) {
        assert!(j.axis_error_deg.expect("axis") < 5.0, "{j:?}");
        assert!(j.prismatic_origin_distance_m.expect("origin") < 0.02, "{j:?}");
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read dir").flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).expect("copy");
        }
    }
}
