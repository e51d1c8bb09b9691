#!/usr/bin/env python3
"""Multi-joint arm recordings made by Drake (pydrake's MultibodyPlant, its SAP discrete solver), a third engine for
the arms after MuJoCo and Bullet, with dry friction as Drake's own DoorHinge force element makes it: smooth through
zero speed (tanh), the law real joints have. Two robots that ship with pybullet_data (another project's models),
the KUKA LBR iiwa 7 R800 and the Franka Panda, prepared exactly as gap_suite_bullet_arms.py prepares them, driven
by torques for 20 s at 200 Hz. The same case format as gap_suite.py, cases named drake_iiwa_* and drake_panda_*.

    gap_suite_drake_arms.py --out DIR [--seed N] [--only PATTERN]

Needs the pinned packages of gap_suite_drake_requirements.txt (drake, and gap_suite.py's). Every case is a folder
DIR/<case>/ with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's
"engine" is "drake <version>".

Engine: the robot's URDF text (geometry removed, no joint damping of its own, the Panda's fingers welded) parsed
by pydrake's Parser into a discrete MultibodyPlant (1 ms steps, discrete contact approximation kLagged, so the
SAP solver), its root link welded to the world, gravity -9.81 z, no collision geometry; one step is the plant's
own discrete update (ExecuteForcedEvents). Efforts are generalized forces on the applied generalized force input
port, set at each sample and held between samples; the actuation input (where a rotor makes an actuator) is held
at zero. The identified-model cases write model.urdf with every link's mass and inertia tensor scaled alike by a
factor drawn within +-5 % (gap_suite_bullet_arms.identified), the engine keeping the shipped values.

Concealed effects, each made the way Drake's API makes it:
  coulomb_friction  a DoorHinge force element on the joint with only its dynamic friction set:
                    -dynamic_friction_torque * tanh(qd / motion_threshold), explicit in the step; truth
                    friction = dynamic_friction_torque, transition_speed = motion_threshold
  viscous_damping   Joint.set_default_damping(b), implicit in SAP's step
  armature          a JointActuator with set_default_rotor_inertia(I_r) and set_default_gear_ratio(rho): Drake's
                    reflected inertia rho^2 I_r on the mass matrix's diagonal
  effort_offset     a constant added to the recorded effort (a torque sensor's bias), not engine physics; truth.json's
                    offset is minus it (the spec's offset adds to the recorded effort to give the felt one)
  gravity_tilt      of the base joint: the plant's gravity field leaning by tilt_deg (the whole robot stands
                    tilted, model.urdf level); equilibrium_position as gap_suite.lean_equilibrium says, from the
                    plant's own frames

Checks (a failure stops the run), per case before it is recorded:
  rigid bodies  Drake's joint-space inertia and bias force (CalcMassMatrix, CalcBiasTerm -
                CalcGravityGeneralizedForces) of the engine's plant without effects against model.urdf's engine
                text as MuJoCo reads it, at 5 random states, to 1e-9 relative (gap_suite.compare_dynamics).
  friction      the joints' generalized forces (CalcForceElementsContribution: the DoorHinge's and the joint's
                damping) at 5 speeds per joint against -friction * tanh(qd / transition_speed) - damping * qd, to
                1e-9 relative.
  armature      the plant's joint-space inertia with the rotors minus without them against the armature set, on
                the diagonal, to 1e-9 relative; nothing off it.
Excitation: gap_suite.arm_excitation, the MuJoCo and Bullet arm suites': computed torque with model.urdf (1.5 Hz,
damping ratio 0.7) around a slow 3-sine target inside the joint ranges, plus 3 sines per joint, decided at 200 Hz
and held; the controller knows none of the concealed effects. Noise: 1e-4 rad on positions, 1 % of each joint's
RMS effort on efforts. Levels: the Bullet suite's friction levels (sized to what the excitation asks of each
joint), smooth over 0.05 rad/s (within the 0.05-0.4 rad/s real joints' friction is smooth over); damping and rotor
inertia sized so that each is material (truth.json's visibility_effort_share has each one's share).
"""
import math
import re
from dataclasses import dataclass
from importlib import metadata

