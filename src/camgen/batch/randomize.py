"""Per-job randomisation of a dataset (`randomize:`): drawn at expansion, recorded, applied at compile.

`draw` turns a dataset's `randomize` block, its `seed` and one job into a JSON-serialisable record of
the drawn values (`BatchJob.randomized`); `apply` changes a scene and its cameras' profiles by exactly
that record. Recording the values rather than re-drawing them lets a plan show them and a dataset
manifest keep them.

Seeding: each job draws from ``SeedSequence(dataset.seed, spawn_key=(*name_key, knob))``, where
`name_key` is the SHA-256 of the job's name (``<scene>-<profile>-seed<seed>``, unique in a dataset)
as four 32-bit words and `knob` numbers the knob. Keying by name rather than by place in the
expansion means adding or removing scenes, profiles or seeds leaves every other job's draws as they
were; one stream per knob means switching a knob on or off leaves the others' draws as they were.

Not built: weather-like illumination that changes during a sequence, which would need per-frame
lights the scene schema does not have; every draw here is constant over a job.
"""

from __future__ import annotations

import hashlib
import math
from typing import Any

import numpy as np
from pydantic import TypeAdapter, ValidationError

from camgen.config.dataset import Randomize
from camgen.config.loader import check_cameras
from camgen.config.profile import Profile
from camgen.config.ptz_program import FollowProgram, PtzProgram
from camgen.config.scene import Actor, Camera, Scene
from camgen.config.validation import problems_from
from camgen.errors import ConfigError, Problem

KNOBS = {"light_scale": 0, "mount": 1, "actors": 2, "walk_seeds": 3, "profile_spread": 4, "ptz_programs": 5}
"""Spawn key of each knob's stream; fixed, so that the draws of a knob never depend on the others."""

ILLUMINANCE_MAX_LUX = 200_000.0
"""Largest sun or ambient illuminance the scene schema takes."""

SEED_LIMIT = 2**31
"""Drawn walk seeds and serials lie in [0, SEED_LIMIT)."""

SPREAD_KEYS = ("read_noise_e", "prnu_pct", "dsnu_e", "dark_current_e_per_s", "focus_distance_m")


def knob_rng(dataset_seed: int, job_name: str, knob: str) -> np.random.Generator:
    """The generator of one knob of the job named `job_name` in a dataset with root seed `dataset_seed`."""
    digest = hashlib.sha256(job_name.encode("utf-8")).digest()
    name_key = tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4))
    return np.random.default_rng(np.random.SeedSequence(dataset_seed, spawn_key=(*name_key, KNOBS[knob])))


