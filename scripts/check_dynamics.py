#!/usr/bin/env python3
"""Checks partscene's multibody dynamics against Pinocchio and MuJoCo on public robot URDFs.

    check_dynamics.py [--bin PATH] [--states N] [--seed S] [--self-test]

For each model (URDFs shipped by the `example-robot-data` wheel, found at run time through
importlib.metadata, plus a small branched prismatic/revolute/continuous URDF written here),
draws N seeded random states (q inside URDF limits, qd, qdd, tau) and runs

    partscene dynamics --model MODEL.urdf --states STATES.json --out OUT.json

(by default `cargo run --release --quiet --no-default-features -- dynamics ...` in the repo
root; `--bin PATH` runs a built binary instead). Its answers are compared, per state, with
  - Pinocchio (fixed base, mimic joints as independent joints): rnea -> tau, crba -> mass
    matrix, nonLinearEffects -> bias, aba -> qdd;
  - MuJoCo on a copy of the URDF without geometry and with passive forces zeroed: mj_rne ->
    tau, mj_fullM -> mass matrix, qfrc_bias -> bias, mj_solveM(tau - bias) -> qdd. Models MuJoCo
    refuses to compile (massless moving links, inertias it finds invalid) are checked against
    Pinocchio only, with the reason printed.
Convention: tau = M(q) qdd + bias(q, qd), gravity from STATES.json. The joints in STATES.json
are every movable URDF joint in a seeded shuffled order, so the CLI must map them by name.
Error = |ours - ref| / max(|ref|, 1e-12) (2-norm; Frobenius for M), worst over the states;
limits 1e-9 for tau, M and bias and 1e-8 for qdd. One line per model; exits 1 on any failure.

--self-test needs no partscene: it compares MuJoCo against Pinocchio through the same state
mapping, which shows the references (and the mapping) agree.

Setup: python3 -m venv /tmp/dyn-venv &&
       /tmp/dyn-venv/bin/pip install -r scripts/check_dynamics_requirements.txt
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from importlib.metadata import distribution

import mujoco
import numpy as np
import pinocchio as pin

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROBOTS = "cmeel.prefix/share/example-robot-data/robots"
MODELS = [  # (name, path under ROBOTS)
    ("panda", "panda_description/urdf/panda.urdf"),
    ("ur5", "ur_description/urdf/ur5_robot.urdf"),
    ("double_pendulum", "double_pendulum_description/urdf/double_pendulum_continuous.urdf"),
    ("kinova", "kinova_description/robots/kinova.urdf"),
    ("solo12", "solo_description/robots/solo12.urdf"),
    ("simple_humanoid", "simple_humanoid_description/urdf/simple_humanoid_classical.urdf"),
    ("baxter", "baxter_description/urdf/baxter.urdf"),
    ("tiago", "tiago_description/robots/tiago_no_hand.urdf"),
    ("human", "human_description/robots/human.urdf"),
]
STANDARD_GRAVITY = [0.0, 0.0, -9.81]
TOY_GRAVITY = [0.4, -1.1, -9.7]  # tilted, so a wrong gravity frame shows
TOL = {"tau": 1e-9, "mass_matrix": 1e-9, "bias": 1e-9, "qdd": 1e-8}
ABS_FLOOR = 1e-12
MOVABLE = ("revolute", "continuous", "prismatic")

# Branched at two links, a weld in the middle, unaligned axes, rotated origins, full inertias.
TOY_URDF = """<?xml version="1.0"?>
<robot name="toy_branched">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  {links}
  <joint name="slider" type="prismatic"><parent link="base"/><child link="carriage"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.3 -0.2 0.5"/><axis xyz="0.6 0 0.8"/>
    <limit lower="-0.4" upper="0.6" effort="100" velocity="1"/></joint>
  <joint name="weld" type="fixed"><parent link="carriage"/><child link="plate"/>
    <origin xyz="0 0.15 0.05" rpy="0.7 0 -0.4"/></joint>
  <joint name="elbow" type="revolute"><parent link="plate"/><child link="arm"/>
    <origin xyz="0.2 0 0.1" rpy="0 0.4 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2.5" effort="50" velocity="2"/></joint>
  <joint name="wrist" type="continuous"><parent link="arm"/><child link="hand"/>
    <origin xyz="0.3 0.02 -0.05" rpy="-0.2 0.1 0.3"/><axis xyz="0.48 0.6 0.64"/></joint>
  <joint name="finger" type="prismatic"><parent link="arm"/><child link="finger_link"/>
    <origin xyz="0.25 -0.05 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.08" effort="10" velocity="0.5"/></joint>
  <joint name="side" type="revolute"><parent link="carriage"/><child link="side_link"/>
    <origin xyz="-0.1 0 0.2" rpy="1.2 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="20" velocity="2"/></joint>