import mujoco
import numpy as np
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import DiscreteContactApproximation, MultibodyPlant
from pydrake.multibody.tree import DoorHinge, DoorHingeConfig, MultibodyForces

import gap_suite as gs
import gap_suite_bullet_arms as bullet
import gap_suite_drake
from gap_suite import DT, SuiteError

ENGINE = f"drake {metadata.version('drake')}"
TRANSITION_SPEED = 0.05  # rad/s: the DoorHinge's motion_threshold
GEAR_RATIO = 100.0  # a rotor of armature / GEAR_RATIO^2 behind this gear
CHECK_RTOL = 1e-9


@dataclass
class ArmCase(bullet.RotorArmCase):
    """The arm case with rotors and sensor biases (gap_suite_bullet_arms.RotorArmCase); friction is a DoorHinge's
    dynamic friction (N m), smooth over TRANSITION_SPEED."""

    engine: str = "drake"

    def friction_params(self, level):
        return {"friction": float(level), "transition_speed": TRANSITION_SPEED}


IIWA_FRICTION = bullet.FRICTION
PANDA_FRICTION = bullet.PANDA_FRICTION
# The Panda's rotor inertia, sized as bullet.IIWA_ROTOR is: a sizeable share of each joint's own inertia.
PANDA_ROTOR = [0.2, 0.2, 0.1, 0.1, 0.05, 0.05, 0.02]


def cases():
    return [
        ArmCase("drake_iiwa_none", "iiwa; nothing missing", "iiwa"),
        ArmCase("drake_iiwa_friction", "iiwa; smooth dry friction (DoorHinge) on every joint", "iiwa", friction=IIWA_FRICTION),
        ArmCase("drake_iiwa_rotor_damping", "iiwa; rotor inertia on every joint, damping on joints 2, 4, 6", "iiwa",
                damping=[0.0, 1.0, 0.0, 0.3, 0.0, 0.004, 0.0], armature=bullet.IIWA_ROTOR),
        ArmCase("drake_iiwa_identified_model", "iiwa; smooth dry friction on every joint, sensor biases on joints 2 "
                "and 4, model.urdf's inertias up to 5 % off", "iiwa", friction=IIWA_FRICTION,
                offset=[0.0, 1.0, 0.0, -0.5, 0.0, 0.0, 0.0], model_error=0.05),
        ArmCase("drake_panda_none", "Panda; nothing missing", "panda"),
        ArmCase("drake_panda_friction", "Panda; smooth dry friction (DoorHinge) on every joint", "panda",
                friction=PANDA_FRICTION),
        ArmCase("drake_panda_rotor_friction", "Panda; rotor inertia on every joint, smooth dry friction on joints 1, "
                "3, 5, 7, damping on 2", "panda", friction=[1.0, 0.0, 0.8, 0.0, 0.3, 0.0, 0.05],
                damping=[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0], armature=PANDA_ROTOR),
        ArmCase("drake_panda_identified_model", "Panda; smooth dry friction on every joint, model.urdf's inertias up "
                "to 5 % off", "panda", friction=PANDA_FRICTION, model_error=0.05),
        ArmCase("drake_panda_tilted_base", "Panda on a base tilted 0.8 deg (model.urdf level); smooth dry friction on "
                "joints 1-4", "panda", friction=[1.0, 1.0, 0.8, 0.8, 0.0, 0.0, 0.0], base_tilt=(0.8, 0.6)),
    ]


def root_link(text):
    """The URDF's root link: the one that is no joint's child."""
    links = re.findall(r'<link\s+name="([^"]+)"', text)
    children = set(re.findall(r'<child\s+link="([^"]+)"', text))
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise SuiteError(f"the arm's URDF has {len(roots)} root links")
    return roots[0]


