#!/usr/bin/env python3
"""Recordings of articulated mechanisms made by DART (dartpy), a fourth engine held out from `partscene gap`'s
development: the same case format as gap_suite.py, cases named dart_*.

    gap_suite_dart.py --out DIR [--seed N] [--only PATTERN]

PATTERN is an fnmatch pattern on the case name ('dart_lid*'). Needs the pinned packages of
gap_suite_dart_requirements.txt beside this file (gap_suite.py's, and dartpy). Every case is a folder DIR/<case>/
with model.urdf, recording.csv and truth.json exactly as gap_suite.py describes them; truth.json's "engine" is
"dart <version>".

Engine: model.urdf itself, read by dartpy.utils.DartLoader with the root link welded to the world, in a
dartpy.simulation.World of its own: gravity -9.81 z, 1 ms steps (DART's semi-implicit Euler), the default
constraint solver (boxed LCP, Dantzig with PGS as fallback), no collision shapes. Efforts are generalized forces
(Skeleton.setForces) set before every step, since World.step clears them: held between samples as the spec says.
What DART adds silently and model.urdf lacks is switched off: deactivation (sleeping: on by default, a body slower
than 0.05 rad/s for 0.5 s is frozen). The loader reads model.urdf's joint limits without enforcing them; they are
enforced (Joint.setLimitEnforcement(True)), so that a stop is DART's JointConstraint: a hard, inelastic impulse
that clips the joint's velocity so that the next position stays inside (restitution measured, 0). The URDF's
velocity (100) and effort (1000) limits stay as loaded; the motions never come near them.

Concealed effects, each made the way DART's joint and body API makes it (after loading model.urdf):
  coulomb_friction  DegreeOfFreedom.setCoulombFriction: DART's JointCoulombFrictionConstraint, an LCP impulse
                    bounded by friction*dt that drives the joint's velocity to zero: it sticks exactly
  viscous_damping   DegreeOfFreedom.setDampingCoefficient (implicit in the step: -b*qd(t+dt))
  spring            DegreeOfFreedom.setSpringStiffness + setRestPosition (implicit: -k*(q(t+dt) - r))
  mass_scale        BodyNode.setMass and setMomentOfInertia of the child link, scaled
  end_stop          Joint.setPositionUpperLimit/LowerLimit narrower than model.urdf's, limits enforced
No armature (DART 6 joints have none) and no tilted axis or effort offset (not engine effects).

Checks (a failure stops the run):
  rigid bodies   DART's joint-space inertia and bias force, both as Skeleton.getMassMatrix /
                 getCoriolisAndGravityForces give them and as one World.step moves the joints (accelerations with
                 zero and small efforts, limits off), against model.urdf as MuJoCo reads it, and for a heavier link
                 the engine's bodies against MuJoCo's model of them, to DART_RTOL, plus every link's pose to POSE_TOL,
                 at 3 random states per case.
  effects        the damping, spring and friction efforts and the added inertia, measured one step at a time at 8
                 random states (the difference to the same skeleton without them, speeds 0.5-1.5 so that friction
                 slides through the step) and fitted by -b qd - f sign(qd) - k (q - r) and the added diagonal
                 inertia, to EFFECT_RTOL of the values set (truth.json gives the values set and the fits). DART's
                 damping and spring are implicit: the fit sees b + k*dt of damping and b*dt + k*dt^2 of inertia.
                 Joints without effects get under EFFECT_RTOL of the others' efforts. Before any damped case, a
                 damped free door under a constant effort must reach the speed of -b*qd after 1 s
                 (gap_suite.check_joint_damping); before any case with friction, a free door under an effort
                 below the friction must stay at rest for 1 s, and above it reach the speed of (u - f)/I.
  end stops      restitution measured in the engine (gap_suite.measure_restitution).

Cases (efforts, noise and sampling as gap_suite.py's, each from its own generator
default_rng([seed, crc32(name)])):
  dart_door_friction                   heavy wardrobe door pushed and released; dry hinge
  dart_drawer_friction                 loaded drawer pushed and released; dry runners
  dart_door_damping                    cabinet door pushed and released; damped hinge
  dart_flap_spring                     light flap on a vertical hinge with a return spring, pushed
  dart_sash_mass_scale                 window sash lifted by a multisine; heavier than modelled
  dart_drawer_end_stop                 drawer pushed open and shut; a stop inside the modelled travel
  dart_door_friction_damping           cabinet door pushed: dry friction and viscous damping
  dart_lid_spring_damping              counterbalanced lid with a damper, pushed
  dart_lid_mass_friction               lid pushed open and let fall: heavier than modelled, dry hinge
  dart_double_pendulum_elbow_friction  double pendulum released; dry friction at the elbow only
  dart_none_door_pushes                NOTHING missing: door pushed toward targets spanning past its stops
  dart_none_double_pendulum            NOTHING missing: double pendulum released, no effort column
  dart_none_lid_pose                   NOTHING missing: lid pushed and dropped onto its stop, tracked by its link
                                       pose; jittered sample times, dropouts
"""

