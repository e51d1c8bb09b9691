#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by NVIDIA PhysX (through SAPIEN), a third engine held out from
`partscene gap`'s development: the same case format as gap_suite.py, cases named px_*.

    gap_suite_physx.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('px_lid*'). Needs the pinned packages of
gap_suite_physx_requirements.txt beside this file (gap_suite.py's, and sapien). Every case is a folder
DIR/<case>/ with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's
"engine" is "sapien <version> (PhysX <version>)".

Engine: SAPIEN's PhysX 5 CPU system alone (no render system, so no Vulkan device is needed), TGS solver, one
articulation built by hand from the mechanism description that model.urdf is written from: root link fixed,
each link's mass, centre of mass and principal inertia (eigenvectors of the URDF inertia), each joint's frame
at the URDF origin with its x axis turned onto the URDF axis (revolute and continuous joints are PhysX
`revolute_unwrapped`, so positions do not wrap; prismatic joints `prismatic`), no collision shapes. 1 ms steps;
efforts set as joint forces (qf), which PhysX keeps applying until they are set again (the spec's hold).
What PhysX adds silently and model.urdf lacks is switched off: joint friction (a coefficient, 0.05 by default),
link linear and angular damping (0.05), joint velocity limit (100), link velocity limits (10 m/s, 50 rad/s) and
sleeping (threshold 0.005); 10 position / 1 velocity solver iterations (the defaults) are set explicitly.
Joint limits are PhysX's: hard, reached exactly within a step, with no restitution parameter.

Concealed effects, each made the way the articulation API makes it:
  viscous_damping   a joint drive, stiffness 0, damping b, velocity target 0 (force mode, no force limit)
  spring            a joint drive, stiffness k, position target = rest position (with damping: one drive)
  armature          the joint's armature
  mass_scale        the child link's mass and inertia scaled
  end_stop          the joint limit narrower than model.urdf's
No coulomb_friction: PhysX 5.3's articulation joint friction is a coefficient that bounds the friction torque by
coefficient * (|transmitted force| + |transmitted torque|) of the joint, so its level follows the load (a door's
weight, the applied effort) instead of being a torque of known size.

Checks (a failure stops the run):
  rigid bodies   PhysX's joint-space inertia and bias force (from the accelerations of one step with zero and unit
                 efforts, limits widened) against model.urdf as MuJoCo reads it, and for a heavier link the
                 engine's bodies against MuJoCo's model of them, to PHYSX_RTOL (PhysX computes in float32), plus
                 every link's pose to POSE_TOL, at 3 random states per case.
  effects        the drives' efforts and the armature, measured one step at a time at 8 random states (the
                 difference to the same articulation without them) and fitted by -k (q - r) - b qd and by the
                 added diagonal inertia, to EFFECT_RTOL of the values set (truth.json gives the values set and
                 the fits). Drives are implicit in the step, close to -b (qd + dt qdd) - k (q + dt qd - r), so a
                 damper also shows as b*dt of inertia; joints without effects get under EFFECT_RTOL of the
                 others' efforts. Before any damped case, a drive with damping 0.5 on a free door under a
                 constant effort must reach the speed of -b*qd after 1 s, to EFFECT_RTOL.
  end stops      restitution measured in the engine (gap_suite.measure_restitution).

Cases (efforts, noise and sampling as gap_suite.py's, each from its own generator
default_rng([seed, crc32(name)])):
  px_door_damping                   cabinet door pushed and released; damped hinge
  px_flap_spring                    light flap on a vertical hinge with a return spring, pushed
  px_pendulum_armature              geared pendulum pushed and released (inertia without weight)
  px_sash_mass_scale                window sash lifted by a multisine; heavier than modelled
  px_drawer_end_stop                drawer pushed open and shut; a stop inside the modelled travel
  px_lid_mass_damping               lid pushed open and let fall: heavier than modelled, damped hinge
  px_lid_spring_damping             counterbalanced lid with a damper (one drive), pushed
  px_double_pendulum_elbow_damping  double pendulum released; only the elbow is damped
  px_none_door_pushes               NOTHING missing: door pushed, at times into its stops
  px_none_double_pendulum           NOTHING missing: double pendulum released, no effort column
  px_none_lid_pose                  NOTHING missing: lid pushed and dropped onto its stop, tracked by its link
                                    pose; jittered sample times, dropouts
