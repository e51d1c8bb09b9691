"""partscene: part-level interactive scenes from part-segmented 3D scans.

    import partscene
    scan = partscene.read_scan("room.ply")            # or .npz; labels JSON beside it
    scene = partscene.reconstruct(scan)               # or reconstruct(points, object_ids, part_ids, labels)
    scene.save("out")                                 # scene.urdf, scene.json, objects/, ... as the CLI
    print(scene.joints[0]["type"], scene.urdf()[:80])

Arrays in: points float32/float64 (N, 3); object and part ids any integer dtype (N,), -1 for
background; labels ``{"parts": {part_id: label}, "objects": {object_id: category}}`` (or just
``{part_id: label}``). Bad input raises ``PartsceneError`` (``PartsceneInputError``, also a
``ValueError``, for bad arguments) naming the array or file and what was expected. The work runs
with the GIL released.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _native
from ._native import PartsceneError

__all__ = ["PartsceneError", "PartsceneInputError", "Scan", "Scene", "read_scan", "reconstruct", "load_scene", "evaluate", "gap"]

PathLike = Union[str, "os.PathLike[str]"]


class Scan:
    """A part-segmented scan: ``points`` (N, 3) float32, ``normals`` (N, 3) or None,
    ``object_ids`` and ``part_ids`` (N,) int64 (-1: background), ``labels``
    (``{"parts": {id: label}, "objects": {id: category}}``), ``source`` and ``warnings``."""

    def __init__(self, native: Any) -> None:
        self._native = native
        self.points, self.normals, self.object_ids, self.part_ids = native.arrays()
        parts, objects = native.labels()
        self.labels: Dict[str, Dict[int, str]] = {"parts": dict(parts), "objects": dict(objects)}
        self.source: str = native.source
        self.warnings: List[str] = list(native.warnings)

    def __repr__(self) -> str:
        return f"Scan({self.source!r}, {len(self.points)} points, {len(self.labels['parts'])} parts)"


class Scene:
    """A reconstructed scene. ``parts``, ``joints``, ``objects``, ``contact_edges``, ``warnings``
    are plain Python data (the content of ``scene.json``)."""

    def __init__(self, native: Any) -> None:
        self._native = native
        self._doc: Dict[str, Any] = json.loads(native.json())

    @property
    def parts(self) -> List[Dict[str, Any]]:
        return self._doc["parts"]

    @property
    def joints(self) -> List[Dict[str, Any]]:
        return self._doc["joints"]

    @property
    def objects(self) -> List[Dict[str, Any]]:
        return self._doc["objects"]

    @property
    def contact_edges(self) -> List[Dict[str, Any]]:
        return self._doc["contact_edges"]

    @property
    def warnings(self) -> List[Dict[str, Any]]:
        return self._doc.get("warnings", [])

    def json(self) -> str:
        """``scene.json`` as text."""
        return self._native.json()

    def urdf(self) -> str:
        """``scene.urdf`` as text."""
        return self._native.urdf()

    def mjcf(self) -> str:
        """``scene.mjcf.xml`` as text."""
        return self._native.mjcf()

    def usda(self) -> str:
        """``scene.usda`` (text USD with ``UsdPhysics``, for Isaac Sim) as text."""
        return self._native.usda()

    def save(self, directory: PathLike) -> List[str]:
        """Writes the files ``partscene reconstruct --out DIR`` writes; returns their paths."""
        return [str(p) for p in self._native.save(os.fspath(directory))]

    def __repr__(self) -> str:
        movable = sum(1 for j in self.joints if j["type"] != "fixed")
        return f"Scene({len(self.objects)} objects, {len(self.parts)} parts, {len(self.joints)} joints, {movable} movable)"


def read_scan(path: PathLike) -> Scan:
    """Reads a scan file: PLY or ``.npz``, with the labels JSON beside it (``NAME.json``)."""
    return Scan(_native.read_scan(os.fspath(path)))


class PartsceneInputError(PartsceneError, ValueError):
    """Bad arguments (array dtype, shape or length, labels, config): also a ``ValueError``."""


_ValueError = PartsceneInputError


def _array_error(name: str, detail: str, expected: str) -> PartsceneError:
    return PartsceneInputError(f"array `{name}` {detail}; expected {expected}")


def _points(name: str, a: Any, n: Optional[int]) -> np.ndarray:
    arr = np.asarray(a)
    expected = "a float32 or float64 array of shape (N, 3)"
    if arr.dtype.kind != "f":
        raise _array_error(name, f"has dtype {arr.dtype}", expected)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise _array_error(name, f"has shape {arr.shape}", expected)
    if n is not None and arr.shape[0] != n:
        raise _array_error(name, f"has {arr.shape[0]} rows, `points` has {n}", "one row per point")
    return np.ascontiguousarray(arr, dtype=np.float64)


def _ids(name: str, a: Any, n: int) -> np.ndarray:
    arr = np.asarray(a)
    expected = "an integer array of shape (N,): one id per row of `points`"
    if arr.dtype.kind not in "iu":
        raise _array_error(name, f"has dtype {arr.dtype}", expected)
    if arr.ndim != 1:
        raise _array_error(name, f"has shape {arr.shape}", expected)
    if arr.shape[0] != n:
        raise _array_error(name, f"has {arr.shape[0]} rows, `points` has {n}", expected)
    if arr.dtype.kind == "u" and arr.size and int(arr.max()) > np.iinfo(np.int64).max:
        raise _array_error(name, f"holds {int(arr.max())}", "ids that fit in int64")
    return np.ascontiguousarray(arr, dtype=np.int64)


def _labels(labels: Optional[Mapping[Any, Any]]) -> "tuple[Dict[int, str], Dict[int, str]]":
    if labels is None:
        return {}, {}
    if "parts" in labels or "objects" in labels:
        parts = labels.get("parts", {}) or {}
        objects = labels.get("objects", {}) or {}
    else:
        parts, objects = labels, {}

    def table(name: str, m: Mapping[Any, Any], value_key: str) -> Dict[int, str]:
        out: Dict[int, str] = {}
        for k, v in m.items():
            try:
                key = int(k)
            except (TypeError, ValueError):
                raise _ValueError(f"labels[{name!r}]: key {k!r} is not an integer id; expected ids like 17 or \"17\"") from None
            if isinstance(v, Mapping):  # the labels JSON's {"label": ..., "object": ...} / {"category": ...}
                v = v.get(value_key)
                if v is None:
                    continue
            if not isinstance(v, str):
                raise _ValueError(f"labels[{name!r}][{k!r}] is {type(v).__name__}; expected a string")
            out[key] = v
        return out

    return table("parts", parts, "label"), table("objects", objects, "category")


def reconstruct(
    points: Any,
    object_ids: Any = None,
    part_ids: Any = None,
    labels: Optional[Mapping[Any, Any]] = None,
    config: Optional[Mapping[str, Any]] = None,
    *,
    normals: Any = None,
    source: str = "arrays",
) -> Scene:
    """Reconstructs a scene from a :class:`Scan` or from arrays.

    ``config`` may hold ``"vocabulary"``: a TOML file laid over the built-in part vocabulary (the
    CLI's ``--vocab``). ``source`` names the arrays in errors, warnings and ``scene.json``."""
    vocabulary = None
    if config:
        unknown = sorted(set(config) - {"vocabulary"})
        if unknown:
            raise _ValueError(f"config: unknown keys {unknown}; expected only 'vocabulary' (a TOML file path)")
        if config.get("vocabulary") is not None:
            vocabulary = os.fspath(config["vocabulary"])
    if isinstance(points, Scan):
        if object_ids is not None or part_ids is not None or labels is not None or normals is not None:
            raise _ValueError("reconstruct(scan): a Scan carries its ids and labels; pass no arrays with it")
        native_scan = points._native
    else:
        if object_ids is None or part_ids is None:
            raise _ValueError("reconstruct(points, object_ids, part_ids, labels): object_ids and part_ids are required")
        pts = _points("points", points, None)
        n = pts.shape[0]
        nrm = None if normals is None else _points("normals", normals, n)
        parts, objects = _labels(labels)
        native_scan = _native.scan_from_numpy(
            pts, _ids("object_ids", object_ids, n), _ids("part_ids", part_ids, n), parts, objects, nrm, source
        )
    return Scene(_native.reconstruct(native_scan, vocabulary))


def load_scene(path: PathLike) -> Scene:
    """Reads a ``scene.json`` written by partscene."""
    path = os.fspath(path)
    with open(path, encoding="utf-8") as f:
        text = f.read()
    return Scene(_native.scene_from_json_text(text, path))


def evaluate(scene: Scene, truth: Union[PathLike, Mapping[str, Any]]) -> Dict[str, Any]:
    """The paper's metrics of ``scene`` against ground truth: a ``gt.json`` path or its content."""
    if isinstance(truth, Mapping):
        text, name = json.dumps(truth), "truth"
    else:
        name = os.fspath(truth)
        with open(name, encoding="utf-8") as f:
            text = f.read()
    return json.loads(_native.evaluate(scene._native, text, name))


from . import gap  # noqa: E402  (the submodule uses the names above)
