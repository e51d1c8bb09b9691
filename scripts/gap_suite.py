#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by physics engines we do not own, for `partscene gap`.

    gap_suite.py --out DIR [--seed N] [--only PATTERN]            objects (issue 10)
    gap_suite.py --arms --out DIR [--seed N] [--only PATTERN]     arms by MuJoCo (issue 16)
    gap_suite.py --stuck-arms --out DIR [--seed N]                 arms by MuJoCo that stick (STUCK_ARM_CASES)
                 [--arm-source auto|menagerie|builtin] [--arm-duration S]

PATTERN is an fnmatch pattern on the case name ('mj_door*'). Needs the pinned packages of
gap_suite_requirements.txt beside this file (mujoco, pybullet, numpy, mujoco-menagerie).

Every case is a folder DIR/<case>/ with
  model.urdf     what the analyser is given: rigid bodies with <inertial>, joints, the limits the
                 model knows, <dynamics damping> only where the engine's own model has it. No
                 concealed effect.
  recording.csv  shared/spec/gap-recording.md format v1: optional `# key: value` lines, then
                 `time,<joint>.q,...,<joint>.effort` (or link poses `<link>.pos.x` .. `.quat.z`).
                 An effort is decided at a sample instant and held by the engine until the next one
                 (the spec's zero-order hold); it is recorded with sensor noise (and, for
                 effort_offset, minus the offset).
  truth.json     what the engine had that model.urdf lacks:
      {"format": "partscene-gap-truth/1", "engine": "mujoco 4.0.0", "case": ..., "description": ...,
       "effects": [{"joint": ..., "kind": ..., "params": {...}, "engine_detail": ...}],
       "joints": [movable joints of model.urdf], "engine_detail": how the engine was set up,
       "seed", "duration_s", "rate_hz", "timestep_s", "sampling", "observed", "excitation",
       "noise", "dropouts", and how visible the effects are: "visibility_effort_share"
       {"<joint>.<kind>": RMS of the effect's effort along the engine's motion / RMS of the effort
       model.urdf's inverse dynamics needs for that motion} and, for objects, "visibility_rmse"
       {joint: RMSE between the engine's motion and the same engine without the concealed effects
       replaying the recorded efforts from the same state}}
     `effects` empty = nothing is missing. Kinds and params are the spec's, in SI units.

Objects (two engines, our own rigid bodies built equal in both; checked against model.urdf as
MuJoCo reads it: mass matrix and bias forces to 1e-9 at random states):
  mj_* MuJoCo (mujoco.MjSpec built from the same description as model.urdf): damping, frictionloss,
       stiffness+springref, armature, heavier body, joint range the URDF lacks, tilted joint axis,
       effort offset, their common pairs, stick-slip, small-but-real effects, nothing-missing cases
       (pushes, link pose tracking, soft bouncing limits, a jittered cabinet with dropouts).
  bt_* Bullet (pybullet.loadURDF of an engine-side URDF): jointDamping (checked at start to act as
       -b*qd), a velocity motor with target 0 as Coulomb friction, heavier link, limit, tilted axis,
       effort offset, pairs, stick-slip, nothing-missing cases. Link damping is zeroed, default
       motors are off, URDF inertia is used.
Excitations: pushes (a hand pulling toward random targets, re-decided every 0.1 s and held, with
releases in between and at the end), multisines (with a centring PD and the modelled weight),
shaking (stick-slip), or a release from an angle with no effort column. Each case draws from its
own generator, default_rng([seed, crc32(name)]): --only gives the same files as the whole suite.

Arms (--arms): Menagerie arms (Franka Panda without hand, UR5e) compiled by MuJoCo, actuators,
keyframes, contacts and gravity compensation removed; where Menagerie cannot be had (its package
downloads the models), built-in MJCF arms with the same joint names (Panda-like, UR5e-like) stand
in, and truth.json says which was used. model.urdf is written from the compiled tree and verified
(mj_fullM and qfrc_bias of model.urdf loaded back into MuJoCo against the original, without its
armature, at 5 random states, to 1e-9 relative; a failure stops the run). The arm is driven by
joint torques (computed torque with model.urdf around a slow moving target inside the range, plus
sums of sines, decided at 200 Hz and held), 10 s at 1 ms steps, q noise 1e-4 rad, effort noise 1 %
of each joint's RMS; frictionloss/damping/armature are added on chosen joints. The model's own
damping goes into the URDF's <dynamics>; its own armature and frictionloss (which the URDF does not
carry) are listed in the truth, merged with what was added. Two arm cases are recorded as a real arm
is analysed, against a published identified model: their model.urdf (written after the check above)
has every link's mass, centre of mass and inertia drawn up to 5 % off the engine's, and torque-sensor
biases (effort_offset) are added to the recorded efforts; the controller knows only model.urdf.
A third such case has on every joint the smooth, direction-dependent friction identified on a real
Panda (Gaz et al., RA-L 2019: a logistic law of the speed, applied at every engine step) instead of
the engine's ideal friction loss; its truth is that law in the spec's terms (friction,
transition_speed, friction_reverse). One arm stands on a base tilted by a degree (the engine's
option gravity leaning, model.urdf level): its truth is a gravity_tilt on the base joint, tilt_deg
and the equilibrium_position at which the base joint's child frame x axis points where gravity
leans (lean_equilibrium).
"""

import argparse
import copy
import fnmatch
import json
import math
import os
import re
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zlib
from dataclasses import dataclass, field, replace
from importlib import metadata

import mujoco
import mujoco_menagerie
import numpy as np
import pybullet

DT = 0.001  # engine step, s
GRAVITY = (0.0, 0.0, -9.81)
RIGID_RTOL = 1e-9
TRUTH_FORMAT = "partscene-gap-truth/1"
ENGINES = {
    "mujoco": f"mujoco {mujoco.__version__}",
    "bullet": f"pybullet {metadata.version('pybullet')}",
}
SPEC_PARAMS = {  # kind -> (required params, optional params), shared/spec/gap-recording.md
    "viscous_damping": ({"damping"}, set()),
    "coulomb_friction": ({"friction"}, {"transition_speed", "friction_reverse"}),
    "stribeck_friction": ({"friction", "breakaway", "stribeck_speed"}, set()),
    "effort_offset": ({"offset"}, set()),
    "armature": ({"armature"}, set()),
    "spring": ({"stiffness", "rest_position"}, set()),
    "gravity_tilt": ({"tilt_deg", "equilibrium_position"}, set()),
    "end_stop": ({"position"}, {"restitution"}),
    "mass_scale": ({"scale"}, set()),
    "soft_close": ({"damping", "engage_position"}, set()),
}


class SuiteError(RuntimeError):
    """A check failed: the suite would not mean what truth.json says."""


# ---------------------------------------------------------------- rigid-body descriptions


@dataclass
class Link:
    """A rigid body: mass, centre of mass and inertia about it (3x3), in the link's frame."""

    name: str
    mass: float
    com: tuple
    inertia: np.ndarray


@dataclass
class Joint:
    """A URDF joint; the child link's frame is the joint frame (origin xyz/rpy in the parent's)."""

    name: str
    kind: str  # revolute | continuous | prismatic | fixed
    parent: str
    child: str
    xyz: tuple = (0.0, 0.0, 0.0)
    rpy: tuple = (0.0, 0.0, 0.0)
    axis: tuple = (0.0, 0.0, 1.0)
    lower: float | None = None
    upper: float | None = None
    damping: float = 0.0  # URDF <dynamics damping>: the model knows it


@dataclass
class Mechanism:
    """Links and joints of a tree whose root link is fixed to the world at the identity."""

    name: str
    links: list
    joints: list

    def link(self, name):
        return next(link for link in self.links if link.name == name)

    def joint(self, name):
        return next(joint for joint in self.joints if joint.name == name)

    def movable(self):
        return [joint.name for joint in self.joints if joint.kind != "fixed"]

    def root(self):
        children = {joint.child for joint in self.joints}
        return next(link.name for link in self.links if link.name not in children)


def box_inertia(mass, sx, sy, sz):
    """Inertia of a solid box about its centre."""
    return np.diag([sy * sy + sz * sz, sx * sx + sz * sz, sx * sx + sy * sy]) * mass / 12.0


def cylinder_inertia(mass, radius, height):
    """Inertia of a solid cylinder (axis z) about its centre."""
    side = mass * (3 * radius * radius + height * height) / 12.0
    return np.diag([side, side, mass * radius * radius / 2.0])


def combine(parts):
    """Mass, centre and inertia about it of rigid parts [(mass, centre, inertia about own centre)]."""
    mass = sum(m for m, _, _ in parts)
    com = sum(m * np.asarray(c, float) for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, i in parts:
        d = np.asarray(c, float) - com
        inertia += i + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, tuple(com), inertia


def base_link(name="base"):
    return Link(name, 1.0, (0.0, 0.0, 0.0), box_inertia(1.0, 0.1, 0.1, 0.1))


def door(width, height, mass, open_limit=2.0, joint="hinge", thickness=0.02):
    """A door on a vertical hinge at the origin, opening with +q; no gravity torque."""
    panel = Link("door_panel", mass, (width / 2, 0.0, height / 2), box_inertia(mass, width, thickness, height))
    hinge = Joint(joint, "revolute", "base", panel.name, axis=(0, 0, 1), lower=0.0, upper=open_limit)
    return Mechanism("door", [base_link(), panel], [hinge])


def drawer(depth, width, height, mass, travel, joint="slide"):
    """A drawer sliding out along +x."""
    box = Link("drawer_box", mass, (-depth / 2, 0.0, 0.0), box_inertia(mass, depth, width, height))
    slide = Joint(joint, "prismatic", "base", box.name, axis=(1, 0, 0), lower=0.0, upper=travel)
    return Mechanism("drawer", [base_link(), box], [slide])


def sash(width, height, mass, travel, joint="sash"):
    """A window sash sliding up along +z: gravity loads it."""
    panel = Link("sash_panel", mass, (0.0, 0.0, height / 2), box_inertia(mass, width, 0.03, height))
    slide = Joint(joint, "prismatic", "base", panel.name, axis=(0, 0, 1), lower=0.0, upper=travel)
    return Mechanism("sash", [base_link(), panel], [slide])


def pendulum(length, mass, radius, joint="pivot"):
    """A bob on a light rod, axis +y, q = 0 hanging down, no stops."""
    bob = Link("pendulum_bob", mass, (0.0, 0.0, -length), np.eye(3) * 0.4 * mass * radius * radius)
    pivot = Joint(joint, "continuous", "base", bob.name, axis=(0, 1, 0))
    return Mechanism("pendulum", [base_link(), bob], [pivot])


def lid(depth, width, mass, open_limit=1.9, joint="lid_hinge"):
    """A lid closed at q = 0 (lying flat on its lower stop), opening upward with +q."""
    panel = Link("lid_panel", mass, (depth / 2, 0.0, 0.01), box_inertia(mass, depth, width, 0.02))
    hinge = Joint(joint, "revolute", "base", panel.name, axis=(0, -1, 0), lower=0.0, upper=open_limit)
    return Mechanism("lid", [base_link(), panel], [hinge])


def knob(radius, mass, limit=None, joint="knob"):
    """A rotary knob on a vertical axis; `limit` gives symmetric stops (a volume knob)."""
    cap = Link("knob_cap", mass, (0.0, 0.0, 0.01), cylinder_inertia(mass, radius, 0.02))
    kind, lo, hi = ("continuous", None, None) if limit is None else ("revolute", -limit, limit)
    return Mechanism("knob", [base_link(), cap], [Joint(joint, kind, "base", cap.name, lower=lo, upper=hi)])


def turntable(radius, mass, load, offset, joint="spin"):
    """A lazy susan with an off-centre load, vertical axis, no stops."""
    m, com, inertia = combine([
        (mass, (0.0, 0.0, 0.01), cylinder_inertia(mass, radius, 0.02)),
        (load, (offset, 0.0, 0.07), box_inertia(load, 0.1, 0.1, 0.1)),
    ])
    top = Link("table_top", m, com, inertia)
    return Mechanism("turntable", [base_link(), top], [Joint(joint, "continuous", "base", top.name)])


def cabinet():
    """A cabinet facing +x: two doors that swing out with +q and a drawer above them."""
    links, joints = [base_link("carcass")], []
    for side, y, axis in (("left", -0.4, (0, 0, -1)), ("right", 0.4, (0, 0, 1))):
        panel = Link(f"door_{side}_panel", 2.0, (0.0, -0.5 * y, 0.35), box_inertia(2.0, 0.02, 0.4, 0.7))
        links.append(panel)
        joints.append(Joint(f"door_{side}", "revolute", "carcass", panel.name, xyz=(0.0, y, 0.1), axis=axis,
                            lower=0.0, upper=1.9))
    box = Link("drawer_box", 3.0, (-0.2, 0.0, 0.0), box_inertia(3.0, 0.4, 0.6, 0.15))
    links.append(box)
    joints.append(Joint("drawer", "prismatic", "carcass", box.name, xyz=(0.0, 0.0, 0.9), axis=(1, 0, 0), lower=0.0, upper=0.35))
    return Mechanism("cabinet", links, joints)


def double_pendulum(l1, m1, l2, m2):
    """Two rods on parallel axes +y, q = 0 hanging down, no stops."""
    upper = Link("upper_rod", m1, (0.0, 0.0, -l1 / 2), box_inertia(m1, 0.03, 0.03, l1))
    lower = Link("lower_rod", m2, (0.0, 0.0, -l2 / 2), box_inertia(m2, 0.03, 0.03, l2))
    return Mechanism("double_pendulum", [base_link(), upper, lower], [
        Joint("shoulder", "continuous", "base", upper.name, axis=(0, 1, 0)),
        Joint("elbow", "continuous", upper.name, lower.name, xyz=(0.0, 0.0, -l1), axis=(0, 1, 0)),
    ])


def cabinet_door():
    """A cabinet door: I = 0.135 kg m^2 about its hinge."""
    return door(0.45, 0.7, 2.0)


def wardrobe_door():
    """A heavy wardrobe door: I = 0.96 kg m^2 about its hinge."""
    return door(0.6, 1.9, 8.0)


def chest_lid():
    """A chest lid: I = 0.08 kg m^2 about its hinge, 2.9 N m of weight."""
    return lid(0.4, 0.5, 1.5)


# ---------------------------------------------------------------- URDF


def num(x):
    """Full precision, so that a model read back is the same to ~1e-16."""
    return repr(float(x))


def vec(v):
    return " ".join(num(x) for x in v)


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def urdf_text(mech, comment=""):
    """The mechanism as URDF (links with <inertial> only, no geometry)."""
    out = ['<?xml version="1.0"?>']
    if comment:
        out.append(f"<!-- {comment.replace('--', '-')} -->")  # '--' may not appear in an XML comment
    out.append(f'<robot name="{mech.name}">')
    for link in mech.links:
        i = link.inertia
        out += [
            f'  <link name="{link.name}">',
            "    <inertial>",
            f'      <origin xyz="{vec(link.com)}" rpy="0 0 0"/>',
            f'      <mass value="{num(link.mass)}"/>',
            f'      <inertia ixx="{num(i[0, 0])}" ixy="{num(i[0, 1])}" ixz="{num(i[0, 2])}" '
            f'iyy="{num(i[1, 1])}" iyz="{num(i[1, 2])}" izz="{num(i[2, 2])}"/>',
            "    </inertial>",
            "  </link>",
        ]
    for joint in mech.joints:
        out += [
            f'  <joint name="{joint.name}" type="{joint.kind}">',
            f'    <parent link="{joint.parent}"/>',
            f'    <child link="{joint.child}"/>',
            f'    <origin xyz="{vec(joint.xyz)}" rpy="{vec(joint.rpy)}"/>',
        ]
        if joint.kind != "fixed":
            out.append(f'    <axis xyz="{vec(unit(joint.axis))}"/>')
        if joint.kind in ("revolute", "prismatic"):
            out.append(f'    <limit lower="{num(joint.lower)}" upper="{num(joint.upper)}" effort="1000" velocity="100"/>')
        if joint.damping:
            out.append(f'    <dynamics damping="{num(joint.damping)}" friction="0"/>')
        out.append("  </joint>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


def rpy_from_quat(quat):
    """URDF roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) of a MuJoCo quaternion (w x y z)."""
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, np.asarray(quat, float))
    r = r.reshape(3, 3)
    pitch = math.atan2(-r[2, 0], math.hypot(r[0, 0], r[1, 0]))
    if math.hypot(r[0, 0], r[1, 0]) < 1e-12:  # pitch = +-90 deg: only yaw - roll is defined
        return (0.0, pitch, math.atan2(-r[0, 1], r[1, 1]))
    return (math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0]))


