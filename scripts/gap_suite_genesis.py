#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by Genesis (genesis-world, its rigid solver on the CPU backend,
float64), an eleventh engine held out from `partscene gap`'s development: the same case format as gap_suite.py,
cases named genesis_*. Its arms are gap_suite_genesis_arms.py's.

    gap_suite_genesis.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('genesis_lid*'). Needs the pinned packages of
gap_suite_genesis_requirements.txt beside this file (an environment of its own). Every case is a folder
DIR/<case>/ with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's
"engine" is "genesis <version>".

Engine: the engine's bodies written as URDF (model.urdf, with a heavier link or a narrower joint range where the case
conceals one) read by Genesis's own URDF importer (gs.morphs.URDF, fixed=True: the root link welded to the world)
into a scene of its own: gravity -9.81 z, 1 ms steps, one substep, collisions off, Genesis's default integrator
(approximate_implicitfast) and constraint solver, hibernation off (its default). Efforts are generalized forces set by control_dofs_force at each
sample and held between samples. What Genesis adds to a URDF and URDF cannot say is taken out: the
rotor inertia its URDF morph fills in at build for every one-dof joint left at zero (default_armature, 0.1 kg m^2 in
genesis-world 1.4) is set to what the case conceals, zero where none (gap_suite_genesis_arms.py keeps it in one
case), and the bound the importer puts on each joint's applied force (the URDF's <limit effort>) is lifted. A stop is model.urdf's joint range as Genesis enforces it: a
joint-limit row of its constraint solver (soft, as MuJoCo's; restitution measured).

Concealed effects, each made the way Genesis's API makes it (set on the built scene):
  coulomb_friction  set_dofs_frictionloss: a friction-loss constraint row solved with the step, its force bounded by
                    the level
  viscous_damping   set_dofs_damping (in the integrator's implicit part)
  armature          set_dofs_armature: added to the joint-space inertia's diagonal
  mass_scale        the child link's mass and inertia scaled in the URDF the engine reads
  end_stop          a joint range narrower than model.urdf's in the URDF the engine reads
No spring: Genesis's dofs_stiffness pulls a joint toward its zero (qpos0) and the shared spring cases rest
elsewhere. No tilted axis or effort offset (not engine effects).

Checks (a failure stops the run):
  rigid bodies   the joint-space inertia and bias force one Genesis step has (gap_suite.probe_step_dynamics, the
                 limits lifted meanwhile) against model.urdf as MuJoCo reads it, and for a heavier link against
                 MuJoCo's model of the engine's bodies, to RIGID_RTOL, plus every link's pose to POSE_TOL, at 3 random
                 states per case.
  effects        the damping and friction efforts and the added inertia, measured one step at a time at 8 random
                 states (the difference to the same bodies without them, speeds 0.5-1.5 so that friction slides
                 through the step) and fitted by -b qd - f sign(qd) and the added diagonal inertia, to EFFECT_RTOL of
                 the values set. Damping is implicit: the fit sees b of damping and the armature plus b*dt of inertia.
  end stops      restitution measured in the engine (gap_suite.measure_restitution).

Cases: gap_suite.ENGINE_CASES without the springs (efforts, noise and sampling as gap_suite.py's, each from its own
generator default_rng([seed, crc32(name)])).
"""
import functools
import os
import tempfile
from importlib import metadata

import genesis
import mujoco
import numpy as np

import gap_suite as gs
from gap_suite import DT, GRAVITY, SuiteError, joint_params, urdf_text

ENGINE = f"genesis {metadata.version('genesis-world')}"
RIGID_RTOL = 1e-8  # one step's inertia and bias against MuJoCo, relative to the largest entry
POSE_TOL = 1e-9  # link positions (m) and quaternion components against MuJoCo
EFFECT_RTOL = 1e-6  # damping, friction and added inertia as measured against the values set
SPEED = (0.5, 1.5)  # |qd| of the states where effects are measured: friction must slide through the step
PROBE = 1.0  # rad/s^2 or m/s^2: the efforts that measure the inertia accelerate each joint about this much
FREE = 1e9  # a joint range that never binds, while one step is measured


class GenesisScene:
    """URDF `text` read by Genesis's importer into a scene of its own (root link welded to the world, collisions off,
    DT steps, one substep, `gravity`), its joints `names` (in order); efforts through control_dofs_force, held
    between steps; beside it, MuJoCo's reading of the same text (dynamics)."""

    def __init__(self, text, names, gravity=GRAVITY):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "model.urdf")
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
            self.scene = genesis.Scene(
                sim_options=genesis.options.SimOptions(dt=DT, substeps=1, gravity=tuple(gravity)),
                rigid_options=genesis.options.RigidOptions(enable_collision=False, enable_self_collision=False),
                show_viewer=False)
            self.entity = self.scene.add_entity(genesis.morphs.URDF(file=path, fixed=True))
            self.scene.build()
        self.names = list(names)
        if self.entity.n_dofs != len(self.names):
            raise SuiteError(f"Genesis made {self.entity.n_dofs} degrees of freedom of a model of {len(self.names)} "
                             "joints")
        self.idx = [self.entity.get_joint(name).dofs_idx_local[0] for name in self.names]
        self.mujoco = gs.MujocoSim(mujoco.MjSpec.from_string(text).compile(), self.names)
        # The importer bounds each joint's applied force by the URDF's <limit effort> (the Panda's wrist: 12 N m),
        # silently: the recording's efforts must be the ones the engine applied, so the bound is lifted.
        unbounded = np.full(len(self.names), np.inf)
        self.entity.set_dofs_force_range(-unbounded, unbounded, self.idx)
        self.effort = np.zeros(len(self.names))
        self.hold(self.effort)

    def set_state(self, q, qd):
        self.entity.set_dofs_position(np.asarray(q, float), self.idx)
        self.entity.set_dofs_velocity(np.asarray(qd, float), self.idx)

    def state(self):
        return (np.asarray(self.entity.get_dofs_position(self.idx), float).copy(),
                np.asarray(self.entity.get_dofs_velocity(self.idx), float).copy())

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()
        self.entity.control_dofs_force(self.effort, self.idx)

    def advance(self, steps):
        for _ in range(int(steps)):
            self.scene.step()

    def dynamics(self, q, qd):
        """Joint-space inertia and bias force as MuJoCo reads the same URDF: what a Genesis step is checked against,
        and the size of gap_suite.probe_step_dynamics's probes (every check measures Genesis through its steps)."""
        return self.mujoco.dynamics(q, qd)


