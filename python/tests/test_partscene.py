"""The Python package against the CLI and on bad input (issue 13).

Needs the package installed (`pip install ./python`) and, for the tests that compare with the
command line, `PARTSCENE_BIN` naming a built `partscene` binary (`.ci/run` sets it; see
conftest.py).
"""

import filecmp
import json
import subprocess
import threading
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import partscene

SHARED_RECORDINGS = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "recordings"


@pytest.fixture(scope="session")
def demo(tmp_path_factory, partscene_bin):
    """A demo room written by the CLI: scan.ply + scan.json, gt.json."""
    out = tmp_path_factory.mktemp("demo")
    subprocess.run([partscene_bin, "demo", "--seed", "3", "--out", str(out)], check=True, capture_output=True)
    return out


def files_under(root):
    return sorted(p.relative_to(root) for p in Path(root).rglob("*") if p.is_file())


def test_python_writes_byte_identical_files_to_the_cli(demo, tmp_path, partscene_bin):
    by_cli = tmp_path / "cli"
    subprocess.run([partscene_bin, "reconstruct", str(demo / "scan.ply"), "--out", str(by_cli)], check=True, capture_output=True)
    scene = partscene.reconstruct(partscene.read_scan(demo / "scan.ply"))
    by_python = tmp_path / "python"
    written = scene.save(by_python)
    assert sorted(Path(p).relative_to(by_python) for p in written) == files_under(by_cli)
    for rel in files_under(by_cli):
        assert filecmp.cmp(by_cli / rel, by_python / rel, shallow=False), f"{rel} differs"
    assert scene.urdf() == (by_cli / "scene.urdf").read_text()
    assert scene.mjcf() == (by_cli / "scene.mjcf.xml").read_text()
    assert scene.usda() == (by_cli / "scene.usda").read_text()


def test_arrays_of_any_integer_and_float_dtype_reconstruct_like_the_file(demo):
    scan = partscene.read_scan(demo / "scan.ply")
    assert scan.points.dtype == np.float32 and scan.points.shape[1] == 3
    assert scan.object_ids.dtype == np.int64 and len(scan.part_ids) == len(scan.points)
    from_file = partscene.reconstruct(scan)
    same = partscene.reconstruct(
        scan.points.astype(np.float64),
        scan.object_ids.astype(np.int32),
        scan.part_ids.astype(np.int32),
        scan.labels,
        normals=scan.normals,
        source=scan.source,
    )
    assert same.json() == from_file.json()
    # Plain data: the joints and parts of scene.json.
    movable = [j for j in from_file.joints if j["type"] != "fixed"]
    assert movable and all(isinstance(j["axis_world"], list) for j in movable)
    assert {p["id"] for p in from_file.parts} == set(int(k) for k in scan.labels["parts"])


def test_evaluate_scores_against_ground_truth(demo):
    scene = partscene.reconstruct(partscene.read_scan(demo / "scan.ply"))
    metrics = partscene.evaluate(scene, demo / "gt.json")
    assert metrics["objects"] and all(0.0 <= o["ap"] <= 1.0 for o in metrics["objects"] if o["ap"] is not None)
    assert partscene.evaluate(scene, json.loads((demo / "gt.json").read_text())) == metrics


def box_points(center, size, n, rng):
    """Points on the surface of an axis-aligned box."""
    c, s = np.asarray(center, float), np.asarray(size, float)
    pts = rng.uniform(-0.5, 0.5, size=(n, 3))
    axis = rng.integers(0, 3, size=n)
    pts[np.arange(n), axis] = np.where(rng.random(n) < 0.5, -0.5, 0.5)
    return c + pts * s


