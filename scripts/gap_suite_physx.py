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

import math

import mujoco
import numpy as np
import sapien
import sapien.physx as physx

import gap_suite as gs
from gap_suite import (DT, GRAVITY, Case, MujocoSim, SuiteError, compare_dynamics, door, double_pendulum, drawer, fx,
                       joint_params, lid, measure_restitution, mujoco_model, pendulum, push, quat_from_rpy, sash,
                       sines, tree_order, unit)

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


def state_box(mech):
    """Random states are drawn within the limits, or within +-pi for a continuous joint."""
    joints = [mech.joint(name) for name in mech.movable()]
    return (np.array([-math.pi if j.lower is None else j.lower for j in joints]),
            np.array([math.pi if j.upper is None else j.upper for j in joints]))


def check_rigid(case, engine_mech, nominal, rng):
    """PhysX's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies
    against MuJoCo's model of them): inertia, bias force and link poses at 3 random states. Returns the
    worst relative inertia/bias error."""
    pairs = [(case.mech, nominal)]
    if any(e.kind == "mass_scale" for e in case.effects):
        pairs.append((engine_mech, MujocoSim(mujoco_model(engine_mech, []), engine_mech.movable())))
    worst = 0.0
    for mech, reference in pairs:
        sim = PhysxSim(mech, [])
        lo, hi = state_box(mech)
        for _ in range(3):
            q, qd = rng.uniform(lo, hi), rng.normal(0.0, 1.0, len(lo))
            worst = max(worst, compare_dynamics(f"{case.name} (PhysX)", sim.dynamics(q, qd), reference.dynamics(q, qd),
                                                PHYSX_RTOL))
            sim.set_state(q, qd)
            reference.set_state(q, qd)
            for link in (joint.child for joint in mech.joints):
                got, want = sim.pose(link), reference.pose(link)
                turn = min(np.abs(got[3:] - want[3:]).max(), np.abs(got[3:] + want[3:]).max())  # q and -q: one turn
                err = max(np.abs(got[:3] - want[:3]).max(), turn)
                if err > POSE_TOL:
                    raise SuiteError(f"{case.name}: PhysX puts link {link} {err:.1e} away from model.urdf")
        sim.close()
    return worst


def measure_effects(case, engine_mech, rng):
    """The efforts of the drives and the armature as PhysX applies them, one step from 8 random states: the
    difference of PhysxSim.dynamics with and without the effects, fitted per joint by -k (q - r) - b qd and
    an added diagonal inertia. A drive is implicit, close to -b (qd + DT qdd) - k (q + DT qd - r): it shows
    as b*DT more inertia, and up to k*DT more damping and k*DT^2 more inertia. Raises unless the fits match
    the values set (with that) to EFFECT_RTOL, the rest position to 1e-3, and joints without effects get
    under EFFECT_RTOL of the others' (the step couples joints a little). Returns the fits per joint with
    effects: {joint: {"damping", "armature" (all the added inertia)[, "stiffness", "rest_position"]}}."""
    names = engine_mech.movable()
    bare, full = PhysxSim(engine_mech, []), PhysxSim(engine_mech, case.effects)
    lo, hi = state_box(engine_mech)
    q, qd, effort, added, scale = [], [], [], [], 0.0
    for _ in range(8):
        q.append(rng.uniform(lo, hi))
        qd.append(rng.normal(0.0, 1.0, len(names)))
        (m0, b0), (m1, b1) = bare.dynamics(q[-1], qd[-1]), full.dynamics(q[-1], qd[-1])
        effort.append(b0 - b1)
        added.append(np.diag(m1 - m0))
        scale = max(scale, np.abs(m0).max(), np.abs(b0).max())
    bare.close()
    full.close()
    q, qd, effort, added = (np.array(x) for x in (q, qd, effort, added))
    out = {}
    for n, name in enumerate(names):
        p = joint_params(case.effects, name)
        if not (p["stiffness"] or p["damping"] or p["armature"]):
            if (np.abs(effort[:, n]).max() > EFFECT_RTOL * np.abs(effort).max() + PHYSX_RTOL * scale or
                    np.abs(added[:, n]).max() > EFFECT_RTOL * np.abs(added).max() + PHYSX_RTOL * scale):
                raise SuiteError(f"{case.name}: PhysX adds an effort or inertia on {name}, which has no effect")
            continue
        columns = [-qd[:, n]] + ([-q[:, n], np.ones(len(q))] if p["stiffness"] else [])
        fit = np.linalg.lstsq(np.column_stack(columns), effort[:, n], rcond=None)[0]
        got = {"damping": fit[0], "armature": float(np.mean(added[:, n]))}
        want = {"damping": (p["damping"], EFFECT_RTOL * p["damping"] + p["stiffness"] * DT),
                "armature": (p["armature"] + p["damping"] * DT,
                             EFFECT_RTOL * (p["armature"] + p["damping"] * DT) + p["stiffness"] * DT ** 2)}
        if p["stiffness"]:
            got.update(stiffness=fit[1], rest_position=fit[2] / fit[1])
            want.update(stiffness=(p["stiffness"], EFFECT_RTOL * p["stiffness"]), rest_position=(p["springref"], 1e-3))
        for key, (value, tol) in want.items():
            if abs(got[key] - value) > max(tol, PHYSX_RTOL * scale):  # float32 floor
                raise SuiteError(f"{case.name}: PhysX applies {key} {got[key]:.6g} on {name}, {value} was set")
        out[name] = {key: float(f"{value:.4g}") for key, value in got.items()}
    return out


