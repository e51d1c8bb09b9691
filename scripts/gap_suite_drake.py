#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by Drake (pydrake's MultibodyPlant), a fifth engine held out from
`partscene gap`'s development: the same case format as gap_suite.py, cases named drake_*.

    gap_suite_drake.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('drake_lid*'). Needs the pinned packages of
gap_suite_drake_requirements.txt beside this file (gap_suite.py's, and drake). Every case is a folder DIR/<case>/
with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's "engine" is
"drake <version>".

Engine: model.urdf itself, read by pydrake.multibody.parsing.Parser(plant).AddModelsFromString(text, "urdf") into
a discrete MultibodyPlant(time_step=0.001) of its own, the root link welded to the world (WeldFrames), gravity
-9.81 z, no collision geometry (so no contact), the discrete contact approximation set explicitly to kLagged
(Drake 1.51's default; TAMSI is deprecated): the plant's discrete solver is then SAP. One step is the plant's
own discrete update, run by plant.ExecuteForcedEvents(context) (the update the Simulator applies every period:
checked at start to give a Simulator's states to 1e-12). SAP's step is symplectic Euler with the joints' damping
implicit, (M + dt D)(v(t+dt) - v(t))/dt = tau - C v - g - D v(t) (everything else, the springs' forces included,
taken at the start of the step), then q(t+dt) = q(t) + dt v(t+dt), with the constraints solved as a convex
problem. Efforts are generalized forces on the plant's applied generalized force input port (a fixed value, set
at each sample and held between samples as the spec says); where the plant has an actuator its actuation port
is fixed at zero. Joint limits: model.urdf's (and an end stop's) <limit> is what SAP enforces (TAMSI would
use penalty forces instead), as a SapLimitConstraint added while the limit is within 2*dt*max(|v|, |v*|) of q:
compliant in form (stiffness 1e12, dissipation time scale dt) but solved in SAP's "near rigid" regime (beta
0.1). In effect a hard, inelastic stop that is never passed: once the stop is within a step's reach the joint
closes half the remaining gap per step (its speed halves every step), so it comes to rest on the stop within
~20 steps of the first slowed one, whatever the speed; a weight pressing it onto the stop leaves it ~1e-8 past
it. No restitution parameter (restitution measured, 0; truth.json gives the overshoot and settling measured at
the impact speed). The URDF's velocity (100) and effort (1000) limits stay as parsed: Drake does not enforce a
joint's velocity limits in simulation, and an effort limit binds actuators only.

Concealed effects, each made the way MultibodyPlant's joint, force element, actuator and body API makes it
(after parsing model.urdf, before Finalize unless said):
  viscous_damping   Joint.set_default_damping(b): implicit in SAP's step (-b*qd(t+dt))
  spring            a RevoluteSpring(joint, nominal_angle, k) / PrismaticSpring(joint, nominal_position, k) force
                    element: explicit (-k*(q(t) - r), at the start of the step)
  armature          a JointActuator on the joint (AddJointActuator), set_default_rotor_inertia(I_r) and
                    set_default_gear_ratio(GEAR_RATIO): Drake's reflected inertia rho^2*I_r, which it adds to the
                    mass matrix's diagonal; the actuator's input is held at zero (efforts still go through the
                    applied generalized force port)
  mass_scale        the child body's SpatialInertia (mass, centre of mass, rotational inertia x scale) set in the
                    plant's context (RigidBody.SetSpatialInertiaInBodyFrame, a context parameter) after Finalize
  end_stop          Joint.set_position_limits narrower than model.urdf's
Drake's joints have no dry (Coulomb) friction (a Joint has damping only; MultibodyPlant's friction is contact
friction), so no case has coulomb_friction. (The DoorHinge force element, for revolute joints, has a
tanh-regularised "dynamic friction" -k_df*tanh(qd/v0) among its hinge torques, explicit in the step: a smooth
friction law of a force element rather than a joint's, not used here.) No tilted axis or effort offset (not
engine effects).