class GenesisSim(GenesisScene):
    """The engine's bodies (`mech`) written as URDF and read by Genesis's importer into a scene of its own, the
    effects set on the joints' degrees of freedom."""

    def __init__(self, mech, effects, gravity=True):
        super().__init__(urdf_text(mech), mech.movable(), GRAVITY if gravity else (0.0, 0.0, 0.0))
        params = [joint_params(effects, name) for name in self.names]
        for p, name in zip(params, self.names):
            if p["stiffness"]:
                raise SuiteError(f"joint {name}: Genesis's springs rest at the joint's zero, not where the case's does")
        self._set("frictionloss", [p["friction"] for p in params])
        self._set("damping", [mech.joint(name).damping + p["damping"] for p, name in zip(params, self.names)])
        self._set("armature", [p["armature"] for p in params])
        self.limits = [np.asarray(x, float).copy() for x in self.entity.get_dofs_limit(self.idx)]

    def _set(self, what, values):
        getattr(self.entity, f"set_dofs_{what}")(np.asarray(values, float), self.idx)
        got = np.asarray(getattr(self.entity, f"get_dofs_{what}")(self.idx), float)
        if not np.array_equal(got, np.asarray(values, float)):
            raise SuiteError(f"Genesis keeps {what} {got}, {values} was set")

    def pose(self, link):
        body = self.entity.get_link(link)
        return np.concatenate([np.asarray(body.get_pos(), float), np.asarray(body.get_quat(), float)])  # w x y z

    def step_dynamics(self, q, qd):
        """Joint-space inertia and bias force as one Genesis step has them, with everything the step adds (implicit
        damping, armature, friction loss while the joint slides): the velocity change of one step from (q, qd) with
        zero effort and with a small effort on each joint (PROBE of acceleration), the joint ranges lifted
        meanwhile. Raises where a joint's velocity changes sign within the step (friction would not slide).
        (gap_suite.probe_step_dynamics)"""
        def slides(after):
            if np.any(np.sign(after) != np.sign(qd)):
                raise SuiteError("a joint's velocity changed sign within the measuring step")

        free = np.full(len(self.names), FREE)
        self.entity.set_dofs_limit(-free, free, self.idx)
        out = gs.probe_step_dynamics(self, q, qd, PROBE, check=slides)
        self.entity.set_dofs_limit(*self.limits, self.idx)
        self.hold(np.zeros(len(q)))
        return out

    def close(self):
        self.scene.destroy()
        self.scene = self.entity = self.mujoco = None


