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
    let path = dir.path().join("demo.rrd");
    let observer = RerunObserver::save(&path).unwrap();
    let scene = reconstruct_observed(&scan, &PipelineConfig::default(), &PinnedEdits::default(), &Quiet, &observer);
    drop(observer);

    let file = std::fs::File::open(&path).unwrap();
    let mut entities = BTreeSet::new();
    let mut stages = BTreeSet::new();
    for msg in DecoderApp::decode_lazy(BufReader::new(file)) {
        if let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() {
            let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
            entities.insert(chunk.entity_path().to_string().trim_start_matches('/').to_owned());
            if let Some(column) = chunk.timelines().iter().find(|(name, _)| name.as_str() == STAGE_TIMELINE).map(|(_, c)| c) {
                stages.extend(column.times_raw().iter().copied());
            }
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
