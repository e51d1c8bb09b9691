#!/usr/bin/env python3
"""Multi-joint arm recordings made by Genesis (genesis-world, its rigid solver on the CPU backend, float64), an
eleventh engine held out from `partscene gap`'s development: the KUKA LBR iiwa 7 R800 and the Franka Panda that
ship with pybullet_data (another project's models), prepared exactly as gap_suite_drake_arms.py prepares them,
driven by torques for 20 s at 200 Hz. The same case format as gap_suite.py, cases named genesis_iiwa_* and
genesis_panda_*.

    gap_suite_genesis_arms.py --out DIR [--seed N] [--only PATTERN]

Needs the pinned packages of gap_suite_genesis_requirements.txt (genesis-world, torch, and gap_suite.py's). Every
case is a folder DIR/<case>/ with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them;
truth.json's "engine" is "genesis <version>".

Engine: the robot's URDF text (geometry removed, no joint damping of its own, the Panda's fingers welded, massless
links made explicit as gap_suite_bullet_arms.massless_made_explicit does) loaded by Genesis's own URDF importer
(gs.morphs.URDF, fixed=True: the root link welded to the world) into a scene of its own (1 ms steps, one substep,
gravity -9.81 z, collisions off, Genesis's default integrator and constraint solver, joint limits on as Genesis
has them). Efforts are generalized forces set by control_dofs_force at each sample and held between samples.
What Genesis adds that URDF cannot say: its URDF morph fills in a rotor inertia at build for every one-dof joint
left at zero (default_armature, 0.1 kg m^2 in genesis-world 1.4): the cases set each joint's armature to what the
case conceals (zero where none), except genesis_panda_default_armature, which keeps what Genesis gave, read back from
the engine (the first thing a user of Genesis who loads a URDF meets); and the bound its importer puts on each
joint's applied force (the URDF's <limit effort>: 12 N m on the Panda's wrist) is lifted
(gap_suite_genesis.GenesisScene). The identified-model cases write model.urdf with every link's mass and
inertia tensor scaled alike by a factor drawn within +-5 % (gap_suite_bullet_arms.identified), the engine keeping
the shipped values.

Concealed effects, each made the way Genesis's API makes it (set on the built scene):
  coulomb_friction  set_dofs_frictionloss: a friction-loss constraint row solved with the step (as MuJoCo's
                    frictionloss), its force bounded by the level; truth friction = the level
  viscous_damping   set_dofs_damping (in the integrator's implicit part)
  armature          set_dofs_armature: added to the joint-space inertia's diagonal
  effort_offset     a constant added to the recorded effort (a torque sensor's bias), not engine physics; truth.json's
                    offset is minus it (the spec's offset adds to the recorded effort to give the felt one)

Checks (a failure stops the run), per case before it is recorded:
  rigid bodies  the joint-space inertia and bias force one step has (gap_suite.probe_step_dynamics) with every
                effect zeroed against model.urdf's engine text as MuJoCo reads it, at 5 random states, to CHECK_RTOL.
  effects       the same step with the case's effects against that: the inertia's diagonal gains the armature plus
                one step's worth of damping (dt b, the implicit damping), the bias gains b qd plus, at speeds of
                +-1 rad/s (past where a friction-loss row gives its whole level), friction sign(qd), to CHECK_RTOL;
                nothing off the diagonal.
Excitation: gap_suite.arm_excitation, the MuJoCo, Bullet and Drake arm suites': computed torque with model.urdf
(1.5 Hz, damping ratio 0.7) around a slow 3-sine target inside the joint ranges, plus 3 sines per joint, decided at
200 Hz and held; the controller knows none of the concealed effects. Noise: 1e-4 rad on positions, 1 % of each
joint's RMS effort on efforts.
"""
import dataclasses
from dataclasses import dataclass
from importlib import metadata

import mujoco
import numpy as np

import gap_suite as gs
import gap_suite_bullet_arms as bullet
import gap_suite_genesis as genesis_suite
from gap_suite import DT, SuiteError

ENGINE = genesis_suite.ENGINE
CHECK_RTOL = 1e-8
FRICTION_CHECK_SPEED = 1.0  # rad/s: where a friction-loss row gives its whole level (checked)


@dataclass
class ArmCase(bullet.RotorArmCase):
    """The arm case with rotors and sensor biases (gap_suite_bullet_arms.RotorArmCase); friction is a friction-loss
    level (N m). With imported_armature, the armature is what Genesis fills in (read back), not `armature`."""

    imported_armature: bool = False
    engine: str = "genesis"


def cases():
    return [
        ArmCase("genesis_iiwa_none", "iiwa; nothing missing (Genesis's armature set to zero)", "iiwa"),
        ArmCase("genesis_iiwa_friction", "iiwa; dry friction (friction loss) on every joint", "iiwa",
                friction=bullet.FRICTION),
        ArmCase("genesis_iiwa_rotor_damping", "iiwa; rotor inertia on every joint, damping on joints 2, 4, 6", "iiwa",
                damping=[0.0, 1.0, 0.0, 0.3, 0.0, 0.004, 0.0], armature=bullet.IIWA_ROTOR),
        ArmCase("genesis_iiwa_identified_model", "iiwa; dry friction on every joint, sensor biases on joints 2 and 4, "
                "model.urdf's inertias up to 5 % off", "iiwa", friction=bullet.FRICTION,
                offset=[0.0, 1.0, 0.0, -0.5, 0.0, 0.0, 0.0], model_error=0.05),
        ArmCase("genesis_panda_none", "Panda; nothing missing (Genesis's armature set to zero)", "panda"),
        ArmCase("genesis_panda_default_armature", "Panda as Genesis's URDF importer loads it: the rotor inertia it "
                "gives every joint, nothing else", "panda", imported_armature=True),
        ArmCase("genesis_panda_friction_damping", "Panda; dry friction on joints 1, 3, 5, 7, damping on 2 and 4",
                "panda", friction=[1.0, 0.0, 0.8, 0.0, 0.3, 0.0, 0.05], damping=[0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0]),
        ArmCase("genesis_panda_identified_model", "Panda; dry friction on every joint, model.urdf's inertias up to "
                "5 % off", "panda", friction=bullet.PANDA_FRICTION, model_error=0.05),
    ]