import functools

import dartpy
import mujoco
import numpy as np

import gap_suite as gs
from gap_suite import DT, GRAVITY, SuiteError, door, fx, joint_params, urdf_text

ENGINE = f"dart {dartpy.__version__}"
DART_RTOL = 1e-9  # inertia and bias against MuJoCo, relative to the largest entry (both compute in double)
POSE_TOL = 1e-9  # link positions (m) and quaternion components against MuJoCo
EFFECT_RTOL = 0.01  # damping, spring, friction and added inertia as measured against the values set
SPEED = (0.5, 1.5)  # |qd| of the states where effects are measured: friction must slide through the step
PROBE = 1.0  # rad/s^2 or m/s^2: the efforts that measure the inertia accelerate each joint about this much


def load_skeleton(mech):
    """model.urdf of `mech` read by DART's URDF loader, root link welded to the world."""
    loader = dartpy.utils.DartLoader()
    options = dartpy.utils.DartLoaderOptions()
    options.mDefaultRootJointType = dartpy.utils.DartLoaderRootJointType.FIXED
    loader.setOptions(options)
    skel = loader.parseSkeletonString(urdf_text(mech), dartpy.common.Uri(""))
    if skel is None:
        raise SuiteError(f"DART's URDF loader could not read the {mech.name} model")
    return skel


class DartSim:
    """model.urdf (of `model`, default `mech`) loaded into its own DART world; where `mech` (the engine's bodies)
    differs from it, a link's mass, centre of mass and inertia and a joint's limits are set through DART's API, and
    the effects on the joints' degrees of freedom. Efforts through setForces before every step (held)."""

    def __init__(self, mech, effects, gravity=True, model=None):
        model = mech if model is None else model
        self.skel = load_skeleton(model)
        self.world = dartpy.simulation.World()
        options = self.world.getDeactivationOptions()
        options.mEnabled = False
        self.world.setDeactivationOptions(options)
        self.world.setGravity(np.array(GRAVITY if gravity else (0.0, 0.0, 0.0)))
        self.world.setTimeStep(DT)
        self.world.addSkeleton(self.skel)
        if self.skel.getTimeStep() != DT:
            raise SuiteError(f"DART skeleton time step {self.skel.getTimeStep()}, {DT} was set")
        for link in mech.links:
            self._set_body(self.skel.getBodyNode(link.name), link, model.link(link.name))
        self.names = mech.movable()
        self.joints = [self.skel.getJoint(name) for name in self.names]
        self.idx = [joint.getIndexInSkeleton(0) for joint in self.joints]
        self.limited = []
        for joint, name in zip(self.joints, self.names):
            self._set_joint(joint, mech.joint(name), model.joint(name), joint_params(effects, name))
            if mech.joint(name).lower is not None:
                self.limited.append(joint)
        self.effort = np.zeros(len(self.names))

    @staticmethod
    def _set_body(body, link, urdf_link):
        if body is None:
            raise SuiteError(f"DART has no body {link.name}")
        if link.mass != urdf_link.mass or not np.array_equal(link.inertia, urdf_link.inertia):
            i = link.inertia
            body.setMass(link.mass)
            body.setMomentOfInertia(i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
        if tuple(link.com) != tuple(urdf_link.com):
            body.setLocalCOM(np.array(link.com, float))

    @staticmethod
    def _set_joint(dart_joint, joint, urdf_joint, p):
        if dart_joint is None or dart_joint.getNumDofs() != 1:
            raise SuiteError(f"DART has no one-dof joint {joint.name}")
        if p["armature"]:
            raise SuiteError(f"joint {joint.name}: DART 6 joints have no armature")
        gs.check_joint_frame(joint, urdf_joint)
        if joint.lower is not None:
            if joint.lower != urdf_joint.lower:
                dart_joint.setPositionLowerLimit(0, joint.lower)
            if joint.upper != urdf_joint.upper:
                dart_joint.setPositionUpperLimit(0, joint.upper)
            dart_joint.setLimitEnforcement(True)
        dof = dart_joint.getSkeleton().getDof(dart_joint.getIndexInSkeleton(0))
        dof.setDampingCoefficient(joint.damping + p["damping"])
        dof.setCoulombFriction(p["friction"])
        dof.setSpringStiffness(p["stiffness"])
        dof.setRestPosition(p["springref"])

    def _full(self, values):
        out = np.zeros(self.skel.getNumDofs())
        out[self.idx] = values
        return out

    def set_state(self, q, qd):
        self.skel.setPositions(self._full(q))
        self.skel.setVelocities(self._full(qd))
        self.skel.resetAccelerations()

    def state(self):
        return self.skel.getPositions()[self.idx].copy(), self.skel.getVelocities()[self.idx].copy()

    def hold(self, effort):
        self.effort = np.asarray(effort, float).copy()

    def advance(self, steps):
        forces = self._full(self.effort)
        for _ in range(int(steps)):
            self.skel.setForces(forces)  # World.step clears the forces after each step
            self.world.step()

    def pose(self, link):
        transform = self.skel.getBodyNode(link).getWorldTransform()
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(transform.rotation()).flatten())
        return np.concatenate([np.asarray(transform.translation(), float).flatten(), quat])

    def dynamics(self, q, qd):
        """Joint-space inertia and bias force C(q, qd) qd + g(q) as DART's Skeleton computes them."""
        self.set_state(q, qd)
        full, bias = self.skel.getMassMatrix(), self.skel.getCoriolisAndGravityForces()
        return full[np.ix_(self.idx, self.idx)].copy(), bias[self.idx].copy()

    def step_dynamics(self, q, qd):
        """Joint-space inertia and bias force as one World.step has them, with everything the step adds (implicit
        damping and spring, the friction impulse): the velocity change of one step from (q, qd) with zero effort
        and with a small effort on each joint (PROBE of acceleration), limits not enforced meanwhile. Raises where
        a joint's velocity changes sign within the step (friction would not slide). (gap_suite.probe_step_dynamics)"""
        def slides(after):
            if np.any(np.sign(after) != np.sign(qd)):
                raise SuiteError("a joint's velocity changed sign within the measuring step")

        for joint in self.limited:
            joint.setLimitEnforcement(False)
        out = gs.probe_step_dynamics(self, q, qd, PROBE, check=slides)
        for joint in self.limited:
            joint.setLimitEnforcement(True)
        self.hold(np.zeros(len(q)))
        return out

    def close(self):
        self.world.removeAllSkeletons()
        self.world = self.skel = self.joints = self.limited = None


