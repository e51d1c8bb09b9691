#!/usr/bin/env python3
"""Multi-joint arm recordings made by Bullet (PyPI pybullet, its multibody solver), of two robots that ship with
pybullet_data: the KUKA LBR iiwa 7 R800 (kuka_iiwa/model.urdf), a robot the MuJoCo arm suite does not have, and
the Franka Panda (franka_panda/panda.urdf: another project's model of an arm that suite builds itself), driven by
torques for 20 s at 200 Hz, the size of recording issue 16 budgets. The same case format as gap_suite.py, cases
named bullet_iiwa_* and bullet_panda_*.

    gap_suite_bullet_arms.py --out DIR [--seed N] [--only PATTERN]

Needs the pinned packages of gap_suite_requirements.txt (pybullet, numpy; mujoco only because gap_suite.py, whose
helpers this uses, imports it). Every case is a folder DIR/<case>/ with model.urdf, recording.csv and truth.json
exactly as gap_suite.py describes them; truth.json's "engine" is "pybullet <version>".

Model: the robot's URDF as shipped (its masses, centres of mass and inertia tensors), with the visual and collision
elements removed (no contact, no meshes needed), any <dynamics damping> removed (the iiwa's 0.5: the damping a case
adds is the only damping, so model.urdf says none) and the Panda's two finger joints welded (type fixed: the hand is
one rigid body). The engine loads that same text
(URDF_USE_INERTIA_FROM_FILE); the identified-model case then writes model.urdf with every link's mass and inertia
tensor scaled alike by a factor drawn within +-5 % (an identified model's error), the engine keeping the shipped
values.

Engine: pybullet DIRECT, fixed base, gravity -9.81 z, 1 ms steps, every link's linear and angular damping 0 (Bullet
damps every link by default). Efforts are TORQUE_CONTROL forces set again before every step (Bullet clears them
after each one), held between samples as the spec says. Concealed effects, each made the way Bullet users make it:
  coulomb_friction  a VELOCITY_CONTROL motor at target speed 0 whose force bound is the friction level (pybullet's
                    joint-friction idiom): a bounded impulse that sticks
  viscous_damping   changeDynamics(jointDamping=b), checked to act as -b*qd (gap_suite.check_bullet_joint_damping)
  gravity_tilt      of the base joint: setGravity leaning by tilt_deg (the whole robot stands tilted, model.urdf
                    level); equilibrium_position as gap_suite.lean_equilibrium says, from the engine's own frames
Excitation: gap_suite.arm_excitation, the MuJoCo arm suite's: computed torque with model.urdf (1.5 Hz, damping
ratio 0.7) around a slow 3-sine target inside the joint ranges, plus 3 sines per joint, decided at 200 Hz and held.
Noise: 1e-4 rad on positions, 1 % of each joint's RMS effort on efforts. The friction levels are sized to what the
excitation asks of each joint (the iiwa model's wrist links are light: 0.001-0.01 kg m^2 about their axes), so that
every joint slides, and the damping levels so that each is material (at least 3 % of the joint's effort, the least
`partscene gap` names; truth.json's visibility_effort_share has each one's share).
"""
import os
import re
from dataclasses import dataclass, field
from importlib import metadata

import numpy as np
import pybullet
import pybullet_data

import gap_suite as gs
from gap_suite import DT

DURATION_S, RATE_HZ = 20.0, 200


@dataclass
class Robot:
    """An arm of pybullet_data: its URDF (path inside pybullet_data), its 7 joints, the pose the excitation swings
    about."""

    key: str
    path: tuple
    joints: list
    home: np.ndarray


ROBOTS = {
    "iiwa": Robot("iiwa", ("kuka_iiwa", "model.urdf"), [f"lbr_iiwa_joint_{i}" for i in range(1, 8)],
                  np.array([0.0, 0.6, 0.0, -1.2, 0.0, 0.8, 0.0])),
    "panda": Robot("panda", ("franka_panda", "panda.urdf"), [f"panda_joint{i}" for i in range(1, 8)],
                   np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])),
}
ENGINE = f"pybullet {metadata.version('pybullet')}"


@dataclass
class Effect:
    joint: str
    kind: str
    params: dict


