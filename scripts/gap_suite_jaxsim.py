#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by JaxSim (PyPI jaxsim, ami-iit: a multibody simulator written in JAX,
reduced coordinates, its own integrators), an eighth engine held out from `partscene gap`'s development: the same case
format as gap_suite.py, cases named jaxsim_*.

    gap_suite_jaxsim.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('jaxsim_lid*'). Needs the pinned packages of
gap_suite_jaxsim_requirements.txt beside this file (gap_suite.py's, and jaxsim with the jax and jaxlib it runs on).
Every case is a folder DIR/<case>/ with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes
them; truth.json's "engine" is "jaxsim <version>". JAX runs on the CPU (JAX_PLATFORMS=cpu, set here) in float64
(JAX_ENABLE_X64, JaxSim's default, checked).

Engine: JaxSim reads a URDF only through Gazebo's `gz sdf -p` (rod.Sdf.load runs that executable to turn URDF into
SDF), which is no pip package; it reads SDF itself (rod, pure Python). So model.urdf is written out as SDF here, element
for element (sdf_of_urdf: each <inertial>, joint origin, axis and <limit>, and <dynamics damping friction> where
model.urdf has it; anything else in model.urdf stops the run), link frames in URDF's convention (each link's pose is its
parent joint's frame, each joint's pose in its parent link), plus a fixed joint from SDF's `world` to the root link
(JaxSim welds a model whose root is jointed to the world; no floating base), and read by
JaxSimModel.build_from_model_description; the rigid-body check below compares what JaxSim built with model.urdf as
MuJoCo reads it. Gravity -9.81 z (JaxSim's default is 9.80665), 1 ms steps (js.model.step with JaxSim's default
integrator, semi-implicit Euler: the joint accelerations from JaxSim's ABA at the start of the step, then
v += dt a, q += dt v; JaxSim also has RK4), advanced in a jax.lax.fori_loop of steps between samples. Efforts are
js.model.step's joint_force_references, the same every step until the next sample (held). JaxSim computes every joint
force it adds (friction, limits) from the state at the start of the step and adds them to the references (explicit).
What JaxSim adds silently and model.urdf lacks is switched off: the actuation model's torque-speed curve
(ActuationParams: every joint's total force clipped to 3000 N m, falling to 0 between 30 and 100 rad/s; set to
infinity); contact with the ground (JaxSim's default soft contact model, Hunt-Crossley against a flat terrain, acts at
collidable points, which come from collision geometry: the SDF has none, checked: no collidable point); gravity's
9.80665. JaxSim's joint friction is on (ActuationParams.enable_friction, default) and zero where nothing is set; there
is no body damping and no sleeping. What remains:
  - JaxSim does not enforce a joint's limits unless asked to: a limit acts only through its
    JointParameters.position_limit_spring, 0 by default (JAXSIM_JOINT_POSITION_LIMIT_SPRING), so model.urdf's limits
    would be ignored. Every limited joint gets a spring here, stiffness I * STOP_OMEGA^2 with I the joint's inertia in
    model.urdf at q = 0 (a contact of pi/STOP_OMEGA = 10.5 ms, a joint at 0.5 rad/s sinks 1.7 mm): the force
    -k * (q - limit) beyond a limit, 0 inside, computed at the start of the step. JaxSim's limit damper
    (position_limit_damper) is left at 0, so the stops are undamped springs that throw a joint back at a restitution
    of about 1 (0.98-1.02 by the phase of the impact, measured; a lid dropped onto its stop bounces on it for
    seconds): JaxSim's damper term is -d * qd * (the spring's force) (actuation_model.compute_resultant_torques:
    tau -= jnp.positive(tau) * d * qd, where jnp.positive is the identity), which dissipates at a lower limit and adds
    energy at an upper one (measured: with d = 0.5 s/rad a door hits its lower limit at 0.5 rad/s and comes back at
    0.86 of its speed, its upper at 1.2; with d = 0.1 s/rad a lid hits its upper limit at 3 rad/s and comes back at
    3.76, and a lid pushed against it repeatedly gains energy until its state is not finite), so no damper setting
    gives both stops a restitution below 1.
  - JaxSim's Coulomb friction is -f * sign(qd(t)), explicit, with no sticking: a joint whose other forces are below f
    does not stop but chatters about zero speed, its velocity changing sign every step or few by up to
    (f + |u|) dt / I, and creeps (a free door with f = 0.5 N m held at 0.3 N m moves 3 mrad in 1 s, at speeds of
    +-5 mrad/s).

