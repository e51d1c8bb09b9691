#!/usr/bin/env python3
"""Throughput of many scans: `partscene batch` against the Ray path on the same scans (issue 13).

    bench_batch.py --bin target/release/partscene [--scans 20] [--cpus 2] [--work DIR]

Needs the `partscene` Python package and PyPI `ray` in this interpreter. Makes SCANS demo rooms
with the CLI (generated rooms: this measures speed, not quality), then, side by side in one run:
  - `partscene batch` on CPUS threads;
  - `partscene.ray.reconstruct_all` on a local `ray.init(num_cpus=CPUS)` (started beforehand);
  - Ray's own overhead per task: round trips of empty tasks.
Prints a Markdown table (scans per core-second, seconds per scan) and what 1,500 scenes would take
on N nodes, computed from the measured cost per scan (a calculation, not a measurement).
"""

import argparse
import os
import shutil
import subprocess
import tempfile
import time


def timed(fn):
    t = time.perf_counter()
    result = fn()
    return time.perf_counter() - t, result


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--scans", type=int, default=20)
    ap.add_argument("--cpus", type=int, default=2)
    ap.add_argument("--work", default=None)
    args = ap.parse_args()
    import ray

    import partscene.ray

    work = args.work or tempfile.mkdtemp(prefix="partscene-bench-batch-")
    demo = os.path.join(work, "demo")
    if not os.path.isdir(demo):
        subprocess.run([args.bin, "demo", "--count", str(args.scans), "--out", demo], check=True, capture_output=True)
    manifest = os.path.join(work, "scans.txt")
    with open(manifest, "w") as f:
        for s in range(args.scans):
            f.write(os.path.join(demo, f"seed-{s}", "scan.ply") + "\n")

    out_batch = os.path.join(work, "batch")
    shutil.rmtree(out_batch, ignore_errors=True)
    batch_s, _ = timed(lambda: subprocess.run([args.bin, "batch", manifest, "--out", out_batch, "--jobs", str(args.cpus)], check=True,
                                              capture_output=True))

    init_s, _ = timed(lambda: ray.init(num_cpus=args.cpus, include_dashboard=False, log_to_driver=False))
    noop = ray.remote(num_cpus=1)(lambda: None)
    ray.get([noop.remote() for _ in range(20)])  # warm the workers
    n_empty = 200
    empty_s, _ = timed(lambda: ray.get([noop.remote() for _ in range(n_empty)]))
    out_ray = os.path.join(work, "ray")
    shutil.rmtree(out_ray, ignore_errors=True)
    ray_s, report = timed(lambda: partscene.ray.reconstruct_all(manifest, out_ray))
    ray.shutdown()
    assert report["done"] == args.scans, report

    n, c = args.scans, args.cpus
    rows = [
        ("partscene batch", batch_s),
        ("Ray (partscene.ray)", ray_s),
    ]
    print(f"{n} demo rooms, {c} cores, one run\n")
    print("| path | wall s | scans per core-second | core-seconds per scan |")
    print("| --- | ---: | ---: | ---: |")
    for name, s in rows:
        print(f"| {name} | {s:.1f} | {n / (s * c):.3f} | {s * c / n:.2f} |")
    per_task_ms = 1000.0 * empty_s * c / n_empty
    print(f"\nRay: start-up {init_s:.1f} s (not in the wall time above); an empty task costs {per_task_ms:.1f} core-ms "
          f"({n_empty} round trips on {c} workers); Ray's wall time is {ray_s / batch_s:.2f}x the batch's.")
    cost = ray_s * c / n
    print(f"\n1,500 scenes at {cost:.2f} core-seconds each (this run's Ray figure; a real room scan may cost more):")
    for nodes, cores in ((1, 16), (10, 16), (50, 16)):
        seconds = 1500 * cost / (nodes * cores)
        # Each node also pays Ray's start-up and per-task overhead; 1,500 tasks is far from Ray's limits.
        print(f"- {nodes} node(s) x {cores} cores: {seconds:.0f} s of work per core (+ {init_s:.0f} s start-up)")


if __name__ == "__main__":
    main()
