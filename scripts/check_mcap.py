#!/usr/bin/env python3
"""ROS recordings in the reality gap (issue 12): each real recording of ../shared/data/recordings
is written as an MCAP of sensor_msgs/msg/JointState by PyPI `mcap-ros2-support` (the writer ROS
tools use), then `partscene gap` reads the MCAP and the CSV; the effects found must be the same.

    check_mcap.py --bin PARTSCENE RECORDINGS_DIR

Needs mcap and mcap-ros2-support. Exits 1 on a difference or an error.
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


def effects(binary, model, recording, out):
    subprocess.run([binary, "gap", "--model", model, "--recording", recording, "--out", out], check=True, capture_output=True)
    report = json.load(open(os.path.join(out, "report.json")))
    return sorted((e["joint"], e["kind"]) for e in report["effects"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("recordings")
    args = ap.parse_args()
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        for case in sorted(os.listdir(args.recordings)):
            d = os.path.join(args.recordings, case)
            if not os.path.isfile(os.path.join(d, "recording.csv")):
                continue
            mcap_path = os.path.join(tmp, case + ".mcap")
            write_mcap(os.path.join(d, "recording.csv"), mcap_path)
            model = os.path.join(d, "model.urdf")
            from_csv = effects(args.bin, model, os.path.join(d, "recording.csv"), os.path.join(tmp, case + "-csv"))
            from_mcap = effects(args.bin, model, mcap_path, os.path.join(tmp, case + "-mcap"))
            same = from_csv == from_mcap
            bad += not same
            print(f"{case}: MCAP {os.path.getsize(mcap_path)} bytes; effects from CSV {from_csv}, from MCAP {from_mcap}: {'same' if same else 'DIFFERENT'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