def quat_from_rpy(rpy):
    """MuJoCo quaternion (w x y z) of URDF roll-pitch-yaw."""
    out = np.array([1.0, 0.0, 0.0, 0.0])
    for angle, axis in zip(reversed(rpy), ((0, 0, 1), (0, 1, 0), (1, 0, 0))):
        q = np.zeros(4)
        mujoco.mju_axisAngle2Quat(q, np.asarray(axis, float), float(angle))
        mujoco.mju_mulQuat(out, out.copy(), q)
    return out


# ---------------------------------------------------------------- concealed effects


@dataclass
class Effect:
    """One concealed effect on one joint: spec kind and params, plus engine-only settings
    (`toward`: the q that a tilted axis pulls toward; `side`: which bound an end stop replaces)."""

    joint: str
    kind: str
    params: dict
    setting: dict = field(default_factory=dict)
    detail: str = ""


def fx(joint, kind, **params):
    setting = {k: params.pop(k) for k in ("toward", "side") if k in params}
    return Effect(joint, kind, params, setting)


def rotate(axis, angle, v):
    """Rodrigues: v rotated by `angle` about the unit `axis`."""
    a, v = unit(axis), np.asarray(v, float)
    return v * math.cos(angle) + np.cross(a, v) * math.sin(angle) + a * (a @ v) * (1 - math.cos(angle))


def engine_mechanism(mech, effects):
    """The engine's rigid bodies: heavier links, extra stops and tilted axes applied."""
    out = copy.deepcopy(mech)
    for effect in effects:
        joint = out.joint(effect.joint)
        child = out.link(joint.child)
        if effect.kind == "mass_scale":
            if any(j.parent == child.name for j in out.joints):
                raise SuiteError(f"mass_scale on {joint.name}: its child link must be a leaf")
            child.mass *= effect.params["scale"]
            child.inertia = child.inertia * effect.params["scale"]
        elif effect.kind == "end_stop":
            if joint.kind not in ("revolute", "prismatic"):
                raise SuiteError(f"end_stop on {joint.name}: it replaces one bound of a limited joint")
            setattr(joint, effect.setting["side"], effect.params["position"])
        elif effect.kind == "gravity_tilt":
            a = unit(joint.axis)
            c = np.asarray(child.com, float)
            c_perp = c - a * (a @ c)
            toward = unit(rotate(a, effect.setting["toward"], c_perp))
            tilt = math.radians(effect.params["tilt_deg"])
            joint.axis = tuple(math.cos(tilt) * a + math.sin(tilt) * toward)
            effect.params["equilibrium_position"] = round(tilt_equilibrium(out, joint), 6)
    return out


def tilt_equilibrium(mech, joint):
    """Where gravity pulls a revolute joint whose (tilted) axis is not vertical: the child's COM
    height about the joint is c + A cos q + B sin q, lowest at q = atan2(B, A) + pi."""
    if any(any(j.rpy) for j in mech.joints) or any(j.parent == joint.child for j in mech.joints):
        raise SuiteError("gravity_tilt is set up for a leaf link under unrotated frames")
    a, c = unit(joint.axis), np.asarray(mech.link(joint.child).com, float)
    big_a = c[2] - a[2] * (a @ c)
    big_b = np.cross(a, c)[2]
    return math.remainder(math.atan2(big_b, big_a) + math.pi, 2 * math.pi)


def joint_params(effects, joint):
    """Engine joint parameters of the concealed effects on one joint."""
    out = {"damping": 0.0, "friction": 0.0, "stiffness": 0.0, "springref": 0.0, "armature": 0.0}
    for effect in effects:
        if effect.joint != joint:
            continue
        p = effect.params
        if effect.kind == "viscous_damping":
            out["damping"] += p["damping"]
        elif effect.kind == "coulomb_friction":
            out["friction"] += p["friction"]
        elif effect.kind == "spring":
            out["stiffness"], out["springref"] = p["stiffness"], p["rest_position"]
        elif effect.kind == "armature":
            out["armature"] += p["armature"]
    return out


# ---------------------------------------------------------------- engines


class MujocoSim:
    """A compiled MuJoCo model driven through qfrc_applied (held between samples)."""

    def __init__(self, model, names):
        self.model, self.data = model, mujoco.MjData(model)
        ids = [model.joint(name).id for name in names]
        self.names = list(names)
        self.qadr, self.dadr = model.jnt_qposadr[ids], model.jnt_dofadr[ids]

    def set_state(self, q, qd):
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self.qadr], self.data.qvel[self.dadr] = q, qd
        mujoco.mj_forward(self.model, self.data)

    def state(self):
        return self.data.qpos[self.qadr].copy(), self.data.qvel[self.dadr].copy()

    def hold(self, effort):
        self.data.qfrc_applied[self.dadr] = effort

    def advance(self, steps):
        if steps:
            mujoco.mj_step(self.model, self.data, nstep=steps)

    def pose(self, link):
        mujoco.mj_kinematics(self.model, self.data)
        body = self.model.body(link).id
        return np.concatenate([self.data.xpos[body], self.data.xquat[body]])

    def dynamics(self, q, qd):
        """Joint-space inertia (with armature) and bias force C(q, qd) qd + g(q)."""
        self.set_state(q, qd)
        full = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, self.data, full)
        return full[np.ix_(self.dadr, self.dadr)], self.data.qfrc_bias[self.dadr].copy()

    def gravity(self, q):
        return self.dynamics(q, np.zeros(len(q)))[1]

    def close(self):
        pass


def mujoco_model(mech, effects, gravity=True, solref_limit=None):
    """Our own MuJoCo model of the mechanism (MjSpec), with the joint-level effects set natively."""
    spec = mujoco.MjSpec()
    spec.modelname = mech.name
    spec.compiler.degree = False
    spec.option.timestep = DT
    spec.option.gravity = GRAVITY if gravity else (0.0, 0.0, 0.0)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    bodies = {mech.root(): spec.worldbody.add_body(name=mech.root())}
    set_inertial(bodies[mech.root()], mech.link(mech.root()))
    kinds = {"revolute": mujoco.mjtJoint.mjJNT_HINGE, "continuous": mujoco.mjtJoint.mjJNT_HINGE,
             "prismatic": mujoco.mjtJoint.mjJNT_SLIDE}
    for joint in tree_order(mech):
        body = bodies[joint.parent].add_body(name=joint.child, pos=list(joint.xyz), quat=list(quat_from_rpy(joint.rpy)))
        bodies[joint.child] = body
        set_inertial(body, mech.link(joint.child))
        if joint.kind == "fixed":
            continue
        p = joint_params(effects, joint.name)
        jnt = body.add_joint(name=joint.name, type=kinds[joint.kind], axis=list(unit(joint.axis)))
        jnt.damping = [joint.damping + p["damping"], 0.0, 0.0]
        jnt.frictionloss, jnt.armature = p["friction"], p["armature"]
        jnt.stiffness, jnt.springref = [p["stiffness"], 0.0, 0.0], p["springref"]
        limited = joint.kind in ("revolute", "prismatic")
        jnt.limited = mujoco.mjtLimited.mjLIMITED_TRUE if limited else mujoco.mjtLimited.mjLIMITED_FALSE
        if limited:
            jnt.range = [joint.lower, joint.upper]
        if solref_limit is not None:
            jnt.solref_limit = list(solref_limit)
    return spec.compile()


def tree_order(mech):
    """Joints, parents before children."""
    order, frontier = [], [mech.root()]
    while frontier:
        link = frontier.pop(0)
        for joint in mech.joints:
            if joint.parent == link:
                order.append(joint)
                frontier.append(joint.child)
    return order


def set_inertial(body, link):
    i = link.inertia
    body.mass = link.mass
    body.ipos = list(link.com)
    body.fullinertia = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]


class BulletSim:
    """pybullet (DIRECT) with an engine-side URDF; efforts through TORQUE_CONTROL every step."""

    def __init__(self, mech, effects, gravity=True):
        self.cid = pybullet.connect(pybullet.DIRECT)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "engine.urdf")
            with open(path, "w", encoding="utf-8") as f:
                f.write(urdf_text(mech))
            self.body = pybullet.loadURDF(path, useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
                                          physicsClientId=self.cid)
        pybullet.setTimeStep(DT, physicsClientId=self.cid)
        pybullet.setGravity(*(GRAVITY if gravity else (0, 0, 0)), physicsClientId=self.cid)
        infos = [pybullet.getJointInfo(self.body, i, physicsClientId=self.cid) for i in range(len(mech.joints))]
        index = {info[1].decode(): info[0] for info in infos}
        self.link_index = {info[12].decode(): info[0] for info in infos}
        self.names = mech.movable()
        self.idx = [index[name] for name in self.names]
        self.dof = [sorted(self.idx).index(i) for i in self.idx]  # Bullet's dof of each of our joints
        for link in [-1] + list(range(len(infos))):  # Bullet damps every link by default
            pybullet.changeDynamics(self.body, link, linearDamping=0.0, angularDamping=0.0, physicsClientId=self.cid)
        pybullet.changeDynamics(self.body, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
                                physicsClientId=self.cid)
        self._set_joint_effects(effects)
        self.effort = np.zeros(len(self.idx))

    def _set_joint_effects(self, effects):
        """Velocity motors (target 0) as Coulomb friction, force 0 (off) elsewhere; jointDamping."""
        params = [joint_params(effects, name) for name in self.names]
        for effect in effects:
            if effect.kind in ("spring", "armature"):
                raise SuiteError(f"Bullet has no native {effect.kind}")
        pybullet.setJointMotorControlArray(self.body, self.idx, pybullet.VELOCITY_CONTROL,
                                           targetVelocities=[0.0] * len(self.idx),
                                           forces=[p["friction"] for p in params], physicsClientId=self.cid)
        for i, p in zip(self.idx, params):
            pybullet.changeDynamics(self.body, i, jointDamping=p["damping"], physicsClientId=self.cid)

    def set_state(self, q, qd):
        for i, qi, vi in zip(self.idx, q, qd):
            pybullet.resetJointState(self.body, i, float(qi), float(vi), physicsClientId=self.cid)

    def state(self):
        states = pybullet.getJointStates(self.body, self.idx, physicsClientId=self.cid)
        return np.array([s[0] for s in states]), np.array([s[1] for s in states])

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()

    def advance(self, steps):
        forces = list(self.effort)
        for _ in range(steps):
            if any(forces):  # TORQUE_CONTROL is cleared after every step
                pybullet.setJointMotorControlArray(self.body, self.idx, pybullet.TORQUE_CONTROL, forces=forces,
                                                   physicsClientId=self.cid)
            pybullet.stepSimulation(physicsClientId=self.cid)

    def pose(self, link):
        s = pybullet.getLinkState(self.body, self.link_index[link], computeForwardKinematics=True,
                                  physicsClientId=self.cid)
        x, y, z, w = s[5]
        return np.array([*s[4], w, x, y, z])

    def dynamics(self, q, qd):
        qb, qdb = np.zeros(len(q)), np.zeros(len(q))
        qb[self.dof], qdb[self.dof] = q, qd
        full = np.array(pybullet.calculateMassMatrix(self.body, list(qb), physicsClientId=self.cid))
        bias = np.array(pybullet.calculateInverseDynamics(self.body, list(qb), list(qdb), [0.0] * len(q),
                                                          physicsClientId=self.cid))
        return full[np.ix_(self.dof, self.dof)], bias[self.dof]

    def close(self):
        pybullet.disconnect(self.cid)


def check_joint_damping(sim_class, what, rtol=0.01):
    """An engine's viscous damping (`what`, made by `sim_class`) must act as -b*qd: a constant effort u on a free
    door of inertia I reaches u/b (1 - exp(-b t / I)) after t = 1 s. Fails loudly if the engine does otherwise."""
    mech = door(0.5, 0.5, 1.2, open_limit=100.0)
    inertia = mech.link("door_panel").inertia[2, 2] + 1.2 * 0.25 ** 2
    sim = sim_class(mech, [fx("hinge", "viscous_damping", damping=0.5)])
    sim.set_state([0.0], [0.0])
    sim.hold([1.0])
    sim.advance(1000)
    expected = 1.0 / 0.5 * (1 - math.exp(-0.5 / inertia * 1.0))
    got = sim.state()[1][0]
    sim.close()
    if abs(got - expected) > rtol * expected:
        raise SuiteError(f"{what} does not act as -b*qd: {got} rad/s after 1 s, expected {expected}")


def check_bullet_joint_damping():
    """Bullet's changeDynamics(jointDamping=b) must act as -b*qd (check_joint_damping)."""
    check_joint_damping(BulletSim, "Bullet jointDamping")


# ---------------------------------------------------------------- cases and excitation


@dataclass
class Excite:
    """How efforts are decided at sample instants (then held): `kind` pushes | multisine | shake on
    `joints`, bounded by `amp` (N m or N each); `centre` (multisine), `span` (push targets (lo, hi)
    per joint; default the inner 80 % of the limits), `freq` (shake, Hz)."""

    kind: str
    joints: tuple
    amp: tuple
    centre: tuple = None
    span: tuple = None
    freq: float = 0.5