class DrakeArm(gap_suite_drake.DrakeSim):
    """An arm in a discrete MultibodyPlant of its own, loaded from URDF text, with DoorHinge friction, joint damping
    and rotor inertia per joint (`joints`, in order): gap_suite_drake.DrakeSim's stepping, state and dynamics."""

    def __init__(self, text, joints, friction=None, damping=None, armature=None, gravity=gs.GRAVITY):  # noqa: DrakeSim builds from mechanisms
        n = len(joints)
        friction, damping, armature = (np.zeros(n) if x is None else np.asarray(x, float) for x in (friction, damping, armature))
        self.plant = MultibodyPlant(time_step=DT)
        self.plant.set_discrete_contact_approximation(DiscreteContactApproximation.kLagged)
        (instance,) = Parser(self.plant).AddModelsFromString(text, "urdf")
        self.plant.WeldFrames(self.plant.world_frame(), self.plant.GetBodyByName(root_link(text), instance).body_frame())
        self.plant.mutable_gravity_field().set_gravity_vector(np.array(gravity))
        self.names = list(joints)
        self.joints = [self.plant.GetJointByName(name, instance) for name in joints]
        for joint, f, b, a in zip(self.joints, friction, damping, armature):
            joint.set_default_damping(float(b))
            if f > 0.0:
                config = DoorHingeConfig()
                config.spring_zero_angle_rad = config.spring_constant = 0.0
                config.catch_width = config.catch_torque = 0.0
                config.static_friction_torque = config.viscous_friction = 0.0
                config.dynamic_friction_torque, config.motion_threshold = float(f), TRANSITION_SPEED
                self.plant.AddForceElement(DoorHinge(joint, config))
            if a > 0.0:
                actuator = self.plant.AddJointActuator(f"{joint.name()}_motor", joint)
                actuator.set_default_rotor_inertia(float(a) / GEAR_RATIO ** 2)
                actuator.set_default_gear_ratio(GEAR_RATIO)
        self.plant.Finalize()
        if self.plant.get_discrete_contact_solver().name != "kSap":
            raise SuiteError(f"Drake's discrete solver is {self.plant.get_discrete_contact_solver()}, SAP was expected")
        self.context = self.plant.CreateDefaultContext()
        if self.plant.num_actuators():
            self.plant.get_actuation_input_port().FixValue(self.context, np.zeros(self.plant.num_actuators()))
        self.qidx = [j.position_start() for j in self.joints]
        self.vidx = [j.velocity_start() for j in self.joints]
        self.lo = np.array([j.position_lower_limits()[0] for j in self.joints])
        self.hi = np.array([j.position_upper_limits()[0] for j in self.joints])
        self.effort = np.zeros(n)
        self.hold(self.effort)

    def force_elements(self, q, qd):
        """The generalized forces the plant's force elements apply at (q, qd): the DoorHinges' and the joints'
        damping (gravity, also a force element, acts as spatial forces on the bodies, not among these)."""
        self.set_state(q, qd)
        forces = MultibodyForces(self.plant)
        self.plant.CalcForceElementsContribution(self.context, forces)
        return forces.generalized_forces()[self.vidx].copy()


def check_rigid(bare, text, rng):
    """The engine's plant without effects (`bare`, of URDF `text`) against the same text as MuJoCo reads it, at 5
    random states."""
    mj = gs.MujocoSim(mujoco.MjSpec.from_string(text).compile(), bare.names)
    for _ in range(5):
        q, qd = rng.uniform(bare.lo, bare.hi), rng.normal(0.0, 1.0, len(bare.names))
        gs.compare_dynamics("Drake arm against MuJoCo", bare.dynamics(q, qd), mj.dynamics(q, qd), CHECK_RTOL)


def check_effects(plant, bare, case, rng):
    """The joints' generalized forces (a DoorHinge's friction and the joint's damping, which Drake counts among
    them) against -friction tanh(qd / transition_speed) - damping qd at 5 speeds per joint, and the rotors' inertia
    against the armature set, on the diagonal and nothing off it."""
    q = rng.uniform(plant.lo, plant.hi)
    for n, (f, b) in enumerate(zip(case.friction, case.damping)):
        for speed in (-1.0, -0.04, 0.003, 0.05, 0.7):
            qd = np.zeros(len(q))
            qd[n] = speed
            got, want = plant.force_elements(q, qd), np.zeros(len(q))
            want[n] = -f * math.tanh(speed / TRANSITION_SPEED) - b * speed
            if np.abs(got - want).max() > CHECK_RTOL * max(1.0, f, b):
                raise SuiteError(f"{case.name}: Drake's joint forces are {got} at joint {n} speed {speed}, {want} expected")
    added = plant.dynamics(q, np.zeros(len(q)))[0] - bare.dynamics(q, np.zeros(len(q)))[0]
    if np.abs(added - np.diag(case.armature)).max() > CHECK_RTOL * max(1.0, max(case.armature)):
        raise SuiteError(f"{case.name}: Drake's rotors add {np.diag(added)} of inertia, {case.armature} was set")