Checks (a failure stops the run):
  stepping       ExecuteForcedEvents steps against a Simulator's AdvanceTo (a damped door under an effort).
  rigid bodies   Drake's joint-space inertia and bias force, both as CalcMassMatrix / CalcBiasTerm -
                 CalcGravityGeneralizedForces give them and as one step moves the joints (accelerations with zero
                 and small efforts, at states where SAP adds no limit constraint), against model.urdf as MuJoCo
                 reads it, and for a heavier link the engine's bodies against MuJoCo's model of them, to DRAKE_RTOL,
                 plus every link's pose (EvalBodyPoseInWorld) to POSE_TOL, at 3 random states per case.
  effects        the damping and spring efforts and the added inertia, measured one step at a time at 8 random
                 states (the difference to the same plant without them, speeds 0.5-1.5) and fitted by
                 -b qd - k (q - r) and the added diagonal inertia, to EFFECT_RTOL of the values set (truth.json gives
                 the values set and the fits). Drake's damping is implicit, its springs explicit: the fit sees b of
                 damping and b*dt of inertia (plus the armature), k of stiffness and nothing else. Joints without
                 effects get under EFFECT_RTOL of the others' efforts. The actuator's reflected inertia must also be
                 the armature set, as JointActuator.default_reflected_inertia gives it. Before any damped case, a
                 damped free door under a constant effort must reach the speed of -b*qd after 1 s
                 (gap_suite.check_joint_damping).
  end stops      restitution measured in the engine (gap_suite.measure_restitution).

Cases (efforts, noise and sampling as gap_suite.py's, each from its own generator
default_rng([seed, crc32(name)])):
  drake_door_damping                   cabinet door pushed and released; damped hinge
  drake_flap_spring                    light flap on a vertical hinge with a return spring, pushed
  drake_knob_armature                  geared knob (rotor inertia behind a gear) driven by a multisine
  drake_sash_mass_scale                window sash lifted by a multisine; heavier than modelled
  drake_drawer_end_stop                drawer pushed open and shut; a stop inside the modelled travel
  drake_lid_spring_damping             counterbalanced lid with a damper, pushed
  drake_lid_mass_scale                 lid pushed open and let fall: heavier than modelled
  drake_double_pendulum_elbow_damping  double pendulum released; only the elbow is damped
  drake_drawer_small_damping           drawer pushed and released; SMALL but real damping, at the edge
  drake_none_door_pushes               NOTHING missing: door pushed toward targets spanning past its stops
  drake_none_double_pendulum           NOTHING missing: double pendulum released, no effort column
  drake_none_lid_pose                  NOTHING missing: lid pushed and dropped onto its stop, tracked by its link
                                       pose; jittered sample times, dropouts
