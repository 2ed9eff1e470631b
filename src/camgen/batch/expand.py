"""A dataset file expanded into batch jobs (scene × profile × seed), and each compiled into a Job.

The expansion is deterministic: the same dataset file gives the same jobs in the same order, with the
same names. A job's profile replaces every camera's own and its seed replaces the scene's `seed`, so
distinct (scene, profile, seed) give distinct scenes and hence distinct job hashes.

A dataset's `randomize:` block is drawn here, per job, into `BatchJob.randomized` (see
`camgen.batch.randomize` for the seeding), and applied when the job is compiled; the drawn values
change the compiled scene and so the job hash.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from camgen.batch import randomize
from camgen.config.loader import find_profile, load_dataset, load_profile, load_scene
from camgen.config.scene import Scene
from camgen.config.validation import validate
from camgen.config.yaml_source import load_yaml
from camgen.errors import ConfigError, Problem
from camgen.job import Job
from camgen.plan import PlanSettings
from camgen.plan.compile import compile


@dataclass(frozen=True)
class BatchJob:
    """One entry of a dataset: which scene, with which profile and seed."""

    name: str
    """`<scene>-<profile or "own">-seed<seed>`: stable, and unique within the dataset."""
    dataset_path: Path
    index: int
    """Place of this job in the dataset's expansion, from 0."""
    scene_path: Path
    profile: str | None
    """The profile reference as the dataset writes it (a name or a path), or None: keep the scene's."""
    profile_path: Path | None
    seed: int
    randomized: dict[str, Any] = field(default_factory=dict)
    """The values the dataset's `randomize:` drew for this job (`camgen.batch.randomize.draw`), plain JSON
    data; empty without one. Compiling applies exactly these."""


def expand(dataset_path: str | Path, profile_dirs: Sequence[Path] = ()) -> list[BatchJob]:
    """The jobs of a dataset file, in order: scenes × profiles × seeds (product), or the i-th of each (zip).

    Raises ConfigError, naming the dataset file and the entry, for a missing scene file or an unknown profile.
    """
    dataset_path = Path(dataset_path)
    if not dataset_path.is_file():
        raise ConfigError(f"{dataset_path}: no such dataset file; give the path of a dataset YAML file")
    dataset = load_dataset(dataset_path, profile_dirs)
    profile_paths = {ref: find_profile(ref, dataset_path, profile_dirs) for ref in dataset.profiles}
    scenes = [dataset_path.parent / scene for scene in dataset.scenes]
    profiles: list[str | None] = list(dataset.profiles) or [None]
    seeds = dataset.seed_list
    if dataset.combine == "zip":
        count = len(scenes)
        entries = [(scenes[i], profiles[i] if dataset.profiles else None, seeds[i]) for i in range(count)]
    else:
        entries = [(scene, profile, seed) for scene in scenes for profile in profiles for seed in seeds]
    jobs = []
    scenes_read: dict[Path, Scene] = {}
    for index, (scene_path, profile, seed) in enumerate(entries):
        label = "own" if profile is None else Path(profile).stem
        name = f"{scene_path.stem}-{label}-seed{seed}"
        randomized = {}
        if dataset.randomize is not None and not dataset.randomize.is_identity:
            if scene_path not in scenes_read:
                scenes_read[scene_path] = _read_scene(dataset_path, scene_path)
            randomized = randomize.draw(dataset.randomize, dataset.seed, name, scenes_read[scene_path])
        jobs.append(
            BatchJob(
                name=name,
                dataset_path=dataset_path,
                index=index,
                scene_path=scene_path,
                profile=profile,
                profile_path=None if profile is None else profile_paths[profile],
                seed=seed,
                randomized=randomized,
            )
        )
    names = [job.name for job in jobs]
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ConfigError(
            f"{dataset_path}: the jobs {', '.join(repeated)} appear more than once; remove the repeated scene, "
            "profile or seed"
        )
    return jobs


def _read_scene(dataset_path: Path, scene_path: Path) -> Scene:
    """The scene a dataset names, validated alone (its actors and cameras are what `randomize` draws for)."""
    try:
        return validate(Scene, load_yaml(scene_path))
    except ConfigError as exc:
        raise ConfigError(
            [Problem((), f"{dataset_path}: scene {scene_path}: {problem}", None) for problem in exc.problems]
        ) from None


def compile_batch_job(
    batch_job: BatchJob, settings: PlanSettings | None = None, profile_dirs: Sequence[Path] = ()
) -> Job:
    """Load the job's scene, give every camera the job's profile (if any) and the scene the job's seed, apply
    the job's randomized values, compile.

    Raises ConfigError naming the dataset file and the job when the scene or the combination is invalid.
    """
    try:
        loaded = load_scene(batch_job.scene_path, profile_dirs)
        profiles, profile_names = loaded.profile_models, loaded.profile_names
        cameras = loaded.scene.cameras
        if batch_job.profile_path is not None:
            override = load_profile(batch_job.profile_path, profile_dirs)
            cameras = [camera.model_copy(update={"profile": override.name}) for camera in cameras]
            profiles = {camera.name: override.profile for camera in cameras}
            profile_names = {camera.name: override.name for camera in cameras}
        scene = loaded.scene.model_copy(update={"cameras": cameras, "seed": batch_job.seed})
        if batch_job.randomized:
            scene, profiles = randomize.apply(scene, profiles, batch_job.randomized)
        return compile(
            scene,
            profiles,
            scene_name=loaded.name,
            profile_names=profile_names,
            settings=settings,
            file_bounds=loaded.file_bounds,
        )
    except ConfigError as exc:
        where = f"{batch_job.dataset_path}: job {batch_job.name} (entry {batch_job.index})"
        raise ConfigError([Problem((), f"{where}: {problem}", None) for problem in exc.problems]) from None


def compile_dataset(
    dataset_path: str | Path, profile_dirs: Sequence[Path] = ()
) -> list[tuple[BatchJob, Job | ConfigError]]:
    """Every job of a dataset (`expand`) with its compiled Job, or the ConfigError that says why it does not
    compile (`compile_batch_job`); one job failing does not stop the others. A compile that fails inside
    camgen itself is reported the same way, naming the job and the exception, not as a traceback."""
    compiled: list[tuple[BatchJob, Job | ConfigError]] = []
    for batch_job in expand(dataset_path, profile_dirs):
        try:
            compiled.append((batch_job, compile_batch_job(batch_job, profile_dirs=profile_dirs)))
        except ConfigError as exc:
            compiled.append((batch_job, exc))
        except Exception as exc:
            where = f"{batch_job.dataset_path}: job {batch_job.name}"
            compiled.append((batch_job, ConfigError(f"{where}: does not compile ({type(exc).__name__}: {exc})")))
    return compiled
