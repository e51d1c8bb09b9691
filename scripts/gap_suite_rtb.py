#!/usr/bin/env python3
"""Multi-joint arm recordings made by the Robotics Toolbox for Python (PyPI roboticstoolbox-python: Corke's
recursive Newton-Euler with its motor and friction model), of the
Unimation PUMA 560 as the toolbox ships it (`models.DH.Puma560`): the dynamics identified on the real robot
(Armstrong, Khatib and Burdick 1986; Corke and Armstrong-Hélouvry 1994), its link masses and inertias, and per joint
the motor's rotor inertia, gear ratio, viscous and direction-dependent Coulomb friction. The same case format as
gap_suite.py, cases named rtb_*.

    gap_suite_rtb.py --out DIR [--seed N] [--only PATTERN]

Needs scripts/gap_suite_rtb_requirements.txt (roboticstoolbox-python, Pinocchio, numpy) beside gap_suite.py's (whose helpers
this uses). Every case is a folder DIR/<case>/ with model.urdf, recording.csv and truth.json exactly as gap_suite.py
describes them; truth.json's "engine" is "roboticstoolbox-python <version>".

Model: model.urdf holds the toolbox's rigid bodies, written from its standard Denavit-Hartenberg parameters (a joint
frame per DH frame before its rotation; each link's centre of mass and inertia tensor about it from the DH frame
after), and is checked against the toolbox's own inverse dynamics (`rne`, motors and friction off) at random states
to 1e-9 (`check_urdf`). The toolbox's link 1 has no mass and a rank-one inertia (0.35 kg m^2 about the joint, 0
across): the engine and model.urdf both take the same link with 0.175 kg m^2 across, which the motion cannot see
(link 1 only turns about its own joint).

Engine: the toolbox's forward dynamics (`accel`: its rne's mass matrix, bias and friction) stepped by semi-implicit
Euler at 1 ms (its own `fdyn`, scipy's adaptive RK45, stalls on a friction that is exactly a sign function), gravity
-9.81 z, efforts held between samples as the spec says. What the toolbox adds to each joint, in model.urdf's terms (the joint side of
the gear, as `Link.friction` and `rne` compute it): a rotor inertia G^2 Jm (`armature`), viscous friction G^2 B
(`viscous_damping`) and Coulomb friction |G| Tc+ while the joint turns forward, |G| |Tc-| backward
(`coulomb_friction` with `friction_reverse`; exactly a sign function: no smooth transition, no stiction). None at a
speed of exactly 0, which the steps never hold: a joint the friction holds chatters about zero speed within a step's
worth of it, and the sign law holds it, as the spec's law does.
Excitation: gap_suite.arm_excitation (computed torque with model.urdf plus the rotor inertia a controller knows from
the data sheet, around a slow 3-sine target, plus 3 sines per joint), here with the feed-forward of the friction the
toolbox ships too (a controller of a geared arm compensates its known friction; without it the PUMA's 25 N m of dry
friction on joint 1 narrows its swing, +-0.20 rad against +-0.28 at seed 0), decided at 200 Hz and held, 20 s; the
case rtb_puma560_plain_drive leaves the feed-forward out, as a plain drive does: the dry friction then holds the joints
still at and around their reversals, 14-53 % of the time (a stick-slip arm). Noise: 1e-4 rad on positions, 1 %
of each joint's RMS effort on efforts.
"""
import math
import os
from dataclasses import dataclass
from importlib import metadata

import numpy as np
import roboticstoolbox as rtb

import gap_suite as gs
import gap_suite_bullet_arms as bullet
from gap_suite import DT

DURATION_S, RATE_HZ = 20.0, 200
ENGINE = f"roboticstoolbox-python {metadata.version('roboticstoolbox-python')}"
JOINTS = [f"joint{i}" for i in range(1, 7)]
# The pose the excitation swings about: the toolbox's "qn" (arm out, elbow up, wrist bent).
HOME = np.array([0.0, math.pi / 4, -math.pi, 0.0, math.pi / 4, 0.0])


