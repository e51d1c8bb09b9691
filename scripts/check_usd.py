#!/usr/bin/env python3
"""Opens partscene's `scene.usda` with Pixar's USD (PyPI `usd-core`) and checks it against the
`scene.json` beside it (issue 12 item 3):

- the stage opens, Z up, metres and kilograms;
- `UsdPhysics`'s own parser (`LoadUsdPhysicsFromRange`) finds one articulation per object of two
  or more parts, rooted by a fixed joint to the world, whose bodies are exactly that object's parts
  (a one-part object is a body fixed to the world);
- every part is a rigid body with a collision shape, its `physics:mass` the primitive's volume
  times the export density;
- every movable joint of scene.json is a revolute or prismatic joint between the right bodies, its
  X axis turned onto `axis_world`, its limits those of scene.json (degrees for revolute, metres
  for prismatic, none for continuous);
- with `--fitted`: `partscene usd --effects` writes known fitted effects on the first revolute and
  prismatic joints, and the drive and `PhysxJointAxisAPI` values come back in USD's units
  (per degree for rotational drives).

Usage: check_usd.py --bin PARTSCENE [--density 600] [--fitted] DIR...  (each DIR holds scene.json
and scene.usda). Exits non-zero on the first scene that fails, naming it.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

from pxr import Usd, UsdGeom, UsdPhysics


def volume(prim):
    sx, sy, sz = prim["size"]
    kind = prim["kind"]
    r = sx / 2
    if kind == "cuboid":
        return sx * sy * sz
    if kind == "cylinder":
        return math.pi * r * r * sz
    if kind == "sphere":
        return 4 / 3 * math.pi * r ** 3
    if kind == "capsule":
        straight = max(sz - sx, 0.0)
        return math.pi * r * r * straight + 4 / 3 * math.pi * r ** 3
    raise ValueError(kind)


def rotate(q, v):
    """Rotates v by the Gf.Quatf q: v + 2w(u×v) + 2u×(u×v) (Gf.Rotation goes through an angle, acos(w),
    which loses rotations under ~1e-3 rad in float)."""
    n = math.sqrt(q.GetReal() ** 2 + sum(c * c for c in q.GetImaginary()))
    w, u = q.GetReal() / n, [c / n for c in q.GetImaginary()]
    cross = lambda a, b: (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    t = cross(u, v)
    tt = cross(u, t)
    return tuple(v[i] + 2 * w * t[i] + 2 * tt[i] for i in range(3))


def physics(stage):
    with_warnings = getattr(UsdPhysics, "LoadUsdPhysicsFromRange")
    parsed = with_warnings(stage, ["/"])
    out = {}
    for kind, (paths, descs) in parsed.items():
        out[kind] = {str(p): d for p, d in zip(paths, descs)}
    return out


def check_scene(d, density, fail):
    scene = json.load(open(os.path.join(d, "scene.json")))
    stage = Usd.Stage.Open(os.path.join(d, "scene.usda"))
    if stage is None:
        fail("the stage does not open")
    if UsdGeom.GetStageUpAxis(stage) != UsdGeom.Tokens.z or UsdGeom.GetStageMetersPerUnit(stage) != 1.0:
        fail("stage not Z up in metres")
    links = {p.GetName(): p for p in stage.Traverse() if p.HasAPI(UsdPhysics.RigidBodyAPI)}
    parsed = physics(stage)
    T = UsdPhysics.ObjectType
    path_of = {}
    for part in scene["parts"]:
        prim = links.get(part["urdf_link"])
        if prim is None:
            fail(f"part {part['id']}: no rigid body named {part['urdf_link']}")
        path = str(prim.GetPath())
        path_of[part["id"]] = path
        body = parsed[T.RigidBody].get(path)
        if body is None or not body.collisions:
            fail(f"{path}: the UsdPhysics parser finds no rigid body with a collision shape")
        mass = UsdPhysics.MassAPI(prim).GetMassAttr().Get()
        want = max(volume(part["primitive"]) * density, 1e-3)
        if abs(mass - want) > 1e-4 * want:
            fail(f"{path}: mass {mass} kg, scene.json's primitive gives {want} kg")
    articulations = parsed.get(T.Articulation, {})
    for obj in scene["objects"]:
        paths = sorted(path_of[p["id"]] for p in scene["parts"] if p["object"] == obj["id"])
        if not paths:
            continue
        owner = os.path.dirname(paths[0])
        fixed = parsed.get(T.FixedJoint, {})
        if len(paths) == 1:
            # One part: a lone rigid body fixed to the world, no articulation.
            if owner in articulations or not any(str(j.body1) == paths[0] and str(j.body0) in ("", "/") for j in fixed.values()):
                fail(f"object {obj['id']}: a one-part object must be a body fixed to the world, not an articulation")
            continue
        art = articulations.get(owner)
        if art is None:
            fail(f"object {obj['id']}: {owner} is not an articulation")
        # The world (an empty path) is the fixed base.
        bodies = sorted(str(b) for b in art.articulatedBodies if str(b) not in ("", "/"))
        if bodies != paths:
            fail(f"{owner}: articulated bodies {bodies}, the object's parts are {paths}")
        roots = [str(r) for r in art.rootPrims]
        if len(roots) != 1 or roots[0] not in fixed or str(fixed[roots[0]].body0) not in ("", "/"):
            fail(f"{owner}: not rooted by one fixed joint to the world ({roots})")
    moving = {**parsed.get(T.RevoluteJoint, {}), **parsed.get(T.PrismaticJoint, {})}
    by_bodies = {(str(j.body0), str(j.body1)): (p, j) for p, j in moving.items()}
    checked = 0
    for joint in scene["joints"]:
        if joint["type"] == "fixed":
            continue
        parent, child = scene_part(scene, joint["parent"]), scene_part(scene, joint["child"])
        if parent["object"] != child["object"]:
            continue
        key = (path_of[joint["parent"]], path_of[joint["child"]])
        if key not in by_bodies:
            fail(f"joint {joint['parent']} -> {joint['child']}: no revolute or prismatic joint between {key}")
        path, desc = by_bodies[key]
        check_joint(path, desc, joint, fail)
        checked += 1
    return checked, len(path_of), len(articulations)


def scene_part(scene, pid):
    return next(p for p in scene["parts"] if p["id"] == pid)


def check_joint(path, desc, joint, fail):
    prismatic = joint["type"] == "prismatic"
    if (desc.type == UsdPhysics.ObjectType.PrismaticJoint) != prismatic:
        fail(f"{path}: joint type does not match scene.json's {joint['type']}")
    if str(desc.axis) != "X":
        fail(f"{path}: axis {desc.axis}, expected X of the joint frame")
    axis = rotate(desc.localPose0Orientation, (1, 0, 0))
    want = joint["axis_world"]
    n = math.sqrt(sum(c * c for c in want))
    if max(abs(axis[i] - want[i] / n) for i in range(3)) > 1e-4:
        fail(f"{path}: axis {tuple(axis)} in the world, scene.json has {want}")
    if joint["type"] == "continuous":
        if desc.limit.enabled and math.isfinite(desc.limit.lower):
            fail(f"{path}: a continuous joint has limits {desc.limit.lower}..{desc.limit.upper}")
        return
    scale = 1.0 if prismatic else 180 / math.pi
    lo, hi = sorted((joint["lower"] * scale, joint["upper"] * scale))
    if not desc.limit.enabled or abs(desc.limit.lower - lo) > 1e-3 or abs(desc.limit.upper - hi) > 1e-3:
        fail(f"{path}: limits {desc.limit.lower}..{desc.limit.upper}, scene.json gives {lo}..{hi}")


def check_fitted(binary, d, fail):
    """Known effects through `partscene usd --effects`, read back in USD's units."""
    scene = json.load(open(os.path.join(d, "scene.json")))
    link = {p["id"]: p["urdf_link"] for p in scene["parts"]}
    picks = {}
    for j in scene["joints"]:
        kind = "prismatic" if j["type"] == "prismatic" else ("revolute" if j["type"] in ("revolute", "continuous") else None)
        if kind and kind not in picks:
            picks[kind] = f"{link[j['child']]}_joint"
    effects = []
    for name in picks.values():
        effects += [
            {"joint": name, "kind": "viscous_damping", "params": {"damping": 0.5}},
            {"joint": name, "kind": "coulomb_friction", "params": {"friction": 0.2}},
            {"joint": name, "kind": "spring", "params": {"stiffness": 2.0, "rest_position": 0.1}},
            {"joint": name, "kind": "armature", "params": {"armature": 0.01}},
        ]
    with tempfile.TemporaryDirectory() as tmp:
        fitted = os.path.join(tmp, "model.fitted.json")
        json.dump({"format": "partscene-gap-fitted/1", "effects": effects}, open(fitted, "w"))
        out = os.path.join(tmp, "fitted.usda")
        subprocess.run([binary, "usd", "--scene", os.path.join(d, "scene.json"), "--effects", fitted, "--out", out], check=True,
                       stdout=subprocess.DEVNULL)
        stage = Usd.Stage.Open(out)
        joints = {p.GetName(): p for p in stage.Traverse() if p.IsA(UsdPhysics.Joint)}
        for kind, name in picks.items():
            prim = joints.get(name)
            if prim is None:
                fail(f"fitted: no joint {name}")
            inst = "linear" if kind == "prismatic" else "angular"
            per = 1.0 if kind == "prismatic" else math.pi / 180
            pos = 1.0 if kind == "prismatic" else 180 / math.pi
            drive = UsdPhysics.DriveAPI(prim, inst)
            got = {
                "damping": drive.GetDampingAttr().Get(),
                "stiffness": drive.GetStiffnessAttr().Get(),
                "target": drive.GetTargetPositionAttr().Get(),
                "friction": prim.GetAttribute(f"physxJointAxis:{inst}:staticFrictionEffort").Get(),
                "armature": prim.GetAttribute(f"physxJointAxis:{inst}:armature").Get(),
            }
            want = {"damping": 0.5 * per, "stiffness": 2.0 * per, "target": 0.1 * pos, "friction": 0.2, "armature": 0.01}
            for k, v in want.items():
                if got[k] is None or abs(got[k] - v) > 1e-5 * max(1.0, abs(v)):
                    fail(f"fitted {name}: {k} = {got[k]}, expected {v}")
    return len(picks)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--density", type=float, default=600.0)
    ap.add_argument("--fitted", action="store_true")
    ap.add_argument("dirs", nargs="+")
    args = ap.parse_args()
    for d in args.dirs:
        def fail(msg, d=d):
            print(f"USD CHECK FAILED: {d}/scene.usda: {msg}", file=sys.stderr)
            sys.exit(1)
        joints, parts, arts = check_scene(d, args.density, fail)
        fitted = check_fitted(args.bin, d, fail) if args.fitted else 0
        print(f"{d}/scene.usda: {arts} articulations, {parts} rigid bodies, {joints} movable joints match scene.json"
              + (f"; fitted dynamics on {fitted} joints read back" if args.fitted else ""))


if __name__ == "__main__":
    main()