@dataclass
class Case:
    """One recording. `excite` None: released from `q0`, no effort column. `noise`: sigma on q in
    rad and m (pose tracking: rotation rad, position m); `effort_noise`: sigma as a share of the
    effort's RMS; `solref_limit`: MuJoCo limit softness; `impact_speed`: where an end stop's
    restitution is measured (rad/s or m/s)."""

    name: str
    engine: str
    mech: Mechanism
    description: str
    effects: list = field(default_factory=list)
    excite: Excite = None
    q0: dict = field(default_factory=dict)
    duration: float = 8.0
    rate: int = 200
    observe: str = "q"
    noise: tuple = (7e-4, 3e-4)
    effort_noise: float = 0.0
    jitter: bool = False
    dropouts: float = 0.0
    model_line: bool = True
    solref_limit: tuple = None
    impact_speed: float = 0.5


def push(joints, amp, span=None):
    return Excite("pushes", tuple(joints), tuple(amp), span=span)


def sines(joints, amp, centre):
    return Excite("multisine", tuple(joints), tuple(amp), centre=tuple(centre))


def mujoco_cases():
    return [
        Case("mj_door_damping", "mujoco", cabinet_door(),
             "cabinet door pushed and released; the hinge is viscously damped",
             [fx("hinge", "viscous_damping", damping=0.25)], push(["hinge"], [1.5]), {"hinge": 0.3}),
        Case("mj_door_friction", "mujoco", wardrobe_door(),
             "heavy wardrobe door pushed and released; dry hinge friction",
             [fx("hinge", "coulomb_friction", friction=1.0)], push(["hinge"], [5.0]), {"hinge": 0.4}, effort_noise=0.01),
        Case("mj_flap_spring", "mujoco", door(0.25, 0.3, 0.4), "light flap on a vertical hinge with a return spring, pushed",
             [fx("hinge", "spring", stiffness=0.15, rest_position=1.0)], push(["hinge"], [0.2]), {"hinge": 0.1},
             duration=6.0, rate=250),
        Case("mj_knob_armature", "mujoco", knob(0.04, 0.12), "geared knob (rotor inertia) driven by a multisine",
             [fx("knob", "armature", armature=1.5e-4)], sines(["knob"], [2e-3], [0.0]), duration=6.0, rate=500,
             noise=(1e-3, 3e-4)),
        Case("mj_lid_mass_scale", "mujoco", chest_lid(),
             "chest lid held open by a multisine effort; the lid is heavier than modelled",
             [fx("lid_hinge", "mass_scale", scale=1.35)], sines(["lid_hinge"], [0.8], [0.9]), {"lid_hinge": 0.9},
             effort_noise=0.01),
        Case("mj_drawer_end_stop", "mujoco", drawer(0.45, 0.5, 0.15, 4.0, 0.45),
             "drawer pushed open and shut; a stop inside stops it short of the modelled travel",
             [fx("slide", "end_stop", position=0.3, side="upper")], push(["slide"], [12.0], span=[(0.05, 0.42)]),
             {"slide": 0.05}, rate=250, impact_speed=0.3),
        Case("mj_door_gravity_tilt", "mujoco", door(0.5, 0.8, 3.0), "door on a hinge out of plumb, released: swings to rest",
             [fx("hinge", "gravity_tilt", tilt_deg=3.0, toward=1.0)], None, {"hinge": 0.15}, duration=10.0, rate=100),
        Case("mj_drawer_effort_offset", "mujoco", drawer(0.4, 0.45, 0.12, 2.5, 0.4),
             "drawer pushed and released; the force sensor reads low by a constant",
             [fx("slide", "effort_offset", offset=2.0)], push(["slide"], [12.0]), {"slide": 0.1}, effort_noise=0.01),
        Case("mj_door_friction_damping", "mujoco", cabinet_door(),
             "cabinet door, pushed: dry friction and viscous damping",
             [fx("hinge", "coulomb_friction", friction=0.2), fx("hinge", "viscous_damping", damping=0.15)],
             push(["hinge"], [1.5]), {"hinge": 0.3}),
        Case("mj_lid_spring_damping", "mujoco", lid(0.35, 0.45, 1.2), "counterbalanced lid (spring) with a damper, pushed",
             [fx("lid_hinge", "spring", stiffness=1.2, rest_position=1.6), fx("lid_hinge", "viscous_damping", damping=0.15)],
             push(["lid_hinge"], [1.5]), {"lid_hinge": 0.8}),
        Case("mj_lid_mass_friction", "mujoco", chest_lid(),
             "lid pushed open and let fall: heavier than modelled, dry hinge",
             [fx("lid_hinge", "mass_scale", scale=1.3), fx("lid_hinge", "coulomb_friction", friction=0.6)],
             push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6}),
        Case("mj_cabinet_drawer_damping", "mujoco", cabinet(),
             "cabinet with two doors and a drawer, all pushed; only the drawer is damped",
             [fx("drawer", "viscous_damping", damping=6.0)], push(["door_left", "door_right", "drawer"], [1.5, 1.5, 10.0]),
             {"door_left": 0.2, "door_right": 0.4, "drawer": 0.05}, duration=10.0),
        Case("mj_double_pendulum_elbow_friction", "mujoco", double_pendulum(0.3, 0.6, 0.25, 0.4),
             "double pendulum released from an angle; dry friction at the elbow only",
             [fx("elbow", "coulomb_friction", friction=0.05)], None, {"shoulder": 1.2, "elbow": -0.8}, rate=250),
        Case("mj_knob_stick_slip", "mujoco", knob(0.04, 0.12, limit=2.35),
             "volume knob shaken back and forth against its stops: stick-slip",
             [fx("knob", "coulomb_friction", friction=4e-3)], Excite("shake", ("knob",), (7e-3,), freq=0.5),
             rate=500, noise=(1e-3, 3e-4)),
        Case("mj_drawer_small_damping", "mujoco", drawer(0.45, 0.5, 0.15, 4.0, 0.45),
             "drawer pushed and released; SMALL but real viscous damping (time constant 5 s), at the edge",
             [fx("slide", "viscous_damping", damping=0.8)], push(["slide"], [10.0]), {"slide": 0.1}, duration=10.0),
        Case("mj_pendulum_armature", "mujoco", pendulum(0.35, 0.8, 0.04),
             "geared pendulum pushed and released: rotor inertia (inertia without weight)",
             [fx("pivot", "armature", armature=0.02)], push(["pivot"], [1.5]), {"pivot": 0.5}, duration=10.0),
        Case("mj_door_small_tilt", "mujoco", cabinet_door(),
             "door pushed and released; hinge SMALL tilt (0.6 deg), at the edge",
             [fx("hinge", "gravity_tilt", tilt_deg=0.6, toward=0.8)], push(["hinge"], [1.0]), {"hinge": 0.3}, duration=10.0),
        Case("mj_pendulum_damping", "mujoco", pendulum(0.12, 0.15, 0.02),
             "small pendulum released from 1.4 rad; damped pivot, no noise",
             [fx("pivot", "viscous_damping", damping=1e-3)], None, {"pivot": 1.4}, rate=500, noise=(0.0, 0.0)),
    ]


def nothing_missing_cases():
    return [
        Case("mj_none_door_pushes", "mujoco", door(0.45, 0.7, 2.0),
             "NOTHING missing: cabinet door pushed (at times into its stops) and released",
             [], push(["hinge"], [2.0], span=[(0.1, 2.2)]), {"hinge": 0.3}, effort_noise=0.01),
        Case("mj_none_double_pendulum_pose", "mujoco", double_pendulum(0.3, 0.6, 0.25, 0.4),
             "NOTHING missing: double pendulum released, tracked by its links' poses", [], None, {"shoulder": 0.7, "elbow": 0.3},
             observe="pose"),
        Case("mj_none_lid_soft_stops", "mujoco", lid(0.4, 0.5, 1.5), "NOTHING missing: lid pushed past both stops and dropped; "
             "MuJoCo's soft limits (solref 0.02 0.15) bounce", [], push(["lid_hinge"], [5.0], span=[(-0.5, 2.4)]),
             {"lid_hinge": 1.0}, solref_limit=(0.02, 0.15)),
        Case("mj_none_cabinet_irregular", "mujoco", cabinet(), "NOTHING missing: cabinet doors and drawer pushed; jittered sample "
             "times, dropouts", [], push(["door_left", "door_right", "drawer"], [1.5, 1.5, 10.0]),
             {"door_left": 0.3, "door_right": 0.2, "drawer": 0.1}, duration=10.0, jitter=True, dropouts=0.03),
        Case("bt_none_drawer_pushes", "bullet", drawer(0.45, 0.5, 0.15, 4.0, 0.45), "NOTHING missing: drawer pushed and released "
             "(no `# model:` line)", [], push(["slide"], [12.0]), {"slide": 0.1}, rate=250, effort_noise=0.01, model_line=False),
        Case("bt_none_double_pendulum", "bullet", double_pendulum(0.3, 0.6, 0.25, 0.4), "NOTHING missing: double pendulum released",
             [], None, {"shoulder": 1.0, "elbow": 0.5}, rate=250),
        Case("bt_none_door_pose", "bullet", door(0.45, 0.7, 2.0), "NOTHING missing: door pushed, tracked by its link pose; "
             "jittered sample times, dropouts", [], push(["hinge"], [1.5]), {"hinge": 0.3}, observe="pose", jitter=True,
             dropouts=0.02, effort_noise=0.01),
    ]


def bullet_cases():
    return [
        Case("bt_door_damping", "bullet", door(0.6, 1.9, 8.0), "heavy wardrobe door pushed and released; damped hinge",
             [fx("hinge", "viscous_damping", damping=0.8)], push(["hinge"], [5.0]), {"hinge": 0.4}),
        Case("bt_drawer_friction", "bullet", drawer(0.5, 0.55, 0.2, 6.0, 0.45), "loaded drawer pushed and released; dry runners",
             [fx("slide", "coulomb_friction", friction=6.0)], push(["slide"], [30.0]), {"slide": 0.1}, rate=250),
        Case("bt_sash_mass_scale", "bullet", sash(0.8, 0.6, 5.0, 0.5), "window sash lifted by a multisine; heavier than modelled",
             [fx("sash", "mass_scale", scale=1.3)], sines(["sash"], [30.0], [0.25]), {"sash": 0.25}, effort_noise=0.01),
        Case("bt_door_end_stop", "bullet", door(0.45, 0.7, 2.0, open_limit=2.4), "door pushed open; a door stopper the model lacks",
             [fx("hinge", "end_stop", position=1.3, side="upper")], push(["hinge"], [1.5], span=[(0.2, 2.1)]), {"hinge": 0.3},
             impact_speed=1.0),
        Case("bt_turntable_gravity_tilt", "bullet", turntable(0.2, 1.5, 1.0, 0.15), "lazy susan with an off-centre load, pushed; "
             "its axis is out of plumb", [fx("spin", "gravity_tilt", tilt_deg=2.0, toward=0.5)],
             push(["spin"], [0.3], span=[(-1.0, 2.0)]),
             {"spin": -0.5}, duration=10.0, rate=100),
        Case("bt_knob_effort_offset", "bullet", knob(0.045, 0.1), "knob turned and let go; the torque sensor has a bias",
             [fx("knob", "effort_offset", offset=5e-4)], push(["knob"], [2e-3]), rate=500,
             noise=(1e-3, 3e-4)),
        Case("bt_lid_mass_friction", "bullet", lid(0.45, 0.6, 2.5),
             "big lid pushed open and let fall: heavier than modelled, dry hinge",
             [fx("lid_hinge", "mass_scale", scale=1.25), fx("lid_hinge", "coulomb_friction", friction=1.2)],
             push(["lid_hinge"], [9.0]), {"lid_hinge": 0.6}),
        Case("bt_door_friction_damping", "bullet", cabinet_door(),
             "cabinet door pushed: dry friction and viscous damping",
             [fx("hinge", "coulomb_friction", friction=0.15), fx("hinge", "viscous_damping", damping=0.2)],
             push(["hinge"], [1.5]), {"hinge": 0.3}, effort_noise=0.01),
        Case("bt_double_pendulum_shoulder_damping", "bullet", double_pendulum(0.3, 0.6, 0.25, 0.4),
             "double pendulum released; only the shoulder is damped", [fx("shoulder", "viscous_damping", damping=0.03)],
             None, {"shoulder": 1.2, "elbow": -0.6}, duration=10.0),
        Case("bt_knob_stick_slip", "bullet", knob(0.04, 0.12, limit=2.35), "volume knob shaken against its stops: stick-slip",
             [fx("knob", "coulomb_friction", friction=3e-3)], Excite("shake", ("knob",), (5e-3,), freq=0.4), rate=500,
             noise=(1e-3, 3e-4)),
        Case("bt_drawer_small_friction", "bullet", drawer(0.45, 0.5, 0.15, 4.0, 0.45),
             "drawer pushed and released; SMALL but real dry friction (0.4 N against 12 N pushes), at the edge",
             [fx("slide", "coulomb_friction", friction=0.4)], push(["slide"], [12.0]), {"slide": 0.1}, duration=10.0),
        Case("bt_cabinet_door_friction", "bullet", cabinet(), "cabinet, all pushed; only the right door's hinge has dry friction",
             [fx("door_right", "coulomb_friction", friction=0.25)], push(["door_left", "door_right", "drawer"], [1.5, 1.5, 10.0]),
             {"door_left": 0.2, "door_right": 0.4, "drawer": 0.05}, duration=10.0, jitter=True),
    ]