@dataclass
class RtbCase:
    name: str
    description: str
    motors: bool  # the toolbox's motors: rotor inertia and friction (all as shipped)
    model_error: float = 0.0  # model.urdf's masses and inertia tensors scaled by up to this share, link by link
    feedforward: bool = True  # the toolbox's friction fed forward by the excitation (with motors only)
    engine: str = "rtb"
    duration: float = DURATION_S
    rate: int = RATE_HZ


def cases():
    return [
        RtbCase("rtb_puma560_none", "PUMA 560, its motors' inertia and friction off: nothing missing", motors=False),
        RtbCase("rtb_puma560_published", "PUMA 560 as the toolbox ships it: every joint's rotor inertia, viscous and "
                "direction-dependent Coulomb friction, none in model.urdf", motors=True),
        RtbCase("rtb_puma560_identified_model", "PUMA 560 as the toolbox ships it, against a model.urdf whose masses "
                "and inertias are up to 5 % off (an identified model's error)", motors=True, model_error=0.05),
        RtbCase("rtb_puma560_plain_drive", "PUMA 560 as the toolbox ships it, its friction not fed forward: the "
                "computed-torque drive alone, against which the dry friction holds the joints still for 14-53 % of "
                "the time", motors=True, feedforward=False),
    ]


def puma(motors):
    """The toolbox's PUMA 560, with link 1's inertia across its axis made physical (see the module doc); without
    `motors`, no rotor inertia and no friction."""
    robot = rtb.models.DH.Puma560()
    robot.links[0].I = np.diag([0.175, 0.35, 0.175])
    if not motors:
        robot = robot.nofriction(coulomb=True, viscous=True)
        for link in robot.links:
            link.Jm = 0.0
    robot.dynchanged()
    return robot


def joint_effects(robot):
    """What the toolbox's motors add on each joint, in model.urdf's terms (truth.json's effects)."""
    out = []
    for name, link in zip(JOINTS, robot.links):
        g = abs(link.G)
        if link.Jm > 0:
            out.append(gs.Effect(name, "armature", {"armature": float(g * g * link.Jm)}))
        if link.B > 0:
            out.append(gs.Effect(name, "viscous_damping", {"damping": float(g * g * link.B)}))
        if link.Tc[0] != 0 or link.Tc[1] != 0:
            out.append(gs.Effect(name, "coulomb_friction",
                                 {"friction": float(g * link.Tc[0]), "friction_reverse": float(-g * link.Tc[1])}))
    return out


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def urdf_text(robot):
    """model.urdf of a standard-DH robot's rigid bodies: link i's frame is DH frame i-1 turned by joint i (axis z);
    DH frame i sits at (a_i, 0, d_i) in it, turned by alpha_i about x, and holds link i's centre of mass and
    inertia tensor. Only what the PUMA has: revolute joints without offsets or flips, the base and the tool where
    the world and the last frame are (check_urdf cannot see limits, nor a base the gravity does not turn)."""
    plain = np.allclose(np.asarray(robot.base.A), np.eye(4)) and np.allclose(np.asarray(robot.tool.A), np.eye(4))
    for link in robot.links:
        plain = plain and link.isrevolute and link.offset == 0.0 and not link.isflip
    if not plain:
        raise gs.SuiteError("urdf_text writes revolute standard-DH joints without offsets or flips, at an identity base")
    num = gs.num
    out = ['<robot name="puma560">', '  <link name="base"/>']
    parent, above = "base", (0.0, 0.0, 0.0)
    for i, (name, link) in enumerate(zip(JOINTS, robot.links)):
        child = f"link{i + 1}"
        com = np.array([link.a, 0.0, link.d]) + rot_x(link.alpha) @ np.asarray(link.r, float)
        inertia = np.asarray(link.I, float)
        out += [f'  <link name="{child}">', "    <inertial>",
                f'      <origin xyz="{num(com[0])} {num(com[1])} {num(com[2])}" rpy="{num(link.alpha)} 0 0"/>',
                f'      <mass value="{num(link.m)}"/>',
                f'      <inertia ixx="{num(inertia[0, 0])}" ixy="{num(inertia[0, 1])}" ixz="{num(inertia[0, 2])}" '
                f'iyy="{num(inertia[1, 1])}" iyz="{num(inertia[1, 2])}" izz="{num(inertia[2, 2])}"/>',
                "    </inertial>", "  </link>"]
        lo, hi = link.qlim
        a, d, alpha = above
        out += [f'  <joint name="{name}" type="revolute">', f'    <parent link="{parent}"/>', f'    <child link="{child}"/>',
                f'    <origin xyz="{num(a)} 0 {num(d)}" rpy="{num(alpha)} 0 0"/>', '    <axis xyz="0 0 1"/>',
                f'    <limit lower="{num(lo)}" upper="{num(hi)}" effort="1000" velocity="10"/>', "  </joint>"]
        parent, above = child, (link.a, link.d, link.alpha)
    return "\n".join(out + ["</robot>", ""])


