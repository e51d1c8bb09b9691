//! The fuzz findings, replayed on stable: every file of `fuzz/regressions/TARGET/` goes through the
//! same harness as the libFuzzer target `TARGET` (`fuzz/src/lib.rs`, included here as a module),
//! so an input that once crashed, hung or exhausted memory is checked by every `cargo test`.
//! New findings: minimise (`cargo +nightly fuzz tmin TARGET ARTIFACT`), copy into the folder.

#[path = "../fuzz/src/lib.rs"]
mod fuzz_entry;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use fuzz_entry::TARGETS;

fn regressions_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz").join("regressions")
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

#[test]
fn every_regression_input_runs_through_its_target_without_a_crash() {
    let root = regressions_dir();
    for (name, harness) in TARGETS {
        let files = files_in(&root.join(name));
        assert!(!files.is_empty(), "{}: no regression inputs for target {name}", root.join(name).display());
        assert!(
            files.iter().any(|f| f.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("valid-"))),
            "{}: no valid-* input for target {name}",
            root.join(name).display()
        );
        for file in files {
            let bytes = std::fs::read(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            let start = Instant::now();
            let accepted = harness(&bytes);
            // Files named `valid-*` keep the paths after the reader covered: they must be read.
            let valid = file.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("valid-"));
            assert!(accepted || !valid, "{}: the reader refused a valid input", file.display());
            // The fuzzers fail at 10 s per input (optimised); a test build is slower, so only a
            // clear hang fails here.
            let took = start.elapsed();
            assert!(took < Duration::from_mins(1), "{}: {name} took {took:?}", file.display());
        }
    }
}

#[test]
fn every_regression_folder_belongs_to_a_target() {
    for dir in std::fs::read_dir(regressions_dir()).expect("fuzz/regressions exists") {
        let dir = dir.expect("a directory entry").path();
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_owned();
        assert!(TARGETS.iter().any(|(t, _)| *t == name), "{}: no fuzz target named {name}", dir.display());
        let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz").join("fuzz_targets").join(format!("{name}.rs"));
        assert!(target.is_file(), "{}: the target's source is missing", target.display());
    }
}

/// Issue 14: a binary PLY with a finite coordinate near 1e37 once made reconstruction allocate
/// 13 GB. The reader refuses it, naming the file and the vertex, at once.
#[test]
fn a_finite_but_huge_coordinate_is_refused_naming_the_file_and_vertex() {
    let path = regressions_dir().join("scan_ply").join("huge-coordinate-1e37.ply");
    let start = Instant::now();
    let err = partscene::scan::read_scan(&path).expect_err("a 1e37 coordinate is refused").to_string();
    assert!(start.elapsed() < Duration::from_secs(1), "took {:?}", start.elapsed());
    assert!(err.contains("huge-coordinate-1e37.ply") && err.contains("vertex 5") && err.contains("`x`"), "{err}");
}

/// Seeds for the gap fuzz targets from `gap::generate` (run by `fuzz/seed.sh`, not by default):
/// a short recording for every URDF in `PARTSCENE_FUZZ_SEED_URDFS` (`:`-separated), written with
/// the URDF into `PARTSCENE_FUZZ_SEED_OUT`.
#[test]
#[ignore = "writes fuzz seeds; run by fuzz/seed.sh"]
fn write_generated_gap_seeds() {
    use partscene::gap::generate::{GenerateConfig, generate_recording};
    let (Ok(urdfs), Ok(out)) = (std::env::var("PARTSCENE_FUZZ_SEED_URDFS"), std::env::var("PARTSCENE_FUZZ_SEED_OUT")) else {
        panic!("set PARTSCENE_FUZZ_SEED_URDFS and PARTSCENE_FUZZ_SEED_OUT");
    };
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out).expect("create the seed folder");
    for (i, urdf) in urdfs.split(':').filter(|s| !s.is_empty()).enumerate() {
        let text = std::fs::read_to_string(urdf).unwrap_or_else(|e| panic!("{urdf}: {e}"));
        let model = partscene::gap::parse_model(&text, Path::new(urdf)).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(out.join(format!("model-{i}.urdf")), &text).expect("write a seed");
        let variants = [
            GenerateConfig { duration_s: 1.0, rate_hz: 40.0, seed: 1, ..GenerateConfig::default() },
            GenerateConfig { duration_s: 1.0, rate_hz: 40.0, irregular: true, dropout_fraction: 0.1, seed: 2, ..GenerateConfig::default() },
            GenerateConfig { duration_s: 0.5, rate_hz: 40.0, pose_only: true, seed: 3, ..GenerateConfig::default() },
        ];
        for (v, cfg) in variants.iter().enumerate() {
            match generate_recording(&model, cfg) {
                Ok(csv) => std::fs::write(out.join(format!("recording-{i}-{v}.csv")), csv).expect("write a seed"),
                Err(e) => eprintln!("{urdf}: variant {v}: {e}"),
            }
        }
    }
}

