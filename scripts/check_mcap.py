#!/usr/bin/env python3
"""ROS recordings in the reality gap (issue 12): each recording of the given folders is written
as ROS messages, and `partscene gap` must find from them what it finds from the CSV:

- as an MCAP file of sensor_msgs/msg/JointState by PyPI `mcap-ros2-support` (the writer ROS tools
  use);
- as a rosbag2 folder (MCAP storage, metadata.yaml) by PyPI `rosbags`, with tracked link poses
  (`<link>.pos.*`, `<link>.quat.*` columns) as tf2_msgs/msg/TFMessage on /tf (parent `world`,
  the link the child frame) beside the JointState messages.

Same effects (joint and kind) and the same misfit before fitting (to 2 %: times pass through whole
nanoseconds and poses through quaternions, and a 10 s open-loop replay of a chaotic double
pendulum released from 1.2 rad magnifies that to half a percent) are required.

    check_mcap.py --bin PARTSCENE [--tracked-only] CASES_DIR...   (folders of case folders:
        model.urdf + recording.csv; --tracked-only: only those with tracked link poses)

Needs mcap, mcap-ros2-support and rosbags. Exits 1 on a difference or an error.
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

from mcap_ros2.writer import Writer

JOINT_STATE = """std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""


def write_mcap(csv_path, mcap_path, start_s=1_700_000_000.0):
    rows = [line for line in open(csv_path, encoding="utf-8") if not line.startswith("#")]
    reader = csv.reader(rows)
    header = next(reader)
    joints = sorted({c.rsplit(".", 1)[0] for c in header if c.endswith(".q")})
    with open(mcap_path, "wb") as f:
        w = Writer(f)
        schema = w.register_msgdef("sensor_msgs/msg/JointState", JOINT_STATE)
        for row in reader:
            cells = dict(zip(header, row))
            t = start_s + float(cells["time"])
            sec = int(t)
            nsec = int(round((t - sec) * 1e9))
            names = [j for j in joints if cells.get(j + ".q", "") != ""]
            msg = {
                "header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": "base"},
                "name": names,
                "position": [float(cells[j + ".q"]) for j in names],
                "velocity": [],
                "effort": [float(cells.get(j + ".effort") or 0.0) for j in names],
            }
            w.write_message(topic="/joint_states", schema=schema, message=msg, log_time=int(t * 1e9), publish_time=int(t * 1e9))
        w.finish()


def rows_of(csv_path):
    lines = [line for line in open(csv_path, encoding="utf-8") if not line.startswith("#")]
    reader = csv.reader(lines)
    header = next(reader)
    return header, [dict(zip(header, row)) for row in reader]


def write_rosbag(csv_path, bag_dir, start_s=1_700_000_000.0):
    """A rosbag2 (MCAP storage) by `rosbags`: JointState rows on /joint_states, link poses on /tf."""
    import numpy as np
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    header, rows = rows_of(csv_path)
    q_joints = sorted({c.rsplit(".", 1)[0] for c in header if c.endswith(".q")})
    e_joints = sorted({c.rsplit(".", 1)[0] for c in header if c.endswith(".effort")})
    links = sorted({c.split(".pos.")[0] for c in header if ".pos." in c})
    with Writer(bag_dir, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        js = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
        tf = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts) if links else None
        for cells in rows:
            t = start_s + float(cells["time"])
            ns = int(round(t * 1e9))
            stamp = T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            names = [j for j in q_joints if cells.get(j + ".q", "") != ""]
            efforts = [j for j in e_joints if cells.get(j + ".effort", "") != ""]
            if names or efforts:
                # Positions and efforts must name the same joints: efforts alone when q is absent.
                named = names or efforts
                msg = T["sensor_msgs/msg/JointState"](
                    header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="base"),
                    name=named,
                    position=np.array([float(cells[j + ".q"]) for j in names], dtype=np.float64),
                    velocity=np.array([], dtype=np.float64),
                    effort=np.array([float(cells.get(j + ".effort") or 0.0) for j in named] if efforts else [], dtype=np.float64),
                )
                w.write(js, ns, ts.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
            poses = [l for l in links if cells.get(l + ".pos.x", "") != "" and cells.get(l + ".quat.w", "") != ""]
            if tf and poses:
                transforms = [
                    T["geometry_msgs/msg/TransformStamped"](
                        header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="world"),
                        child_frame_id=l,
                        transform=T["geometry_msgs/msg/Transform"](
                            translation=T["geometry_msgs/msg/Vector3"](*(float(cells[f"{l}.pos.{a}"]) for a in "xyz")),
                            rotation=T["geometry_msgs/msg/Quaternion"](*(float(cells[f"{l}.quat.{a}"]) for a in "xyzw")),
                        ),
                    )
                    for l in poses
                ]
                w.write(tf, ns, ts.serialize_cdr(T["tf2_msgs/msg/TFMessage"](transforms=transforms), "tf2_msgs/msg/TFMessage"))


def analysed(binary, model, recording, out):
    subprocess.run([binary, "gap", "--model", model, "--recording", recording, "--out", out], check=True, capture_output=True)
    report = json.load(open(os.path.join(out, "report.json")))
    return sorted((e["joint"], e["kind"]) for e in report["effects"]), report["fit"]["rmse_before"]


def same(a, b):
    # Open-loop replays of chaotic mechanisms (a double pendulum) magnify the nanosecond rounding
    # of the times and the quaternion round trip of poses; 2 % of the misfit is far below any
    # effect, and the effects themselves must match exactly.
    return a[0] == b[0] and abs(a[1] - b[1]) <= 2e-2 * max(abs(a[1]), 1e-12)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--tracked-only", action="store_true", help="only the cases whose CSV has tracked link poses")
    ap.add_argument("cases", nargs="+")
    args = ap.parse_args()
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        for folder in args.cases:
            for case in sorted(os.listdir(folder)):
                d = os.path.join(folder, case)
                csv_path = os.path.join(d, "recording.csv")
                if not os.path.isfile(csv_path):
                    continue
                model = os.path.join(d, "model.urdf")
                header, _ = rows_of(csv_path)
                if args.tracked_only and not any(".pos." in c for c in header):
                    continue
                base = analysed(args.bin, model, csv_path, os.path.join(tmp, case + "-csv"))
                results = []
                if any(c.endswith(".q") for c in header):
                    mcap_path = os.path.join(tmp, case + ".mcap")
                    write_mcap(csv_path, mcap_path)
                    results.append(("MCAP", analysed(args.bin, model, mcap_path, os.path.join(tmp, case + "-mcap"))))
                bag = os.path.join(tmp, case + "-bag")
                write_rosbag(csv_path, bag)
                kind = "rosbag2 + /tf" if any(".pos." in c for c in header) else "rosbag2"
                results.append((kind, analysed(args.bin, model, bag, os.path.join(tmp, case + "-bag-out"))))
                for kind, got in results:
                    ok = same(base, got)
                    bad += not ok
                    print(f"{case}: {kind}: effects {got[0]}, misfit {got[1]:.6g}; CSV: {base[0]}, {base[1]:.6g}: {'same' if ok else 'DIFFERENT'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
