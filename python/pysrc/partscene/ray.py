"""Many scans on a Ray cluster: one Ray task per scan, each calling this package.

    import ray, partscene.ray
    ray.init(address="auto")                       # or ray.init() on one machine
    report = partscene.ray.reconstruct_all(["scans/"], "out")

or ``python -m partscene.ray scans/ --out out [--address auto]``.

Inputs are what ``partscene batch`` takes (scan files, folders, glob patterns, ``.txt``
manifests) and so are the outputs: ``out/<name>/`` per scan with its ``batch-entry.json``, and
``out/batch.json`` + ``out/batch.md``. Each task runs exactly what ``partscene batch`` runs for one
scan (the same skipping of scans done before with the same inputs, the same failure records), so
a Ray run and a local batch run can resume each other. A task that dies (a node lost) is recorded
as failed and the rest go on.

On a multi-node cluster, ``out`` and the scans must be on storage every node sees (NFS, a shared
volume) at the same paths; install this package on every node (or ship it with a runtime
environment).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Union

from . import _native

__all__ = ["reconstruct_all", "main"]

PathLike = Union[str, "os.PathLike[str]"]


def _task(scan: str, name: str, out: str, vocabulary: Optional[str]) -> str:
    from partscene import _native as native  # imported on the worker

    return native.batch_run_one(scan, name, out, vocabulary)


def _lost(scan: str, name: str, out: str, error: str) -> str:
    return json.dumps(
        {
            "scan": scan,
            "name": name,
            "out": os.path.join(out, name),
            "status": "failed",
            "fingerprint": "",
            "objects": 0,
            "parts": 0,
            "joints": 0,
            "movable_joints": 0,
            "warnings": 0,
            "seconds": 0.0,
            "error": f"Ray task failed: {error}",
        }
    )


def reconstruct_all(
    inputs: Union[PathLike, Sequence[PathLike]],
    out: PathLike,
    *,
    vocabulary: Optional[PathLike] = None,
    num_cpus: float = 1,
) -> Dict[str, Any]:
    """Reconstructs every scan named by ``inputs`` into ``out`` as Ray tasks (``num_cpus`` each) on
    the Ray instance this process is connected to (``ray.init`` first; a local one is started if
    none is). Returns the summary (``batch.json``'s content)."""
    import ray

    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    out = os.path.abspath(os.fspath(out))
    vocab = None if vocabulary is None else os.path.abspath(os.fspath(vocabulary))
    scans = [(os.path.abspath(s), n) for s, n in _native.batch_inputs([os.fspath(i) for i in inputs])]
    os.makedirs(out, exist_ok=True)
    if not ray.is_initialized():
        ray.init()
    remote = ray.remote(num_cpus=num_cpus, max_retries=0)(_task)
    started = time.perf_counter()
    refs = [remote.remote(scan, name, out, vocab) for scan, name in scans]
    outcomes: List[str] = []
    for (scan, name), ref in zip(scans, refs):
        try:
            outcomes.append(ray.get(ref))
        except Exception as e:  # a worker or node died: recorded, the rest go on
            outcomes.append(_lost(scan, name, out, str(e).splitlines()[0] if str(e) else type(e).__name__))
    seconds = time.perf_counter() - started
    threads = int(ray.cluster_resources().get("CPU", 0) // max(num_cpus, 1e-9))
    return json.loads(_native.batch_write_report(outcomes, out, seconds, threads))


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m partscene.ray", description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="+", help="scan files, folders, glob patterns or .txt manifests")
    parser.add_argument("--out", required=True)
    parser.add_argument("--address", default=None, help="Ray cluster address (e.g. auto); default: start a local instance")
    parser.add_argument("--num-cpus", type=int, default=None, help="CPUs of a local instance (default: all)")
    parser.add_argument("--vocab", default=None, help="a TOML vocabulary laid over the built-in one")
    args = parser.parse_args(argv)
    import ray

    ray.init(address=args.address, num_cpus=None if args.address else args.num_cpus)
    report = reconstruct_all(args.inputs, args.out, vocabulary=args.vocab)
    with open(os.path.join(args.out, "batch.md"), encoding="utf-8") as f:
        sys.stdout.write(f.read())
    return 1 if report["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