gs.SIMULATORS["dart"] = lambda case, mech, effects, gravity: DartSim(mech, effects, gravity, model=case.mech)


# ---------------------------------------------------------------- checks


def check_rigid(case, engine_mech, nominal, rng):
    """DART's bodies against model.urdf as MuJoCo reads it (and, for a heavier link, the engine's bodies against
    MuJoCo's model of them): inertia and bias from the Skeleton and from one step, link poses, at 3 random states.
    Returns the worst relative inertia/bias error (gap_suite.check_engine_rigid)."""
    return max(gs.check_engine_rigid(case, engine_mech, nominal, rng, "DART",
                                     [("DART Skeleton", DartSim.dynamics, DART_RTOL),
                                      ("DART step", DartSim.step_dynamics, DART_RTOL)], POSE_TOL, speed=SPEED))


def measure_effects(case, engine_mech, rng):
    """The efforts of damping, spring and friction and the added inertia as DART applies them, one step from 8
    random states: the difference of DartSim.step_dynamics with and without the effects, fitted per joint by
    -b qd - f sign(qd) - k (q - r) and an added diagonal inertia. DART's damping and spring are implicit,
    -b qd(t+dt) - k (q(t+dt) - r): they show as b + k*DT of damping and b*DT + k*DT^2 of inertia. Raises unless the
    fits match the values set (with that) to EFFECT_RTOL, the rest position to 1e-3, and joints without effects get
    under EFFECT_RTOL of the others'. Returns the fits per joint with effects (gap_suite.measure_engine_effects)."""
    def expected(p):
        implicit_b, implicit_i = p["damping"] + p["stiffness"] * DT, p["damping"] * DT + p["stiffness"] * DT ** 2
        return {"damping": (implicit_b, EFFECT_RTOL * implicit_b), "armature": (implicit_i, EFFECT_RTOL * implicit_i)}

    return gs.measure_engine_effects(case, engine_mech, rng, "DART", DartSim.step_dynamics, expected, EFFECT_RTOL,
                                     1e-8, speed=SPEED)


def check_joint_damping():
    """DART's damping coefficient must act as -b*qd over time (gap_suite.check_joint_damping)."""
    gs.check_joint_damping(DartSim, "DART joint damping", EFFECT_RTOL)