def check_drive_damping():
    """A drive with stiffness 0 and damping b must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(PhysxSim, "PhysX drive damping", EFFECT_RTOL)


# ---------------------------------------------------------------- cases


def cases():
    door_s = lambda: door(0.45, 0.7, 2.0)  # noqa: E731  I = 0.135 kg m^2
    lid_m = lambda: lid(0.4, 0.5, 1.5)  # noqa: E731  I = 0.08 kg m^2, 2.9 N m of weight
    return [
        Case("px_door_damping", "physx", door_s(), "cabinet door pushed and released; the hinge is viscously damped",
             [fx("hinge", "viscous_damping", damping=0.25)], push(["hinge"], [1.5]), {"hinge": 0.3}),
        Case("px_flap_spring", "physx", door(0.25, 0.3, 0.4), "light flap on a vertical hinge with a return spring, pushed",
             [fx("hinge", "spring", stiffness=0.15, rest_position=1.0)], push(["hinge"], [0.2]), {"hinge": 0.1},
             duration=6.0, rate=250),
        Case("px_pendulum_armature", "physx", pendulum(0.35, 0.8, 0.04),
             "geared pendulum pushed and released: rotor inertia (inertia without weight)",
             [fx("pivot", "armature", armature=0.02)], push(["pivot"], [1.5]), {"pivot": 0.5}, duration=10.0),
        Case("px_sash_mass_scale", "physx", sash(0.8, 0.6, 5.0, 0.5), "window sash lifted by a multisine; heavier than modelled",
             [fx("sash", "mass_scale", scale=1.3)], sines(["sash"], [30.0], [0.25]), {"sash": 0.25}, effort_noise=0.01),
        Case("px_drawer_end_stop", "physx", drawer(0.45, 0.5, 0.15, 4.0, 0.45),
             "drawer pushed open and shut; a stop inside stops it short of the modelled travel",
             [fx("slide", "end_stop", position=0.3, side="upper")], push(["slide"], [12.0], span=[(0.05, 0.42)]),
             {"slide": 0.05}, rate=250, impact_speed=0.3),
        Case("px_lid_mass_damping", "physx", lid_m(), "lid pushed open and let fall: heavier than modelled, damped hinge",
             [fx("lid_hinge", "mass_scale", scale=1.3), fx("lid_hinge", "viscous_damping", damping=0.2)],
             push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6}),
        Case("px_lid_spring_damping", "physx", lid(0.35, 0.45, 1.2), "counterbalanced lid (spring) with a damper, pushed",
             [fx("lid_hinge", "spring", stiffness=1.2, rest_position=1.6), fx("lid_hinge", "viscous_damping", damping=0.15)],
             push(["lid_hinge"], [1.5]), {"lid_hinge": 0.8}),
        Case("px_double_pendulum_elbow_damping", "physx", double_pendulum(0.3, 0.6, 0.25, 0.4),
             "double pendulum released from an angle; only the elbow is damped",
             [fx("elbow", "viscous_damping", damping=0.01)], None, {"shoulder": 1.2, "elbow": -0.8}, rate=250),
        Case("px_none_door_pushes", "physx", door_s(), "NOTHING missing: cabinet door pushed (at times into its stops) and "
             "released", [], push(["hinge"], [2.0], span=[(-0.8, 2.8)]), {"hinge": 0.3}, effort_noise=0.01),
        Case("px_none_double_pendulum", "physx", double_pendulum(0.3, 0.6, 0.25, 0.4),
             "NOTHING missing: double pendulum released", [], None, {"shoulder": 1.0, "elbow": 0.5}, rate=250),
        Case("px_none_lid_pose", "physx", lid_m(), "NOTHING missing: lid pushed and dropped onto its stop, tracked by its "
             "link pose; jittered sample times, dropouts", [], push(["lid_hinge"], [4.5]), {"lid_hinge": 0.6},
             observe="pose", jitter=True, dropouts=0.02, effort_noise=0.01),
    ]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How PhysX made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    if kind == "viscous_damping":
        return (f"PhysX joint drive stiffness {joint_params(case.effects, joint.name)['stiffness']:g} damping {p['damping']} "
                "(force mode, velocity target 0), implicit in the TGS step, close to -b*(qd + dt*qdd); measured over one "
                f"step at 8 random states as -{got['damping']:g}*qd with {got['armature']:.3g} of apparent inertia")
    if kind == "spring":
        return (f"PhysX joint drive stiffness {p['stiffness']} position target {p['rest_position']} (force mode), implicit "
                f"in the TGS step; measured over one step at 8 random states as -{got['stiffness']:g}*(q - "
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
    return (f"{ENGINE}: physics-only scene (PhysxCpuSystem, no render system), TGS solver, {POSITION_ITERATIONS} position / "
            f"{VELOCITY_ITERATIONS} velocity iterations, our own articulation from model.urdf's description (fixed root, "
            f"principal inertia, joint frame x along the URDF axis, revolute_unwrapped / prismatic joints, no shapes), "
            f"{DT} s steps, efforts through qf held between samples; joint friction coefficient, link damping, velocity "
            f"limits and sleeping off; hard joint limits. Rigid bodies checked against model.urdf as MuJoCo reads it "
            f"(inertia and bias from one-step accelerations, link poses): {rigid_err:.1e} relative")


def run_case(case, seed, out):
    """Simulates one case with PhysX and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: PhysxSim(engine_mech, case.effects))


def main():
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_drive_damping)])


if __name__ == "__main__":
    main()