Concealed effects, each made the way JaxSim makes it (JaxSim's own model parameters, set after reading model.urdf):
  coulomb_friction  KinDynParameters.joint_parameters.friction_static (SDF <dynamics><friction>): -f * sign(qd(t))
                    added to the joint's force (compute_resultant_torques), explicit, no stiction (above)
  viscous_damping   KinDynParameters.joint_parameters.friction_viscous (SDF <dynamics><damping>): -b * qd(t),
                    explicit (the speed at the start of the step)
  mass_scale        KinDynParameters.set_link_mass and set_link_inertia (inertia about the centre of mass) of the child
                    link, scaled
  end_stop          JointParameters.position_limits_min/max narrower than model.urdf's: JaxSim's limit spring (above)
JaxSim's joints have no spring (rod reads SDF <spring_stiffness>, JaxSim's parser drops it) and no armature
(JointDescription.motor_inertia exists but nothing reads it), so no case has either. No tilted axis or effort offset
(not engine effects).

Checks (a failure stops the run):
  rigid bodies   JaxSim's joint-space inertia and bias force, both as js.model.free_floating_mass_matrix /
                 free_floating_bias_forces give them and as one js.model.step moves the joints (accelerations with zero
                 and small efforts), at 3 random moving states (speeds 0.5-1.5, so the step holds the velocity terms),
                 against model.urdf as MuJoCo reads it, and for a heavier link the engine's bodies against MuJoCo's
                 model of them, to JAXSIM_RTOL, plus every link's pose (js.model.forward_kinematics) to POSE_TOL. No
                 collidable point in any model (no contact).
  effects        the damping and friction efforts and the added inertia, measured one step at a time at 8 random
                 states (the difference to the same model without them, speeds 0.5-1.5 so that friction slides through
                 the step) and fitted by -b qd - f sign(qd) and the added diagonal inertia, to EFFECT_RTOL of the values
                 set (truth.json gives the values set and the fits): b of damping and no inertia (explicit). Joints
                 without effects get under EFFECT_RTOL of the others' efforts. Before any damped case, a damped free
                 door under a constant effort must reach the speed of -b*qd after 1 s (gap_suite.check_joint_damping);
                 before any case with friction, a free door under an effort below the friction must stay within one
                 step's chatter of rest ((f + |u|) dt / I in speed, f dt / I per second in position) for 1 s, and above
                 it reach the speed of (u - f)/I.
  end stops      restitution measured in the engine hitting the stop at the case's impact speed from 16 phases of one
                 step's travel (gravity off): truth.json gives the mean, engine_detail the range.

Cases (efforts, noise and sampling as gap_suite.py's, each from its own generator
default_rng([seed, crc32(name)])):
  jaxsim_door_friction                   heavy wardrobe door pushed and released; dry hinge
  jaxsim_drawer_friction                 loaded drawer pushed and released; dry runners
  jaxsim_door_damping                    cabinet door pushed and released; damped hinge
  jaxsim_sash_mass_scale                 window sash lifted by a multisine; heavier than modelled
  jaxsim_drawer_end_stop                 drawer pushed open and shut; a stop inside the modelled travel
  jaxsim_door_friction_damping           cabinet door pushed: dry friction and viscous damping
  jaxsim_lid_mass_damping                lid pushed open and let fall: heavier than modelled, damped hinge
  jaxsim_lid_mass_friction               lid pushed open and let fall: heavier than modelled, dry hinge
  jaxsim_double_pendulum_elbow_friction  double pendulum released; dry friction at the elbow only
  jaxsim_double_pendulum_elbow_damping   double pendulum released; only the elbow is damped
  jaxsim_drawer_small_damping            drawer pushed and released; SMALL but real damping, at the edge
  jaxsim_none_door_pushes                NOTHING missing: door pushed toward targets spanning past its stops
  jaxsim_none_double_pendulum            NOTHING missing: double pendulum released, no effort column
  jaxsim_none_lid_pose                   NOTHING missing: lid pushed and dropped onto its stop, tracked by its link
                                         pose; jittered sample times, dropouts