# The cases that several engine suites (gap_suite_physx.py, gap_suite_dart.py, gap_suite_drake.py,
# gap_suite_newton.py) record alike: key -> Case of (name, engine); engine_case names and makes them.
ENGINE_CASES = {
    "door_friction": lambda name, engine: Case(
        name, engine, wardrobe_door(), "heavy wardrobe door pushed and released; dry hinge friction",
        [fx("hinge", "coulomb_friction", friction=1.0)], push(["hinge"], [5.0]), {"hinge": 0.4},
        effort_noise=0.01),
    "drawer_friction": lambda name, engine: Case(
        name, engine, drawer(0.5, 0.55, 0.2, 6.0, 0.45), "loaded drawer pushed and released; dry runners",
        [fx("slide", "coulomb_friction", friction=6.0)], push(["slide"], [30.0]), {"slide": 0.1}, rate=250),
    "door_friction_damping": lambda name, engine: Case(
        name, engine, cabinet_door(), "cabinet door, pushed: dry friction and viscous damping",
        [fx("hinge", "coulomb_friction", friction=0.2), fx("hinge", "viscous_damping", damping=0.15)],
        push(["hinge"], [1.5]), {"hinge": 0.3}),
    "lid_mass_friction": lambda name, engine: Case(
        name, engine, chest_lid(), "lid pushed open and let fall: heavier than modelled, dry hinge",
        [fx("lid_hinge", "mass_scale", scale=1.3), fx("lid_hinge", "coulomb_friction", friction=0.6)],
        push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6}),
    "double_pendulum_elbow_friction": lambda name, engine: Case(
        name, engine, double_pendulum(0.3, 0.6, 0.25, 0.4),
        "double pendulum released from an angle; dry friction at the elbow only",
        [fx("elbow", "coulomb_friction", friction=0.05)], None, {"shoulder": 1.2, "elbow": -0.8}, rate=250),
    "door_damping": lambda name, engine: Case(
        name, engine, cabinet_door(), "cabinet door pushed and released; the hinge is viscously damped",
        [fx("hinge", "viscous_damping", damping=0.25)], push(["hinge"], [1.5]), {"hinge": 0.3}),
    "flap_spring": lambda name, engine: Case(
        name, engine, door(0.25, 0.3, 0.4), "light flap on a vertical hinge with a return spring, pushed",
        [fx("hinge", "spring", stiffness=0.15, rest_position=1.0)], push(["hinge"], [0.2]), {"hinge": 0.1},
        duration=6.0, rate=250),
    "knob_armature": lambda name, engine: Case(
        name, engine, knob(0.04, 0.12), "geared knob (rotor inertia) driven by a multisine",
        [fx("knob", "armature", armature=1.5e-4)], sines(["knob"], [2e-3], [0.0]), duration=6.0, rate=500,
        noise=(1e-3, 3e-4)),
    "pendulum_armature": lambda name, engine: Case(
        name, engine, pendulum(0.35, 0.8, 0.04),
        "geared pendulum pushed and released: rotor inertia (inertia without weight)",
        [fx("pivot", "armature", armature=0.02)], push(["pivot"], [1.5]), {"pivot": 0.5}, duration=10.0),
    "sash_mass_scale": lambda name, engine: Case(
        name, engine, sash(0.8, 0.6, 5.0, 0.5), "window sash lifted by a multisine; heavier than modelled",
        [fx("sash", "mass_scale", scale=1.3)], sines(["sash"], [30.0], [0.25]), {"sash": 0.25}, effort_noise=0.01),
    "drawer_end_stop": lambda name, engine: Case(
        name, engine, drawer(0.45, 0.5, 0.15, 4.0, 0.45),
        "drawer pushed open and shut; a stop inside stops it short of the modelled travel",
        [fx("slide", "end_stop", position=0.3, side="upper")], push(["slide"], [12.0], span=[(0.05, 0.42)]),
        {"slide": 0.05}, rate=250, impact_speed=0.3),
    "lid_mass_damping": lambda name, engine: Case(
        name, engine, chest_lid(), "lid pushed open and let fall: heavier than modelled, damped hinge",
        [fx("lid_hinge", "mass_scale", scale=1.3), fx("lid_hinge", "viscous_damping", damping=0.2)],
        push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6}),
    "lid_spring_damping": lambda name, engine: Case(
        name, engine, lid(0.35, 0.45, 1.2), "counterbalanced lid (spring) with a damper, pushed",
        [fx("lid_hinge", "spring", stiffness=1.2, rest_position=1.6),
         fx("lid_hinge", "viscous_damping", damping=0.15)], push(["lid_hinge"], [1.5]), {"lid_hinge": 0.8}),
    "double_pendulum_elbow_damping": lambda name, engine: Case(
        name, engine, double_pendulum(0.3, 0.6, 0.25, 0.4),
        "double pendulum released from an angle; only the elbow is damped",
        [fx("elbow", "viscous_damping", damping=0.01)], None, {"shoulder": 1.2, "elbow": -0.8}, rate=250),
    "drawer_small_damping": lambda name, engine: Case(
        name, engine, drawer(0.45, 0.5, 0.15, 4.0, 0.45),
        "drawer pushed and released; SMALL but real viscous damping (time constant 5 s), at the edge",
        [fx("slide", "viscous_damping", damping=0.8)], push(["slide"], [10.0]), {"slide": 0.1}, duration=10.0),
    "none_door_pushes": lambda name, engine: Case(
        name, engine, cabinet_door(),
        "NOTHING missing: cabinet door pushed toward random targets (the span reaches past both stops) and released",
        [], push(["hinge"], [2.0], span=[(-0.8, 2.8)]), {"hinge": 0.3}, effort_noise=0.01),
    "none_double_pendulum": lambda name, engine: Case(
        name, engine, double_pendulum(0.3, 0.6, 0.25, 0.4), "NOTHING missing: double pendulum released", [], None,
        {"shoulder": 1.0, "elbow": 0.5}, rate=250),
    "none_lid_pose": lambda name, engine: Case(
        name, engine, chest_lid(),
        "NOTHING missing: lid pushed and dropped onto its stop, tracked by its link pose; jittered sample times, "
        "dropouts", [], push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6},
        observe="pose", jitter=True, dropouts=0.02, effort_noise=0.01),
}


# The ENGINE_CASES an engine with joint friction and damping but neither joint springs nor
# armature makes (Klamp't, JaxSim).
FRICTION_DAMPING_CASES = (
    "door_friction", "drawer_friction", "door_damping", "sash_mass_scale", "drawer_end_stop", "door_friction_damping",
    "lid_mass_damping", "lid_mass_friction", "double_pendulum_elbow_friction", "double_pendulum_elbow_damping",
    "drawer_small_damping", "none_door_pushes", "none_double_pendulum", "none_lid_pose",
)


def engine_case(prefix, engine, key, **changes):
    """The shared case ENGINE_CASES[key] of an engine suite: named <prefix>_<key>, simulated by `engine` (a key of
    SIMULATORS), with the fields in `changes` (an engine's own description) replaced."""
    return replace(ENGINE_CASES[key](f"{prefix}_{key}", engine), **changes)


def push_spans(case, ex):
    """Push targets (lo, hi) per joint: given, else the inner 80 % of the limits, else q0 +- 1.5."""
    if ex.span is not None:
        return ex.span
    spans = []
    for name in ex.joints:
        joint = case.mech.joint(name)
        if joint.lower is None:
            q0 = case.q0.get(name, 0.0)
            spans.append((q0 - 1.5, q0 + 1.5))
        else:
            spans.append((joint.lower + 0.1 * (joint.upper - joint.lower), joint.upper - 0.1 * (joint.upper - joint.lower)))
    return spans


def contact_schedule(rng, duration, span):
    """Contact phases (t0, t1, target) separated by releases; none starts in the last 2 s."""
    out, t = [], rng.uniform(0.1, 0.8)
    while t < duration - 2.0:
        d = rng.uniform(0.4, 1.0)
        out.append((t, t + d, rng.uniform(*span)))
        t += d + rng.uniform(0.6, 1.8)
    return out


def pushes(case, ex, idx, inertia, nominal, rng):
    """A hand: in contact it pulls toward a target (PD + the weight the model predicts, clipped to
    amp), re-deciding every 0.1 s and holding; out of contact, zero."""
    w = 2 * math.pi * 1.0
    kp, kd = inertia * w * w, 2 * 0.8 * inertia * w
    schedules = [contact_schedule(rng, case.duration, span) for span in push_spans(case, ex)]
    held, last = np.zeros(len(case.mech.movable())), np.full(len(idx), -np.inf)

    def effort(t, q, qd):
        gravity = None
        for n, j in enumerate(idx):
            target = next((tgt for t0, t1, tgt in schedules[n] if t0 <= t < t1), None)
            if target is None:
                held[j], last[n] = 0.0, -np.inf
            elif t - last[n] >= 0.1 - 1e-9:
                gravity = nominal.gravity(q) if gravity is None else gravity
                held[j] = np.clip(kp[n] * (target - q[j]) - kd[n] * qd[j] + gravity[j], -ex.amp[n], ex.amp[n])
                last[n] = t
        return held.copy()

    return effort


def multisine(case, ex, idx, inertia, nominal, rng):
    """Five sines per joint (0.2-2.5 Hz, peak <= amp) + a PD to `centre` (1 Hz) + the model's weight."""
    w = 2 * math.pi * 1.0
    kp, kd = inertia * w * w, 2 * 0.6 * inertia * w
    freq = rng.uniform(0.2, 2.5, (len(idx), 5))
    phase = rng.uniform(0, 2 * math.pi, (len(idx), 5))
    weight = rng.uniform(0.5, 1.0, (len(idx), 5))
    weight *= np.asarray(ex.amp)[:, None] / weight.sum(axis=1, keepdims=True)

    def effort(t, q, qd):
        gravity, out = nominal.gravity(q), np.zeros(len(q))
        for n, j in enumerate(idx):
            out[j] = (weight[n] @ np.sin(2 * math.pi * freq[n] * t + phase[n]) + kp[n] * (ex.centre[n] - q[j])
                      - kd[n] * qd[j] + gravity[j])
        return out

    return effort


def shake(case, ex, idx, inertia, nominal, rng):
    """amp * sin(2 pi f t) under a slow envelope (0.3-1.0), + the model's weight."""
    phase = rng.uniform(0, 2 * math.pi)

    def effort(t, q, qd):
        gravity, out = nominal.gravity(q), np.zeros(len(q))
        envelope = 0.65 + 0.35 * math.sin(2 * math.pi * 0.11 * t + phase)
        for n, j in enumerate(idx):
            out[j] = ex.amp[n] * envelope * math.sin(2 * math.pi * ex.freq * t) + gravity[j]
        return out

    return effort


def make_source(case, nominal, q0, rng):
    """effort(t, q, qd) -> efforts of all movable joints, or None for a release."""
    ex = case.excite
    if ex is None:
        return None
    idx = [case.mech.movable().index(name) for name in ex.joints]
    inertia = np.diag(nominal.dynamics(q0, np.zeros(len(q0)))[0])[idx]
    effort = {"pushes": pushes, "multisine": multisine, "shake": shake}[ex.kind](case, ex, idx, inertia, nominal, rng)
    return lambda k, t, q, qd: effort(t, q, qd)


def excitation_text(case):
    ex = case.excite
    if ex is None:
        return "released from rest at q0, no effort"
    return {"pushes": "pushes: a hand pulls toward random targets (PD + modelled weight, clipped), decided every 0.1 s and "
                      "held, with releases in between and at the end",
            "multisine": "multisine (5 sines, 0.2-2.5 Hz) + centring PD (1 Hz) + modelled weight, decided every sample",
            "shake": f"shaking: {ex.freq} Hz sine under a slow envelope (+ modelled weight), decided every sample"}[ex.kind] + \
        f"; efforts on {', '.join(ex.joints)} up to {', '.join(f'{a:g}' for a in ex.amp)}"


# ---------------------------------------------------------------- simulation


@dataclass
class Trajectory:
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray  # applied, held from each sample to the next
    poses: dict


def case_rng(seed, name):
    return np.random.default_rng([seed, zlib.crc32(name.encode())])


def sample_steps(duration, rate, jitter, rng):
    """Engine steps at which samples are taken: uniform, or jittered by up to +-(period-1)/2 steps."""
    period = round(1.0 / (rate * DT))
    if abs(period * DT * rate - 1.0) > 1e-9:
        raise SuiteError(f"{rate} Hz is not a whole number of {DT} s steps")
    steps = np.arange(round(duration * rate) + 1) * period
    if jitter:
        half = (period - 1) // 2
        steps[1:-1] += rng.integers(-half, half + 1, len(steps) - 2)
    return steps


def simulate(sim, steps, q0, source, pose_links=()):
    """Samples the engine at `steps`; after each sample the source's effort is held until the next."""
    n, nj = len(steps), len(sim.names)
    traj = Trajectory(steps * DT, np.zeros((n, nj)), np.zeros((n, nj)), np.zeros((n, nj)),
                      {link: np.zeros((n, 7)) for link in pose_links})
    sim.set_state(q0, np.zeros(nj))
    done = 0
    for k, step in enumerate(steps):
        sim.advance(int(step - done))
        done = step
        traj.q[k], traj.qd[k] = sim.state()
        for link in pose_links:
            traj.poses[link][k] = sim.pose(link)
        if source is not None:
            traj.effort[k] = source(k, traj.t[k], traj.q[k], traj.qd[k])
            sim.hold(traj.effort[k])
    return traj


# case.engine -> sim of (case, mech, effects, gravity); gap_suite_physx.py adds "physx", the other engine suites theirs
SIMULATORS = {
    "mujoco": lambda case, mech, effects, gravity: MujocoSim(mujoco_model(mech, effects, gravity, case.solref_limit),
                                                             mech.movable()),
    "bullet": lambda case, mech, effects, gravity: BulletSim(mech, effects, gravity),
}


def make_sim(case, mech, effects, gravity=True):
    return SIMULATORS[case.engine](case, mech, effects, gravity)


def check_rigid(case, nominal, rng):
    """The engine's rigid bodies (no effects) equal model.urdf's as MuJoCo reads it."""
    sim = make_sim(case, case.mech, [])
    try:
        for _ in range(3):
            q = rng.uniform(-1.5, 1.5, len(sim.names))
            qd = rng.normal(0.0, 1.0, len(sim.names))
            compare_dynamics(case.name, sim.dynamics(q, qd), nominal.dynamics(q, qd))
    finally:
        sim.close()


def compare_dynamics(what, got, want, rtol=RIGID_RTOL):
    """The error of (inertia, bias) `got` against `want`, relative to the largest entry of want's inertia (of either
    for the bias); raises above rtol."""
    (m1, b1), (m2, b2) = got, want
    scale = max(np.abs(m2).max(), np.abs(b2).max())
    err = max(np.abs(m1 - m2).max() / np.abs(m2).max(), np.abs(b1 - b2).max() / scale)
    if not err <= rtol:
        raise SuiteError(f"{what}: engine and model.urdf differ in inertia or bias forces ({err:.2e} relative)")
    return err


def stop_hit(case, engine_mech, effect):
    """The engine's bodies without effects, gravity off, set 0.02 before `effect`'s end stop and moving toward it at
    the case's `impact_speed` (the other joints at q0, at rest): (sim, the joint's index, +1 toward an upper stop or
    -1 toward a lower one)."""
    names = engine_mech.movable()
    n, sign = names.index(effect.joint), 1.0 if effect.setting["side"] == "upper" else -1.0
    q = np.array([case.q0.get(name, 0.0) for name in names])
    qd = np.zeros(len(names))
    q[n], qd[n] = effect.params["position"] - sign * 0.02, sign * case.impact_speed
    sim = make_sim(case, engine_mech, [], gravity=False)
    sim.set_state(q, qd)
    return sim, n, sign


def measure_restitution(case, engine_mech, effect):
    """An end stop's restitution as the engine has it: hit at `impact_speed`, gravity off (stop_hit)."""
    sim, n, sign = stop_hit(case, engine_mech, effect)
    sim.advance(400)
    out = max(0.0, -sign * float(sim.state()[1][n]) / case.impact_speed)
    sim.close()
    return round(out, 3)


def effort_offsets(case):
    out = np.zeros(len(case.mech.movable()))
    for effect in case.effects:
        if effect.kind == "effort_offset":
            if case.excite is None or effect.joint not in case.excite.joints:
                raise SuiteError(f"{case.name}: effort_offset needs an effort column on {effect.joint}")
            out[case.mech.movable().index(effect.joint)] += effect.params["offset"]
    return out


