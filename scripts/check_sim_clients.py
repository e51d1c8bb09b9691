#!/usr/bin/env python3
"""Loads partscene's exports in real simulators and checks they mean what scene.json says.

    check_sim_clients.py [SCENE_DIR ...]

Each SCENE_DIR holds scene.json, scene.urdf and scene.mjcf.xml (`partscene demo --out SCENE_DIR`;
`demo --count K --out DIR` gives DIR/seed-*); without one the demo scene is exported first with
`cargo run --release --no-default-features -- demo --out <temporary folder>`.

Checks, each against scene.json (joint `<child urdf_link>_joint`, type, world axis, world
origin, limits):
  1. PyBullet loads scene.urdf (fixed base): every joint there, same type, axis and origin in the
     world after PyBullet's frames, same limits.
  2. MuJoCo loads scene.urdf: the movable joints (MuJoCo welds fixed ones), same type, world axis
     and anchor, same range.
  3. MuJoCo compiles scene.mjcf.xml: one body per part, the movable joints as above, and the
     joint-space inertia (diagonal of the mass matrix) equal to PyBullet's from the URDF.
  4. A push: each movable joint alone gets a constant generalized force for 0.5 s (gravity off),
     sized to move it a fifth of its range if nothing resists; MuJoCo (MJCF) and PyBullet (URDF)
     must move it the same way: positive (opening), within 10 % of each other and of the
     prediction from the inertia.
Exits 1 with one line per mismatch. Needs only the standard library, numpy, pybullet, mujoco.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

PUSH_SECONDS = 0.5
TIMESTEP = 0.001
PUSH_SHARE = 0.2  # of the joint's range
AXIS_TOL = 1e-4  # 1 - cos(angle)
POS_TOL = 1e-4  # m
LIMIT_TOL = 1e-5
INERTIA_RTOL = 1e-3
MOTION_RTOL = 0.10

failures = []


def fail(message):
    failures.append(message)
    print("MISMATCH: " + message, flush=True)


def unit(v):
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def scene_joints(scene):
    """name -> expected joint (type, axis, origin, lower, upper) from scene.json."""
    link = {p["id"]: p["urdf_link"] for p in scene["parts"]}
    out = {}
    for j in scene["joints"]:
        out[link[j["child"]] + "_joint"] = {
            "type": j["type"],
            "axis": unit(j["axis_world"]),
            "origin": np.asarray(j["origin_world"], dtype=float),
            "lower": float(j["lower"]),
            "upper": float(j["upper"]),
            "parent": link[j["parent"]],
            "child": link[j["child"]],
        }
    return out


def compare_joint(client, name, want, kind, axis, origin, lower, upper):
    if kind != want["type"]:
        fail(f"{client}: joint {name} is {kind}, scene.json says {want['type']}")
        return
    if want["type"] == "fixed":
        return
    if 1.0 - float(np.dot(unit(axis), want["axis"])) > AXIS_TOL:
        fail(f"{client}: joint {name} axis {np.round(axis, 5)} in the world, scene.json says {np.round(want['axis'], 5)}")
    # Any point on the axis will do for a slide; a hinge must sit on the hinge line.
    offset = np.asarray(origin) - want["origin"]
    off_axis = offset - np.dot(offset, want["axis"]) * want["axis"]
    if np.linalg.norm(off_axis if want["type"] == "prismatic" else offset) > POS_TOL:
        fail(f"{client}: joint {name} origin {np.round(origin, 5)}, scene.json says {np.round(want['origin'], 5)}")
    if abs(lower - want["lower"]) > LIMIT_TOL or abs(upper - want["upper"]) > LIMIT_TOL:
        fail(f"{client}: joint {name} limits [{lower:.6f}, {upper:.6f}], scene.json says [{want['lower']:.6f}, {want['upper']:.6f}]")


# --------------------------------------------------------------------------------------------
# PyBullet


def pybullet_load(urdf):
    import pybullet as p

    client = p.connect(p.DIRECT)
    p.setGravity(0, 0, 0, physicsClientId=client)
    p.setPhysicsEngineParameter(fixedTimeStep=TIMESTEP, physicsClientId=client)
    body = p.loadURDF(urdf, useFixedBase=True, flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
    return p, client, body


def check_pybullet(p, client, body, expected, scene):
    types = {p.JOINT_REVOLUTE: "revolute", p.JOINT_PRISMATIC: "prismatic", p.JOINT_FIXED: "fixed"}
    seen = {}
    for i in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, i, physicsClientId=client)
        name = info[1].decode()
        seen[name] = i
        if name.endswith("_mount"):
            if info[2] != p.JOINT_FIXED:
                fail(f"pybullet: object mount {name} is not fixed")
            continue
        want = expected.get(name)
        if want is None:
            fail(f"pybullet: joint {name} is not in scene.json")
            continue
        if info[12].decode() != want["child"]:
            fail(f"pybullet: joint {name} moves link {info[12].decode()}, expected {want['child']}")
        state = p.getLinkState(body, i, computeForwardKinematics=True, physicsClientId=client)
        # PyBullet keeps a link's joint axis in the link's inertial (centre-of-mass) frame.
        rot = np.asarray(p.getMatrixFromQuaternion(state[1])).reshape(3, 3)
        axis_world = rot @ np.asarray(info[13])
        compare_joint("pybullet", name, want, types.get(info[2], f"type {info[2]}"), axis_world, state[4], info[8], info[9])
    for name in expected:
        if name not in seen:
            fail(f"pybullet: joint {name} of scene.json is missing")
    mounts = sum(1 for n in seen if n.endswith("_mount"))
    if mounts != len(scene["objects"]):
        fail(f"pybullet: {mounts} object mounts, scene.json has {len(scene['objects'])} objects")
    return seen


def pybullet_mass_diag(p, client, body, movable_indices):
    """Diagonal of the joint-space mass matrix at rest, by joint index."""
    dofs = [0.0] * len(movable_indices)
    m = np.asarray(p.calculateMassMatrix(body, dofs, physicsClientId=client))
    return {j: m[k, k] for k, j in enumerate(movable_indices)}


def pybullet_push(p, client, body, all_indices, index, force):
    for i in all_indices:
        p.resetJointState(body, i, 0.0, 0.0, physicsClientId=client)
    p.setJointMotorControlArray(body, all_indices, p.VELOCITY_CONTROL, forces=[0.0] * len(all_indices), physicsClientId=client)
    for i in range(-1, p.getNumJoints(body, physicsClientId=client)):
        p.changeDynamics(body, i, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0, physicsClientId=client)
    for _ in range(round(PUSH_SECONDS / TIMESTEP)):
        p.setJointMotorControl2(body, index, p.TORQUE_CONTROL, force=force, physicsClientId=client)
        p.stepSimulation(physicsClientId=client)
    return p.getJointState(body, index, physicsClientId=client)[0]


# --------------------------------------------------------------------------------------------
# MuJoCo


def check_mujoco(mujoco, model, expected, client):
    types = {int(mujoco.mjtJoint.mjJNT_HINGE): "revolute", int(mujoco.mjtJoint.mjJNT_SLIDE): "prismatic"}
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    movable = {n: w for n, w in expected.items() if w["type"] != "fixed"}
    seen = {}
    for j in range(model.njnt):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        seen[name] = j
        want = movable.get(name)
        if want is None:
            fail(f"{client}: joint {name} is not a movable joint of scene.json")
            continue
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])
        if body != want["child"]:
            fail(f"{client}: joint {name} moves body {body}, expected {want['child']}")
        if not model.jnt_limited[j]:
            fail(f"{client}: joint {name} is not limited")
        lo, hi = model.jnt_range[j]
        kind = types.get(int(model.jnt_type[j]), f"type {model.jnt_type[j]}")
        compare_joint(client, name, want, kind, data.xaxis[j], data.xanchor[j], lo, hi)
    for name in movable:
        if name not in seen:
            fail(f"{client}: joint {name} of scene.json is missing")
    return data, seen


def mujoco_mass_diag(mujoco, model, data, joints):
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    try:
        mujoco.mj_fullM(model, data, full)  # MuJoCo >= 3.4 / 4
    except TypeError:
        mujoco.mj_fullM(model, full, data.qM)  # older MuJoCo
    return {name: full[model.jnt_dofadr[j], model.jnt_dofadr[j]] for name, j in joints.items()}


def mujoco_push(mujoco, model, data, joint, force):
    mujoco.mj_resetData(model, data)
    model.opt.timestep = TIMESTEP
    model.opt.gravity[:] = 0.0
    data.qfrc_applied[:] = 0.0
    data.qfrc_applied[model.jnt_dofadr[joint]] = force
    contacts = 0
    for _ in range(round(PUSH_SECONDS / TIMESTEP)):
        mujoco.mj_step(model, data)
        contacts = max(contacts, data.ncon)
    return data.qpos[model.jnt_qposadr[joint]], contacts


# --------------------------------------------------------------------------------------------


def export_demo(out):
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    cmd = ["cargo", "run", "--quiet", "--release", "--no-default-features", "--", "demo", "--out", out]
    print("exporting the demo scene: " + " ".join(cmd), flush=True)
    subprocess.run(cmd, cwd=root, check=True, stdout=subprocess.DEVNULL)


def check_dir(scene_dir):
    """Runs every check on one exported scene; mismatches go to `failures`."""
    import mujoco

    paths = {k: os.path.join(scene_dir, f) for k, f in [("json", "scene.json"), ("urdf", "scene.urdf"), ("mjcf", "scene.mjcf.xml")]}
    for path in paths.values():
        if not os.path.isfile(path):
            fail(f"{path} is missing (export the scene with `partscene demo --out DIR`)")
            return
    with open(paths["json"]) as f:
        scene = json.load(f)
    expected = scene_joints(scene)
    movable = [n for n, w in expected.items() if w["type"] != "fixed"]
    print(f"{scene_dir}: {len(scene['parts'])} parts, {len(expected)} joints ({len(movable)} movable)", flush=True)

    p, client, body = pybullet_load(paths["urdf"])
    pb_index = check_pybullet(p, client, body, expected, scene)
    print(f"  pybullet {p.getAPIVersion()}: scene.urdf loaded, {p.getNumJoints(body, physicsClientId=client)} joints compared", flush=True)

    try:
        urdf_model = mujoco.MjModel.from_xml_path(paths["urdf"])
    except Exception as e:  # MuJoCo raises ValueError on compile errors
        fail(f"mujoco: scene.urdf does not load: {e}")
        urdf_model = None
    if urdf_model is not None:
        check_mujoco(mujoco, urdf_model, expected, "mujoco (urdf)")
        print(f"  mujoco {mujoco.__version__}: scene.urdf loaded, {urdf_model.njnt} joints compared", flush=True)

    try:
        model = mujoco.MjModel.from_xml_path(paths["mjcf"])
    except Exception as e:
        fail(f"mujoco: scene.mjcf.xml does not compile: {e}")
        model = None
    if model is not None:
        data, mj_joint = check_mujoco(mujoco, model, expected, "mujoco (mjcf)")
        if model.nbody != len(scene["parts"]) + 1:
            fail(f"mujoco (mjcf): {model.nbody - 1} bodies, scene.json has {len(scene['parts'])} parts")
        print(f"  mujoco {mujoco.__version__}: scene.mjcf.xml compiled, {model.nbody - 1} bodies, {model.njnt} joints compared", flush=True)

        movable_pb = [pb_index[n] for n in sorted(movable, key=lambda n: pb_index.get(n, 1 << 30)) if n in pb_index]
        pb_diag = pybullet_mass_diag(p, client, body, movable_pb)
        mj_diag = mujoco_mass_diag(mujoco, model, data, {n: mj_joint[n] for n in movable if n in mj_joint})
        for name in movable:
            if name not in pb_index or name not in mj_joint:
                continue
            a, b = pb_diag[pb_index[name]], mj_diag[name]
            if abs(a - b) > INERTIA_RTOL * max(a, b):
                fail(f"inertia along {name}: pybullet {a:.6g}, mujoco (mjcf) {b:.6g}")

        all_pb = list(range(p.getNumJoints(body, physicsClientId=client)))
        worst = 0.0
        for name in movable:
            if name not in pb_index or name not in mj_joint:
                continue
            want = expected[name]
            target = PUSH_SHARE * (want["upper"] - want["lower"])
            force = mj_diag[name] * 2.0 * target / PUSH_SECONDS**2
            q_mj, contacts = mujoco_push(mujoco, model, data, mj_joint[name], force)
            q_pb = pybullet_push(p, client, body, all_pb, pb_index[name], force)
            unit_name = "rad" if want["type"] == "revolute" else "m"
            line = f"push {name}: {force:.4g} for {PUSH_SECONDS} s -> mujoco {q_mj:+.4f}, pybullet {q_pb:+.4f}, predicted {target:+.4f} {unit_name}"
            print("    " + line + (f" ({contacts} contacts)" if contacts else ""), flush=True)
            if target <= 0:
                fail(f"{name}: empty range [{want['lower']}, {want['upper']}]")
                continue
            if q_mj <= 0 or q_pb <= 0:
                fail(line + ": not both positive (opening)")
            if abs(q_mj - q_pb) > MOTION_RTOL * target:
                fail(line + ": the simulators disagree")
            if abs(q_mj - target) > MOTION_RTOL * target:
                fail(line + ": mujoco is off the prediction from the inertia")
            if abs(q_pb - target) > MOTION_RTOL * target:
                fail(line + ": pybullet is off the prediction from the inertia")
            worst = max(worst, abs(q_mj - q_pb) / target)
        print(f"  pushes: {len(movable)} joints, largest mujoco/pybullet difference {100 * worst:.2f} % of the motion", flush=True)
    p.disconnect(client)


def main():
    started = time.time()
    if any(a.startswith("-") for a in sys.argv[1:]):
        print(__doc__)
        return 2
    tmp = None
    dirs = sys.argv[1:]
    if not dirs:
        tmp = tempfile.TemporaryDirectory(prefix="partscene-sim-")
        export_demo(tmp.name)
        dirs = [tmp.name]
    for d in dirs:
        check_dir(d)
    if tmp is not None:
        tmp.cleanup()
    took = time.time() - started
    if failures:
        print(f"check_sim_clients: {len(failures)} mismatches in {len(dirs)} scenes ({took:.1f} s)", file=sys.stderr)
        return 1
    print(f"check_sim_clients: {len(dirs)} scenes: URDF in PyBullet and MuJoCo, MJCF in MuJoCo agree with scene.json ({took:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