"""

import functools
from importlib import metadata

import numpy as np
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import DiscreteContactApproximation, MultibodyPlant
from pydrake.multibody.tree import PrismaticSpring, RevoluteSpring, RotationalInertia, SpatialInertia
from pydrake.systems.analysis import Simulator

import gap_suite as gs
from gap_suite import DT, GRAVITY, Case, SuiteError, chest_lid, door, fx, joint_params, push, urdf_text

ENGINE = f"drake {metadata.version('drake')}"
APPROXIMATION = DiscreteContactApproximation.kLagged  # no contact here: what matters is that the solver is SAP
DRAKE_RTOL = 1e-9  # inertia and bias against MuJoCo, relative to the largest entry (both compute in double)
POSE_TOL = 1e-9  # link positions (m) and quaternion components against MuJoCo
EFFECT_RTOL = 0.01  # damping, spring and added inertia as measured against the values set
SPEED = (0.5, 1.5)  # |qd| of the states where effects are measured
PROBE = 1.0  # rad/s^2 or m/s^2: the efforts that measure the inertia accelerate each joint about this much
LIMIT_MARGIN = 0.02  # rad or m: measuring states stay this far inside the limits, well outside SAP's 2*dt*|v| window
GEAR_RATIO = 10.0  # an armature is a rotor of inertia armature / GEAR_RATIO^2 behind this gear


def load_plant(mech, gravity=True):
    """model.urdf of `mech` parsed into a discrete MultibodyPlant of its own, root link welded to the world
    (not finalized)."""
    plant = MultibodyPlant(time_step=DT)
    plant.set_discrete_contact_approximation(APPROXIMATION)
    instances = Parser(plant).AddModelsFromString(urdf_text(mech), "urdf")
    if len(instances) != 1:
        raise SuiteError(f"Drake's URDF parser read {len(instances)} models from the {mech.name} model")
    plant.WeldFrames(plant.world_frame(), plant.GetBodyByName(mech.root(), instances[0]).body_frame())
    plant.mutable_gravity_field().set_gravity_vector(np.array(GRAVITY if gravity else (0.0, 0.0, 0.0)))
    return plant, instances[0]


class DrakeSim:
    """model.urdf (of `model`, default `mech`) parsed into its own MultibodyPlant; where `mech` (the engine's bodies)
    differs from it, a joint's limits are set through the joint's API and a link's mass, centre of mass and inertia
    through the body's (in the context); the effects through the joint (damping), force elements (springs) and
    actuators (reflected inertia). Efforts through the applied generalized force port (fixed at each sample, held);
    one step is the plant's discrete update (ExecuteForcedEvents)."""

    def __init__(self, mech, effects, gravity=True, model=None):
        model = mech if model is None else model
        self.plant, instance = load_plant(model, gravity)
        self.names = mech.movable()
        self.joints = [self.plant.GetJointByName(name, instance) for name in self.names]
        self.actuators = []
        for drake_joint, name in zip(self.joints, self.names):
            self._set_joint(drake_joint, mech.joint(name), model.joint(name), joint_params(effects, name))
        self.plant.Finalize()
        if self.plant.get_discrete_contact_solver().name != "kSap":
            raise SuiteError(f"Drake's discrete solver is {self.plant.get_discrete_contact_solver()}, SAP was expected")
        self.context = self.plant.CreateDefaultContext()
        for link in mech.links:
            self._set_body(self.plant.GetBodyByName(link.name, instance), link, model.link(link.name))
        for actuator, armature in self.actuators:
            if abs(actuator.default_reflected_inertia() - armature) > 1e-12 * armature:
                raise SuiteError(f"Drake reflects {actuator.default_reflected_inertia()} of inertia, {armature} "
                                 "was set")
        if self.plant.num_actuators():
            self.plant.get_actuation_input_port().FixValue(self.context, np.zeros(self.plant.num_actuators()))
        self.qidx = [joint.position_start() for joint in self.joints]
        self.vidx = [joint.velocity_start() for joint in self.joints]
        self.limited = [(n, mech.joint(name).lower, mech.joint(name).upper) for n, name in enumerate(self.names)
                        if mech.joint(name).lower is not None]
        self.effort = np.zeros(len(self.names))
        self.hold(self.effort)

    def _set_joint(self, drake_joint, joint, urdf_joint, p):
        if drake_joint.num_velocities() != 1 or drake_joint.num_positions() != 1:
            raise SuiteError(f"Drake has no one-dof joint {joint.name}")
        if p["friction"]:
            raise SuiteError(f"joint {joint.name}: Drake's joints have no Coulomb friction")
        gs.check_joint_frame(joint, urdf_joint)
        if joint.lower is not None and (joint.lower, joint.upper) != (urdf_joint.lower, urdf_joint.upper):
            drake_joint.set_position_limits(np.array([joint.lower]), np.array([joint.upper]))
        drake_joint.set_default_damping(joint.damping + p["damping"])
        if p["stiffness"]:
            spring = RevoluteSpring if joint.kind in ("revolute", "continuous") else PrismaticSpring
            self.plant.AddForceElement(spring(drake_joint, p["springref"], p["stiffness"]))
        if p["armature"]:
            actuator = self.plant.AddJointActuator(f"{joint.name}_motor", drake_joint)
            actuator.set_default_rotor_inertia(p["armature"] / GEAR_RATIO ** 2)
            actuator.set_default_gear_ratio(GEAR_RATIO)
            self.actuators.append((actuator, p["armature"]))

    def _set_body(self, body, link, urdf_link):
        if link.mass != urdf_link.mass or not np.array_equal(link.inertia, urdf_link.inertia) or \
                tuple(link.com) != tuple(urdf_link.com):
            i = link.inertia
            central = RotationalInertia(i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
            body.SetSpatialInertiaInBodyFrame(self.context, SpatialInertia.MakeFromCentralInertia(
                link.mass, np.array(link.com, float), central))

    def _full(self, values, idx, size):
        out = np.zeros(size)
        out[idx] = values
        return out

    def set_state(self, q, qd):
        self.plant.SetPositions(self.context, self._full(q, self.qidx, self.plant.num_positions()))
        self.plant.SetVelocities(self.context, self._full(qd, self.vidx, self.plant.num_velocities()))

    def state(self):
        return (self.plant.GetPositions(self.context)[self.qidx].copy(),
                self.plant.GetVelocities(self.context)[self.vidx].copy())

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()
        self.plant.get_applied_generalized_force_input_port().FixValue(
            self.context, self._full(self.effort, self.vidx, self.plant.num_velocities()))

    def advance(self, steps):
        for _ in range(int(steps)):
            self.plant.ExecuteForcedEvents(self.context, publish=False)

    def pose(self, link):
        transform = self.plant.EvalBodyPoseInWorld(self.context, self.plant.GetBodyByName(link))
        return np.concatenate([transform.translation(), transform.rotation().ToQuaternion().wxyz()])

    def dynamics(self, q, qd):
        """Joint-space inertia (with reflected inertia) and bias force C(q, qd) qd + g(q) as Drake's plant computes
        them."""
        self.set_state(q, qd)
        full = self.plant.CalcMassMatrix(self.context)
        bias = self.plant.CalcBiasTerm(self.context) - self.plant.CalcGravityGeneralizedForces(self.context)
        return full[np.ix_(self.vidx, self.vidx)].copy(), bias[self.vidx].copy()

    def step_dynamics(self, q, qd):
        """Joint-space inertia and bias force as one discrete step has them, with everything the step adds (implicit
        damping, the springs, reflected inertia): the velocity change of one step from (q, qd) with zero effort and
        with a small effort on each joint (PROBE of acceleration). Raises where a limited joint is within
        LIMIT_MARGIN of a limit (SAP would add a limit constraint). (gap_suite.probe_step_dynamics)"""
        for n, lower, upper in self.limited:
            if not lower + LIMIT_MARGIN <= q[n] <= upper - LIMIT_MARGIN:
                raise SuiteError(f"joint {self.names[n]} at {q[n]} is too near its limits to measure a free step")
        held = self.effort
        out = gs.probe_step_dynamics(self, q, qd, PROBE)
        self.hold(held)
        return out

    def close(self):
        self.plant = self.context = self.joints = self.actuators = None


gs.SIMULATORS["drake"] = lambda case, mech, effects, gravity: DrakeSim(mech, effects, gravity, model=case.mech)


# ---------------------------------------------------------------- checks


def check_stepping():
    """plant.ExecuteForcedEvents must be the step a Simulator takes: a damped door under a held effort, 500 steps
    each way, states equal to 1e-12."""
    mech = door(0.5, 0.5, 1.2, open_limit=100.0)
    sim = DrakeSim(mech, [fx("hinge", "viscous_damping", damping=0.5)])
    sim.set_state([0.1], [0.2])
    sim.hold([0.7])
    sim.advance(500)
    forced = np.concatenate(sim.state())
    other = DrakeSim(mech, [fx("hinge", "viscous_damping", damping=0.5)])
    other.set_state([0.1], [0.2])
    other.hold([0.7])
    simulator = Simulator(other.plant, other.context)
    simulator.Initialize()
    simulator.AdvanceTo(500 * DT)
    stepped = np.concatenate(other.state())
    sim.close()
    other.close()
    if np.abs(forced - stepped).max() > 1e-12:
        raise SuiteError(f"Drake's forced discrete update {forced} differs from a Simulator's steps {stepped}")


def check_rigid(case, engine_mech, nominal, rng):
    """Drake's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies against
    MuJoCo's model of them): inertia and bias from the plant and from one step, link poses, at 3 random states
    (LIMIT_MARGIN inside the limits). Returns the worst relative inertia/bias error (gap_suite.check_engine_rigid)."""
    return max(gs.check_engine_rigid(case, engine_mech, nominal, rng, "Drake",
                                     [("Drake plant", DrakeSim.dynamics, DRAKE_RTOL),
                                      ("Drake step", DrakeSim.step_dynamics, DRAKE_RTOL)], POSE_TOL, speed=SPEED,
                                     margin=LIMIT_MARGIN))


def measure_effects(case, engine_mech, rng):
    """The efforts of damping and springs and the added inertia as Drake applies them, one step from 8 random
    states: the difference of DrakeSim.step_dynamics with and without the effects, fitted per joint by
    -b qd - k (q - r) and an added diagonal inertia. Drake's damping is implicit, -b qd(t+dt): it shows as b of
    damping and b*DT of inertia; its springs are explicit, -k (q(t) - r): k of stiffness, nothing more; the
    reflected inertia adds the armature. Raises unless the fits match the values set (with that) to EFFECT_RTOL,
    the rest position to 1e-3, and joints without effects get under EFFECT_RTOL of the others'. Returns the fits
    per joint with effects (gap_suite.measure_engine_effects)."""
    def expected(p):
        inertia = p["armature"] + p["damping"] * DT
        return {"damping": (p["damping"], EFFECT_RTOL * p["damping"]), "armature": (inertia, EFFECT_RTOL * inertia)}

    return gs.measure_engine_effects(case, engine_mech, rng, "Drake", DrakeSim.step_dynamics, expected, EFFECT_RTOL,
                                     1e-8, speed=SPEED, margin=LIMIT_MARGIN)


def check_joint_damping():
    """Drake's joint damping must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(DrakeSim, "Drake joint damping", EFFECT_RTOL)


def stop_approach(case, engine_mech, effect):
    """How SAP's limit constraint stops a joint that hits an end stop at the case's impact speed (gravity off): how
    far it goes past the stop, and in how many steps from the first one the constraint slows it (speed down by
    0.1 %) it is within 1e-6 of the stop: (overshoot, steps) (gap_suite.stop_hit)."""
    sim, n, sign = gs.stop_hit(case, engine_mech, effect)
    gap, speed = [], []
    for _ in range(400):
        sim.advance(1)
        gap.append(sign * (sim.state()[0][n] - effect.params["position"]))
        speed.append(sign * sim.state()[1][n])
    sim.close()
    gap, speed = np.array(gap), np.array(speed)
    slowed = int(np.argmax(speed < 0.999 * case.impact_speed))
    settled = slowed + int(np.argmax(np.abs(gap[slowed:]) < 1e-6))
    return max(0.0, float(gap.max())), settled - slowed + 1


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "drake", "drake")  # gap_suite.ENGINE_CASES, named drake_<key>
    return [
        shared("door_damping"),
        shared("flap_spring"),
        shared("knob_armature", description="geared knob (rotor inertia behind a 10:1 gear) driven by a multisine"),
        shared("sash_mass_scale"),
        shared("drawer_end_stop"),
        shared("lid_spring_damping"),
        Case("drake_lid_mass_scale", "drake", chest_lid(), "lid pushed open and let fall: heavier than modelled",
             [fx("lid_hinge", "mass_scale", scale=1.3)], push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6}),
        shared("double_pendulum_elbow_damping"),
        shared("drawer_small_damping"),
        shared("none_door_pushes"),
        shared("none_double_pendulum"),
        shared("none_lid_pose"),
    ]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How Drake made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    step = "measured over one step at 8 random states (speeds 0.5-1.5)"
    if kind == "viscous_damping":
        return (f"Drake Joint.set_default_damping({p['damping']}), implicit in SAP's step (-b*qd(t+dt)); {step} as "
                f"-{got['damping']:g}*qd with {got['armature']:.3g} of apparent inertia (b*dt)")
    if kind == "spring":
        element = "RevoluteSpring" if joint.kind in ("revolute", "continuous") else "PrismaticSpring"
        return (f"Drake {element}({joint.name}, {p['rest_position']}, {p['stiffness']}) force element, explicit "
                f"(-k*(q(t) - r) at the start of the step); {step} as -{got['stiffness']:g}*(q - "
                f"{got['rest_position']:g})")
    if kind == "armature":
        rotor = p["armature"] / GEAR_RATIO ** 2
        return (f"Drake JointActuator {joint.name}_motor: set_default_rotor_inertia({rotor:g}), "
                f"set_default_gear_ratio({GEAR_RATIO:g}): reflected inertia rho^2*I_r = {p['armature']:g} in the mass "
                f"matrix; actuation input held at zero, efforts through the applied generalized force port; {step} as "
                f"{got['armature']:g} added to the joint-space inertia")
    if kind == "mass_scale":
        return (f"Drake RigidBody {joint.child}: SetSpatialInertiaInBodyFrame in the context, mass and rotational "
                f"inertia x{p['scale']}, after parsing model.urdf; inertia and bias checked against MuJoCo's model of "
                f"the heavier link to {DRAKE_RTOL:g}")
    overshoot, steps = stop_approach(case, engine_mech, effect)
    unit = "m" if joint.kind == "prismatic" else "rad"
    return (f"Drake Joint.set_position_limits: {effect.setting['side']} bound {p['position']} instead of model.urdf's; "
            "SAP's SapLimitConstraint (stiffness 1e12, dissipation time scale dt, near-rigid regime beta 0.1: "
            "compliant in form, a hard inelastic stop in effect, no restitution parameter: once the stop is within "
            "a step's reach the joint closes half the remaining gap per step); hit at "
            f"{case.impact_speed} per second, gravity off, it goes {overshoot:.2g} {unit} past the stop and is within "
            f"1e-6 of it {steps} steps after the constraint first slows it; restitution measured in the engine")


def engine_text(rigid_err):
    return (f"{ENGINE}: model.urdf parsed by pydrake Parser.AddModelsFromString into a discrete MultibodyPlant of its "
            f"own (root link welded to the world, no collision geometry), gravity {GRAVITY[2]} z, {DT} s steps, "
            "discrete contact approximation kLagged (SAP solver; joint damping implicit, other forces explicit, "
            "symplectic Euler), each step the plant's own discrete update (ExecuteForcedEvents, checked against a "
            "Simulator); efforts through the applied generalized force input port, fixed at each sample and held "
            "between samples, actuation input (where an actuator exists) zero; model.urdf's joint limits as SAP's "
            "limit constraints (near rigid: a hard inelastic stop); URDF velocity and effort limits as parsed (not "
            "enforced). Rigid bodies checked against model.urdf as MuJoCo reads it (CalcMassMatrix / CalcBiasTerm - "
            f"CalcGravityGeneralizedForces and one-step accelerations, link poses): {rigid_err:.1e} relative")


def run_case(case, seed, out):
    """Simulates one case with Drake and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: DrakeSim(engine_mech, case.effects, model=case.mech))


def main():
    check_stepping()
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_joint_damping)])


if __name__ == "__main__":
    main()