@dataclass
class ArmCase:
    name: str
    description: str
    robot: str = "iiwa"
    friction: list = field(default_factory=lambda: [0.0] * 7)
    damping: list = field(default_factory=lambda: [0.0] * 7)
    model_error: float = 0.0
    # (tilt_deg, toward): the robot stands on a base tilted by tilt_deg, the engine's gravity leaning towards the
    # world's horizontal direction at angle `toward` (gap_suite.tilted_gravity); model.urdf stands level.
    base_tilt: tuple = ()
    engine: str = "bullet"
    duration: float = DURATION_S
    rate: int = RATE_HZ

    @property
    def effects(self):
        """The concealed effects, as truth.json names them."""
        joints = ROBOTS[self.robot].joints
        out = [Effect(n, "coulomb_friction", {"friction": float(f)}) for n, f in zip(joints, self.friction) if f > 0]
        return out + [Effect(n, "viscous_damping", {"damping": float(b)}) for n, b in zip(joints, self.damping) if b > 0]


@dataclass
class RotorArmCase(ArmCase):
    """An arm case whose engine also has, per joint (in the robot's order), armature (reflected rotor inertia,
    kg m^2) and offset (the torque sensor's bias, N m): the Drake and Genesis arm suites'. Each says how its engine's
    friction level is parametrised (friction_params)."""

    armature: list = field(default_factory=lambda: [0.0] * 7)
    offset: list = field(default_factory=lambda: [0.0] * 7)

    def friction_params(self, level):
        """truth.json's parameters of a friction of `level` (N m)."""
        return {"friction": float(level)}

    @property
    def effects(self):
        """The concealed effects, as truth.json names them."""
        joints = ROBOTS[self.robot].joints
        kinds = (("coulomb_friction", self.friction, self.friction_params),
                 ("viscous_damping", self.damping, lambda b: {"damping": float(b)}),
                 ("armature", self.armature, lambda a: {"armature": float(a)}),
                 # The spec's offset adds to the recorded effort to give the felt one: minus the bias.
                 ("effort_offset", self.offset, lambda o: {"offset": -float(o)}))
        return [Effect(n, kind, params(v)) for kind, values, params in kinds for n, v in zip(joints, values) if v]


# How a sensor bias (RotorArmCase.offset) is made, in truth.json.
OFFSET_DETAIL = "minus the bias added to the recorded effort (a torque sensor's): the joint felt the recorded effort + offset"


FRICTION = [2.0, 2.0, 0.8, 0.8, 0.03, 0.02, 0.003]
PANDA_FRICTION = [1.0, 1.0, 0.8, 0.8, 0.3, 0.2, 0.05]
# Rotor inertia as a geared iiwa has it (the Drake and Genesis arm suites): a sizeable share of each joint's own
# inertia, more on the wrist.
IIWA_ROTOR = [0.3, 0.3, 0.1, 0.1, 0.02, 0.02, 0.005]


def cases():
    return [
        ArmCase("bullet_iiwa_none", "iiwa; nothing missing"),
        ArmCase("bullet_iiwa_friction", "iiwa; dry friction on every joint", friction=FRICTION),
        ArmCase("bullet_iiwa_damping", "iiwa; damping on joints 1, 3, 5, 7", damping=[1.0, 0.0, 0.3, 0.0, 0.005, 0.0, 0.0005]),
        ArmCase("bullet_iiwa_mixed", "iiwa; dry friction on joints 1, 3, 5, damping on 2, 4, 6",
                friction=[2.0, 0.0, 0.8, 0.0, 0.03, 0.0, 0.0], damping=[0.0, 1.0, 0.0, 0.3, 0.0, 0.004, 0.0]),
        ArmCase("bullet_iiwa_identified_model", "iiwa; dry friction on every joint, model.urdf's inertias up to 5 % off",
                friction=FRICTION, model_error=0.05),
        ArmCase("bullet_panda_none", "Panda; nothing missing", robot="panda"),
        ArmCase("bullet_panda_friction", "Panda; dry friction on every joint", robot="panda", friction=PANDA_FRICTION),
        ArmCase("bullet_panda_mixed", "Panda; dry friction on joints 1, 3, 5, 7, damping on 2, 4, 6", robot="panda",
                friction=[1.0, 0.0, 0.8, 0.0, 0.3, 0.0, 0.05], damping=[0.0, 1.0, 0.0, 0.5, 0.0, 0.2, 0.0]),
        ArmCase("bullet_panda_identified_model", "Panda; dry friction on every joint, model.urdf's inertias up to 5 % off",
                robot="panda", friction=PANDA_FRICTION, model_error=0.05),
        ArmCase("bullet_iiwa_tilted_base", "iiwa on a base tilted 0.7 deg (model.urdf level); dry friction on joints 1-4",
                friction=[2.0, 2.0, 0.8, 0.8, 0.0, 0.0, 0.0], base_tilt=(0.7, -0.9)),
    ]


