#!/usr/bin/env python3
"""Self-collision check of partscene's exports in PyBullet and MuJoCo (issue 12).

    check_self_collision.py SCENE_DIR [SCENE_DIR ...] [--untrimmed] [--min-pushed SHARE]

Each SCENE_DIR holds scene.urdf, scene.mjcf.xml, scene_objects.json and objects/*.urdf, *.xml
(`partscene demo --out`, `partscene reconstruct --out`, `partscene bench --export`).
Loaded as a robotics user loads them, with self-collision on:
  - PyBullet: `URDF_USE_SELF_COLLISION` (parent-child pairs excluded, PyBullet's default; PyBullet
    reads no SRDF, so this tests the clearance of the collision shapes), every object file alone,
    all object files together at the poses of scene_objects.json, and scene.urdf;
  - MuJoCo: every object's MJCF and scene.mjcf.xml (MuJoCo collides every pair its
    `<contact><exclude>` does not list, and those are the SRDF's pairs);
  - SAPIEN 3 (when installed): every object's URDF with its SRDF, CPU PhysX, at rest only.
Checks:
  1. At rest under gravity, no motors, 2 s: a joint that stays still with contacts off (the same
     model with self-collision off / MuJoCo's contact flag disabled) stays within 1 mm / 0.5 deg
     with them on. Joints gravity moves anyway (a lid hinged below its centre) are counted apart.
  2. Push through the range and back (PyBullet, each object alone): every limited movable joint,
     position-controlled while the others are free, reaches 90 % of its range and comes back
     within 2 % of the range.
--untrimmed replaces every URDF collision shape by the visual one (the fitted primitive) before
loading, PyBullet only: the figures of an export without clearance, for comparison; it never fails.
--min-pushed SHARE: a joint that cannot be pushed through its range is reported, and fails the run
only when fewer than SHARE of all pushed joints come through (reconstructions of others' objects,
where a wrong parent or axis of the reconstruction itself sweeps a part into another); the checks
at rest always fail the run.
Exits 1 with one line per failure. Needs numpy, pybullet, mujoco.
"""

import json
import math
import os
import re
import shutil
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

TIMESTEP = 1.0 / 240.0
REST_SECONDS = 2.0
TOL_M = 0.001
TOL_RAD = math.radians(0.5)
PUSH_SHARE = 0.9
BACK_SHARE = 0.02
PUSH_SECONDS = 3.0

failures = []
push_failures = []


def fail(message, strict, push=False):
    if strict:
        (push_failures if push else failures).append(message)
    print(("FAIL: " if strict else "would fail: ") + message, flush=True)


def untrimmed_copy(urdf, tmp):
    """The URDF with each link's collision elements replaced by its visual geometry."""
    tree = ET.parse(urdf)
    for link in tree.getroot().iter("link"):
        for c in list(link.findall("collision")):
            link.remove(c)
        for v in link.findall("visual"):
            c = ET.SubElement(link, "collision")
            for child in v:
                if child.tag in ("origin", "geometry"):
                    c.append(child)
    out = os.path.join(tmp, os.path.basename(urdf))
    tree.write(out)
    return out


def tolerance(kind):
    return TOL_M if kind == "prismatic" else TOL_RAD


# --------------------------------------------------------------------------------------------
# PyBullet


def pb_world(p, self_collision):
    client = p.connect(p.DIRECT)
    p.setGravity(0, 0, -9.81, physicsClientId=client)
    p.setPhysicsEngineParameter(fixedTimeStep=TIMESTEP, physicsClientId=client)
    return client


def pb_load(p, client, urdf, xyz, self_collision):
    flags = p.URDF_USE_INERTIA_FROM_FILE | (p.URDF_USE_SELF_COLLISION if self_collision else 0)
    body = p.loadURDF(urdf, basePosition=xyz, useFixedBase=True, flags=flags, physicsClientId=client)
    joints = []
    for i in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, i, physicsClientId=client)
        if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
            kind = "revolute" if info[2] == p.JOINT_REVOLUTE else "prismatic"
            joints.append((body, i, info[1].decode(), kind, info[8], info[9]))
    # No motors: PyBullet's default velocity motors would hold every joint.
    for b, i, *_ in joints:
        p.setJointMotorControl2(b, i, p.VELOCITY_CONTROL, force=0.0, physicsClientId=client)
    return body, joints


def pb_rest(p, files, self_collision):
    """Joint displacement after REST_SECONDS under gravity, by joint name."""
    client = pb_world(p, self_collision)
    joints = []
    for urdf, xyz in files:
        _, js = pb_load(p, client, urdf, xyz, self_collision)
        joints += js
    try:
        start = {name: p.getJointState(b, i, physicsClientId=client)[0] for b, i, name, *_ in joints}
    except p.error:
        # PyBullet's client reads the state of at most MAX_DEGREE_OF_FREEDOM joints of one body.
        p.disconnect(physicsClientId=client)
        return None
    for _ in range(round(REST_SECONDS / TIMESTEP)):
        p.stepSimulation(physicsClientId=client)
    out = {name: (kind, abs(p.getJointState(b, i, physicsClientId=client)[0] - start[name])) for b, i, name, kind, *_ in joints}
    p.disconnect(physicsClientId=client)
    return out