</robot>
"""
TOY_LINK = """<link name="{name}"><inertial><origin xyz="{com}" rpy="{rpy}"/>
    <mass value="{mass}"/><inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0.001" ixz="-0.002"
    iyz="0.0015"/></inertial></link>"""


def toy_urdf():
    links = [("carriage", "0.05 0.02 -0.03", "0.1 0.2 0.3", 1.5),
             ("plate", "0 0.1 0", "0 0 0", 0.8),
             ("arm", "0.15 0 0.01", "-0.3 0 0.2", 1.2),
             ("hand", "0.02 -0.01 0.04", "0 0.5 0", 0.4),
             ("finger_link", "0 0 0.02", "0 0 0", 0.05),
             ("side_link", "0 0.1 0.05", "0.2 0.2 0.2", 0.6)]
    text = "\n  ".join(TOY_LINK.format(name=n, com=c, rpy=r, mass=m) for n, c, r, m in links)
    return TOY_URDF.format(links=text)


def urdf_joints(path):
    """Movable joints in document order: [(name, type, (lower, upper) or None)]."""
    joints = []
    for j in ET.parse(path).getroot().iter("joint"):
        kind = j.get("type")
        if kind not in MOVABLE:
            continue
        lim = j.find("limit")
        bounds = None
        if kind != "continuous" and lim is not None:
            lo, hi = float(lim.get("lower", 0)), float(lim.get("upper", 0))
            bounds = (lo, hi) if lo < hi else None
        joints.append((j.get("name"), kind, bounds))
    return joints


def random_states(rng, joints, n):
    """q inside limits (else a plausible range), qd, qdd; tau is filled in later."""
    states = []
    for _ in range(n):
        q = [rng.uniform(*(b or ((-0.5, 0.5) if k == "prismatic" else (-math.pi, math.pi))))
             for _, k, b in joints]
        states.append({"q": np.array(q), "qd": rng.uniform(-2, 2, len(joints)),
                       "qdd": rng.uniform(-5, 5, len(joints))})
    return states


class PinRef:
    """Pinocchio on the URDF, indexed in the given joint order."""

    def __init__(self, path, names, gravity):
        self.model = pin.buildModelFromUrdf(path)
        self.model.gravity.linear = np.array(gravity, dtype=float)
        self.data = self.model.createData()
        assert self.model.nv == len(names), f"pinocchio nv {self.model.nv} != {len(names)}"
        assert not self.model.armature.any(), "pinocchio armature is not zero"
        joints = [self.model.joints[self.model.getJointId(n)] for n in names]
        assert all(j.nv == 1 for j in joints), "pinocchio joint with nv != 1"
        self.joints = joints
        self.iv = np.array([j.idx_v for j in joints])

    def config(self, q):
        out = pin.neutral(self.model)
        for j, x in zip(self.joints, q):
            out[j.idx_q:j.idx_q + j.nq] = [x] if j.nq == 1 else [math.cos(x), math.sin(x)]
        return out

    def velocity(self, x):
        out = np.zeros(self.model.nv)
        out[self.iv] = x
        return out

    def inverse(self, q, qd, qdd):
        m, d = self.model, self.data
        return pin.rnea(m, d, self.config(q), self.velocity(qd), self.velocity(qdd))[self.iv]

    def compute(self, s):
        m, d, iv = self.model, self.data, self.iv
        q, v = self.config(s["q"]), self.velocity(s["qd"])
        full = pin.crba(m, d, q)
        full = np.triu(full) + np.triu(full, 1).T  # no-op where crba already fills both halves
        return {"tau": self.inverse(s["q"], s["qd"], s["qdd"]),
                "mass_matrix": full[np.ix_(iv, iv)],
                "bias": pin.nonLinearEffects(m, d, q, v)[iv],
                "qdd": pin.aba(m, d, q, v, self.velocity(s["tau"]))[iv]}


def mujoco_xml(path):
    """The URDF without geometry, with compiler options that keep every link as it is."""
    root = ET.parse(path).getroot()
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for e in link.findall(tag):
                link.remove(e)
    for e in root.findall("mujoco"):
        root.remove(e)
    ET.SubElement(ET.SubElement(root, "mujoco"), "compiler", discardvisual="true",
                  fusestatic="false", balanceinertia="false", inertiafromgeom="false")
    return ET.tostring(root, encoding="unicode")


class MjRef:
    """MuJoCo on the stripped URDF, passive forces off, indexed in the given joint order."""

    def __init__(self, path, joints, gravity):
        m = mujoco.MjModel.from_xml_string(mujoco_xml(path))
        names = [n for n, _, _ in joints]
        found = sorted(m.joint(i).name for i in range(m.njnt))
        if found != sorted(names) or m.nv != len(names):
            raise ValueError(f"MuJoCo has joints {found}, nv {m.nv}")
        kinds = {"prismatic": mujoco.mjtJoint.mjJNT_SLIDE}
        for n, k, _ in joints:
            want = kinds.get(k, mujoco.mjtJoint.mjJNT_HINGE)
            assert m.jnt_type[m.joint(n).id] == want, f"MuJoCo joint {n} has the wrong type"
        assert not m.dof_armature.any(), "MuJoCo armature is not zero"
        for field in (m.dof_damping, m.dof_frictionloss, m.jnt_stiffness, m.body_gravcomp):
            field[:] = 0
        m.opt.gravity[:] = gravity
        self.model, self.data = m, mujoco.MjData(m)
        self.iq = np.array([m.jnt_qposadr[m.joint(n).id] for n in names])
        self.iv = np.array([m.jnt_dofadr[m.joint(n).id] for n in names])

    def compute(self, s):
        m, d, iv = self.model, self.data, self.iv
        d.qpos[self.iq], d.qvel[iv] = s["q"], s["qd"]
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        bias = d.qfrc_bias.copy()
        rhs = np.zeros((1, m.nv))
        rhs[0, iv] = s["tau"]
        rhs -= bias
        qdd = np.zeros((1, m.nv))
        mujoco.mj_solveM(m, d, qdd, rhs)
        d.qacc[:] = 0
        d.qacc[iv] = s["qdd"]
        tau = np.zeros(m.nv)
        mujoco.mj_rne(m, d, 1, tau)
        return {"tau": tau[iv], "mass_matrix": full[np.ix_(iv, iv)], "bias": bias[iv],
                "qdd": qdd[0, iv]}


def run_partscene(args, path, names, gravity, states, tmp):
    """Runs `partscene dynamics`; returns its results as arrays (raises on a bad answer)."""
    states_path, out_path = os.path.join(tmp, "states.json"), os.path.join(tmp, "out.json")
    doc = {"joints": names, "gravity": gravity,
           "states": [{k: s[k].tolist() for k in ("q", "qd", "qdd", "tau")} for s in states]}
    with open(states_path, "w") as f:
        json.dump(doc, f)
    cmd = ([args.bin] if args.bin else
           ["cargo", "run", "--release", "--quiet", "--no-default-features", "--"])
    cmd += ["dynamics", "--model", path, "--states", states_path, "--out", out_path]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"exit {proc.returncode}: {proc.stderr.strip()[-2000:]}")
    with open(out_path) as f:
        out = json.load(f)
    if out.get("joints") != names or len(out.get("results", [])) != len(states):
        raise RuntimeError("OUT.json joints or number of results differ from STATES.json")
    n = len(names)
    shapes = {"tau": (n,), "mass_matrix": (n, n), "bias": (n,), "qdd": (n,)}
    results = [{k: np.array(r[k], dtype=float) for k in shapes} for r in out["results"]]
    for r in results:
        for k, shape in shapes.items():
            if r[k].shape != shape:
                raise RuntimeError(f"{k} has shape {r[k].shape}, want {shape}")
    return results


def worst_errors(got, ref):
    """Worst relative error per quantity over the states."""
    def err(a, b):
        return np.linalg.norm(a - b) / max(np.linalg.norm(b), ABS_FLOOR)
    return {k: max(err(g[k], r[k]) for g, r in zip(got, ref)) for k in TOL}


def describe(label, errors):
    short = {k: "M" if k == "mass_matrix" else k for k in TOL}
    bad = [short[k] for k in TOL if not errors[k] <= TOL[k]]  # NaN fails
    text = " ".join(f"{short[k]} {errors[k]:.1e}" for k in TOL)
    return f"{label}: {text}" + (f" FAIL({','.join(bad)})" if bad else ""), not bad


def mujoco_refs(path, joints, gravity, states):
    """MuJoCo's answers, or None and the reason MuJoCo cannot take the model."""
    try:
        ref = MjRef(path, joints, gravity)
    except (ValueError, AssertionError) as e:
        return None, " ".join(str(e).split())
    return [ref.compute(s) for s in states], None