class GenesisArm(genesis_suite.GenesisScene):
    """An arm in a Genesis scene of its own, loaded from URDF text by Genesis's importer (gap_suite_genesis.py's
    scene): the joints `joints` (in order), effects set per joint on the built scene."""

    def __init__(self, text, joints):
        super().__init__(text, joints)
        lo, hi = self.entity.get_dofs_limit(self.idx)
        self.lo, self.hi = np.asarray(lo, float), np.asarray(hi, float)
        self.imported_armature = np.asarray(self.entity.get_dofs_armature(self.idx), float)

    def set_effects(self, friction, damping, armature):
        for setter, values in ((self.entity.set_dofs_frictionloss, friction), (self.entity.set_dofs_damping, damping),
                               (self.entity.set_dofs_armature, armature)):
            setter(np.asarray(values, float), self.idx)

    def close(self):
        """Nothing: the scene is kept for the robot's next case (arm_of), its effects set again there."""


def check_engine(arm, case, armature, rng):
    """The step's rigid bodies with every effect zeroed against MuJoCo's reading of the arm's URDF, then the case's effects
    against that (module docstring), at 5 random states at FRICTION_CHECK_SPEED."""
    n = len(arm.names)
    friction, damping = np.asarray(case.friction, float), np.asarray(case.damping, float)
    for _ in range(5):
        q = rng.uniform(arm.lo + 0.1, arm.hi - 0.1)
        qd = FRICTION_CHECK_SPEED * rng.choice([-1.0, 1.0], n)
        arm.set_effects(np.zeros(n), np.zeros(n), np.zeros(n))
        bare = gs.probe_step_dynamics(arm, q, qd, 1.0)
        gs.compare_dynamics("Genesis arm against MuJoCo", bare, arm.dynamics(q, qd), CHECK_RTOL)
        arm.set_effects(friction, damping, armature)
        full, bias = gs.probe_step_dynamics(arm, q, qd, 1.0)
        want = (bare[0] + np.diag(armature + DT * damping), bare[1] + damping * qd + friction * np.sign(qd))
        scale = max(1.0, np.abs(want[0]).max(), np.abs(want[1]).max())
        if max(np.abs(full - want[0]).max(), np.abs(bias - want[1]).max()) > CHECK_RTOL * scale:
            raise SuiteError(f"{case.name}: Genesis's step has inertia {np.diag(full)} and bias {bias}, "
                             f"{np.diag(want[0])} and {want[1]} expected")
    arm.hold(np.zeros(n))


ARMS = {}


def arm_of(robot, text):
    """One Genesis scene per robot, built once (each build compiles the solver's kernels)."""
    if robot.key not in ARMS:
        ARMS[robot.key] = GenesisArm(text, robot.joints)
    return ARMS[robot.key]


def run_case(case, seed, out):
    rng = gs.case_rng(seed, case.name)
    robot = bullet.ROBOTS[case.robot]
    joints = robot.joints
    engine_text = bullet.massless_made_explicit(bullet.shipped_urdf(robot))
    arm = arm_of(robot, engine_text)
    armature = arm.imported_armature.copy() if case.imported_armature else np.asarray(case.armature, float)
    check_engine(arm, case, armature, rng)
    model_text = bullet.identified(engine_text, case.model_error, rng) if case.model_error > 0 else engine_text
    nominal = gs.MujocoSim(mujoco.MjSpec.from_string(model_text).compile(), joints)
    arm.set_effects(case.friction, case.damping, armature)
    traj, table, effort_sigma = bullet.drive(arm, nominal, case, rng, case.offset)
    note = bullet.shipped_note(robot, case)
    model_effort = gs.inverse_dynamics(nominal, traj, np.gradient(traj.qd, traj.t, axis=0))
    detail = {
        "coulomb_friction": "set_dofs_frictionloss: a friction-loss constraint row solved with the step, its force "
                            "bounded by the level",
        "viscous_damping": "set_dofs_damping, in the integrator's implicit part",
        "armature": "set_dofs_armature: added to the joint-space inertia's diagonal" + (
            " (what Genesis's URDF morph fills in for every joint, default_armature, read back)"
            if case.imported_armature else ""),
        "effort_offset": bullet.OFFSET_DETAIL,
    }
    engine_detail = (f"{ENGINE} (torch {metadata.version('torch')}), CPU backend, float64, {note}; Genesis's URDF "
                     f"importer, root welded, {DT} s steps, one substep, collisions off, default integrator "
                     "(approximate_implicitfast) and constraint solver, the force bound lifted, efforts through "
                     "control_dofs_force, held between samples; one step's rigid bodies checked against MuJoCo's "
                     f"reading of the same URDF to {CHECK_RTOL:g}")
    shown = dataclasses.replace(case, armature=[float(a) for a in armature])
    truth = bullet.arm_truth(ENGINE, shown, seed, (detail, engine_detail), traj, effort_sigma, model_effort)
    bullet.write_arm_case(out, case, (model_text, note), table, truth)
    return gs.summary_line(shown, traj, truth)


if __name__ == "__main__":
    genesis_suite.init()
    gs.engine_suite_main(cases, run_case)
