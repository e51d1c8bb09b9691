#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by NVIDIA Newton (on NVIDIA Warp, CPU device), a sixth engine held out
from `partscene gap`'s development: the same case format as gap_suite.py, cases named newton_*.

    gap_suite_newton.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('newton_lid*'). Needs the pinned packages of
gap_suite_newton_requirements.txt beside this file (gap_suite.py's, newton and warp-lang) and a C++ compiler: Warp
compiles its CPU kernels on first use (a minute or so; cached in ~/.cache/warp). Every case is a folder DIR/<case>/
with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's "engine" is
"newton <version> (warp <version>)".

Engine: model.urdf itself, read by Newton's URDF importer (ModelBuilder.add_urdf with floating=False: the root link
fixed to the world) into a ModelBuilder of its own (up axis z, gravity -9.81 z), finalized on Warp's "cpu" device,
and stepped by SolverFeatherstone: Newton's own reduced-coordinate solver (composite rigid body algorithm, the
joint-space inertia factored by Cholesky every step, symplectic Euler: qd(t+dt) = qd + dt qdd(q(t), qd(t)),
q(t+dt) = q + dt qd(t+dt)). Not SolverMuJoCo (that is MuJoCo, tested by gap_suite.py), nor the maximal-coordinate
SolverSemiImplicit / SolverXPBD (their joints are penalty springs or position constraints, not joint coordinates).
Everything in the step is explicit: joint damping, springs and limits are evaluated at (q(t), qd(t)). Newton's
models and Featherstone's matrices are float32 (Warp arrays; no float64 models), which sets the precision of every
check below. 1 ms steps, no substeps: the stiffest thing in a step is a joint limit's penalty on the lightest
limited part, the flap (0.0084 kg m^2): omega*dt = 1.1 and limit_kd*dt/I = 1.2, where the step is still stable
(its eigenvalues 0.68 and 0.29: the flap's stops are all but dead, the heavier parts bounce). model.urdf has no
geometry, so the importer makes no shapes: there is nothing to collide and no contacts are computed (the step is
given contacts=None). Efforts are generalized joint forces, Control.joint_f, set at each sample and held between
samples as the spec says (Newton keeps applying them until they are set again). Joint positions are read from
State.joint_q / joint_qd, link poses from State.body_q (the link frame, warp's x y z w quaternion reordered).
What Newton would add silently and model.urdf lacks is off: the solver's angular_damping argument (0.05 by default;
Featherstone 1.8 does not apply it, it is set to 0 anyway), the importer's drives (target_ke = target_kd = 0, so
the POSITION target mode it gives the joints exerts nothing). The URDF's velocity (100) and effort (1000) limits are
imported as joint_velocity_limit / joint_effort_limit, which SolverFeatherstone does not enforce. Joint limits:
Newton's are penalty springs, explicit in the step: outside [lower, upper] the joint gets
limit_ke*(bound - q) - limit_kd*qd (ModelBuilder.JointDofConfig's defaults, limit_ke 1e4 and limit_kd 10 per rad or
m, which the importer gives every joint): a compliant stop that lets the joint a little past it and bounces
(restitution measured per stop, truth.json gives it with the overshoot and the contact time).

Concealed effects, each made the way Newton's ModelBuilder makes it (its per-degree-of-freedom and per-body arrays,
set after add_urdf, before finalize):
  viscous_damping   ModelBuilder.joint_damping (the passive joint damping that URDF <dynamics damping> also fills):
                    explicit in the step, -b*qd(t)
  spring            ModelBuilder.joint_stiffness and joint_rest_q (Newton's passive joint spring): explicit,
                    -k*(q(t) - r)
  armature          ModelBuilder.joint_armature: added to the joint-space inertia's diagonal before the Cholesky
                    factorization
  mass_scale        ModelBuilder.body_mass and body_inertia of the child link, scaled
  end_stop          ModelBuilder.joint_limit_lower / joint_limit_upper narrower than model.urdf's (the default
                    penalty limit_ke / limit_kd kept)
No coulomb_friction: SolverFeatherstone does not implement Model.joint_friction (its documentation says so, and a
door with joint_friction 0.5 under a held 0.3 N m moves exactly as one without; the experimental SolverSteel has
dry joint friction rows, but it is another solver). No tilted axis or effort offset (not engine effects).