class RtbArm:
    """The toolbox's robot as a gap_suite sim (set_state, state, hold, advance, dynamics, close)."""

    def __init__(self, robot):
        self.robot = robot
        self.names = list(JOINTS)
        self.lo, self.hi = robot.qlim[0].copy(), robot.qlim[1].copy()
        self.q, self.qd, self.effort = np.zeros(6), np.zeros(6), np.zeros(6)

    def set_state(self, q, qd):
        self.q, self.qd = np.asarray(q, float).copy(), np.asarray(qd, float).copy()

    def state(self):
        return self.q.copy(), self.qd.copy()

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()

    def advance(self, steps):
        """`steps` semi-implicit Euler steps of DT with the toolbox's forward dynamics (`accel`). Not its `fdyn`:
        scipy's adaptive RK45 cannot step through a friction that is exactly a sign function (it halves its step
        at every reversal and every stick; the toolbox's documentation says so), and a robot's controller and
        every engine of the suite step at a fixed rate anyway."""
        for _ in range(int(steps)):
            qdd = np.asarray(self.robot.accel(self.q, self.qd, self.effort), float)
            self.qd = self.qd + DT * qdd
            self.q = self.q + DT * self.qd

    def dynamics(self, q, qd):
        """(M(q), bias(q, qd)) of the toolbox's `rne`: M with the rotor inertia where the robot has it, the bias
        with gravity, velocity products and friction."""
        q, qd = np.asarray(q, float), np.asarray(qd, float)
        return np.asarray(self.robot.inertia(q)), np.asarray(self.robot.rne(q, qd, np.zeros(6)))

    def close(self):
        pass


def check_urdf(text, robot, rng, states=20):
    """model.urdf's inverse dynamics (Pinocchio's RNEA, from the URDF text) against the toolbox's rne at random
    states, relative to the largest effort. Pinocchio, not MuJoCo: the toolbox's link 3 inertia breaks the triangle
    inequality (0.066 + 0.0125 < 0.086 kg m^2, as published), which MuJoCo's compiler refuses."""
    import pinocchio

    model = pinocchio.buildModelFromXML(text)
    model.gravity.linear[:] = (0.0, 0.0, -9.81)
    data = model.createData()
    worst = 0.0
    for _ in range(states):
        q, qd, qdd = rng.uniform(-1.5, 1.5, 6), rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        got = pinocchio.rnea(model, data, q, qd, qdd)
        want = np.asarray(robot.rne(q, qd, qdd))
        worst = max(worst, float(np.max(np.abs(got - want)) / max(1.0, float(np.max(np.abs(want))))))
    if worst > 1e-9:
        raise gs.SuiteError(f"model.urdf's inverse dynamics differ from the toolbox's rne by {worst:.2e} (relative)")
    return worst