/// Seeds for the session fuzz target (run by `fuzz/seed.sh`, not by default): sessions as the
/// editor saves them, pinning the parts of the object the target assembles, written into
/// `PARTSCENE_FUZZ_SEED_OUT`.
#[test]
#[ignore = "writes fuzz seeds; run by fuzz/seed.sh"]
fn write_session_seeds() {
    use partscene::edit::{SceneSource, Session};
    use partscene::kinematics::JointKind;
    use partscene::math::Vec3;
    use partscene::pipeline::PinnedEdits;
    use partscene::primitive::PrimitiveKind;
    let out = PathBuf::from(std::env::var("PARTSCENE_FUZZ_SEED_OUT").expect("set PARTSCENE_FUZZ_SEED_OUT"));
    std::fs::create_dir_all(&out).expect("create the seed folder");
    let ids: Vec<i64> = fuzz_entry::fitted_object().0.parts.iter().map(|p| p.id).collect();
    let (first, second, last) = (ids[0], ids[1 % ids.len()], ids[ids.len() - 1]);
    let mut hinge = PinnedEdits::default();
    hinge.parent.insert(second, first);
    hinge.joint_kind.insert(second, JointKind::Revolute);
    hinge.axis.insert(second, Vec3::Z);
    hinge.limits.insert(second, (0.0, 1.5));
    let mut slide = PinnedEdits::default();
    slide.primitive_kind.insert(last, PrimitiveKind::Cylinder);
    slide.joint_kind.insert(last, JointKind::Prismatic);
    slide.axis.insert(last, Vec3::X);
    slide.limits.insert(last, (0.0, 0.4));
    let mut fixed = PinnedEdits::default();
    fixed.joint_kind.insert(second, JointKind::Fixed);
    fixed.primitive_kind.insert(first, PrimitiveKind::Sphere);
    let sessions = [
        Session::new(SceneSource::Demo { seed: 0, clean: true }, PinnedEdits::default()),
        Session::new(SceneSource::Demo { seed: 0, clean: true }, hinge),
        Session::new(SceneSource::Demo { seed: 0, clean: false }, slide),
        Session::new(SceneSource::Scan { path: PathBuf::from("/nonexistent/room.ply") }, fixed),
    ];
    for (i, session) in sessions.iter().enumerate() {
        session.save(&out.join(format!("session-{i}.json"))).expect("write a seed");
    }
}

/// Issue 14, `gap_mcap`: a 4 KB MCAP whose chunk claims 4 GB once made the reader allocate what it
/// claimed, and a 2 KB one whose zstd chunk stops short of its declared size spun the `mcap`
/// crate's inflation forever. Both are refused at once, naming the file and what is wrong.
#[test]
fn mcap_chunks_that_claim_too_much_or_stop_short_are_refused() {
    for (name, expected) in [
        ("oom-chunk-claims-gigabytes.mcap", "a record of 4294967296 bytes"),
        ("hang-zstd-chunk-stops-short.mcap", "bytes uncompressed, more than the 1048576 allowed"),
    ] {
        let path = regressions_dir().join("gap_mcap").join(name);
        let bytes = std::fs::read(&path).expect("the regression input");
        let started = Instant::now();
        let err = partscene::gap::mcap::mcap_to_csv(&bytes, &path, None, None).expect_err("refused").to_string();
        assert!(err.contains(name) && err.contains(expected), "{err}");
        assert!(started.elapsed() < Duration::from_secs(1), "{name}: {:?}", started.elapsed());
    }
}
