"""The reality gap (``partscene gap``): where a simulation of the model and a recording of the
real mechanism differ, which physics the model left out, fitted.

    report = partscene.gap.analyze("door.urdf", "push.csv")
    report = partscene.gap.analyze("door.urdf", {"time": t, "door_hinge.q": q, "door_hinge.effort": tau})

The recording format is ``../shared/spec/gap-recording.md``: ``time``, ``<joint>.q``,
``<joint>.effort``, ``<link>.pos.x`` ... columns. As arrays, NaN is a missing sample.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Mapping, Optional, Sequence, Union

import numpy as np

from . import _native

__all__ = ["analyze"]


def _csv(columns: Mapping[str, Any], gravity: Optional[Sequence[float]]) -> str:
    from . import _ValueError

    if "time" not in columns:
        raise _ValueError("recording: no `time` array; expected a mapping with `time` and `<joint>.q` / `<joint>.effort` arrays")
    names = ["time"] + sorted(k for k in columns if k != "time")
    arrays = []
    for name in names:
        a = np.asarray(columns[name])
        if a.dtype.kind not in "fiu" or a.ndim != 1:
            raise _ValueError(f"recording: array `{name}` has dtype {a.dtype} and shape {a.shape}; expected a 1-D numeric array")
        arrays.append(a.astype(np.float64))
    n = len(arrays[0])
    for name, a in zip(names, arrays):
        if len(a) != n:
            raise _ValueError(f"recording: array `{name}` has {len(a)} samples, `time` has {n}; expected one per time")
    lines = []
    if gravity is not None:
        lines.append("# gravity: " + " ".join(repr(float(g)) for g in gravity))
    lines.append(",".join(names))
    for row in range(n):
        lines.append(",".join("" if np.isnan(a[row]) else repr(float(a[row])) for a in arrays))
    return "\n".join(lines) + "\n"


def analyze(
    model_urdf: Union[str, "os.PathLike[str]"],
    recording: Union[str, "os.PathLike[str]", Mapping[str, Any]],
    *,
    gravity: Optional[Sequence[float]] = None,
) -> Dict[str, Any]:
    """Analyses a recording against a model URDF; returns the report (``report.json``'s content).
    ``recording`` is a CSV path or a mapping of column name to array."""
    model = os.fspath(model_urdf)
    if isinstance(recording, Mapping):
        text = _native.gap_analyze(model, "recording", _csv(recording, gravity))
    else:
        if gravity is not None:
            from . import _ValueError

            raise _ValueError("gravity: give it in the CSV's `# gravity:` line when the recording is a file")
        text = _native.gap_analyze(model, os.fspath(recording), None)
    return json.loads(text)