def shipped_urdf(robot):
    """The robot's pybullet_data URDF without geometry, without joint damping of its own, its fingers welded."""
    with open(os.path.join(pybullet_data.getDataPath(), *robot.path), encoding="utf-8") as f:
        text = f.read()
    text = re.sub(r'\s*<dynamics damping="[^"]*"/>', "", text)
    text = text.replace('type="prismatic"', 'type="fixed"')
    return re.sub(r"\s*<(visual|collision)>.*?</\1>", "", text, flags=re.S)


def identified(text, share, rng):
    """Each link's mass and inertia tensor scaled alike by 1 + U(-share, share) (its centre of mass kept)."""

    def link(match):
        factor = 1.0 + rng.uniform(-share, share)
        scaled = re.sub(r'(<mass value=")([^"]+)(")', lambda m: f"{m[1]}{float(m[2]) * factor:.9g}{m[3]}", match[0])
        return re.sub(r'(i[xyz]{2}=")([^"]+)(")', lambda m: f"{m[1]}{float(m[2]) * factor:.9g}{m[3]}", scaled)

    return re.sub(r"<inertial>.*?</inertial>", link, text, flags=re.S)


ZERO_INERTIAL = ('<inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'
                 '</inertial>')


def massless_made_explicit(text):
    """Every link of no mass made massless alike, its rotational inertia zeroed (and one without an <inertial> given
    that zero one): readers disagree on a link of mass 0 with rotational inertia (the Panda's link 8 and grasp
    target: 0.1 kg m^2 each), which no body has. Drake's parser replaces it by 1 kg at the link's origin, Bullet
    keeps its inertia, MuJoCo drops it (gap_suite_drake_arms.py and gap_suite_genesis_arms.py load it so)."""

    def inertial(match):
        mass = re.search(r'<mass\s+value="([^"]+)"', match[0])
        return ZERO_INERTIAL if mass is None or float(mass[1]) == 0.0 else match[0]

    def link(match):
        whole = match[0]
        if "<inertial>" in whole:
            return re.sub(r"<inertial>.*?</inertial>", inertial, whole, flags=re.S)
        if whole.endswith("/>"):
            return whole[:-2].rstrip() + f">{ZERO_INERTIAL}</link>"
        return whole.replace("</link>", f"{ZERO_INERTIAL}</link>")

    return re.sub(r"<link\s[^>]*?/>|<link\s[^>]*?>.*?</link>", link, text, flags=re.S)


class BulletArm(gs.BulletSim):
    """An arm in pybullet DIRECT, loaded from URDF text: gap_suite.BulletSim's stepping (TORQUE_CONTROL before
    every step), state and dynamics, with friction motors and joint damping per joint (`joints`, in order)."""

    def __init__(self, text, joints, friction, damping, gravity=gs.GRAVITY):  # noqa: super().__init__ builds from gap_suite's mechanisms
        self.cid = pybullet.connect(pybullet.DIRECT)
        path = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"gap_suite_bullet_arm_{os.getpid()}.urdf")
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        try:
            self.body = pybullet.loadURDF(path, useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
                                          physicsClientId=self.cid)
        finally:
            os.remove(path)
        pybullet.setTimeStep(DT, physicsClientId=self.cid)
        pybullet.setGravity(*gravity, physicsClientId=self.cid)
        infos = [pybullet.getJointInfo(self.body, i, physicsClientId=self.cid)
                 for i in range(pybullet.getNumJoints(self.body, physicsClientId=self.cid))]
        index = {info[1].decode(): info[0] for info in infos}
        self.link_index = {info[12].decode(): info[0] for info in infos}
        self.names, self.idx = list(joints), [index[n] for n in joints]
        self.dof = [sorted(self.idx).index(i) for i in self.idx]
        self.lo, self.hi = np.array([infos[i][8] for i in self.idx]), np.array([infos[i][9] for i in self.idx])
        for link in [-1] + list(range(len(infos))):  # Bullet damps every link by default
            pybullet.changeDynamics(self.body, link, linearDamping=0.0, angularDamping=0.0, physicsClientId=self.cid)
        for i, b in zip(self.idx, damping):
            pybullet.changeDynamics(self.body, i, jointDamping=float(b), physicsClientId=self.cid)
        pybullet.setJointMotorControlArray(self.body, self.idx, pybullet.VELOCITY_CONTROL, targetVelocities=[0.0] * 7,
                                           forces=[float(f) for f in friction], physicsClientId=self.cid)
        self.effort = np.zeros(7)