def friction_feedforward(engine, source):
    """The excitation with the toolbox's own friction at the joint's speed compensated (the law as shipped)."""

    def effort(k, t, q, qd):
        return source(k, t, q, qd) - np.array([link.friction(v) for link, v in zip(engine.links, qd)])

    return effort


def run_case(case, seed, out):
    rng = gs.case_rng(seed, case.name)
    engine = puma(case.motors)
    rigid = puma(False)
    text = urdf_text(rigid)
    check_urdf(text, rigid, rng)
    if case.model_error > 0:
        # What the controller and model.urdf know: every link's mass and inertia tensor scaled alike (its centre of
        # mass kept), as gap_suite_bullet_arms.identified draws it.
        for link in rigid.links:
            factor = 1.0 + rng.uniform(-case.model_error, case.model_error)
            link.m, link.I = link.m * factor, np.asarray(link.I, float) * factor
        rigid.dynchanged()  # the toolbox's compiled rne keeps the parameters it was first given otherwise
        text = urdf_text(rigid)
        check_urdf(text, rigid, rng)
    nominal = RtbArm(rigid)
    plant = RtbArm(engine)
    armature = np.array([link.G ** 2 * link.Jm for link in engine.links])
    q0, source = gs.arm_excitation(nominal, armature, HOME, plant.lo, plant.hi, rng)
    if case.motors and case.feedforward:
        source = friction_feedforward(engine, source)
    traj = gs.simulate(plant, gs.sample_steps(case.duration, case.rate, False, rng), q0, source)
    table, effort_sigma = bullet.noisy_table(traj, JOINTS, rng)
    folder = os.path.join(out, case.name)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "model.urdf"), "w", encoding="utf-8") as f:
        note = "; masses and inertias drawn up to 5 % off (an identified model)" if case.model_error > 0 else ""
        f.write(f"<!-- roboticstoolbox-python models.DH.Puma560: rigid bodies only (no motors, no friction){note} -->\n" + text)
    gs.write_csv(os.path.join(folder, "recording.csv"), table, {"model": "model.urdf", "gravity": "0 0 -9.81"})
    model_effort = gs.inverse_dynamics(nominal, traj, np.gradient(traj.qd, traj.t, axis=0))
    effects = joint_effects(engine) if case.motors else []
    truth = {
        "format": gs.TRUTH_FORMAT, "engine": ENGINE, "case": case.name, "description": case.description,
        "effects": [{"joint": e.joint, "kind": e.kind, "params": e.params,
                     "engine_detail": "the toolbox's motor model (Link.Jm, B, Tc, G) as shipped"} for e in effects],
        "joints": JOINTS,
        "engine_detail": f"{ENGINE}, models.DH.Puma560, accel stepped by semi-implicit Euler at {DT} s, gravity -9.81 z",
        "seed": seed, "duration_s": case.duration, "rate_hz": case.rate, "timestep_s": DT, "sampling": "uniform",
        "observed": "joint positions",
        "noise": {"q_rad": 1e-4, **{f"{n}.effort": gs.sig3(s) for n, s in effort_sigma.items()}},
        "dropouts": 0.0,
        "excitation": "computed torque with model.urdf plus the rotor inertia (1.5 Hz, damping ratio 0.7) around a "
                      "slow 3-sine target (0.05-0.3 Hz) + 3 sines per joint (0.5-3 Hz)"
                      + (", the toolbox's friction fed forward" if case.motors and case.feedforward else "")
                      + ", decided at 200 Hz and held (gap_suite.arm_excitation)",
        "visibility_effort_share": gs.effect_shares(effects, JOINTS, traj, model_effort),
    }
    gs.write_json(os.path.join(folder, "truth.json"), truth)
    return gs.summary_line(case, traj, truth)


if __name__ == "__main__":
    gs.engine_suite_main(cases, run_case)