def draw(randomize: Randomize, dataset_seed: int, job_name: str, scene: Scene) -> dict[str, Any]:
    """The values `randomize` draws for one job of `scene`, as plain JSON data.

    Keys, each present only when its knob is on: ``light_scale`` (factor); ``cameras`` (by camera name:
    ``mount_position_offset_m`` [dx, dy, dz], ``mount_angle_offset_deg`` {yaw_deg, pitch_deg,
    roll_deg}, ``profile_factors`` {key: factor}, ``serial``, ``ptz_program_index`` and
    ``ptz_program`` (the chosen program)); ``actors_kept``
    (names, scene order); ``walk_seeds`` (by actor name).
    """
    drawn: dict[str, Any] = {}
    cameras: dict[str, dict[str, Any]] = {camera.name: {} for camera in scene.cameras}
    if randomize.light_scale_range is not None:
        low, high = randomize.light_scale_range
        u = knob_rng(dataset_seed, job_name, "light_scale").uniform()
        drawn["light_scale"] = float(math.exp(math.log(low) + u * (math.log(high) - math.log(low))))
    if randomize.mount_position_jitter_m > 0 or randomize.mount_angle_jitter_deg > 0:
        rng = knob_rng(dataset_seed, job_name, "mount")
        for camera in scene.cameras:
            offsets = rng.uniform(-1.0, 1.0, size=6)
            if randomize.mount_position_jitter_m > 0:
                cameras[camera.name]["mount_position_offset_m"] = [
                    float(v) for v in offsets[:3] * randomize.mount_position_jitter_m
                ]
            if randomize.mount_angle_jitter_deg > 0:
                yaw, pitch, roll = (float(v) for v in offsets[3:] * randomize.mount_angle_jitter_deg)
                cameras[camera.name]["mount_angle_offset_deg"] = {"yaw_deg": yaw, "pitch_deg": pitch, "roll_deg": roll}
    programs = {camera.name: camera.head.program if camera.head is not None else None for camera in scene.cameras}
    if randomize.ptz_programs:
        rng = knob_rng(dataset_seed, job_name, "ptz_programs")
        for camera in scene.cameras:
            if camera.head is not None:
                index = int(rng.integers(len(randomize.ptz_programs)))
                cameras[camera.name]["ptz_program_index"] = index
                cameras[camera.name]["ptz_program"] = randomize.ptz_programs[index].model_dump(mode="json")
                programs[camera.name] = randomize.ptz_programs[index]
    if randomize.actor_count_range is not None:
        followed = {p.target for p in programs.values() if isinstance(p, FollowProgram)}
        drawn["actors_kept"] = _kept_actors(
            scene.actors, randomize.actor_count_range, followed, knob_rng(dataset_seed, job_name, "actors")
        )
    if randomize.walk_seeds:
        rng = knob_rng(dataset_seed, job_name, "walk_seeds")
        drawn["walk_seeds"] = {
            actor.name: int(rng.integers(SEED_LIMIT)) for actor in scene.actors if actor.random_walk is not None
        }
    if randomize.profile_spread_pct is not None:
        rng = knob_rng(dataset_seed, job_name, "profile_spread")
        spread = randomize.profile_spread_pct
        for camera in scene.cameras:
            z = rng.standard_normal(len(SPREAD_KEYS))
            cameras[camera.name]["profile_factors"] = {
                key: max(0.0, 1.0 + float(z_key) * getattr(spread, key) / 100.0)
                for key, z_key in zip(SPREAD_KEYS, z, strict=True)
                if getattr(spread, key) > 0
            }
            cameras[camera.name]["serial"] = int(rng.integers(SEED_LIMIT))
    if any(cameras.values()):
        drawn["cameras"] = {name: values for name, values in cameras.items() if values}
    return drawn


def _kept_actors(
    actors: list[Actor], count_range: tuple[int, int], followed: set[str], rng: np.random.Generator
) -> list[str]:
    """Names of a random subset of `actors` of a size drawn in `count_range` (capped), in scene order. A
    rider (`Actor.rides`) goes with its bicycle or motorcycle: the two count as one and are kept or left
    out together."""
    index = {actor.name: i for i, actor in enumerate(actors)}
    units: dict[int, list[int]] = {}  # the first member's index → every member's (a two-wheeler and its rider)
    for i, actor in enumerate(actors):
        if actor.rides is None:
            units.setdefault(i, []).insert(0, i)
        else:
            units.setdefault(index[actor.rides], []).append(i)
    firsts = sorted(units)
    low, high = (min(n, len(firsts)) for n in count_range)
    required = [u for u in firsts if any(actors[i].name in followed for i in units[u])]
    others = [u for u in firsts if u not in required]
    count = max(int(rng.integers(low, high + 1)), len(required))
    chosen = rng.choice(others, size=count - len(required), replace=False) if count > len(required) else []
    kept = sorted(i for u in [*required, *(int(u) for u in chosen)] for i in units[u])
    return [actors[i].name for i in kept]