def run_case(case, seed, out):
    rng = gs.case_rng(seed, case.name)
    robot = ROBOTS[case.robot]
    joints = robot.joints
    engine_text = shipped_urdf(robot)
    model_text = identified(engine_text, case.model_error, rng) if case.model_error > 0 else engine_text
    nominal = BulletArm(model_text, joints, [0.0] * 7, [0.0] * 7)
    gravity = gs.tilted_gravity(*case.base_tilt) if case.base_tilt else gs.GRAVITY
    plant = BulletArm(engine_text, joints, case.friction, case.damping, gravity)
    tilt = base_tilt_effect(plant, case) if case.base_tilt else None
    traj, table, effort_sigma = drive(plant, nominal, case, rng)
    source_path = "/".join(robot.path)
    model_effort = gs.inverse_dynamics(nominal, traj, np.gradient(traj.qd, traj.t, axis=0))
    tilt_effort = None
    if tilt is not None:
        tilted = BulletArm(model_text, joints, [0.0] * 7, [0.0] * 7, gravity)
        tilt_effort = np.array([tilted.dynamics(q, np.zeros(7))[1] - nominal.dynamics(q, np.zeros(7))[1] for q in traj.q])
        tilted.close()
    nominal.close()
    detail = {"coulomb_friction": "VELOCITY_CONTROL motor, target speed 0, force bound = friction",
              "viscous_damping": "changeDynamics(jointDamping)",
              "gravity_tilt": f"setGravity{tuple(round(g, 6) for g in gravity)}: the whole robot stands tilted"}
    engine_detail = (f"{ENGINE}, pybullet_data {source_path} (no geometry, no joint damping of its own, fingers welded), "
                     f"DIRECT, fixed base, {DT} s steps, link damping 0, torques through TORQUE_CONTROL set before every step")
    truth = arm_truth(ENGINE, case, seed, (detail, engine_detail), traj, effort_sigma, model_effort, (tilt, tilt_effort))
    write_arm_case(out, case, (model_text, shipped_note(robot, case)), table, truth)
    return gs.summary_line(case, traj, truth)


def shipped_note(robot, case):
    """What a case's model.urdf is, for a comment before its <robot>: the shipped URDF as shipped_urdf prepares it,
    and whether its inertias were drawn off (identified)."""
    note = f"pybullet_data {'/'.join(robot.path)} without geometry and without joint damping, fingers (if any) welded"
    return note + ("; inertial parameters drawn up to 5 % off (an identified model)" if case.model_error > 0 else "")


def write_arm_case(out, case, model, table, truth):
    """The case's folder DIR/<case>/: model.urdf (`model` is its text and the note put in a comment before its
    <robot>), recording.csv of `table` and truth.json."""
    model_text, note = model
    folder = os.path.join(out, case.name)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "model.urdf"), "w", encoding="utf-8") as f:
        f.write(model_text.replace("<robot ", f"<!-- {note} -->\n<robot ", 1))
    gs.write_csv(os.path.join(folder, "recording.csv"), table, {"model": "model.urdf", "gravity": "0 0 -9.81"})
    gs.write_json(os.path.join(folder, "truth.json"), truth)