def check_coulomb_friction():
    """DART's Coulomb friction f on a free door (inertia I, no gravity torque): under a held effort below f the door
    stays at rest for 1 s (|q|, |qd| under 1e-9); under u above f it reaches (u - f)/I after 1 s, to EFFECT_RTOL."""
    mech = door(0.5, 0.5, 1.2, open_limit=100.0)
    inertia = mech.link("door_panel").inertia[2, 2] + 1.2 * 0.25 ** 2
    sim = DartSim(mech, [fx("hinge", "coulomb_friction", friction=0.5)])
    for effort, expected in ((0.3, 0.0), (-0.45, 0.0), (1.0, 0.5 / inertia)):
        sim.set_state([0.0], [0.0])
        sim.hold([effort])
        sim.advance(1000)
        (q,), (qd,) = sim.state()
        if expected == 0.0 and max(abs(q), abs(qd)) > 1e-9:
            raise SuiteError(f"DART Coulomb friction 0.5 does not hold the door under {effort}: q {q}, qd {qd} "
                             "after 1 s")
        if expected and abs(qd - expected) > EFFECT_RTOL * expected:
            raise SuiteError(f"DART Coulomb friction does not act as f*sign(qd): {qd} rad/s after 1 s, "
                             f"expected {expected}")
    sim.close()


# ---------------------------------------------------------------- cases


def cases():
    shared = functools.partial(gs.engine_case, "dart", "dart")  # gap_suite.ENGINE_CASES, named dart_<key>
    return [
        shared("door_friction"),
        shared("drawer_friction"),
        shared("door_damping"),
        shared("flap_spring"),
        shared("sash_mass_scale"),
        shared("drawer_end_stop"),
        shared("door_friction_damping"),
        shared("lid_spring_damping"),
        shared("lid_mass_friction"),
        shared("double_pendulum_elbow_friction"),
        shared("none_door_pushes"),
        shared("none_double_pendulum"),
        shared("none_lid_pose"),
    ]


# ---------------------------------------------------------------- recording and truth


def effect_detail(case, effect, engine_mech, measured):
    """How DART made one effect, and what was measured of it."""
    p, kind, got = effect.params, effect.kind, measured.get(effect.joint, {})
    joint = engine_mech.joint(effect.joint)
    step = "measured over one step at 8 random states (speeds 0.5-1.5)"
    if kind == "coulomb_friction":
        return (f"DART DegreeOfFreedom.setCoulombFriction({p['friction']}): JointCoulombFrictionConstraint, a "
                f"boxed-LCP impulse bounded by friction*dt that drives the joint's velocity to zero (sticks exactly); "
                f"{step} as -{got['friction']:g}*sign(qd)")
    if kind == "viscous_damping":
        return (f"DART DegreeOfFreedom.setDampingCoefficient({p['damping']}), implicit in the step (-b*qd(t+dt)); "
                f"{step} as -{got['damping']:g}*qd with {got['armature']:.3g} of apparent inertia (b*dt)")
    if kind == "spring":
        return (f"DART DegreeOfFreedom.setSpringStiffness({p['stiffness']}) and setRestPosition({p['rest_position']}), "
                f"implicit in the step (-k*(q(t+dt) - r)); {step} as -{got['stiffness']:g}*(q - "
                f"{got['rest_position']:g})")
    if kind == "mass_scale":
        return (f"DART BodyNode {joint.child}: setMass and setMomentOfInertia x{p['scale']} after loading model.urdf; "
                f"inertia and bias checked against MuJoCo's model of the heavier link to {DART_RTOL:g}")
    return (f"DART Joint.setPosition{effect.setting['side'].capitalize()}Limit({p['position']}) instead of "
            "model.urdf's, setLimitEnforcement(True): DART's JointConstraint, a hard inelastic impulse (velocity "
            "clipped so that the next position stays inside, no restitution parameter); restitution measured in the "
            f"engine hitting it at {case.impact_speed} per second, gravity off")


def engine_text(rigid_err):
    return (f"{ENGINE}: model.urdf read by dartpy.utils.DartLoader (root link welded to the world, no collision "
            f"shapes), its own World: gravity {GRAVITY[2]} z, {DT} s steps (semi-implicit Euler), default boxed-LCP "
            "constraint solver (Dantzig, PGS fallback), deactivation (sleeping) off; efforts through "
            "Skeleton.setForces before every step, held between samples; model.urdf's joint limits enforced "
            "(setLimitEnforcement(True)): hard inelastic JointConstraint; URDF velocity and effort limits as loaded. "
            "Rigid bodies checked against model.urdf as MuJoCo reads it (getMassMatrix / getCoriolisAndGravityForces "
            f"and one-step accelerations, link poses): {rigid_err:.1e} relative")


def run_case(case, seed, out):
    """Simulates one case with DART and writes DIR/<case>/{model.urdf, recording.csv, truth.json}."""
    return gs.run_engine_case(case, seed, out, ENGINE, (check_rigid, measure_effects, effect_detail, engine_text),
                              lambda engine_mech: DartSim(engine_mech, case.effects, model=case.mech))


def main():
    gs.engine_suite_main(cases, run_case, [("viscous_damping", check_joint_damping),
                                           ("coulomb_friction", check_coulomb_friction)])


if __name__ == "__main__":
    main()