def test_a_cabinet_from_arrays_gets_a_sliding_drawer():
    rng = np.random.default_rng(0)
    body = box_points([0, 0, 0.5], [0.8, 0.5, 1.0], 6000, rng)
    drawer = box_points([0, 0.26, 0.8], [0.7, 0.02, 0.25], 2000, rng)
    floor = np.column_stack([rng.uniform(-1, 1, 500), rng.uniform(-1, 1, 500), np.zeros(500)])
    points = np.vstack([body, drawer, floor]).astype(np.float32)
    objects = np.concatenate([np.full(8000, 7), np.full(500, -1)]).astype(np.int16)
    parts = np.concatenate([np.full(6000, 70), np.full(2000, 71), np.full(500, -1)]).astype(np.int64)
    scene = partscene.reconstruct(points, objects, parts, {"parts": {70: "body", 71: "drawer"}, "objects": {7: "cabinet"}})
    (joint,) = scene.joints
    assert (joint["parent"], joint["child"], joint["type"]) == (70, 71, "prismatic")
    robot = ET.fromstring(scene.urdf())
    assert [j.get("type") for j in robot.iter("joint") if j.get("type") != "fixed"] == ["prismatic"]
    assert scene.objects[0]["category"] == "cabinet"


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda a: a.update(points=a["points"].astype(np.int32)), "array `points` has dtype int32; expected a float32 or float64 array of shape (N, 3)"),
        (lambda a: a.update(points=a["points"][:, :2]), "array `points` has shape (3, 2)"),
        (lambda a: a.update(part_ids=a["part_ids"][:2]), "array `part_ids` has 2 rows, `points` has 3"),
        (lambda a: a.update(object_ids=a["object_ids"].astype(np.float64)), "array `object_ids` has dtype float64"),
        (lambda a: a["points"].__setitem__((1, 2), np.nan), "array `points` row 1 has a non-finite z (NaN)"),
        (lambda a: a["points"].__setitem__((2, 0), 3e4), "row 2"),
        (lambda a: a.update(labels={5: "door"}), "the labels name part 5, which is not in the scan"),
        (lambda a: a.update(labels={"parts": {"x": "door"}}), "key 'x' is not an integer id"),
        (lambda a: a.update(labels={1: 3}), "is int; expected a string"),
    ],
)
def test_bad_arrays_raise_errors_naming_the_array_and_what_was_expected(change, message):
    args = {
        "points": np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0.2]], np.float64),
        "object_ids": np.array([1, 1, 1]),
        "part_ids": np.array([1, 1, 1]),
        "labels": {1: "body"},
    }
    change(args)
    with pytest.raises(partscene.PartsceneError) as e:
        partscene.reconstruct(args["points"], args["object_ids"], args["part_ids"], args["labels"])
    assert message in str(e.value)


def test_bad_files_and_arguments_raise_named_errors(tmp_path):
    with pytest.raises(partscene.PartsceneError, match="nope.ply"):
        partscene.read_scan(tmp_path / "nope.ply")
    bad = tmp_path / "bad.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n")
    with pytest.raises(partscene.PartsceneError, match="bad.ply"):
        partscene.read_scan(bad)
    with pytest.raises(ValueError, match="unknown keys"):
        partscene.reconstruct(np.zeros((3, 3)), np.ones(3, int), np.ones(3, int), config={"speed": 2})
    with pytest.raises(partscene.PartsceneError, match="scene.json"):
        (tmp_path / "scene.json").write_text('{"format": "other"}')
        partscene.load_scene(tmp_path / "scene.json")


def test_the_work_runs_with_the_gil_released(demo):
    scan = partscene.read_scan(demo / "scan.ply")
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(1)

    t = threading.Thread(target=count)
    t.start()
    before = len(ticks)
    try:
        partscene.reconstruct(scan)
        during = len(ticks) - before
    finally:
        done.set()
        t.join()
    assert during > 0, "no Python thread ran while reconstructing"


def test_a_saved_scene_reads_back():
    rng = np.random.default_rng(1)
    pts = np.vstack([box_points([0, 0, 0.5], [1, 1, 1], 3000, rng), box_points([0, 0, 1.05], [0.3, 0.3, 0.1], 800, rng)])
    scene = partscene.reconstruct(pts, np.ones(len(pts), int), np.repeat([1, 2], [3000, 800]), {1: "base", 2: "lid"})
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        scene.save(d)
        back = partscene.load_scene(Path(d) / "scene.json")
        assert back.json() == scene.json()


@pytest.mark.skipif(not SHARED_RECORDINGS.is_dir(), reason=f"SKIPPED: {SHARED_RECORDINGS} is absent (shared real recordings)")
def test_gap_analysis_from_a_file_and_from_arrays_agree():
    case = SHARED_RECORDINGS / "dfki_pendulum"
    model, recording = case / "model.urdf", case / "recording.csv"
    from_file = partscene.gap.analyze(model, recording)
    assert from_file["format"] == "partscene-gap-report/1"
    lines = [l for l in recording.read_text().splitlines() if not l.startswith("#")]
    header = lines[0].split(",")
    values = np.array([[float(v) if v else np.nan for v in l.split(",")] for l in lines[1:]])
    from_arrays = partscene.gap.analyze(model, {name: values[:, k] for k, name in enumerate(header)})
    assert [e["kind"] for e in from_arrays["effects"]] == [e["kind"] for e in from_file["effects"]]
    with pytest.raises(ValueError, match="no `time` array"):
        partscene.gap.analyze(model, {"x.q": np.zeros(3)})