def drive(plant, nominal, case, rng, offsets=None):
    """The plant driven by gap_suite.arm_excitation (computed torque with `nominal`) for the case's duration, then
    closed: (the trajectory, the recording's table with 1e-4 rad of noise on positions and 1 % of each joint's RMS
    effort on efforts, plus each joint's `offsets` (a torque sensor's bias), that effort noise per joint)."""
    joints = ROBOTS[case.robot].joints
    q0, source = gs.arm_excitation(nominal, np.zeros(7), ROBOTS[case.robot].home, plant.lo, plant.hi, rng)
    traj = gs.simulate(plant, gs.sample_steps(case.duration, case.rate, False, rng), q0, source)
    plant.close()
    table, effort_sigma = noisy_table(traj, joints, rng, offsets)
    return traj, table, effort_sigma


def noisy_table(traj, joints, rng, offsets=None):
    """The arm recording's table of `traj` (joints in order): 1e-4 rad of noise on positions and 1 % of each joint's
    RMS effort on efforts, plus each joint's `offsets` (a torque sensor's bias); and that effort noise per joint."""
    bias = np.zeros(len(joints)) if offsets is None else np.asarray(offsets, float)
    table = {"time": traj.t}
    table.update({f"{n}.q": traj.q[:, i] + rng.normal(0.0, 1e-4, len(traj.t)) for i, n in enumerate(joints)})
    effort_sigma = {n: 0.01 * gs.rms(traj.effort[:, i]) for i, n in enumerate(joints)}
    table.update({f"{n}.effort": traj.effort[:, i] + bias[i] + rng.normal(0.0, effort_sigma[n], len(traj.t))
                  for i, n in enumerate(joints)})
    return table, effort_sigma


def base_tilt_effect(plant, case):
    """The gravity_tilt of the case's base tilt on the robot's first joint (gap_suite.lean_equilibrium), from the
    engine's own frames at the zero pose."""
    for i in plant.idx:
        pybullet.resetJointState(plant.body, i, 0.0, 0.0, physicsClientId=plant.cid)
    first = plant.idx[0]
    frame = pybullet.getLinkState(plant.body, first, computeForwardKinematics=True, physicsClientId=plant.cid)[5]
    rot = np.array(pybullet.getMatrixFromQuaternion(frame)).reshape(3, 3)
    axis = pybullet.getJointInfo(plant.body, first, physicsClientId=plant.cid)[13]
    tilt_deg, toward = case.base_tilt
    return Effect(plant.names[0], "gravity_tilt",
                  {"tilt_deg": tilt_deg, "equilibrium_position": gs.lean_equilibrium(rot, axis, toward)})


def arm_truth(engine, case, seed, details, traj, effort_sigma, model_effort, tilted=(None, None)):
    """truth.json of an arm case recorded by `engine` with gap_suite.arm_excitation: `details` is (how the engine made
    each effect kind, how it made the recording), `effort_sigma` the noise put on each joint's effort, `model_effort`
    model.urdf's inverse dynamics along the motion (for the effects' shares); `tilted` the base tilt's effect and the
    efforts it adds along the motion, where the robot stands tilted."""
    detail, engine_detail = details
    joints = ROBOTS[case.robot].joints
    tilt, tilt_effort = tilted
    effects = case.effects + ([tilt] if tilt is not None else [])
    return {
        "format": gs.TRUTH_FORMAT, "engine": engine, "case": case.name, "description": case.description,
        "effects": [{"joint": e.joint, "kind": e.kind, "params": e.params, "engine_detail": detail[e.kind]} for e in effects],
        "joints": joints,
        "engine_detail": engine_detail,
        "seed": seed, "duration_s": case.duration, "rate_hz": case.rate, "timestep_s": DT, "sampling": "uniform",
        "observed": "joint positions",
        "noise": {"q_rad": 1e-4, **{f"{n}.effort": gs.sig3(s) for n, s in effort_sigma.items()}},
        "dropouts": 0.0,
        "excitation": "computed torque with model.urdf (1.5 Hz, damping ratio 0.7) around a slow 3-sine target "
                      "(0.05-0.3 Hz) + 3 sines per joint (0.5-3 Hz), decided at 200 Hz and held (gap_suite.arm_excitation)",
        "visibility_effort_share": gs.effect_shares(effects, joints, traj, model_effort, tilt_effort),
    }


if __name__ == "__main__":
    gs.engine_suite_main(cases, run_case, checks=[("viscous_damping", gs.check_bullet_joint_damping)])
