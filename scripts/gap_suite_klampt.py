#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by Klamp't's simulator (PyPI klampt, rigid bodies on ODE, the Open
Dynamics Engine), a seventh engine held out from `partscene gap`'s development: the same case format as gap_suite.py,
cases named klampt_*.

    gap_suite_klampt.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('klampt_lid*'). Needs the pinned packages of
gap_suite_klampt_requirements.txt beside this file (gap_suite.py's, and klampt). Every case is a folder DIR/<case>/
with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's "engine" is
"klampt <version>".

Engine: model.urdf itself plus a <klampt> element (Klamp't's URDF extension), read by WorldModel.loadRobot: the
element names the root link as the world frame (world_frame, so the root is welded to the world and Klamp't adds no
floating base), sets every moving link's servo gains to zero (servoP/servoI/servoD; Klamp't's default is a PID servo
of 100/0/10 holding the start pose) and carries the joint friction below; nothing else of the URDF changes. A
klampt.Simulator of its own (Klamp't's WorldSimulation over the ODE built into the wheel, dWorldStep: maximal
coordinates, every link an ODE body, every joint an ODE hinge or slider constraint, solved by ODE's Dantzig LCP;
semi-implicit Euler), 1 ms substeps (setSimStep) advanced one at a time (simulate(0.001)), gravity -9.81 z
(Klamp't's default is -9.8), no collision geometry (so no contact). Efforts are the robot's driver torques,
SimRobotController.setTorque: the torque command replaces the servo (the manual-override controller keeps it) and
Klamp't adds it to the ODE joint (dJointAddHingeTorque / dJointAddSliderForce) before every substep: held between
samples as the spec says. The drivers' torque limits clamp the command at model.urdf's effort (1000); its velocity
limit (100) is not enforced in simulation; the motions never come near either. A state is set by building a new
Simulator from the robot model's configuration and velocity (ODE places every body by forward kinematics), positions
read back as ODE's joint angles, unwrapped every step to the turn nearest the last (Klamp't wraps a hinge into
[0, 2pi)). What Klamp't adds silently and model.urdf lacks is switched off: the servo (above); adaptive time stepping
(adaptiveTimeStepping 0: it rolls back and halves steps around contacts); the instability correction (which scales
every velocity down when the kinetic energy grows by more than 1.5x + 1 J/kg in one step, or past 1e5 J: both
thresholds set to 1e300, and every step's status must stay STATUS_NORMAL); ODE's global constraint-force mixing
(dampedLeastSquaresParameter, 1e-6 by default: it makes every joint compliant, 0.1-0.2 % of inertia lost in a step;
set to 0). ODE's auto-disable (sleep) is off (Klamp't's default), its body damping 0 (ODE's default).
What remains of ODE and cannot be set through Klamp't's API:
  - ODE enforces a joint at the velocity level with the Jacobian of the step's start, and corrects the drift at the
    next step with the global error reduction (errorReductionParameter, left at Klamp't's 0.95): the centripetal
    and Coriolis forces of a chain act one step late, through that correction, instead of within the step. One
    step from a moving state misses them (a double pendulum's bias is 0.1-6 % off); over a motion it integrates
    model.urdf as accurately as MuJoCo's semi-implicit Euler at the same step (checked).
  - Joint stops are ODE's (dParamLoStop/HiStop, bounce 0), with the error reduction 0.95 and mixing 1e-6 that ODE
    copies from the world when Klamp't creates the joint, in the Simulator's constructor, before any setting can be
    changed (a world's <simulation> settings are applied after it too): a stop becomes active only once a step has
    carried the joint past it, and pushes it back out at 0.95 x overshoot / dt, so a stop throws a joint back at a
    restitution that depends on where in its step the joint met it, anywhere in 0-0.95 (mean 0.475) whatever the
    speed. This holds for model.urdf's own limits too. Klamp't also turns a revolute joint's stops off where a limit
    lies outside (-pi, pi) (no case has such limits; checked).
  - Klamp't's dry friction is an ODE joint motor with target speed 0 bounded by the friction (below); the motor
    keeps the mixing 1e-6 it got at creation, so a stuck joint creeps at about 1e-6 x the effort it holds per
    second (rad/s per N m).

Concealed effects, each made the way Klamp't makes it:
  coulomb_friction  <klampt><link dryFriction="f">: Klamp't sets the ODE joint's motor to target speed 0 with
                    force bound f (ODERobot::SetLinkDryFriction): a bounded impulse that sticks (to the creep above)
  viscous_damping   <klampt><link viscousFriction="b">: before every substep Klamp't sets that motor's bound to
                    dryFriction + b*|qd(t)|: -b*qd(t), explicit (the speed at the start of the step), and with dry
                    friction on the same joint the two share the motor
  mass_scale        RobotModelLink.setMass (klampt.Mass: mass, centre of mass, inertia about it) of the child link,
                    scaled, before the Simulator is built
  end_stop          RobotModel.setJointLimits narrower than model.urdf's, before the Simulator is built: an ODE stop
Klamp't's joints have no spring and no armature (a driver has servo gains and friction only; ODE has no rotor
inertia), so no case has either. No tilted axis or effort offset (not engine effects).

Checks (a failure stops the run):
  rigid bodies   Klamp't's joint-space inertia and bias force as RobotModel.getMassMatrix / getCoriolisForces +
                 getGravityForces give them, at 3 random moving states; ODE's as one step moves the joints from rest
                 (accelerations with zero and small efforts: inertia and gravity exactly, at 3 random states), both
                 against model.urdf as MuJoCo reads it and, for a heavier link, the engine's bodies against MuJoCo's
                 model of them, to KLAMPT_RTOL, plus every link's pose (SimBody.getObjectTransform) to POSE_TOL.
                 The velocity terms, which one ODE step does not hold (above), over a motion: from 3 random moving
                 states, 50 steps with stops off, the joint positions against model.urdf integrated finely by MuJoCo
                 (RK4, 10 us) must be within MOTION_FACTOR x the error of MuJoCo's own semi-implicit Euler at 1 ms
                 (+ MOTION_FLOOR: a door turning freely drifts ~1e-8 rad in 50 steps, ODE's rotation update).
  effects        the damping and friction efforts and the added inertia, measured one step at a time at 8 random
                 states (the difference to the same robot without them, speeds 0.5-1.5 so that friction slides
                 through the step, LIMIT_MARGIN inside the limits so that no stop is active) and fitted by
                 -b qd - f sign(qd) and the added diagonal inertia, to EFFECT_RTOL of the values set (truth.json
                 gives the values set and the fits): b of damping and no inertia (explicit). Joints without effects
                 get under EFFECT_RTOL of the others' efforts. Before any damped case, a damped free door under a
                 constant effort must reach the speed of -b*qd after 1 s (gap_suite.check_joint_damping); before any
                 case with friction, a free door under an effort below the friction must stay within CREEP of rest
                 for 1 s, and above it reach the speed of (u - f)/I.
  end stops      restitution measured in the engine hitting the stop at the case's impact speed from 16 phases of
                 one step's travel (gravity off): truth.json gives the mean, engine_detail the range.
  limits         every limited revolute joint of a case lies within (-pi, pi), where Klamp't keeps ODE's stops.

Cases (efforts, noise and sampling as gap_suite.py's, each from its own generator
default_rng([seed, crc32(name)])):
  klampt_door_friction                   heavy wardrobe door pushed and released; dry hinge
  klampt_drawer_friction                 loaded drawer pushed and released; dry runners
  klampt_door_damping                    cabinet door pushed and released; damped hinge
  klampt_sash_mass_scale                 window sash lifted by a multisine; heavier than modelled
  klampt_drawer_end_stop                 drawer pushed open and shut; a stop inside the modelled travel
  klampt_door_friction_damping           cabinet door pushed: dry friction and viscous damping
  klampt_lid_mass_damping                lid pushed open and let fall: heavier than modelled, damped hinge
  klampt_lid_mass_friction               lid pushed open and let fall: heavier than modelled, dry hinge
  klampt_double_pendulum_elbow_friction  double pendulum released; dry friction at the elbow only
  klampt_double_pendulum_elbow_damping   double pendulum released; only the elbow is damped
  klampt_drawer_small_damping            drawer pushed and released; SMALL but real damping, at the edge
  klampt_none_door_pushes                NOTHING missing: door pushed toward targets spanning past its stops
  klampt_none_double_pendulum            NOTHING missing: double pendulum released, no effort column
  klampt_none_lid_pose                   NOTHING missing: lid pushed and dropped onto its stop, tracked by its link
                                         pose; jittered sample times, dropouts
"""

import contextlib
import functools
import math
import os
import sys
import tempfile

import klampt
import mujoco
import numpy as np

import gap_suite as gs
from gap_suite import DT, GRAVITY, SuiteError, door, fx, joint_params, urdf_text

ENGINE = f"klampt {klampt.__version__}"
KLAMPT_RTOL = 1e-9  # inertia and bias against MuJoCo, relative to the largest entry (all compute in double)
POSE_TOL = 1e-9  # link positions (m) and quaternion components against MuJoCo
EFFECT_RTOL = 0.01  # damping, friction and added inertia as measured against the values set
SPEED = (0.5, 1.5)  # |qd| of the states where effects are measured: friction must slide through the step
PROBE = 1.0  # rad/s^2 or m/s^2: the efforts that measure the inertia accelerate each joint about this much
LIMIT_MARGIN = 0.02  # rad or m: measuring states stay this far inside the limits, where no ODE stop is active
MOTION_STEPS = 50  # steps of the motion that checks the velocity terms
MOTION_FACTOR = 2.0  # ... whose position error may be this many times MuJoCo's semi-implicit Euler's
MOTION_FLOOR = 1e-6  # ... plus this (rad or m): ODE's rotation update (a normalised quaternion step) is not exact
CREEP = 1e-5  # rad, rad/s: how far a door held by dry friction may creep in 1 s (the motor's mixing, ~1e-6 x effort)
STOP_PHASES = 16  # impacts, spread over one step's travel, that measure an end stop's restitution
SETTINGS = {  # Klamp't Simulator settings: see the docstring
    "adaptiveTimeStepping": "0",
    "instabilityConstantEnergyThreshold": "1e300",
    "instabilityMaxEnergyThreshold": "1e300",
    "dampedLeastSquaresParameter": "0",
    "autoDisable": "0",
}

klampt.robotsim.set_log_level("ERROR")


@contextlib.contextmanager
def quiet():
    """Klamp't's C++ loader prints to the process's stdout: silenced around it, so that stdout keeps the summary."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w", encoding="utf-8") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)


def klampt_urdf(mech, effects):
    """model.urdf of `mech` and a <klampt> element: the root link is the world frame (welded), every moving link's
    servo gains zero, and the joints' dry and viscous friction of `effects` (the viscous friction adds to the
    damping model.urdf knows, which Klamp't would read from <dynamics damping> and the element overrides)."""
    rows = []
    for name in mech.movable():
        p, joint = joint_params(effects, name), mech.joint(name)
        rows.append(f'    <link name="{joint.child}" servoP="0" servoI="0" servoD="0" '
                    f'dryFriction="{gs.num(p["friction"])}" viscousFriction="{gs.num(joint.damping + p["damping"])}"/>')
    element = [f'  <klampt world_frame="{mech.root()}">'] + rows + ["  </klampt>"]
    text = urdf_text(mech)
    if text.count("</robot>") != 1:
        raise SuiteError("model.urdf must end its <robot> once")
    return text.replace("</robot>", "\n".join(element) + "\n</robot>")


def load_robot(mech, effects):
    """model.urdf of `mech` with its <klampt> element, read by WorldModel.loadRobot into a world of its own."""
    world = klampt.WorldModel()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "model.urdf")
        with open(path, "w", encoding="utf-8") as f:
            f.write(klampt_urdf(mech, effects))
        with quiet():
            robot = world.loadRobot(path)
    if world.numRobots() != 1 or robot.numLinks() == 0:
        raise SuiteError(f"Klamp't could not read the {mech.name} model")
    return world, robot


class KlamptSim:
    """model.urdf (of `model`, default `mech`) with its <klampt> element (the friction and damping of `effects`) in a
    Klamp't world of its own; where `mech` (the engine's bodies) differs from it, a link's mass, centre of mass and
    inertia and a joint's limits are set through the robot model's API. Every set_state builds a new Simulator from
    the robot model's state; efforts through SimRobotController.setTorque (held). `stops` False removes every joint
    limit (so that a free motion checks the dynamics alone)."""

    def __init__(self, mech, effects, gravity=True, model=None, stops=True):
        model = mech if model is None else model
        for effect in effects:
            if effect.kind in ("spring", "armature"):
                raise SuiteError(f"joint {effect.joint}: Klamp't's joints have no {effect.kind}")
        self.world, self.robot = load_robot(model, effects)
        self.gravity = list(GRAVITY if gravity else (0.0, 0.0, 0.0))
        self.names = mech.movable()
        self.nlinks = self.robot.numLinks()
        links = {self.robot.link(i).getName(): i for i in range(self.nlinks)}
        for link in mech.links:
            if link.name != mech.root():
                self._set_body(self.robot.link(link.name), link, model.link(link.name))
        self.idx, self.revolute = [], []
        qmin, qmax = (list(x) for x in self.robot.getJointLimits())
        for name in self.names:
            joint, urdf_joint = mech.joint(name), model.joint(name)
            gs.check_joint_frame(joint, urdf_joint)
            if joint.child not in links:
                raise SuiteError(f"Klamp't has no link {joint.child}")
            k = links[joint.child]
            link = self.robot.link(k)
            prismatic = bool(link.isPrismatic())
            if link.getParent() != links.get(joint.parent, -1) or prismatic != (joint.kind == "prismatic"):
                raise SuiteError(f"Klamp't reads joint {name} otherwise than model.urdf")
            self.idx.append(k)
            self.revolute.append(joint.kind != "prismatic")
            if joint.lower is not None and (joint.lower, joint.upper) != (urdf_joint.lower, urdf_joint.upper):
                qmin[k], qmax[k] = joint.lower, joint.upper
            if not stops:
                qmin[k], qmax[k] = -math.inf, math.inf
        self.robot.setJointLimits(qmin, qmax)
        self.drivers = [self.robot.driver(d).getAffectedLink() for d in range(self.robot.numDrivers())]
        if sorted(self.drivers) != sorted(self.idx):
            raise SuiteError(f"Klamp't's drivers move links {self.drivers}, the joints' are {self.idx}")
        self.sim = None
        self.effort = np.zeros(len(self.names))
        self.last_q = np.zeros(len(self.names))
        self.set_state(np.zeros(len(self.names)), np.zeros(len(self.names)))

    @staticmethod
    def _set_body(klampt_link, link, urdf_link):
        if klampt_link.getName() != link.name:
            raise SuiteError(f"Klamp't has no link {link.name}")
        if link.mass != urdf_link.mass or not np.array_equal(link.inertia, urdf_link.inertia) or \
                tuple(link.com) != tuple(urdf_link.com):
            mass = klampt.Mass()
            mass.setMass(link.mass)
            mass.setCom(list(link.com))
            mass.setInertia(list(np.asarray(link.inertia, float).flatten()))
            klampt_link.setMass(mass)

    def _full(self, values):
        out = [0.0] * self.nlinks
        for k, v in zip(self.idx, values):
            out[k] = float(v)
        return out

    def _torques(self):
        by_link = dict(zip(self.idx, self.effort))
        return [float(by_link[k]) for k in self.drivers]

    def set_state(self, q, qd):
        self.robot.setConfig(self._full(q))
        self.robot.setVelocity(self._full(qd))
        self.sim = None
        self.sim = klampt.Simulator(self.world)
        self.sim.setSimStep(DT)
        self.sim.setGravity(self.gravity)
        for key, value in SETTINGS.items():
            self.sim.setSetting(key, value)
        self.controller = self.sim.controller(0)
        self.controller.setTorque(self._torques())
        self.last_q = np.asarray(q, float).copy()

    def state(self):
        raw = np.array(self.sim.getActualConfig(0))[self.idx]
        turns = np.where(self.revolute, np.round((self.last_q - raw) / (2 * math.pi)), 0.0)
        q = raw + 2 * math.pi * turns
        self.last_q = q.copy()
        return q, np.array(self.sim.getActualVelocity(0))[self.idx]

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()
        self.controller.setTorque(self._torques())

    def advance(self, steps):
        for _ in range(int(steps)):
            self.sim.simulate(DT)
            if self.sim.getStatus() != klampt.Simulator.STATUS_NORMAL:
                raise SuiteError(f"Klamp't's simulation left its normal status: {self.sim.getStatusString()}")
            if any(self.revolute):
                self.state()  # keeps the turn count: a hinge moves far less than half a turn in a step

    def pose(self, link):
        rot, pos = self.sim.body(self.robot.link(link)).getObjectTransform()
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(np.array(rot).reshape(3, 3).T).flatten())  # column-major
        return np.concatenate([np.asarray(pos, float), quat])

    def dynamics(self, q, qd):
        """Joint-space inertia and bias force C(q, qd) qd + g(q) as Klamp't's robot model computes them."""
        self.robot.setConfig(self._full(q))
        self.robot.setVelocity(self._full(qd))
        full = np.array(self.robot.getMassMatrix())
        bias = np.array(self.robot.getCoriolisForces()) + np.array(self.robot.getGravityForces(self.gravity))
        return full[np.ix_(self.idx, self.idx)].copy(), bias[self.idx].copy()

    def step_dynamics(self, q, qd):
        """Joint-space inertia and bias force as one ODE step has them, with everything the step adds (the friction
        motors): the velocity change of one step from (q, qd) with zero effort and with a small effort on each joint
        (PROBE of acceleration). Raises where a limited joint is within LIMIT_MARGIN of a limit or a moving joint's
        velocity changes sign within the step (friction would not slide). (gap_suite.probe_step_dynamics)"""
        for n, name in enumerate(self.names):
            lo, hi = self.robot.getJointLimits()[0][self.idx[n]], self.robot.getJointLimits()[1][self.idx[n]]
            if not lo + LIMIT_MARGIN <= q[n] <= hi - LIMIT_MARGIN:
                raise SuiteError(f"joint {name} at {q[n]} is too near its limits to measure a free step")

        def slides(after):
            moving = np.asarray(qd) != 0
            if np.any(np.sign(after[moving]) != np.sign(np.asarray(qd)[moving])):
                raise SuiteError("a joint's velocity changed sign within the measuring step")

        held = self.effort
        out = gs.probe_step_dynamics(self, q, qd, PROBE, read_back=True, check=slides)
        self.hold(held)
        return out

    def close(self):
        self.sim = self.controller = self.robot = self.world = None


gs.SIMULATORS["klampt"] = lambda case, mech, effects, gravity: KlamptSim(mech, effects, gravity, model=case.mech)


# ---------------------------------------------------------------- checks


def check_limits(case):
    """Klamp't keeps ODE's stops on a revolute joint only where both limits lie within (-pi, pi)."""
    for joint in case.mech.joints:
        if joint.kind == "revolute" and not -math.pi < joint.lower <= joint.upper < math.pi:
            raise SuiteError(f"{case.name}: joint {joint.name}'s limits reach past +-pi, where Klamp't drops "
                             "ODE's stops")


def check_motion(case, engine_mech, rng):
    """The velocity terms over a motion: from 3 random states (speeds SPEED), MOTION_STEPS steps of the engine's
    bodies, stops off, zero effort; the joint positions against MuJoCo's model of those bodies integrated finely
    (RK4, 10 us) must be within MOTION_FACTOR x the error of MuJoCo's semi-implicit Euler at DT (+MOTION_FLOOR). Returns
    the largest of each error."""
    names = engine_mech.movable()
    sim = KlamptSim(engine_mech, [], model=case.mech, stops=False)

    def mujoco_run(integrator, dt, q, qd):
        model = gs.mujoco_model(engine_mech, [])
        model.opt.timestep, model.opt.integrator = dt, integrator
        model.jnt_limited[:] = 0
        reference = gs.MujocoSim(model, names)
        reference.set_state(q, qd)
        reference.advance(round(MOTION_STEPS * DT / dt))
        return reference.state()[0]

    worst, worst_euler = 0.0, 0.0
    lo, hi = gs.state_box(engine_mech, LIMIT_MARGIN)
    for _ in range(3):
        q, qd = rng.uniform(lo, hi), gs.random_speeds(rng, len(names), SPEED)
        sim.set_state(q, qd)
        sim.hold(np.zeros(len(names)))
        sim.advance(MOTION_STEPS)
        got = sim.state()[0]
        fine = mujoco_run(mujoco.mjtIntegrator.mjINT_RK4, 1e-5, q, qd)
        euler = mujoco_run(mujoco.mjtIntegrator.mjINT_EULER, DT, q, qd)
        err, euler_err = np.abs(got - fine).max(), np.abs(euler - fine).max()
        if err > MOTION_FACTOR * euler_err + MOTION_FLOOR:
            raise SuiteError(f"{case.name}: Klamp't's motion is {err:.2e} off model.urdf's after {MOTION_STEPS} "
                             f"steps, MuJoCo's Euler {euler_err:.2e}")
        worst, worst_euler = max(worst, err), max(worst_euler, euler_err)
    sim.close()
    return worst, worst_euler


def check_rigid(case, engine_mech, nominal, rng):
    """Klamp't's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies against
    MuJoCo's model of them): the robot model's inertia and bias at 3 random moving states, one ODE step's inertia
    and bias at 3 random states at rest, link poses (gap_suite.check_engine_rigid); the velocity terms over a
    motion (check_motion). Returns (worst relative inertia/bias error, (worst motion error, MuJoCo's Euler's)))."""
    check_limits(case)
    model = gs.check_engine_rigid(case, engine_mech, nominal, rng, "Klamp't",
                                  [("Klamp't RobotModel", KlamptSim.dynamics, KLAMPT_RTOL)], POSE_TOL, speed=SPEED,
                                  margin=LIMIT_MARGIN)
    step = gs.check_engine_rigid(case, engine_mech, nominal, rng, "Klamp't",
                                 [("ODE step at rest", KlamptSim.step_dynamics, KLAMPT_RTOL)], POSE_TOL,
                                 speed=(0.0, 0.0), margin=LIMIT_MARGIN)
    return max(model + step), check_motion(case, engine_mech, rng)


def measure_effects(case, engine_mech, rng):
    """The efforts of damping and friction and the added inertia as Klamp't applies them, one step from 8 random
    states: the difference of KlamptSim.step_dynamics with and without the effects, fitted per joint by
    -b qd - f sign(qd) and an added diagonal inertia. Klamp't's viscous friction is explicit (-b qd(t)): it shows as
    b of damping and no inertia. Raises unless the fits match the values set to EFFECT_RTOL, and joints without
    effects get under EFFECT_RTOL of the others'. Returns the fits per joint with effects
    (gap_suite.measure_engine_effects)."""
    def expected(p):
        return {"damping": (p["damping"], EFFECT_RTOL * p["damping"]), "armature": (0.0, 0.0)}

    return gs.measure_engine_effects(case, engine_mech, rng, "Klamp't", KlamptSim.step_dynamics, expected,
                                     EFFECT_RTOL, 1e-9, speed=SPEED, margin=LIMIT_MARGIN)


def check_joint_damping():
    """Klamp't's viscousFriction must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(KlamptSim, "Klamp't viscousFriction", EFFECT_RTOL)


def check_coulomb_friction():
    """Klamp't's dry friction f on a free door (inertia I, no gravity torque, stops outside its motion): under a
    held effort below f the door stays within CREEP of rest for 1 s; under u above f it reaches (u - f)/I after
    1 s, to EFFECT_RTOL."""
    mech = door(0.5, 0.5, 1.2, open_limit=3.0)
    inertia = mech.link("door_panel").inertia[2, 2] + 1.2 * 0.25 ** 2
    sim = KlamptSim(mech, [fx("hinge", "coulomb_friction", friction=0.5)])
    for effort, expected in ((0.3, 0.0), (-0.45, 0.0), (1.0, 0.5 / inertia)):
        sim.hold([effort])
        sim.set_state([0.2], [0.0])
        sim.advance(1000)
        (q,), (qd,) = sim.state()
        if expected == 0.0 and max(abs(q - 0.2), abs(qd)) > CREEP:
            raise SuiteError(f"Klamp't dryFriction 0.5 does not hold the door under {effort}: q {q}, qd {qd} "
                             "after 1 s")
        if expected and abs(qd - expected) > EFFECT_RTOL * expected:
            raise SuiteError(f"Klamp't dryFriction does not act as f*sign(qd): {qd} rad/s after 1 s, "
                             f"expected {expected}")
    sim.close()


def measure_restitution(case, engine_mech, effect):
    """An end stop's restitution as Klamp't's ODE stop has it: hit at the case's impact speed, gravity off, from
    STOP_PHASES starts spread over one step's travel (gap_suite.stop_hit, moved back by a share of speed*DT). ODE's
    stop throws the joint back at 0.95 x its overshoot / DT, so the restitution depends on the phase: returns the
    mean (what truth.json gives) and keeps the range in `effect.setting` for engine_detail."""
    out = []
    for k in range(STOP_PHASES):
        sim, n, sign = gs.stop_hit(case, engine_mech, effect)
        q, qd = sim.state()
        q[n] -= sign * k / STOP_PHASES * case.impact_speed * DT
        sim.set_state(q, qd)
        sim.advance(400)
        out.append(max(0.0, -sign * float(sim.state()[1][n]) / case.impact_speed))
        sim.close()
    effect.setting["restitution_range"] = (round(min(out), 3), round(max(out), 3))
    return round(float(np.mean(out)), 3)


# gap_suite.run_engine_case measures an end stop's restitution through gap_suite.measure_restitution (one impact);
# Klamp't's depends on where in its step the joint meets the stop, so this suite's measurement (16 phases) is used.
gs.measure_restitution = measure_restitution


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "klampt", "klampt")  # gap_suite.ENGINE_CASES, named klampt_<key>
    return [shared(key) for key in gs.FRICTION_DAMPING_CASES]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How Klamp't made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    step = "measured over one step at 8 random states (speeds 0.5-1.5)"
    both = joint_params(case.effects, effect.joint)
    if kind == "coulomb_friction":
        return (f"Klamp't URDF <klampt><link name=\"{joint.child}\" dryFriction=\"{p['friction']}\">: the ODE joint's "
                f"motor at target speed 0 with force bound {p['friction']} (a bounded impulse: sticks, creeping at "
                f"~1e-6 x the held effort per second from the motor's mixing); {step} as "
                f"-{got['friction']:g}*sign(qd)")
    if kind == "viscous_damping":
        shared_motor = f" (sharing the motor with dryFriction {both['friction']})" if both["friction"] else ""
        return (f"Klamp't URDF <klampt><link name=\"{joint.child}\" viscousFriction=\"{p['damping']}\">: before every "
                f"substep the ODE motor's force bound is set to dryFriction + {p['damping']}*|qd(t)|{shared_motor}, "
                f"explicit; {step} as -{got['damping']:g}*qd with {got['armature']:.3g} of apparent inertia")
    if kind == "mass_scale":
        return (f"Klamp't RobotModelLink {joint.child}: setMass (mass, inertia about the centre of mass) x{p['scale']} "
                f"before the Simulator is built; inertia and bias checked against MuJoCo's model of the heavier link "
                f"to {KLAMPT_RTOL:g}")
    lo, hi = effect.setting.get("restitution_range", (None, None))
    return (f"Klamp't RobotModel.setJointLimits: {effect.setting['side']} bound {p['position']} instead of "
            "model.urdf's, before the Simulator is built: an ODE joint stop (bounce 0, stop ERP 0.95 and CFM 1e-6 "
            "copied from the world at creation), active once a step has carried the joint past it, pushing it back "
            "at 0.95 x overshoot / dt; restitution measured in the engine hitting it at "
            f"{case.impact_speed} per second, gravity off, from {STOP_PHASES} phases of one step's travel: mean "
            f"{p['restitution']}, range {lo}-{hi}")


def engine_text(checked):
    rigid_err, (motion, euler) = checked
    return (f"{ENGINE}: model.urdf + a <klampt> element (world_frame = the root link, servo gains 0, the joints' "
            "dryFriction/viscousFriction) read by WorldModel.loadRobot, no collision geometry; a Simulator of its "
            f"own (ODE dWorldStep, maximal coordinates, Dantzig LCP): gravity {GRAVITY[2]} z, {DT} s substeps "
            "simulated one at a time, adaptive time stepping off, instability correction off (thresholds 1e300, "
            "status checked every step), global CFM 0, ERP 0.95 (Klamp't's), auto-disable off; efforts through "
            "SimRobotController.setTorque (servo overridden), added to the ODE joints every substep, held between "
            "samples; joint limits are ODE stops (bounce 0, ERP 0.95, CFM 1e-6: a restitution of 0-0.95 by the "
            "phase of the impact). Rigid bodies checked against model.urdf as MuJoCo reads it (getMassMatrix / "
            "getCoriolisForces + getGravityForces at moving states, one ODE step's accelerations at rest, link "
            f"poses): {rigid_err:.1e} relative; Coriolis and centripetal forces act one step late through ODE's "
            f"error reduction: over {MOTION_STEPS} steps from moving states the joint positions are at most "
            f"{motion:.1e} off a fine integration of model.urdf (MuJoCo's semi-implicit Euler at the same step: "
            f"{euler:.1e})")


def run_case(case, seed, out):
    """Simulates one case with Klamp't and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: KlamptSim(engine_mech, case.effects, model=case.mech))


def main():
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_joint_damping),
                                           ("coulomb_friction", check_coulomb_friction)])


if __name__ == "__main__":
    main()