gs.SIMULATORS["genesis"] = lambda case, mech, effects, gravity: GenesisSim(mech, effects, gravity)


# ---------------------------------------------------------------- checks


def check_rigid(case, engine_mech, nominal, rng):
    """Genesis's bodies, through one step, against model.urdf as MuJoCo reads it (and, for a heavier link, the
    engine's bodies against MuJoCo's model of them), link poses too, at 3 random states. Returns the worst relative
    inertia/bias error (gap_suite.check_engine_rigid)."""
    return max(gs.check_engine_rigid(case, engine_mech, nominal, rng, "Genesis",
                                     [("Genesis step", GenesisSim.step_dynamics, RIGID_RTOL)], POSE_TOL, speed=SPEED))


def measure_effects(case, engine_mech, rng):
    """The efforts of damping and friction and the added inertia as Genesis applies them, one step from 8 random
    states: the difference of GenesisSim.step_dynamics with and without the effects, fitted per joint by
    -b qd - f sign(qd) and an added diagonal inertia. Damping is implicit: b of damping, the armature plus b*DT of
    inertia. Raises unless the fits match the values set to EFFECT_RTOL and joints without effects get under
    EFFECT_RTOL of the others'. Returns the fits per joint with effects (gap_suite.measure_engine_effects)."""
    def expected(p):
        inertia = p["armature"] + p["damping"] * DT
        return {"damping": (p["damping"], EFFECT_RTOL * max(p["damping"], 1.0)),
                "armature": (inertia, EFFECT_RTOL * max(inertia, 1.0))}

    return gs.measure_engine_effects(case, engine_mech, rng, "Genesis", GenesisSim.step_dynamics, expected, EFFECT_RTOL,
                                     RIGID_RTOL, speed=SPEED)


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "genesis", "genesis")  # gap_suite.ENGINE_CASES, named genesis_<key>
    return [shared(key) for key in gs.ENGINE_CASES
            if not any(e.kind == "spring" for e in gs.ENGINE_CASES[key]("", "genesis").effects)]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How Genesis made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    step = "measured over one step at 8 random states (speeds 0.5-1.5)"
    if kind == "coulomb_friction":
        return (f"Genesis set_dofs_frictionloss({p['friction']}): a friction-loss row of the constraint solver, its "
                f"force bounded by the level; {step} as -{got['friction']:g}*sign(qd) while it slides")
    if kind == "viscous_damping":
        return (f"Genesis set_dofs_damping({p['damping']}), implicit in the step; {step} as -{got['damping']:g}*qd with "
                f"{got['armature']:.3g} of apparent inertia (b*dt)")
    if kind == "armature":
        return f"Genesis set_dofs_armature({p['armature']}); {step} as {got['armature']:.6g} of added inertia"
    if kind == "mass_scale":
        joint = engine_mech.joint(effect.joint)
        return (f"link {joint.child} x{p['scale']} (mass and inertia) in the URDF Genesis reads; inertia and bias "
                f"checked against MuJoCo's model of the heavier link to {RIGID_RTOL:g}")
    return (f"a joint range ending at {p['position']} in the URDF Genesis reads (model.urdf's is wider): a joint-limit "
            f"row of Genesis's constraint solver; restitution measured in the engine hitting it at {case.impact_speed} "
            "per second, gravity off")


def engine_text(rigid_err):
    return (f"{ENGINE} (torch {metadata.version('torch')}), CPU backend, float64: the engine's bodies as URDF read by "
            f"Genesis's importer (root link welded to the world, collisions off), a scene of its own: gravity "
            f"{GRAVITY[2]} z, {DT} s steps, one substep, default integrator and constraint solver, the importer's "
            "armature replaced by the case's (zero where none); efforts through control_dofs_force, held between "
            "samples; joint ranges enforced by the constraint solver's limit rows. One step's rigid bodies checked "
            f"against model.urdf as MuJoCo reads it, link poses too: {rigid_err:.1e} relative")


def run_case(case, seed, out):
    """Simulates one case with Genesis and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: GenesisSim(engine_mech, case.effects))


def init():
    """Genesis on its CPU backend in float64, seeded (both suites)."""
    genesis.init(backend=genesis.cpu, precision="64", logging_level="warning", seed=0)


if __name__ == "__main__":
    init()
    gs.engine_suite_main(cases, run_case)