def replay_visibility(case, traj, steps, q0):
    """RMSE per joint between the engine's motion and the engine without the concealed effects
    replaying the recorded (noise-free) efforts from the same initial state."""
    recorded = traj.effort - effort_offsets(case)
    sim = make_sim(case, case.mech, [])
    replay = simulate(sim, steps, q0, lambda k, t, q, qd: recorded[k])
    sim.close()
    return {name: sig3(rms(traj.q[:, n] - replay.q[:, n])) for n, name in enumerate(case.mech.movable())}


def rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def sig3(x):
    return float(f"{x:.3g}")


def inverse_dynamics(sim, traj, qdd):
    """M(q) qdd + C(q, qd) qd + g(q) of a sim's rigid bodies along a trajectory."""
    return np.array([m @ a + b for (m, b), a in zip((sim.dynamics(q, v) for q, v in zip(traj.q, traj.qd)), qdd)])


def effort_share(case, traj, engine_mech, nominal):
    """Objects: shares of the effects' efforts (see effect_shares); a heavier part or a tilted axis
    as the difference of the engine's rigid-body inverse dynamics and model.urdf's."""
    qdd = np.gradient(traj.qd, traj.t, axis=0)
    model = inverse_dynamics(nominal, traj, qdd)
    rigid = None
    if any(e.kind in ("mass_scale", "gravity_tilt") for e in case.effects):
        sim = make_sim(case, engine_mech, [])
        rigid = inverse_dynamics(sim, traj, qdd) - model
        sim.close()
    return effect_shares(case.effects, case.mech.movable(), traj, model, rigid)


def effect_shares(effects, names, traj, model, rigid=None):
    """{"<joint>.<kind>": RMS of the effect's effort along the engine's motion over the RMS of the
    effort that model.urdf needs for that motion (inverse dynamics `model`, per joint)}. Coulomb
    friction counts only where |qd| > 1e-3, at its backward level (friction_reverse) where qd < 0;
    end stops are not counted."""
    qdd = np.gradient(traj.qd, traj.t, axis=0)
    out = {}
    for e in effects:
        n, p = names.index(e.joint), e.params
        q, v = traj.q[:, n], traj.qd[:, n]
        force = {
            "viscous_damping": lambda: p["damping"] * v,
            "coulomb_friction": lambda: np.where(v < 0, p.get("friction_reverse", p["friction"]), p["friction"])
            * np.sign(v) * (np.abs(v) > 1e-3),
            "spring": lambda: p["stiffness"] * (q - p["rest_position"]),
            "armature": lambda: p["armature"] * qdd[:, n],
            "mass_scale": lambda: rigid[:, n],
            "gravity_tilt": lambda: rigid[:, n],
            "effort_offset": lambda: np.full(len(v), p["offset"]),
        }.get(e.kind)
        if force is not None:
            out[f"{e.joint}.{e.kind}"] = sig3(rms(force()) / rms(model[:, n]))
    return out


# ---------------------------------------------------------------- checks of an engine suite's engine
# (gap_suite_physx.py, gap_suite_dart.py, gap_suite_drake.py, gap_suite_newton.py: their sims, as SIMULATORS makes
# them, have the methods of MujocoSim)


def check_joint_frame(joint, urdf_joint):
    """The engine's joint (of the engine's bodies) must sit where model.urdf's does: same axis and origin."""
    if tuple(joint.axis) != tuple(urdf_joint.axis) or joint.xyz != urdf_joint.xyz or joint.rpy != urdf_joint.rpy:
        raise SuiteError(f"joint {joint.name}: the engine's joint frame differs from model.urdf's")


def state_box(mech, margin=0.0):
    """Random states are drawn within the limits (`margin` inside), or within +-pi for a continuous joint."""
    joints = [mech.joint(name) for name in mech.movable()]
    return (np.array([-math.pi if j.lower is None else j.lower + margin for j in joints]),
            np.array([math.pi if j.upper is None else j.upper - margin for j in joints]))


def random_speeds(rng, n, speed=None):
    """n joint speeds: of random sign and a size uniform within `speed` (low, high), or standard normal where speed
    is None."""
    if speed is None:
        return rng.normal(0.0, 1.0, n)
    return rng.choice([-1.0, 1.0], n) * rng.uniform(*speed, n)


def check_engine_rigid(case, engine_mech, nominal, rng, engine, measures, pose_tol, speed=None, margin=0.0):
    """An engine's bodies (`engine` names it in messages) against model.urdf as MuJoCo reads it (`nominal`) and, for a
    heavier link, the engine's bodies against MuJoCo's model of them, at 3 random states each (state_box with
    `margin`, random_speeds with `speed`): the joint-space inertia and bias of each of `measures`, (what,
    dynamics(sim, q, qd), rtol), by compare_dynamics, and every link's pose to pose_tol (a quaternion q and -q are
    one turn). Returns the worst relative inertia/bias error of each measure."""
    pairs = [(case.mech, nominal)]
    if any(e.kind == "mass_scale" for e in case.effects):
        pairs.append((engine_mech, MujocoSim(mujoco_model(engine_mech, []), engine_mech.movable())))
    worst = [0.0] * len(measures)
    for mech, reference in pairs:
        sim = make_sim(case, mech, [])
        lo, hi = state_box(mech, margin)
        for _ in range(3):
            q, qd = rng.uniform(lo, hi), random_speeds(rng, len(lo), speed)
            want = reference.dynamics(q, qd)
            worst = [max(err, compare_dynamics(f"{case.name} ({what})", dynamics(sim, q, qd), want, rtol))
                     for err, (what, dynamics, rtol) in zip(worst, measures)]
            sim.set_state(q, qd)
            reference.set_state(q, qd)
            for link in (joint.child for joint in mech.joints):
                got, want_pose = sim.pose(link), reference.pose(link)
                turn = min(np.abs(got[3:] - want_pose[3:]).max(), np.abs(got[3:] + want_pose[3:]).max())
                err = max(np.abs(got[:3] - want_pose[:3]).max(), turn)
                if err > pose_tol:
                    raise SuiteError(f"{case.name}: {engine} puts link {link} {err:.1e} away from model.urdf")
        sim.close()
    return worst


def probe_step_dynamics(sim, q, qd, probe, read_back=False, check=None):
    """Joint-space inertia M and bias force as one step of `sim` has them, with everything the step adds: the
    velocity change of one step from (q, qd) with zero effort and with an effort on each joint of `probe` times its
    inertia (sim.dynamics at rest: about `probe` of acceleration), M = diag(probe I) (A - a0)^-1, bias -M a0. The
    velocity before the step is qd, or as sim.state() reads it back (`read_back`); `check(velocity)` may raise at the
    velocity after each step. Leaves the last effort held: the caller restores its own."""
    inertia = np.diag(sim.dynamics(q, np.zeros(len(q)))[0])
    acc = []
    for effort in np.vstack([np.zeros(len(q)), np.diag(probe * inertia)]):
        sim.set_state(q, qd)
        before = sim.state()[1] if read_back else np.asarray(qd, float)
        sim.hold(effort)
        sim.advance(1)
        after = sim.state()[1]
        if check is not None:
            check(after)
        acc.append((after - before) / DT)
    full = np.diag(probe * inertia) @ np.linalg.inv(np.column_stack([a - acc[0] for a in acc[1:]]))
    return full, -full @ acc[0]


def measure_engine_effects(case, engine_mech, rng, engine, dynamics, expected, rtol, floor_rtol, speed=None,
                           margin=0.0, was="{:.6g} was expected"):
    """The efforts of damping, springs and friction and the added inertia as an engine (`engine` names it in
    messages) applies them, one step from 8 random states (state_box with `margin`, random_speeds with `speed`): the
    difference of `dynamics(sim, q, qd)` (inertia, bias) with and without the case's effects, fitted per joint by
    -b qd - f sign(qd) - k (q - r) and an added diagonal inertia. Raises unless the damping and the added inertia
    match `expected(joint_params)` ({"damping": (value, tol), "armature": (value, tol)}), friction and stiffness the
    values set to rtol and the rest position to 1e-3 (no tolerance under floor_rtol of the largest inertia or bias
    entry), and joints without effects get under rtol of the others' efforts and inertia (plus that floor). `was`
    words the expected value in the message. Returns the fits per joint with effects:
    {joint: {"damping", "armature" (all the added inertia)[, "friction"][, "stiffness", "rest_position"]}}."""
    names = engine_mech.movable()
    bare, full = make_sim(case, engine_mech, []), make_sim(case, engine_mech, case.effects)
    lo, hi = state_box(engine_mech, margin)
    q, qd, effort, added, scale = [], [], [], [], 0.0
    for _ in range(8):
        q.append(rng.uniform(lo, hi))
        qd.append(random_speeds(rng, len(names), speed))
        (m0, b0), (m1, b1) = dynamics(bare, q[-1], qd[-1]), dynamics(full, q[-1], qd[-1])
        effort.append(b0 - b1)
        added.append(np.diag(m1 - m0))
        scale = max(scale, np.abs(m0).max(), np.abs(b0).max())
    bare.close()
    full.close()
    q, qd, effort, added = (np.array(x) for x in (q, qd, effort, added))
    floor = floor_rtol * scale
    out = {}
    for n, name in enumerate(names):
        p = joint_params(case.effects, name)
        if not (p["stiffness"] or p["damping"] or p["friction"] or p["armature"]):
            if (np.abs(effort[:, n]).max() > rtol * np.abs(effort).max() + floor or
                    np.abs(added[:, n]).max() > rtol * np.abs(added).max() + floor):
                raise SuiteError(f"{case.name}: {engine} adds an effort or inertia on {name}, which has no effect")
            continue
        columns, keys = [-qd[:, n]], ["damping"]
        if p["friction"]:
            columns.append(-np.sign(qd[:, n]))
            keys.append("friction")
        if p["stiffness"]:
            columns += [-q[:, n], np.ones(len(q))]
            keys += ["stiffness", "k_rest"]
        fit = dict(zip(keys, np.linalg.lstsq(np.column_stack(columns), effort[:, n], rcond=None)[0]))
        got = {"damping": fit["damping"], "armature": float(np.mean(added[:, n]))}
        want = expected(p)
        if p["friction"]:
            got["friction"] = fit["friction"]
            want["friction"] = (p["friction"], rtol * p["friction"])
        if p["stiffness"]:
            got.update(stiffness=fit["stiffness"], rest_position=fit["k_rest"] / fit["stiffness"])
            want.update(stiffness=(p["stiffness"], rtol * p["stiffness"]), rest_position=(p["springref"], 1e-3))
        for key, (value, tol) in want.items():
            if abs(got[key] - value) > max(tol, floor):
                raise SuiteError(f"{case.name}: {engine} applies {key} {got[key]:.6g} on {name}, {was.format(value)}")
        out[name] = {key: float(f"{value:.4g}") for key, value in got.items()}
    return out


# ---------------------------------------------------------------- recording and truth


def quat_mul(a, b):
    """Hamilton product of quaternions (w x y z), row-wise."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = b.T
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=1)


def noisy_quats(quats, sigma, rng):
    """Each orientation turned by a small random rotation (sigma rad per axis), renormalised."""
    half = rng.normal(0.0, sigma, (len(quats), 3)) / 2
    small = np.concatenate([np.sqrt(np.maximum(0.0, 1 - (half ** 2).sum(axis=1)))[:, None], half], axis=1)
    out = quat_mul(quats, small)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def measurement_columns(case, traj, rng):
    """Noisy joint positions or link poses, as {column: values} groups (a dropout loses a group)."""
    sigma_rot, sigma_lin = case.noise
    groups = []
    if case.observe == "q":
        for n, name in enumerate(case.mech.movable()):
            sigma = sigma_lin if case.mech.joint(name).kind == "prismatic" else sigma_rot
            groups.append({f"{name}.q": traj.q[:, n] + rng.normal(0.0, sigma, len(traj.t))})
    else:
        for link, pose in traj.poses.items():
            pos = pose[:, :3] + rng.normal(0.0, sigma_lin, (len(traj.t), 3))
            quat = noisy_quats(pose[:, 3:], sigma_rot, rng)
            groups.append({**{f"{link}.pos.{a}": pos[:, i] for i, a in enumerate("xyz")},
                           **{f"{link}.quat.{a}": quat[:, i] for i, a in enumerate("wxyz")}})
    return groups


def drop(groups, share, gap, rng):
    """Empties cells: each group's sample with probability `share`, and `gap` samples of all of them
    at mid-recording; the first five and the last sample stay."""
    n = len(next(iter(groups[0].values())))
    burst = np.zeros(n, bool)
    burst[n // 2: n // 2 + gap] = True
    for group in groups:
        lost = (rng.random(n) < share) | burst
        lost[:5] = lost[-1] = False
        for values in group.values():
            values[lost] = np.nan


def recording_table(case, traj, rng):
    """{column: values} of recording.csv (NaN = empty cell) and the noise levels used."""
    groups = measurement_columns(case, traj, rng)
    if case.dropouts:
        drop(groups, case.dropouts, int(0.15 * case.rate), rng)
    table = {"time": traj.t}
    for group in groups:
        table.update(group)
    noise = {"q_rad": case.noise[0], "q_m": case.noise[1]} if case.observe == "q" else \
        {"orientation_rad": case.noise[0], "position_m": case.noise[1]}
    if case.excite is not None:
        offsets = effort_offsets(case)
        for name in case.excite.joints:
            n = case.mech.movable().index(name)
            recorded = traj.effort[:, n] - offsets[n]
            sigma = case.effort_noise * float(np.sqrt(np.mean(recorded ** 2)))
            table[f"{name}.effort"] = recorded + rng.normal(0.0, sigma, len(recorded))
            noise[f"{name}.effort"] = float(f"{sigma:.3g}")
    return table, noise


def write_csv(path, table, meta):
    """Spec format: `# key: value` lines, one header row, numbers or empty cells."""
    cells = []
    for name, values in table.items():
        fmt = "{:.6f}" if name == "time" else "{:.9g}"
        cells.append(["" if not np.isfinite(v) else fmt.format(v) for v in values])
    lines = [f"# {k}: {v}" for k, v in meta.items()] + [",".join(table)]
    lines += [",".join(row) for row in zip(*cells)]
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")


def write_json(path, data):
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


def effect_detail(case, effect, engine_mech):
    """How the engine made one effect."""
    p, kind, mj = effect.params, effect.kind, case.engine == "mujoco"
    joint = engine_mech.joint(effect.joint)
    if kind == "viscous_damping":
        return (f"MuJoCo joint damping={p['damping']} (implicit in the Euler step)" if mj else
                f"Bullet changeDynamics(jointDamping={p['damping']}), checked at start to act as -b*qd")
    if kind == "coulomb_friction":
        return (f"MuJoCo joint frictionloss={p['friction']} (soft constraint, solref_friction 0.02 1: regularised, a little "
                "viscous near zero speed, creeps slowly while 'stuck')" if mj else
                f"Bullet velocity motor targetVelocity=0 force={p['friction']} (bounded impulse: sticks exactly)")
    if kind == "spring":
        return f"MuJoCo joint stiffness={p['stiffness']} springref={p['rest_position']}"
    if kind == "armature":
        return f"MuJoCo joint armature={p['armature']}"
    if kind == "mass_scale":
        return f"{'MuJoCo body' if mj else 'engine-side URDF link'} {joint.child}: mass and inertia x{p['scale']}"
    if kind == "end_stop":
        solref = case.solref_limit or (0.02, 1.0)
        how = f"MuJoCo joint range, soft limit solref {solref[0]} {solref[1]}" if mj else \
            "engine-side URDF <limit>, Bullet joint-limit constraint"
        return (f"{how}: {effect.setting['side']} bound {p['position']} instead of model.urdf's; restitution measured "
                f"in the engine hitting it at {case.impact_speed} per second, gravity off")
    if kind == "gravity_tilt":
        axes = [[round(float(a), 6) for a in unit(j.axis)] for j in (joint, case.mech.joint(effect.joint))]
        return f"engine joint axis {axes[0]} against model.urdf's {axes[1]}; equilibrium from the engine's geometry"
    return f"the engine applied the recorded effort + {p['offset']}"


def engine_text(case):
    if case.engine == "mujoco":
        solref = case.solref_limit or (0.02, 1.0)
        return (f"MuJoCo {mujoco.__version__}: our own model (mujoco.MjSpec) with model.urdf's rigid bodies, Euler "
                f"integrator, {DT} s steps, efforts through qfrc_applied held between samples, contacts off, joint "
                f"limits soft (solref {solref[0]} {solref[1]})")
    return (f"pybullet {metadata.version('pybullet')} (Bullet Featherstone multibody): loadURDF of an engine-side URDF "
            f"(model.urdf + the concealed rigid-body changes), URDF_USE_INERTIA_FROM_FILE, {DT} s steps, link damping 0, "
            "default velocity motors off, efforts by TORQUE_CONTROL every step held between samples, limits by Bullet's "
            "joint-limit constraint")


def run_case(case, seed, out):
    """Simulates one case with MuJoCo or Bullet and writes DIR/<case>/ (run_engine_case)."""
    checks = (lambda case, engine_mech, nominal, rng: check_rigid(case, nominal, rng),
              lambda case, engine_mech, rng: None,
              lambda case, effect, engine_mech, measured: effect_detail(case, effect, engine_mech),
              lambda rigid_err: engine_text(case))
    return run_engine_case(case, seed, out, ENGINES[case.engine], checks,
                           lambda engine_mech: make_sim(case, engine_mech, case.effects))


def run_engine_case(case, seed, out, engine, checks, make_sim):
    """Simulates one case with an engine and writes DIR/<case>/{model.urdf, recording.csv, truth.json}
    (this suite's engines and those of gap_suite_physx.py, gap_suite_dart.py, gap_suite_drake.py,
    gap_suite_newton.py): `checks` holds the engine's check_rigid(case, engine_mech, nominal, rng),
    measure_effects(case, engine_mech, rng), effect_detail(case, effect, engine_mech, measured) and
    engine_text(rigid_err); `make_sim(engine_mech)` builds the engine's simulation of the case."""
    check_rigid, measure_effects, effect_detail, engine_text = checks
    rng = case_rng(seed, case.name)
    names = case.mech.movable()
    urdf = urdf_text(case.mech)
    nominal = MujocoSim(mujoco.MjSpec.from_string(urdf).compile(), names)
    engine_mech = engine_mechanism(case.mech, case.effects)
    rigid_err = check_rigid(case, engine_mech, nominal, rng)
    measured = measure_effects(case, engine_mech, rng)
    for effect in case.effects:
        if effect.kind == "end_stop":
            effect.params["restitution"] = measure_restitution(case, engine_mech, effect)
    q0 = np.array([case.q0.get(name, 0.0) for name in names])
    steps = sample_steps(case.duration, case.rate, case.jitter, rng)
    source = make_source(case, nominal, q0, rng)
    pose_links = [case.mech.joint(name).child for name in names] if case.observe == "pose" else []
    sim = make_sim(engine_mech)
    traj = simulate(sim, steps, q0, source, pose_links)
    sim.close()
    head = {
        "format": TRUTH_FORMAT, "engine": engine, "case": case.name, "description": case.description,
        "effects": [{"joint": e.joint, "kind": e.kind, "params": e.params,
                     "engine_detail": effect_detail(case, e, engine_mech, measured)} for e in case.effects],
        "joints": names, "engine_detail": engine_text(rigid_err),
    }
    return write_case(out, case, urdf, head, CaseRun(seed, traj, steps, q0, engine_mech, nominal), rng)