"""

import functools

import mujoco
import numpy as np
import sapien
import sapien.physx as physx

import gap_suite as gs
from gap_suite import DT, GRAVITY, SuiteError, joint_params, quat_from_rpy, tree_order, unit

ENGINE = f"sapien {sapien.__version__} (PhysX {physx.version()})"
PHYSX_RTOL = 2e-5  # inertia and bias against MuJoCo, relative to the largest entry (PhysX computes in float32)
POSE_TOL = 1e-6  # link positions (m) and quaternion components against MuJoCo
EFFECT_RTOL = 0.01  # drives and armature as measured against the values set
FREE = 1e4  # limits are widened to +-FREE while PhysxSim.dynamics measures
POSITION_ITERATIONS, VELOCITY_ITERATIONS = 10, 1
UNLIMITED_SPEED = 1e6  # rad/s or m/s: PhysX's velocity limits moved out of the way
JOINT_TYPES = {"revolute": "revolute_unwrapped", "continuous": "revolute_unwrapped", "prismatic": "prismatic",
               "fixed": "fixed"}


def frame_quat(columns):
    """Quaternion (w x y z) of the rotation whose matrix has these columns."""
    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.column_stack(columns).flatten())
    return out


def axis_quat(axis):
    """A rotation that turns x onto the unit axis (PhysX moves a joint along its frame's x)."""
    a = unit(axis)
    b = unit(np.cross((0.0, 0.0, 1.0) if abs(a[2]) < 0.9 else (1.0, 0.0, 0.0), a))
    return frame_quat([a, b, np.cross(a, b)])


class PhysxSim:
    """One PhysX articulation in its own physics-only SAPIEN scene, driven through qf (held between samples)."""

    def __init__(self, mech, effects, gravity=True):
        physx.set_scene_config(gravity=np.array(GRAVITY, np.float32), enable_tgs=True, cpu_workers=0)
        self.scene = sapien.Scene([physx.PhysxCpuSystem()])
        self.scene.timestep = DT
        self.links = {}
        parents = {joint.child: joint for joint in mech.joints}
        for name in [mech.root()] + [joint.child for joint in tree_order(mech)]:
            joint = parents.get(name)
            link = physx.PhysxArticulationLinkComponent(self.links[joint.parent] if joint else None)
            self._set_body(link, mech.link(name), gravity)
            link.joint.type = JOINT_TYPES[joint.kind] if joint else "fixed"
            if joint:
                self._set_joint(link.joint, joint, joint_params(effects, joint.name))
            entity = sapien.Entity()
            entity.name = name
            entity.add_component(link)
            self.scene.add_entity(entity)
            self.links[name] = link
        self.art = self.links[mech.root()].articulation
        self.art.sleep_threshold = 0.0
        self.art.solver_position_iterations = POSITION_ITERATIONS
        self.art.solver_velocity_iterations = VELOCITY_ITERATIONS
        self.names = mech.movable()
        order = [joint.name for joint in self.art.active_joints]
        self.idx = [order.index(name) for name in self.names]
        self.limited = [joint for joint in self.art.active_joints if np.isfinite(joint.limit).all()]

    @staticmethod
    def _set_body(link, body, gravity):
        moments, axes = np.linalg.eigh(body.inertia)
        if np.linalg.det(axes) < 0:
            axes[:, 0] *= -1
        link.name = body.name
        link.mass = body.mass
        link.cmass_local_pose = sapien.Pose(list(body.com), list(frame_quat(axes.T)))
        link.inertia = moments.astype(np.float32)
        link.linear_damping = link.angular_damping = 0.0
        link.max_linear_velocity = link.max_angular_velocity = UNLIMITED_SPEED
        link.disable_gravity = not gravity

    @staticmethod
    def _set_joint(px_joint, joint, p):
        if p["friction"]:
            raise SuiteError(f"joint {joint.name}: PhysX articulation friction is a coefficient of the joint's "
                             "transmitted force, not a Coulomb torque of known size")
        px_joint.name = joint.name
        turn = axis_quat(joint.axis)
        origin = np.zeros(4)
        mujoco.mju_mulQuat(origin, quat_from_rpy(joint.rpy), turn)
        px_joint.pose_in_parent = sapien.Pose(list(joint.xyz), list(origin))
        px_joint.pose_in_child = sapien.Pose([0.0, 0.0, 0.0], list(turn))
        if joint.kind == "fixed":
            return
        px_joint.limit = np.array([[joint.lower, joint.upper] if joint.lower is not None else [-np.inf, np.inf]])
        px_joint.friction = 0.0
        px_joint.max_velocity = UNLIMITED_SPEED
        damping = joint.damping + p["damping"]
        if p["stiffness"] or damping:
            px_joint.set_drive_properties(p["stiffness"], damping, mode="force")
            px_joint.drive_target = np.array([p["springref"]])
            px_joint.drive_velocity_target = np.array([0.0])
        px_joint.armature = np.array([p["armature"]])

    def _full(self, values):
        out = np.zeros(self.art.dof)
        out[self.idx] = values
        return out

    def set_state(self, q, qd):
        self.art.qpos, self.art.qvel = self._full(q), self._full(qd)

    def state(self):
        return self.art.qpos[self.idx].astype(float), self.art.qvel[self.idx].astype(float)

    def hold(self, effort):
        self.art.qf = self._full(effort)

    def advance(self, steps):
        for _ in range(steps):
            self.scene.step()

    def pose(self, link):
        pose = self.links[link].entity_pose
        return np.concatenate([pose.p, pose.q]).astype(float)

    def dynamics(self, q, qd):
        """Joint-space inertia (with armature) and bias force (with the drives' efforts) as the engine's
        forward dynamics has them: accelerations of one step from (q, qd) with zero effort and with a unit
        effort on each joint, limits widened to +-FREE meanwhile so that they do not act."""
        limits, held = [joint.limit for joint in self.limited], self.art.qf
        for joint in self.limited:
            joint.limit = np.array([[-FREE, FREE]])
        acc = []
        for effort in np.vstack([np.zeros(len(q)), np.eye(len(q))]):
            self.set_state(q, qd)
            self.hold(effort)
            self.advance(1)
            acc.append(self.art.qacc[self.idx].astype(float))
        for joint, limit in zip(self.limited, limits):
            joint.limit = limit
        self.art.qf = held
        full = np.linalg.inv(np.column_stack([a - acc[0] for a in acc[1:]]))
        return full, -full @ acc[0]

    def close(self):
        self.scene = self.art = self.links = self.limited = None


gs.SIMULATORS["physx"] = lambda case, mech, effects, gravity: PhysxSim(mech, effects, gravity)


# ---------------------------------------------------------------- checks


def check_rigid(case, engine_mech, nominal, rng):
    """PhysX's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies
    against MuJoCo's model of them): inertia, bias force and link poses at 3 random states. Returns the
    worst relative inertia/bias error (gap_suite.check_engine_rigid)."""
    return max(gs.check_engine_rigid(case, engine_mech, nominal, rng, "PhysX",
                                     [("PhysX", PhysxSim.dynamics, PHYSX_RTOL)], POSE_TOL))


def measure_effects(case, engine_mech, rng):
    """The efforts of the drives and the armature as PhysX applies them, one step from 8 random states: the
    difference of PhysxSim.dynamics with and without the effects, fitted per joint by -k (q - r) - b qd and
    an added diagonal inertia. A drive is implicit, close to -b (qd + DT qdd) - k (q + DT qd - r): it shows
    as b*DT more inertia, and up to k*DT more damping and k*DT^2 more inertia. Raises unless the fits match
    the values set (with that) to EFFECT_RTOL, the rest position to 1e-3, and joints without effects get
    under EFFECT_RTOL of the others' (the step couples joints a little; PHYSX_RTOL of the largest inertia or
    bias is float32's floor). Returns the fits per joint with effects: {joint: {"damping", "armature" (all the
    added inertia)[, "stiffness", "rest_position"]}} (gap_suite.measure_engine_effects)."""
    def expected(p):
        return {"damping": (p["damping"], EFFECT_RTOL * p["damping"] + p["stiffness"] * DT),
                "armature": (p["armature"] + p["damping"] * DT,
                             EFFECT_RTOL * (p["armature"] + p["damping"] * DT) + p["stiffness"] * DT ** 2)}

    return gs.measure_engine_effects(case, engine_mech, rng, "PhysX", PhysxSim.dynamics, expected, EFFECT_RTOL,
                                     PHYSX_RTOL, was="{} was set")


def check_drive_damping():
    """A drive with stiffness 0 and damping b must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(PhysxSim, "PhysX drive damping", EFFECT_RTOL)


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "px", "physx")  # gap_suite.ENGINE_CASES, named px_<key>
    return [
        shared("door_damping"),
        shared("flap_spring"),
        shared("pendulum_armature"),
        shared("sash_mass_scale"),
        shared("drawer_end_stop"),
        shared("lid_mass_damping"),
        shared("lid_spring_damping"),
        shared("double_pendulum_elbow_damping"),
        shared("none_door_pushes", description="NOTHING missing: cabinet door pushed (at times into its stops) and "
               "released"),
        shared("none_double_pendulum"),
        shared("none_lid_pose"),
    ]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How PhysX made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    if kind == "viscous_damping":
        return (f"PhysX joint drive stiffness {joint_params(case.effects, joint.name)['stiffness']:g} damping "
                f"{p['damping']} (force mode, velocity target 0), implicit in the TGS step, close to -b*(qd + dt*qdd); "
                f"measured over one step at 8 random states as -{got['damping']:g}*qd with {got['armature']:.3g} of "
                "apparent inertia")
    if kind == "spring":
        return (f"PhysX joint drive stiffness {p['stiffness']} position target {p['rest_position']} (force mode), "
                f"implicit in the TGS step; measured over one step at 8 random states as -{got['stiffness']:g}*(q - "
                f"{got['rest_position']:g})")
    if kind == "armature":
        return f"PhysX joint armature {p['armature']}; measured as {got['armature']:g} added to the joint-space inertia"
    if kind == "mass_scale":
        return (f"PhysX link {joint.child}: mass and inertia x{p['scale']}; inertia and bias checked against MuJoCo's "
                f"model of the heavier link to {PHYSX_RTOL:g}")
    return (f"PhysX joint limit: {effect.setting['side']} bound {p['position']} instead of model.urdf's (hard, no "
            f"restitution parameter); restitution measured in the engine hitting it at {case.impact_speed} per second, "
            "gravity off")


def engine_text(rigid_err):
    return (f"{ENGINE}: physics-only scene (PhysxCpuSystem, no render system), TGS solver, {POSITION_ITERATIONS} "
            f"position / {VELOCITY_ITERATIONS} velocity iterations, our own articulation from model.urdf's description "
            "(fixed root, principal inertia, joint frame x along the URDF axis, revolute_unwrapped / prismatic "
            f"joints, no shapes), {DT} s steps, efforts through qf held between samples; joint friction coefficient, "
            "link damping, velocity limits and sleeping off; hard joint limits. Rigid bodies checked against "
            "model.urdf as MuJoCo reads it (inertia and bias from one-step accelerations, link poses): "
            f"{rigid_err:.1e} relative")


def run_case(case, seed, out):
    """Simulates one case with PhysX and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: PhysxSim(engine_mech, case.effects))


def main():
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_drive_damping)])


if __name__ == "__main__":
    main()