def pb_push(p, urdf, label, strict):
    """Each limited joint alone: to 90 % of its range and back, self-collision on."""
    moved = 0
    client = pb_world(p, True)
    body, joints = pb_load(p, client, urdf, [0, 0, 0], True)
    for b, i, name, kind, lower, upper in joints:
        if not upper > lower:
            continue
        for _, k, *_ in joints:
            p.resetJointState(b, k, 0.0, 0.0, physicsClientId=client)
        span = upper - lower
        start = min(max(0.0, lower), upper)
        far = lower + PUSH_SHARE * span if start - lower < 0.5 * span else upper - PUSH_SHARE * span
        ok = True
        for target, share in ((far, 0.05), (start, BACK_SHARE)):
            # The pushed joint position-controlled, the others free (no motor), as a hand
            # opening one door leaves the rest alone.
            for _, k, *_ in joints:
                if k == i:
                    p.setJointMotorControl2(b, k, p.POSITION_CONTROL, targetPosition=target, force=500.0, maxVelocity=1.0,
                                            physicsClientId=client)
                else:
                    p.setJointMotorControl2(b, k, p.VELOCITY_CONTROL, force=0.0, physicsClientId=client)
            for _ in range(round(PUSH_SECONDS / TIMESTEP)):
                p.stepSimulation(physicsClientId=client)
            q = p.getJointState(b, i, physicsClientId=client)[0]
            if abs(q - target) > share * span:
                fail(f"pybullet {label}: joint {name} pushed to {target:.3f} stops at {q:.3f} (range [{lower:.3f}, {upper:.3f}])", strict,
                     push=True)
                ok = False
                break
        moved += ok
    p.disconnect(physicsClientId=client)
    return moved, sum(1 for j in joints if j[5] > j[4])


# --------------------------------------------------------------------------------------------
# MuJoCo


def mj_rest(mujoco, path, contacts):
    model = mujoco.MjModel.from_xml_path(path)
    model.opt.timestep = TIMESTEP
    model.opt.gravity[:] = (0.0, 0.0, -9.81)
    if not contacts:
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = data.qpos.copy()
    for _ in range(round(REST_SECONDS / TIMESTEP)):
        mujoco.mj_step(model, data)
    out = {}
    for j in range(model.njnt):
        kind = {int(mujoco.mjtJoint.mjJNT_HINGE): "revolute", int(mujoco.mjtJoint.mjJNT_SLIDE): "prismatic"}.get(int(model.jnt_type[j]))
        if kind:
            a = model.jnt_qposadr[j]
            out[mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)] = (kind, abs(data.qpos[a] - start[a]))
    return out


# --------------------------------------------------------------------------------------------
# SAPIEN (optional: run when the `sapien` package is installed)


def sapien_module():
    try:
        import sapien
    except ImportError:
        return None
    return sapien


def sp_rest(sapien, urdf, srdf, tmp):
    """One object in SAPIEN 3's CPU PhysX with its SRDF, drives off: joint displacement after
    REST_SECONDS. SAPIEN's URDF loader builds render materials for visual elements and needs a
    Vulkan device for that (it finds none on lavapipe), so a copy without <visual> is loaded:
    collision, inertia and joints are what is tested."""
    with open(urdf) as f:
        text = re.sub(r"<visual\b.*?</visual>", "", f.read(), flags=re.S)
    path = os.path.join(tmp, "sapien_" + os.path.basename(urdf))
    with open(path, "w") as f:
        f.write(text)
    scene = sapien.Scene([sapien.physx.PhysxCpuSystem()])
    scene.set_timestep(TIMESTEP)
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    # A one-link object is an actor to SAPIEN, not an articulation.
    articulations, _actors = loader.load_multiple(path, srdf_file=srdf)
    if not articulations:
        return {}
    art = articulations[0]
    joints = art.get_active_joints()
    for j in joints:
        j.set_drive_properties(0.0, 0.0)
    start = art.get_qpos().copy()
    for _ in range(round(REST_SECONDS / TIMESTEP)):
        scene.step()
    q = art.get_qpos()
    kinds = {"revolute": "revolute", "revolute_unwrapped": "revolute", "continuous": "revolute", "prismatic": "prismatic"}
    return {j.name: (kinds.get(j.type, "revolute"), abs(float(q[k] - start[k]))) for k, j in enumerate(joints)}


# --------------------------------------------------------------------------------------------