@dataclass
class CaseRun:
    """What a simulated object case leaves for write_case."""

    seed: int
    traj: object
    steps: object
    q0: object
    engine_mech: object
    nominal: object


def write_case(out, case, urdf, head, run, rng):
    """Writes DIR/<case>/{model.urdf, recording.csv, truth.json}: truth.json is `head` (format, engine, case,
    description, effects, joints, engine_detail) and what every engine's case says alike; the summary line."""
    table, noise = recording_table(case, run.traj, rng)
    folder = os.path.join(out, case.name)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "model.urdf"), "w", encoding="utf-8") as f:
        f.write(urdf)
    write_csv(os.path.join(folder, "recording.csv"), table, {"model": "model.urdf"} if case.model_line else {})
    truth = {
        **head,
        "seed": run.seed, "duration_s": case.duration, "rate_hz": case.rate, "timestep_s": DT,
        "sampling": "jittered (each sample moved by up to +-(period-1)/2 engine steps)" if case.jitter else "uniform",
        "observed": "link poses" if case.observe == "pose" else "joint positions", "excitation": excitation_text(case),
        "noise": noise, "dropouts": case.dropouts,
        "visibility_rmse": replay_visibility(case, run.traj, run.steps, run.q0) if case.effects else {},
        "visibility_effort_share": effort_share(case, run.traj, run.engine_mech, run.nominal) if case.effects else {},
    }
    write_json(os.path.join(folder, "truth.json"), truth)
    return summary_line(case, run.traj, truth)


def summary_line(case, traj, truth):
    spans = ", ".join(f"{name} [{traj.q[:, n].min():.3g}, {traj.q[:, n].max():.3g}]" for n, name in enumerate(truth["joints"]))
    effects = "; ".join(f"{e['joint']} {e['kind']} {e['params']}" for e in truth["effects"]) or "none"
    return (f"{case.name:38s} {case.engine:6s} {case.duration:4.1f} s {case.rate:3d} Hz  q: {spans}  effects: {effects}"
            f"  visibility: {truth.get('visibility_rmse', '-')} {truth['visibility_effort_share'] or ''}")


# ---------------------------------------------------------------- checks of what was written


def check_case_folder(folder):
    """Parses a case as the spec says a reader must: metadata lines, one header of known columns,
    numbers or empty cells, strictly increasing time; and truth.json against the spec's kinds."""
    root = ET.parse(os.path.join(folder, "model.urdf")).getroot()
    links = {link.get("name") for link in root.iter("link")}
    joints = [j.get("name") for j in root.iter("joint") if j.get("type") != "fixed"]
    with open(os.path.join(folder, "recording.csv"), encoding="utf-8") as f:
        lines = f.read().splitlines()
    while lines and lines[0].startswith("#"):
        if not re.fullmatch(r"# [A-Za-z_]+: .*", lines.pop(0)):
            raise SuiteError(f"{folder}: malformed metadata line")
    header = lines[0].split(",")
    pattern = re.compile(r"(?:(?P<j>.+)\.(?:q|effort)|(?P<l>.+)\.(?:pos\.[xyz]|quat\.[wxyz]))")
    for column in header[1:]:
        m = pattern.fullmatch(column)
        if not m or (m["j"] not in joints and m["l"] not in links) or header.count(column) > 1:
            raise SuiteError(f"{folder}: unknown or repeated column {column!r}")
    if header[0] != "time":
        raise SuiteError(f"{folder}: the first column is not time")
    times = []
    for number, line in enumerate(lines[1:], start=2):
        cells = line.split(",")
        if len(cells) != len(header) or not cells[0]:
            raise SuiteError(f"{folder}: row {number} has {len(cells)} cells or no time")
        values = [float(c) for c in cells if c]
        if not all(math.isfinite(v) for v in values):
            raise SuiteError(f"{folder}: row {number} has a non-finite number")
        times.append(float(cells[0]))
    if not all(b > a for a, b in zip(times, times[1:])):
        raise SuiteError(f"{folder}: time is not strictly increasing")
    check_truth(folder, joints)
    return len(times)


def check_truth(folder, joints):
    with open(os.path.join(folder, "truth.json"), encoding="utf-8") as f:
        truth = json.load(f)
    if truth["format"] != TRUTH_FORMAT or truth["joints"] != joints:
        raise SuiteError(f"{folder}: truth.json format or joints differ from model.urdf")
    for effect in truth["effects"]:
        required, optional = SPEC_PARAMS[effect["kind"]]
        if effect["joint"] not in joints or not required <= set(effect["params"]) <= required | optional:
            raise SuiteError(f"{folder}: effect {effect} does not follow the spec")


# ---------------------------------------------------------------- arms (issue 16)

# Stand-ins where Menagerie cannot be had: our own MJCF with the public kinematics of the Franka
# Panda and the UR5e (the joint names of their Menagerie models), masses as published, inertias
# plausible. joint7's anchor sits on its own axis away from the body origin (jnt_pos), to exercise
# that part of the URDF writer; the UR5e-like arm has Menagerie-style armature 0.1 on every joint.
PANDA_LIKE = """<mujoco model="panda_like">
  <compiler angle="radian" autolimits="true"/>
  <option integrator="implicitfast"/>
  <default><joint axis="0 0 1" damping="0.5"/></default>
  <worldbody>
    <body name="link0">
      <inertial mass="2.92" pos="-0.041 0 0.05" diaginertia="0.0084 0.0109 0.0102"/>
      <body name="link1" pos="0 0 0.333">
        <inertial mass="4.97" pos="0.0039 0.0021 -0.0476" quat="1 0.05 0.02 0" diaginertia="0.0246 0.0228 0.0091"/>
        <joint name="joint1" range="-2.8973 2.8973"/>
        <body name="link2" quat="1 -1 0 0">
          <inertial mass="0.646" pos="-0.0031 -0.0287 0.0035" quat="1 0.3 0 0.1" diaginertia="0.0106 0.0097 0.0034"/>
          <joint name="joint2" range="-1.7628 1.7628"/>
          <body name="link3" pos="0 -0.316 0" quat="1 1 0 0">
            <inertial mass="3.228" pos="0.0275 0.0392 -0.0666" diaginertia="0.0179 0.0161 0.0073"/>
            <joint name="joint3" range="-2.8973 2.8973"/>
            <body name="link4" pos="0.0825 0 0" quat="1 1 0 0">
              <inertial mass="3.587" pos="-0.0532 0.1044 0.0275" quat="1 0 0 0.2" diaginertia="0.0203 0.0179 0.0081"/>
              <joint name="joint4" range="-3.0718 -0.0698"/>
              <body name="link5" pos="-0.0825 0.384 0" quat="1 -1 0 0">
                <inertial mass="1.226" pos="-0.012 0.0411 -0.0384" diaginertia="0.0356 0.0294 0.0087"/>
                <joint name="joint5" range="-2.8973 2.8973"/>
                <body name="link6" quat="1 1 0 0">
                  <inertial mass="1.666" pos="0.0601 -0.0141 -0.0105" quat="0.9 0 0.2 0.1" diaginertia="0.0042 0.0032 0.0029"/>
                  <joint name="joint6" range="-0.0175 3.7525"/>
                  <body name="link7" pos="0.088 0 0" quat="1 1 0 0">
                    <inertial mass="0.735" pos="0.0105 -0.0043 0.0617" diaginertia="0.0013 0.0012 0.001"/>
                    <joint name="joint7" pos="0 0 0.05" range="-2.8973 2.8973"/>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

UR5E_LIKE = """<mujoco model="ur5e_like">
  <compiler angle="radian" autolimits="true"/>
  <option integrator="implicitfast"/>
  <default><joint axis="0 1 0" range="-6.2832 6.2832" armature="0.1"/></default>
  <worldbody>
    <body name="base" quat="0 0 0 -1">
      <inertial mass="4.0" pos="0 0 0" diaginertia="0.0044 0.0044 0.0072"/>
      <body name="shoulder_link" pos="0 0 0.163">
        <inertial mass="3.761" pos="0 -0.0026 -0.0039" diaginertia="0.0102 0.0102 0.0067"/>
        <joint name="shoulder_pan_joint" axis="0 0 1"/>
        <body name="upper_arm_link" pos="0 0.138 0" quat="1 0 1 0">
          <inertial mass="8.058" pos="0 0 0.2125" diaginertia="0.1339 0.1339 0.0151"/>
          <joint name="shoulder_lift_joint"/>
          <body name="forearm_link" pos="0 -0.131 0.425">
            <inertial mass="2.846" pos="0 0 0.196" diaginertia="0.0312 0.0312 0.0041"/>
            <joint name="elbow_joint" range="-3.1415 3.1415"/>
            <body name="wrist_1_link" pos="0 0 0.392" quat="1 0 1 0">
              <inertial mass="1.37" pos="0 0.127 0" diaginertia="0.0026 0.0026 0.0022"/>
              <joint name="wrist_1_joint"/>
              <body name="wrist_2_link" pos="0 0.127 0">
                <inertial mass="1.3" pos="0 0 0.1" diaginertia="0.0026 0.0026 0.0022"/>
                <joint name="wrist_2_joint" axis="0 0 1"/>
                <body name="wrist_3_link" pos="0 0 0.1">
                  <inertial mass="0.365" pos="0 0.0771 0" quat="1 0 0 1" diaginertia="0.00013 0.0001 0.0001"/>
                  <joint name="wrist_3_joint"/>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@dataclass
class ArmSource:
    """A Menagerie arm (robot, entry point), its built-in stand-in, and the posture it swings about."""

    robot: str
    entry: str
    builtin: str
    builtin_note: str
    home: tuple


ARMS = {
    "panda": ArmSource("franka_emika_panda", "panda_nohand", PANDA_LIKE, "Panda-like, 7 revolute joints",
                       (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)),
    "ur5e": ArmSource("universal_robots_ur5e", "ur5e", UR5E_LIKE, "UR5e-like, 6 revolute joints",
                      (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)),
}


@dataclass
class ArmCase:
    """Added on joints: [(joint, kind, value)], kind coulomb_friction (MuJoCo frictionloss),
    viscous_damping (damping), armature or effort_offset (a bias of the recorded torque).
    `model_error`: model.urdf's inertial parameters as a published identification has them, not
    as the engine does: each link's mass, centre of mass and inertia drawn off the engine's by up to
    this share (seeded), as a real robot's identified model is off its true rigid bodies."""

    name: str
    arm: str
    description: str
    added: list
    model_error: float = 0.0
    # joint -> (A, k, c): the joint's friction as a published identification of a real arm has
    # it, A / (1 + exp(-k (v + c))) - A / (1 + exp(-k c)), applied at every engine step.
    friction_law: dict = field(default_factory=dict)
    # (tilt_deg, toward): the arm stands on a base tilted by tilt_deg, the engine's gravity leaning
    # towards the world's horizontal direction at angle `toward` (rad from x about z); model.urdf
    # stands level, as a robot on a floor or cart not quite level is modelled.
    base_tilt: tuple = ()