"""

import os

os.environ["JAX_PLATFORMS"] = "cpu"  # before jax is imported: CPU only
os.environ["JAX_ENABLE_X64"] = "1"  # JaxSim's default, made explicit: float64
# The same recordings on every x86-64 machine: XLA compiles for the CPU it runs on, and with
# AVX-512 its float64 results differ in the last bits from an AVX2 machine's, which a lid's
# stick-slip turns into a different recording (seed 3 gave another soft_close on an AMD EPYC
# than on the machines the CI gates were first measured on). Capped at AVX2, which every CI
# machine has.
os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " --xla_cpu_max_isa=AVX2").strip()

import functools  # noqa: E402
import math  # noqa: E402
import warnings  # noqa: E402
import xml.etree.ElementTree as ET  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import jaxsim  # noqa: E402
import jaxsim.api as js  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from jaxsim.utils import Mutability  # noqa: E402

import gap_suite as gs  # noqa: E402
from gap_suite import DT, GRAVITY, SuiteError, door, fx, joint_params, urdf_text  # noqa: E402

ENGINE = f"jaxsim {jaxsim.__version__}"
JAXSIM_RTOL = 1e-9  # inertia and bias against MuJoCo, relative to the largest entry (both compute in double)
POSE_TOL = 1e-9  # link positions (m) and quaternion components against MuJoCo
EFFECT_RTOL = 0.01  # damping, friction and added inertia as measured against the values set
SPEED = (0.5, 1.5)  # |qd| of the states where effects are measured: friction must slide through the step
PROBE = 1.0  # rad/s^2 or m/s^2: the efforts that measure the inertia accelerate each joint about this much
STOP_OMEGA = 300.0  # rad/s: a limit's spring is the joint's inertia x STOP_OMEGA^2 (a contact of pi/STOP_OMEGA)
STOP_PHASES = 16  # impacts, spread over one step's travel, that measure an end stop's restitution
WORLD_JOINT = "jaxsim_world_weld"  # the fixed joint from SDF's world to the root link
# JaxSim's actuation model clips every joint's total force by a torque-speed curve (3000 N m, falling to 0 between 30
# and 100 rad/s): switched off. Joint friction stays on (it is zero where nothing is set).
ACTUATION = jaxsim.rbda.actuation.ActuationParams(torque_max=math.inf, omega_th=math.inf, omega_max=math.inf,
                                                   enable_friction=True)

# JaxSim hashes its models' arrays for jit; an unlimited joint's limits (+-1.8e308) overflow that hash's arithmetic
# (a warning, the hash stays deterministic).
warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"jaxsim\.utils\.wrappers")
if not jax.config.jax_enable_x64:
    raise SuiteError("JAX runs in float32: JaxSim's float64 (JAX_ENABLE_X64) is needed")


# ---------------------------------------------------------------- the engine's description of model.urdf


def _pose(origin):
    xyz = origin.get("xyz", "0 0 0") if origin is not None else "0 0 0"
    rpy = origin.get("rpy", "0 0 0") if origin is not None else "0 0 0"
    return f"{xyz} {rpy}"


def sdf_of_urdf(text):
    """model.urdf's text as SDF 1.10 for JaxSim's reader (rod), element for element, in URDF's frame convention: a
    link's pose is its parent joint's frame (the root's the model's), a joint's pose is its <origin> in its parent
    link, an <inertial>'s pose is in its link (SDF's and URDF's roll-pitch-yaw are the same rotation), a joint's axis
    is in the joint frame (SDF's default, as in URDF). <limit lower upper effort velocity> and <dynamics damping
    friction> carry over; a fixed joint WORLD_JOINT welds the root link to SDF's world. Raises on anything model.urdf
    may hold that this does not translate (geometry, mimic joints, other joint types)."""
    robot = ET.fromstring(text)
    links, joints = robot.findall("link"), robot.findall("joint")
    if len(robot) != len(links) + len(joints):
        raise SuiteError("model.urdf holds elements other than <link> and <joint>: not translated for JaxSim")
    parent_joint = {joint.find("child").get("link"): joint.get("name") for joint in joints}
    roots = [link.get("name") for link in links if link.get("name") not in parent_joint]
    if len(roots) != 1:
        raise SuiteError(f"model.urdf has {len(roots)} root links")
    out = ['<?xml version="1.0"?>', '<sdf version="1.10">', f'  <model name="{robot.get("name")}">']
    for link in links:
        name, inertial = link.get("name"), link.find("inertial")
        if [child.tag for child in link] != ["inertial"]:
            raise SuiteError(f"link {name}: only an <inertial> is translated for JaxSim")
        i = inertial.find("inertia")
        out += [f'    <link name="{name}">',
                f'      <pose relative_to="{parent_joint.get(name, "__model__")}">0 0 0 0 0 0</pose>',
                f'      <inertial><pose>{_pose(inertial.find("origin"))}</pose>'
                f'<mass>{inertial.find("mass").get("value")}</mass><inertia>'
                + "".join(f"<{k}>{i.get(k)}</{k}>" for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"))
                + "</inertia></inertial>",
                "    </link>"]
    out += [f'    <joint name="{WORLD_JOINT}" type="fixed"><parent>world</parent><child>{roots[0]}</child></joint>']
    for joint in joints:
        kind, parent, child = joint.get("type"), joint.find("parent").get("link"), joint.find("child").get("link")
        known = {"parent", "child", "origin", "axis", "limit", "dynamics"}
        if kind not in ("revolute", "continuous", "prismatic", "fixed") or {c.tag for c in joint} - known:
            raise SuiteError(f"joint {joint.get('name')}: not translated for JaxSim")
        out += [f'    <joint name="{joint.get("name")}" type="{kind}"><parent>{parent}</parent><child>{child}</child>',
                f'      <pose relative_to="{parent}">{_pose(joint.find("origin"))}</pose>']
        if kind != "fixed":
            axis, limit, dynamics = joint.find("axis"), joint.find("limit"), joint.find("dynamics")
            inner = f'<xyz>{axis.get("xyz") if axis is not None else "1 0 0"}</xyz>'
            if kind != "continuous" and limit is not None:
                inner += "<limit>" + "".join(f"<{k}>{limit.get(k)}</{k}>" for k in ("lower", "upper", "effort",
                                                                                   "velocity") if limit.get(k)) + \
                         "</limit>"
            if dynamics is not None:
                inner += "<dynamics>" + "".join(f"<{k}>{dynamics.get(k)}</{k}>" for k in ("damping", "friction")
                                                if dynamics.get(k)) + "</dynamics>"
            out.append(f"      <axis>{inner}</axis>")
        out.append("    </joint>")
    out += ["  </model>", "</sdf>"]
    return "\n".join(out) + "\n"


@functools.lru_cache(maxsize=None)
def load_model(text, gravity):
    """model.urdf's text (as SDF, sdf_of_urdf) read by JaxSimModel.build_from_model_description: 1 ms steps,
    semi-implicit Euler, gravity -9.81 z (or none), the actuation curve off. Raises unless JaxSim welded the root (no
    floating base) and made no collidable point (no contact). Cached: a model is immutable, changes make new ones.
    JaxSim keeps the description it read in the model's static `built_from`, so that every model.urdf would compile
    every jitted function anew: it is cleared (as JaxSim sets it, without validation), and models of one mechanism
    (same links and joints, other numbers) share their compiled steps."""
    model = js.model.JaxSimModel.build_from_model_description(
        sdf_of_urdf(text), is_urdf=False, time_step=DT, gravity=-GRAVITY[2] if gravity else 0.0,
        actuation_params=ACTUATION, integrator=js.model.IntegratorType.SemiImplicitEuler)
    if model.floating_base():
        raise SuiteError(f"JaxSim gave the {model.name()} model a floating base")
    if len(model.kin_dyn_parameters.contact_parameters.body) or model.time_step != DT:
        raise SuiteError(f"JaxSim's {model.name()} model has collidable points or another time step")
    with model.mutable_context(mutability=Mutability.MUTABLE_NO_VALIDATION):
        model.built_from = None
    return model


def _data(model, q, qd):
    return js.data.JaxSimModelData.build(model=model, joint_positions=q, joint_velocities=qd,
                                         velocity_representation=jaxsim.VelRepr.Inertial)


@jax.jit
def _advance(model, q, qd, effort, steps):
    """`steps` js.model.step of `model` from (q, qd) with the joint force references `effort` held: (q, qd) after.
    (A fixed-base model without collidable points has no state beyond q and qd.)"""
    data = jax.lax.fori_loop(0, steps, lambda _, d: js.model.step(model, d, joint_force_references=effort),
                             _data(model, q, qd))
    return data.joint_positions, data.joint_velocities


@jax.jit
def _dynamics(model, q, qd):
    """The joints' block of JaxSim's free-floating mass matrix and bias forces (the base is welded), and every link's
    world transform (js.model.forward_kinematics)."""
    data = _data(model, q, qd)
    return (js.model.free_floating_mass_matrix(model, data)[6:, 6:],
            js.model.free_floating_bias_forces(model, data)[6:], js.model.forward_kinematics(model, data))


class JaxsimSim:
    """model.urdf (of `model`, default `mech`) read by JaxSim (load_model); where `mech` (the engine's bodies) differs
    from it, a link's mass, centre of mass and inertia and a joint's limits are set in JaxSim's KinDynParameters, and
    the friction and damping of `effects` in its JointParameters; every limited joint gets its limit spring (stiffness
    from model.urdf's inertia, damper 0). Efforts as js.model.step's joint force references (held)."""

    def __init__(self, mech, effects, gravity=True, model=None):
        model = mech if model is None else model
        for effect in effects:
            if effect.kind in ("spring", "armature"):
                raise SuiteError(f"joint {effect.joint}: JaxSim's joints have no {effect.kind}")
        self.model = load_model(urdf_text(model), bool(gravity))
        self.names = mech.movable()
        order = list(self.model.joint_names())
        if sorted(order) != sorted(self.names):
            raise SuiteError(f"JaxSim reads joints {order}, model.urdf's are {self.names}")
        self.idx = [order.index(name) for name in self.names]
        self.links = list(self.model.link_names())
        self.effort = np.zeros(len(self.names))
        kdp = self.model.kin_dyn_parameters
        for link in mech.links:
            if link.name == mech.root():
                continue
            if link.name not in self.links:
                raise SuiteError(f"JaxSim has no link {link.name}")
            kdp = self._set_body(kdp, self.links.index(link.name), link, model.link(link.name))
        # limit springs from model.urdf's inertia at q = 0 (before the engine's bodies change it)
        zero = jnp.zeros(self.model.dofs())
        inertia = np.diag(np.asarray(_dynamics(self.model, zero, zero)[0]))
        jp = kdp.joint_parameters
        arrays = {key: np.array(getattr(jp, key), float) for key in
                  ("friction_static", "friction_viscous", "position_limits_min", "position_limits_max",
                   "position_limit_spring", "position_limit_damper")}
        if np.any(arrays["position_limit_spring"]) or np.any(arrays["position_limit_damper"]):
            raise SuiteError("JaxSim read limit springs or dampers that model.urdf does not have")
        self.stiffness = {}
        for name, k in zip(self.names, self.idx):
            joint, urdf_joint, p = mech.joint(name), model.joint(name), joint_params(effects, name)
            gs.check_joint_frame(joint, urdf_joint)
            if arrays["friction_viscous"][k] != urdf_joint.damping or arrays["friction_static"][k] != 0.0:
                raise SuiteError(f"JaxSim reads joint {name}'s damping or friction otherwise than model.urdf")
            arrays["friction_static"][k] += p["friction"]
            arrays["friction_viscous"][k] += p["damping"]
            if joint.lower is not None:
                if (arrays["position_limits_min"][k], arrays["position_limits_max"][k]) != \
                        (urdf_joint.lower, urdf_joint.upper):
                    raise SuiteError(f"JaxSim reads joint {name}'s limits otherwise than model.urdf")
                arrays["position_limits_min"][k], arrays["position_limits_max"][k] = joint.lower, joint.upper
                arrays["position_limit_spring"][k] = inertia[k] * STOP_OMEGA ** 2
            self.stiffness[name] = float(arrays["position_limit_spring"][k])
        kdp = kdp.replace(joint_parameters=jp.replace(**{key: jnp.asarray(v) for key, v in arrays.items()}))
        self.model = self.model.replace(kin_dyn_parameters=kdp)
        self.set_state(np.zeros(len(self.names)), np.zeros(len(self.names)))

    @staticmethod
    def _set_body(kdp, index, link, urdf_link):
        if link.mass != urdf_link.mass:
            kdp = kdp.set_link_mass(index, link.mass)
        if not np.array_equal(link.inertia, urdf_link.inertia):
            kdp = kdp.set_link_inertia(index, jnp.asarray(link.inertia, float))
        if tuple(link.com) != tuple(urdf_link.com):
            params = kdp.link_parameters
            kdp = kdp.replace(link_parameters=params.replace(
                center_of_mass=params.center_of_mass.at[index].set(jnp.asarray(link.com, float))))
        return kdp

    def _full(self, values):
        out = np.zeros(self.model.dofs())
        out[self.idx] = values
        return jnp.asarray(out)

    def set_state(self, q, qd):
        self.q, self.qd = self._full(q), self._full(qd)

    def state(self):
        return np.asarray(self.q)[self.idx].copy(), np.asarray(self.qd)[self.idx].copy()

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()

    def advance(self, steps):
        if int(steps) > 0:
            self.q, self.qd = _advance(self.model, self.q, self.qd, self._full(self.effort), int(steps))
            if not np.all(np.isfinite(np.asarray(self.qd))):
                raise SuiteError("JaxSim's state is no longer finite")

    def pose(self, link):
        transform = np.asarray(_dynamics(self.model, self.q, self.qd)[2])[self.links.index(link)]
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(transform[:3, :3]).flatten())
        return np.concatenate([transform[:3, 3], quat])

    def dynamics(self, q, qd):
        """Joint-space inertia and bias force C(q, qd) qd + g(q) as JaxSim computes them."""
        self.set_state(q, qd)
        full, bias, _ = (np.asarray(x) for x in _dynamics(self.model, self.q, self.qd))
        return full[np.ix_(self.idx, self.idx)].copy(), bias[self.idx].copy()

    def step_dynamics(self, q, qd):
        """Joint-space inertia and bias force as one js.model.step has them, with everything the step adds (friction,
        damping; no limit spring acts inside the limits): the velocity change of one step from (q, qd) with zero
        effort and with a small effort on each joint (PROBE of acceleration). Raises where a joint's velocity changes
        sign within the step (friction would not slide). (gap_suite.probe_step_dynamics)"""
        def slides(after):
            moving = np.asarray(qd) != 0
            if np.any(np.sign(after[moving]) != np.sign(np.asarray(qd)[moving])):
                raise SuiteError("a joint's velocity changed sign within the measuring step")

        held = self.effort
        out = gs.probe_step_dynamics(self, q, qd, PROBE, check=slides)
        self.hold(held)
        return out

    def close(self):
        self.model = self.q = self.qd = None


gs.SIMULATORS["jaxsim"] = lambda case, mech, effects, gravity: JaxsimSim(mech, effects, gravity, model=case.mech)


# ---------------------------------------------------------------- checks


def check_rigid(case, engine_mech, nominal, rng):
    """JaxSim's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies against
    MuJoCo's model of them): inertia and bias from JaxSim's model functions and from one step, at 3 random moving
    states, link poses (gap_suite.check_engine_rigid). Returns the worst relative inertia/bias error."""
    return max(gs.check_engine_rigid(case, engine_mech, nominal, rng, "JaxSim",
                                     [("JaxSim free_floating_mass_matrix/bias_forces", JaxsimSim.dynamics,
                                       JAXSIM_RTOL),
                                      ("JaxSim step", JaxsimSim.step_dynamics, JAXSIM_RTOL)], POSE_TOL, speed=SPEED))


def measure_effects(case, engine_mech, rng):
    """The efforts of damping and friction and the added inertia as JaxSim applies them, one step from 8 random
    states: the difference of JaxsimSim.step_dynamics with and without the effects, fitted per joint by
    -b qd - f sign(qd) and an added diagonal inertia. JaxSim's viscous friction is explicit (-b qd(t)): it shows as
    b of damping and no inertia. Raises unless the fits match the values set to EFFECT_RTOL, and joints without
    effects get under EFFECT_RTOL of the others'. Returns the fits per joint with effects
    (gap_suite.measure_engine_effects)."""
    def expected(p):
        return {"damping": (p["damping"], EFFECT_RTOL * p["damping"]), "armature": (0.0, 0.0)}

    return gs.measure_engine_effects(case, engine_mech, rng, "JaxSim", JaxsimSim.step_dynamics, expected,
                                     EFFECT_RTOL, 1e-9, speed=SPEED)


def check_joint_damping():
    """JaxSim's friction_viscous must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(JaxsimSim, "JaxSim friction_viscous", EFFECT_RTOL)


def check_coulomb_friction():
    """JaxSim's static friction f on a free door (inertia I, no gravity torque, stops outside its motion): under a
    held effort u below f the door chatters about rest, each step changing its speed by at most (f + |u|) dt / I:
    after 1 s its speed must be within that and its position within f dt / I (per second) of where it started; under
    u above f it reaches (u - f)/I after 1 s, to EFFECT_RTOL."""
    mech = door(0.5, 0.5, 1.2, open_limit=3.0)
    inertia = mech.link("door_panel").inertia[2, 2] + 1.2 * 0.25 ** 2
    sim = JaxsimSim(mech, [fx("hinge", "coulomb_friction", friction=0.5)])
    for effort, expected in ((0.3, 0.0), (-0.45, 0.0), (1.0, 0.5 / inertia)):
        sim.hold([effort])
        sim.set_state([0.2], [0.0])
        sim.advance(1000)
        (q,), (qd,) = sim.state()
        if expected == 0.0 and (abs(qd) > (0.5 + abs(effort)) * DT / inertia or abs(q - 0.2) > 0.5 * DT / inertia):
            raise SuiteError(f"JaxSim friction_static 0.5 does not hold the door under {effort}: q {q}, qd {qd} "
                             "after 1 s")
        if expected and abs(qd - expected) > EFFECT_RTOL * expected:
            raise SuiteError(f"JaxSim friction_static does not act as f*sign(qd): {qd} rad/s after 1 s, "
                             f"expected {expected}")
    sim.close()


def measure_restitution(case, engine_mech, effect):
    """An end stop's restitution as JaxSim's limit spring has it: hit at the case's impact speed, gravity off, from
    STOP_PHASES starts spread over one step's travel (gap_suite.stop_hit, moved back by a share of speed*DT). Returns
    the mean (what truth.json gives) and keeps the range in `effect.setting` for engine_detail."""
    out = []
    for k in range(STOP_PHASES):
        sim, n, sign = gs.stop_hit(case, engine_mech, effect)
        q, qd = sim.state()
        q[n] -= sign * k / STOP_PHASES * case.impact_speed * DT
        sim.set_state(q, qd)
        sim.advance(400)
        out.append(max(0.0, -sign * float(sim.state()[1][n]) / case.impact_speed))
        effect.setting["stiffness"] = sim.stiffness[effect.joint]
        sim.close()
    effect.setting["restitution_range"] = (round(min(out), 3), round(max(out), 3))
    return round(float(np.mean(out)), 3)


# gap_suite.run_engine_case measures an end stop's restitution through gap_suite.measure_restitution (one impact);
# JaxSim's explicit spring depends a little on where in its step the joint meets the stop, so this suite's
# measurement (16 phases) is used.
gs.measure_restitution = measure_restitution


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "jaxsim", "jaxsim")  # gap_suite.ENGINE_CASES, named jaxsim_<key>
    return [shared(key) for key in gs.FRICTION_DAMPING_CASES]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How JaxSim made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    step = "measured over one step at 8 random states (speeds 0.5-1.5)"
    if kind == "coulomb_friction":
        return (f"JaxSim JointParameters.friction_static = {p['friction']} (SDF <dynamics><friction>): "
                f"-{p['friction']}*sign(qd(t)) added to the joint's force at the start of every step, explicit, no "
                f"stiction (a joint held below it chatters about zero speed and creeps); {step} as "
                f"-{got['friction']:g}*sign(qd)")
    if kind == "viscous_damping":
        return (f"JaxSim JointParameters.friction_viscous = {p['damping']} (SDF <dynamics><damping>): "
                f"-{p['damping']}*qd(t) added to the joint's force at the start of every step, explicit; {step} as "
                f"-{got['damping']:g}*qd with {got['armature']:.3g} of apparent inertia")
    if kind == "mass_scale":
        return (f"JaxSim KinDynParameters.set_link_mass and set_link_inertia of {joint.child} x{p['scale']} after "
                f"reading model.urdf; inertia and bias checked against MuJoCo's model of the heavier link to "
                f"{JAXSIM_RTOL:g}")
    lo, hi = effect.setting.get("restitution_range", (None, None))
    return (f"JaxSim JointParameters.position_limits_{'max' if effect.setting['side'] == 'upper' else 'min'} = "
            f"{p['position']} instead of model.urdf's, with the joint's limit spring position_limit_spring "
            f"{effect.setting.get('stiffness', 0.0):.4g} (the joint's inertia x {STOP_OMEGA:g}^2) and damper 0: an "
            "undamped penalty spring beyond the limit, explicit; restitution measured in the engine hitting it at "
            f"{case.impact_speed} per second, gravity off, from {STOP_PHASES} phases of one step's travel: mean "
            f"{p['restitution']}, range {lo}-{hi}")


def engine_text(rigid_err):
    return (f"{ENGINE} on jax {jax.__version__} (CPU, float64): model.urdf written out as SDF element for element "
            "(JaxSim reads URDF only through Gazebo's gz sdf), a fixed joint from the world to the root link, read by "
            "JaxSimModel.build_from_model_description; no collision geometry (no collidable point, so JaxSim's soft "
            f"ground contact never acts); gravity {GRAVITY[2]} z, {DT} s steps of js.model.step, semi-implicit Euler "
            "(ABA), actuation torque-speed curve off (infinite), joint friction on; efforts as joint force references "
            "held between samples; every force JaxSim adds at a joint (friction, limits) computed at the start of the "
            "step; joint limits (not enforced by JaxSim by default) as its limit springs, stiffness the joint's "
            f"inertia in model.urdf x {STOP_OMEGA:g}^2 (contact {math.pi / STOP_OMEGA * 1e3:.1f} ms), damper 0 "
            "(JaxSim's limit damper adds energy at an upper limit): undamped, restitution about 1. Rigid bodies "
            "checked against model.urdf as MuJoCo reads it (free_floating_mass_matrix / free_floating_bias_forces "
            f"and one step's accelerations at moving states, link poses): {rigid_err:.1e} relative")


def run_case(case, seed, out):
    """Simulates one case with JaxSim and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: JaxsimSim(engine_mech, case.effects, model=case.mech))


def main():
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_joint_damping),
                                           ("coulomb_friction", check_coulomb_friction)])


if __name__ == "__main__":
    main()