def base_tilt_effect(plant, case):
    """The gravity_tilt of the case's base tilt on the robot's first joint (gap_suite.lean_equilibrium), from the
    plant's own frames at the zero pose."""
    plant.set_state(np.zeros(len(plant.names)), np.zeros(len(plant.names)))
    first = plant.joints[0]
    rot = first.frame_on_child().CalcPoseInWorld(plant.context).rotation().matrix()
    tilt_deg, toward = case.base_tilt
    return bullet.Effect(plant.names[0], "gravity_tilt",
                         {"tilt_deg": tilt_deg, "equilibrium_position": gs.lean_equilibrium(rot, first.revolute_axis(), toward)})


def run_case(case, seed, out):
    rng = gs.case_rng(seed, case.name)
    robot = bullet.ROBOTS[case.robot]
    joints = robot.joints
    engine_text = bullet.massless_made_explicit(bullet.shipped_urdf(robot))
    bare = DrakeArm(engine_text, joints)
    check_rigid(bare, engine_text, rng)
    model_text = bullet.identified(engine_text, case.model_error, rng) if case.model_error > 0 else engine_text
    nominal = DrakeArm(model_text, joints)
    gravity = gs.tilted_gravity(*case.base_tilt) if case.base_tilt else gs.GRAVITY
    plant = DrakeArm(engine_text, joints, case.friction, case.damping, case.armature, gravity)
    check_effects(plant, bare, case, rng)
    bare.close()
    tilt = base_tilt_effect(plant, case) if case.base_tilt else None
    traj, table, effort_sigma = bullet.drive(plant, nominal, case, rng, case.offset)
    note = bullet.shipped_note(robot, case)
    model_effort = gs.inverse_dynamics(nominal, traj, np.gradient(traj.qd, traj.t, axis=0))
    tilt_effort = None
    if tilt is not None:
        tilted = DrakeArm(model_text, joints, gravity=gravity)
        zero = np.zeros(len(joints))
        tilt_effort = np.array([tilted.dynamics(q, zero)[1] - nominal.dynamics(q, zero)[1] for q in traj.q])
        tilted.close()
    nominal.close()
    detail = {
        "coulomb_friction": f"DoorHinge force element, dynamic_friction_torque = friction, motion_threshold = "
                            f"{TRANSITION_SPEED} (-friction tanh(qd / {TRANSITION_SPEED})), explicit in the step",
        "viscous_damping": "Joint.set_default_damping, implicit in SAP's step",
        "armature": f"JointActuator rotor inertia armature / {GEAR_RATIO:g}^2 behind a {GEAR_RATIO:g}:1 gear (reflected "
                    "inertia), actuation input zero",
        "effort_offset": bullet.OFFSET_DETAIL,
        "gravity_tilt": f"the plant's gravity field {tuple(round(g, 6) for g in gravity)}: the whole robot stands tilted",
    }
    engine_detail = (f"{ENGINE}, {note}; discrete MultibodyPlant (SAP, kLagged), root welded, {DT} s steps "
                     "(ExecuteForcedEvents), efforts through the applied generalized force port, held between samples; "
                     f"rigid bodies checked against MuJoCo's reading of the same URDF to {CHECK_RTOL:g}")
    truth = bullet.arm_truth(ENGINE, case, seed, (detail, engine_detail), traj, effort_sigma, model_effort,
                             (tilt, tilt_effort))
    bullet.write_arm_case(out, case, (model_text, note), table, truth)
    return gs.summary_line(case, traj, truth)


if __name__ == "__main__":
    gs.engine_suite_main(cases, run_case)