# The joint friction identified on a real Franka Emika Panda (C. Gaz, M. Cognetti, A. Oliva,
# P. Robuffo Giordano, A. De Luca, "Dynamic Identification of the Franka Emika Panda Robot With
# Retrieval of Feasible Parameters Using Penalty-Based Optimization", IEEE RA-L 4(4), 2019,
# Table of friction parameters phi_1, phi_2, phi_3 per joint): a logistic law of the link-side
# speed, smooth over 0.12-0.39 rad/s (2 / k) and different by direction (the shift c), the
# friction of a real torque-sensed arm rather than an engine's ideal one.
PANDA_PUBLISHED_FRICTION = {
    "joint1": (0.54615, 5.1181, 0.039533), "joint2": (0.87224, 9.0657, 0.025882),
    "joint3": (0.64068, 10.136, -0.04607), "joint4": (1.2794, 5.5903, 0.036194),
    "joint5": (0.83904, 8.3469, 0.026226), "joint6": (0.30301, 17.133, -0.021047),
    "joint7": (0.56489, 10.336, 0.0035526),
}


def logistic_friction(law, v):
    """The published law's friction effort at speed v (it opposes the motion: subtract it)."""
    a, k, c = law
    return a / (1.0 + math.exp(-k * (v + c))) - a / (1.0 + math.exp(-k * c))


def logistic_friction_truth(law):
    """The law in the spec's terms: levels forward and backward, tanh's transition speed (the
    logistic's slope is tanh's at 2 / k)."""
    a, k, c = law
    at_rest = 1.0 / (1.0 + math.exp(-k * c))
    return {"friction": round(a * (1.0 - at_rest), 6), "transition_speed": round(2.0 / k, 6),
            "friction_reverse": round(a * at_rest, 6)}


ARM_CASES = [
    ArmCase("arm_panda_none", "panda", "Panda driven by joint torques; NO added effect", []),
    ArmCase("arm_panda_friction_damping", "panda", "Panda; dry friction on joints 1, 2, 4, damping on 2 and 6", [
        ("joint1", "coulomb_friction", 0.5), ("joint2", "coulomb_friction", 1.5), ("joint4", "coulomb_friction", 2.0),
        ("joint2", "viscous_damping", 2.0), ("joint6", "viscous_damping", 0.3)]),
    ArmCase("arm_panda_wrist_armature", "panda", "Panda; rotor inertia on the wrist (5, 6, 7) and dry friction on 7", [
        ("joint5", "armature", 0.05), ("joint6", "armature", 0.05), ("joint7", "armature", 0.005),
        ("joint7", "coulomb_friction", 0.01)]),
    ArmCase("arm_ur5e_none", "ur5e", "UR5e driven by joint torques; NO added effect (only the model's own armature)", []),
    ArmCase("arm_ur5e_friction", "ur5e", "UR5e; dry friction on shoulder lift, elbow and wrist 1", [
        ("shoulder_lift_joint", "coulomb_friction", 2.0), ("elbow_joint", "coulomb_friction", 1.5),
        ("wrist_1_joint", "coulomb_friction", 0.3)]),
    ArmCase("arm_ur5e_mixed", "ur5e", "UR5e; damping on the pan, more armature on wrist 2, dry friction at the elbow", [
        ("shoulder_pan_joint", "viscous_damping", 1.5), ("wrist_2_joint", "armature", 0.1),
        ("elbow_joint", "coulomb_friction", 1.0)]),
    # As a real torque-sensed arm is recorded against its published model: friction on six of
    # seven joints at the levels published for such an arm, two sensor biases, and a model.urdf
    # whose inertial parameters are up to 5 % off the engine's.
    ArmCase("arm_panda_identified_model", "panda",
            "Panda against a model.urdf with identification errors (masses, centres of mass, inertias up to 5 % off); "
            "dry friction on joints 1-6, damping on 4, torque-sensor biases on 2 and 5", [
                ("joint1", "coulomb_friction", 0.3), ("joint2", "coulomb_friction", 0.45), ("joint3", "coulomb_friction", 0.3),
                ("joint4", "coulomb_friction", 0.6), ("joint5", "coulomb_friction", 0.4), ("joint6", "coulomb_friction", 0.15),
                ("joint4", "viscous_damping", 0.5), ("joint2", "effort_offset", 0.3), ("joint5", "effort_offset", -0.15)],
            model_error=0.05),
    ArmCase("arm_ur5e_identified_model_none", "ur5e",
            "UR5e against a model.urdf with identification errors (up to 5 % off); NO added effect "
            "(only the model's own armature)", [], model_error=0.05),
    # Friction as a real arm has it: smooth through zero speed and different by direction, on
    # every joint, at the levels and transitions published for the real Panda.
    ArmCase("arm_panda_published_friction", "panda",
            "Panda against a model.urdf with identification errors (up to 5 % off); on every joint the logistic "
            "friction identified on the real arm (Gaz et al., RA-L 2019), applied at every engine step", [],
            model_error=0.05, friction_law=PANDA_PUBLISHED_FRICTION),
    # A base that is not level: the engine's gravity leans by a degree, model.urdf stands level.
    ArmCase("arm_panda_tilted_base", "panda",
            "Panda on a base tilted 1 deg, its model.urdf standing level; dry "
            "friction on joints 1, 2 and 4", [
                ("joint1", "coulomb_friction", 0.3), ("joint2", "coulomb_friction", 0.5), ("joint4", "coulomb_friction", 0.4)],
            base_tilt=(1.0, 2.2)),
]


def tilted_gravity(tilt_deg, toward):
    """GRAVITY leaning by tilt_deg towards the horizontal direction at angle `toward` about z."""
    tilt, g = math.radians(tilt_deg), -GRAVITY[2]
    return (g * math.sin(tilt) * math.cos(toward), g * math.sin(tilt) * math.sin(toward), -g * math.cos(tilt))


def frame_at_zero(mech, joint):
    """World rotation of `joint`'s frame (its child's frame at q = 0): the origins' rpy from the root."""
    chain, name = [], joint.name
    while True:
        j = mech.joint(name)
        chain.append(j)
        parent = next((k for k in mech.joints if k.child == j.parent), None)
        if parent is None:
            break
        name = parent.name
    rot = np.eye(3)
    for j in reversed(chain):
        rot = rot @ quat_to_matrix(quat_from_rpy(j.rpy))
    return rot


def quat_to_matrix(quat):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat, float))
    return out.reshape(3, 3)


def base_tilt_truth(mech, tilt_deg, toward):
    """The spec's gravity_tilt of a chain's base joint (partscene's reading, issue 16): tilt_deg, and
    equilibrium_position, the base joint's angle at which its child frame's x axis (y where x lies
    along the joint axis) at the zero pose points where gravity leans."""
    base = mech.joint(mech.movable()[0])
    return base.name, {"tilt_deg": tilt_deg, "equilibrium_position": lean_equilibrium(frame_at_zero(mech, base), base.axis, toward)}


def lean_equilibrium(rot, axis, toward):
    """The equilibrium_position of a base tilt leaning towards `toward` (rad from x about z), for a base joint whose
    frame at the zero pose has world rotation `rot` and whose axis is `axis` in that frame: the joint's angle at
    which the frame's x axis (y where x lies along the joint axis) points where gravity leans."""
    down = np.array([0.0, 0.0, -1.0])

    def horizontal(v):
        v = v - (v @ down) * down
        return v / np.linalg.norm(v)

    axis = rot @ unit(axis)
    first = rot[:, 0] if abs(rot[:, 0] @ axis) < 0.9 else rot[:, 1]
    h1 = horizontal(first)
    h2 = horizontal(np.cross(axis, h1))
    lean = np.array([math.cos(toward), math.sin(toward), 0.0])
    return round(math.atan2(lean @ h2, lean @ h1), 6)


def arm_xml(key, mode, cache={}):  # noqa: B006  the cache lives for the run
    """(path of the Menagerie XML or None, where the arm comes from). A failed download (the
    package retries for ~7 s) is not tried again for the next arm."""
    if (key, mode) not in cache:
        source, reason = ARMS[key], cache.get("unreachable", "chosen by arm source 'builtin'")
        if mode == "menagerie" or (mode == "auto" and "unreachable" not in cache):
            try:
                path = mujoco_menagerie.get(source.robot).xml(source.entry)
                where = " (from MENAGERIE_ROOT)" if os.environ.get("MENAGERIE_ROOT") else ""
                cache[key, mode] = (str(path), f"mujoco-menagerie {mujoco_menagerie.__version__} (registry of Menagerie "
                                                f"{mujoco_menagerie.commit()[:12]}): {source.robot}/{path.name}{where}")
                return cache[key, mode]
            except mujoco_menagerie.MenagerieError as err:
                if mode == "menagerie":
                    raise SuiteError(f"Menagerie arm {source.robot}: {err}") from err
                reason = f"Menagerie unavailable ({type(err).__name__})"
                if isinstance(err, mujoco_menagerie.DownloadError):
                    cache["unreachable"] = reason
        cache[key, mode] = (None, f"built-in MJCF ({source.builtin_note}); {reason}")
    return cache[key, mode]


def prepare_arm(spec):
    """Leaves the rigid-body tree: no actuators, keyframes, sensors or contacts, no gravity
    compensation; 1 ms steps, standard gravity. Returns the bodies whose gravcomp was removed."""
    if spec.tendons or spec.equalities:
        raise SuiteError("arm has tendons or equality constraints: not a plain kinematic tree")
    for element in list(spec.actuators) + list(spec.keys) + list(spec.sensors):
        spec.delete(element)
    spec.option.timestep = DT
    spec.option.gravity = GRAVITY
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    compensated = [body.name for body in spec.bodies if body.gravcomp]
    for body in spec.bodies:
        body.gravcomp = 0.0
    return compensated


def arm_defaults(model, names):
    """The model's own joint armature, damping and frictionloss; refuses what URDF + truth cannot say."""
    out = {}
    for name in names:
        j = model.joint(name).id
        dof = model.jnt_dofadr[j]
        if mujoco.mjtJoint(model.jnt_type[j]) not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            raise SuiteError(f"joint {name}: only hinge and slide joints")
        if model.jnt_stiffness[j] or np.any(model.jnt_stiffnesspoly[j]) or np.any(model.dof_dampingpoly[dof]):
            raise SuiteError(f"joint {name}: the arm's own springs / nonlinear damping are not supported")
        out[name] = {"armature": float(model.dof_armature[dof]), "damping": float(model.dof_damping[dof]),
                     "friction": float(model.dof_frictionloss[dof])}
    return out


def arm_mechanism(model, name, defaults):
    """The compiled tree as URDF links and joints: one link per body, its frame at the joint anchor."""
    world = base_link("world")
    links, joints, anchor, link_names = [world], [], {0: np.zeros(3)}, {0: world.name}
    for b in range(1, model.nbody):
        link_names[b] = model.body(b).name or f"body{b}"
        parent, count = model.body_parentid[b], model.body_jntnum[b]
        if count > 1:
            raise SuiteError(f"body {link_names[b]} has {count} joints")
        j = model.body_jntadr[b] if count else None
        anchor[b] = model.jnt_pos[j].copy() if count else np.zeros(3)
        rot, irot = np.zeros(9), np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.body_quat[b])
        mujoco.mju_quat2Mat(irot, model.body_iquat[b])
        irot = irot.reshape(3, 3)
        xyz = model.body_pos[b] + rot.reshape(3, 3) @ anchor[b] - anchor[parent]
        inertia = irot @ np.diag(model.body_inertia[b]) @ irot.T
        links.append(Link(link_names[b], float(model.body_mass[b]), tuple(model.body_ipos[b] - anchor[b]), inertia))
        joint = Joint(f"{link_names[b]}_fixed", "fixed", link_names[parent], link_names[b], tuple(xyz),
                      rpy_from_quat(model.body_quat[b]))
        if count:
            joint.name, joint.axis = model.joint(j).name, tuple(model.jnt_axis[j])
            hinge = mujoco.mjtJoint(model.jnt_type[j]) == mujoco.mjtJoint.mjJNT_HINGE
            joint.kind = ("revolute" if model.jnt_limited[j] else "continuous") if hinge else "prismatic"
            if model.jnt_limited[j]:
                joint.lower, joint.upper = (float(x) for x in model.jnt_range[j])
            joint.damping = defaults[joint.name]["damping"]
        joints.append(joint)
    return Mechanism(name, links, joints)


def verify_arm_urdf(rigid, nominal, names, rng):
    """model.urdf read back by MuJoCo against the original (armature zeroed) at 5 random states."""
    sim = MujocoSim(rigid, names)
    ids = [rigid.joint(name).id for name in names]
    lo = np.where(rigid.jnt_limited[ids], rigid.jnt_range[ids, 0], -math.pi)
    hi = np.where(rigid.jnt_limited[ids], rigid.jnt_range[ids, 1], math.pi)
    for _ in range(5):
        q, qd = rng.uniform(lo, hi), rng.normal(0.0, 1.0, len(names))
        compare_dynamics("arm model.urdf", nominal.dynamics(q, qd), sim.dynamics(q, qd))
    return lo, hi


def arm_excitation(nominal, armature, home, lo, hi, rng):
    """(q0, source): computed torque with model.urdf (plus the arm's own rotor inertia, which a
    controller knows from the data sheet), M(q) (w^2 e + 2 0.7 w e') + bias(q, qd) with w = 2 pi 1.5
    Hz, around a slow 3-sine target (0.05-0.3 Hz) inside the range, + 3 sines per joint (0.5-3 Hz)."""
    home = np.asarray(home, float)
    amp = np.maximum(0.05, np.minimum.reduce([np.full(len(home), 0.6), 0.35 * (hi - lo) / 2, home - lo - 0.15, hi - home - 0.15]))
    f_slow, p_slow = rng.uniform(0.05, 0.3, (len(home), 3)), rng.uniform(0, 2 * math.pi, (len(home), 3))
    w_slow = rng.uniform(0.5, 1.0, (len(home), 3))
    w_slow *= amp[:, None] / w_slow.sum(axis=1, keepdims=True)
    omega = 2 * math.pi * 1.5
    inertia = np.diag(nominal.dynamics(home, np.zeros(len(home)))[0]) + armature
    f_fast, p_fast = rng.uniform(0.5, 3.0, (len(home), 3)), rng.uniform(0, 2 * math.pi, (len(home), 3))
    w_fast = 0.1 * (inertia * omega ** 2 * amp)[:, None] / 3

    def target(t):
        arg = 2 * math.pi * f_slow * t + p_slow
        return home + (w_slow * np.sin(arg)).sum(axis=1), (w_slow * 2 * math.pi * f_slow * np.cos(arg)).sum(axis=1)

    def effort(k, t, q, qd):
        qt, qdt = target(t)
        m, bias = nominal.dynamics(q, qd)
        dither = (w_fast * np.sin(2 * math.pi * f_fast * t + p_fast)).sum(axis=1)
        return (m + np.diag(armature)) @ (omega ** 2 * (qt - q) + 2 * 0.7 * omega * (qdt - qd)) + bias + dither

    return target(0.0)[0], effort