def check_model(args, index, name, path, gravity, tmp):
    """Checks one model; prints its line and returns whether it passed."""
    rng = np.random.default_rng([args.seed, index])
    joints = urdf_joints(path)
    joints = [joints[i] for i in rng.permutation(len(joints))]
    names = [n for n, _, _ in joints]
    pin_ref = PinRef(path, names, gravity)
    states = random_states(rng, joints, args.states)
    for s in states:  # a torque that gives a well-scaled acceleration
        s["tau"] = pin_ref.inverse(s["q"], s["qd"], rng.uniform(-5, 5, len(names)))
    refs = {"pinocchio": [pin_ref.compute(s) for s in states]}
    refs["mujoco"], skip = mujoco_refs(path, joints, gravity, states)
    head = f"{name:16s} {len(names):2d} dof  "
    if args.self_test:
        pairs = [("mujoco", refs["mujoco"], "pinocchio", refs["pinocchio"])] if not skip else []
    else:
        try:
            got = run_partscene(args, path, names, gravity, states, tmp)
        except (RuntimeError, OSError, ValueError, KeyError, TypeError, AttributeError) as e:
            print(head + f"partscene FAILED: {' '.join(str(e).split())}", flush=True)
            return False
        pairs = [("partscene", got, k, v) for k, v in refs.items() if v is not None]
    parts, ok = [], True
    for who, got, ref_name, ref in pairs:
        line, good = describe(f"{who} vs {ref_name}", worst_errors(got, ref))
        parts.append(line)
        ok &= good
    if skip:
        parts.append(f"mujoco skipped: {skip}")
    print(head + " | ".join(parts), flush=True)
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", help="built partscene binary (default: cargo run --release)")
    ap.add_argument("--states", type=int, default=20, help="random states per model")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--self-test", action="store_true",
                    help="compare MuJoCo with Pinocchio only (no partscene needed)")
    args = ap.parse_args()
    if args.bin and os.sep in args.bin:
        args.bin = os.path.abspath(args.bin)  # the CLI runs in the repo root
    robots = distribution("example-robot-data").locate_file(ROBOTS)
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        toy = os.path.join(tmp, "toy_branched.urdf")
        with open(toy, "w") as f:
            f.write(toy_urdf())
        models = [(n, str(robots / p), STANDARD_GRAVITY) for n, p in MODELS]
        models.append(("toy_branched", toy, TOY_GRAVITY))
        for index, (name, path, gravity) in enumerate(models):
            ok &= check_model(args, index, name, path, gravity, tmp)
    print("all models agree" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