def compare_rest(label, free, held, strict, tally):
    """Joints still without contacts must stay still with them."""
    for name, (kind, d_off) in sorted(free.items()):
        tol = tolerance(kind)
        if d_off > tol:
            tally["gravity"] += 1
            continue
        tally["still"] += 1
        d_on = held.get(name, (kind, float("nan")))[1]
        if not d_on <= tol:
            tally["moved"] += 1
            unit = "mm" if kind == "prismatic" else "deg"
            scale = 1000.0 if kind == "prismatic" else 180.0 / math.pi
            fail(f"{label}: joint {name} moves {d_on * scale:.2f} {unit} in {REST_SECONDS:.0f} s at rest with self-collision on", strict)


def check_dir(scene_dir, untrimmed, tmp):
    import mujoco
    import pybullet as p

    strict = not untrimmed
    with open(os.path.join(scene_dir, "scene_objects.json")) as f:
        index = json.load(f)
    prepare = (lambda u: untrimmed_copy(u, tmp)) if untrimmed else (lambda u: u)
    objects = [(prepare(os.path.join(scene_dir, o["urdf"])), o["world_xyz"], o["name"], os.path.join(scene_dir, o["mjcf"]),
                os.path.join(scene_dir, o["srdf"])) for o in index["objects"]]
    scene_urdf = prepare(os.path.join(scene_dir, "scene.urdf"))
    scene_mjcf = os.path.join(scene_dir, "scene.mjcf.xml")
    tally = {"still": 0, "moved": 0, "gravity": 0}
    pushed = [0, 0]
    sapien = None if untrimmed else sapien_module()
    for urdf, xyz, name, mjcf, srdf in objects:
        free = pb_rest(p, [(urdf, [0, 0, 0])], False)
        compare_rest(f"pybullet {name}", free, pb_rest(p, [(urdf, [0, 0, 0])], True), strict, tally)
        if not untrimmed:
            compare_rest(f"mujoco {name}", mj_rest(mujoco, mjcf, False), mj_rest(mujoco, mjcf, True), strict, tally)
        if sapien is not None:
            # Which joints gravity moves anyway: PyBullet's run without contacts.
            compare_rest(f"sapien {name}", free, sp_rest(sapien, urdf, srdf, tmp), strict, tally)
        ok, n = pb_push(p, urdf, name, strict)
        pushed[0] += ok
        pushed[1] += n
    together = [(u, xyz) for u, xyz, *_ in objects]
    compare_rest("pybullet all objects together", pb_rest(p, together, False), pb_rest(p, together, True), strict, tally)
    free = pb_rest(p, [(scene_urdf, [0, 0, 0])], False)
    if free is None:
        print(f"{scene_dir}: NOTE: scene.urdf has more joints than PyBullet's client reads the state of; "
              "it is checked as the objects' files together (above)", flush=True)
    else:
        compare_rest("pybullet scene.urdf", free, pb_rest(p, [(scene_urdf, [0, 0, 0])], True), strict, tally)
    if not untrimmed:
        compare_rest("mujoco scene.mjcf.xml", mj_rest(mujoco, scene_mjcf, False), mj_rest(mujoco, scene_mjcf, True), strict, tally)
    print(f"{scene_dir}{' (untrimmed)' if untrimmed else ''}: {len(objects)} objects; at rest with self-collision on: "
          f"{tally['moved']} of {tally['still']} still joint loads moved (gravity moves {tally['gravity']} anyway); "
          f"pushed through their range and back: {pushed[0]}/{pushed[1]}", flush=True)
    return tally, pushed


def main():
    argv = sys.argv[1:]
    min_pushed = None
    if "--min-pushed" in argv:
        at = argv.index("--min-pushed")
        min_pushed = float(argv[at + 1])
        del argv[at:at + 2]
    args = [a for a in argv if not a.startswith("--")]
    untrimmed = "--untrimmed" in argv
    if not args:
        print(__doc__)
        return 2
    tmp = tempfile.mkdtemp()
    try:
        totals = {"still": 0, "moved": 0, "gravity": 0}
        pushed = [0, 0]
        for d in args:
            tally, pu = check_dir(d, untrimmed, tmp)
            for k in totals:
                totals[k] += tally[k]
            pushed[0] += pu[0]
            pushed[1] += pu[1]
        print(f"total: {totals['moved']} of {totals['still']} still joint loads moved at rest with self-collision on; "
              f"pushed through range and back {pushed[0]}/{pushed[1]}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    share = pushed[0] / pushed[1] if pushed[1] else 1.0
    if min_pushed is not None and push_failures and share >= min_pushed:
        print(f"{len(push_failures)} joints could not be pushed through their range; {share:.3f} came through, "
              f"at least {min_pushed} required", flush=True)
    else:
        failures.extend(push_failures)
    if failures:
        print(f"{len(failures)} self-collision failures", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