class FrictionLawSim(MujocoSim):
    """MuJoCo with a joint friction law of the speed added at every step (explicitly, from the
    step's starting speed: the laws here are smooth over ~0.1 rad/s, far wider than a 1 ms step
    moves the speed); `laws`: joint -> (A, k, c) of [`logistic_friction`]."""

    def __init__(self, model, names, laws):
        super().__init__(model, names)
        self.laws = [(i, laws[name]) for i, name in enumerate(names) if name in laws]
        self.effort = np.zeros(len(names))

    def set_state(self, q, qd):
        super().set_state(q, qd)
        self.effort = np.zeros(len(self.names))

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()

    def advance(self, steps):
        for _ in range(int(steps)):
            applied = self.effort.copy()
            for i, law in self.laws:
                applied[i] -= logistic_friction(law, float(self.data.qvel[self.dadr[i]]))
            self.data.qfrc_applied[self.dadr] = applied
            mujoco.mj_step(self.model, self.data)


def added_level(case, joint, kind):
    """What the arm case adds of one kind on one joint (0 where nothing)."""
    return sum(v for j, k, v in case.added if j == joint and k == kind)


def arm_effects(case, defaults):
    """Truth effects: added ones, with the model's own armature/frictionloss (not in the URDF) merged."""
    out = []
    for name, own in defaults.items():
        added = {kind: added_level(case, name, kind) for kind in ("armature", "coulomb_friction", "viscous_damping")}
        for kind, param, mine, engine in (("armature", "armature", own["armature"], "armature"),
                                          ("coulomb_friction", "friction", own["friction"], "frictionloss"),
                                          ("viscous_damping", "damping", 0.0, "damping")):
            total = mine + added[kind]
            if kind == "coulomb_friction" and name in case.friction_law:
                if total > 0:
                    raise SuiteError(f"joint {name}: a published friction law on top of frictionloss {total:g}")
                out.append(Effect(name, kind, logistic_friction_truth(case.friction_law[name]),
                                  detail="the published logistic law A / (1 + exp(-k (v + c))) - A / (1 + exp(-k c)), "
                                         f"(A, k, c) = {case.friction_law[name]}, applied through qfrc_applied at every "
                                         "engine step; transition_speed 2 / k (the logistic's slope at rest as tanh's)"))
                continue
            if total > 0:
                detail = f"MuJoCo joint {engine}: model's own {mine:g} + added {added[kind]:g}"
                if kind == "viscous_damping":
                    detail = (f"MuJoCo joint damping: added {added[kind]:g} on top of the model's own {own['damping']:g}, "
                              "which model.urdf's <dynamics> has")
                out.append(Effect(name, kind, {param: round(total, 9)}, detail=detail))
        bias = added_level(case, name, "effort_offset")
        if bias != 0.0:
            # The spec's offset is what adds to the recorded effort to give the one the joint
            # feels (as the objects' offsets here are: the engine applied the recorded effort +
            # offset); a sensor reading `bias` over the felt effort is the offset -bias.
            out.append(Effect(name, "effort_offset", {"offset": -bias},
                              detail=f"a constant {bias:g} added to the recorded effort (torque-sensor bias): the joint "
                                     f"felt the recorded effort {-bias:+g}"))
    return out


def add_arm_effects(spec, case):
    for name, kind, value in case.added:
        joint = spec.joint(name)
        if kind == "coulomb_friction":
            joint.frictionloss += value
        elif kind == "viscous_damping":
            joint.damping = [joint.damping[0] + value, *joint.damping[1:]]
        elif kind == "armature":
            joint.armature += value


def arm_offsets(case, names):
    """The torque sensors' biases: a constant added to each recorded effort (truth.json's offset is
    minus the bias: what adds to the recorded effort to give the one the joint felt)."""
    return np.array([added_level(case, n, "effort_offset") for n in names])


def identification_error(mech, share, rng):
    """`mech` with every moving link's mass, centre of mass and inertia drawn off by up to `share`:
    mass x (1 +- share), the centre of mass moved by up to `share` of its distance from the joint
    (at least 2 mm x share/0.05), the principal inertias x (1 +- share) about the same axes."""
    out = copy.deepcopy(mech)
    for link in out.links:
        if link.mass <= 0.0:
            continue
        link.mass *= 1.0 + rng.uniform(-share, share)
        com = np.asarray(link.com, float)
        reach = max(float(np.linalg.norm(com)), 0.04)
        link.com = tuple(com + rng.uniform(-1.0, 1.0, 3) * share * reach)
        vals, vecs = np.linalg.eigh(np.asarray(link.inertia, float))
        vals = vals * (1.0 + rng.uniform(-share, share, 3))
        # A physical inertia: each principal moment no larger than the other two together.
        vals = np.minimum(vals, np.array([vals[1] + vals[2], vals[0] + vals[2], vals[0] + vals[1]]))
        link.inertia = vecs @ np.diag(vals) @ vecs.T
    return out


# Length of an arm recording, s (--arm-duration; issue 16 budgets the analysis of 20 s).
ARM_DURATION_S = 10.0


def run_arm_case(case, seed, out, mode, duration=ARM_DURATION_S):
    """Drives the original arm (plus the case's effects) for `duration` s and writes DIR/<case>/."""
    rng = case_rng(seed, case.name)
    source = ARMS[case.arm]
    path, origin = arm_xml(case.arm, mode)
    spec = mujoco.MjSpec.from_file(path) if path else mujoco.MjSpec.from_string(source.builtin)
    compensated = prepare_arm(spec)
    rigid = spec.compile()
    names = [rigid.joint(j).name for j in range(rigid.njnt)]
    defaults = arm_defaults(rigid, names)
    rigid.dof_armature[:] = 0.0
    mech = arm_mechanism(rigid, case.arm, defaults)
    urdf = urdf_text(mech, f"rigid-body tree of {origin}, compiled by MuJoCo {mujoco.__version__}; no geometry")
    nominal = MujocoSim(mujoco.MjSpec.from_string(urdf).compile(), names)
    lo, hi = verify_arm_urdf(rigid, nominal, names, rng)
    if case.model_error > 0.0:
        # Verified as the engine has it, then written as an identification would have it.
        urdf = urdf_text(identification_error(mech, case.model_error, rng),
                         f"rigid-body tree of {origin}, compiled by MuJoCo {mujoco.__version__}, inertial parameters "
                         f"drawn up to {case.model_error:.0%} off the engine's (an identified model); no geometry")
        nominal.close()
        nominal = MujocoSim(mujoco.MjSpec.from_string(urdf).compile(), names)
    add_arm_effects(spec, case)
    if case.base_tilt:
        spec.option.gravity = tilted_gravity(*case.base_tilt)
    plant = (FrictionLawSim(spec.compile(), names, case.friction_law) if case.friction_law
             else MujocoSim(spec.compile(), names))
    armature = np.array([defaults[n]["armature"] for n in names])
    q0, source_fn = arm_excitation(nominal, armature, source.home, lo, hi, rng)
    traj = simulate(plant, sample_steps(duration, 200, False, rng), q0, source_fn)
    table = {"time": traj.t}
    table.update({f"{n}.q": traj.q[:, i] + rng.normal(0.0, 1e-4, len(traj.t)) for i, n in enumerate(names)})
    effort_sigma = {n: 0.01 * rms(traj.effort[:, i]) for i, n in enumerate(names)}
    bias = arm_offsets(case, names)
    table.update({f"{n}.effort": traj.effort[:, i] + bias[i] + rng.normal(0.0, effort_sigma[n], len(traj.t))
                  for i, n in enumerate(names)})
    folder = os.path.join(out, case.name)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "model.urdf"), "w", encoding="utf-8") as f:
        f.write(urdf)
    write_csv(os.path.join(folder, "recording.csv"), table, {"model": "model.urdf", "gravity": "0 0 -9.81"})
    effects = arm_effects(case, defaults)
    model_effort = inverse_dynamics(nominal, traj, np.gradient(traj.qd, traj.t, axis=0))
    tilt_effort = None
    if case.base_tilt:
        joint, params = base_tilt_truth(mech, *case.base_tilt)
        effects.append(Effect(joint, "gravity_tilt", params,
                              detail=f"MuJoCo option gravity {tuple(round(g, 6) for g in tilted_gravity(*case.base_tilt))}: "
                                     "the whole arm stands tilted; model.urdf stands level"))
        tilted_spec = mujoco.MjSpec.from_string(urdf)
        tilted_spec.option.gravity = tilted_gravity(*case.base_tilt)
        tilted = MujocoSim(tilted_spec.compile(), names)
        tilt_effort = np.array([tilted.gravity(q) - nominal.gravity(q) for q in traj.q])
    truth = {
        "format": TRUTH_FORMAT, "engine": ENGINES["mujoco"], "case": case.name, "description": case.description,
        "effects": [{"joint": e.joint, "kind": e.kind, "params": e.params, "engine_detail": e.detail} for e in effects],
        "joints": names,
        "engine_detail": f"MuJoCo {mujoco.__version__}, {origin}: actuators, keyframes and sensors removed, contacts off"
                         f"{', gravcomp removed from ' + ', '.join(compensated) if compensated else ''}, integrator "
                         f"{mujoco.mjtIntegrator(rigid.opt.integrator).name}, {DT} s steps, torques through qfrc_applied "
                         "held between samples; model.urdf verified against the compiled model (mj_fullM, qfrc_bias) "
                         f"to {RIGID_RTOL:g}",
        "seed": seed, "duration_s": duration, "rate_hz": 200, "timestep_s": DT, "sampling": "uniform",
        "observed": "joint positions", "noise": {"q_rad": 1e-4, **{f"{n}.effort": sig3(s) for n, s in effort_sigma.items()}},
        "dropouts": 0.0,
        "excitation": "computed torque with model.urdf + the arm's own armature (1.5 Hz, damping ratio 0.7) around a "
                      "slow 3-sine target (0.05-0.3 Hz) + 3 sines per joint (0.5-3 Hz), decided at 200 Hz and held",
        "visibility_effort_share": effect_shares(effects, names, traj, model_effort, tilt_effort),
    }
    write_json(os.path.join(folder, "truth.json"), truth)
    return summary_line(ArmRun(case.name, "mujoco", duration, 200), traj, truth)


@dataclass
class ArmRun:
    """What summary_line needs of an arm case."""

    name: str
    engine: str
    duration: float
    rate: int


# ---------------------------------------------------------------- main


def engine_suite_main(cases, run_case, checks=()):
    """The command line of an engine's suite of its own (gap_suite_physx.py, gap_suite_dart.py, gap_suite_drake.py,
    gap_suite_newton.py): --out, --seed, --only over `cases()`; each (kind, check) in `checks` runs once before the
    cases when a chosen case has an effect of that kind; `run_case(case, seed, out)` writes a case."""
    parser = argparse.ArgumentParser(description=sys.modules["__main__"].__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="folder to write DIR/<case>/ into")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", default="*", help="fnmatch pattern on case names")
    args = parser.parse_args()
    start = time.perf_counter()
    chosen = [c for c in cases() if fnmatch.fnmatch(c.name, args.only)]
    if not chosen:
        raise SystemExit(f"no case matches {args.only!r}")
    for kind, check in checks:
        if any(e.kind == kind for c in chosen for e in c.effects):
            check()
    for case in chosen:
        print(run_case(case, args.seed, args.out), flush=True)
    rows = sum(check_case_folder(os.path.join(args.out, case.name)) for case in chosen)
    print(f"{len(chosen)} cases, {rows} samples, written and parsed in {time.perf_counter() - start:.1f} s")


# Arms that stick: dry friction strong beside what the excitation's drive asks of the joint (it
# does not feed the friction forward), so that it holds joints still at and around their reversals
# (the Panda's joint 2 for 23-41 % of the samples, the UR5e's pan, lift and wrist 1 for 14-51 %):
# a stick-slip arm, as a plain drive against real friction makes one. Written after the rule that
# leaves such rests out of effort space (src/gap/rests.rs), which was found on the Robotics
# Toolbox's PUMA, not on these.
STUCK_ARM_CASES = [
    ArmCase("arm_panda_stuck", "panda", "Panda; strong dry friction on joints 1, 2, 4, 6, damping on 2 and 4", [
        ("joint1", "coulomb_friction", 2.0), ("joint2", "coulomb_friction", 5.0), ("joint4", "coulomb_friction", 4.0),
        ("joint6", "coulomb_friction", 0.8), ("joint2", "viscous_damping", 2.0), ("joint4", "viscous_damping", 1.0)]),
    ArmCase("arm_ur5e_stuck", "ur5e", "UR5e; strong dry friction on pan, lift, elbow, wrist 1, damping on lift", [
        ("shoulder_pan_joint", "coulomb_friction", 4.0), ("shoulder_lift_joint", "coulomb_friction", 8.0),
        ("elbow_joint", "coulomb_friction", 5.0), ("wrist_1_joint", "coulomb_friction", 1.0),
        ("shoulder_lift_joint", "viscous_damping", 3.0)]),
]


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="folder to write DIR/<case>/ into")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", default="*", help="fnmatch pattern on case names")
    parser.add_argument("--arms", action="store_true", help="the multi-joint arms of issue 16 instead of the objects")
    parser.add_argument("--stuck-arms", action="store_true", help="arms whose dry friction holds joints still (STUCK_ARM_CASES)")
    parser.add_argument("--arm-duration", type=float, default=ARM_DURATION_S,
                        help=f"length of each arm recording, s (default {ARM_DURATION_S:g})")
    parser.add_argument("--arm-source", choices=("auto", "menagerie", "builtin"), default="auto",
                        help="arms from mujoco-menagerie, the built-in MJCF, or Menagerie where it can be had (default)")
    return parser.parse_args()


def main():
    args = parse_args()
    start = time.perf_counter()
    if args.arms or args.stuck_arms:
        arm_cases = STUCK_ARM_CASES if args.stuck_arms else ARM_CASES
        cases = [c for c in arm_cases if fnmatch.fnmatch(c.name, args.only)]
        run = lambda case: run_arm_case(case, args.seed, args.out, args.arm_source, args.arm_duration)  # noqa: E731
    else:
        cases = [c for c in mujoco_cases() + bullet_cases() + nothing_missing_cases() if fnmatch.fnmatch(c.name, args.only)]
        if any(c.engine == "bullet" and c.effects for c in cases):
            check_bullet_joint_damping()
        run = lambda case: run_case(case, args.seed, args.out)  # noqa: E731
    if not cases:
        raise SystemExit(f"no case matches {args.only!r}")
    for case in cases:
        print(run(case), flush=True)
    rows = sum(check_case_folder(os.path.join(args.out, case.name)) for case in cases)
    print(f"{len(cases)} cases, {rows} samples, written and parsed in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