Checks (a failure stops the run):
  rigid bodies   Newton's joint-space inertia and bias force, both as newton.eval_inverse_dynamics_passive gives
                 them (mass matrix with armature, Coriolis and gravity forces) to NEWTON_RTOL and as one
                 SolverFeatherstone step moves the joints (the velocity change with zero effort and with small
                 efforts, PROBE of acceleration) to STEP_RTOL, against model.urdf as MuJoCo reads it, and for a
                 heavier link the engine's bodies against MuJoCo's model of them, plus every link's pose
                 (State.body_q after newton.eval_fk) to POSE_TOL, at 3 random states per case. The step is float32:
                 a velocity of ~1 is resolved to ~1e-7, so one step's acceleration to ~1e-4, hence STEP_RTOL.
  effects        the damping and spring efforts and the added inertia, measured one step at a time at 8 random
                 states (the difference to the same model without them, speeds 0.5-1.5) and fitted by
                 -b qd - k (q - r) and the added diagonal inertia, to EFFECT_RTOL of the values set (truth.json gives
                 the values set and the fits). Everything is explicit: the fit sees b of damping, k of stiffness and
                 only the armature as added inertia. Joints without effects get under EFFECT_RTOL of the others'
                 efforts (plus STEP_RTOL of the largest inertia or bias, float32's floor). Before any damped case, a
                 damped free door under a constant effort must reach the speed of -b*qd after 1 s
                 (gap_suite.check_joint_damping).
  end stops      restitution measured in the engine (gap_suite.measure_restitution); the limit stiffness and damping
                 the model has must be the builder's defaults stated in truth.json.

Cases (efforts, noise and sampling as gap_suite.py's, each from its own generator
default_rng([seed, crc32(name)])):
  newton_door_damping                   cabinet door pushed and released; damped hinge
  newton_flap_spring                    light flap on a vertical hinge with a return spring, pushed
  newton_knob_armature                  geared knob (rotor inertia) driven by a multisine
  newton_pendulum_armature              geared pendulum pushed and released (inertia without weight)
  newton_sash_mass_scale                window sash lifted by a multisine; heavier than modelled
  newton_drawer_end_stop                drawer pushed open and shut; a stop inside the modelled travel
  newton_door_end_stop                  door pushed open; a door stopper the model lacks
  newton_lid_spring_damping             counterbalanced lid with a damper, pushed
  newton_lid_mass_damping               lid pushed open and let fall: heavier than modelled, damped hinge
  newton_double_pendulum_elbow_damping  double pendulum released; only the elbow is damped
  newton_drawer_small_damping           drawer pushed and released; SMALL but real damping, at the edge
  newton_none_door_pushes               NOTHING missing: door pushed toward targets spanning past its stops
  newton_none_double_pendulum           NOTHING missing: double pendulum released, no effort column
  newton_none_lid_pose                  NOTHING missing: lid pushed and dropped onto its stop, tracked by its link
                                        pose; jittered sample times, dropouts
"""

import functools

import numpy as np
import warp as wp

import gap_suite as gs
from gap_suite import DT, GRAVITY, Case, SuiteError, door, fx, joint_params, push, urdf_text

wp.config.log_level = wp.LOG_WARNING  # no initialisation or kernel-module load lines among the summary lines
import newton  # noqa: E402  (after Warp is quietened)

ENGINE = f"newton {newton.__version__} (warp {wp.__version__})"
DEVICE = "cpu"
NEWTON_RTOL = 1e-5  # eval_inverse_dynamics_passive's inertia and bias against MuJoCo (float32)
STEP_RTOL = 5e-4  # one step's inertia and bias against MuJoCo: float32 velocities resolve its acceleration to ~1e-4
POSE_TOL = 1e-6  # link positions (m) and quaternion components against MuJoCo (float32)
EFFECT_RTOL = 0.01  # damping, spring and added inertia as measured against the values set
SPEED = (0.5, 1.5)  # |qd| of the states where effects are measured
PROBE = 10.0  # rad/s^2 or m/s^2: the efforts that measure the inertia accelerate each joint about this much
LIMIT_KE, LIMIT_KD = newton.ModelBuilder.JointDofConfig().limit_ke, newton.ModelBuilder.JointDofConfig().limit_kd


def load_builder(mech, gravity=True):
    """model.urdf of `mech` read by Newton's URDF importer into a ModelBuilder of its own (up axis z), root link fixed
    to the world; returns it and {joint name: joint index}, {link name: body index}."""
    builder = newton.ModelBuilder(up_axis=newton.Axis.Z, gravity=GRAVITY if gravity else (0.0, 0.0, 0.0))
    builder.add_urdf(urdf_text(mech), floating=False)
    prefix = f"{mech.name}/"
    joints = {label.removeprefix(prefix): n for n, label in enumerate(builder.joint_label)}
    bodies = {label.removeprefix(prefix): n for n, label in enumerate(builder.body_label)}
    if len(builder.shape_type) or set(bodies) != {link.name for link in mech.links}:
        raise SuiteError(f"Newton's URDF importer read shapes or other links from the {mech.name} model")
    return builder, joints, bodies


class NewtonSim:
    """model.urdf (of `model`, default `mech`) read into its own ModelBuilder; where `mech` (the engine's bodies)
    differs from it, a joint's limits and a link's mass and inertia are set in the builder's arrays, and the effects
    in its joint arrays; finalized on the CPU and stepped by SolverFeatherstone. Efforts through Control.joint_f
    (set at each sample, held)."""

    def __init__(self, mech, effects, gravity=True, model=None):
        model = mech if model is None else model
        builder, joints, self.bodies = load_builder(model, gravity)
        self.names = mech.movable()
        self.qidx = [builder.joint_q_start[joints[name]] for name in self.names]
        self.vidx = [builder.joint_qd_start[joints[name]] for name in self.names]
        for link in mech.links:
            self._set_body(builder, self.bodies[link.name], link, model.link(link.name))
        for name in self.names:
            self._set_joint(builder, joints[name], mech.joint(name), model.joint(name), joint_params(effects, name))
        self.model = builder.finalize(device=DEVICE)
        if self.model.articulation_count != 1:
            raise SuiteError(f"Newton made {self.model.articulation_count} articulations of the {mech.name} model")
        if np.any(self.model.joint_target_ke.numpy()) or np.any(self.model.joint_target_kd.numpy()):
            raise SuiteError("Newton's importer gave the joints a drive")
        if np.any(self.model.joint_limit_ke.numpy() != np.float32(LIMIT_KE)) or \
                np.any(self.model.joint_limit_kd.numpy() != np.float32(LIMIT_KD)):
            raise SuiteError("Newton's joint limits are not the builder's default limit_ke / limit_kd")
        self.solver = newton.solvers.SolverFeatherstone(self.model, angular_damping=0.0)
        self.current, self.spare = self.model.state(), self.model.state()
        self.control = self.model.control()
        size = self.model.max_dofs_per_articulation
        self.mass_matrix = wp.zeros((1, size, size), dtype=wp.float32, device=DEVICE)
        self.gravity_force = wp.zeros(self.model.joint_dof_count, dtype=wp.float32, device=DEVICE)
        self.coriolis_force = wp.zeros(self.model.joint_dof_count, dtype=wp.float32, device=DEVICE)
        self.effort = np.zeros(len(self.names))
        self.hold(self.effort)

    @staticmethod
    def _set_body(builder, body, link, urdf_link):
        if tuple(link.com) != tuple(urdf_link.com):
            raise SuiteError(f"link {link.name}: the engine's centre of mass differs from model.urdf's")
        if link.mass != urdf_link.mass or not np.array_equal(link.inertia, urdf_link.inertia):
            builder.body_mass[body] = link.mass
            builder.body_inertia[body] = wp.mat33(*np.asarray(link.inertia, float).flatten())

    @staticmethod
    def _set_joint(builder, index, joint, urdf_joint, p):
        if tuple(builder.joint_dof_dim[index]) not in ((1, 0), (0, 1)):
            raise SuiteError(f"Newton has no one-dof joint {joint.name}")
        q, v = builder.joint_q_start[index], builder.joint_qd_start[index]
        if p["friction"]:
            raise SuiteError(f"joint {joint.name}: SolverFeatherstone has no joint friction")
        gs.check_joint_frame(joint, urdf_joint)
        if joint.lower is not None:
            builder.joint_limit_lower[v], builder.joint_limit_upper[v] = joint.lower, joint.upper
        builder.joint_damping[v] = joint.damping + p["damping"]
        builder.joint_stiffness[v] = p["stiffness"]
        builder.joint_rest_q[q] = p["springref"]
        builder.joint_armature[v] = p["armature"]

    def _full(self, values, idx, size):
        out = np.zeros(size, np.float32)
        out[idx] = values
        return out

    def set_state(self, q, qd):
        self.current.joint_q.assign(self._full(q, self.qidx, self.model.joint_coord_count))
        self.current.joint_qd.assign(self._full(qd, self.vidx, self.model.joint_dof_count))
        newton.eval_fk(self.model, self.current.joint_q, self.current.joint_qd, self.current)

    def state(self):
        return (self.current.joint_q.numpy()[self.qidx].astype(float),
                self.current.joint_qd.numpy()[self.vidx].astype(float))

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()
        self.control.joint_f.assign(self._full(self.effort, self.vidx, self.model.joint_dof_count))

    def advance(self, steps):
        for _ in range(int(steps)):
            self.solver.step(self.current, self.spare, self.control, None, DT)
            self.current, self.spare = self.spare, self.current

    def pose(self, link):
        x, y, z, qx, qy, qz, qw = self.current.body_q.numpy()[self.bodies[link]].astype(float)
        return np.array([x, y, z, qw, qx, qy, qz])

    def dynamics(self, q, qd):
        """Joint-space inertia (with armature) and bias force C(q, qd) qd + g(q) as Newton computes them
        (eval_inverse_dynamics_passive)."""
        self.set_state(q, qd)
        newton.eval_inverse_dynamics_passive(self.model, self.current, mass_matrix=self.mass_matrix,
                                             gravity_force=self.gravity_force, coriolis_force=self.coriolis_force)
        full = self.mass_matrix.numpy()[0].astype(float)  # one articulation: its dofs are the model's
        bias = self.gravity_force.numpy().astype(float) + self.coriolis_force.numpy().astype(float)
        return full[np.ix_(self.vidx, self.vidx)], bias[self.vidx]

    def step_dynamics(self, q, qd):
        """Joint-space inertia and bias force as one SolverFeatherstone step has them, with everything the step adds
        (damping, springs, armature): the velocity change of one step from (q, qd) with zero effort and with a small
        effort on each joint (PROBE of acceleration). Inside the limits the penalty limit adds nothing. The velocity
        before the step is read back as the float32 state holds it. (gap_suite.probe_step_dynamics)"""
        held = self.effort
        out = gs.probe_step_dynamics(self, q, qd, PROBE, read_back=True)
        self.hold(held)
        return out

    def close(self):
        self.model = self.solver = self.current = self.spare = self.control = None


gs.SIMULATORS["newton"] = lambda case, mech, effects, gravity: NewtonSim(mech, effects, gravity, model=case.mech)


# ---------------------------------------------------------------- checks


def check_rigid(case, engine_mech, nominal, rng):
    """Newton's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies against
    MuJoCo's model of them): inertia and bias from eval_inverse_dynamics_passive and from one step, link poses, at 3
    random states. Returns the worst relative inertia/bias errors (functions, step) (gap_suite.check_engine_rigid)."""
    return gs.check_engine_rigid(case, engine_mech, nominal, rng, "Newton",
                                 [("Newton functions", NewtonSim.dynamics, NEWTON_RTOL),
                                  ("Newton step", NewtonSim.step_dynamics, STEP_RTOL)], POSE_TOL, speed=SPEED)


def measure_effects(case, engine_mech, rng):
    """The efforts of damping and springs and the added inertia as SolverFeatherstone applies them, one step from 8
    random states: the difference of NewtonSim.step_dynamics with and without the effects, fitted per joint by
    -b qd - k (q - r) and an added diagonal inertia. Everything is explicit, -b qd(t) - k (q(t) - r): b of damping,
    k of stiffness, and the armature alone as added inertia. Raises unless the fits match the values set to
    EFFECT_RTOL (plus STEP_RTOL of the largest inertia or bias: float32), the rest position to 1e-3, and joints
    without effects get under EFFECT_RTOL of the others'. Returns the fits per joint with effects
    (gap_suite.measure_engine_effects)."""
    def expected(p):
        return {"damping": (p["damping"], EFFECT_RTOL * p["damping"]),
                "armature": (p["armature"], EFFECT_RTOL * p["armature"])}

    return gs.measure_engine_effects(case, engine_mech, rng, "Newton", NewtonSim.step_dynamics, expected, EFFECT_RTOL,
                                     STEP_RTOL, speed=SPEED)


def check_joint_damping():
    """Newton's joint damping must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(NewtonSim, "Newton joint damping", EFFECT_RTOL)


def stop_contact(case, engine_mech, effect):
    """How Newton's penalty limit stops a joint that hits an end stop at the case's impact speed (gravity off): how
    far it goes past the stop and for how many steps it is past it: (overshoot, steps) (gap_suite.stop_hit)."""
    sim, n, sign = gs.stop_hit(case, engine_mech, effect)
    past = []
    for _ in range(400):
        sim.advance(1)
        past.append(sign * (sim.state()[0][n] - effect.params["position"]))
    sim.close()
    past = np.array(past)
    return max(0.0, float(past.max())), int(np.sum(past > 0.0))


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "newton", "newton")  # gap_suite.ENGINE_CASES, named newton_<key>
    return [
        shared("door_damping"),
        shared("flap_spring"),
        shared("knob_armature"),
        shared("pendulum_armature"),
        shared("sash_mass_scale"),
        shared("drawer_end_stop"),
        Case("newton_door_end_stop", "newton", door(0.45, 0.7, 2.0, open_limit=2.4),
             "door pushed open; a door stopper the model lacks",
             [fx("hinge", "end_stop", position=1.3, side="upper")], push(["hinge"], [1.5], span=[(0.2, 2.1)]),
             {"hinge": 0.3}, impact_speed=1.0),
        shared("lid_spring_damping"),
        shared("lid_mass_damping"),
        shared("double_pendulum_elbow_damping"),
        shared("drawer_small_damping"),
        shared("none_door_pushes"),
        shared("none_double_pendulum"),
        shared("none_lid_pose"),
    ]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How Newton made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    step = "measured over one SolverFeatherstone step at 8 random states (speeds 0.5-1.5)"
    if kind == "viscous_damping":
        return (f"Newton ModelBuilder.joint_damping = {p['damping']} (passive joint damping), explicit in "
                f"SolverFeatherstone's symplectic Euler step (-b*qd(t)); {step} as -{got['damping']:g}*qd, "
                f"{got['armature']:.3g} of apparent inertia")
    if kind == "spring":
        return (f"Newton ModelBuilder.joint_stiffness = {p['stiffness']}, joint_rest_q = {p['rest_position']} (passive "
                f"joint spring), explicit (-k*(q(t) - r)); {step} as -{got['stiffness']:g}*(q - "
                f"{got['rest_position']:g})")
    if kind == "armature":
        return (f"Newton ModelBuilder.joint_armature = {p['armature']}: added to the joint-space inertia's diagonal "
                f"before SolverFeatherstone's Cholesky factorization; {step} as {got['armature']:g} added to the "
                "joint-space inertia")
    if kind == "mass_scale":
        return (f"Newton ModelBuilder.body_mass and body_inertia of {joint.child} x{p['scale']} after add_urdf, before "
                f"finalize; inertia and bias checked against MuJoCo's model of the heavier link to {NEWTON_RTOL:g} "
                f"(eval_inverse_dynamics_passive) and {STEP_RTOL:g} (one step)")
    overshoot, steps = stop_contact(case, engine_mech, effect)
    unit = "m" if joint.kind == "prismatic" else "rad"
    return (f"Newton ModelBuilder.joint_limit_{effect.setting['side']} = {p['position']} instead of model.urdf's; "
            f"SolverFeatherstone's penalty limit, explicit in the step: past the bound limit_ke*(bound - q) - "
            f"limit_kd*qd with the builder's defaults limit_ke {LIMIT_KE:g}, limit_kd {LIMIT_KD:g} (a compliant, "
            f"bouncing stop); hit at {case.impact_speed} per second, gravity off, it goes {overshoot:.2g} {unit} past "
            f"the stop and stays past it for {steps} steps; restitution measured in the engine")


def engine_text(rigid_err):
    return (f"{ENGINE}: model.urdf read by Newton's URDF importer (ModelBuilder.add_urdf, floating=False: root link "
            f"fixed to the world; no geometry, so no shapes and no contacts), up axis z, gravity {GRAVITY[2]} z, "
            f"finalized on Warp's {DEVICE} device (float32), stepped by SolverFeatherstone (reduced coordinates, "
            f"composite rigid body algorithm, symplectic Euler, everything explicit; angular_damping 0) at {DT} s, no "
            "substeps; efforts through Control.joint_f, set at each sample and held between samples; joint positions "
            "from State.joint_q, link poses from State.body_q; model.urdf's joint limits as Newton's penalty limits "
            f"(explicit, limit_ke {LIMIT_KE:g}, limit_kd {LIMIT_KD:g}: the ModelBuilder.JointDofConfig defaults the "
            "importer gives every joint; compliant, the joint goes a little past a stop and bounces); the importer's "
            "drives have zero gains; URDF velocity and effort limits imported but not enforced by SolverFeatherstone. "
            "Rigid bodies checked against model.urdf as MuJoCo reads it: eval_inverse_dynamics_passive "
            f"{rigid_err[0]:.1e} relative, one-step accelerations {rigid_err[1]:.1e} (float32), link poses to "
            f"{POSE_TOL:g}")


def run_case(case, seed, out):
    """Simulates one case with Newton and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: NewtonSim(engine_mech, case.effects, model=case.mech))


def main():
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_joint_damping)])


if __name__ == "__main__":
    main()