def apply(scene: Scene, profiles: dict[str, Profile], drawn: dict[str, Any]) -> tuple[Scene, dict[str, Profile]]:
    """`scene` and its cameras' `profiles` (by camera name) changed by the values `draw` recorded.

    Raises ConfigError when the changed scene is invalid (e.g. a drawn PTZ program names a preset the
    camera lacks, or a jitter pushes a head position out of range).
    """
    profiles = dict(profiles)
    update: dict[str, Any] = {}
    if "light_scale" in drawn:
        scale = drawn["light_scale"]
        update["lights"] = [_scaled_light(light, scale) for light in scene.lights]
        environment = scene.environment
        update["environment"] = environment.model_copy(
            update={"sky_luminance_cd_m2": environment.sky_luminance_cd_m2 * scale}
        )
    actors = scene.actors
    if "actors_kept" in drawn:
        kept = set(drawn["actors_kept"])
        actors = [actor for actor in actors if actor.name in kept]
    if "walk_seeds" in drawn:
        seeds = drawn["walk_seeds"]
        actors = [
            actor.model_copy(update={"random_walk": actor.random_walk.model_copy(update={"seed": seeds[actor.name]})})
            if actor.name in seeds and actor.random_walk is not None
            else actor
            for actor in actors
        ]
    update["actors"] = actors
    cameras = []
    for camera in scene.cameras:
        values = drawn.get("cameras", {}).get(camera.name, {})
        camera, profiles[camera.name] = _changed_camera(camera, profiles[camera.name], values)
        cameras.append(camera)
    update["cameras"] = cameras
    changed = scene.model_copy(update=update)
    try:
        # model_copy does not validate: check the changed scene as if it had been written so
        changed = Scene.model_validate(changed.model_dump(by_alias=True))
    except ValidationError as exc:
        raise ConfigError(
            [Problem(p.path, f"after randomize: {p.message}", None) for p in problems_from(exc, None, Scene)]
        ) from None
    problems = check_cameras(changed, profiles)
    if problems:
        raise ConfigError([Problem(p.path, f"after randomize: {p.message}", None) for p in problems])
    return changed, profiles


def _scaled_light(light: Any, scale: float) -> Any:
    if hasattr(light, "illuminance_lux"):
        return light.model_copy(update={"illuminance_lux": min(light.illuminance_lux * scale, ILLUMINANCE_MAX_LUX)})
    return light.model_copy(update={"intensity_cd": light.intensity_cd * scale})


def _changed_camera(camera: Camera, profile: Profile, values: dict[str, Any]) -> tuple[Camera, Profile]:
    mount = camera.mount
    if "mount_position_offset_m" in values:
        position = tuple(p + d for p, d in zip(mount.position_m, values["mount_position_offset_m"], strict=True))
        mount = mount.model_copy(update={"position_m": position})
    if "mount_angle_offset_deg" in values:
        offset = values["mount_angle_offset_deg"]
        mount = mount.model_copy(
            update={
                "yaw_deg": mount.yaw_deg + offset["yaw_deg"],
                "pitch_deg": float(np.clip(mount.pitch_deg + offset["pitch_deg"], -90.0, 90.0)),
                "roll_deg": float(np.clip(mount.roll_deg + offset["roll_deg"], -180.0, 180.0)),
            }
        )
    update: dict[str, Any] = {"mount": mount}
    if "serial" in values:
        update["serial"] = values["serial"]
    if "ptz_program" in values and camera.head is not None:
        head_key = "ptz" if camera.ptz is not None else "eptz"
        program = TypeAdapter(PtzProgram).validate_python(values["ptz_program"])
        update[head_key] = camera.head.model_copy(update={"program": program})
    factors = values.get("profile_factors", {})
    if factors:
        noise = profile.sensor.noise
        noise_update = {
            key: min(getattr(noise, key) * factor, 100.0) if key == "prnu_pct" else getattr(noise, key) * factor
            for key, factor in factors.items()
            if key != "focus_distance_m"
        }
        sensor = profile.sensor.model_copy(update={"noise": noise.model_copy(update=noise_update)})
        profile = profile.model_copy(update={"sensor": sensor})
        focus = camera.focus_distance_m if camera.focus_distance_m is not None else profile.lens.focus_distance_m
        if "focus_distance_m" in factors and focus is not None:
            update["focus_distance_m"] = max(focus * factors["focus_distance_m"], profile.lens.min_focus_distance_m)
    return camera.model_copy(update=update), profile
